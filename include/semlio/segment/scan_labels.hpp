#pragma once
/// \file
/// The two trivial segmenters: labels that arrived with the scan (from
/// SemanticKITTI `.label` files read by io::KittiSequence from `labels/` or
/// a predictions folder, or from a PCD/PLY label field), and no labels at all.

#include <algorithm>

#include <semlio/concepts.hpp>
#include <semlio/core/scan.hpp>

namespace semlio {

/// Keeps the labels already in the scan; a scan without labels becomes all
/// unlabeled (so every downstream stage sees labels.size() == points.size()).
struct ScanLabels {
  /// Fills missing labels with unlabeled; existing labels are kept.
  void segment(Scan& scan) const {
    if (scan.labels.size() != scan.points.size()) scan.labels.assign(scan.points.size(), Class::kUnlabeled);
  }
};

/// Ignores any labels: every point unlabeled. With it, SemanticWeighted
/// residuals weigh every match 1 and SemanticAdaptive sees no labels.
struct NoLabels {
  /// Sets every label to unlabeled.
  void segment(Scan& scan) const { scan.labels.assign(scan.points.size(), Class::kUnlabeled); }
};

static_assert(Segmenter<ScanLabels>);
static_assert(Segmenter<NoLabels>);

}  // namespace semlio
