#pragma once
/// \file
/// A second label stream that behaves like a segmentation network's
/// predictions (RangeNet++-style) from exact per-point labels:
/// - errors concentrate at object boundaries in the range image: the flip
///   probability of a point decays with its pixel distance d to the nearest
///   pixel whose 8-neighbour has another label or instance,
///   p(d) = 1 - exp(-s (beta_boundary exp(-d / decay) + beta_interior));
///   a flipped point near a boundary usually takes the neighbouring segment's
///   class (bleeding), otherwise a similar class;
/// - class confusions between similar classes (road <-> sidewalk/parking,
///   vegetation <-> terrain, car <-> truck/other-vehicle, pole <->
///   traffic-sign, building <-> fence, ...);
/// - region-level confusion: a whole object (instance), or all points of one
///   class inside a range-image tile, switch to a similar class with
///   probability 1 - exp(-s beta_region);
/// - similar classes absent from the frame are avoided (absent_class_rate);
/// - one quality knob: the error scale s is calibrated by bisection so the mIoU
///   (eval/miou.hpp rules, confusion pooled over the calibration frames as
///   SemanticKITTI pools a sequence) equals `target_miou`; the same s is then
///   used for every frame. Per-frame mIoU scatters around it (rare classes
///   with few points weigh as much as road), typically a few hundredths
///   below the pooled value.
/// Points whose true label is unlabeled keep unlabeled (they are ignored by
/// the mIoU). Randomness is counter-based (seed, frame, point), so a frame's
/// predictions do not depend on the order frames are generated in.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/eval/miou.hpp>
#include <semlio/sim/rng.hpp>

namespace semlio::sim {

/// Settings of the prediction-noise model. Only target_miou is meant to be
/// changed routinely; the rest shape where the errors go.
struct LabelNoiseConfig {
  double target_miou = 0.5;         ///< quality knob: mIoU the predictions aim at (RangeNet++ ~0.5)
  std::uint64_t seed = 1;           ///< randomness seed
  double beta_boundary = 1.0;       ///< flip rate per unit scale at a boundary pixel
  double beta_interior = 0.01;      ///< flip rate per unit scale far from boundaries
  double boundary_decay_px = 0.8;   ///< e-folding distance of the boundary rate [pixels]
  double beta_region = 0.03;        ///< whole-region confusion rate per unit scale
  double neighbour_share = 0.75;    ///< flipped points at d <= 1 take the neighbour segment's class
  double absent_class_rate = 0.0;   ///< share of confusions kept when the similar class is absent from the frame (else a present similar class, or none)
  int tile_rings = 8;               ///< stuff-class region tiles: rings per tile
  int tile_columns = 64;            ///< stuff-class region tiles: columns per tile
};

/// Per-point labels with their range-image coordinates (non-owning views; the
/// data must outlive the call).
struct RangeImageLabels {
  std::span<const Class> labels;                ///< exact label per point
  std::span<const std::uint16_t> instances;     ///< instance per point (empty: all 0)
  std::span<const std::uint16_t> rings;         ///< row: beam index, < num_rings
  std::span<const std::uint16_t> columns;       ///< column: azimuth bin, < num_columns
  int num_rings = 64;                           ///< range-image height
  int num_columns = 2048;                       ///< range-image width (azimuth wraps around)
};

/// Azimuth column of each point, RangeNet++ convention
/// u = floor(0.5 (1 - atan2(y, x) / pi) W) mod W: column 0 looks backwards
/// (-x), W/4 left, W/2 forward, 3W/4 right (clockwise seen from above).
inline std::vector<std::uint16_t> azimuth_columns(const std::vector<Eigen::Vector3f>& points, int num_columns) {
  if (num_columns <= 0 || num_columns > 65535) {
    throw ConfigError("azimuth_columns: num_columns must be in 1..65535, got " + std::to_string(num_columns));
  }
  std::vector<std::uint16_t> out(points.size());
  const double w = static_cast<double>(num_columns);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double yaw = std::atan2(static_cast<double>(points[i].y()), static_cast<double>(points[i].x()));
    auto u = static_cast<long>(std::floor(0.5 * (1.0 - yaw / std::numbers::pi) * w));
    u = ((u % num_columns) + num_columns) % num_columns;
    out[i] = static_cast<std::uint16_t>(u);
  }
  return out;
}

namespace detail {

/// Up to three similar classes with cumulative choice probabilities.
struct Similar {
  std::array<Class, 3> cls;
  std::array<double, 3> cum;
};

/// Which classes a network confuses a class with (weights sum to 1).
inline Similar similar_classes(Class c) {
  using C = Class;
  switch (c) {
    case C::kCar: return {{C::kTruck, C::kOtherVehicle, C::kOtherVehicle}, {0.5, 1.0, 1.0}};
    case C::kBicycle: return {{C::kBicyclist, C::kMotorcycle, C::kMotorcycle}, {0.5, 1.0, 1.0}};
    case C::kMotorcycle: return {{C::kBicycle, C::kMotorcyclist, C::kMotorcyclist}, {0.5, 1.0, 1.0}};
    case C::kTruck: return {{C::kCar, C::kOtherVehicle, C::kOtherVehicle}, {0.6, 1.0, 1.0}};
    case C::kOtherVehicle: return {{C::kTruck, C::kCar, C::kCar}, {0.5, 1.0, 1.0}};
    case C::kPerson: return {{C::kBicyclist, C::kTrunk, C::kTrunk}, {0.7, 1.0, 1.0}};
    case C::kBicyclist: return {{C::kPerson, C::kBicycle, C::kBicycle}, {0.6, 1.0, 1.0}};
    case C::kMotorcyclist: return {{C::kBicyclist, C::kMotorcycle, C::kMotorcycle}, {0.5, 1.0, 1.0}};
    case C::kRoad: return {{C::kSidewalk, C::kParking, C::kParking}, {0.5, 1.0, 1.0}};
    case C::kParking: return {{C::kRoad, C::kSidewalk, C::kSidewalk}, {0.5, 1.0, 1.0}};
    case C::kSidewalk: return {{C::kRoad, C::kParking, C::kTerrain}, {0.5, 0.75, 1.0}};
    case C::kOtherGround: return {{C::kSidewalk, C::kTerrain, C::kTerrain}, {0.5, 1.0, 1.0}};
    case C::kBuilding: return {{C::kFence, C::kVegetation, C::kVegetation}, {0.6, 1.0, 1.0}};
    case C::kFence: return {{C::kBuilding, C::kVegetation, C::kVegetation}, {0.6, 1.0, 1.0}};
    case C::kVegetation: return {{C::kTerrain, C::kTrunk, C::kTrunk}, {0.6, 1.0, 1.0}};
    case C::kTrunk: return {{C::kVegetation, C::kPole, C::kPole}, {0.6, 1.0, 1.0}};
    case C::kTerrain: return {{C::kVegetation, C::kSidewalk, C::kSidewalk}, {0.6, 1.0, 1.0}};
    case C::kPole: return {{C::kTrafficSign, C::kTrunk, C::kTrunk}, {0.5, 1.0, 1.0}};
    case C::kTrafficSign: return {{C::kPole, C::kBuilding, C::kBuilding}, {0.7, 1.0, 1.0}};
    case C::kUnlabeled: break;
  }
  return {{C::kUnlabeled, C::kUnlabeled, C::kUnlabeled}, {1.0, 1.0, 1.0}};
}

/// A similar class of c chosen by a uniform draw u in [0, 1).
inline Class pick_similar(Class c, double u) {
  const Similar s = similar_classes(c);
  for (std::size_t k = 0; k < 3; ++k) {
    if (u < s.cum[k]) return s.cls[k];
  }
  return s.cls[2];
}

/// A similar class of c present in the frame, chosen by u among the present
/// ones with their weights; c itself (no confusion) when none is present.
inline Class pick_similar_present(Class c, double u, const std::array<bool, kNumClasses>& present) {
  const Similar s = similar_classes(c);
  std::array<double, 3> w{};
  double total = 0.0;
  double prev = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    const double wk = s.cum[k] - prev;
    prev = s.cum[k];
    if (present[static_cast<std::size_t>(index(s.cls[k]))]) w[k] = wk;
    total += w[k];
  }
  if (total <= 0.0) return c;
  double acc = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    acc += w[k] / total;
    if (w[k] > 0.0 && u < acc) return s.cls[k];
  }
  for (std::size_t k = 3; k-- > 0;) {
    if (w[k] > 0.0) return s.cls[k];
  }
  return s.cls[0];
}

/// Everything about one frame that does not depend on the error scale.
struct NoiseDraws {
  std::vector<Class> truth;
  std::vector<std::uint8_t> distance_px;  ///< to the nearest boundary pixel, capped
  std::vector<Class> neighbour;           ///< class across that boundary (own class if none)
  std::vector<double> u_flip;
  std::vector<double> u_kind;
  std::vector<Class> similar;             ///< similar class drawn for this point
  std::vector<std::uint32_t> region;      ///< region index of the point
  std::vector<double> region_u;           ///< per region: flip draw
  std::vector<Class> region_class;        ///< per region: class it switches to
};

inline constexpr std::uint8_t kMaxDistancePx = 15;

/// Builds the range image, boundary distances and all random draws of a frame.
inline NoiseDraws prepare_draws(const RangeImageLabels& in, const LabelNoiseConfig& cfg, std::uint64_t frame) {
  const std::size_t n = in.labels.size();
  if (in.rings.size() != n || in.columns.size() != n || (!in.instances.empty() && in.instances.size() != n)) {
    throw ValueError("LabelNoise: " + std::to_string(n) + " labels but " + std::to_string(in.rings.size()) +
                     " rings, " + std::to_string(in.columns.size()) + " columns, " +
                     std::to_string(in.instances.size()) + " instances");
  }
  if (in.num_rings <= 0 || in.num_columns <= 0) {
    throw ConfigError("LabelNoise: range image size must be positive, got " + std::to_string(in.num_rings) + "x" +
                      std::to_string(in.num_columns));
  }
  const auto H = static_cast<std::size_t>(in.num_rings);
  const auto W = static_cast<std::size_t>(in.num_columns);
  auto inst = [&](std::size_t i) -> std::uint32_t { return in.instances.empty() ? 0U : in.instances[i]; };
  auto key_of = [&](std::size_t i) { return (static_cast<std::uint32_t>(index(in.labels[i])) << 16U) | inst(i); };

  auto wrap = [W](std::size_t c, int dc) -> std::size_t {  // column c + dc, azimuth wraps
    if (dc < 0) return c == 0 ? W - 1 : c - 1;
    if (dc > 0) return c + 1 == W ? 0 : c + 1;
    return c;
  };
  // Range image: the last point in each pixel represents it.
  constexpr std::uint32_t kEmpty = 0xFFFFFFFFU;
  std::vector<std::uint32_t> pixel(H * W, kEmpty);
  for (std::size_t i = 0; i < n; ++i) {
    if (in.rings[i] >= H || in.columns[i] >= W) {
      throw ValueError("LabelNoise: point " + std::to_string(i) + " at ring " + std::to_string(in.rings[i]) +
                       ", column " + std::to_string(in.columns[i]) + " is outside the " + std::to_string(H) + "x" +
                       std::to_string(W) + " range image");
    }
    pixel[in.rings[i] * W + in.columns[i]] = static_cast<std::uint32_t>(i);
  }
  // Boundary pixels (8-neighbourhood, azimuth wraps) and the class across.
  std::vector<std::uint8_t> dist(H * W, kMaxDistancePx);
  std::vector<Class> across(H * W, Class::kUnlabeled);
  std::vector<std::size_t> queue;
  queue.reserve(H * W);
  for (std::size_t r = 0; r < H; ++r) {
    for (std::size_t c = 0; c < W; ++c) {
      const std::uint32_t p = pixel[r * W + c];
      if (p == kEmpty) continue;
      const std::uint32_t key = key_of(p);
      across[r * W + c] = in.labels[p];
      std::array<int, kNumClasses> votes{};
      bool boundary = false;
      for (int dr = -1; dr <= 1; ++dr) {
        const long rr = static_cast<long>(r) + dr;
        if (rr < 0 || rr >= static_cast<long>(H)) continue;
        for (int dc = -1; dc <= 1; ++dc) {
          if (dr == 0 && dc == 0) continue;
          const std::size_t cc = wrap(c, dc);
          const std::uint32_t q = pixel[static_cast<std::size_t>(rr) * W + cc];
          if (q == kEmpty || key_of(q) == key) continue;
          boundary = true;
          if (in.labels[q] != in.labels[p]) ++votes[static_cast<std::size_t>(index(in.labels[q]))];
        }
      }
      if (!boundary) continue;
      dist[r * W + c] = 0;
      queue.push_back(r * W + c);
      const auto best = std::max_element(votes.begin() + 1, votes.end());
      if (*best > 0) across[r * W + c] = class_from_index(static_cast<int>(best - votes.begin()));
    }
  }
  // Multi-source BFS (chessboard distance) inside same-key segments; each
  // pixel inherits the class across its nearest boundary.
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::size_t pix = queue[head];
    const std::size_t r = pix / W;
    const std::size_t c = pix % W;
    const std::uint8_t d = dist[pix];
    if (d + 1 >= kMaxDistancePx) continue;
    for (int dr = -1; dr <= 1; ++dr) {
      const long rr = static_cast<long>(r) + dr;
      if (rr < 0 || rr >= static_cast<long>(H)) continue;
      for (int dc = -1; dc <= 1; ++dc) {
        const std::size_t cc = wrap(c, dc);
        const std::size_t q = static_cast<std::size_t>(rr) * W + cc;
        if (pixel[q] == kEmpty || dist[q] <= d + 1) continue;
        dist[q] = static_cast<std::uint8_t>(d + 1);
        across[q] = across[pix];
        queue.push_back(q);
      }
    }
  }

  NoiseDraws out;
  out.truth.assign(in.labels.begin(), in.labels.end());
  out.distance_px.resize(n);
  out.neighbour.resize(n);
  out.u_flip.resize(n);
  out.u_kind.resize(n);
  out.similar.resize(n);
  out.region.resize(n);
  std::unordered_map<std::uint64_t, std::uint32_t> region_index;
  // Networks mostly confuse a class with similar classes in view: a similar
  // class absent from the frame is kept only at absent_class_rate, else a
  // present similar class is used, or the point keeps its class. Spurious
  // classes would each add an IoU of 0 to the mean and make the knob jumpy.
  std::array<bool, kNumClasses> present{};
  for (const Class c : in.labels) present[static_cast<std::size_t>(index(c))] = true;
  auto choose = [&](Class c, double u, double u_keep) {
    const Class pick = pick_similar(c, u);
    if (present[static_cast<std::size_t>(index(pick))] || u_keep < cfg.absent_class_rate) return pick;
    return pick_similar_present(c, u, present);
  };
  const std::uint64_t frame_key = Xoshiro256::hashed_uniform_bits(cfg.seed, frame);
  std::uint64_t last_key = ~0ULL;
  std::uint32_t last_region = 0;
  const auto tr = static_cast<std::size_t>(std::max(1, cfg.tile_rings));
  const auto tc = static_cast<std::size_t>(std::max(1, cfg.tile_columns));
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t pix = in.rings[i] * W + in.columns[i];
    const std::uint32_t rep = pixel[pix];
    if (key_of(rep) != key_of(i)) {
      // Hidden behind another point of another segment in the same pixel.
      out.distance_px[i] = 0;
      out.neighbour[i] = in.labels[rep];
    } else {
      out.distance_px[i] = dist[pix];
      out.neighbour[i] = across[pix];
    }
    // Counter-based draws: one hash per point, then one mix per draw.
    const std::uint64_t base = Xoshiro256::mix(frame_key ^ Xoshiro256::mix(static_cast<std::uint64_t>(i)));
    out.u_flip[i] = Xoshiro256::to_unit(Xoshiro256::mix(base + 1));
    out.u_kind[i] = Xoshiro256::to_unit(Xoshiro256::mix(base + 2));
    out.similar[i] = choose(in.labels[i], Xoshiro256::to_unit(Xoshiro256::mix(base + 3)),
                            Xoshiro256::to_unit(Xoshiro256::mix(base + 4)));
    // Objects are regions by instance; stuff by class within a tile.
    const std::uint64_t label_bits = static_cast<std::uint64_t>(index(in.labels[i]));
    const std::uint64_t key = inst(i) != 0
                                  ? (label_bits << 48U) | inst(i)
                                  : (label_bits << 48U) | (1ULL << 40U) | ((in.rings[i] / tr) << 20U) | (in.columns[i] / tc);
    if (key != last_key) {  // consecutive points mostly share a region
      auto [it, inserted] = region_index.try_emplace(key, static_cast<std::uint32_t>(out.region_u.size()));
      if (inserted) {
        const std::uint64_t rbase = Xoshiro256::mix(frame_key ^ Xoshiro256::mix(~key));
        out.region_u.push_back(Xoshiro256::to_unit(Xoshiro256::mix(rbase + 1)));
        out.region_class.push_back(choose(in.labels[i], Xoshiro256::to_unit(Xoshiro256::mix(rbase + 2)),
                                          Xoshiro256::to_unit(Xoshiro256::mix(rbase + 3))));
      }
      last_key = key;
      last_region = it->second;
    }
    out.region[i] = last_region;
  }
  return out;
}

/// Predictions of one frame at error scale s (monotone: a larger s flips a
/// superset of points, given the same draws).
inline void apply_draws(const NoiseDraws& d, double scale, const LabelNoiseConfig& cfg, std::vector<Class>& out) {
  const std::size_t n = d.truth.size();
  out.resize(n);
  const double p_region = 1.0 - std::exp(-scale * cfg.beta_region);
  std::array<double, kMaxDistancePx + 1> p_point{};
  for (std::size_t k = 0; k <= kMaxDistancePx; ++k) {
    const double rate = cfg.beta_boundary * std::exp(-static_cast<double>(k) / cfg.boundary_decay_px) + cfg.beta_interior;
    p_point[k] = 1.0 - std::exp(-scale * rate);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Class truth = d.truth[i];
    if (truth == Class::kUnlabeled) {
      out[i] = truth;
      continue;
    }
    Class pred = truth;
    if (d.region_u[d.region[i]] < p_region) pred = d.region_class[d.region[i]];
    if (d.u_flip[i] < p_point[d.distance_px[i]]) {
      const bool bleed = d.distance_px[i] <= 1 && d.neighbour[i] != truth && d.u_kind[i] < cfg.neighbour_share;
      pred = bleed ? d.neighbour[i] : d.similar[i];
    }
    out[i] = pred;
  }
}

}  // namespace detail

/// Segmentation-network-like label noise with a calibrated quality knob.
/// predict() is const and thread-safe; calibrate() is not.
class LabelNoise {
 public:
  using Config = LabelNoiseConfig;

  /// Throws ConfigError when target_miou is outside (0, 1] or a rate is negative.
  explicit LabelNoise(const LabelNoiseConfig& config) : config_(config) {
    if (!(config.target_miou > 0.0 && config.target_miou <= 1.0)) {
      throw ConfigError("LabelNoiseConfig.target_miou must be in (0, 1], got " + std::to_string(config.target_miou));
    }
    if (!(config.beta_boundary >= 0.0 && config.beta_interior >= 0.0 && config.beta_region >= 0.0 &&
          config.boundary_decay_px > 0.0)) {
      throw ConfigError("LabelNoiseConfig: beta_* must be >= 0 and boundary_decay_px > 0");
    }
  }

  /// Finds the error scale whose predictions on `scenes` (frames 0, 1, ...)
  /// reach target_miou (pooled confusion matrix, bisection on log scale),
  /// stores it and returns the achieved mIoU.
  double calibrate(const std::vector<RangeImageLabels>& scenes) {
    std::vector<detail::NoiseDraws> draws;
    draws.reserve(scenes.size());
    for (std::size_t f = 0; f < scenes.size(); ++f) draws.push_back(detail::prepare_draws(scenes[f], config_, f));
    std::vector<Class> pred;
    auto achieved = [&](double s) {
      eval::ConfusionMatrix m;
      for (const auto& d : draws) {
        detail::apply_draws(d, s, config_, pred);
        m.add(d.truth, pred);
      }
      return m.report().miou;
    };
    double lo = -12.0;  // log(scale)
    double hi = 6.0;
    if (config_.target_miou >= 1.0) {
      scale_ = 0.0;
    } else {
      for (int it = 0; it < 40; ++it) {
        const double mid = 0.5 * (lo + hi);
        (achieved(std::exp(mid)) > config_.target_miou ? lo : hi) = mid;
      }
      scale_ = std::exp(0.5 * (lo + hi));
    }
    calibrated_ = true;
    calibration_miou_ = achieved(scale_);
    return calibration_miou_;
  }

  /// Convenience: calibrate on a single scene.
  double calibrate(const RangeImageLabels& scene) { return calibrate(std::vector<RangeImageLabels>{scene}); }

  /// Predicted label per point of one frame; `frame` selects independent
  /// randomness (same seed and frame: same output). Throws ConfigError when
  /// neither calibrate() nor set_error_scale() was called.
  [[nodiscard]] std::vector<Class> predict(const RangeImageLabels& scene, std::uint64_t frame) const {
    if (!calibrated_) {
      throw ConfigError("LabelNoise::predict: call calibrate() or set_error_scale() first");
    }
    std::vector<Class> out;
    detail::apply_draws(detail::prepare_draws(scene, config_, frame), scale_, config_, out);
    return out;
  }

  /// Uses a known error scale (e.g. from an earlier calibration) instead of calibrating.
  void set_error_scale(double scale) {
    if (!(scale >= 0.0) || !std::isfinite(scale)) {
      throw ConfigError("LabelNoise::set_error_scale: scale must be finite and >= 0, got " + std::to_string(scale));
    }
    scale_ = scale;
    calibrated_ = true;
  }
  /// The calibrated (or set) error scale.
  [[nodiscard]] double error_scale() const { return scale_; }
  /// mIoU reached on the calibration scenes (0 before calibrate()).
  [[nodiscard]] double calibration_miou() const { return calibration_miou_; }
  /// True once an error scale is known.
  [[nodiscard]] bool calibrated() const { return calibrated_; }
  /// The configuration.
  [[nodiscard]] const LabelNoiseConfig& config() const { return config_; }

 private:
  LabelNoiseConfig config_;
  double scale_ = 0.0;
  double calibration_miou_ = 0.0;
  bool calibrated_ = false;
};

}  // namespace semlio::sim
