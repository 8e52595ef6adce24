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
///
/// Leaves (why they are blocks of coordinates): a leaf's up to 16 points are
/// stored as one block [x0..x15 | y0..y15 | z0..z15], so that on x86-64 the
/// leaf loop computes four squared distances per SSE2 instruction and turns
/// the reject test into one mask; only the points that pass it reach the
/// (distance, index) insertion. Lane arithmetic is the scalar one --
/// (dx^2 + dy^2) + dz^2, separate multiply and add -- so distances, and with
/// them the results, are bit for bit those of the scalar loop (the fallback
/// on other targets, or anywhere with SEMLIO_SCALAR_KDTREE defined, which the
/// tests use to run the same comparisons on it). Testing each point against
/// the k-th distance of the leaf's start instead of the current one changes
/// nothing: the insertion re-tests every candidate against the current k-th
/// by (distance, index).
/// With distances this cheap, 16-point leaves beat 8-point ones (fewer nodes
/// visited); the search walks the tree with an explicit stack instead of
/// recursion. Measured on the KITTI surface map (`bench_gauss_newton
/// --benchmark_filter=MapKnn`, idle core, two alternated runs), 8-point
/// scalar leaves -> SSE2 blocks -> explicit stack -> 16-point leaves:
/// 20-NN refills 3.81 -> 3.17 -> 2.85 -> 2.42 ms, 10-NN axes 3.15 -> 2.93 ->
/// 2.74 -> 2.45 ms, 32-NN lists 7.87 -> 7.27 -> 7.10 -> 6.37 ms (32-point
/// leaves: no better than 16).
///
/// First leaf (why its points are sorted as a block): a search meets its
/// first leaf with an empty k-best list and passes it up to 16 points in leaf
/// order -- most of a query's candidates (10-NN axes: up to 16 of the ~21
/// offered). Offered one at a time, each pays the shifts of an insertion and
/// a data-dependent exit of its loop. They are instead made keys, sorted by a
/// branch-free network and taken as one block (KBest::assign_unsorted; 5, 19
/// or 63 compare-exchanges for up to 4, 8 or 16 keys): the entries the offers
/// would have kept. Later leaves meet a list that is (nearly) full and pass it
/// a few points each, where the insertion is cheap (a merge of sorted blocks
/// there measured no better in the frame; the scalar fallback keeps the
/// plain insertion). `MapKnn`, two builds alternated, three runs: 10-NN axes
/// 2.80 -> 2.39 ms, 32-NN lists 7.05 -> 6.40 ms, 20-NN refills 2.64 -> 2.55 ms.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#if defined(__SSE2__) && !defined(SEMLIO_SCALAR_KDTREE)
#define SEMLIO_KDTREE_SSE2 1
#include <emmintrin.h>
#endif

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
    reserve_discarding(work_, pts.size());
    if (&pts != &points_) points_.assign(pts.begin(), pts.end());  // build(points()) rebuilds in place
    // The splits partition (point, index) pairs in one contiguous array: an
    // index array partitioned through a comparator that looks each point up
    // made the build ~1.8x nanoflann's (bench_gauss_newton SmallKdTreeBuild vs KdTreeBuild).
    work_.resize(points_.size());
    for (std::size_t i = 0; i < work_.size(); ++i) work_[i] = Entry{points_[i], static_cast<std::uint32_t>(i)};
    nodes_.clear();
    order_.clear();
    blocks_.clear();
    if (points_.empty()) return;
    // Split nodes hold > kLeaf points and give each side at least a quarter,
    // so every leaf holds >= kLeaf / 4 (or all n): at most 2n / (kLeaf / 4) + 1
    // nodes. Reserved so the vector keeps its capacity from frame to frame.
    reserve_discarding(nodes_, 2 * (points_.size() / (kLeaf / 4) + 1) + 1);
    build_node(0, static_cast<std::uint32_t>(points_.size()));
    order_.resize(work_.size());
    for (std::size_t i = 0; i < work_.size(); ++i) order_[i] = work_[i].index;
    // Each leaf's coordinates as one block (file comment): a contiguous copy
    // also spares the indirection through order_ in the innermost loop.
    std::size_t leaves = 0;
    for (const Node& n : nodes_) leaves += n.left == 0 ? 1U : 0U;
    // Reserved for the most leaves n points can make (each holds >= kLeaf / 4,
    // see above), so that a rebuild of as many points, split differently,
    // does not reallocate; the unused tail is never touched.
    reserve_discarding(blocks_, (points_.size() / (kLeaf / 4) + 1) * kBlock);
    blocks_.resize(leaves * kBlock);
    std::uint32_t block = 0;
    for (Node& n : nodes_) {
      if (n.left != 0) continue;
      float* b = blocks_.data() + static_cast<std::size_t>(block) * kBlock;
      for (std::uint32_t j = 0; j < kLeaf; ++j) {
        // Unused lanes repeat the leaf's first point; they are masked out.
        const Eigen::Vector3f& p = work_[n.begin + (n.begin + j < n.end ? j : 0)].p;
        b[j] = p.x();
        b[kLeaf + j] = p.y();
        b[2 * kLeaf + j] = p.z();
      }
      n.right = block++;
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
    if (k <= detail::kKBestMax) {
      KeyResult r(k, 0.0F);
      search<false>(q, r);
      return r.best.write(idx, sq_dist);
    }
    Result r{idx, sq_dist, k, 0, 0.0F};
    search<false>(q, r);
    return r.count;
  }

  /// As knn(q, k, idx, sq_dist) -- the same result -- where idx[0..known)
  /// already holds points of the tree, e.g. the k nearest of a nearby
  /// earlier query: when known == k, the k nearest of q lie within the
  /// largest of those points' distances from q, so a search bounded there
  /// finds them and prunes from the start (the nearer the earlier query, the
  /// more). Allocates nothing.
  std::size_t knn_seeded(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* idx, float* out_sq_dist,
                         std::size_t known) const {
    if (known != k || k == 0) return knn(q, k, idx, out_sq_dist);
    float bound = 0.0F;
    for (std::size_t j = 0; j < k; ++j) bound = std::max(bound, sq_dist(q, points_[idx[j]]));
    return knn(q, k, idx, out_sq_dist, bound);
  }

  /// As knn(q, k, idx, sq_dist), keeping only points with squared distance
  /// <= max_sq_dist [m^2] (nothing when it is negative or NaN): equal to
  /// KdTree3f's bounded knn. The bound also prunes the search, so a query far
  /// from every point costs little. Allocates nothing.
  std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* idx, float* sq_dist,
                  float max_sq_dist) const {
    if (k == 0 || empty() || !(max_sq_dist >= 0.0F)) return 0;
    if (k <= detail::kKBestMax) {
      KeyResult r(k, max_sq_dist);
      search<true>(q, r);
      return r.best.write(idx, sq_dist);
    }
    Result r{idx, sq_dist, k, 0, max_sq_dist};
    search<true>(q, r);
    return r.count;
  }

 private:
  static constexpr std::uint32_t kLeaf = 16;  // most points per leaf (file comment)
  static_assert(kLeaf % 4 == 0 && kLeaf >= 8 && kLeaf <= 32,
                "leaf lanes come in SSE2 groups of 4 and fit a 32-bit mask; kMaxDepth assumes >= 8");
  static constexpr std::size_t kBlock = 3 * kLeaf;  // floats per leaf block (x, y, z lanes)
  static constexpr std::uint32_t kSplitSample = 15;  // coordinates sampled for a lopsided node's split (<= kLeaf)
  static_assert(kSplitSample <= kLeaf, "a node that splits holds more than kLeaf points to sample from");
  static constexpr std::size_t kMaxDepth = 72;      // most far sides pending at once: see search()

  struct Node {
    std::uint32_t begin;  // range in order_ (leaves) / unused (inner)
    std::uint32_t end;
    std::uint32_t left;   // child node indices (inner); 0 = leaf
    std::uint32_t right;  // right child (inner) / coordinate block (leaf)
    float split;          // splitting value along axis
    std::uint8_t axis;
  };

  // The k best so far, written straight into the caller's arrays (any k).
  struct Result {
    std::uint32_t* idx;
    float* d2;
    std::size_t k;
    std::size_t count;
    float cap;  // largest admitted squared distance (bounded searches only)
    [[nodiscard]] bool full() const { return count == k; }
    [[nodiscard]] float worst() const { return d2[k - 1]; }
    // What a point or subtree must not exceed to matter: the k-th distance
    // once full (<= cap, as every entry is), else the cap.
    [[nodiscard]] float limit() const { return full() ? worst() : cap; }
    // Admits (d, i) when it beats the current k-th by (distance, index).
    void add(float d, std::uint32_t i) { count = detail::insert_by_distance_index(d, i, idx, d2, count, k); }
  };

  // The same for k <= kKBestMax, kept as keys (detail::KBest: cheaper
  // insertions) and written out once at the end. A constructor, not
  // aggregate initialisation: GCC 12 zero-filled the whole struct for
  // `KeyResult r{detail::KBest(k), 0.0F}` -- 544 bytes of keys never read,
  // on every unbounded search (`rep stos` in every 1-NN anchor and 5-NN
  // query).
  struct KeyResult {
    KeyResult(std::size_t k, float c) noexcept : best(k), cap(c) {}
    detail::KBest best;
    float cap;
    [[nodiscard]] bool full() const { return best.full(); }
    [[nodiscard]] float worst() const { return best.worst(); }
    [[nodiscard]] float limit() const { return full() ? worst() : cap; }
    void add(float d, std::uint32_t i) { best.offer(d, i); }
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
    Eigen::Vector3f lo;
    Eigen::Vector3f hi;
#if defined(SEMLIO_KDTREE_SSE2)
    {
      // The node's bounding box, four lanes at a time: an entry is 16 bytes,
      // (x, y, z, index), one load each with the index lane ignored, and two
      // accumulator pairs halve the min / max latency chain. For finite
      // points the boxes, and so the tree, are the scalar loop's. A third of
      // the build's time was this loop; SmallKdTreeBuild (bench_gauss_newton,
      // KITTI surface map, three alternated runs) 0.178 -> 0.138 ms.
      static_assert(sizeof(Entry) == 16);
      const float* base = reinterpret_cast<const float*>(work_.data());
      __m128 lo0 = _mm_loadu_ps(base + 4 * static_cast<std::size_t>(begin));
      __m128 hi0 = lo0;
      __m128 lo1 = lo0;
      __m128 hi1 = lo0;
      std::uint32_t i = begin + 1;
      for (; i + 1 < end; i += 2) {
        const __m128 a0 = _mm_loadu_ps(base + 4 * static_cast<std::size_t>(i));
        const __m128 a1 = _mm_loadu_ps(base + 4 * static_cast<std::size_t>(i + 1));
        lo0 = _mm_min_ps(lo0, a0);
        hi0 = _mm_max_ps(hi0, a0);
        lo1 = _mm_min_ps(lo1, a1);
        hi1 = _mm_max_ps(hi1, a1);
      }
      if (i < end) {
        const __m128 a0 = _mm_loadu_ps(base + 4 * static_cast<std::size_t>(i));
        lo0 = _mm_min_ps(lo0, a0);
        hi0 = _mm_max_ps(hi0, a0);
      }
      alignas(16) std::array<float, 4> l;
      alignas(16) std::array<float, 4> h;
      _mm_store_ps(l.data(), _mm_min_ps(lo0, lo1));
      _mm_store_ps(h.data(), _mm_max_ps(hi0, hi1));
      lo = Eigen::Vector3f(l[0], l[1], l[2]);
      hi = Eigen::Vector3f(h[0], h[1], h[2]);
    }
#else
    lo = work_[begin].p;
    hi = lo;
    for (std::uint32_t i = begin + 1; i < end; ++i) {
      lo = lo.cwiseMin(work_[i].p);
      hi = hi.cwiseMax(work_[i].p);
    }
#endif
    Eigen::Index axis = 0;
    (hi - lo).maxCoeff(&axis);
    const auto a = static_cast<Eigen::Index>(axis);
    // Split the widest extent at its middle (one partition pass, as
    // nanoflann does), unless that leaves less than a quarter on one side:
    // then at the median of an even sample of the node's coordinates (one
    // more pass), and only if that is lopsided too (many equal coordinates)
    // at the median point (std::nth_element: as the only fallback it was a
    // quarter of a KITTI map's build time; ~1.8x the build when used at
    // every node). Each way bounds the depth by log_{4/3}(n); the tree's
    // shape decides its speed, never a result.
    // Left: [begin, mid) with coordinate <= split; right: [mid, end) with >= split.
    float split = 0.5F * (lo[a] + hi[a]);
    const auto first = work_.begin() + begin;
    const auto last = work_.begin() + end;
    const auto partition_at = [&](float s) {
      return static_cast<std::uint32_t>(
          std::partition(first, last, [a, s](const Entry& e) { return e.p[a] < s; }) - work_.begin());
    };
    auto mid = partition_at(split);
    const std::uint32_t quarter = (end - begin) / 4;
    if (mid - begin < quarter || end - mid < quarter) {
      std::array<float, kSplitSample> sample;
      const std::size_t n = end - begin;  // > kLeaf >= kSplitSample
      for (std::size_t j = 0; j < kSplitSample; ++j) sample[j] = work_[begin + j * n / kSplitSample].p[a];
      std::nth_element(sample.begin(), sample.begin() + kSplitSample / 2, sample.end());
      split = sample[kSplitSample / 2];
      mid = partition_at(split);
    }
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

  // Depth-first search from the root with an explicit stack of the far
  // sides still to visit, each with the per-axis squared offsets of its
  // region from q (see the file comment) and the lower bound they sum to.
  // The order is the recursive one -- near side first, the far side tested
  // against the k-th distance only once the near side is done -- and so are
  // the results; the loop spares the calls' register saves. Bounded: only
  // points with squared distance <= r.cap; a template parameter, so that the
  // unbounded search pays nothing for it (one search with an infinite cap
  // made 32-NN list queries 3-9 % slower, MapKnn/list, three alternated runs).
  template <bool Bounded, typename R>
  void search(const Eigen::Vector3f& q, R& r) const {
    struct Pending {
      std::uint32_t node;
      float bound;
      std::array<float, 3> off;
    };
    // A split leaves each side all but a quarter (rounded down) of its
    // parent at most (build_node), so a path from the root to a leaf (which
    // holds up to kLeaf >= 8 points) crosses at most 71 splits in any
    // 32-bit-indexed tree.
    std::array<Pending, kMaxDepth> stack;  // uninitialised: only pushed entries are read
    std::size_t top = 0;
    std::uint32_t node = 0;
    std::array<float, 3> off{};
    for (;;) {
      const Node& n = nodes_[node];
      if (n.left != 0) {
        const float diff = q[n.axis] - n.split;
        // Every far-side point p has |q_a - p_a| >= |diff| (the split lies between them).
        Pending& far = stack[top];
        far.node = diff <= 0.0F ? n.right : n.left;
        far.off = off;
        far.off[n.axis] = std::max(off[n.axis], diff * diff);
        far.bound = (far.off[0] + far.off[1]) + far.off[2];
        // A far side already out of reach stays so (the limit only shrinks):
        // not pushing it skips only what the resume test below would skip,
        // so the leaves visited, their order and the results are unchanged.
        bool keep = true;
        if constexpr (Bounded) {
          keep = far.bound <= r.limit();
        } else {
          keep = !r.full() || far.bound <= r.worst();
        }
        top += keep ? 1U : 0U;
        node = diff <= 0.0F ? n.left : n.right;
        continue;
      }
      // Bounded: only distances up to the cap (the k-th once full) matter;
      // unbounded: everything until full, then up to the k-th.
      float limit = std::numeric_limits<float>::infinity();
      if constexpr (Bounded) {
        limit = r.limit();
      } else {
        if (r.full()) limit = r.worst();
      }
      scan_leaf(n, q, limit, r);
      // Resume at the deepest far side whose bound does not strictly exceed
      // the k-th distance (ties may still enter by index) or, bounded and not
      // yet full, the cap.
      for (;;) {
        if (top == 0) return;
        const Pending& p = stack[--top];
        bool visit = false;
        if constexpr (Bounded) {
          visit = p.bound <= r.limit();
        } else {
          visit = !r.full() || p.bound <= r.worst();
        }
        if (visit) {
          node = p.node;
          off = p.off;
          break;
        }
      }
    }
  }

  // Offers every point of leaf n with squared distance not above `limit`
  // (NaN distances too, as the scalar test `d > limit` lets them pass) to r,
  // in leaf order.
  template <typename R>
  void scan_leaf(const Node& n, const Eigen::Vector3f& q, float limit, R& r) const {
    const float* b = blocks_.data() + static_cast<std::size_t>(n.right) * kBlock;
    const std::uint32_t count = n.end - n.begin;
#if defined(SEMLIO_KDTREE_SSE2)
    alignas(16) std::array<float, kLeaf> d;
    const __m128 qx = _mm_set1_ps(q.x());
    const __m128 qy = _mm_set1_ps(q.y());
    const __m128 qz = _mm_set1_ps(q.z());
    const __m128 lim = _mm_set1_ps(limit);
    unsigned mask = 0;
    for (std::uint32_t g = 0; g < count; g += 4) {
      const __m128 dx = _mm_sub_ps(qx, _mm_loadu_ps(b + g));
      const __m128 dy = _mm_sub_ps(qy, _mm_loadu_ps(b + kLeaf + g));
      const __m128 dz = _mm_sub_ps(qz, _mm_loadu_ps(b + 2 * kLeaf + g));
      const __m128 s = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
      _mm_store_ps(d.data() + g, s);
      mask |= static_cast<unsigned>(_mm_movemask_ps(_mm_cmpngt_ps(s, lim))) << g;
    }
    mask &= count >= 32 ? ~0U : (1U << count) - 1U;
    if constexpr (std::is_same_v<R, KeyResult>) {
      if (r.best.size() == 0) {
        // The first leaf of a search (file comment): its passing points taken
        // as one block.
        static_assert(kLeaf <= 16, "KBest::assign_unsorted takes at most 16 keys");
        alignas(16) std::array<std::uint64_t, 16> keys;
        std::size_t m = 0;
        for (unsigned bits = mask; bits != 0; bits &= bits - 1U) {
          const auto j = static_cast<std::uint32_t>(std::countr_zero(bits));
          keys[m++] = detail::distance_index_key(d[j], order_[n.begin + j]);
        }
        r.best.assign_unsorted(keys.data(), m);
        return;
      }
    }
    while (mask != 0) {
      const auto j = static_cast<std::uint32_t>(std::countr_zero(mask));
      mask &= mask - 1U;
      r.add(d[j], order_[n.begin + j]);
    }
#else
    for (std::uint32_t j = 0; j < count; ++j) {
      const Eigen::Vector3f p(b[j], b[kLeaf + j], b[2 * kLeaf + j]);
      const float d = sq_dist(q, p);
      if (d > limit) continue;
      r.add(d, order_[n.begin + j]);
    }
#endif
  }

  struct Entry {
    Eigen::Vector3f p;
    std::uint32_t index;
  };

  std::vector<Eigen::Vector3f> points_;
  std::vector<Entry> work_;  // build(): the (point, index) pairs being partitioned
  std::vector<std::uint32_t> order_;
  std::vector<float> blocks_;  // per leaf: x, y, z lanes of its points (kBlock floats)
  std::vector<Node> nodes_;
};

}  // namespace semlio
