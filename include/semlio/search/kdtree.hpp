#pragma once
/// \file
/// A static 3D k-d tree over float points: nanoflann underneath, a small
/// owning value type on top. This is the ONE header of semlio that includes
/// <nanoflann.hpp> (Debian ships 1.4.x: SearchParams, pair radius results and
/// an index that keeps a reference to its dataset adaptor), so nanoflann's
/// API drift stays in one place.
///
/// Ownership: KdTree3f COPIES the points passed to build() and owns them; the
/// nanoflann index refers to that owned copy, which lives on the heap beside
/// it, so moving a KdTree3f is cheap and never invalidates the index.
///
/// Order of results: neighbours come sorted by squared distance; points at
/// exactly the same (float) squared distance come in ascending index order.
/// For knn this also decides which of several equally distant points make the
/// cut at the k-th place (the lowest indices win), so results are fully
/// deterministic and equal a brute-force sort by (squared distance, index).

#include <Eigen/Core>

#include <nanoflann.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>

#include <semlio/search/k_best.hpp>
#include <vector>

namespace semlio {

namespace detail {

/// nanoflann dataset adaptor over an owned vector of points.
struct KdPoints {
  std::vector<Eigen::Vector3f> points;

  [[nodiscard]] std::size_t kdtree_get_point_count() const { return points.size(); }
  [[nodiscard]] float kdtree_get_pt(std::uint32_t i, std::size_t dim) const {
    return points[i][static_cast<Eigen::Index>(dim)];
  }
  template <class Box>
  bool kdtree_get_bbox(Box& /*unused*/) const {
    return false;
  }
};

using KdIndex = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, KdPoints>,
                                                    KdPoints, 3, std::uint32_t>;

/// Smallest float strictly greater than d (keeps equal-distance candidates in
/// play: nanoflann only offers points with distance < worstDist()). Inline bit
/// step for the finite non-negative values squared distances take (equal to
/// std::nextafter(d, +inf) there); std::nextafter otherwise.
inline float next_up(float d) {
  if (d >= 0.0F && d < std::numeric_limits<float>::max()) {
    // +0 and -0 compare equal: +0's successor is the smallest denormal either way.
    const std::uint32_t bits = d == 0.0F ? 0U : std::bit_cast<std::uint32_t>(d);
    return std::bit_cast<float>(bits + 1U);
  }
  return std::nextafter(d, std::numeric_limits<float>::infinity());
}

/// k-nearest result set ordered by (squared distance, index), optionally
/// limited to squared distances <= max_sq_dist; no allocation.
class KnnTieResult {
 public:
  using DistanceType = float;
  using IndexType = std::uint32_t;

  KnnTieResult(std::size_t capacity, std::uint32_t* idx, float* dist,
               float max_sq_dist = std::numeric_limits<float>::infinity())
      : idx_(idx),
        dist_(dist),
        capacity_(capacity),
        cap_(max_sq_dist),
        worst_(max_sq_dist < std::numeric_limits<float>::max() ? next_up(max_sq_dist)
                                                                : std::numeric_limits<float>::max()) {}

  [[nodiscard]] std::size_t size() const { return count_; }
  [[nodiscard]] bool full() const { return count_ == capacity_; }

  bool addPoint(float d, std::uint32_t index) {
    if (d > cap_) return true;
    count_ = detail::insert_by_distance_index(d, index, idx_, dist_, count_, capacity_);
    if (full()) worst_ = next_up(dist_[count_ - 1]);  // <= next_up(cap_): accepted d <= cap_
    return true;
  }

  /// Bound nanoflann prunes with: just above the k-th distance once full, else
  /// just above the cap (float max when unlimited).
  [[nodiscard]] float worstDist() const { return worst_; }

 private:
  std::uint32_t* idx_;
  float* dist_;
  std::size_t capacity_;
  std::size_t count_ = 0;
  float cap_;
  float worst_;
};

/// Radius result set collecting the indices with squared distance <= r^2.
class RadiusCollect {
 public:
  using DistanceType = float;
  using IndexType = std::uint32_t;

  RadiusCollect(float r2, std::vector<std::uint32_t>& out) : r2_(r2), out_(out) {}

  [[nodiscard]] std::size_t size() const { return out_.size(); }
  [[nodiscard]] bool full() const { return true; }
  bool addPoint(float d, std::uint32_t index) {
    if (d <= r2_) out_.push_back(index);
    return true;
  }
  [[nodiscard]] float worstDist() const { return next_up(r2_); }

 private:
  float r2_;
  std::vector<std::uint32_t>& out_;
};

/// Squared distance summed exactly as nanoflann's L2_Simple_Adaptor does, so
/// that recomputed distances equal the ones the search compared.
inline float sq_dist_l2(const Eigen::Vector3f& q, const Eigen::Vector3f& p) {
  float s = 0.0F;
  for (int i = 0; i < 3; ++i) {
    const float d = q[i] - p[i];
    s += d * d;
  }
  return s;
}

/// Owned points plus the index referring to them, kept together on the heap.
struct KdTreeImpl {
  KdPoints data;
  std::unique_ptr<KdIndex> index;
};

// GCC 12 reports a false "potential null pointer dereference" deep inside
// nanoflann's index construction (std::vector growth inlined into buildIndex);
// silenced for this one function only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#endif
/// (Re)builds impl.index over impl.data.
inline void build_index(KdTreeImpl& impl, std::size_t max_leaf_size) {
  impl.index = std::make_unique<KdIndex>(3, impl.data,
                                         nanoflann::KDTreeSingleIndexAdaptorParams(max_leaf_size));
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

}  // namespace detail

/// Static k-d tree over 3D float points [m] (any frame; queries use the same).
/// Owns a copy of its points. Thread-safety: concurrent const queries are
/// safe; build() must not run concurrently with anything else.
class KdTree3f {
 public:
  /// Empty tree: every query finds nothing.
  KdTree3f() = default;
  /// Builds over a copy of pts (see build()).
  explicit KdTree3f(const std::vector<Eigen::Vector3f>& pts, std::size_t max_leaf_size = 10)
      : max_leaf_size_(max_leaf_size) {
    build(pts);
  }
  /// Copies the points and rebuilds the index (nanoflann indices cannot be copied).
  KdTree3f(const KdTree3f& other) : max_leaf_size_(other.max_leaf_size_) { build(other.points()); }
  KdTree3f& operator=(const KdTree3f& other) {
    if (this != &other) {
      max_leaf_size_ = other.max_leaf_size_;
      build(other.points());
    }
    return *this;
  }
  KdTree3f(KdTree3f&&) noexcept = default;
  KdTree3f& operator=(KdTree3f&&) noexcept = default;
  ~KdTree3f() = default;

  /// Copies pts and builds the index, replacing any previous content. Reuses
  /// the owned buffer's capacity. O(n log n).
  void build(const std::vector<Eigen::Vector3f>& pts) {
    if (!impl_) impl_ = std::make_unique<detail::KdTreeImpl>();
    impl_->index.reset();
    impl_->data.points.assign(pts.begin(), pts.end());
    if (impl_->data.points.empty()) return;
    detail::build_index(*impl_, max_leaf_size_);
  }

  /// Number of points in the tree.
  [[nodiscard]] std::size_t size() const { return impl_ ? impl_->data.points.size() : 0; }
  /// True when the tree holds no points.
  [[nodiscard]] bool empty() const { return size() == 0; }
  /// The owned points, in the order given to build() (indices refer to it).
  [[nodiscard]] const std::vector<Eigen::Vector3f>& points() const {
    static const std::vector<Eigen::Vector3f> kNone;
    return impl_ ? impl_->data.points : kNone;
  }
  /// Point i (precondition: i < size()).
  [[nodiscard]] const Eigen::Vector3f& point(std::size_t i) const { return impl_->data.points[i]; }

  /// The k nearest points to q: writes min(k, size()) indices and squared
  /// distances [m^2] sorted by (distance, index) into idx / sq_dist (each at
  /// least k long) and returns that count. Allocates nothing.
  std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* idx,
                  float* sq_dist) const {
    if (k == 0 || empty()) return 0;
    detail::KnnTieResult result(k, idx, sq_dist);
    impl_->index->findNeighbors(result, q.data(), nanoflann::SearchParams());
    return result.size();
  }

  /// As knn(q, k, idx, sq_dist), keeping only points with squared distance
  /// <= max_sq_dist [m^2]: exactly knn()'s result cut there, but the search
  /// stops expanding beyond it (cheap for queries far from every point).
  std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* idx, float* sq_dist,
                  float max_sq_dist) const {
    if (k == 0 || empty() || !(max_sq_dist >= 0.0F)) return 0;
    detail::KnnTieResult result(k, idx, sq_dist, max_sq_dist);
    impl_->index->findNeighbors(result, q.data(), nanoflann::SearchParams());
    return result.size();
  }

  /// All points within r_m of q (inclusive, ||p - q|| <= r_m) into out
  /// (cleared first), sorted by (distance, index). Allocates only when out
  /// must grow.
  void radius(const Eigen::Vector3f& q, float r_m, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (empty() || !(r_m >= 0.0F)) return;
    detail::RadiusCollect result(r_m * r_m, out);
    impl_->index->findNeighbors(result, q.data(), nanoflann::SearchParams());
    const auto& pts = impl_->data.points;
    std::sort(out.begin(), out.end(), [&](std::uint32_t a, std::uint32_t b) {
      const float da = detail::sq_dist_l2(q, pts[a]);
      const float db = detail::sq_dist_l2(q, pts[b]);
      return da < db || (da == db && a < b);
    });
  }

  /// As radius(), also returning the squared distances [m^2] (sq_dist[k]
  /// belongs to out[k]).
  void radius(const Eigen::Vector3f& q, float r_m, std::vector<std::uint32_t>& out,
              std::vector<float>& sq_dist) const {
    radius(q, r_m, out);
    sq_dist.clear();
    for (const std::uint32_t i : out) sq_dist.push_back(detail::sq_dist_l2(q, impl_->data.points[i]));
  }

 private:
  std::unique_ptr<detail::KdTreeImpl> impl_;
  std::size_t max_leaf_size_ = 10;
};

}  // namespace semlio
