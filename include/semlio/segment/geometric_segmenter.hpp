#pragma once
/// \file
/// GeometricSegmenter: a no-network default segmenter that labels a scan from
/// point positions alone (no rings, no intensity), for use when no network
/// predictions are available.
///
/// 1. Ground (detail/polar_ground.hpp): per azimuth sector (1 deg) the lowest
///    point of each flat range bin, reachable from the previous ground bin
///    within a slope limit, is the local ground height; points within
///    `ground_tolerance_m` of it are ground (in bins that are not flat
///    ground, e.g. the foot of a wall, only within `curb_min_m`). Ground on
///    the road line of the sector (fitted from a local ground plane around the
///    vehicle and the road bins so far) is road (`Class::kRoad`; parking is
///    not told apart); past a curb step up it is sidewalk, past a step down
///    (a verge) or more than `sidewalk_width_m` behind the curb it is
///    terrain. Road bins between a kerb step up and a step (or a ramp of at
///    most 2 m) back down along the same ring of range bins, walked both
///    ways round, within 20 m, are sidewalk too: beside a vehicle near the
///    kerb, or on a crowned road, the walk outwards never sees the kerb. With `split_ground = false` all
///    ground is kRoad (one ground class, as the issue allows).
/// 2. Objects (detail/obstacle_grid.hpp): the other points go into a 2D grid
///    (0.4 m cells) with per-cell heights above ground, grouped into
///    8-connected components, classified in this order:
///    - below `min_object_height_m` -> kUnlabeled (clutter);
///    - rider-sized (top 1.5-2.0 m and in view, reaching down below 0.5 m,
///      footprint <= 2.8 m, at least half over road) and 0.3-1.2 m wide
///      across the line of sight (no car shows less than its 1.5-2 m width)
///      -> `rider_class` (kBicyclist by default): a person on a two-wheeler
///      seen from ahead or behind. Pedestrians are not looked for: a
///      person-sized rule turned bushes, young trunks and fence ends of the
///      simulated worlds into people;
///    - car-sized (smallest-area footprint 2-6.5 m x <= 2.8 m, top 1.35-2.3 m,
///      reaching down below 0.7 m, at least half over road, or 30 % when its
///      surface is not foliage-rough: parked on a curb or in a bay) -> kCar;
///    - truck-sized boxes (5-12 m x <= 3.2 m, top 2.5-4.5 m and in view,
///      flat-topped, over road) -> kTruck;
///    - thin (<= 1 m) and tall columns -> kTrunk when at least
///      `trunk_min_width_m` wide across the line of sight, else kPole; thin
///      low ones -> kVegetation (bushes);
///    - low (top < 2.5 m): thin and long -> kFence (fences, walls, guard
///      rails), car-height rows standing on road -> kCar (cars parked in a
///      row merge into one component), else kVegetation (hedges, bushes);
///    - tall and extended: split by cell. Wall cells (reaching down below
///      1.9 m, top >= 2.5 m, >= 1.5 m tall) in runs wider than a column
///      whose points lie mostly on locally planar surfaces (foliage is
///      rough; `wall_max_roughness_m`) -> kBuilding; thin columns standing
///      on the ground -> kTrunk (its points above the canopy base are
///      vegetation) or kPole (also a column of tall cells inside a wider
///      group of ground-standing cells that rises 1 m above the rest, e.g. a
///      pole in a bush: trunk when a crown surrounds it, pole when at most a
///      sign or an arm is beside it); the rest (canopy) -> kVegetation.
///    Then traffic signs: a free-standing column (pole, trunk or a wall
///    fragment at most a panel wide) whose visible width across the line of
///    sight jumps from a post's (<= 0.25 m, seen over most of its height) to
///    a flat panel's (0.3-1.5 m) at 1.2 m or higher, up to its top (<= 4.5 m),
///    is a pole below a kTrafficSign. Geometry only: the retro-reflective
///    face is bright, but signs seen from behind or the side are not.
///    Heights are judged knowing the field of view: a cell whose top reaches
///    the highest beam (+2 deg) counts as taller than any threshold (a wall
///    10 m away looks only ~2 m tall to a 64-beam KITTI lidar).
///    Points outside the grid (`grid_radius_m`) stay kUnlabeled.
/// Runs in a few milliseconds on a 120k-point KITTI scan, deterministic, and
/// allocates nothing once its buffers have grown to the largest scan seen.
/// Quality: per-class IoU from scripts/segmenter_miou.sh (docs/results.md; CTest script_segmenter_miou).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/segment/detail/obstacle_grid.hpp>
#include <semlio/segment/detail/polar_ground.hpp>

namespace semlio {

/// Settings of GeometricSegmenter; defaults suit KITTI's HDL-64E on a car.
struct GeometricSegmenterConfig {
  // Ground.
  double sensor_height_m = 1.73;     ///< lidar origin above the road under the vehicle (KITTI: 1.73) [m]
  double max_range_m = 120.0;        ///< polar grid reach; farther points use the last bin [m]
  int sectors = 360;                 ///< azimuth sectors of the polar grid (1 deg each)
  double bins_per_sqrt_m = 8.0;      ///< range bins per sqrt(m): bin length 2 sqrt(r) / 8 (0.5 m at 4 m, 2 m at 64 m)
  double ground_tolerance_m = 0.2;   ///< points up to this above the local ground are ground [m]
  double ground_step_m = 0.1;        ///< height jump allowed between ground bins besides the slope [m]
  double max_ground_slope = 0.15;    ///< steepest ground slope followed between bins (rise over run)
  double flat_tolerance_m = 0.12;    ///< a bin is flat when enough points lie this close to its lowest point [m]
  double min_flat_fraction = 0.5;    ///< ... namely at least this fraction of its points
  bool split_ground = true;          ///< false: every ground point is kRoad
  double curb_min_m = 0.08;          ///< a step off the road surface at least this high is a curb/verge [m]
  double road_bend_per_m = 0.01;     ///< the road may leave its fitted line by this much more per metre past the last road bin (vertical curves)
  double sidewalk_width_m = 5.0;     ///< raised ground this far behind a curb is still sidewalk [m]
  // Object grid.
  double cell_size_m = 0.4;          ///< cell size of the object grid [m]
  double grid_radius_m = 100.0;      ///< object grid half-width; farther object points stay unlabeled [m]
  double min_object_height_m = 0.3;  ///< components lower than this stay unlabeled [m]
  double car_min_length_m = 2.0;     ///< car footprint length range (visible part) [m]
  double car_max_length_m = 6.5;
  double car_max_width_m = 2.8;      ///< car footprint width limit [m]: a 2.0 m body with mirrors, plus up to a 0.4 m cell of quantisation per side
  double car_min_height_m = 1.35;    ///< car height range above ground [m]
  double car_max_height_m = 2.3;
  double car_max_base_m = 0.7;       ///< a car reaches down to at least this height [m]
  double car_min_road_fraction = 0.3;  ///< cars stand on the road: this share of their points at least (a car parked with two wheels on the curb, or in a bay the ground walk calls sidewalk, has half or less over road)
  double car_row_min_road_fraction = 0.5;  ///< cars parked in a row (merged into one component) stand on the road: this share of their points at least (a long low component partly off the road is more often a hedge)
  // Riders: a person on a bicycle or motorcycle seen from ahead or behind,
  // as long as a small car but much narrower across the line of sight.
  double rider_min_height_m = 1.5;   ///< top of a rider at least this high [m]: a seated adult's head is 1.5-1.9 m above the road; most cars are lower (1.4-1.5 m), so a car partly hidden behind another is not taken for one
  double rider_max_height_m = 2.0;   ///< ... and at most [m]: above any rider; vans and buses are taller
  double rider_max_base_m = 0.5;     ///< a rider reaches down to at least this height [m] (wheels on the road; a higher base is the top of something behind an occluder)
  double rider_min_width_m = 0.3;    ///< visible width across the line of sight at least [m]: a rider's shoulders 0.4-0.5 m; thinner is a post
  double rider_max_width_m = 1.2;    ///< ... and at most [m]: a two-wheeler with its rider is 0.6-0.9 m wide, a car shows at least its 1.5-2 m width from any side
  double rider_max_length_m = 2.8;   ///< a rider's grid footprint at most [m]: a 2.3 m motorcycle plus a 0.4 m cell of quantisation
  double rider_min_road_fraction = 0.5;  ///< riders ride on the road: this share of their points at least (bushes and posts at the verge are not)
  /// Class given to riders: geometry cannot tell a bicycle from a
  /// motorcycle; bicyclists are the more common in SemanticKITTI, and the
  /// simulator's riders are bicyclists.
  Class rider_class = Class::kBicyclist;
  double truck_min_length_m = 5.0;   ///< truck/bus footprint length range (visible part) [m]
  double truck_max_length_m = 12.0;
  double truck_max_width_m = 3.2;    ///< truck footprint width limit [m]
  double truck_max_height_m = 4.5;   ///< truck height limit when its top is in view [m]
  double truck_min_road_fraction = 0.5;  ///< a truck stands on the road: this share of its points at least
  double truck_min_flat_top_fraction = 0.6;  ///< a truck's cells reach its top: this share at least
  double flat_top_tolerance_m = 0.3;  ///< a cell reaches the top when within this of it [m]
  double pole_max_diameter_m = 1.0;  ///< thin columns (poles, trunks) are at most this wide [m]
  double pole_min_height_m = 2.2;    ///< a free-standing pole is at least this tall [m]
  double trunk_min_width_m = 0.28;   ///< columns at least this wide across the line of sight are trunks, thinner ones poles [m]
  double trunk_min_height_m = 1.2;   ///< a trunk column under a canopy is at least this tall [m]
  double fence_max_width_m = 0.5;    ///< thin linear low structures (fences) are at most this wide [m]
  double fence_min_length_m = 2.0;   ///< ... and at least this long [m]
  double rail_max_mean_width_m = 0.6;  ///< long low structures (guard rails) this thin on average are fences [m]
  double rail_min_length_m = 30.0;   ///< ... when at least this long [m]
  double building_min_height_m = 2.5;  ///< wall cells reach at least this high [m]
  double stem_max_base_m = 0.8;      ///< a cell with a point below this height stands on the ground [m]
  /// Within a group of ground-standing cells too wide for a column (a pole
  /// in a bush), cells at least this tall are searched for columns [m]:
  /// above most shrubs and hedges beside a footpath, below any pole, sign
  /// post or trunk under a canopy (trunk_min_height_m).
  double stem_min_cell_height_m = 1.2;
  /// ... and such a column must rise at least this far above the rest of
  /// its group [m]: a pole or trunk over a bush, not the higher parts of a
  /// hedge or shrub (their tops vary by a few decimetres).
  double stem_min_prominence_m = 1.0;
  double wall_max_base_m = 1.9;      ///< wall cells reach down at least this low (a wall over a parked car) [m]
  double wall_min_span_m = 1.5;      ///< wall cells have at least this vertical extent [m]
  /// A run of wall cells is a wall only when most of its points lie in
  /// planar cells: the points of a cell and its 8 neighbours (a 1.2 m
  /// square) spread at most this much across their best-fitting vertical
  /// plane (standard deviation) [m]. A wall's spread is range noise (~0.02 m
  /// on an HDL-64E) plus window and door recesses (up to ~0.1 m over 1.2 m);
  /// the visible surface of foliage (hedges, tree crowns) is rough on the
  /// scale of its leaves and twigs, 0.1-0.3 m. Wall corners are rough too,
  /// hence the vote over the run rather than a per-cell test.
  double wall_max_roughness_m = 0.15;
  /// Fewest points (cell and neighbours) to judge roughness; fewer are taken as planar.
  int roughness_min_points = 8;
  // Traffic signs: a free-standing column (pole or trunk with no canopy)
  // whose top is a flat panel much wider than the post under it.
  double sign_slice_m = 0.2;         ///< height slices in which a column's visible width is measured [m]: two or more beams on a sign 10-20 m away
  double sign_min_base_m = 1.2;      ///< a sign panel starts at least this high [m]: above bushes and parked-car roofs; panels over footways hang at 2-2.5 m, over verges from ~1.5 m
  double sign_max_top_m = 4.5;       ///< ... and ends at most this high [m]: panels are mounted at 1.8-3.5 m (issue #38) plus their own size; street-light heads are higher
  double sign_min_width_m = 0.3;     ///< visible panel width at least [m]: the smallest panels are 0.4 m (0.3 when seen 40 deg off-axis)
  double sign_max_width_m = 1.5;     ///< ... and at most [m]: single-post panels are up to ~1.2 m
  double sign_max_panel_height_m = 1.6;  ///< panel (or stack of panels) at most this tall [m]
  double sign_max_post_width_m = 0.25;   ///< the post under a panel is at most this wide (visible) [m]: sign posts are 0.05-0.2 m
  double sign_post_min_height_m = 0.6;   ///< ... measured above this height [m]: grass, litter and kerb stones at its foot are lower
  /// The post is seen in at least this share of the height slices between
  /// sign_post_min_height_m and the panel: a post is continuous, whereas the
  /// top of a wall seen over a bush or a car shows only in patches.
  double sign_min_post_cover = 0.6;
  /// The panel's points spread at most this much across their best-fitting
  /// vertical plane (standard deviation) [m]: a panel is flat (range noise
  /// ~0.02 m), the crown of a young tree on a thin trunk is rough (0.1-0.3 m).
  double sign_max_roughness_m = 0.06;
  double top_beam_elevation_rad = 0.0349;  ///< elevation of the highest beam (HDL-64E: +2 deg) [rad]
  double clip_margin_m = 0.15;       ///< a cell reaching within this of the highest visible height is cut off by the field of view [m]
};

/// Geometry-only segmenter (see the file comment). `segment` is const but
/// reuses internal buffers: one instance must not be used from several
/// threads at once (give each thread its own copy).
class GeometricSegmenter {
 public:
  using Config = GeometricSegmenterConfig;

  /// Uses the default configuration.
  GeometricSegmenter() = default;
  /// Uses `config`; throws ConfigError naming the field when a size or
  /// count is not positive or not finite.
  explicit GeometricSegmenter(const GeometricSegmenterConfig& config)
      : config_(config), tan_top_(std::tan(static_cast<float>(config.top_beam_elevation_rad))) {
    const auto positive = [](double v, const char* field) {
      if (!(v > 0.0 && std::isfinite(v))) {
        throw ConfigError(std::string("GeometricSegmenterConfig.") + field + " must be > 0 and finite, got " +
                          std::to_string(v));
      }
    };
    positive(config.sensor_height_m, "sensor_height_m");
    positive(config.max_range_m, "max_range_m");
    positive(static_cast<double>(config.sectors), "sectors");
    positive(config.bins_per_sqrt_m, "bins_per_sqrt_m");
    positive(config.ground_tolerance_m, "ground_tolerance_m");
    positive(config.cell_size_m, "cell_size_m");
    positive(config.grid_radius_m, "grid_radius_m");
    if (config.grid_radius_m / config.cell_size_m > 4096.0) {
      throw ConfigError("GeometricSegmenterConfig.grid_radius_m / cell_size_m must be <= 4096, got " +
                        std::to_string(config.grid_radius_m / config.cell_size_m));
    }
  }

  /// The configuration.
  [[nodiscard]] const GeometricSegmenterConfig& config() const noexcept { return config_; }

  /// Fills scan.labels (one per point, existing labels are overwritten).
  void segment(Scan& scan) const {
    const std::size_t n = scan.points.size();
    scan.labels.assign(n, Class::kUnlabeled);
    if (n == 0) return;
    label_ground(scan);
    build_grid(scan);
    grid_.connect();
    for (const detail::GridComponent& comp : grid_.components()) classify(comp);
    find_signs(scan);
    label_objects(scan);
  }

 private:
  struct Extent {
    float length_m = 0.0F;
    float width_m = 0.0F;
    float h_min_m = 0.0F;
    float h_max_m = 0.0F;
    float road_fraction = 0.0F;  // share of points standing over road
  };

  // Components with at most this many cells get the 13-heading footprint search.
  static constexpr int kSmallComponentCells = 160;

  static std::uint8_t id(Class c) noexcept { return static_cast<std::uint8_t>(c); }

  void label_ground(Scan& scan) const {
    const Config& c = config_;
    const detail::PolarGroundParams p{
        .sensor_height_m = static_cast<float>(c.sensor_height_m),
        .max_range_m = static_cast<float>(c.max_range_m),
        .sectors = c.sectors,
        .bins_per_sqrt_m = static_cast<float>(c.bins_per_sqrt_m),
        .ground_tolerance_m = static_cast<float>(c.ground_tolerance_m),
        .step_m = static_cast<float>(c.ground_step_m),
        .max_slope = static_cast<float>(c.max_ground_slope),
        .flat_tolerance_m = static_cast<float>(c.flat_tolerance_m),
        .min_flat_fraction = static_cast<float>(c.min_flat_fraction),
        .curb_min_m = static_cast<float>(c.curb_min_m),
        .road_bend_per_m = static_cast<float>(c.road_bend_per_m),
        .sidewalk_width_m = static_cast<float>(c.sidewalk_width_m),
    };
    ground_.run(scan.points, p, height_m_, kind_);
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      // Near-ground points take their bin's ground class unless an object's
      // cell claims them later (label_objects).
      const detail::GroundKind k = kind_[i] == detail::GroundKind::kNearGround ? ground_.bin_state(i) : kind_[i];
      switch (k) {
        case detail::GroundKind::kRoad: scan.labels[i] = Class::kRoad; break;
        case detail::GroundKind::kSidewalk: scan.labels[i] = c.split_ground ? Class::kSidewalk : Class::kRoad; break;
        case detail::GroundKind::kTerrain: scan.labels[i] = c.split_ground ? Class::kTerrain : Class::kRoad; break;
        default: break;
      }
    }
  }

  void build_grid(const Scan& scan) const {
    grid_.configure(static_cast<float>(config_.cell_size_m), static_cast<float>(config_.grid_radius_m));
    cell_of_.resize(scan.points.size());
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      cell_of_[i] = -1;
      if (kind_[i] != detail::GroundKind::kObstacle && kind_[i] != detail::GroundKind::kNearGround) continue;
      const Eigen::Vector3f& q = scan.points[i];
      const std::int32_t c = grid_.cell_of(q.x(), q.y());
      if (c < 0) continue;
      cell_of_[i] = c;
      // Near-ground points do not shape objects (they would join everything
      // along a curb); they only follow the object above them, if any.
      if (kind_[i] == detail::GroundKind::kObstacle) {
        grid_.add(c, q.x(), q.y(), q.z(), height_m_[i], ground_.bin_state(i) == detail::GroundKind::kRoad);
      }
    }
  }

  // Oriented footprint (principal axes of the cell centres) and height range
  // of cells order[begin, end) that pass `use`.
  template <typename Use>
  Extent extent(std::uint32_t begin, std::uint32_t end, Use use) const {
    const auto& order = grid_.order();
    double sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
    int m = 0;
    std::uint64_t points = 0, road_points = 0;
    Extent e;
    e.h_min_m = std::numeric_limits<float>::infinity();
    e.h_max_m = -std::numeric_limits<float>::infinity();
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::uint32_t c = order[k];
      if (!use(c)) continue;
      const Eigen::Vector2f p = grid_.centre(c);
      const auto px = static_cast<double>(p.x());
      const auto py = static_cast<double>(p.y());
      sx += px;
      sy += py;
      sxx += px * px;
      syy += py * py;
      sxy += px * py;
      ++m;
      const detail::GridCell& g = grid_.cell(c);
      points += g.count;
      road_points += g.road_count;
      e.h_min_m = std::min(e.h_min_m, g.h_min_m);
      e.h_max_m = std::max(e.h_max_m, g.h_max_m);
    }
    if (m == 0) return Extent{};
    e.road_fraction = static_cast<float>(static_cast<double>(road_points) / static_cast<double>(std::max<std::uint64_t>(points, 1)));
    const double inv = 1.0 / m;
    const double mx = sx * inv;
    const double my = sy * inv;
    const double cxx = sxx * inv - mx * mx;
    const double cyy = syy * inv - my * my;
    const double cxy = sxy * inv - mx * my;
    // Footprint: the smallest-area box over the principal axes and, for
    // object-sized components (where an L-shaped view of a car tilts the
    // principal axes), 12 more headings 15 deg apart.
    const double theta = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
    const int headings = m <= kSmallComponentCells ? 13 : 1;
    float best_area = std::numeric_limits<float>::infinity();
    const float cell = grid_.cell_size_m();
    for (int h = 0; h < headings; ++h) {
      const double angle = h == 0 ? theta : static_cast<double>(h - 1) * (std::numbers::pi / 12.0);
      const auto ux = static_cast<float>(std::cos(angle));
      const auto uy = static_cast<float>(std::sin(angle));
      float a0 = std::numeric_limits<float>::infinity(), a1 = -a0, b0 = a0, b1 = -a0;
      for (std::uint32_t k = begin; k < end; ++k) {
        const std::uint32_t c = order[k];
        if (!use(c)) continue;
        const Eigen::Vector2f p = grid_.centre(c);
        const float a = ux * p.x() + uy * p.y();
        const float b = -uy * p.x() + ux * p.y();
        a0 = std::min(a0, a);
        a1 = std::max(a1, a);
        b0 = std::min(b0, b);
        b1 = std::max(b1, b);
      }
      const float la = a1 - a0 + cell;
      const float lb = b1 - b0 + cell;
      if (la * lb < best_area) {
        best_area = la * lb;
        e.length_m = std::max(la, lb);
        e.width_m = std::min(la, lb);
      }
    }
    return e;
  }

  // Height of cell c's top, or infinity when the top beam cuts it off (near
  // walls look only ~2 m tall to a lidar whose highest beam is at +2 deg).
  float top_m(std::uint32_t c) const {
    const detail::GridCell& g = grid_.cell(c);
    const float ceiling_z = grid_.centre(c).norm() * tan_top_;
    return g.z_max_m >= ceiling_z - static_cast<float>(config_.clip_margin_m) ? std::numeric_limits<float>::infinity()
                                                                              : g.h_max_m;
  }

  // True when most cells of the component reach its top (the sides of a box;
  // a canopy is dome-shaped) and the field of view cuts off none of them.
  bool flat_topped(const detail::GridComponent& comp, float h_max_m) const {
    std::uint32_t high = 0;
    for (std::uint32_t k = comp.begin; k < comp.end; ++k) {
      const std::uint32_t c = grid_.order()[k];
      const float top = top_m(c);
      if (top == std::numeric_limits<float>::infinity()) return false;
      high += top >= h_max_m - static_cast<float>(config_.flat_top_tolerance_m) ? 1U : 0U;
    }
    return static_cast<double>(high) >= config_.truck_min_flat_top_fraction * static_cast<double>(comp.end - comp.begin);
  }

  void set_all(const detail::GridComponent& comp, Class cls) const {
    for (std::uint32_t k = comp.begin; k < comp.end; ++k) {
      detail::GridCell& g = grid_.cell(grid_.order()[k]);
      g.label = id(cls);
      g.upper_label = id(cls);
    }
  }

  void classify(const detail::GridComponent& comp) const {
    const Config& c = config_;
    const Extent e = extent(comp.begin, comp.end, [](std::uint32_t) { return true; });
    const auto f = [](double v) { return static_cast<float>(v); };
    if (e.h_max_m < f(c.min_object_height_m)) return set_all(comp, Class::kUnlabeled);
    if (is_rider(comp, e)) return set_all(comp, c.rider_class);
    if (e.length_m >= f(c.car_min_length_m) && e.length_m <= f(c.car_max_length_m) && e.width_m <= f(c.car_max_width_m) &&
        e.h_max_m >= f(c.car_min_height_m) && e.h_max_m <= f(c.car_max_height_m) && e.h_min_m <= f(c.car_max_base_m) &&
        e.road_fraction >= f(c.car_min_road_fraction) &&
        (e.road_fraction >= f(c.car_row_min_road_fraction) || !mostly_rough(comp))) {
      // Partly off the road (parked on a curb or in a bay): only when its
      // surface is not foliage-rough, so a car-sized bush at the verge stays
      // vegetation.
      return set_all(comp, Class::kCar);
    }
    float top = e.h_max_m;
    for (std::uint32_t k = comp.begin; k < comp.end && top < f(c.building_min_height_m); ++k) {
      top = std::max(top, top_m(grid_.order()[k]));
    }
    if (e.length_m >= f(c.truck_min_length_m) && e.length_m <= f(c.truck_max_length_m) &&
        e.width_m <= f(c.truck_max_width_m) && e.h_min_m <= f(c.car_max_base_m) + 0.3F &&
        top >= f(c.building_min_height_m) && e.h_max_m <= f(c.truck_max_height_m) &&
        e.road_fraction >= f(c.truck_min_road_fraction) && flat_topped(comp, e.h_max_m)) {
      return set_all(comp, Class::kTruck);  // a free-standing box too big for a car, too small for a building
    }
    if (e.length_m <= f(c.pole_max_diameter_m)) {
      if (top < f(c.pole_min_height_m)) return set_all(comp, Class::kVegetation);
      stack_.assign(grid_.order().begin() + comp.begin, grid_.order().begin() + comp.end);
      return set_all(comp, stack_width_m() >= f(c.trunk_min_width_m) ? Class::kTrunk : Class::kPole);
    }
    if (top < f(c.building_min_height_m)) {
      // Thin and long. Long rails along a curving road have a wide box but
      // a small mean width (footprint area over length).
      const float cell = grid_.cell_size_m();
      const float mean_width = static_cast<float>(comp.end - comp.begin) * cell * cell / e.length_m;
      if ((e.width_m <= f(c.fence_max_width_m) && e.length_m >= f(c.fence_min_length_m)) ||
          (mean_width <= f(c.rail_max_mean_width_m) && e.length_m >= f(c.rail_min_length_m))) {
        return set_all(comp, Class::kFence);
      }
      if (e.h_max_m >= f(c.car_min_height_m) && e.width_m <= f(c.car_max_width_m) && e.h_min_m <= f(c.car_max_base_m) &&
          e.road_fraction >= f(c.car_row_min_road_fraction)) {
        return set_all(comp, Class::kCar);  // cars parked in a row, merged into one component
      }
      return set_all(comp, Class::kVegetation);
    }
    split_tall(comp);
  }

  // True for a rider seen from ahead or behind: rider-high, standing on the
  // road, car-long at most, but narrower across the line of sight than any
  // car. Heights must be in view (a cluster cut off by the top beam may be
  // anything taller). Seen from the side a two-wheeler is as wide as it is
  // long and is not recognised.
  bool is_rider(const detail::GridComponent& comp, const Extent& e) const {
    const Config& c = config_;
    const auto f = [](double v) { return static_cast<float>(v); };
    if (e.h_max_m < f(c.rider_min_height_m) || e.h_max_m > f(c.rider_max_height_m) || e.h_min_m > f(c.rider_max_base_m) ||
        e.length_m > f(c.rider_max_length_m) || e.road_fraction < f(c.rider_min_road_fraction)) {
      return false;
    }
    for (std::uint32_t k = comp.begin; k < comp.end; ++k) {
      if (top_m(grid_.order()[k]) == std::numeric_limits<float>::infinity()) return false;
    }
    stack_.assign(grid_.order().begin() + comp.begin, grid_.order().begin() + comp.end);
    const float visible = stack_width_m();
    return visible >= f(c.rider_min_width_m) && visible <= f(c.rider_max_width_m);
  }

  // Grows the sub-component of seed over the cells of the same component that
  // pass `member` (8-connected) into stack_; marks them with `mark`.
  template <typename Member>
  void grow(std::uint32_t seed, std::int32_t mark, Member member) const {
    stack_.clear();
    stack_.push_back(seed);
    grid_.cell(seed).mark = mark;
    const std::int32_t comp = grid_.cell(seed).component;
    for (std::size_t q = 0; q < stack_.size(); ++q) {
      visit_neighbours(stack_[q], [&](std::uint32_t nc) {
        detail::GridCell& g = grid_.cell(nc);
        if (g.count > 0 && g.component == comp && g.mark != mark && member(nc)) {
          g.mark = mark;
          stack_.push_back(nc);
        }
      });
    }
  }

  // Visible width across the line of sight of the cells in stack_ [m].
  // Cells store offsets across their own line of sight; they are combined as
  // azimuth angles relative to the first cell, then scaled back to metres.
  float stack_width_m() const {
    const Eigen::Vector2f ref = grid_.centre(stack_.front());
    const float ref_az = std::atan2(ref.y(), ref.x());
    const float pi = std::numbers::pi_v<float>;
    float a0 = std::numeric_limits<float>::infinity(), a1 = -a0;
    for (const std::uint32_t c : stack_) {
      const Eigen::Vector2f p = grid_.centre(c);
      const float r = std::max(p.norm(), 0.5F * grid_.cell_size_m());
      float az = std::atan2(p.y(), p.x()) - ref_az;
      if (az > pi) az -= 2.0F * pi;
      if (az < -pi) az += 2.0F * pi;
      a0 = std::min(a0, az + grid_.cell(c).t_min_m / r);
      a1 = std::max(a1, az + grid_.cell(c).t_max_m / r);
    }
    return (a1 - a0) * std::max(ref.norm(), 0.5F * grid_.cell_size_m());
  }

  // Spread of the points of cell c and its occupied 8 neighbours across
  // their best-fitting vertical plane: the standard deviation along the
  // minor axis of their horizontal covariance [m]; 0 with too few points.
  float roughness_m(std::uint32_t c) const {
    const int side = grid_.side();
    const int ix = static_cast<int>(c) % side;
    const int iy = static_cast<int>(c) / side;
    const float cell = grid_.cell_size_m();
    double n = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = ix + dx;
        const int ny = iy + dy;
        if (nx < 0 || ny < 0 || nx >= side || ny >= side) continue;
        const detail::GridCell& g = grid_.cell(static_cast<std::uint32_t>(ny * side + nx));
        if (g.count == 0) continue;
        // Shift the neighbour's moments to cell c's centre.
        const auto m = static_cast<double>(g.count);
        const double ox = dx * static_cast<double>(cell);
        const double oy = dy * static_cast<double>(cell);
        const auto gx = static_cast<double>(g.sx_m);
        const auto gy = static_cast<double>(g.sy_m);
        n += m;
        sx += gx + m * ox;
        sy += gy + m * oy;
        sxx += static_cast<double>(g.sxx_m2) + 2.0 * ox * gx + m * ox * ox;
        syy += static_cast<double>(g.syy_m2) + 2.0 * oy * gy + m * oy * oy;
        sxy += static_cast<double>(g.sxy_m2) + ox * gy + oy * gx + m * ox * oy;
      }
    }
    if (n < static_cast<double>(config_.roughness_min_points)) return 0.0F;
    return static_cast<float>(minor_axis_sd_m(n, sx, sy, sxx, syy, sxy));
  }

  // Standard deviation along the minor axis of the horizontal covariance of
  // n points with sums sx, sy and sums of products sxx, syy, sxy [m]: their
  // spread across their best-fitting vertical plane.
  static double minor_axis_sd_m(double n, double sx, double sy, double sxx, double syy, double sxy) {
    const double mx = sx / n;
    const double my = sy / n;
    const double cxx = sxx / n - mx * mx;
    const double cyy = syy / n - my * my;
    const double cxy = sxy / n - mx * my;
    // Smaller eigenvalue of [[cxx, cxy], [cxy, cyy]].
    const double half_trace = 0.5 * (cxx + cyy);
    const double minor = half_trace - std::sqrt(std::max(0.0, 0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy));
    return std::sqrt(std::max(0.0, minor));
  }

  // True when most points of the component lie in rough cells (roughness_m
  // above wall_max_roughness_m): foliage rather than a wall or a body.
  bool mostly_rough(const detail::GridComponent& comp) const {
    std::uint64_t rough = 0, all = 0;
    for (std::uint32_t k = comp.begin; k < comp.end; ++k) {
      const std::uint32_t c = grid_.order()[k];
      const std::uint32_t m = grid_.cell(c).count;
      all += m;
      rough += roughness_m(c) > static_cast<float>(config_.wall_max_roughness_m) ? m : 0U;
    }
    return 2 * rough > all;
  }

  // Largest side of the axis-aligned box around the cells in stack_ [m].
  float stack_size_m() const {
    float a0 = std::numeric_limits<float>::infinity(), a1 = -a0, b0 = a0, b1 = -a0;
    for (const std::uint32_t c : stack_) {
      const Eigen::Vector2f p = grid_.centre(c);
      a0 = std::min(a0, p.x());
      a1 = std::max(a1, p.x());
      b0 = std::min(b0, p.y());
      b1 = std::max(b1, p.y());
    }
    return std::max(a1 - a0, b1 - b0) + grid_.cell_size_m();
  }

  // A tall extended component, split by cell: walls (-> building), thin
  // columns standing on the ground (-> trunk under a canopy, else pole) and
  // the rest (canopy, hedges -> vegetation).
  void split_tall(const detail::GridComponent& comp) const {
    const Config& cfg = config_;
    const auto f = [](double v) { return static_cast<float>(v); };
    const auto& order = grid_.order();
    float canopy_base = std::numeric_limits<float>::infinity();
    for (std::uint32_t k = comp.begin; k < comp.end; ++k) {
      detail::GridCell& g = grid_.cell(order[k]);
      g.label = id(Class::kVegetation);
      g.upper_label = id(Class::kVegetation);
      g.split_m = std::numeric_limits<float>::infinity();
      g.mark = -1;
      if (g.h_min_m > f(cfg.stem_max_base_m)) {
        canopy_base = std::min(canopy_base, g.h_min_m);
      }
    }
    // Walls: 8-connected tall cells that reach down below wall_max_base_m
    // (a wall seen over a parked car starts at the car's roof), wider than a
    // column.
    const auto is_wall = [&](std::uint32_t c) {
      const detail::GridCell& g = grid_.cell(c);
      const float top = top_m(c);
      return g.h_min_m <= f(cfg.wall_max_base_m) && top >= f(cfg.building_min_height_m) &&
             top - g.h_min_m >= f(cfg.wall_min_span_m);
    };
    std::int32_t mark = 0;
    for (std::uint32_t k = comp.begin; k < comp.end; ++k) {
      const std::uint32_t seed = order[k];
      if (grid_.cell(seed).mark >= 0 || !is_wall(seed)) continue;
      grow(seed, mark++, is_wall);
      if (stack_size_m() <= f(cfg.pole_max_diameter_m)) continue;
      // Foliage, not a wall, when most of the run's points lie in rough cells
      // (a run-level vote: corners and recesses of a wall are rough too).
      std::uint64_t rough = 0, all = 0;
      for (const std::uint32_t c : stack_) {
        const std::uint32_t m = grid_.cell(c).count;
        all += m;
        rough += roughness_m(c) > f(cfg.wall_max_roughness_m) ? m : 0U;
      }
      if (2 * rough > all) continue;
      for (const std::uint32_t c : stack_) {
        grid_.cell(c).label = id(Class::kBuilding);
        grid_.cell(c).upper_label = id(Class::kBuilding);
      }
    }
    // Thin columns standing on the ground.
    const auto is_stem = [&](std::uint32_t c) {
      const detail::GridCell& g = grid_.cell(c);
      return g.h_min_m <= f(cfg.stem_max_base_m) && g.label != id(Class::kBuilding);
    };
    // Of those, the cells that are themselves tall: a pole or trunk standing
    // in a bush or hedge joins the low cells around it into a group too wide
    // for a column; its own cells still rise above them.
    const auto is_tall_stem = [&](std::uint32_t c) {
      return is_stem(c) && top_m(c) >= f(cfg.stem_min_cell_height_m);
    };
    // Labels the cells in stack_ as a column (trunk or pole) when they form one.
    const auto label_column = [&](bool under_canopy) {
      if (stack_size_m() > f(cfg.pole_max_diameter_m)) return false;
      bool touches_wall = false;
      for (const std::uint32_t c : stack_) {
        visit_neighbours(c, [&](std::uint32_t nc) { touches_wall |= grid_.cell(nc).label == id(Class::kBuilding); });
      }
      if (touches_wall) {  // a short stretch of wall next to a taller one
        for (const std::uint32_t c : stack_) {
          grid_.cell(c).label = id(Class::kBuilding);
          grid_.cell(c).upper_label = id(Class::kBuilding);
        }
        return true;
      }
      float top = -std::numeric_limits<float>::infinity();
      for (const std::uint32_t c : stack_) top = std::max(top, top_m(c));
      const bool thick = under_canopy || stack_width_m() >= f(cfg.trunk_min_width_m);
      if (thick && top >= f(cfg.trunk_min_height_m)) {
        for (const std::uint32_t c : stack_) {
          grid_.cell(c).label = id(Class::kTrunk);
          grid_.cell(c).split_m = canopy_base;
        }
      } else if (top >= f(cfg.pole_min_height_m)) {
        for (const std::uint32_t c : stack_) {
          grid_.cell(c).label = id(Class::kPole);
          grid_.cell(c).upper_label = id(Class::kPole);
        }
      }
      return true;
    };
    const std::int32_t first_stem = mark;
    for (std::uint32_t k = comp.begin; k < comp.end; ++k) {
      const std::uint32_t seed = order[k];
      if (grid_.cell(seed).mark >= first_stem || !is_stem(seed)) continue;
      grow(seed, mark++, is_stem);
      if (label_column(false)) continue;
      // Too wide: look for tall thin columns inside the group, unless it
      // leans on a wall (the foot of a building is no place to look for poles).
      bool by_wall = false;
      for (const std::uint32_t c : stack_) {
        visit_neighbours(c, [&](std::uint32_t nc) { by_wall |= grid_.cell(nc).label == id(Class::kBuilding); });
      }
      if (by_wall) continue;
      group_.assign(stack_.begin(), stack_.end());
      const std::int32_t first_tall = mark;
      for (const std::uint32_t c : group_) {
        if (grid_.cell(c).mark >= first_tall || !is_tall_stem(c)) continue;
        const std::int32_t sub = mark++;
        grow(c, sub, is_tall_stem);
        // A column rises well above the rest of its group (a pole over a
        // bush); the higher parts of a hedge or a shrub do not.
        float top = -std::numeric_limits<float>::infinity();
        float rest = -std::numeric_limits<float>::infinity();
        for (const std::uint32_t o : group_) {
          // Visible heights: near columns are cut off by the field of view.
          float& h = grid_.cell(o).mark == sub ? top : rest;
          h = std::max(h, grid_.cell(o).h_max_m);
        }
        if (top < rest + f(cfg.stem_min_prominence_m)) continue;
        // Under a crown (raised cells on most sides of a column cell) it is a
        // trunk however thin; a pole carries at most a sign or a lamp arm on
        // one side.
        int raised = 0;
        for (const std::uint32_t o : stack_) {
          int around = 0;
          visit_neighbours(o, [&](std::uint32_t nc) {
            const detail::GridCell& g = grid_.cell(nc);
            around += g.count > 0 && g.h_min_m > f(cfg.stem_max_base_m) ? 1 : 0;
          });
          raised = std::max(raised, around);
        }
        // 3-4 raised neighbours are neither: left to vegetation.
        if (raised >= 5 || raised <= 2) label_column(raised >= 5);
      }
    }
  }

  template <typename Fn>
  void visit_neighbours(std::uint32_t c, Fn fn) const {
    const int side = grid_.side();
    const int ix = static_cast<int>(c) % side;
    const int iy = static_cast<int>(c) / side;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = ix + dx;
        const int ny = iy + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= side || ny >= side) continue;
        fn(static_cast<std::uint32_t>(ny * side + nx));
      }
    }
  }

  // Traffic signs: among the free-standing columns (8-connected cells
  // labelled pole or trunk with no canopy above), those whose visible width
  // across the line of sight jumps from a post's (<= sign_max_post_width_m)
  // to a panel's (sign_min_width_m..sign_max_width_m) at sign_min_base_m or
  // higher and stays so up to the column's top, with the panel's points on
  // a vertical plane, become a pole (post) below a traffic sign (panel). A
  // sign's wide panel is also what makes a sign post look like a trunk.
  void find_signs(const Scan& scan) const {
    const Config& c = config_;
    const auto f = [](double v) { return static_cast<float>(v); };
    const auto is_column = [&](std::uint32_t cell) {
      const detail::GridCell& g = grid_.cell(cell);
      return g.count > 0 &&
             (g.label == id(Class::kPole) || g.label == id(Class::kTrunk) || g.label == id(Class::kBuilding)) &&
             (g.upper_label == g.label || g.split_m == std::numeric_limits<float>::infinity());
    };
    for (const std::uint32_t cell : grid_.touched()) grid_.cell(cell).mark = -1;
    col_dir_.clear();
    std::int32_t columns = 0;
    constexpr std::int32_t kTooWide = std::numeric_limits<std::int32_t>::max();
    for (const std::uint32_t cell : grid_.touched()) {
      if (grid_.cell(cell).mark != -1 || !is_column(cell)) continue;
      grow(cell, columns, is_column);
      // A sign's panel spans up to sign_max_width_m and its cells; wider
      // groups (walls, a pole against a wall) are no single sign.
      if (stack_size_m() > f(c.sign_max_width_m) + grid_.cell_size_m()) {
        for (const std::uint32_t o : stack_) grid_.cell(o).mark = kTooWide;
        continue;
      }
      ++columns;
      const Eigen::Vector2f p = grid_.centre(cell);
      col_dir_.push_back(p.norm() > 1e-3F ? Eigen::Vector2f(p.normalized()) : Eigen::Vector2f(1.0F, 0.0F));
    }
    if (columns == 0) return;
    const float slice = f(c.sign_slice_m);
    const int slices = std::max(1, static_cast<int>(std::ceil(f(c.sign_max_top_m) / slice)));
    const auto k_cols = static_cast<std::size_t>(columns);
    const auto k_slices = static_cast<std::size_t>(slices);
    col_t_min_.assign(k_cols * k_slices, std::numeric_limits<float>::infinity());
    col_t_max_.assign(k_cols * k_slices, -std::numeric_limits<float>::infinity());
    col_top_m_.assign(k_cols, -std::numeric_limits<float>::infinity());
    col_base_m_.assign(k_cols, std::numeric_limits<float>::infinity());
    // Pass 1: visible width per column and height slice.
    const auto column_of = [&](std::size_t i) -> std::int32_t {
      if (cell_of_[i] < 0 || kind_[i] != detail::GroundKind::kObstacle) return -1;
      const auto cell = static_cast<std::uint32_t>(cell_of_[i]);
      return is_column(cell) && grid_.cell(cell).mark != kTooWide ? grid_.cell(cell).mark : -1;
    };
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      const std::int32_t k = column_of(i);
      if (k < 0) continue;
      const auto ks = static_cast<std::size_t>(k);
      const float h = height_m_[i];
      col_top_m_[ks] = std::max(col_top_m_[ks], h);
      col_base_m_[ks] = std::min(col_base_m_[ks], h);
      if (h >= f(c.sign_max_top_m)) continue;
      const auto s = static_cast<std::size_t>(std::clamp(static_cast<int>(h / slice), 0, slices - 1));
      const Eigen::Vector3f& q = scan.points[i];
      const float t = col_dir_[ks].x() * q.y() - col_dir_[ks].y() * q.x();
      col_t_min_[ks * k_slices + s] = std::min(col_t_min_[ks * k_slices + s], t);
      col_t_max_[ks * k_slices + s] = std::max(col_t_max_[ks * k_slices + s], t);
    }
    // Panel base per column (infinity: no sign).
    col_panel_m_.assign(k_cols, std::numeric_limits<float>::infinity());
    for (std::size_t k = 0; k < k_cols; ++k) {
      if (col_top_m_[k] > f(c.sign_max_top_m) || col_base_m_[k] > f(c.stem_max_base_m)) continue;  // too tall, or not standing
      float post = 0.0F;
      int post_slices = 0;   // slices between sign_post_min_height_m and the panel ...
      int post_seen = 0;     // ... and those with points
      float base = std::numeric_limits<float>::infinity();
      bool ok = true;
      for (std::size_t s = 0; s < k_slices; ++s) {
        const float lo = col_t_min_[k * k_slices + s];
        const float hi = col_t_max_[k * k_slices + s];
        const float h = static_cast<float>(s) * slice;
        if (base == std::numeric_limits<float>::infinity() && h >= f(c.sign_post_min_height_m)) ++post_slices;
        if (!(hi >= lo)) continue;  // no points at this height (occluded)
        const float w = hi - lo;
        if (base == std::numeric_limits<float>::infinity()) {
          if (h >= f(c.sign_min_base_m) && w >= f(c.sign_min_width_m)) {
            base = h;
          } else if (h >= f(c.sign_post_min_height_m)) {
            post = std::max(post, w);
            ++post_seen;
          }
        }
        if (base != std::numeric_limits<float>::infinity() && w > f(c.sign_max_width_m)) ok = false;
      }
      // The panel's own first slice was counted as a post slice.
      const bool post_visible = post_seen > 0 && static_cast<double>(post_seen) >= c.sign_min_post_cover * (post_slices - 1);
      if (ok && post_visible && post <= f(c.sign_max_post_width_m) && base < col_top_m_[k] &&
          col_top_m_[k] - base <= f(c.sign_max_panel_height_m)) {
        col_panel_m_[k] = base;
      }
    }
    // Pass 2: the panel's flatness (horizontal spread across its best line).
    col_moments_.assign(k_cols * 6, 0.0);
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      const std::int32_t k = column_of(i);
      if (k < 0 || height_m_[i] < col_panel_m_[static_cast<std::size_t>(k)]) continue;
      double* m = &col_moments_[static_cast<std::size_t>(k) * 6];
      const auto x = static_cast<double>(scan.points[i].x());
      const auto y = static_cast<double>(scan.points[i].y());
      m[0] += 1.0;
      m[1] += x;
      m[2] += y;
      m[3] += x * x;
      m[4] += y * y;
      m[5] += x * y;
    }
    for (const std::uint32_t cell : grid_.touched()) {
      detail::GridCell& g = grid_.cell(cell);
      if (g.mark < 0 || g.mark == kTooWide) continue;  // only columns were marked above
      const auto k = static_cast<std::size_t>(g.mark);
      if (col_panel_m_[k] == std::numeric_limits<float>::infinity()) continue;
      const double* m = &col_moments_[k * 6];
      if (m[0] < 3.0) continue;
      if (minor_axis_sd_m(m[0], m[1], m[2], m[3], m[4], m[5]) > c.sign_max_roughness_m) continue;
      g.label = id(Class::kPole);
      g.upper_label = id(Class::kTrafficSign);
      g.split_m = col_panel_m_[k];
    }
  }

  void label_objects(Scan& scan) const {
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      if (cell_of_[i] < 0) continue;
      const detail::GridCell& g = grid_.cell(static_cast<std::uint32_t>(cell_of_[i]));
      if (g.count == 0) continue;  // a near-ground point with no object above it
      scan.labels[i] = static_cast<Class>(height_m_[i] > g.split_m ? g.upper_label : g.label);
    }
  }

  GeometricSegmenterConfig config_;
  float tan_top_ = std::tan(static_cast<float>(GeometricSegmenterConfig{}.top_beam_elevation_rad));
  // Reused buffers (segment() is const; these are scratch space, not state).
  mutable detail::PolarGround ground_;
  mutable detail::ObstacleGrid grid_;
  mutable std::vector<float> height_m_;
  mutable std::vector<detail::GroundKind> kind_;
  mutable std::vector<std::int32_t> cell_of_;
  mutable std::vector<std::uint32_t> stack_;
  mutable std::vector<std::uint32_t> group_;
  // find_signs: per column, its reference direction, visible width per height
  // slice, height range, panel base and panel point moments.
  mutable std::vector<Eigen::Vector2f> col_dir_;
  mutable std::vector<float> col_t_min_;
  mutable std::vector<float> col_t_max_;
  mutable std::vector<float> col_top_m_;
  mutable std::vector<float> col_base_m_;
  mutable std::vector<float> col_panel_m_;
  mutable std::vector<double> col_moments_;
};

static_assert(Segmenter<GeometricSegmenter>);

}  // namespace semlio
