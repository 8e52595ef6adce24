#pragma once
/// \file
/// The Detector policy of loop closure: proposes older keyframes that may
/// show the same place as the newest one (the query). Shipped detectors:
/// RadiusLoopDetector (radius_detector.hpp, LIO-SAM) and ScanContextDetector
/// (scan_context.hpp, Kim & Kim 2018). Verification is not the detector's job
/// (LoopCloser does it).

#include <concepts>
#include <cstddef>
#include <vector>

#include <semlio/lie/se3.hpp>
#include <semlio/loop/loop_keyframe.hpp>

namespace semlio {

/// One loop candidate: an older keyframe and a guess of the relative pose.
struct LoopCandidate {
  std::size_t index = 0;   ///< index of the older keyframe (the match)
  SE3d T_from_to_guess;    ///< initial guess of the query's pose in the match's frame
  double score = 0.0;      ///< detector distance, lower is better (radius: metres; Scan Context: descriptor distance)
};

/// A loop detector: `detect(keyframes, out)` treats keyframes.back() as the
/// query and fills `out` (cleared first) with candidates, best first. It may
/// keep per-keyframe caches (hence non-const); keyframes are append-only
/// between calls (poses may change). Must not throw on data; deterministic.
template <typename D>
concept LoopDetector = requires(D d, const std::vector<LoopKeyframe>& keyframes, std::vector<LoopCandidate>& out) {
  d.detect(keyframes, out);
};

}  // namespace semlio
