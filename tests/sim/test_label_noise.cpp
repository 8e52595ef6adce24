#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstdint>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/eval/miou.hpp>
#include <semlio/sim/label_noise.hpp>
#include <semlio/sim/rng.hpp>

namespace test_label_noise {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::sim::LabelNoise;
using semlio::sim::LabelNoiseConfig;
using semlio::sim::RangeImageLabels;

namespace {

// A synthetic 64 x 1024 range image of a street: road, sidewalk/parking and
// terrain rings below, buildings / vegetation / fences above (sky rows have no
// return), and objects in front: cars, a truck, people, poles with signs,
// trees (trunk + canopy). One point per pixel.
struct Scene {
  static constexpr int kRings = 64;
  static constexpr int kColumns = 1024;
  std::vector<Class> labels;
  std::vector<std::uint16_t> instances;
  std::vector<std::uint16_t> rings;
  std::vector<std::uint16_t> columns;

  [[nodiscard]] RangeImageLabels view() const { return {labels, instances, rings, columns, kRings, kColumns}; }
};

Scene make_scene(std::uint64_t seed) {
  semlio::sim::Xoshiro256 rng(seed);
  auto uniform_int = [&](int lo, int hi) { return lo + static_cast<int>(rng.uniform() * (hi - lo + 1)); };
  std::vector<Class> img(Scene::kRings * Scene::kColumns, Class::kUnlabeled);
  std::vector<std::uint16_t> inst(img.size(), 0);
  auto at = [&](int r, int c) -> std::size_t {
    return static_cast<std::size_t>(r) * Scene::kColumns + static_cast<std::size_t>((c % Scene::kColumns + Scene::kColumns) % Scene::kColumns);
  };
  auto fill = [&](int r0, int r1, int c0, int c1, Class k, std::uint16_t id) {
    for (int r = std::max(0, r0); r <= std::min(Scene::kRings - 1, r1); ++r) {
      for (int c = c0; c <= c1; ++c) {
        img[at(r, c)] = k;
        inst[at(r, c)] = id;
      }
    }
  };
  // Ground and background in column bands.
  for (int c = 0; c < Scene::kColumns;) {
    const int w = uniform_int(40, 140);
    const double u = rng.uniform();
    fill(0, 13, c, c + w - 1, Class::kRoad, 0);
    fill(14, 19, c, c + w - 1, u < 0.2 ? Class::kParking : Class::kSidewalk, 0);
    fill(20, 25, c, c + w - 1, u < 0.5 ? Class::kTerrain : Class::kSidewalk, 0);
    const int top = uniform_int(40, 60);
    const Class bg = u < 0.45 ? Class::kBuilding : (u < 0.8 ? Class::kVegetation : Class::kFence);
    fill(26, bg == Class::kFence ? 34 : top, c, c + w - 1, bg, 0);
    if (bg == Class::kFence) fill(35, top, c, c + w - 1, Class::kBuilding, 0);
    c += w;
  }
  std::uint16_t next_id = 1;
  // Cars and a truck.
  for (int k = 0; k < 7; ++k) {
    const int c = uniform_int(0, Scene::kColumns - 1);
    const bool truck = k == 0;
    fill(6, truck ? 40 : 30, c, c + uniform_int(truck ? 60 : 25, truck ? 90 : 55), truck ? Class::kTruck : Class::kCar, next_id++);
  }
  // People.
  for (int k = 0; k < 3; ++k) {
    const int c = uniform_int(0, Scene::kColumns - 1);
    fill(10, 30, c, c + uniform_int(3, 6), Class::kPerson, next_id++);
  }
  // Poles with signs, trees.
  for (int k = 0; k < 6; ++k) {
    const int c = uniform_int(0, Scene::kColumns - 1);
    fill(12, 56, c, c + 1, Class::kPole, next_id++);
    if (k % 2 == 0) fill(50, 56, c - 3, c + 4, Class::kTrafficSign, next_id++);
  }
  for (int k = 0; k < 5; ++k) {
    const int c = uniform_int(0, Scene::kColumns - 1);
    fill(14, 36, c, c + 2, Class::kTrunk, next_id++);
    fill(37, 55, c - 10, c + 12, Class::kVegetation, 0);
  }
  Scene s;
  for (int r = 0; r < Scene::kRings; ++r) {
    for (int c = 0; c < Scene::kColumns; ++c) {
      if (img[at(r, c)] == Class::kUnlabeled) continue;  // sky: no return
      s.labels.push_back(img[at(r, c)]);
      s.instances.push_back(inst[at(r, c)]);
      s.rings.push_back(static_cast<std::uint16_t>(r));
      s.columns.push_back(static_cast<std::uint16_t>(c));
    }
  }
  return s;
}

// Chessboard distance (capped at 3) of each point's pixel to the nearest
// pixel with another label or instance among its 8 neighbours; 0 = boundary.
std::vector<int> boundary_distance(const Scene& s) {
  std::vector<int> pix(Scene::kRings * Scene::kColumns, -1);
  for (std::size_t i = 0; i < s.labels.size(); ++i) pix[s.rings[i] * Scene::kColumns + s.columns[i]] = static_cast<int>(i);
  auto differs_within = [&](std::size_t i, int radius) {
    for (int dr = -radius; dr <= radius; ++dr) {
      for (int dc = -radius; dc <= radius; ++dc) {
        const int r = s.rings[i] + dr;
        const int c = (s.columns[i] + dc + Scene::kColumns) % Scene::kColumns;
        if (r < 0 || r >= Scene::kRings) continue;
        const int q = pix[static_cast<std::size_t>(r * Scene::kColumns + c)];
        if (q < 0) continue;
        const auto k = static_cast<std::size_t>(q);
        if (s.labels[k] != s.labels[i] || s.instances[k] != s.instances[i]) return true;
      }
    }
    return false;
  };
  std::vector<int> out(s.labels.size(), 3);
  for (std::size_t i = 0; i < s.labels.size(); ++i) {
    for (int radius = 1; radius <= 3; ++radius) {
      if (differs_within(i, radius)) {
        out[i] = radius - 1;
        break;
      }
    }
  }
  return out;
}

}  // namespace

TEST_CASE("label noise reaches the target mIoU on unseen scenes", "[sim]") {
  const Scene calib_a = make_scene(1);
  const Scene calib_b = make_scene(2);
  const Scene calib_c = make_scene(3);
  for (double target : {0.5, 0.8}) {
    LabelNoiseConfig cfg;
    cfg.target_miou = target;
    LabelNoise noise(cfg);
    const double achieved_calib = noise.calibrate({calib_a.view(), calib_b.view(), calib_c.view()});
    INFO("target " << target << " calibration mIoU " << achieved_calib << " scale " << noise.error_scale());
    CHECK(achieved_calib == Approx(target).margin(0.01));
    // Scenes the knob never saw, several frames each.
    semlio::eval::ConfusionMatrix pooled;
    for (std::uint64_t seed = 10; seed < 14; ++seed) {
      const Scene s = make_scene(seed);
      const auto pred = noise.predict(s.view(), seed);
      const double m = semlio::eval::miou(s.labels, pred).miou;
      INFO("scene " << seed << " mIoU " << m << " accuracy " << semlio::eval::miou(s.labels, pred).accuracy);
      CHECK(m == Approx(target).margin(0.07));
      pooled.add(s.labels, pred);
    }
    CHECK(pooled.report().miou == Approx(target).margin(0.05));
  }
}

TEST_CASE("label noise errors concentrate at range-image boundaries", "[sim]") {
  const Scene s = make_scene(3);
  LabelNoise noise(LabelNoiseConfig{});
  noise.calibrate(s.view());
  const auto pred = noise.predict(s.view(), 7);
  const auto dist = boundary_distance(s);
  double err_b = 0.0;
  double n_b = 0.0;
  double err_i = 0.0;
  double n_i = 0.0;
  for (std::size_t i = 0; i < pred.size(); ++i) {
    const double e = pred[i] != s.labels[i] ? 1.0 : 0.0;
    if (dist[i] == 0) {
      err_b += e;
      n_b += 1.0;
    } else if (dist[i] >= 2) {  // interior: no other segment within 2 pixels
      err_i += e;
      n_i += 1.0;
    }
  }
  INFO("boundary error " << err_b / n_b << " interior error " << err_i / n_i << " accuracy "
                         << semlio::eval::miou(s.labels, pred).accuracy);
  CHECK(err_b / n_b > 5.0 * (err_i / n_i));
  CHECK(err_i / n_i > 0.0);  // interior errors exist (region-level, confusions)
}

TEST_CASE("label noise confuses similar classes", "[sim]") {
  const Scene s = make_scene(4);
  LabelNoiseConfig cfg;
  cfg.target_miou = 0.4;
  LabelNoise noise(cfg);
  noise.calibrate(s.view());
  semlio::eval::ConfusionMatrix m;
  m.add(s.labels, noise.predict(s.view(), 1));
  // Road errors go to sidewalk/parking far more than to building.
  CHECK(m.count(Class::kRoad, Class::kSidewalk) + m.count(Class::kRoad, Class::kParking) >
        10 * m.count(Class::kRoad, Class::kBuilding));
  CHECK(m.count(Class::kCar, Class::kTruck) + m.count(Class::kCar, Class::kOtherVehicle) > 0);
  CHECK(m.count(Class::kVegetation, Class::kTerrain) > 0);
  CHECK(m.count(Class::kPole, Class::kTrafficSign) > 0);
  CHECK(m.count(Class::kCar, Class::kTrafficSign) == 0);  // not similar and never adjacent
}

TEST_CASE("label noise is deterministic and frame-dependent", "[sim]") {
  const Scene s = make_scene(5);
  LabelNoise a(LabelNoiseConfig{});
  LabelNoise b(LabelNoiseConfig{});
  CHECK(a.calibrate(s.view()) == b.calibrate(s.view()));
  CHECK(a.error_scale() == b.error_scale());
  CHECK(a.predict(s.view(), 3) == b.predict(s.view(), 3));
  CHECK(a.predict(s.view(), 3) != a.predict(s.view(), 4));
  LabelNoiseConfig other;
  other.seed = 99;
  LabelNoise c(other);
  c.set_error_scale(a.error_scale());
  CHECK(c.predict(s.view(), 3) != a.predict(s.view(), 3));
  // Perfect quality: predictions equal the truth.
  LabelNoiseConfig perfect;
  perfect.target_miou = 1.0;
  LabelNoise p(perfect);
  CHECK(p.calibrate(s.view()) == 1.0);
  CHECK(p.predict(s.view(), 0) == s.labels);
}

TEST_CASE("label noise rejects bad input", "[sim]") {
  const Scene s = make_scene(6);
  LabelNoiseConfig bad;
  bad.target_miou = 0.0;
  CHECK_THROWS_AS(LabelNoise(bad), semlio::ConfigError);
  LabelNoise n(LabelNoiseConfig{});
  CHECK_THROWS_AS(n.predict(s.view(), 0), semlio::ConfigError);  // not calibrated
  n.set_error_scale(1.0);
  RangeImageLabels short_rings = s.view();
  short_rings.rings = short_rings.rings.first(10);
  CHECK_THROWS_AS(n.predict(short_rings, 0), semlio::ValueError);
  RangeImageLabels small = s.view();
  small.num_rings = 32;
  CHECK_THROWS_AS(n.predict(small, 0), semlio::ValueError);
}

TEST_CASE("azimuth columns follow the RangeNet++ convention", "[sim]") {
  const std::vector<Eigen::Vector3f> pts{{-1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, -1, 0}};
  const auto cols = semlio::sim::azimuth_columns(pts, 2048);
  CHECK(cols[1] == 512);
  CHECK(cols[2] == 1024);
  CHECK(cols[3] == 1536);
  CHECK((cols[0] == 0 || cols[0] == 2047));
}

}  // namespace test_label_noise
