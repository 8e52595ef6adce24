#pragma once
/// \file
/// The contract between semlio's stages: the policy concepts (Associator,
/// Residual, Segmenter, KeyframePolicy) and the small value types they
/// exchange (FeatureMatches, MatchedPoints, ResidualTerm, KeyframeEvidence).
/// Shipped policies are checked with `static_assert(Concept<P>)` beside them.

#include <Eigen/Core>

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio {

/// Most map points an associator keeps per feature (Algorithm 1 keeps 5).
inline constexpr int kMaxKeptMatches = 5;

/// The map points chosen for one scan feature, in the order chosen.
/// `rank[j]` is the 1-based position (1..15) of `index[j]` among the
/// distance-sorted candidates, for the paper's eq. 23 statistics.
struct FeatureMatches {
  std::array<std::uint32_t, kMaxKeptMatches> index{};  ///< map point indices
  std::array<std::uint8_t, kMaxKeptMatches> rank{};    ///< candidate rank, 1-based
  std::uint8_t count = 0;                              ///< number of valid entries (0 = no match)
};

/// One FeatureMatches per scan feature, in scan-feature order.
using Correspondences = std::vector<FeatureMatches>;

/// The kept map points of one feature, gathered for a residual (map frame, double).
struct MatchedPoints {
  std::array<Eigen::Vector3d, kMaxKeptMatches> p_map{};  ///< positions in the map frame [m]
  std::array<Class, kMaxKeptMatches> labels{};           ///< their labels
  int count = 0;                                         ///< number of valid entries
};

/// A residual block of dimension kDim for one feature at one pose.
/// The cost contributed is `weight * r^T r`; `r` already holds any semantic
/// weight (eq. 11-12), `weight` is the robust (IRLS) weight on the squared cost.
template <int kDim>
struct ResidualTerm {
  Eigen::Matrix<double, kDim, 1> r = Eigen::Matrix<double, kDim, 1>::Zero();      ///< residual [m]
  Eigen::Matrix<double, kDim, 6> J_r_xi = Eigen::Matrix<double, kDim, 6>::Zero(); ///< d r / d xi, xi the right perturbation of T_map_scan
  double weight = 1.0;  ///< IRLS weight on the squared cost
  bool valid = false;   ///< false: no residual (degenerate matches); r and J are zero
};

/// A scan feature as residuals see it.
struct FeaturePoint {
  Eigen::Vector3d p_scan = Eigen::Vector3d::Zero();  ///< position in the scan frame [m]
  Class label = Class::kUnlabeled;                   ///< its semantic label
};

/// Associates scan features with points of a map of type Map.
/// `set_map` (re)binds the map (non-owning; it must outlive the use),
/// `set_scan` binds the frame's feature positions (scan frame, non-owning) and
/// computes any per-frame cache, `associate` fills one FeatureMatches per
/// feature for the pose T_map_scan; const, so safe to call from several
/// threads at once.
template <typename A, typename Map>
concept Associator = requires(A a, const A ca, const Map& map, const std::vector<Eigen::Vector3f>& points_scan,
                              const SE3d& T_map_scan, Correspondences& out) {
  a.set_map(map);
  a.set_scan(points_scan);
  ca.associate(T_map_scan, out);
};

/// A residual policy: `kDim` and a const `evaluate(feature, matches, T_map_scan)`
/// returning ResidualTerm<kDim> with the analytic Jacobian (right perturbation).
template <typename R>
concept Residual = requires(const R r, const FeaturePoint& feature, const MatchedPoints& matches,
                            const SE3d& T_map_scan) {
  { R::kDim } -> std::convertible_to<int>;
  { r.evaluate(feature, matches, T_map_scan) } -> std::same_as<ResidualTerm<R::kDim>>;
};

/// A Residual whose per-match-set work (fitting the line or plane through the
/// matches) can be done once and reused while the matches stay the same --
/// as they do over most late Gauss-Newton iterations. `prepare(matches)`
/// returns that fit (`Model`); `evaluate(feature, matches, model, T)` must
/// equal `evaluate(feature, matches, T)` bit for bit when `model` came from
/// `prepare(matches)` (the plain evaluate is defined as the two in a row).
template <typename R>
concept PreparedResidual =
    Residual<R> && requires(const R r, const FeaturePoint& feature, const MatchedPoints& matches,
                            const typename R::Model& model, const SE3d& T_map_scan) {
      { r.prepare(matches) } -> std::same_as<typename R::Model>;
      { r.evaluate(feature, matches, model, T_map_scan) } -> std::same_as<ResidualTerm<R::kDim>>;
    };

namespace detail {

/// Stand-in Model of a residual that has no separate fit.
struct NoModel {};

template <typename R>
struct ModelOfImpl {
  using type = NoModel;
};
template <typename R>
  requires requires { typename R::Model; }
struct ModelOfImpl<R> {
  using type = typename R::Model;
};

/// R::Model when R declares one, else NoModel (for decorators).
template <typename R>
using ModelOf = typename ModelOfImpl<R>::type;

}  // namespace detail

/// Labels a scan in place: afterwards `labels.size() == points.size()`.
/// In place (not Scan -> Scan) so the per-frame pipeline allocates nothing.
template <typename S>
concept Segmenter = requires(S s, Scan& scan) {
  s.segment(scan);
};

/// What a keyframe decision sees (Algorithm 2).
struct KeyframeEvidence {
  SE3d T_lastkf_current;                     ///< motion since the last keyframe
  double elapsed_s = 0.0;                    ///< time since the last keyframe [s]
  const LabelHistogram* current = nullptr;   ///< label histogram of this frame (may be null)
  const LabelHistogram* last_keyframe = nullptr;  ///< of the last keyframe (may be null)
};

/// Decides whether the current frame becomes a keyframe.
template <typename K>
concept KeyframePolicy = requires(const K k, const KeyframeEvidence& evidence) {
  { k.is_keyframe(evidence) } -> std::convertible_to<bool>;
};

}  // namespace semlio
