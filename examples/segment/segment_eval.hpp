#pragma once
// What semlio_segment_eval measures on a labelled KITTI / SemanticKITTI
// folder, as functions the tests call directly: the frame list of a folder,
// per-scan confusion matrices of a segmenter against the real labels, and
// the six coarse classes of issue #38.
//
// Labels: the reader (io/kitti.hpp) maps raw SemanticKITTI ids to the 19
// learning classes as semantic-kitti.yaml's learning_map does (core/labels.hpp:
// outlier 1, other-structure 52 and other-object 99 -> unlabeled and ignored;
// lane-marking 60 -> road; moving-* 252-259 -> their static class, e.g.
// moving-car 252 -> car, moving-person 254 -> person, moving-bus 257 ->
// other-vehicle).

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/eval/miou.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/io/kitti.hpp>

namespace semlio_examples {

/// Number of coarse classes including unlabeled (ids 0..6).
inline constexpr int kNumCoarse = 7;

/// Names of the coarse classes of issue #38 (index 0 is unlabeled).
inline constexpr std::array<std::string_view, kNumCoarse> kCoarseNames{
    "unlabeled", "ground", "structure", "vegetation", "vehicle", "human", "pole/sign"};

/// Coarse class (0..6) of a learning class: ground = road, parking, sidewalk,
/// other-ground, terrain; structure = building, fence; vegetation =
/// vegetation, trunk; vehicle = car, bicycle, motorcycle, truck,
/// other-vehicle; human = person, bicyclist, motorcyclist; pole/sign = pole,
/// traffic-sign.
constexpr int coarse_class(semlio::Class c) noexcept {
  using semlio::Class;
  switch (c) {
    case Class::kRoad: case Class::kParking: case Class::kSidewalk: case Class::kOtherGround: case Class::kTerrain:
      return 1;
    case Class::kBuilding: case Class::kFence: return 2;
    case Class::kVegetation: case Class::kTrunk: return 3;
    case Class::kCar: case Class::kBicycle: case Class::kMotorcycle: case Class::kTruck: case Class::kOtherVehicle:
      return 4;
    case Class::kPerson: case Class::kBicyclist: case Class::kMotorcyclist: return 5;
    case Class::kPole: case Class::kTrafficSign: return 6;
    case Class::kUnlabeled: return 0;
  }
  return 0;
}

/// Per coarse class IoU and their mean, under eval/miou.hpp's rules
/// (unlabeled truth ignored, unlabeled prediction a miss, classes absent from
/// truth and prediction skipped).
struct CoarseReport {
  std::array<double, kNumCoarse> iou{};    ///< IoU per coarse class (0 when skipped)
  std::array<bool, kNumCoarse> counted{};  ///< class took part in the mean
  double miou = 0.0;                       ///< mean over counted classes
  int classes = 0;                         ///< number of counted classes
};

/// Coarse-class IoUs of a 19-class confusion matrix (both axes grouped).
inline CoarseReport coarse_report(const semlio::eval::ConfusionMatrix& m) {
  std::array<std::array<std::uint64_t, kNumCoarse>, kNumCoarse> g{};
  for (int t = 1; t < semlio::kNumClasses; ++t) {
    for (int p = 0; p < semlio::kNumClasses; ++p) {
      const semlio::Class tc = semlio::class_from_index(t);
      const semlio::Class pc = semlio::class_from_index(p);
      g[static_cast<std::size_t>(coarse_class(tc))][static_cast<std::size_t>(coarse_class(pc))] += m.count(tc, pc);
    }
  }
  CoarseReport r;
  for (std::size_t c = 1; c < kNumCoarse; ++c) {
    std::uint64_t fp = 0, fn = 0;
    for (std::size_t o = 0; o < kNumCoarse; ++o) {
      if (o == c) continue;
      fn += g[c][o];
      fp += g[o][c];
    }
    const std::uint64_t d = g[c][c] + fp + fn;
    if (d == 0) continue;
    r.iou[c] = static_cast<double>(g[c][c]) / static_cast<double>(d);
    r.counted[c] = true;
    r.miou += r.iou[c];
    ++r.classes;
  }
  if (r.classes > 0) r.miou /= static_cast<double>(r.classes);
  return r;
}

/// One labelled scan of a sequence folder.
struct LabelledFrame {
  std::uint64_t index = 0;  ///< frame number (the file name's digits)
  std::string name;         ///< file stem, e.g. "000042"
  std::string bin_path;     ///< velodyne/<name>.bin
  std::string label_path;   ///< <labels>/<name>.label
};

/// The scans of a KITTI sequence folder `dir` (velodyne/NNNNNN.bin) with
/// their labels in `labels_dir` (empty: dir/labels), frame numbers in
/// [first, last], at most `max_frames` of them (0: all), by frame number.
/// Files whose stem is not all digits are not frames. Throws IoError when
/// velodyne/ is missing or cannot be listed, when a chosen scan has no label
/// file (naming it) or when no frame is left.
inline std::vector<LabelledFrame> list_labelled_frames(const std::string& dir, std::string labels_dir,
                                                       std::uint64_t first, std::uint64_t last,
                                                       std::size_t max_frames) {
  namespace fs = std::filesystem;
  if (labels_dir.empty()) labels_dir = (fs::path(dir) / "labels").string();
  const fs::path velodyne = fs::path(dir) / "velodyne";
  std::error_code ec;
  if (!fs::is_directory(velodyne, ec)) throw semlio::IoError("no velodyne/ folder in '" + dir + "'");
  std::vector<LabelledFrame> frames;
  fs::directory_iterator it(velodyne, ec);
  if (ec) throw semlio::IoError("cannot list '" + velodyne.string() + "': " + ec.message());
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) throw semlio::IoError("cannot list '" + velodyne.string() + "': " + ec.message());
    const fs::path& p = it->path();
    std::error_code type_ec;
    if (p.extension() != ".bin" || !it->is_regular_file(type_ec)) continue;
    const std::string stem = p.stem().string();
    // At most 19 digits: fits in uint64 without overflow.
    if (stem.empty() || stem.size() > 19 || stem.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::uint64_t index = std::stoull(stem);
    if (index < first || index > last) continue;
    frames.push_back({index, stem, p.string(), (fs::path(labels_dir) / (stem + ".label")).string()});
  }
  std::sort(frames.begin(), frames.end(),
            [](const LabelledFrame& a, const LabelledFrame& b) { return a.index < b.index || (a.index == b.index && a.name < b.name); });
  if (max_frames > 0 && frames.size() > max_frames) frames.resize(max_frames);
  if (frames.empty()) {
    throw semlio::IoError("no scans in '" + velodyne.string() + "' between frames " + std::to_string(first) + " and " +
                          std::to_string(last));
  }
  for (const LabelledFrame& f : frames) {
    if (!fs::is_regular_file(f.label_path, ec)) throw semlio::IoError("no label file '" + f.label_path + "' for scan '" + f.bin_path + "'");
  }
  return frames;
}

/// The confusion matrix of one scan and its size.
struct FrameResult {
  std::string name;                       ///< file stem
  std::size_t points = 0;                 ///< points read (after dropping invalid ones)
  semlio::eval::ConfusionMatrix matrix;   ///< truth (rows) vs the segmenter (columns)
  double segment_ms = 0.0;                ///< time spent in segment() [ms]
};

/// Reads one labelled scan, applies KITTI's vertical-angle fix when
/// `kitti_correction` (semlio_kitti / semlio_run do so on real KITTI scans
/// before segmenting), segments it and scores it against its labels. When
/// `segmented` is given it receives the scan with the segmenter's labels.
template <semlio::Segmenter S>
FrameResult evaluate_frame(const LabelledFrame& frame, const S& segmenter, bool kitti_correction,
                           semlio::Scan* segmented = nullptr) {
  semlio::Scan scan = semlio::io::read_kitti_scan(frame.bin_path, frame.label_path);
  const std::vector<semlio::Class> truth = scan.labels;
  if (kitti_correction) semlio::correct_kitti_vertical_angle(scan, semlio::kKittiVerticalCorrectionRad);
  FrameResult r;
  r.name = frame.name;
  r.points = scan.size();
  const auto t0 = std::chrono::steady_clock::now();
  segmenter.segment(scan);
  r.segment_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  r.matrix.add(truth, scan.labels);
  if (segmented != nullptr) *segmented = std::move(scan);
  return r;
}

}  // namespace semlio_examples
