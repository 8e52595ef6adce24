#pragma once
/// \file
/// Ground segmentation on a polar grid (sectors of azimuth x range bins), in
/// the spirit of Himmelsbach et al., "Fast segmentation of 3D point clouds for
/// ground vehicles" (2010): each sector is walked outwards from the sensor and
/// a bin's lowest point becomes the local ground height when the bin is flat
/// and its height is reachable from the previous ground bin within a slope
/// limit. Along the walk the ground is also split into road (the surface the
/// vehicle stands on), a raised surface behind a curb (sidewalk) and a lower
/// or rougher surface past a step down (terrain, e.g. a verge).

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include <semlio/segment/detail/fast_atan2.hpp>

namespace semlio::detail {

/// Parameters of PolarGround (see GeometricSegmenterConfig for their meaning).
struct PolarGroundParams {
  float sensor_height_m = 1.73F;
  float max_range_m = 120.0F;
  int sectors = 360;
  float bins_per_sqrt_m = 8.0F;
  float ground_tolerance_m = 0.2F;
  float step_m = 0.1F;
  float max_slope = 0.15F;
  float flat_tolerance_m = 0.12F;
  float min_flat_fraction = 0.5F;
  float curb_min_m = 0.08F;
  float road_bend_per_m = 0.01F;
  float sidewalk_width_m = 5.0F;
};

/// What the ground walk says about a point.
/// kNearGround: within the ground tolerance of a bin that did not pass as
/// ground (the foot of a wall, a car's underside, a curb face).
enum class GroundKind : std::uint8_t { kObstacle = 0, kRoad = 1, kSidewalk = 2, kTerrain = 3, kInvalid = 4, kNearGround = 5 };

/// Polar-grid ground segmentation with reusable buffers (no allocation once
/// the buffers have grown to the largest scan seen). Not thread-safe.
class PolarGround {
 public:
  /// Ground state (road/sidewalk/terrain) of the bin of point i after run().
  [[nodiscard]] GroundKind bin_state(std::size_t i) const {
    return bin_of_[i] < 0 ? GroundKind::kInvalid : state_[static_cast<std::size_t>(bin_of_[i])];
  }

  /// Classifies every point as ground (road/sidewalk/terrain) or obstacle and
  /// writes its height above the local ground [m]. Non-finite points get
  /// kInvalid and height 0.
  void run(const std::vector<Eigen::Vector3f>& points, const PolarGroundParams& p, std::vector<float>& height_m,
           std::vector<GroundKind>& kind) {
    const std::size_t n = points.size();
    height_m.resize(n);
    kind.resize(n);
    const int sectors = std::max(1, p.sectors);
    const int bins = std::max(1, static_cast<int>(std::ceil(std::sqrt(std::max(p.max_range_m, 1.0F)) * p.bins_per_sqrt_m)) + 1);
    const std::size_t cells = static_cast<std::size_t>(sectors) * static_cast<std::size_t>(bins);
    zmin_.assign(cells, std::numeric_limits<float>::infinity());
    count_.assign(cells, 0U);
    flat_count_.assign(cells, 0U);
    ground_z_.resize(cells);
    state_.resize(cells);
    flat_.resize(cells);
    bin_of_.resize(n);
    const float sector_scale = static_cast<float>(sectors) / (2.0F * std::numbers::pi_v<float>);
    // Pass 1: bin every point, lowest height per bin.
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3f& q = points[i];
      if (!q.allFinite()) {
        bin_of_[i] = -1;
        continue;
      }
      const float r = std::sqrt(q.x() * q.x() + q.y() * q.y());
      int b = static_cast<int>(std::sqrt(r) * p.bins_per_sqrt_m);
      b = std::min(b, bins - 1);
      int s = static_cast<int>((fast_atan2(q.y(), q.x()) + std::numbers::pi_v<float>) * sector_scale);
      s = std::clamp(s, 0, sectors - 1);
      const int cell = s * bins + b;
      bin_of_[i] = cell;
      const auto c = static_cast<std::size_t>(cell);
      zmin_[c] = std::min(zmin_[c], q.z());
      if (count_[c] < 0xFFFFU) ++count_[c];
    }
    // Pass 2: how many points of a bin lie near its lowest point (flatness).
    for (std::size_t i = 0; i < n; ++i) {
      if (bin_of_[i] < 0) continue;
      const auto c = static_cast<std::size_t>(bin_of_[i]);
      if (points[i].z() <= zmin_[c] + p.flat_tolerance_m && flat_count_[c] < 0xFFFFU) ++flat_count_[c];
    }
    // The local ground plane around the vehicle anchors every sector's road line.
    fit_local_plane(sectors, bins, p);
    // Walk each sector outwards.
    for (int s = 0; s < sectors; ++s) walk_sector(s, bins, p);
    // Kerbs crossed along a ring (sidewalks the walk outwards cannot see).
    mark_raised_arcs(sectors, bins, p);
    // Label points.
    for (std::size_t i = 0; i < n; ++i) {
      if (bin_of_[i] < 0) {
        height_m[i] = 0.0F;
        kind[i] = GroundKind::kInvalid;
        continue;
      }
      const auto c = static_cast<std::size_t>(bin_of_[i]);
      const float h = points[i].z() - ground_z_[c];
      height_m[i] = h;
      // Bins that did not pass as ground (walls, cars, poles standing in
      // them) keep as ground only points very close to the ground height.
      if (h > p.ground_tolerance_m) {
        kind[i] = GroundKind::kObstacle;
      } else if (flat_[c] == 0U && h > p.curb_min_m) {
        kind[i] = GroundKind::kNearGround;
      } else if (state_[c] == GroundKind::kRoad && h > p.curb_min_m) {
        kind[i] = GroundKind::kSidewalk;  // the raised side of a bin that straddles a curb
      } else {
        kind[i] = state_[c];
      }
    }
  }

 private:
  // Fits z = c0 + cx x + cy y to the lowest points of the flat bins 3-12 m
  // away: the road under and around the vehicle, including the sensor's roll
  // and pitch relative to it. Pass 0 uses only the bins ahead of and behind
  // the vehicle in its own lane (centres within kLaneHalfWidth of its heading
  // axis), within 0.5 m of the sensor-height plane: the vehicle drives along
  // its road, so these are the road, whereas the bins beside it may be a
  // sidewalk a kerb higher (a car driving ~3 m from the kerb sees only
  // sidewalk to its side, since an HDL-64E's lowest ring meets the ground
  // 3.7 m out; an all-round fit sits between road and sidewalk and shrinks
  // the kerb step below curb_min_m, and raised verges tilt it the same way).
  // Pass 1 refits on all bins from 0.15 m below that plane (cross fall to
  // the gutters, dips) to curb_min_m above it (higher is past a kerb). With
  // fewer than 20 bins in the lane (a car just ahead and behind), pass 0
  // takes all bins and pass 1 keeps bins within 0.15 m either way, as an
  // all-round fit. Falls back to z = -sensor_height with too few bins.
  void fit_local_plane(int sectors, int bins, const PolarGroundParams& p) {
    sectors_ = sectors;
    plane_ = Eigen::Vector3f(-p.sensor_height_m, 0.0F, 0.0F);
    lane_grade_ = 0.0F;
    const float inv = 1.0F / p.bins_per_sqrt_m;
    const int b0 = static_cast<int>(std::sqrt(3.0F) * p.bins_per_sqrt_m);
    const int b1 = std::min(bins - 1, static_cast<int>(std::sqrt(12.0F) * p.bins_per_sqrt_m));
    // Half the width of a lane (2.75-3.75 m) [m]: the vehicle's own lane,
    // even when the vehicle is 0.3 m off its centre line.
    constexpr float kLaneHalfWidth = 1.5F;
    bool lane_fit = true;  // false: too few bins in the lane, fit all round
    for (int pass = 0; pass < 2; ++pass) {
      Eigen::Matrix3f A = Eigen::Matrix3f::Zero();
      Eigen::Vector3f rhs = Eigen::Vector3f::Zero();
      int used = 0;
      const bool lane_only = pass == 0 && lane_fit;
      for (int s = 0; s < sectors; ++s) {
        const float az = (static_cast<float>(s) + 0.5F) * 2.0F * std::numbers::pi_v<float> / static_cast<float>(sectors) -
                         std::numbers::pi_v<float>;
        const float cs = std::cos(az);
        const float sn = std::sin(az);
        for (int b = b0; b <= b1; ++b) {
          const auto c = static_cast<std::size_t>(s * bins + b);
          if (count_[c] == 0 || static_cast<float>(flat_count_[c]) < p.min_flat_fraction * static_cast<float>(count_[c])) {
            continue;
          }
          const float rc = (static_cast<float>(b) + 0.5F) * inv;
          const float r = rc * rc;
          if (lane_only && std::fabs(r * sn) > kLaneHalfWidth) continue;
          const Eigen::Vector3f a(1.0F, r * cs, r * sn);
          const float z = zmin_[c];
          const float dz = z - plane_.dot(a);
          if (std::fabs(dz) > (pass == 0 ? 0.5F : 0.15F)) continue;
          if (pass == 1 && lane_fit && dz > p.curb_min_m) continue;  // past a kerb
          A += a * a.transpose();
          rhs += a * z;
          ++used;
        }
      }
      if (used < 20 && lane_only) {
        lane_fit = false;
        pass = -1;  // start again, all round
        continue;
      }
      if (used < 20) return;
      A += 1.0F * Eigen::Matrix3f::Identity() * 1e-3F;  // keeps a one-sided fit well posed
      const Eigen::Vector3f sol = A.ldlt().solve(rhs);
      if (!sol.allFinite()) return;
      plane_ = sol;
      if (lane_only) lane_grade_ = sol.y();
    }
  }

  // Road model of a sector: a line z = a + slope * r fitted (least squares,
  // slope weakly pulled to 0) to the foot of the sensor and the bins accepted
  // as road so far (the vehicle stands on the road). A ground bin off this line
  // by more than curb_min_m (+ road_bend_per_m per metre beyond the last road
  // bin, for vertical curves) ends the road: above it is a sidewalk behind a
  // curb, below it a verge. Comparing with the line rather than with the
  // previous bin also catches edges crossed at a shallow angle, where the
  // height changes slowly from bin to bin.
  void walk_sector(int s, int bins, const PolarGroundParams& p) {
    float prev_z = -p.sensor_height_m;
    float prev_r = 0.0F;
    // Road-line fit sums, starting from two virtual points of the local
    // ground plane along this sector (at the sensor's foot and 5 m out).
    const float az = (static_cast<float>(s) + 0.5F) * 2.0F * std::numbers::pi_v<float> / static_cast<float>(sectors_) -
                     std::numbers::pi_v<float>;
    const float grade = plane_.y() * std::cos(az) + plane_.z() * std::sin(az);
    const float z0 = plane_.x();
    const float z5 = plane_.x() + 5.0F * grade;
    float n = 2.0F, sr = 5.0F, sz = z0 + z5, srr = 25.0F, srz = 5.0F * z5;
    float road_r = 0.0F;
    float step_r = 0.0F;
    GroundKind state = GroundKind::kRoad;
    const float inv = 1.0F / p.bins_per_sqrt_m;
    for (int b = 0; b < bins; ++b) {
      const auto c = static_cast<std::size_t>(s * bins + b);
      const float rc = (static_cast<float>(b) + 0.5F) * inv;
      const float r = rc * rc;  // bin centre range [m]
      bool accepted = false;
      if (count_[c] > 0) {
        const float z = zmin_[c];
        const bool flat = static_cast<float>(flat_count_[c]) >= p.min_flat_fraction * static_cast<float>(count_[c]);
        accepted = flat && std::fabs(z - prev_z) <= p.step_m + p.max_slope * (r - prev_r);
        if (accepted) {
          if (state == GroundKind::kRoad) {
            bool on_road = true;
            {
              constexpr float kSlopePrior = 1.0F;  // [m^2]: keeps the slope near 0 until bins spread in range
              const float mr = sr / n;
              const float mz = sz / n;
              const float slope = (srz - n * mr * mz) / (srr - n * mr * mr + kSlopePrior);
              const float dzr = z - (mz + slope * (r - mr));
              on_road = std::fabs(dzr) <= p.curb_min_m + p.road_bend_per_m * (r - road_r);
              if (!on_road) {
                state = dzr > 0.0F ? GroundKind::kSidewalk : GroundKind::kTerrain;
                step_r = r;
              }
            }
            if (on_road) {
              n += 1.0F;
              sr += r;
              sz += z;
              srr += r * r;
              srz += r * z;
              road_r = r;
            }
          } else if (state == GroundKind::kSidewalk && r - step_r > p.sidewalk_width_m) {
            state = GroundKind::kTerrain;
          }
          prev_z = z;
          prev_r = r;
        }
      }
      ground_z_[c] = prev_z;
      state_[c] = state;
      flat_[c] = accepted ? 1U : 0U;
    }
  }

  // Kerbs along a ring: in each range bin up to kMaxRingRange, the ground
  // bins are followed around the sensor from a road bin, both ways round. A
  // rise of curb_min_m..kMaxKerb off a road bin within kKerbArc of arc
  // (ground bins at most kMaxGap apart), later followed by a drop of the same
  // size (within kMaxRamp of arc: a kerb or a dropped kerb's ramp) back to
  // within curb_min_m / 2 of that road height (moved by the lane's grade
  // between the two), is a raised strip crossed twice. A
  // vehicle within a few metres of a kerb has the sidewalk beside it inside
  // its nearest rings, and on a crowned road the sidewalk is barely above a
  // plane through the lane, so the walk outwards takes it for road. The
  // strip's road bins raised by at least curb_min_m / 2 above the line from
  // one foot to the other become sidewalk. Without the drop (a long ramp, a
  // slope) nothing changes.
  void mark_raised_arcs(int sectors, int bins, const PolarGroundParams& p) {
    constexpr float kMaxRingRange = 20.0F;  // [m]: farther rings are too sparse for a 0.1 m step between sectors
    const float inv = 1.0F / p.bins_per_sqrt_m;
    for (int b = 0; b < bins; ++b) {
      const float rc = (static_cast<float>(b) + 0.5F) * inv;
      const float r = rc * rc;
      if (r > kMaxRingRange) break;
      ring_.clear();
      int start = -1;
      for (int s = 0; s < sectors; ++s) {
        const auto c = static_cast<std::size_t>(s * bins + b);
        if (flat_[c] == 0U) continue;
        if (start < 0 && state_[c] == GroundKind::kRoad) start = static_cast<int>(ring_.size());
        ring_.push_back(s);
      }
      const auto n = static_cast<int>(ring_.size());
      if (start < 0 || n < 3) continue;
      // Both ways round: a walk wants a kerb's step up first and accepts a
      // ramp on the way down, so a strip with a kerb at one end and a ramp
      // (or a kerb too slanted to read as a step) at the other is found only
      // when walked from its kerb end. On the real KITTI 00 scans this and
      // kKerbArc lift the sidewalk IoU from 0.21 to 0.32 (test "the real
      // labelled KITTI 00 scans: GeometricSegmenter reaches issue #38's
      // goals").
      mark_raised_arcs_one_way(start, n, b, bins, sectors, +1, p);
      mark_raised_arcs_one_way(start, n, b, bins, sectors, -1, p);
    }
  }

  // How much the road climbs along the vehicle's lane (its grade ahead, from
  // the lane-only plane fit) from sector s0 to sector s1 on the ring of
  // range r [m]. The lane fit, not the all-round plane: verges and ditches
  // beside a road tilt the all-round fit sideways.
  [[nodiscard]] float lane_rise(int s0, int s1, float r) const {
    const auto az = [&](int s) {
      return (static_cast<float>(s) + 0.5F) * 2.0F * std::numbers::pi_v<float> / static_cast<float>(sectors_) -
             std::numbers::pi_v<float>;
    };
    return r * lane_grade_ * (std::cos(az(s1)) - std::cos(az(s0)));
  }

  // One walk of mark_raised_arcs around range bin b, whose n ground bins
  // are in ring_, from its road bin `start` in direction dir (+1: increasing
  // sector, -1: decreasing).
  void mark_raised_arcs_one_way(int start, int n, int b, int bins, int sectors, int dir, const PolarGroundParams& p) {
    constexpr float kMaxKerb = 0.3F;   // [m]: kerbs are 0.10-0.20 m (up to 0.25 m at bus stops); higher is a wall's foot
    constexpr float kMaxGap = 1.0F;    // [m]: farther apart, cross fall (2-3 %) and bumps mask a kerb
    constexpr float kMaxRamp = 2.0F;   // [m]: a dropped kerb (driveway, crossing) ramps down over 1-2 m; cross fall takes 3+ m for curb_min_m
    constexpr float kKerbArc = 0.3F;   // [m]: a kerb's step, seen over this much arc (three one-degree sectors at 6 m)
    const float rc = (static_cast<float>(b) + 0.5F) / p.bins_per_sqrt_m;
    const float r = rc * rc;  // the ring's range [m]
    const float sector_rad = 2.0F * std::numbers::pi_v<float> / static_cast<float>(sectors);
    // The k-th ground bin of the ring counted from `start` in direction dir: its sector, its cell.
    const auto sector = [&](int k) { return ring_[static_cast<std::size_t>(((start + dir * k) % n + n) % n)]; };
    const auto bin = [&](int k) { return static_cast<std::size_t>(sector(k) * bins + b); };
    const auto sectors_between = [&](int k0, int k1) { return (dir * (sector(k1) - sector(k0)) + sectors) % sectors; };
    int up = -1;  // ring index of the first raised bin, -1: none open
    float road_z = 0.0F;
    for (int k = 1; k < n; ++k) {
      const std::size_t cur = bin(k);
      if (static_cast<float>(sectors_between(k - 1, k)) * sector_rad * r > kMaxGap) {
        up = -1;  // the ring is broken here: no step can be judged across
        continue;
      }
      if (up < 0) {
        // A kerb: a rise of curb_min_m..kMaxKerb off a road bin within
        // kKerbArc of arc. A ring crossing the kerb at a slant, or a bin
        // straddling its face, spreads the step over two or three bins.
        float low = std::numeric_limits<float>::infinity();
        int arc_sectors = 0;
        for (int j = k - 1; j >= 0; --j) {
          arc_sectors += sectors_between(j, j + 1);
          if (j < k - 1 && static_cast<float>(arc_sectors) * sector_rad * r > kKerbArc) break;
          if (state_[bin(j)] == GroundKind::kRoad) low = std::min(low, ground_z_[bin(j)]);
        }
        const float rise = ground_z_[cur] - low;
        if (rise >= p.curb_min_m && rise <= kMaxKerb) {
          up = k;
          road_z = low;
        }
      } else {
        // Back at the height it left -- as the lane's grade climbs or falls
        // from there (on a street with a grade, a ring's two kerb
        // crossings lie metres apart along it: test "GeometricSegmenter
        // finds the sidewalk beside a vehicle driving close to the kerb",
        // grade 1 %) -- it crossed a raised strip when it fell by
        // curb_min_m..kMaxKerb within the last kMaxRamp of arc (a kerb or a
        // dropped kerb's ramp); otherwise it came down gradually: a slope,
        // not a kerb.
        if (ground_z_[cur] > road_z + lane_rise(sector(up - 1), sector(k), r) + 0.5F * p.curb_min_m) continue;  // still up
        float high = -std::numeric_limits<float>::infinity();
        int arc_sectors = 0;
        for (int j = k - 1; j >= up; --j) {
          arc_sectors += sectors_between(j, j + 1);
          if (static_cast<float>(arc_sectors) * sector_rad * r > kMaxRamp) break;
          high = std::max(high, ground_z_[bin(j)]);
        }
        const float drop = high - ground_z_[cur];
        if (drop >= p.curb_min_m && drop <= kMaxKerb) {
          // The strip's bins raised above the road line from the foot of the
          // step up (road_z) to where the ring landed: the road between two
          // kerb feet at different heights climbs between them, so a road
          // bin the ring passed on the way stays road.
          const float land_z = ground_z_[cur];
          const int span = std::max(1, sectors_between(up - 1, k));
          int along = sectors_between(up - 1, up);
          for (int j = up; j < k; ++j) {
            const std::size_t c = bin(j);
            const float base = road_z + (land_z - road_z) * static_cast<float>(along) / static_cast<float>(span);
            if (state_[c] == GroundKind::kRoad && ground_z_[c] >= base + 0.5F * p.curb_min_m) state_[c] = GroundKind::kSidewalk;
            along += sectors_between(j, j + 1);
          }
        }
        up = -1;
      }
    }
  }

  Eigen::Vector3f plane_ = Eigen::Vector3f::Zero();  // local ground plane (c0, cx, cy)
  float lane_grade_ = 0.0F;                           // cx of the lane-only fit (0: none)
  int sectors_ = 1;
  std::vector<float> zmin_;
  std::vector<std::uint16_t> count_;
  std::vector<std::uint16_t> flat_count_;
  std::vector<float> ground_z_;
  std::vector<GroundKind> state_;
  std::vector<std::uint8_t> flat_;  // 1: the bin passed as ground (flat, reachable)
  std::vector<std::int32_t> bin_of_;
  std::vector<int> ring_;  // mark_raised_arcs: sectors of one ring's ground bins
};

}  // namespace semlio::detail
