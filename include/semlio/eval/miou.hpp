#pragma once
/// \file
/// Semantic segmentation quality: a confusion matrix over SemanticKITTI's 19
/// learning classes, per-class IoU and mean IoU, as the SemanticKITTI
/// benchmark defines them.
///
/// Rules (documented choices):
/// - Points whose ground truth is unlabeled (class 0) are ignored entirely.
/// - A prediction of unlabeled on a labelled point counts as a miss (false
///   negative) of the true class and as a false positive of nothing.
/// - IoU_c = TP / (TP + FP + FN).
/// - mIoU is the mean of IoU_c over the classes that occur in the ground truth
///   or in the predictions (TP + FP + FN > 0); classes absent from both are
///   skipped rather than counted as 0 or 1. With no labelled points the mIoU
///   is 0 and `classes` is 0 (never NaN).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>

namespace semlio::eval {

/// Per-class IoU and their mean.
struct MiouReport {
  std::array<double, kNumClasses> iou{};       ///< IoU per class id (0 for skipped classes and unlabeled)
  std::array<bool, kNumClasses> counted{};     ///< class took part in the mean
  double miou = 0.0;                           ///< mean IoU over counted classes
  int classes = 0;                             ///< number of counted classes
  double accuracy = 0.0;                       ///< fraction of labelled points predicted correctly
  std::uint64_t points = 0;                    ///< labelled points evaluated
};

/// Confusion counts rows = ground truth, columns = prediction (class ids
/// 0..19). Accumulate over frames with add(); not thread-safe.
class ConfusionMatrix {
 public:
  /// Adds one point (ignored when the ground truth is unlabeled).
  void add(Class truth, Class predicted) {
    if (truth == Class::kUnlabeled) return;
    ++counts_[static_cast<std::size_t>(index(truth))][static_cast<std::size_t>(index(predicted))];
  }

  /// Adds every point of a frame. Throws ValueError when the sizes differ.
  void add(const std::vector<Class>& truth, const std::vector<Class>& predicted) {
    if (truth.size() != predicted.size()) {
      throw ValueError("ConfusionMatrix::add: " + std::to_string(truth.size()) + " true labels but " +
                       std::to_string(predicted.size()) + " predictions");
    }
    for (std::size_t i = 0; i < truth.size(); ++i) add(truth[i], predicted[i]);
  }

  /// Adds another matrix (e.g. per-thread partial counts).
  void merge(const ConfusionMatrix& other) {
    for (std::size_t r = 0; r < kN; ++r) {
      for (std::size_t c = 0; c < kN; ++c) counts_[r][c] += other.counts_[r][c];
    }
  }

  /// Number of points with ground truth `truth` predicted as `predicted`.
  [[nodiscard]] std::uint64_t count(Class truth, Class predicted) const {
    return counts_[static_cast<std::size_t>(index(truth))][static_cast<std::size_t>(index(predicted))];
  }

  /// Per-class IoU and mIoU under the rules in the file comment.
  [[nodiscard]] MiouReport report() const {
    MiouReport r;
    std::uint64_t correct = 0;
    for (std::size_t c = 1; c < kN; ++c) {
      std::uint64_t tp = counts_[c][c];
      std::uint64_t fn = 0;
      std::uint64_t fp = 0;
      for (std::size_t o = 0; o < kN; ++o) {
        r.points += counts_[c][o];
        if (o != c) {
          fn += counts_[c][o];
          fp += counts_[o][c];  // row 0 (unlabeled truth) is never filled
        }
      }
      correct += tp;
      const std::uint64_t denom = tp + fp + fn;
      if (denom == 0) continue;
      r.iou[c] = static_cast<double>(tp) / static_cast<double>(denom);
      r.counted[c] = true;
      r.miou += r.iou[c];
      ++r.classes;
    }
    if (r.classes > 0) r.miou /= static_cast<double>(r.classes);
    if (r.points > 0) r.accuracy = static_cast<double>(correct) / static_cast<double>(r.points);
    return r;
  }

 private:
  static constexpr std::size_t kN = kNumClasses;
  std::array<std::array<std::uint64_t, kN>, kN> counts_{};
};

/// mIoU of one set of predictions (see the file comment for the rules).
inline MiouReport miou(const std::vector<Class>& truth, const std::vector<Class>& predicted) {
  ConfusionMatrix m;
  m.add(truth, predicted);
  return m.report();
}

}  // namespace semlio::eval
