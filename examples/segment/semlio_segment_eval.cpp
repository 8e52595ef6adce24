// semlio_segment_eval: scores GeometricSegmenter against exact labels:
// the simulator's, or real SemanticKITTI ground truth.
//
//   semlio_segment_eval [--world urban|rural|highway|aliased] [--frames N]
//                       [--seed S] [--stride K] [--traffic none|light|heavy]
//                       [--merged-ground] [--markdown | --tsv]
//   semlio_segment_eval --sequence DIR [--labels-dir DIR] [--first F] [--last L]
//                       [--frames N] [--kitti-correction on|off]
//                       [--merged-ground] [--markdown | --tsv] [--confusion]
//                       [--write-labels OUT_DIR]
//   semlio_segment_eval --kitti-bin FILE.bin [--repeat N]
//
// Simulated worlds: simulates a drive of N * K frames (in memory, nothing is
// written), segments every K-th frame (default K = 10, so the N frames spread
// over the drive) and prints the per-class IoU and the mIoU (SemanticKITTI
// rules, see eval/miou.hpp), the six coarse classes of issue #38 (ground,
// structure, vegetation, vehicle, human, pole/sign; examples/segment/
// segment_eval.hpp) and the segmenter's time per frame. --markdown prints one
// summary row instead:
//   | world | mIoU | ground IoU | building IoU | vegetation IoU | pole/trunk IoU | car IoU |
// --merged-ground labels all ground kRoad (split_ground = false).
//
// --sequence: a KITTI / SemanticKITTI folder (velodyne/NNNNNN.bin and
// labels/NNNNNN.label, or the labels in --labels-dir); frames numbered F..L
// (default all), at most N of them (default all). Raw ids map to the 19
// learning classes as semantic-kitti.yaml's learning_map does. Every scan gets
// KITTI's 0.205 deg vertical-angle fix first, as semlio_kitti applies it to
// real KITTI scans before segmenting (--kitti-correction off: raw points).
// Prints per-class IoU (19 classes and the six coarse classes) per scan and
// pooled over all scans; --markdown prints the same as markdown tables;
// --confusion adds, per true class, where its pooled points went;
// --write-labels writes the predictions as OUT_DIR/NNNNNN.label
// (SemanticKITTI format, one label per point of the .bin; KITTI scans have no
// NaN or (0,0,0) points, which the reader would drop).
//
// --tsv (both modes) prints the pooled IoUs as `name<TAB>value` lines (19
// classes, mIoU, the six coarse classes as coarse:<name>, coarse mIoU; "-"
// for a class absent from truth and prediction): scripts/segmenter_miou.sh
// joins them into one table.
//
// --kitti-bin segments one real KITTI scan N times (default 200) and prints
// the time per scan (median, 10th/90th percentile) and the label shares.
//
// Exit codes: 0 success; 1 error; 2 bad command line.

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <semlio/core/labels.hpp>
#include <semlio/eval/miou.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/segment/geometric_segmenter.hpp>
#include <semlio/sim/simulator.hpp>

#include "segment_eval.hpp"

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: semlio_segment_eval [--world urban|rural|highway|aliased] [--frames N] [--seed S]\n"
               "                           [--stride K] [--traffic none|light|heavy] [--merged-ground] [--markdown]\n"
               "                           [--tsv]\n"
               "       semlio_segment_eval --sequence DIR [--labels-dir DIR] [--first F] [--last L] [--frames N]\n"
               "                           [--kitti-correction on|off] [--merged-ground] [--markdown | --tsv] [--confusion]\n"
               "                           [--write-labels OUT_DIR]\n"
               "       semlio_segment_eval --kitti-bin FILE.bin [--repeat N]\n");
  return 2;
}

// IoU of a group of classes taken as one class.
double group_iou(const semlio::eval::ConfusionMatrix& m, std::initializer_list<semlio::Class> group) {
  const auto in = [&](int k) {
    return std::find(group.begin(), group.end(), semlio::class_from_index(k)) != group.end();
  };
  std::uint64_t tp = 0, fp = 0, fn = 0;
  for (int t = 1; t < semlio::kNumClasses; ++t) {
    for (int p = 0; p < semlio::kNumClasses; ++p) {
      const std::uint64_t n = m.count(semlio::class_from_index(t), semlio::class_from_index(p));
      if (in(t) && in(p)) tp += n;
      if (in(t) && !in(p)) fn += n;
      if (!in(t) && in(p)) fp += n;
    }
  }
  const std::uint64_t d = tp + fp + fn;
  return d == 0 ? 0.0 : static_cast<double>(tp) / static_cast<double>(d);
}

// Times the segmenter on one real scan; prints the label shares.
int time_kitti(const std::string& path, std::size_t repeat) {
  const semlio::Scan original = semlio::io::read_kitti_bin(path);
  const semlio::GeometricSegmenter seg;
  semlio::Scan scan = original;
  std::vector<double> ms;
  for (std::size_t k = 0; k < repeat + 3; ++k) {
    scan.labels.clear();
    const auto t0 = std::chrono::steady_clock::now();
    seg.segment(scan);
    const auto t1 = std::chrono::steady_clock::now();
    if (k >= 3) ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());  // 3 warm-up runs
  }
  std::sort(ms.begin(), ms.end());
  std::printf("%s: %zu points, segment time median %.2f ms (p10 %.2f, p90 %.2f) over %zu runs\n", path.c_str(),
              scan.size(), ms[ms.size() / 2], ms[ms.size() / 10], ms[ms.size() * 9 / 10], ms.size());
  const semlio::LabelHistogram h = semlio::label_histogram(scan);
  for (int k = 0; k < semlio::kNumClasses; ++k) {
    const auto n = h[static_cast<std::size_t>(k)];
    if (n == 0) continue;
    std::printf("  %-12s %6.1f %%\n", std::string(semlio::class_name(semlio::class_from_index(k))).c_str(),
                100.0 * static_cast<double>(n) / static_cast<double>(scan.size()));
  }
  return 0;
}


using semlio_examples::kCoarseNames;
using semlio_examples::kNumCoarse;

std::string class_str(int k) { return std::string(semlio::class_name(semlio::class_from_index(k))); }

// Pooled IoUs as name<TAB>value lines (see the file comment).
void print_tsv(const semlio::eval::ConfusionMatrix& m) {
  const semlio::eval::MiouReport r = m.report();
  const semlio_examples::CoarseReport g = semlio_examples::coarse_report(m);
  for (int k = 1; k < semlio::kNumClasses; ++k) {
    const auto u = static_cast<std::size_t>(k);
    if (r.counted[u]) {
      std::printf("%s\t%.3f\n", class_str(k).c_str(), r.iou[u]);
    } else {
      std::printf("%s\t-\n", class_str(k).c_str());
    }
  }
  std::printf("mIoU\t%.3f\n", r.miou);
  for (std::size_t k = 1; k < kNumCoarse; ++k) {
    if (g.counted[k]) {
      std::printf("coarse:%s\t%.3f\n", std::string(kCoarseNames[k]).c_str(), g.iou[k]);
    } else {
      std::printf("coarse:%s\t-\n", std::string(kCoarseNames[k]).c_str());
    }
  }
  std::printf("coarse mIoU\t%.3f\n", g.miou);
}

// Per true class, where its points went (shares of at least 2 %).
void print_confusion(const semlio::eval::ConfusionMatrix& m) {
  std::printf("%-14s %12s  -> predicted as\n", "true class", "points");
  for (int k = 1; k < semlio::kNumClasses; ++k) {
    const semlio::Class c = semlio::class_from_index(k);
    std::uint64_t n_true = 0;
    for (int p = 0; p < semlio::kNumClasses; ++p) n_true += m.count(c, semlio::class_from_index(p));
    if (n_true == 0) continue;
    std::printf("%-14s %12llu  ->", class_str(k).c_str(), static_cast<unsigned long long>(n_true));
    for (int p = 0; p < semlio::kNumClasses; ++p) {
      const std::uint64_t n = m.count(c, semlio::class_from_index(p));
      if (50 * n >= n_true) std::printf(" %s %.0f%%", class_str(p).c_str(), 100.0 * static_cast<double>(n) / static_cast<double>(n_true));
    }
    std::printf("\n");
  }
}

// Per-class IoU tables (19 classes, then the six coarse ones), one column per
// (name, matrix); plain text or markdown.
void print_tables(const std::vector<std::pair<std::string, semlio::eval::ConfusionMatrix>>& cols, bool markdown) {
  std::vector<semlio::eval::MiouReport> r;
  std::vector<semlio_examples::CoarseReport> g;
  for (const auto& [name, m] : cols) {
    r.push_back(m.report());
    g.push_back(semlio_examples::coarse_report(m));
  }
  const auto row = [&](const std::string& label, auto value) {
    if (markdown) {
      std::printf("| %s |", label.c_str());
      for (std::size_t j = 0; j < cols.size(); ++j) std::printf(" %s |", value(j).c_str());
    } else {
      std::printf("%-14s", label.c_str());
      for (std::size_t j = 0; j < cols.size(); ++j) std::printf(" %10s", value(j).c_str());
    }
    std::printf("\n");
  };
  const auto num = [](bool counted, double v) {
    if (!counted) return std::string("-");
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", v);
    return std::string(buf);
  };
  const auto header = [&](const std::string& first) {
    row(first, [&](std::size_t j) { return cols[j].first; });
    if (markdown) {
      std::printf("|---|");
      for (std::size_t j = 0; j < cols.size(); ++j) std::printf("---|");
      std::printf("\n");
    }
  };
  header("class");
  for (int k = 1; k < semlio::kNumClasses; ++k) {
    const auto u = static_cast<std::size_t>(k);
    row(class_str(k), [&](std::size_t j) { return num(r[j].counted[u], r[j].iou[u]); });
  }
  row(markdown ? "**mIoU**" : "mIoU", [&](std::size_t j) { return num(true, r[j].miou); });
  std::printf("\n");
  header("coarse class");
  for (std::size_t k = 1; k < kNumCoarse; ++k) {
    row(std::string(kCoarseNames[k]), [&](std::size_t j) { return num(g[j].counted[k], g[j].iou[k]); });
  }
  row(markdown ? "**coarse mIoU**" : "coarse mIoU", [&](std::size_t j) { return num(true, g[j].miou); });
}

}  // namespace

/// A non-negative whole number for `option`; anything else (std::stoul took
/// "12abc" and "-1", and said only "stoul") is a ConfigError naming both.
static std::uint64_t whole_number(std::string_view option, const std::string& text) {
  std::uint64_t v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size()) {
    throw semlio::ConfigError(std::string(option) + " needs a non-negative whole number, got '" + text + "'");
  }
  return v;
}

int main(int argc, char** argv) {
  semlio::sim::SimulatorConfig sc;
  sc.traffic = semlio::sim::TrafficLevel::kLight;
  std::size_t frames = 20;
  bool frames_given = false;
  std::size_t stride = 10;
  bool markdown = false;
  bool tsv = false;
  bool confusion = false;
  bool kitti_correction = true;
  std::string sequence;
  std::string labels_dir;
  std::string write_labels;
  std::uint64_t first = 0;
  std::uint64_t last = std::numeric_limits<std::uint64_t>::max();
  bool merged = false;
  std::string kitti_bin;
  std::size_t repeat = 200;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string_view a = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw semlio::ConfigError(std::string(a) + " needs a value");
        return argv[++i];
      };
      if (a == "--world") {
        sc.world = semlio::sim::parse_world(value());
      } else if (a == "--frames") {
        frames = whole_number(a, value());
        frames_given = true;
      } else if (a == "--seed") {
        sc.seed = whole_number(a, value());
      } else if (a == "--stride") {
        stride = std::max<std::size_t>(1, whole_number(a, value()));
      } else if (a == "--traffic") {
        const std::string t = value();
        if (t == "none") {
          sc.traffic = semlio::sim::TrafficLevel::kNone;
        } else if (t == "light") {
          sc.traffic = semlio::sim::TrafficLevel::kLight;
        } else if (t == "heavy") {
          sc.traffic = semlio::sim::TrafficLevel::kHeavy;
        } else {
          throw semlio::ConfigError("--traffic must be none|light|heavy, got '" + t + "'");
        }
      } else if (a == "--markdown") {
        markdown = true;
      } else if (a == "--tsv") {
        tsv = true;
      } else if (a == "--confusion") {
        confusion = true;
      } else if (a == "--sequence") {
        sequence = value();
      } else if (a == "--write-labels") {
        write_labels = value();
      } else if (a == "--labels-dir") {
        labels_dir = value();
      } else if (a == "--first") {
        first = whole_number(a, value());
      } else if (a == "--last") {
        last = whole_number(a, value());
      } else if (a == "--kitti-correction") {
        const std::string v = value();
        if (v != "on" && v != "off") throw semlio::ConfigError("--kitti-correction must be on|off, got '" + v + "'");
        kitti_correction = v == "on";
      } else if (a == "--kitti-bin") {
        kitti_bin = value();
      } else if (a == "--repeat") {
        repeat = std::max<std::size_t>(1, whole_number(a, value()));
      } else if (a == "--merged-ground") {
        merged = true;
      } else {
        return usage();
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semlio_segment_eval: %s\n", e.what());
    return usage();
  }
  if (frames == 0 || (markdown && tsv) || first > last) return usage();
  try {
    if (!kitti_bin.empty()) return time_kitti(kitti_bin, repeat);
    if (!sequence.empty()) {
      semlio::GeometricSegmenterConfig gc;
      gc.split_ground = !merged;
      const semlio::GeometricSegmenter seg(gc);
      const std::vector<semlio_examples::LabelledFrame> list =
          semlio_examples::list_labelled_frames(sequence, labels_dir, first, last, frames_given ? frames : 0);
      std::vector<std::pair<std::string, semlio::eval::ConfusionMatrix>> cols;
      semlio::eval::ConfusionMatrix pooled;
      std::vector<double> ms;
      for (const semlio_examples::LabelledFrame& f : list) {
        semlio::Scan segmented;
        semlio_examples::FrameResult fr = semlio_examples::evaluate_frame(f, seg, kitti_correction, &segmented);
        if (!write_labels.empty()) {
          std::filesystem::create_directories(write_labels);
          segmented.instances.clear();  // the truth's instance ids, not the segmenter's
          semlio::io::write_label_file(write_labels + "/" + f.name + ".label", semlio::io::raw_labels(segmented));
        }
        pooled.merge(fr.matrix);
        ms.push_back(fr.segment_ms);
        cols.emplace_back(fr.name, fr.matrix);
      }
      if (tsv) {
        print_tsv(pooled);
        return 0;
      }
      cols.emplace_back("all", pooled);
      if (!markdown) {
        std::sort(ms.begin(), ms.end());
        std::printf("sequence %s: %zu labelled scans, %llu labelled points, vertical correction %s\n",
                    sequence.c_str(), list.size(), static_cast<unsigned long long>(pooled.report().points),
                    kitti_correction ? "on" : "off");
      }
      print_tables(cols, markdown);
      if (confusion) {
        std::printf("\n");
        print_confusion(pooled);
      }
      if (!markdown) std::printf("segmenter time per scan: median %.2f ms, max %.2f ms\n", ms[ms.size() / 2], ms.back());
      return 0;
    }
    sc.frames = frames * stride;
    const semlio::sim::Simulator sim(sc);
    semlio::GeometricSegmenterConfig gc;
    gc.split_ground = !merged;
    const semlio::GeometricSegmenter seg(gc);
    semlio::eval::ConfusionMatrix cm;
    std::vector<double> ms;
    semlio::Scan scan;
    for (std::size_t f = 0; f < frames; ++f) {
      semlio::sim::Frame fr = sim.frame(f * stride);
      const std::vector<semlio::Class> truth = fr.scan.labels;
      scan = std::move(fr.scan);
      const auto t0 = std::chrono::steady_clock::now();
      seg.segment(scan);
      const auto t1 = std::chrono::steady_clock::now();
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      cm.add(truth, scan.labels);
    }
    std::sort(ms.begin(), ms.end());
    const semlio::eval::MiouReport r = cm.report();
    using semlio::Class;
    const double ground = group_iou(cm, {Class::kRoad, Class::kParking, Class::kSidewalk, Class::kOtherGround,
                                         Class::kTerrain});
    const double stem = group_iou(cm, {Class::kPole, Class::kTrunk});
    const auto iou = [&](Class c) { return r.iou[static_cast<std::size_t>(semlio::index(c))]; };
    const std::string world(semlio::sim::world_name(sc.world));
    if (tsv) {
      print_tsv(cm);
      return 0;
    }
    if (markdown) {
      std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", world.c_str(), r.miou, ground,
                  iou(Class::kBuilding), iou(Class::kVegetation), stem, iou(Class::kCar));
      return 0;
    }
    std::printf("world %s, seed %llu, %zu frames (every %zu-th), %llu labelled points\n", world.c_str(),
                static_cast<unsigned long long>(sc.seed), frames, stride, static_cast<unsigned long long>(r.points));
    std::printf("%-14s %8s %12s\n", "class", "IoU", "true points");
    for (int k = 1; k < semlio::kNumClasses; ++k) {
      if (!r.counted[static_cast<std::size_t>(k)]) continue;
      const Class c = semlio::class_from_index(k);
      std::uint64_t truth_n = 0;
      for (int p = 0; p < semlio::kNumClasses; ++p) truth_n += cm.count(c, semlio::class_from_index(p));
      std::printf("%-14s %8.3f %12llu  ->", std::string(semlio::class_name(c)).c_str(), r.iou[static_cast<std::size_t>(k)],
                  static_cast<unsigned long long>(truth_n));
      // Where the points of this class went (shares of at least 2 %).
      for (int p = 0; p < semlio::kNumClasses; ++p) {
        const std::uint64_t n = cm.count(c, semlio::class_from_index(p));
        if (truth_n > 0 && 50 * n >= truth_n) {
          std::printf(" %s %.0f%%", std::string(semlio::class_name(semlio::class_from_index(p))).c_str(),
                      100.0 * static_cast<double>(n) / static_cast<double>(truth_n));
        }
      }
      std::printf("\n");
    }
    std::printf("mIoU %.3f over %d classes, accuracy %.3f\n", r.miou, r.classes, r.accuracy);
    std::printf("ground (merged) IoU %.3f, pole/trunk (merged) IoU %.3f\n", ground, stem);
    const semlio_examples::CoarseReport g = semlio_examples::coarse_report(cm);
    std::printf("coarse:");
    for (std::size_t k = 1; k < kNumCoarse; ++k) {
      if (g.counted[k]) std::printf(" %s %.3f", std::string(kCoarseNames[k]).c_str(), g.iou[k]);
    }
    std::printf(", coarse mIoU %.3f\n", g.miou);
    std::printf("segmenter time per frame: median %.2f ms, max %.2f ms\n", ms[ms.size() / 2], ms.back());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semlio_segment_eval: %s\n", e.what());
    return 1;
  }
  return 0;
}
