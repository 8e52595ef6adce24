#pragma once
/// \file
/// Pieces every associator shares, written once so that the fast
/// NormalConsistency and the literal NormalConsistencyReference take their
/// decisions with the very same arithmetic (their results must be equal).

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/core/error.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/search/kdtree.hpp>

namespace semlio::detail {

/// A scan point moved into the map frame (rotation R, translation t), as the
/// float query the k-d tree takes.
inline Eigen::Vector3f feature_to_map(const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                              const Eigen::Vector3f& p_scan) {
  return (R * p_scan.cast<double>() + t).cast<float>();
}

/// Distance gate on a candidate's squared distance [m^2].
inline bool within_gate(float sq_dist, double max_sq_dist) {
  return static_cast<double>(sq_dist) <= max_sq_dist;
}

/// Resizes out to n features, every entry empty; reuses capacity.
inline void reset_matches(std::size_t n, Correspondences& out) {
  out.assign(n, FeatureMatches{});
}

/// Appends candidate index i with 1-based rank to m.
inline void push_match(FeatureMatches& m, std::uint32_t i, std::size_t rank) {
  m.index[m.count] = i;
  m.rank[m.count] = static_cast<std::uint8_t>(rank);
  ++m.count;
}

/// Drops a match set too small for the primitive (2 for a line, 3 for a plane).
inline void enforce_min(FeatureKind kind, FeatureMatches& m) {
  if (m.count < min_points(kind)) m = FeatureMatches{};
}

/// Throws ConfigError unless lo <= v <= hi.
inline void check_association_setting(const char* field, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi)) {
    throw ConfigError(std::string(field) + " = " + std::to_string(v) + ", expected " +
                      std::to_string(lo) + ".." + std::to_string(hi));
  }
}

}  // namespace semlio::detail
