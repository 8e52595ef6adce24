#pragma once
// The segmenter a command-line option picks, as one type.
//
// Why not a template argument, as the library's pipelines take it: every
// instantiation of semlio_kitti's pipelines (Slam with a lidar or an inertial
// back end, the LIO alone; baseline and full) costs GCC tens of seconds of
// front end, and one per segmenter tripled their number (18 instead of 6; the
// TU now compiles in 162 s CPU). A scan is segmented once per frame, so one
// std::visit per frame costs nothing measurable against the milliseconds the
// frame takes.

#include <utility>
#include <variant>

#include <semlio/concepts.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/segment/geometric_segmenter.hpp>
#include <semlio/segment/scan_labels.hpp>
#if SEMLIO_HAVE_ONNX
#include <semlio/segment/onnx/onnx_segmenter.hpp>
#endif

namespace semlio_examples {

/// One of the library's segmenters, chosen at run time.
class SegmenterChoice {
 public:
  /// The segmenters on offer.
#if SEMLIO_HAVE_ONNX
  using Variant = std::variant<semlio::NoLabels, semlio::ScanLabels, semlio::GeometricSegmenter, semlio::OnnxSegmenter>;
#else
  using Variant = std::variant<semlio::NoLabels, semlio::ScanLabels, semlio::GeometricSegmenter>;
#endif

  /// The chosen segmenter.
  explicit SegmenterChoice(Variant segmenter) : segmenter_(std::move(segmenter)) {}

  /// Labels the scan with the chosen segmenter.
  void segment(semlio::Scan& scan) const {
    std::visit([&scan](const auto& s) { s.segment(scan); }, segmenter_);
  }

 private:
  Variant segmenter_;
};

static_assert(semlio::Segmenter<SegmenterChoice>);

}  // namespace semlio_examples
