#pragma once
/// \file
/// Loop closure = detection + verification. A Detector policy
/// (RadiusLoopDetector or ScanContextDetector) proposes older keyframes for the
/// newest one; the best few are verified by registration against a submap
/// around each (loop_verifier.hpp); the first accepted becomes a
/// LoopConstraint for the pose graph (a between-factor).

#include <algorithm>
#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include <semlio/core/stopwatch.hpp>
#include <semlio/loop/loop_detector.hpp>
#include <semlio/loop/loop_keyframe.hpp>
#include <semlio/loop/loop_verifier.hpp>
#include <semlio/loop/radius_detector.hpp>
#include <semlio/loop/scan_context.hpp>

namespace semlio {

/// Settings of LoopCloser. Verification defaults (RMS residual <= 0.3 m,
/// inlier ratio >= 0.5, submap of the candidate's +-25 keyframes within 30 m,
/// drift budget 3 m + 3 % of the path, 0.3 rad + 0.002 rad/m) are in
/// LoopVerifierConfig.
struct LoopCloserConfig {
  std::size_t max_verifications = 2;  ///< candidates verified per query, best first (LIO-SAM: 1)
  LoopVerifierConfig verify{};        ///< submap, registration and acceptance thresholds
};

/// Counters of a LoopCloser (cumulative since construction).
struct LoopStats {
  std::size_t queries = 0;             ///< process() calls
  std::size_t candidates = 0;          ///< candidates proposed by the detector
  std::size_t verified = 0;            ///< verifications run
  std::size_t accepted = 0;            ///< loops returned
  std::size_t rejected_empty = 0;      ///< rejected: empty submap or no features
  std::size_t rejected_not_converged = 0;  ///< rejected: solve failed or hit its cap
  std::size_t rejected_degenerate = 0; ///< rejected: degenerate direction
  std::size_t rejected_fitness = 0;    ///< rejected: RMS residual too large
  std::size_t rejected_inliers = 0;    ///< rejected: too few matched features
  std::size_t rejected_correction = 0; ///< rejected: correction beyond the drift budget
  double detect_ms = 0.0;              ///< total detection time [ms]
  double verify_ms = 0.0;              ///< total verification time [ms]

  /// All rejections.
  [[nodiscard]] std::size_t rejected() const noexcept {
    return rejected_empty + rejected_not_converged + rejected_degenerate + rejected_fitness + rejected_inliers +
           rejected_correction;
  }
};

/// Detection (a Detector policy: RadiusLoopDetector or ScanContextDetector) +
/// verification. Not thread-safe (holds the detector's caches and buffers).
template <typename Detector>
  requires LoopDetector<Detector>
class LoopCloser {
 public:
  using Config = LoopCloserConfig;

  /// Owns the detector (by value) and the settings.
  explicit LoopCloser(Detector detector = {}, const Config& config = {})
      : detector_(std::move(detector)), config_(config) {}

  /// Call once after appending each keyframe (keyframes.back() is the query);
  /// returns at most one verified loop. Never throws on data; deterministic.
  std::optional<LoopConstraint> process(const std::vector<LoopKeyframe>& keyframes) {
    ++stats_.queries;
    last_.clear();
    if (keyframes.size() < 2) return std::nullopt;
    const auto t0 = StageClock::now();
    detector_.detect(keyframes, candidates_);
    stats_.detect_ms += ms_since(t0);
    stats_.candidates += candidates_.size();
    const std::size_t query = keyframes.size() - 1;
    const std::size_t n = std::min(candidates_.size(), config_.max_verifications);
    for (std::size_t k = 0; k < n; ++k) {
      const LoopCandidate& c = candidates_[k];
      LoopVerification v = verify_loop(keyframes, c.index, query, c.T_from_to_guess, config_.verify);
      ++stats_.verified;
      stats_.verify_ms += v.time_ms;
      count(v.verdict);
      last_.push_back(v);
      if (v.accepted()) {
        ++stats_.accepted;
        return v.constraint;
      }
    }
    return std::nullopt;
  }

  /// Counters: candidates proposed, verified, rejected (by reason).
  const LoopStats& stats() const { return stats_; }
  /// The verifications of the last process() call (diagnostics).
  [[nodiscard]] const std::vector<LoopVerification>& last_verifications() const noexcept { return last_; }
  /// The candidates of the last process() call.
  [[nodiscard]] const std::vector<LoopCandidate>& last_candidates() const noexcept { return candidates_; }
  /// The detector.
  [[nodiscard]] const Detector& detector() const noexcept { return detector_; }
  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  void count(LoopVerdict v) {
    switch (v) {
      case LoopVerdict::kAccepted: break;
      case LoopVerdict::kEmptySubmap: ++stats_.rejected_empty; break;
      case LoopVerdict::kNotConverged: ++stats_.rejected_not_converged; break;
      case LoopVerdict::kDegenerate: ++stats_.rejected_degenerate; break;
      case LoopVerdict::kPoorFitness: ++stats_.rejected_fitness; break;
      case LoopVerdict::kFewInliers: ++stats_.rejected_inliers; break;
      case LoopVerdict::kLargeCorrection: ++stats_.rejected_correction; break;
    }
  }

  Detector detector_;
  Config config_;
  LoopStats stats_;
  std::vector<LoopCandidate> candidates_;
  std::vector<LoopVerification> last_;
};

}  // namespace semlio
