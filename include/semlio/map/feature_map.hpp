#pragma once
/// \file
/// One searchable feature map (corners or surfaces) in the map frame: points,
/// their labels, a k-d tree, and the shape axis of each point (surface normal
/// or line direction, eq. 3-6 over its nearest map points) cached once at
/// build, so that Algorithm 1 never refits a map neighbourhood per frame.
///
/// Candidate lists (why Algorithm 1 costs about as much as a 5-NN query):
/// build() also stores, per map point m, its K nearest map points (K = 32 by
/// default) and the distance R_m to the K-th. A query q then needs only a 1-NN
/// k-d tree search for an anchor m (distance a = |q - m|): by the triangle
/// inequality every map point within R_m - a of q is in m's list, so when the
/// k-th candidate found in the list (or the distance gate, if fewer lie inside
/// it) is closer than R_m - a (minus a rounding margin), the list holds the
/// exact answer. Otherwise nearest() falls back to a full k-NN search. Results
/// are identical either way: squared distances use nanoflann's float
/// arithmetic ((dx^2 + dy^2) + dz^2) and ties go to the lower index, as in
/// KdTree3f (bit equality assumes both are compiled alike, e.g. no FMA
/// contraction in one and not the other; default x86-64 flags have none).
/// Measured on KITTI 00 LOAM features: ~6% of queries fall back; cost per
/// 15-candidate query ~1.3x a 5-NN k-d tree query instead of ~2x. Memory: K
/// indices (4 bytes each) per map point; build: one K-NN query per point.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/features/pca.hpp>
#include <semlio/search/kdtree.hpp>

namespace semlio {

/// Which geometric primitive a feature class lies on.
enum class FeatureKind : std::uint8_t {
  kLine,   ///< corner (edge) features: compared by line direction, point-to-line residual
  kPlane,  ///< surface features: compared by normal, point-to-plane residual
};

/// Fewest points that define a primitive: 2 for a line, 3 for a plane.
constexpr int min_points(FeatureKind kind) noexcept { return kind == FeatureKind::kLine ? 2 : 3; }

/// Most points a shape neighbourhood may use (stack buffers in the associators).
inline constexpr int kMaxShapeNeighbours = 32;

/// Longest per-point candidate list (FeatureMap::build).
inline constexpr int kMaxCandidateList = 64;

namespace detail {

/// The unit shape axis of a fitted neighbourhood: the normal for planes, the
/// direction for lines; zero when the fit is unusable (fewer points than the
/// primitive needs, or an invalid fit). A zero axis fails every consistency test.
inline Eigen::Vector3f shape_axis(FeatureKind kind, std::size_t n, const LocalShape& shape) {
  if (!shape.valid || n < static_cast<std::size_t>(min_points(kind))) {
    return Eigen::Vector3f::Zero();
  }
  const Eigen::Vector3d& axis = kind == FeatureKind::kPlane ? shape.normal : shape.direction;
  return axis.cast<float>();
}

/// Axis of the tree points idx[0..n-1] (eq. 3-6).
inline Eigen::Vector3f neighbourhood_axis(const KdTree3f& tree, FeatureKind kind, const std::uint32_t* idx,
                                          std::size_t n) {
  const LocalShape shape =
      fit_local_shape(n, [&](std::size_t i) -> const Eigen::Vector3f& { return tree.point(idx[i]); });
  return shape_axis(kind, n, shape);
}

/// Axis of the neighbourhood of query q in tree: eq. 3-6 over the k nearest
/// tree points (q itself included when it is a tree point). Allocation-free.
inline Eigen::Vector3f neighbourhood_axis(const KdTree3f& tree, FeatureKind kind,
                                          const Eigen::Vector3f& q, int k) {
  std::array<std::uint32_t, kMaxShapeNeighbours> idx{};
  std::array<float, kMaxShapeNeighbours> d2{};
  const std::size_t n = tree.knn(q, static_cast<std::size_t>(k), idx.data(), d2.data());
  return neighbourhood_axis(tree, kind, idx.data(), n);
}

/// Squared distance with nanoflann's L2_Simple arithmetic (float, x then y then z),
/// so that list-based and tree-based candidates compare bit for bit.
inline float nanoflann_sq_distance(const Eigen::Vector3f& q, const Eigen::Vector3f& p) {
  float r = 0.0F;
  const float dx = q.x() - p.x();
  r += dx * dx;
  const float dy = q.y() - p.y();
  r += dy * dy;
  const float dz = q.z() - p.z();
  r += dz * dz;
  return r;
}

/// Inserts (d, i) into the ascending (distance, index) list idx/d2 of size
/// count and capacity k; returns the new size.
inline std::size_t insert_by_distance_index(float d, std::uint32_t i, std::uint32_t* idx, float* d2, std::size_t count,
                                 std::size_t k) {
  const auto less = [](float a, std::uint32_t ia, float b, std::uint32_t ib) { return a < b || (a == b && ia < ib); };
  if (count == k && !less(d, i, d2[k - 1], idx[k - 1])) return count;
  std::size_t j = count < k ? count : k - 1;
  while (j > 0 && less(d, i, d2[j - 1], idx[j - 1])) {
    d2[j] = d2[j - 1];
    idx[j] = idx[j - 1];
    --j;
  }
  d2[j] = d;
  idx[j] = i;
  return count < k ? count + 1 : count;
}

/// Normal consistency (eq. 7, unoriented: acos(|n1.n2|) < threshold, written
/// as |n1.n2| > cos(threshold)). n_scan_map is the scan axis rotated into the
/// map frame. The fast and the reference associator both call this, so their
/// decisions agree bit for bit.
inline bool axes_agree(const Eigen::Vector3d& n_scan_map, const Eigen::Vector3f& n_map,
                       double cos_max_angle) {
  return std::abs(n_scan_map.dot(n_map.cast<double>())) > cos_max_angle;
}

}  // namespace detail

/// A feature map in the map frame with per-point labels and cached shape axes.
/// Thread-safety: const member functions may run concurrently; build() not.
class FeatureMap {
 public:
  /// Empty map of the given kind.
  explicit FeatureMap(FeatureKind kind = FeatureKind::kPlane) : kind_(kind) {}

  /// Replaces the content: points [m, map frame] and labels (same length, or
  /// empty = all unlabeled); builds the k-d tree, caches each point's axis
  /// from its `shape_neighbours` nearest map points (itself included) and, when
  /// candidate_list > 0, its max(candidate_list, shape_neighbours) nearest map
  /// points for nearest(). Throws ValueError on a length mismatch,
  /// shape_neighbours outside [2, 32] or candidate_list outside [0, 64].
  void build(std::vector<Eigen::Vector3f> points, std::vector<Class> labels, int shape_neighbours,
             int candidate_list = 32) {
    if (!labels.empty() && labels.size() != points.size()) {
      throw ValueError("FeatureMap::build: labels has " + std::to_string(labels.size()) +
                       " entries but points has " + std::to_string(points.size()));
    }
    if (shape_neighbours < 2 || shape_neighbours > kMaxShapeNeighbours) {
      throw ValueError("FeatureMap::build: shape_neighbours = " + std::to_string(shape_neighbours) +
                       ", expected 2.." + std::to_string(kMaxShapeNeighbours));
    }
    if (candidate_list < 0 || candidate_list > kMaxCandidateList) {
      throw ValueError("FeatureMap::build: candidate_list = " + std::to_string(candidate_list) + ", expected 0.." +
                       std::to_string(kMaxCandidateList));
    }
    if (labels.empty()) labels.assign(points.size(), Class::kUnlabeled);
    shape_neighbours_ = shape_neighbours;
    labels_ = std::move(labels);
    tree_.build(points);
    const std::size_t n = tree_.size();
    axes_.resize(n);
    // The first shape_neighbours of a longer k-NN query equal the shorter query
    // ((distance, index) order), so the axes match a direct 10-NN fit exactly.
    const std::size_t list =
        candidate_list == 0 ? 0 : std::min<std::size_t>(n, static_cast<std::size_t>(std::max(candidate_list, shape_neighbours)));
    const std::size_t k = std::max(list, static_cast<std::size_t>(shape_neighbours));
    list_len_ = list;
    lists_.resize(n * list);
    list_radius_m_.resize(list == 0 ? 0 : n);
    const bool whole_map = list == n;  // the list holds every map point
    std::array<std::uint32_t, kMaxCandidateList> idx{};
    std::array<float, kMaxCandidateList> d2{};
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t found = tree_.knn(tree_.point(i), k, idx.data(), d2.data());
      axes_[i] = detail::neighbourhood_axis(tree_, kind_, idx.data(),
                                            std::min(found, static_cast<std::size_t>(shape_neighbours)));
      if (list == 0) continue;
      std::copy_n(idx.begin(), list, lists_.begin() + static_cast<std::ptrdiff_t>(i * list));
      list_radius_m_[i] = whole_map ? std::numeric_limits<float>::infinity() : std::sqrt(d2[list - 1]);
    }
  }

  /// The k nearest map points of q within the gate (squared distance <=
  /// max_sq_dist_m2), in (squared distance, index) order, into idx / sq_dist
  /// (each k long, k <= 64); returns their count. Exactly equal to
  /// tree().knn(q, k) cut at the gate; uses the candidate lists when they
  /// provably hold the answer (see the file comment). Allocation-free.
  std::size_t nearest(const Eigen::Vector3f& q, std::size_t k, double max_sq_dist_m2, std::uint32_t* idx,
                      float* sq_dist) const {
    if (k == 0 || empty()) return 0;
    if (list_len_ > 0) {
      std::uint32_t anchor = 0;
      float anchor_d2 = 0.0F;
      tree_.knn(q, 1, &anchor, &anchor_d2);
      const std::uint32_t* list = lists_.data() + static_cast<std::size_t>(anchor) * list_len_;
      const std::vector<Eigen::Vector3f>& pts = tree_.points();
      std::size_t count = 0;
      for (std::size_t j = 0; j < list_len_; ++j) {
        const float d = detail::nanoflann_sq_distance(q, pts[list[j]]);
        if (static_cast<double>(d) <= max_sq_dist_m2) count = detail::insert_by_distance_index(d, list[j], idx, sq_dist, count, k);
      }
      // Everything within `reach` of q lies in the anchor's list, so the list
      // answer is exact when the k-th candidate (or, with fewer, the gate) is
      // nearer than that. The margin covers float rounding of the distances [m].
      const double radius = static_cast<double>(list_radius_m_[anchor]);
      const double reach = radius - std::sqrt(static_cast<double>(anchor_d2));
      const double needed = count == k ? std::sqrt(static_cast<double>(sq_dist[k - 1])) : std::sqrt(max_sq_dist_m2);
      const double margin = 1e-4 + 1e-6 * (std::isfinite(radius) ? radius : 0.0);
      if (needed + margin < reach) return count;
    }
    std::size_t n = tree_.knn(q, k, idx, sq_dist);
    while (n > 0 && !(static_cast<double>(sq_dist[n - 1]) <= max_sq_dist_m2)) --n;
    return n;
  }

  /// Line (corners) or plane (surfaces).
  [[nodiscard]] FeatureKind kind() const noexcept { return kind_; }
  /// Number of map points.
  [[nodiscard]] std::size_t size() const noexcept { return tree_.size(); }
  /// True when the map holds no points.
  [[nodiscard]] bool empty() const noexcept { return tree_.empty(); }
  /// Map points [m, map frame]; indices in FeatureMatches refer to these.
  [[nodiscard]] const std::vector<Eigen::Vector3f>& points() const { return tree_.points(); }
  /// Label of each map point.
  [[nodiscard]] const std::vector<Class>& labels() const noexcept { return labels_; }
  /// Cached unit axis per point (normal or line direction; zero = unusable).
  [[nodiscard]] const std::vector<Eigen::Vector3f>& axes() const noexcept { return axes_; }
  /// The neighbourhood size the axes were fitted over.
  [[nodiscard]] int shape_neighbours() const noexcept { return shape_neighbours_; }
  /// The search structure over points().
  [[nodiscard]] const KdTree3f& tree() const noexcept { return tree_; }
  /// Length of each point's candidate list (0 = lists off).
  [[nodiscard]] std::size_t candidate_list() const noexcept { return list_len_; }

  /// The matched points and labels of one feature, for a residual.
  [[nodiscard]] MatchedPoints gather(const FeatureMatches& m) const {
    MatchedPoints out;
    out.count = m.count;
    for (int j = 0; j < m.count; ++j) {
      const auto k = static_cast<std::size_t>(j);
      out.p_map[k] = tree_.point(m.index[k]).cast<double>();
      out.labels[k] = labels_[m.index[k]];
    }
    return out;
  }

 private:
  FeatureKind kind_;
  int shape_neighbours_ = 10;
  KdTree3f tree_;
  std::vector<Class> labels_;
  std::vector<Eigen::Vector3f> axes_;
  std::size_t list_len_ = 0;
  std::vector<std::uint32_t> lists_;   // list_len_ nearest map points of each point
  std::vector<float> list_radius_m_;   // distance to the last of them (inf: the whole map)
};

}  // namespace semlio
