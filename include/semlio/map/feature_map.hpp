#pragma once
/// \file
/// One searchable feature map (corners or surfaces) in the map frame: points,
/// their labels, a k-d tree, and the shape axis of each point (surface normal
/// or line direction, eq. 3-6 over its nearest map points), so that
/// Algorithm 1 never refits a map neighbourhood per frame.
///
/// Lazy shapes (why a keyframe's map rebuild is cheap): build() only stores
/// the points and builds the k-d tree. A point's axis and its candidate list
/// (below) are computed the first time an associator reads them and are kept
/// until the next build(): most map points are never read (NearestK reads
/// none; Algorithm 1 reads the neighbourhoods of the current scan's features
/// only). The values are exactly those an eager build would store -- the same
/// k-NN query ((distance, index) order) and the same fit -- so laziness
/// changes the cost, never a result. The caches are filled from const member
/// functions through per-point atomic states (empty -> busy -> ready): one
/// thread publishes each entry, any other thread that finds it not ready
/// computes the same value for itself, so concurrent const queries stay safe.
///
/// The k-d tree is a SmallKdTree3f, not the nanoflann-backed KdTree3f: it
/// rebuilds in its own buffers, so that (with build() copying its inputs into
/// reused members) a keyframe's map rebuild allocates nothing once the
/// buffers have grown, where nanoflann allocates its index anew. Its k-NN
/// results, bounded or not, equal KdTree3f's bit for bit.
///
/// Queries without a NearestCache (one association at one pose: the
/// association kernel, registration, loop verification) are, by default, a
/// k-d tree k-NN search bounded at the distance gate: only candidates inside
/// the gate matter, and the bound prunes the rest. Since SmallKdTree3f that
/// is also the fastest exact answer on sparse maps: on the 2.6 GHz EPYC VM
/// (bench_association, six alternated rounds) a 15-NN inside 1 m took 0.91
/// ms for the 2 939 KITTI corners against 1.16 ms through the lists below,
/// 0.22 against 0.32 ms for the simulated corners; on surfaces the two were
/// within 2 % (7 % in the tree's favour on the synthetic street), on the
/// synthetic street corners the lists were 31 % faster (0.085 against
/// 0.124 ms, a 1 712-point map). LocalMap therefore builds without lists
/// (and without a voxel index, which only anchors them) unless
/// LocalMapConfig::candidate_list asks for them.
///
/// Candidate lists (optional; build()'s candidate_list > 0): per map point
/// m, its K nearest map points (K = 32 when asked) and the distance R_m to
/// the K-th. A query q then needs only an anchor m near q
/// (distance a = |q - m|; any map point will do, a nearer one passes the test
/// below more often): the point of q's voxel, found by one binary search when
/// the map comes with a VoxelIndex (LocalMap's maps do when lists are on;
/// 81 % of surface and 29 % of corner queries on the simulated urban pair),
/// else q's nearest inside the gate by a bounded 1-NN k-d tree search. By
/// the triangle inequality every map point within R_m - a of q is in m's list, so when the
/// k-th candidate found in the list (or the distance gate, if fewer lie inside
/// it) is closer than R_m - a (minus a rounding margin), the list holds the
/// exact answer. Otherwise nearest() falls back to a full k-NN search. Results
/// are identical either way: squared distances use the k-d tree's float
/// arithmetic ((dx^2 + dy^2) + dz^2, nanoflann's order) and ties go to the
/// lower index, as in the tree (bit equality assumes both are compiled alike,
/// e.g. no FMA contraction in one and not the other; default x86-64 flags
/// have none).
/// The list also keeps each entry's distance from m (ascending), so its scan
/// stops at the first entry that cannot come nearer to q than the k-th found
/// (or the gate): on a sparse corner map the 32 entries reach metres beyond
/// the 1 m gate. Measured on KITTI 00 LOAM features: ~6% of queries fall
/// back. Memory: K indices and K distances (4 bytes each) and a voxel key (8
/// bytes) per map point, plus one state byte per point for the axis and one
/// for the list.
///
/// Repeated queries (NearestCache): Gauss-Newton re-associates the same
/// features at poses that differ by centimetres, then millimetres. A cache
/// slot keeps, per feature, its own L nearest map points at the position q0
/// where it was last filled, and the distance R0 to the L-th. At a new
/// position q (moved by d = |q - q0|) every map point within R0 - d of q is in
/// that list (triangle inequality), so the same exactness test as above
/// applies with q0 as the anchor: when it holds, the answer costs L distance
/// evaluations and no tree search; otherwise the slot is refilled by one
/// L-NN query at q, whose first k entries are the exact answer.
/// A slot keeps its points' coordinates too, as one block of x, y and z lanes
/// (the k-d tree's leaf layout), so a hit computes all L distances four at a
/// time with no lookup into the map's points, then offers those inside the
/// gate -- nearly in order, as the list ascends from q0. It replaced a scalar
/// scan of the map's points that stopped at the first entry the triangle
/// inequality put out of reach (entry distances from q0 kept for that):
/// bench_frame_time, full preset, snippet, core 1, five alternated rounds in
/// each order: 32.00 -> 31.55 ms, every frame 0.3-0.9 ms faster. Memory: 3 x
/// L floats more per slot, and no distances. Distances are the tree's
/// (dx^2 + dy^2) + dz^2 in float, lane for lane.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <thread>
#include <string>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/core/buffers.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/features/pca.hpp>
#include <semlio/search/k_best.hpp>
#include <semlio/search/small_kdtree.hpp>

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
/// The queries' stack buffers of this (or kMaxShapeNeighbours) length are
/// left uninitialised (`std::array<T, N> a;`, not `a{}`): only the entries a
/// search wrote are read, and zeroing 256-512 bytes per query was 14 % of
/// FeatureMap::nearest's samples on the street-corners kernel (perf).
inline constexpr int kMaxCandidateList = 64;

/// How far beyond the distance gate a NearestCache refill searches [m]: a
/// feature may move this far (less the rounding margin) before a list whose
/// L-th entry lies beyond the bound must be refilled. Small, because a
/// bounded k-d tree query that finds fewer than L points must search its
/// whole ball: 0.1 instead of 0.5 m cut the full preset's instructions by
/// 1.9 % on the KITTI raw snippet and 2.0 % on the main job's drive (the
/// baseline's by 1.2 %) with the same hit and refill counts (callgrind).
inline constexpr double kNearestCacheSlackM = 0.1;

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

/// How neighbourhood_axis fits: the full eq. 3-6 fit (fit_local_shape, the
/// literal form NormalConsistencyReference reads) or only the one axis
/// (fit_local_axis: bit for bit the same vector, for less).
enum class AxisFit : std::uint8_t { kAxisOnly, kFullShape };

/// Axis of the tree points idx[0..n-1] (eq. 3-6). Tree: KdTree3f or
/// SmallKdTree3f (anything with point(i) and knn(q, k, idx, sq_dist)).
template <typename Tree>
Eigen::Vector3f neighbourhood_axis(const Tree& tree, FeatureKind kind, const std::uint32_t* idx, std::size_t n,
                                   AxisFit fit = AxisFit::kAxisOnly) {
  const auto point_at = [&](std::size_t i) -> const Eigen::Vector3f& { return tree.point(idx[i]); };
  if (fit == AxisFit::kFullShape) return shape_axis(kind, n, fit_local_shape(n, point_at));
  Eigen::Vector3d axis;
  if (n < static_cast<std::size_t>(min_points(kind)) ||
      !fit_local_axis(n, point_at, kind == FeatureKind::kPlane ? EigenEnd::kSmallest : EigenEnd::kLargest, axis)) {
    return Eigen::Vector3f::Zero();
  }
  return axis.cast<float>();
}

/// Axis of the neighbourhood of query q in tree: eq. 3-6 over the k nearest
/// tree points (q itself included when it is a tree point). Allocation-free.
template <typename Tree>
Eigen::Vector3f neighbourhood_axis(const Tree& tree, FeatureKind kind, const Eigen::Vector3f& q, int k,
                                   AxisFit fit = AxisFit::kAxisOnly) {
  std::array<std::uint32_t, kMaxShapeNeighbours> idx;  // uninitialised (see kMaxCandidateList)
  std::array<float, kMaxShapeNeighbours> d2;
  const std::size_t n = tree.knn(q, static_cast<std::size_t>(k), idx.data(), d2.data());
  return neighbourhood_axis(tree, kind, idx.data(), n, fit);
}

/// Squared distance with nanoflann's L2_Simple arithmetic (float, x then y then
/// z), which SmallKdTree3f and KdTree3f share, so that list-based and
/// tree-based candidates compare bit for bit.
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

/// Largest float c with (double)c <= max_sq_dist (inf when unlimited), so that
/// for a float squared distance d: d <= c exactly when (double)d <= max_sq_dist.
inline float float_gate(double max_sq_dist) {
  if (!(max_sq_dist < static_cast<double>(std::numeric_limits<float>::max()))) {
    return max_sq_dist >= 0.0 ? std::numeric_limits<float>::infinity() : -1.0F;
  }
  float c = static_cast<float>(max_sq_dist);
  if (static_cast<double>(c) > max_sq_dist) c = std::nextafter(c, -std::numeric_limits<float>::infinity());
  return c;
}

/// The reference's voxel key of p (leaf given as its inverse [1/m]); false
/// for the points it drops (non-finite, beyond +-2^20 leaves).
inline bool reference_voxel_key(const Eigen::Vector3f& p, double inv_leaf, std::uint64_t& key) {
  constexpr double kHalf = 1048576.0;
  if (!p.allFinite()) return false;
  key = 0;
  for (int a = 0; a < 3; ++a) {
    const double v = std::floor(static_cast<double>(p[a]) * inv_leaf);
    if (!(v >= -kHalf && v < kHalf)) return false;
    key = (key << 21U) | static_cast<std::uint64_t>(static_cast<std::int64_t>(v) + (std::int64_t{1} << 20));
  }
  return true;
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

class FeatureMap;

/// The voxel grid a map's points come from, one point per voxel (LocalMap's
/// downsampled maps): the key of each point's voxel (detail::reference_voxel_key
/// on a grid of edge leaf_m anchored at the origin), strictly ascending along
/// the points. With it FeatureMap anchors a query at the point of its voxel by
/// a binary search instead of a 1-NN k-d tree search (file comment).
struct VoxelIndex {
  double leaf_m = 0.0;               ///< voxel edge [m]; 0 = no index
  std::vector<std::uint64_t> keys;   ///< one per map point, strictly ascending
};

namespace detail {

/// A process-wide unique id for each FeatureMap::build() (never 0), so that a
/// NearestCache can tell a rebuilt map -- even one at the same address -- from
/// the build its lists refer to.
inline std::uint64_t next_map_build_id() {
  static std::atomic<std::uint64_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed) + 1;
}

/// A process-wide unique id for each set of queries a NearestCache serves
/// (an associator's bound scan; never 0): NearestCache::bind_queries.
inline std::uint64_t next_query_set_id() {
  static std::atomic<std::uint64_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed) + 1;
}

}  // namespace detail

/// Per-feature candidate lists reused across repeated nearest() queries of
/// the same features (see the file comment). One slot per feature; bound to
/// one map build (a rebuilt or different map empties it). Not thread-safe:
/// one cache per thread. Reuses its buffers (no allocation once grown).
class NearestCache {
 public:
  /// Empties every slot and sizes the cache for `slots` features with lists
  /// of `list_len` map points (list_len <= kMaxCandidateList).
  void reset(std::size_t slots, std::size_t list_len) {
    list_len_ = std::min<std::size_t>(list_len, static_cast<std::size_t>(kMaxCandidateList));
    slots_ = slots;
    q0_.resize(slots);
    radius_m_.assign(slots, -1.0F);
    count_.resize(slots);
    lists_.resize(slots * list_len_);
    list_xyz_.resize(slots * 3 * padded_len());
    generation_ = 0;
    queries_ = 0;
    hits_ = 0;
    refills_ = 0;
  }
  /// Says that the slots now stand for the queries of `query_set` (e.g.
  /// detail::next_query_set_id() of a newly bound scan). When that differs
  /// from the last call, every slot is emptied: a list filled for another
  /// scan's feature i is still exact for this one's, but lies elsewhere, so
  /// its test would nearly always fail after a scan of up to its L entries.
  void bind_queries(std::uint64_t query_set) {
    if (query_set == queries_) return;
    std::fill(radius_m_.begin(), radius_m_.end(), -1.0F);
    queries_ = query_set;
  }
  /// Empties every slot (keeps the sizes).
  void clear() { reset(slots_, list_len_); }
  /// Number of slots.
  [[nodiscard]] std::size_t slots() const noexcept { return slots_; }
  /// Map points per slot.
  [[nodiscard]] std::size_t list_len() const noexcept { return list_len_; }
  /// Queries answered from a slot's list / by a k-d tree refill, since the last reset (diagnostics).
  [[nodiscard]] std::size_t hits() const noexcept { return hits_; }
  /// See hits().
  [[nodiscard]] std::size_t refills() const noexcept { return refills_; }

 private:
  friend class FeatureMap;
  std::size_t slots_ = 0;
  std::size_t list_len_ = 0;
  std::vector<Eigen::Vector3f> q0_;       // where each slot was filled [m, map frame]
  std::vector<float> radius_m_;           // distance to its last list entry (inf: whole map; < 0: empty)
  std::vector<std::uint8_t> count_;       // entries in the list
  std::vector<std::uint32_t> lists_;      // list_len_ map indices per slot, (distance, index) order at q0
  std::vector<float> list_xyz_;           // their coordinates: per slot x, y, z lanes of padded_len() (file comment)
  std::uint64_t generation_ = 0;          // FeatureMap build id the lists refer to (0: none)
  std::uint64_t queries_ = 0;             // bind_queries() id the slots stand for (0: none)
  std::size_t hits_ = 0;
  std::size_t refills_ = 0;

  // Lanes per coordinate of a slot's block: list_len_ rounded up to whole
  // groups of four (the lanes past the count hold zeros and are never read).
  [[nodiscard]] std::size_t padded_len() const noexcept { return (list_len_ + 3U) & ~std::size_t{3}; }
};

/// A feature map in the map frame with per-point labels and lazily cached
/// shape axes and candidate lists (see the file comment).
/// Thread-safety: const member functions may run concurrently (the lazy
/// caches are filled through atomic per-point states); build() not.
class FeatureMap {
 public:
  /// Empty map of the given kind.
  explicit FeatureMap(FeatureKind kind = FeatureKind::kPlane) : kind_(kind) {}

  /// Replaces the content: points [m, map frame] and labels (same length, or
  /// empty = all unlabeled); builds the k-d tree. Each point's axis (from its
  /// `shape_neighbours` nearest map points, itself included) and, when
  /// candidate_list > 0, its list of max(candidate_list, shape_neighbours)
  /// nearest map points for nearest() are computed on first use (file
  /// comment). `voxels` (optional) says which voxel each point stands for.
  /// Throws ValueError on a length mismatch, shape_neighbours outside
  /// [2, 32], candidate_list outside [0, 64], or voxel keys that do not
  /// ascend strictly. Copies its inputs into buffers it reuses: once they
  /// have grown, a rebuild allocates nothing.
  void build(const std::vector<Eigen::Vector3f>& points, const std::vector<Class>& labels, int shape_neighbours,
             int candidate_list = 0, const VoxelIndex& voxels = {}) {
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
    if (voxels.leaf_m > 0.0 || !voxels.keys.empty()) {
      const bool ascending =
          std::adjacent_find(voxels.keys.begin(), voxels.keys.end(), std::greater_equal<>()) == voxels.keys.end();
      if (!(voxels.leaf_m > 0.0) || !std::isfinite(voxels.leaf_m) || voxels.keys.size() != points.size() ||
          !ascending) {
        throw ValueError("FeatureMap::build: voxel index with leaf " + std::to_string(voxels.leaf_m) + " m and " +
                         std::to_string(voxels.keys.size()) + " keys for " + std::to_string(points.size()) +
                         " points; expected a leaf > 0 and one strictly ascending key per point");
      }
    }
    // Copies into the members' own buffers (assign keeps their capacity), so
    // that a rebuild no larger than an earlier one allocates nothing.
    // Rebuilds of a map that grows by a little each time (keyframes) would
    // otherwise reallocate every buffer every time (core/buffers.hpp).
    if (&labels != &labels_) reserve_discarding(labels_, points.size());
    if (&voxels.keys != &voxel_keys_) reserve_discarding(voxel_keys_, voxels.keys.size());
    if (labels.empty()) {
      labels_.assign(points.size(), Class::kUnlabeled);
    } else if (&labels != &labels_) {  // build(points(), labels(), ...) keeps them
      labels_.assign(labels.begin(), labels.end());
    }
    voxel_keys_.assign(voxels.keys.begin(), voxels.keys.end());
    voxel_inv_leaf_ = voxels.leaf_m > 0.0 ? 1.0 / voxels.leaf_m : 0.0;
    shape_neighbours_ = shape_neighbours;
    tree_.build(points);
    const std::size_t n = tree_.size();
    // The first shape_neighbours of a longer k-NN query equal the shorter query
    // ((distance, index) order), so a list query also yields the exact axis.
    list_len_ = candidate_list == 0
                    ? 0
                    : std::min<std::size_t>(n, static_cast<std::size_t>(std::max(candidate_list, shape_neighbours)));
    reserve_discarding(axes_, n);
    reserve_discarding(axis_state_, n);
    reserve_discarding(lists_, n * list_len_);
    reserve_discarding(list_dist_m_, n * list_len_);
    reserve_discarding(list_radius_m_, list_len_ == 0 ? 0 : n);
    reserve_discarding(list_state_, list_len_ == 0 ? 0 : n);
    axes_.resize(n);
    axis_state_.assign(n, kEmpty);
    lists_.resize(n * list_len_);
    list_dist_m_.resize(n * list_len_);
    list_radius_m_.resize(list_len_ == 0 ? 0 : n);
    list_state_.assign(list_len_ == 0 ? 0 : n, kEmpty);
    generation_ = detail::next_map_build_id();
  }

  /// The k nearest map points of q within the gate (squared distance <=
  /// max_sq_dist_m2), in (squared distance, index) order, into idx / sq_dist
  /// (each k long, k <= 64); returns their count. Exactly equal to
  /// tree().knn(q, k) cut at the gate; uses the candidate lists when they
  /// provably hold the answer (see the file comment). Allocation-free.
  std::size_t nearest(const Eigen::Vector3f& q, std::size_t k, double max_sq_dist_m2, std::uint32_t* idx,
                      float* sq_dist) const {
    if (k == 0 || empty()) return 0;
    if (list_len_ > 0 && k <= detail::kKBestMax) {
      const float gate_f = detail::float_gate(max_sq_dist_m2);
      std::uint32_t anchor = 0;
      float anchor_d2 = 0.0F;
      if (!anchor_of(q, gate_f, anchor, anchor_d2)) return 0;  // no map point inside the gate
      std::array<std::uint32_t, kMaxCandidateList> own;
      std::array<float, kMaxCandidateList> own_dist;
      float radius_f = 0.0F;
      const float* dist_m = nullptr;
      const std::uint32_t* list = candidates_of(anchor, own.data(), own_dist.data(), radius_f, dist_m);
      const std::vector<Eigen::Vector3f>& pts = tree_.points();
      const auto radius = static_cast<double>(radius_f);
      const double anchor_m = std::sqrt(static_cast<double>(anchor_d2));
      // The margin covers float rounding of the distances [m].
      const double margin = 1e-4 + 1e-6 * (std::isfinite(radius) ? radius : 0.0);
      const double anchor_margin = anchor_m + margin;
      // The list ascends in distance from the anchor, so entry j and every
      // later one lie at least dist_m[j] - anchor_m from q (triangle
      // inequality): past the k-th distance found (or the gate) none can
      // enter the answer. On sparse maps (corners) the 32 entries reach far
      // beyond the gate and most are never evaluated. The test runs on the
      // float entry against a float stop a little beyond that bound, so it
      // never stops before it (evaluating an entry more changes nothing: it
      // fails the gate or the k-th distance); it is updated only when the
      // k-th distance shrinks. With the anchor search bounded at the gate
      // (anchor_of), against a double test per entry and an unbounded 1-NN:
      // KITTI corners 1.19 -> 1.12-1.15 ms, simulated corners 0.36 -> 0.32
      // ms, surfaces within 2-4 % (bench_association, lists on, four
      // alternated rounds).
      const auto stop_for = [anchor_margin](double limit) {
        return static_cast<float>((anchor_margin + std::sqrt(limit)) * (1.0 + 1e-6) + 1e-6);
      };
      float stop = stop_for(max_sq_dist_m2);  // for the gate until k are found
      detail::KBest best(k);
      for (std::size_t j = 0; j < list_len_ && !(dist_m[j] > stop); ++j) {
        const float d = detail::nanoflann_sq_distance(q, pts[list[j]]);
        if (d <= gate_f) {
          best.offer(d, list[j]);
          if (best.full()) stop = stop_for(static_cast<double>(best.worst()));
        }
      }
      // Everything within `reach` of q lies in the anchor's list, so the list
      // answer is exact when the k-th candidate (or, with fewer, the gate) is
      // nearer than that.
      const double reach = radius - anchor_m;
      const double needed =
          best.full() ? std::sqrt(static_cast<double>(best.worst())) : std::sqrt(max_sq_dist_m2);
      if (needed + margin < reach) return best.write(idx, sq_dist);
    }
    // The k-d tree's k-NN cut at the gate, searched only inside the gate.
    return tree_.knn(q, k, idx, sq_dist, detail::float_gate(max_sq_dist_m2));
  }

  /// As nearest(q, k, ...) -- the very same result -- for the feature of
  /// `slot` in `cache`, answered from that slot's list when the exactness test
  /// holds, else by refilling the slot with one k-d tree query (file comment).
  /// Precondition: slot < cache.slots(), k <= cache.list_len(). Allocation-free.
  std::size_t nearest(const Eigen::Vector3f& q, std::size_t k, double max_sq_dist_m2, std::uint32_t* idx,
                      float* sq_dist, NearestCache& cache, std::size_t slot) const {
    if (k == 0 || empty()) return 0;
    const std::size_t len = cache.list_len_;
    if (k > len) return nearest(q, k, max_sq_dist_m2, idx, sq_dist);
    if (cache.generation_ != generation_) {  // filled against another map build: forget it
      std::fill(cache.radius_m_.begin(), cache.radius_m_.end(), -1.0F);
      cache.generation_ = generation_;
    }
    std::uint32_t* list = cache.lists_.data() + slot * len;
    const float radius_f = cache.radius_m_[slot];
    if (radius_f >= 0.0F) {
      const std::size_t stored = cache.count_[slot];
      const auto radius = static_cast<double>(radius_f);
      const double moved = std::sqrt(static_cast<double>(detail::nanoflann_sq_distance(q, cache.q0_[slot])));
      const double margin = 1e-4 + 1e-6 * (std::isfinite(radius) ? radius : 0.0);
      // Every entry's distance from q, from the slot's coordinate block (the
      // hottest loop of a Gauss-Newton iteration after the first).
      const std::size_t lanes = cache.padded_len();
      const float* xs = cache.list_xyz_.data() + slot * 3 * lanes;
      const float* ys = xs + lanes;
      const float* zs = ys + lanes;
      alignas(16) std::array<float, kMaxCandidateList> d;  // uninitialised (see kMaxCandidateList)
#if defined(SEMLIO_KDTREE_SSE2)  // the k-d tree's switch (small_kdtree.hpp): both or neither
      const __m128 qx = _mm_set1_ps(q.x());
      const __m128 qy = _mm_set1_ps(q.y());
      const __m128 qz = _mm_set1_ps(q.z());
      for (std::size_t g = 0; g < stored; g += 4) {
        const __m128 dx = _mm_sub_ps(qx, _mm_loadu_ps(xs + g));
        const __m128 dy = _mm_sub_ps(qy, _mm_loadu_ps(ys + g));
        const __m128 dz = _mm_sub_ps(qz, _mm_loadu_ps(zs + g));
        _mm_store_ps(d.data() + g, _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz)));
      }
#else
      for (std::size_t j = 0; j < stored; ++j) {
        d[j] = detail::nanoflann_sq_distance(q, Eigen::Vector3f(xs[j], ys[j], zs[j]));
      }
#endif
      const float gate_f = detail::float_gate(max_sq_dist_m2);  // the same test as the double gate
      detail::KBest best(k);
      for (std::size_t j = 0; j < stored; ++j) {
        if (d[j] <= gate_f) best.offer(d[j], list[j]);
      }
      const double reach = radius - moved;
      const double needed =
          best.full() ? std::sqrt(static_cast<double>(best.worst())) : std::sqrt(max_sq_dist_m2);
      if (needed + margin < reach) {
        ++cache.hits_;
        return best.write(idx, sq_dist);
      }
    }
    // Refill at q: the L nearest within the gate plus a slack for motion (one
    // bounded k-d tree query); its first k entries are the exact answer. The
    // list then holds every map point within `radius` of q: the L-th
    // distance when L were found, else the search bound itself.
    ++cache.refills_;
    std::array<float, kMaxCandidateList> d2;
    const double slack_m = kNearestCacheSlackM;
    const double bound = std::isfinite(max_sq_dist_m2) ? std::sqrt(max_sq_dist_m2) + slack_m : max_sq_dist_m2;
    const float bound2 = detail::float_gate(bound * bound);
    const std::size_t found = tree_.knn(q, len, list, d2.data(), bound2);
    cache.q0_[slot] = q;
    cache.count_[slot] = static_cast<std::uint8_t>(found);
    const std::size_t lanes = cache.padded_len();
    float* xs = cache.list_xyz_.data() + slot * 3 * lanes;
    const std::vector<Eigen::Vector3f>& pts = tree_.points();
    for (std::size_t j = 0; j < lanes; ++j) {
      const Eigen::Vector3f p = j < found ? pts[list[j]] : Eigen::Vector3f::Zero();
      xs[j] = p.x();
      xs[lanes + j] = p.y();
      xs[2 * lanes + j] = p.z();
    }
    cache.radius_m_[slot] = found == len ? std::sqrt(d2[len - 1])
                                         : std::sqrt(bound2);  // inf when unbounded (then found = size())
    std::size_t n = std::min(found, k);
    std::copy_n(list, n, idx);
    std::copy_n(d2.data(), n, sq_dist);
    while (n > 0 && !(static_cast<double>(sq_dist[n - 1]) <= max_sq_dist_m2)) --n;
    return n;
  }

  /// The shape neighbourhood of the last axis fitted through axis(i, hint).
  struct AxisHint {
    std::array<std::uint32_t, kMaxShapeNeighbours> idx;  ///< its map points (count of them valid)
    std::size_t count = 0;                               ///< 0: none yet
  };

  /// Unit axis of map point i (normal or line direction; zero = unusable),
  /// fitted on first use over its shape_neighbours() nearest map points and
  /// cached until the next build(). Allocation-free. Precondition: i < size().
  [[nodiscard]] Eigen::Vector3f axis(std::size_t i) const {
    AxisHint none;
    return axis(i, none);
  }

  /// As axis(i) -- the same vector -- with the caller's hint, the shape
  /// neighbourhood of the last axis fitted through it: a fit here seeds its
  /// k-NN search with it (SmallKdTree3f::knn_seeded; a feature's candidates
  /// lie together) and leaves its own neighbourhood in the hint. One hint
  /// per thread and map build.
  [[nodiscard]] Eigen::Vector3f axis(std::size_t i, AxisHint& hint) const {
    std::atomic_ref<std::uint8_t> state(axis_state_[i]);
    if (state.load(std::memory_order_acquire) == kReady) return axes_[i];
    std::array<float, kMaxShapeNeighbours> d2;
    hint.count = tree_.knn_seeded(tree_.point(i), static_cast<std::size_t>(shape_neighbours_), hint.idx.data(),
                                  d2.data(), hint.count);
    const Eigen::Vector3f a = detail::neighbourhood_axis(tree_, kind_, hint.idx.data(), hint.count);
    publish_axis(i, a);
    return a;
  }

  /// Every point's axis (as axis(i)); computes all those not cached yet on
  /// first call, so prefer axis(i) on hot paths.
  [[nodiscard]] const std::vector<Eigen::Vector3f>& axes() const {
    for (std::size_t i = 0; i < axes_.size(); ++i) {
      std::atomic_ref<std::uint8_t> state(axis_state_[i]);
      if (state.load(std::memory_order_acquire) == kReady) continue;
      (void)axis(i);
      // Another thread may have claimed the entry first: wait until it is written.
      while (state.load(std::memory_order_acquire) != kReady) std::this_thread::yield();
    }
    return axes_;
  }

  /// Number of axes computed since the last build() (cost diagnostics).
  [[nodiscard]] std::size_t fitted_axes() const {
    std::size_t c = 0;
    for (std::size_t i = 0; i < axis_state_.size(); ++i) {
      c += std::atomic_ref<std::uint8_t>(axis_state_[i]).load(std::memory_order_relaxed) == kReady ? 1U : 0U;
    }
    return c;
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
  /// The neighbourhood size the axes are fitted over.
  [[nodiscard]] int shape_neighbours() const noexcept { return shape_neighbours_; }
  /// The search structure over points().
  [[nodiscard]] const SmallKdTree3f& tree() const noexcept { return tree_; }
  /// Unique id of the last build() (0: never built): a rebuilt map -- even at
  /// the same address -- has a new one, so caches keyed on point indices can
  /// tell when they went stale.
  [[nodiscard]] std::uint64_t build_id() const noexcept { return generation_; }
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
  // Per-point cache states (accessed through std::atomic_ref).
  static constexpr std::uint8_t kEmpty = 0;
  static constexpr std::uint8_t kBusy = 1;   // claimed by one thread, being written
  static constexpr std::uint8_t kReady = 2;  // written; readable after an acquire load

  void publish_axis(std::size_t i, const Eigen::Vector3f& a) const {
    std::atomic_ref<std::uint8_t> state(axis_state_[i]);
    std::uint8_t expected = kEmpty;
    if (state.compare_exchange_strong(expected, kBusy, std::memory_order_acquire)) {
      axes_[i] = a;
      state.store(kReady, std::memory_order_release);
    }
  }

  // A map point near q for nearest() to anchor at: the point of q's voxel
  // when the map has a voxel index (one binary search over the keys), else
  // -- or when that voxel is empty -- q's nearest inside the gate (a 1-NN
  // k-d tree search bounded there: it prunes sooner). False when that search
  // finds none: then no map point lies inside the gate and the answer is
  // empty. Any anchor keeps the answer exact; a farther one only fails the
  // exactness test more often. (Also trying the voxels above and below, one
  // more key each, found an anchor for 3 % more corner queries and cost the
  // surfaces more than it saved: callgrind, simulated urban pair.)
  bool anchor_of(const Eigen::Vector3f& q, float gate_f, std::uint32_t& anchor, float& anchor_d2) const {
    std::uint64_t key = 0;
    if (voxel_inv_leaf_ > 0.0 && detail::reference_voxel_key(q, voxel_inv_leaf_, key)) {
      const auto it = std::lower_bound(voxel_keys_.begin(), voxel_keys_.end(), key);
      if (it != voxel_keys_.end() && *it == key) {
        anchor = static_cast<std::uint32_t>(it - voxel_keys_.begin());
        anchor_d2 = detail::nanoflann_sq_distance(q, tree_.point(anchor));
        return true;
      }
    }
    return tree_.knn(q, 1, &anchor, &anchor_d2, gate_f) == 1;
  }

  // Candidate list of map point m (list_len_ entries), their distances from
  // m (ascending, into dist_m) and the distance to its last entry (inf: the
  // list is the whole map): the cached list, or -- on first use -- computed
  // into `own` / `own_dist` (kMaxCandidateList long each) and published.
  const std::uint32_t* candidates_of(std::uint32_t m, std::uint32_t* own, float* own_dist, float& radius_m,
                                     const float*& dist_m) const {
    std::atomic_ref<std::uint8_t> state(list_state_[m]);
    const std::size_t offset = static_cast<std::size_t>(m) * list_len_;
    if (state.load(std::memory_order_acquire) == kReady) {
      radius_m = list_radius_m_[m];
      dist_m = list_dist_m_.data() + offset;
      return lists_.data() + offset;
    }
    std::array<float, kMaxCandidateList> d2;
    const std::size_t found = tree_.knn(tree_.point(m), list_len_, own, d2.data());
    for (std::size_t j = 0; j < found; ++j) own_dist[j] = std::sqrt(d2[j]);
    dist_m = own_dist;
    radius_m = list_len_ == size() ? std::numeric_limits<float>::infinity() : std::sqrt(d2[list_len_ - 1]);
    // The list's head is the point's shape neighbourhood: its axis comes free.
    if (std::atomic_ref<std::uint8_t>(axis_state_[m]).load(std::memory_order_acquire) != kReady) {
      publish_axis(m, detail::neighbourhood_axis(tree_, kind_, own,
                                                 std::min(found, static_cast<std::size_t>(shape_neighbours_))));
    }
    std::uint8_t expected = kEmpty;
    if (state.compare_exchange_strong(expected, kBusy, std::memory_order_acquire)) {
      std::copy_n(own, list_len_, lists_.begin() + static_cast<std::ptrdiff_t>(offset));
      std::copy_n(own_dist, list_len_, list_dist_m_.begin() + static_cast<std::ptrdiff_t>(offset));
      list_radius_m_[m] = radius_m;
      state.store(kReady, std::memory_order_release);
    }
    return own;
  }

  FeatureKind kind_;
  int shape_neighbours_ = 10;
  SmallKdTree3f tree_;  // rebuilt in its own buffers: no allocation once grown
  std::vector<Class> labels_;
  std::size_t list_len_ = 0;
  // Lazy caches (mutable: filled by const queries, see the file comment).
  mutable std::vector<Eigen::Vector3f> axes_;
  mutable std::vector<std::uint8_t> axis_state_;
  // The lists are read only once list_state_ says written: left
  // uninitialised by resize() (most are never filled; core/buffers.hpp).
  mutable std::vector<std::uint32_t, DefaultInitAllocator<std::uint32_t>> lists_;  // list_len_ nearest map points of each point
  mutable std::vector<float, DefaultInitAllocator<float>> list_dist_m_;  // their distances from that point [m] (ascending): early exit
  mutable std::vector<float> list_radius_m_;   // distance to the last of them (inf: the whole map)
  mutable std::vector<std::uint8_t> list_state_;
  std::uint64_t generation_ = 0;  // unique id of the last build() (NearestCache validity); 0 = never built
  std::vector<std::uint64_t> voxel_keys_;  // VoxelIndex keys (empty: none)
  double voxel_inv_leaf_ = 0.0;            // 1 / VoxelIndex leaf [1/m] (0: none)
};

}  // namespace semlio
