#include <catch2/catch.hpp>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/segment/onnx/onnx_segmenter.hpp>
#include <semlio/segment/range_projection.hpp>
#include <semlio_test/data.hpp>
#if defined(SEMLIO_TEST_ONNX_YAML)
#include "model_card_yaml.hpp"
#endif

namespace test_onnx_segmenter {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::RangeChannel;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// tests/data/onnx/tiny_linear.onnx (scripts/make_onnx_fixture.py) computes
// six scores from the normalised input slots s0..s4:
//   0, s0, s1, s2 - 1, s3 + s4, s4 - s3
// and the output class is the first maximum. Written here from the script's
// definition, not from the segmenter.
int tiny_model_class(const std::array<float, 5>& s) {
  const std::array<float, 6> score{0.0f, s[0], s[1], s[2] - 1.0f, s[3] + s[4], s[4] - s[3]};
  int best = 0;
  for (int c = 1; c < 6; ++c) {
    if (score[static_cast<std::size_t>(c)] > score[static_cast<std::size_t>(best)]) best = c;
  }
  return best;
}

// The output -> class mapping of the cards below: six different classes, so
// a wrong mapping shows.
const std::vector<Class> kMapping{Class::kUnlabeled, Class::kRoad,  Class::kBuilding,
                                  Class::kVegetation, Class::kCar, Class::kPole};

std::string model_path() { return semlio_test::data_path("onnx/tiny_linear.onnx"); }

// A card with a channel order and normalisation unlike RangeNet++'s.
semlio::OnnxModelCard permuted_card() {
  semlio::OnnxModelCard card;
  card.model_path = model_path();
  card.projection.image = {.height_px = 16, .width_px = 240, .fov_up_rad = 5.0 * kDeg, .fov_down_rad = -11.0 * kDeg};
  card.projection.channels = {RangeChannel::kZ, RangeChannel::kIntensity, RangeChannel::kRange, RangeChannel::kX,
                              RangeChannel::kY};
  card.projection.channel_mean = {-1.0, 0.4, 15.0, 2.0, -1.0};
  card.projection.channel_std = {0.5, 0.2, 10.0, 8.0, 4.0};
  card.classes = kMapping;
  return card;
}

// RangeNet++'s KITTI card (as tests/data/onnx/tiny_kitti.yaml).
semlio::OnnxModelCard kitti_card() {
  semlio::OnnxModelCard card;
  card.model_path = model_path();
  card.classes = kMapping;
  return card;
}

// The raw channel value of point i, by the channel's definition.
double raw_channel(const semlio::Scan& s, std::size_t i, RangeChannel c) {
  const Eigen::Vector3f& p = s.points[i];
  switch (c) {
    case RangeChannel::kRange: return static_cast<double>(static_cast<float>(p.cast<double>().norm()));
    case RangeChannel::kX: return static_cast<double>(p.x());
    case RangeChannel::kY: return static_cast<double>(p.y());
    case RangeChannel::kZ: return static_cast<double>(p.z());
    case RangeChannel::kIntensity: return static_cast<double>(s.intensity[i]);
  }
  return 0.0;
}

// The class the tiny model gives point i's own channels under `card`.
Class expected_class(const semlio::OnnxModelCard& card, const semlio::Scan& s, std::size_t i) {
  std::array<float, 5> slots{};
  for (std::size_t k = 0; k < 5; ++k) {
    slots[k] = static_cast<float>((raw_channel(s, i, card.projection.channels[k]) - card.projection.channel_mean[k]) /
                                  card.projection.channel_std[k]);
  }
  return card.classes[static_cast<std::size_t>(tiny_model_class(slots))];
}

// Deterministic values in [lo, hi) (a 64-bit LCG; the test's own).
struct Lcg {
  std::uint64_t state = 12345;
  double uniform(double lo, double hi) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return lo + (hi - lo) * static_cast<double>(state >> 11) / 9007199254740992.0;
  }
};

}  // namespace

TEST_CASE("OnnxSegmenter labels every point with the tiny model's known function of its channels", "[segment][onnx]") {
  const semlio::OnnxModelCard card = permuted_card();
  const semlio::OnnxSegmenter seg(card);
  // Points at the centres of every third pixel (rows 1 deg from +5 deg,
  // columns 1.5 deg from -180 deg yaw), so each is alone in its 5 x 5 kNN
  // window, with random range, intensity and thereby x, y, z; behind every
  // fourth a hidden point 5 m farther in the same pixel.
  Lcg rng;
  semlio::Scan scan;
  std::vector<std::size_t> hidden_behind;  // per point: the visible point it hides behind, or itself
  for (int row = 1; row < 16; row += 3) {
    for (int col = 1; col < 240; col += 3) {
      const double pitch = (5.0 - (row + 0.5)) * kDeg;
      const double azimuth = -(-180.0 + (col + 0.5) * 1.5) * kDeg;
      const auto add = [&](double range_m, float intensity) {
        scan.points.emplace_back(static_cast<float>(range_m * std::cos(pitch) * std::cos(azimuth)),
                                 static_cast<float>(range_m * std::cos(pitch) * std::sin(azimuth)),
                                 static_cast<float>(range_m * std::sin(pitch)));
        scan.intensity.push_back(intensity);
      };
      const double r = rng.uniform(2.0, 40.0);
      add(r, static_cast<float>(rng.uniform(0.0, 1.0)));
      const std::size_t visible = scan.size() - 1;
      hidden_behind.push_back(visible);
      if (col % 4 == 1) {
        add(r + 5.0, static_cast<float>(rng.uniform(0.0, 1.0)));
        hidden_behind.push_back(visible);
      }
    }
  }
  seg.segment(scan);
  REQUIRE(scan.labels.size() == scan.size());
  std::array<int, semlio::kNumClasses> seen{};
  std::size_t hidden = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    INFO("point " << i << " at " << scan.points[i].transpose());
    // A hidden point takes its occluder's class: the occluder's pixel is the only one in its window.
    const Class want = expected_class(card, scan, hidden_behind[i]);
    CHECK(scan.labels[i] == want);
    ++seen[static_cast<std::size_t>(want)];
    hidden += hidden_behind[i] != i ? 1U : 0U;
  }
  CHECK(hidden > 50);
  for (const Class c : kMapping) {
    INFO("class " << semlio::class_name(c));
    CHECK(seen[static_cast<std::size_t>(c)] > 0);  // every output of the model occurs: the test sees the whole mapping
  }
}

namespace {

// The test's own RangeNet++ projection (laserscan.py: 64 x 2048, +3/-25 deg),
// nearest point per pixel, and the tiny model's class per occupied pixel.
struct ReferenceImage {
  static constexpr int kH = 64, kW = 2048;
  std::vector<long> pixel;        // per point, -1 without
  std::vector<float> range;       // per point [m]
  std::vector<long> owner;        // per pixel, -1 empty
  std::vector<float> owner_range; // per pixel [m]
  std::vector<Class> label;       // per pixel (unlabeled where empty)

  ReferenceImage(const semlio::OnnxModelCard& card, const semlio::Scan& scan)
      : pixel(scan.size(), -1), range(scan.size(), 0.0f), owner(kH * kW, -1), owner_range(kH * kW, 0.0f),
        label(kH * kW, Class::kUnlabeled) {
    const double fov_up = 3.0 * kDeg, fov_down = -25.0 * kDeg;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const Eigen::Vector3d p = scan.points[i].cast<double>();
      const double depth = p.norm();
      range[i] = static_cast<float>(depth);
      if (!(depth > 0.0)) continue;
      const double yaw = -std::atan2(p.y(), p.x());
      const double pitch = std::asin(p.z() / depth);
      const double u = std::min(kW - 1.0, std::max(0.0, std::floor(0.5 * (yaw / std::numbers::pi + 1.0) * kW)));
      const double v =
          std::min(kH - 1.0, std::max(0.0, std::floor((1.0 - (pitch + std::abs(fov_down)) / (fov_up - fov_down)) * kH)));
      pixel[i] = static_cast<long>(v) * kW + static_cast<long>(u);
      const auto q = static_cast<std::size_t>(pixel[i]);
      if (owner[q] < 0 || range[i] < owner_range[q]) {
        owner[q] = static_cast<long>(i);
        owner_range[q] = range[i];
      }
    }
    for (std::size_t q = 0; q < owner.size(); ++q) {
      if (owner[q] >= 0) label[q] = expected_class(card, scan, static_cast<std::size_t>(owner[q]));
    }
  }

  // RangeNet++'s KNN.forward for point i, written plainly: the whole 5 x 5
  // window (zero padding outside the image, empty pixels infinitely far, the
  // centre at the point's own range), distances weighted by 1 - the
  // normalised Gaussian (sigma 1), a stable sort, the first 5, those within
  // 1 m that are not unlabeled vote, the first most-voted class wins.
  [[nodiscard]] Class knn(std::size_t i) const {
    if (pixel[i] < 0) return Class::kUnlabeled;
    std::array<double, 25> g{};
    double sum = 0.0;
    for (int a = 0; a < 25; ++a) {
      const int dy = a / 5 - 2, dx = a % 5 - 2;
      g[static_cast<std::size_t>(a)] = std::exp(-(dy * dy + dx * dx) / 2.0);
      sum += g[static_cast<std::size_t>(a)];
    }
    struct Candidate {
      double d;
      Class label;
    };
    std::vector<Candidate> cand;
    const long row = pixel[i] / kW, col = pixel[i] % kW;
    for (int a = 0; a < 25; ++a) {
      const long nr = row + a / 5 - 2, nc = col + a % 5 - 2;
      double r = 0.0;
      Class l = Class::kUnlabeled;
      if (nr >= 0 && nr < kH && nc >= 0 && nc < kW) {
        const auto q = static_cast<std::size_t>(nr * kW + nc);
        l = label[q];
        r = a == 12 ? static_cast<double>(range[i])
                    : owner[q] < 0 ? std::numeric_limits<double>::infinity() : static_cast<double>(owner_range[q]);
      }
      cand.push_back({std::abs(r - static_cast<double>(range[i])) * (1.0 - g[static_cast<std::size_t>(a)] / sum), l});
    }
    std::stable_sort(cand.begin(), cand.end(), [](const Candidate& x, const Candidate& y) { return x.d < y.d; });
    std::array<int, semlio::kNumClasses> votes{};
    for (std::size_t j = 0; j < 5; ++j) {
      if (cand[j].d <= 1.0 && cand[j].label != Class::kUnlabeled) ++votes[static_cast<std::size_t>(cand[j].label)];
    }
    std::size_t best = 0;
    for (std::size_t c = 1; c < votes.size(); ++c) {
      if (votes[c] > votes[best]) best = c;
    }
    return static_cast<Class>(best);
  }
};

}  // namespace

TEST_CASE("OnnxSegmenter on a real KITTI scan: each point gets its pixel's nearest point's class (kNN off)",
          "[segment][onnx]") {
  semlio::OnnxModelCard card = kitti_card();
  card.projection.knn.enabled = false;
  const semlio::OnnxSegmenter seg(card);
  semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  REQUIRE(scan.size() > 100000);
  seg.segment(scan);
  REQUIRE(scan.labels.size() == scan.size());
  const ReferenceImage ref(card, scan);
  std::size_t wrong = 0, hidden = 0;
  std::array<int, semlio::kNumClasses> seen{};
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const Class want = ref.pixel[i] < 0 ? Class::kUnlabeled : ref.label[static_cast<std::size_t>(ref.pixel[i])];
    if (scan.labels[i] != want) {
      if (wrong < 5) UNSCOPED_INFO("point " << i << ": " << semlio::class_name(scan.labels[i]) << " != " << semlio::class_name(want));
      ++wrong;
    }
    hidden += ref.pixel[i] >= 0 && ref.owner[static_cast<std::size_t>(ref.pixel[i])] != static_cast<long>(i) ? 1U : 0U;
    ++seen[static_cast<std::size_t>(want)];
  }
  CHECK(wrong == 0);
  CHECK(hidden > 1000);  // the real scan has many points hidden in another point's pixel
  int classes_seen = 0;
  for (const Class c : kMapping) classes_seen += seen[static_cast<std::size_t>(c)] > 0 ? 1 : 0;
  CHECK(classes_seen >= 5);
}

TEST_CASE("OnnxSegmenter on a real KITTI scan with the kNN vote: every point as a plain RangeNet++ kNN gives it",
          "[segment][onnx]") {
  const semlio::OnnxModelCard card = kitti_card();
  const semlio::OnnxSegmenter seg(card);
  const semlio::Scan raw = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  semlio::Scan a = raw, b = raw;
  seg.segment(a);
  seg.segment(b);
  CHECK(a.labels == b.labels);  // deterministic
  const ReferenceImage ref(card, raw);
  std::size_t wrong = 0, changed = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Class want = ref.knn(i);
    if (a.labels[i] != want) {
      if (wrong < 5) UNSCOPED_INFO("point " << i << ": " << semlio::class_name(a.labels[i]) << " != " << semlio::class_name(want));
      ++wrong;
    }
    const Class own = ref.pixel[i] < 0 ? Class::kUnlabeled : ref.label[static_cast<std::size_t>(ref.pixel[i])];
    changed += want != own ? 1U : 0U;
  }
  CHECK(wrong == 0);
  // The vote changes a point's class where its neighbours in range disagree
  // with its pixel (boundaries, hidden points): some, but a minority.
  CHECK(changed > 1000);
  CHECK(changed < a.size() / 5);
}

TEST_CASE("OnnxSegmenter runs a RangeNet++-shaped network (BN, leaky ReLU, strided conv, Resize, 20-class softmax)",
          "[segment][onnx]") {
  // tests/data/onnx/rangenet_like.onnx: random weights, so its labels mean
  // nothing; what must hold is that OpenCV runs these operators and that
  // OnnxSegmenter is exactly projection -> network -> first-max class ->
  // mapping -> kNN, recomposed here from the public pieces and OpenCV.
  semlio::OnnxModelCard card;
  card.model_path = semlio_test::data_path("onnx/rangenet_like.onnx");
  for (int id = 0; id < semlio::kNumClasses; ++id) card.classes.push_back(semlio::class_from_index(id));
  const semlio::OnnxSegmenter seg(card);
  semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  seg.segment(scan);
  REQUIRE(scan.labels.size() == scan.size());

  semlio::RangeProjection proj(card.projection);
  proj.project(scan);
  cv::dnn::Net net = cv::dnn::readNetFromONNX(card.model_path);
  const int sizes[4] = {1, 5, 64, 2048};
  cv::Mat blob(4, sizes, CV_32F);
  std::copy(proj.input().begin(), proj.input().end(), blob.ptr<float>());
  net.setInput(blob);
  const cv::Mat out = net.forward();
  REQUIRE(out.dims == 4);
  REQUIRE(out.size[1] == 20);
  const std::size_t hw = proj.pixel_count();
  std::vector<Class> pixel_labels(hw);
  std::array<int, semlio::kNumClasses> seen{};
  const float* p = out.ptr<float>();
  for (std::size_t q = 0; q < hw; ++q) {
    std::size_t best = 0;
    for (std::size_t c = 1; c < 20; ++c) {
      if (p[c * hw + q] > p[best * hw + q]) best = c;
    }
    pixel_labels[q] = semlio::class_from_index(static_cast<int>(best));
    if (proj.pixel_points()[q] >= 0) ++seen[best];
  }
  std::vector<Class> want(scan.size());
  proj.back_project(pixel_labels, want);
  CHECK(scan.labels == want);
  int classes_seen = 0;
  for (const int n : seen) classes_seen += n > 0 ? 1 : 0;
  CHECK(classes_seen >= 3);  // random weights still spread the scan over several classes
}

TEST_CASE("OnnxSegmenter: an empty scan gives no labels, and a scan without intensity is a ValueError", "[segment][onnx]") {
  const semlio::OnnxSegmenter seg(kitti_card());
  semlio::Scan empty;
  seg.segment(empty);
  CHECK(empty.labels.empty());
  semlio::Scan no_intensity;
  no_intensity.points = {{10.0f, 0.0f, 0.0f}};
  CHECK_THROWS_AS(seg.segment(no_intensity), semlio::ValueError);
}

TEST_CASE("OnnxSegmenter: a card that does not fit the model is a typed error naming it", "[segment][onnx]") {
  SECTION("missing model file") {
    semlio::OnnxModelCard card = kitti_card();
    card.model_path = semlio_test::data_path("onnx/missing.onnx");
    CHECK_THROWS_AS(semlio::OnnxSegmenter(card), semlio::IoError);
    CHECK_THROWS_WITH(semlio::OnnxSegmenter(card), Catch::Contains("missing.onnx"));
  }
  SECTION("a file that is not an ONNX model") {
    semlio::OnnxModelCard card = kitti_card();
    card.model_path = semlio_test::data_path("onnx/tiny_kitti.yaml");
    CHECK_THROWS_AS(semlio::OnnxSegmenter(card), semlio::FormatError);
  }
  SECTION("fewer classes than the model has outputs") {
    semlio::OnnxModelCard card = kitti_card();
    card.classes.pop_back();
    CHECK_THROWS_AS(semlio::OnnxSegmenter(card), semlio::FormatError);
    CHECK_THROWS_WITH(semlio::OnnxSegmenter(card), Catch::Contains("output is 1 x 6 x 64 x 2048") &&
                                                      Catch::Contains("1 x 5 (one score per entry of 'classes')"));
  }
  SECTION("more classes than the model has outputs") {
    semlio::OnnxModelCard card = kitti_card();
    card.classes.push_back(Class::kTrunk);
    CHECK_THROWS_AS(semlio::OnnxSegmenter(card), semlio::FormatError);
  }
  SECTION("fewer input channels than the model takes") {
    semlio::OnnxModelCard card = kitti_card();
    card.projection.channels.pop_back();
    card.projection.channel_mean.pop_back();
    card.projection.channel_std.pop_back();
    CHECK_THROWS_AS(semlio::OnnxSegmenter(card), semlio::FormatError);
    CHECK_THROWS_WITH(semlio::OnnxSegmenter(card), Catch::Contains("1 x 4 x 64 x 2048 input"));
  }
  SECTION("no classes, or a class id outside the learning classes") {
    semlio::OnnxModelCard card = kitti_card();
    card.classes.clear();
    CHECK_THROWS_AS(semlio::OnnxSegmenter(card), semlio::ConfigError);
    card = kitti_card();
    card.classes[3] = static_cast<Class>(20);
    CHECK_THROWS_AS(semlio::OnnxSegmenter(card), semlio::ConfigError);
    CHECK_THROWS_WITH(semlio::OnnxSegmenter(card), Catch::Contains("classes[3]"));
  }
  SECTION("an invalid projection") {
    semlio::OnnxModelCard card = kitti_card();
    card.projection.channel_std[1] = -1.0;
    CHECK_THROWS_AS(semlio::OnnxSegmenter(card), semlio::ConfigError);
  }
}

#if defined(SEMLIO_TEST_ONNX_YAML)
namespace {

// Writes `text` to a card file in a scratch folder beside a copy of the model.
std::string write_card(const std::string& name, const std::string& text) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "semlio_test_onnx_cards";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / name) << text;
  return (dir / name).string();
}

}  // namespace

TEST_CASE("load_model_card_yaml reads tests/data/onnx/tiny_kitti.yaml", "[segment][onnx]") {
  const semlio::OnnxModelCard card = semlio_examples::load_model_card_yaml(semlio_test::data_path("onnx/tiny_kitti.yaml"));
  CHECK(std::filesystem::equivalent(card.model_path, model_path()));  // relative to the card
  CHECK(card.classes == kMapping);
  const semlio::RangeProjectionConfig defaults;  // the card spells out RangeNet++'s KITTI values
  CHECK(card.projection.image.height_px == 64);
  CHECK(card.projection.image.width_px == 2048);
  CHECK(card.projection.image.fov_up_rad == Approx(3.0 * kDeg));
  CHECK(card.projection.image.fov_down_rad == Approx(-25.0 * kDeg));
  CHECK(card.projection.channels == defaults.channels);
  CHECK(card.projection.channel_mean == defaults.channel_mean);
  CHECK(card.projection.channel_std == defaults.channel_std);
  CHECK(card.projection.knn.enabled);
  CHECK(card.projection.knn.search_px == 5);
  CHECK(card.projection.knn.k == 5);
  CHECK(card.projection.knn.cutoff_m == 1.0);
  // ... and it runs.
  const semlio::OnnxSegmenter seg(card);
  semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000001.bin"));
  seg.segment(scan);
  CHECK(scan.labels.size() == scan.size());
}

TEST_CASE("load_model_card_yaml: rangenet_like.yaml lists SemanticKITTI's 20 learning classes in RangeNet++'s order",
          "[segment][onnx]") {
  const semlio::OnnxModelCard card =
      semlio_examples::load_model_card_yaml(semlio_test::data_path("onnx/rangenet_like.yaml"));
  REQUIRE(card.classes.size() == 20);
  for (int id = 0; id < semlio::kNumClasses; ++id) CHECK(card.classes[static_cast<std::size_t>(id)] == semlio::class_from_index(id));
  CHECK_NOTHROW(semlio::OnnxSegmenter(card));
}

TEST_CASE("load_model_card_yaml: every problem is a ConfigError naming the file, line and key", "[segment][onnx]") {
  const auto fails_with = [](const std::string& name, const std::string& text, const std::string& what) {
    const std::string path = write_card(name, text);
    INFO(text);
    CHECK_THROWS_AS(semlio_examples::load_model_card_yaml(path), semlio::ConfigError);
    CHECK_THROWS_WITH(semlio_examples::load_model_card_yaml(path), Catch::Contains(path) && Catch::Contains(what));
  };
  const std::string head = "model: tiny.onnx\nclasses: [unlabeled, car]\n";
  fails_with("unknown_key.yaml", head + "imgae: {height_px: 64}\n", ":3: unknown key 'imgae'");
  fails_with("unknown_image_key.yaml", head + "image:\n  height: 64\n", ":4: unknown key 'image.height'");
  fails_with("bad_height.yaml", head + "image:\n  height_px: 6.5\n", ":4: 'image.height_px' must be an integer, got '6.5'");
  fails_with("bad_std.yaml", head + "channels:\n  - {name: range, mean: 1, std: 2}\n  - {name: z, mean: 0, std: 0}\n",
             ":5: 'channels[1].std' must be > 0, got '0'");
  fails_with("bad_channel.yaml", head + "channels:\n  - {name: depth, mean: 1, std: 2}\n",
             ":4: 'channels[0].name' must be one of range, x, y, z, intensity, got 'depth'");
  fails_with("missing_std.yaml", head + "channels:\n  - {name: range, mean: 1}\n", ":4: 'channels[0]' needs name, mean and std");
  fails_with("bad_class.yaml", "model: tiny.onnx\nclasses:\n  - car\n  - lamppost\n",
             ":4: 'classes[1]' must be a learning class name");
  fails_with("bad_knn.yaml", head + "knn: {k: five}\n", ":3: 'knn.k' must be an integer, got 'five'");
  fails_with("even_search.yaml", head + "knn:\n  search_px: 4\n", ":4: in 'knn': RangeProjectionConfig.knn.search_px");
  fails_with("fov.yaml", head + "image:\n  fov_up_deg: -30\n", ":4: in 'image': RangeProjectionConfig.image.fov_up_rad");
  fails_with("no_model.yaml", "classes: [car]\n", "no 'model'");
  fails_with("no_classes.yaml", "model: tiny.onnx\n", "no 'classes'");
  fails_with("not_yaml.yaml", "model: [tiny.onnx\n", "not valid YAML");
  // Class ids are accepted as well as names.
  const semlio::OnnxModelCard ids = semlio_examples::load_model_card_yaml(write_card("ids.yaml", "model: /abs/m.onnx\nclasses: [0, 9, car]\n"));
  CHECK(ids.classes == std::vector<Class>{Class::kUnlabeled, Class::kRoad, Class::kCar});
  CHECK(ids.model_path == "/abs/m.onnx");
  CHECK_THROWS_AS(semlio_examples::load_model_card_yaml("/nonexistent/card.yaml"), semlio::IoError);
}
#endif

}  // namespace test_onnx_segmenter
