#pragma once
/// \file
/// SmallKdTree3f: a k-d tree that reuses its buffers, so that a rebuild
/// allocates nothing once they have grown -- unlike KdTree3f, whose nanoflann
/// index allocates its nodes anew on every build. Rebuilt often: per frame
/// for the scan's features, per keyframe for FeatureMap's maps.
///
/// Results equal KdTree3f::knn (also its bounded form) bit for bit: the exact
/// k nearest by (squared distance, index), distances summed as nanoflann's L2
/// metric does ((dx^2 + dy^2) + dz^2 in float). Pruning is exact too: a
/// subtree is skipped only when its lower bound exceeds the current k-th
/// distance (or, in a bounded query not yet full, the bound). The lower bound
/// keeps, per axis, the squared offset c_a = fl((q_a - s)^2) of q from the
/// nearest splitting plane crossed on that axis (|q_a - p_a| >= |q_a - s| for
/// every point beyond it) and sums them in the metric's order,
/// fl(fl(c_x + c_y) + c_z): rounding is monotone, so the bound never exceeds
/// the float distance of any point in the subtree.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <semlio/core/buffers.hpp>
#include <semlio/search/k_best.hpp>

namespace semlio {

/// Static 3D k-d tree over a copy of the points, rebuilt in place with no
/// allocation once its buffers have grown. Const queries are thread-safe.
class SmallKdTree3f {
 public:
  /// Copies pts and builds the tree, replacing any previous content. O(n log n).
  void build(const std::vector<Eigen::Vector3f>& pts) {
    // Headroom (core/buffers.hpp): a map or scan a little larger than the
    // last one does not reallocate every buffer.
    if (&pts != &points_) reserve_discarding(points_, pts.size());
    reserve_discarding(order_, pts.size());
    reserve_discarding(leaf_points_, pts.size());
    reserve_discarding(work_, pts.size());
    if (&pts != &points_) points_.assign(pts.begin(), pts.end());  // build(points()) rebuilds in place
    // The splits partition (point, index) pairs in one contiguous array: an
    // index array partitioned through a comparator that looks each point up
    // made the build ~1.8x nanoflann's (README, frame time).
    work_.resize(points_.size());
    for (std::size_t i = 0; i < work_.size(); ++i) work_[i] = Entry{points_[i], static_cast<std::uint32_t>(i)};
    nodes_.clear();
    order_.clear();
    leaf_points_.clear();
    if (points_.empty()) return;
    // Split nodes hold > kLeaf points and give each side at least a quarter,
    // so every leaf holds >= kLeaf / 4 (or all n): at most 2n / (kLeaf / 4) + 1
    // nodes. Reserved so the vector keeps its capacity from frame to frame.
    reserve_discarding(nodes_, 2 * (points_.size() / (kLeaf / 4) + 1) + 1);
    build_node(0, static_cast<std::uint32_t>(points_.size()));
    // Leaves scan their points in tree order: a contiguous copy spares the
    // indirection (and its cache misses) in the innermost loop.
    order_.resize(work_.size());
    leaf_points_.resize(work_.size());
    for (std::size_t i = 0; i < work_.size(); ++i) {
      order_[i] = work_[i].index;
      leaf_points_[i] = work_[i].p;
    }
  }

  /// Number of points.
  [[nodiscard]] std::size_t size() const noexcept { return points_.size(); }
  /// True when empty.
  [[nodiscard]] bool empty() const noexcept { return points_.empty(); }
  /// The owned points, in the order given to build() (indices refer to it).
  [[nodiscard]] const std::vector<Eigen::Vector3f>& points() const noexcept { return points_; }
  /// Point i (precondition: i < size()).
  [[nodiscard]] const Eigen::Vector3f& point(std::size_t i) const { return points_[i]; }
  /// Point indices in leaf order (neighbours in space are neighbours here):
  /// querying the points in this order keeps the tree's hot nodes in cache.
  [[nodiscard]] const std::vector<std::uint32_t>& leaf_order() const noexcept { return order_; }

  /// The k nearest points to q sorted by (squared distance, index) into idx /
  /// sq_dist (each at least k long); returns min(k, size()). Equal to
  /// KdTree3f::knn on the same points. Allocates nothing.
  std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* idx, float* sq_dist) const {
    if (k == 0 || empty()) return 0;
    Result r{idx, sq_dist, k, 0, 0.0F};
    std::array<float, 3> off{};
    search<false>(0, q, r, off);
    return r.count;
  }

  /// As knn(q, k, idx, sq_dist), keeping only points with squared distance
  /// <= max_sq_dist [m^2] (nothing when it is negative or NaN): equal to
  /// KdTree3f's bounded knn. The bound also prunes the search, so a query far
  /// from every point costs little. Allocates nothing.
  std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* idx, float* sq_dist,
                  float max_sq_dist) const {
    if (k == 0 || empty() || !(max_sq_dist >= 0.0F)) return 0;
    Result r{idx, sq_dist, k, 0, max_sq_dist};
    std::array<float, 3> off{};
    search<true>(0, q, r, off);
    return r.count;
  }

 private:
  static constexpr std::uint32_t kLeaf = 8;

  struct Node {
    std::uint32_t begin;  // range in order_ (leaves) / unused (inner)
    std::uint32_t end;
    std::uint32_t left;   // child node indices (inner); 0 = leaf
    std::uint32_t right;
    float split;          // splitting value along axis
    std::uint8_t axis;
  };

  struct Result {
    std::uint32_t* idx;
    float* d2;
    std::size_t k;
    std::size_t count;
    float cap;  // largest admitted squared distance (bounded searches only)
    [[nodiscard]] bool full() const { return count == k; }
    // What a point or subtree must not exceed to matter: the k-th distance
    // once full (<= cap, as every entry is), else the cap.
    [[nodiscard]] float limit() const { return full() ? d2[k - 1] : cap; }
    // Admits (d, i) when it beats the current k-th by (distance, index).
    void add(float d, std::uint32_t i) { count = detail::insert_by_distance_index(d, i, idx, d2, count, k); }
  };

  static float sq_dist(const Eigen::Vector3f& q, const Eigen::Vector3f& p) {
    float s = 0.0F;
    for (int a = 0; a < 3; ++a) {
      const float d = q[a] - p[a];
      s += d * d;
    }
    return s;
  }

  std::uint32_t build_node(std::uint32_t begin, std::uint32_t end) {
    const auto self = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back(Node{begin, end, 0, 0, 0.0F, 0});
    if (end - begin <= kLeaf) return self;
    Eigen::Vector3f lo = work_[begin].p;
    Eigen::Vector3f hi = lo;
    for (std::uint32_t i = begin + 1; i < end; ++i) {
      lo = lo.cwiseMin(work_[i].p);
      hi = hi.cwiseMax(work_[i].p);
    }
    Eigen::Index axis = 0;
    (hi - lo).maxCoeff(&axis);
    const auto a = static_cast<Eigen::Index>(axis);
    // Split the widest extent at its middle (one partition pass, as
    // nanoflann does), unless that leaves less than a quarter on one side:
    // then at the median point (std::nth_element, ~1.8x the build time when
    // used at every node), which bounds the depth by log_{4/3}(n).
    // Left: [begin, mid) with coordinate <= split; right: [mid, end) with >= split.
    float split = 0.5F * (lo[a] + hi[a]);
    const auto first = work_.begin() + begin;
    const auto last = work_.begin() + end;
    auto mid = static_cast<std::uint32_t>(
        std::partition(first, last, [a, split](const Entry& e) { return e.p[a] < split; }) - work_.begin());
    const std::uint32_t quarter = (end - begin) / 4;
    if (mid - begin < quarter || end - mid < quarter) {
      mid = begin + (end - begin) / 2;
      std::nth_element(first, work_.begin() + mid, last, [a](const Entry& x, const Entry& y) { return x.p[a] < y.p[a]; });
      split = work_[mid].p[a];
    }
    const std::uint32_t left = build_node(begin, mid);
    const std::uint32_t right = build_node(mid, end);
    Node& n = nodes_[self];
    n.left = left;
    n.right = right;
    n.split = split;
    n.axis = static_cast<std::uint8_t>(axis);
    return self;
  }

  // off: per-axis squared offsets of the subtree's region from q (see the
  // file comment). Bounded: only points with squared distance <= r.cap; a
  // template parameter, so that the unbounded search pays nothing for it
  // (one search with an infinite cap made 32-NN list queries 3-9 % slower,
  // MapKnn/list, three alternated runs).
  template <bool Bounded>
  void search(std::uint32_t node, const Eigen::Vector3f& q, Result& r, std::array<float, 3>& off) const {
    const Node& n = nodes_[node];
    if (n.left == 0) {
      for (std::uint32_t i = n.begin; i < n.end; ++i) {
        const float d = sq_dist(q, leaf_points_[i]);
        // Cheap reject before the (distance, index) insertion: a full list
        // admits only distances up to its k-th (ties decided by index there),
        // a bounded one only distances up to the cap.
        if constexpr (Bounded) {
          if (d > r.limit()) continue;
        } else {
          if (r.full() && d > r.d2[r.k - 1]) continue;
        }
        r.add(d, order_[i]);
      }
      return;
    }
    const float diff = q[n.axis] - n.split;
    const std::uint32_t near = diff <= 0.0F ? n.left : n.right;
    const std::uint32_t far = diff <= 0.0F ? n.right : n.left;
    search<Bounded>(near, q, r, off);
    // Every far-side point p has |q_a - p_a| >= |diff| (the split lies between them).
    const float saved = off[n.axis];
    const float cut = diff * diff;
    off[n.axis] = std::max(saved, cut);
    const float bound = (off[0] + off[1]) + off[2];
    // Skip only when the bound strictly exceeds the k-th distance (ties may
    // still enter by index) or, bounded and not yet full, the cap.
    if constexpr (Bounded) {
      if (bound <= r.limit()) search<Bounded>(far, q, r, off);
    } else {
      if (!r.full() || bound <= r.d2[r.k - 1]) search<Bounded>(far, q, r, off);
    }
    off[n.axis] = saved;
  }

  struct Entry {
    Eigen::Vector3f p;
    std::uint32_t index;
  };

  std::vector<Eigen::Vector3f> points_;
  std::vector<Entry> work_;  // build(): the (point, index) pairs being partitioned
  std::vector<std::uint32_t> order_;
  std::vector<Eigen::Vector3f> leaf_points_;  // points_[order_[i]], for the leaf loops
  std::vector<Node> nodes_;
};

}  // namespace semlio
