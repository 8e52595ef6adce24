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
#include <semlio/lie/se3.hpp>
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

/// The loop of every associator's associate(): out gets one FeatureMatches
/// per bound feature (all empty without a non-empty map), each from
/// match(i, R, t) at the pose's rotation and translation.
template <typename Match>
void associate_each(const std::vector<Eigen::Vector3f>* features, const FeatureMap* map, const SE3d& T_map_scan,
                    Correspondences& out, Match&& match) {
  const std::size_t n = features == nullptr ? 0 : features->size();
  reset_matches(n, out);
  if (map == nullptr || map->empty()) return;
  const Eigen::Matrix3d R = T_map_scan.rotation();
  const Eigen::Vector3d& t = T_map_scan.translation();
  for (std::size_t i = 0; i < n; ++i) out[i] = match(i, R, t);
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
