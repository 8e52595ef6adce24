#pragma once
/// \file
/// OnnxSegmenter: labels a scan with a user's range-image segmentation
/// network (RangeNet++, SalsaNext, CENet style) stored as ONNX, run on the
/// CPU through OpenCV's DNN module. The optional component semlio::segment_onnx
/// (cmake/SemlioOnnx.cmake) links OpenCV; nothing else in semlio needs it.
///
/// Per scan: RangeProjection (segment/range_projection.hpp) builds the
/// normalised 1 x C x H x W input the model card describes; the network
/// returns 1 x K x H x W class scores; each pixel takes its best-scoring
/// output (the first on ties), mapped to a learning class by the card; the
/// pixels' classes go back to every point with RangeNet++'s kNN vote.
/// No weights ship with semlio: the model and its card are the user's.

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/segment/range_projection.hpp>

namespace semlio {

/// What OnnxSegmenter needs to know about a network: where it is, the range
/// image it expects (size, field of view, channels with their mean and std,
/// back-projection) and what its outputs mean.
struct OnnxModelCard {
  std::string model_path;             ///< the .onnx file
  RangeProjectionConfig projection;   ///< input image and kNN back-projection (default: RangeNet++'s KITTI card)
  std::vector<Class> classes;         ///< output index -> learning class (one per output score)
};

/// Segmenter running an ONNX range-image network through OpenCV DNN (CPU).
/// Not thread-safe; copies share the loaded network and its input buffer
/// (cv::dnn::Net and cv::Mat are reference-counted), so neither may run
/// while the other does. RangeProjection allocates nothing once grown; the
/// forward pass allocates inside OpenCV.
class OnnxSegmenter {
 public:
  /// Loads the model and runs it once on an empty image to check its output
  /// against the card. Throws ConfigError for an invalid card (no classes, a
  /// class id out of range, a bad projection setting), IoError when the
  /// model file is missing, FormatError when OpenCV cannot read or run it
  /// or its output is not 1 x classes x H x W.
  explicit OnnxSegmenter(OnnxModelCard card) : card_(std::move(card)), projection_(card_.projection) {
    if (card_.classes.empty()) {
      throw ConfigError("OnnxModelCard.classes is empty: list one learning class per output of " + card_.model_path);
    }
    for (std::size_t i = 0; i < card_.classes.size(); ++i) {
      if (static_cast<int>(card_.classes[i]) >= kNumClasses) {
        throw ConfigError("OnnxModelCard.classes[" + std::to_string(i) + "] is class id " +
                          std::to_string(static_cast<int>(card_.classes[i])) + ", learning classes are 0.." +
                          std::to_string(kNumClasses - 1));
      }
    }
    std::error_code ec;
    if (!std::filesystem::is_regular_file(card_.model_path, ec)) {
      throw IoError(card_.model_path + ": ONNX model not found (OnnxModelCard.model_path)");
    }
    try {
      net_ = cv::dnn::readNetFromONNX(card_.model_path);
    } catch (const cv::Exception& e) {
      throw FormatError(card_.model_path + ": OpenCV cannot read it as an ONNX model: " + e.what());
    }
    if (net_.empty()) throw FormatError(card_.model_path + ": OpenCV read an empty network from it");
    net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    const int sizes[4] = {1, projection_.channel_count(), projection_.height_px(), projection_.width_px()};
    blob_.create(4, sizes, CV_32F);
    // An empty scan gives the all-zero image: the model is checked now, not at the first frame.
    projection_.project(Scan{});
    run_network();
  }

  /// The card.
  [[nodiscard]] const OnnxModelCard& card() const noexcept { return card_; }

  /// Fills scan.labels (one per point, existing labels are overwritten).
  /// Throws ValueError when the card needs intensity the scan lacks.
  void segment(Scan& scan) const {
    projection_.project(scan);
    run_network();
    scan.labels.resize(scan.points.size());
    projection_.back_project(pixel_labels_, scan.labels);
  }

 private:
  // Forward pass on the projection's input; per pixel the best output's class.
  void run_network() const {
    const std::span<const float> input = projection_.input();
    std::copy(input.begin(), input.end(), blob_.ptr<float>());
    const std::size_t pixels = projection_.pixel_count();
    const int k = static_cast<int>(card_.classes.size());
    cv::Mat out;
    try {
      net_.setInput(blob_);
      out = net_.forward();
    } catch (const cv::Exception& e) {
      throw FormatError(card_.model_path + ": the forward pass failed on the model card's 1 x " +
                        std::to_string(projection_.channel_count()) + " x " + std::to_string(projection_.height_px()) +
                        " x " + std::to_string(projection_.width_px()) + " input: " + e.what());
    }
    if (out.dims != 4 || out.size[0] != 1 || out.size[1] != k || out.size[2] != projection_.height_px() ||
        out.size[3] != projection_.width_px() || out.type() != CV_32F || !out.isContinuous()) {
      std::string shape;
      for (int d = 0; d < out.dims; ++d) shape += (d > 0 ? " x " : "") + std::to_string(out.size[d]);
      throw FormatError(card_.model_path + ": output is " + (shape.empty() ? std::string("empty") : shape) +
                        (out.type() == CV_32F ? "" : " (not float32)") + ", the model card expects float32 1 x " +
                        std::to_string(k) + " (one score per entry of 'classes') x " +
                        std::to_string(projection_.height_px()) + " x " + std::to_string(projection_.width_px()));
    }
    const float* scores = out.ptr<float>();
    pixel_labels_.resize(pixels);
    for (std::size_t pix = 0; pix < pixels; ++pix) {
      std::size_t best = 0;
      float best_score = scores[pix];
      for (std::size_t c = 1; c < static_cast<std::size_t>(k); ++c) {
        const float s = scores[c * pixels + pix];
        if (s > best_score) {
          best_score = s;
          best = c;
        }
      }
      pixel_labels_[pix] = card_.classes[best];
    }
  }

  OnnxModelCard card_;
  // Scratch and the network's run-time state (segment() is const, as every
  // Segmenter's; cv::dnn::Net::forward is not).
  mutable RangeProjection projection_;
  mutable cv::dnn::Net net_;
  mutable cv::Mat blob_;
  mutable std::vector<Class> pixel_labels_;
};

static_assert(Segmenter<OnnxSegmenter>);

}  // namespace semlio
