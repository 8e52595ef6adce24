#pragma once
/// \file
/// Beam-table detection from the data, for clouds without a ring field and
/// without a known sensor profile: the elevations seen from the sensor origin
/// of the first few scans are clustered, each cluster that holds a beam's
/// share of the points is a beam, and the report says how well the points fit
/// the found table (fraction within a tolerance, RMS residual).
///
/// Method, in order of preference:
/// 1. kScanRings: the scans carry rings (a driver's ring field): one beam per
///    ring index, at the median elevation of its points.
/// 2. kElevation: peaks of the elevation histogram (bin_rad, smoothed with
///    a 1.5-bin Gaussian), thinned by non-maximum suppression whose
///    separation adapts to half the median spacing of the peaks found (so a
///    beam split in two humps counts once); a peak is a beam when it is at
///    least min_beam_fraction as high as a typical peak (the 75th percentile),
///    so the small satellite peaks next to a beam are not beams. Those
///    satellites are real: Ouster beams leave the sensor ~2.8 cm off its axis,
///    which shifts the elevation seen from the origin towards the horizon by
///    up to ~0.4 deg at 2 m (measured on the BALM OS0 recording: a 41-point
///    cluster 0.4 deg above the 1 300-point -35.7 deg beam). Each beam sits at
///    the mean of the points within a quarter spacing of its peak. Accepted
///    when at least min_fit_fraction of the points lie within the tolerance
///    (tolerance_rad, at most relative_tolerance x the median spacing). When
///    the scans pooled fail, the single scan that fits best is tried (a sweep
///    taken during a fast turn smears its beams and hides the others').
/// 3. kPointOrder: the KITTI layout (rings stored one after the other, cut
///    where the azimuth wraps, rings.hpp): accepted when every scan yields the
///    same ring count, between min_order_rings and max_beams.
/// 4. kUniformFallback (separable = false): no beams can be told apart -- a
///    solid-state or non-repetitive scan pattern, or a calibration that smears
///    the beams into each other. The table is then a uniform set of pseudo
///    beams fallback_spacing_rad apart over the 1st-99th percentile of the
///    elevations: rings become elevation bands, which still order points by
///    azimuth within a band for the LOAM curvature (coarser than real rings;
///    surface features dominate then). The note says so.
///
/// Measured with the defaults (scratch runs; the real-data cases are in
/// tests/features/test_beam_detection.cpp):
/// - BALM OS0 (shared data, keyframes 0-2, 220 408 points): 64 beams by
///   elevation, -44.68 .. +45.47 deg, median spacing 1.39 deg (the spacing
///   alternates ~1.3 / ~1.7 deg: the unit's table is not the nominal uniform
///   one), 96.5 % of the points within 0.25 deg, RMS 0.11 deg. Keyframes
///   taken while the sensor turns fast (e.g. 40, 55) are motion-compensated
///   sweeps whose beams smear into each other: there detection says "not
///   separable" -- detect on the first scans, as the tools do.
/// - HDL-32E scan pair (tests/data/scan_pair): 32 beams by elevation,
///   -30.67 .. +10.67 deg, every point within 0.01 deg of its beam.
/// - Real KITTI HDL-64E (tests/data/kitti): the elevations do not separate
///   (elevation peaks explain 59 % of the points): KITTI's per-unit
///   calibration and the lasers' offsets from the origin fill the upper block
///   (1/3 deg nominal spacing) with a continuous band. Point order gives the
///   64 rings; their median elevations run from -23.7 to +2.6 deg, and 55 %
///   of the points lie within 0.25 deg of their ring's median (RMS 0.36 deg):
///   KITTI's elevation seen from the origin varies with range.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/features/sensor_model.hpp>

namespace semlio {

/// Settings of BeamDetector (defaults: see the file comment).
struct BeamDetectionConfig {
  double bin_rad = 0.02 * std::numbers::pi / 180.0;             ///< elevation histogram bin [rad]
  double min_separation_rad = 0.1 * std::numbers::pi / 180.0;   ///< closest two beams may be [rad]
  double min_beam_fraction = 0.2;                                ///< peaks lower than this x a typical peak are no beams
  double tolerance_rad = 0.25 * std::numbers::pi / 180.0;       ///< a point fits its beam within this [rad] ...
  double relative_tolerance = 0.25;                              ///< ... and within this x the median beam spacing
  double min_fit_fraction = 0.8;                                 ///< accept a table when this fraction of points fits
  std::size_t max_beams = 512;                             ///< more clusters than this: not a beam pattern
  std::size_t min_order_rings = 8;                         ///< fewer point-order rings: not the KITTI layout
  double min_range_m = 0.0;                                ///< ignore nearer points [m]
  double fallback_spacing_rad = 1.0 * std::numbers::pi / 180.0;  ///< pseudo-beam spacing when not separable [rad]

  /// Throws ConfigError naming the bad field and value.
  void validate() const {
    const auto fail = [](const char* field, double v) {
      throw ConfigError(std::string("BeamDetectionConfig.") + field + " is invalid: " + std::to_string(v));
    };
    if (!(bin_rad > 1e-6) || !std::isfinite(bin_rad)) fail("bin_rad", bin_rad);
    if (!(min_separation_rad >= bin_rad) || !std::isfinite(min_separation_rad)) fail("min_separation_rad", min_separation_rad);
    if (!(relative_tolerance > 0.0) || !std::isfinite(relative_tolerance)) fail("relative_tolerance", relative_tolerance);
    if (!(min_beam_fraction >= 0.0 && min_beam_fraction <= 1.0)) fail("min_beam_fraction", min_beam_fraction);
    if (!(tolerance_rad > 0.0) || !std::isfinite(tolerance_rad)) fail("tolerance_rad", tolerance_rad);
    if (!(min_fit_fraction >= 0.0 && min_fit_fraction <= 1.0)) fail("min_fit_fraction", min_fit_fraction);
    if (max_beams < 2 || max_beams > 65535) fail("max_beams", static_cast<double>(max_beams));
    if (!(min_range_m >= 0.0) || !std::isfinite(min_range_m)) fail("min_range_m", min_range_m);
    if (!(fallback_spacing_rad > 0.0) || !std::isfinite(fallback_spacing_rad)) {
      fail("fallback_spacing_rad", fallback_spacing_rad);
    }
  }
};

/// Where a detected beam table came from (file comment).
enum class BeamSource : std::uint8_t {
  kScanRings,        ///< the scans' ring field
  kElevation,        ///< elevation clusters
  kPointOrder,       ///< KITTI point order
  kUniformFallback,  ///< beams not separable: uniform elevation bands
};

/// Name of a BeamSource, as written to report.json.
constexpr const char* to_string(BeamSource s) noexcept {
  switch (s) {
    case BeamSource::kScanRings: return "scan_rings";
    case BeamSource::kElevation: return "elevation";
    case BeamSource::kPointOrder: return "point_order";
    case BeamSource::kUniformFallback: return "uniform_fallback";
  }
  return "unknown";
}

/// What BeamDetector found.
struct BeamDetection {
  BeamSource source = BeamSource::kUniformFallback;  ///< method that produced the table
  bool separable = false;               ///< real beams were resolved (false: kUniformFallback)
  std::size_t scans = 0;                ///< scans examined
  std::size_t points = 0;               ///< points examined (finite, non-zero, beyond min_range_m)
  std::vector<double> elevations_rad;   ///< beam elevations, strictly ascending [rad]
  double fit_fraction = 0.0;            ///< points within tolerance_rad of their beam
  double rms_residual_rad = 0.0;        ///< RMS elevation residual to their beam [rad]
  double median_spacing_rad = 0.0;      ///< median gap between neighbouring beams [rad]
  std::size_t elevation_clusters = 0;   ///< clusters separated by gaps (before the size filter)
  std::size_t elevation_beams = 0;      ///< clusters large enough to be beams
  double elevation_fit_fraction = 0.0;  ///< fit of the elevation clusters (whether accepted or not)
  std::size_t order_rings = 0;          ///< rings from point order when consistent over the scans, else 0
  std::string note;                     ///< one line: what was found, or why the fallback was used

  /// Number of beams in the table.
  [[nodiscard]] std::size_t beams() const noexcept { return elevations_rad.size(); }

  /// The table as a SensorModel (ring inference by elevation) at the given
  /// rotation rate. Throws ConfigError when the table is empty.
  [[nodiscard]] SensorModel sensor_model(double rotation_rate_hz = 10.0) const {
    SensorModel m;
    m.elevations_rad = elevations_rad;
    m.rotation_rate_hz = rotation_rate_hz;
    m.validate();
    return m;
  }
};

namespace detail {

/// Elevation atan2(z, hypot(x, y)) of p [rad].
inline double elevation_rad(const Eigen::Vector3f& p) {
  const auto x = static_cast<double>(p.x());
  const auto y = static_cast<double>(p.y());
  return std::atan2(static_cast<double>(p.z()), std::sqrt(x * x + y * y));
}

/// Median of the sorted range [b, e) (b < e).
inline double sorted_median(const std::vector<double>& v, std::size_t b, std::size_t e) {
  const std::size_t n = e - b;
  return n % 2 == 1 ? v[b + n / 2] : 0.5 * (v[b + n / 2 - 1] + v[b + n / 2]);
}

/// Median of the gaps between neighbouring entries of an ascending table.
inline double median_spacing(const std::vector<double>& table) {
  if (table.size() < 2) return 0.0;
  std::vector<double> gaps;
  for (std::size_t i = 1; i < table.size(); ++i) gaps.push_back(table[i] - table[i - 1]);
  std::sort(gaps.begin(), gaps.end());
  return sorted_median(gaps, 0, gaps.size());
}

/// Makes an ascending table strictly ascending (equal medians of two rings
/// are nudged apart by a microradian: SensorModel requires it).
inline void make_strictly_ascending(std::vector<double>& table) {
  std::sort(table.begin(), table.end());
  for (std::size_t i = 1; i < table.size(); ++i) {
    if (!(table[i] > table[i - 1])) table[i] = table[i - 1] + 1e-6;
  }
}

}  // namespace detail

/// Collects elevations (and point-order ring counts) from a few scans, then
/// detects the beam table. Not thread-safe; cheap to construct.
class BeamDetector {
 public:
  using Config = BeamDetectionConfig;

  /// Throws ConfigError for invalid settings.
  explicit BeamDetector(const Config& config = {}) : config_(config) { config_.validate(); }

  /// Adds one scan (sensor frame). Non-finite and (0,0,0) points and points
  /// nearer than min_range_m are ignored. Throws ValueError for a scan whose
  /// fields are inconsistent.
  void add(const Scan& scan) {
    scan.validate();
    ++scans_;
    scan_begin_.push_back(elevations_.size());
    std::vector<std::size_t> begins;
    ring_starts_from_order(scan.points, begins);
    order_counts_.push_back(begins.size());
    const double min2 = config_.min_range_m * config_.min_range_m;
    const bool use_rings = scan.has_rings();
    if (!use_rings) all_rings_ = false;
    std::size_t ring = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      while (ring + 1 < begins.size() && begins[ring + 1] <= i) ++ring;
      const Eigen::Vector3f& p = scan.points[i];
      if (!p.allFinite() || (p.x() == 0.0F && p.y() == 0.0F && p.z() == 0.0F)) continue;
      if (p.cast<double>().squaredNorm() < min2) continue;
      const double e = detail::elevation_rad(p);
      elevations_.push_back(e);
      // Rings of the scan's own field, and of point order, for the first scan only
      // (the per-ring elevations of one scan make the table).
      if (use_rings) scan_ring_.push_back({scans_ - 1, scan.rings[i], e});
      if (scans_ == 1) order_ring_.push_back({0, static_cast<std::uint32_t>(ring), e});
    }
  }

  /// Detects the table from everything added (file comment: the order of
  /// methods). With no points at all: an empty table, separable = false.
  [[nodiscard]] BeamDetection detect() const {
    BeamDetection d;
    d.scans = scans_;
    d.points = elevations_.size();
    if (elevations_.empty()) {
      d.note = "no usable points";
      return d;
    }
    std::vector<double> sorted = elevations_;
    std::sort(sorted.begin(), sorted.end());

    // 1. The scans' ring field.
    if (all_rings_ && scans_ > 0 && !scan_ring_.empty() && assigned_table(scan_ring_, d)) {
      d.source = BeamSource::kScanRings;
      d.separable = true;
      d.note = std::to_string(d.beams()) + " beams from the scans' ring field";
      elevation_clusters(sorted, d);  // reported alongside
      return d;
    }

    // 2. Elevation clusters, of all scans together; else of the single scan
    // that fits best (one sweep taken while the sensor turns fast smears its
    // beams, and pooled with still ones it hides them all).
    const auto accept = [&](const std::vector<double>& table, const BeamDetection& probe) {
      return table.size() >= 2 && table.size() <= config_.max_beams &&
             probe.elevation_fit_fraction >= config_.min_fit_fraction;
    };
    std::vector<double> table = elevation_clusters(sorted, d);
    std::string which = "";
    if (!accept(table, d) && scan_begin_.size() > 1) {
      double best = -1.0;
      for (std::size_t k = 0; k < scan_begin_.size(); ++k) {
        const std::size_t b = scan_begin_[k];
        const std::size_t e = k + 1 < scan_begin_.size() ? scan_begin_[k + 1] : elevations_.size();
        if (e <= b) continue;
        std::vector<double> one(elevations_.begin() + static_cast<std::ptrdiff_t>(b),
                                elevations_.begin() + static_cast<std::ptrdiff_t>(e));
        std::sort(one.begin(), one.end());
        BeamDetection probe;
        const std::vector<double> t = elevation_clusters(one, probe);
        if (accept(t, probe) && probe.elevation_fit_fraction > best) {
          best = probe.elevation_fit_fraction;
          table = t;
          which = " (scan " + std::to_string(k) + " alone; all " + std::to_string(scans_) + " together fit " +
                  std::to_string(d.elevation_fit_fraction) + ")";
        }
      }
      if (best >= 0.0) {
        d.elevation_beams = table.size();
        d.elevation_fit_fraction = best;
      }
    }
    if (accept(table, d)) {
      d.source = BeamSource::kElevation;
      d.separable = true;
      d.elevations_rad = table;
      fit(sorted, d);  // the fit reported is over every scan's points
      d.note = std::to_string(d.beams()) + " beams separated by elevation" + which;
      return d;
    }

    // 3. Point order, when every scan agrees on the ring count.
    const bool order_consistent =
        !order_counts_.empty() &&
        std::all_of(order_counts_.begin(), order_counts_.end(), [&](std::size_t c) { return c == order_counts_[0]; });
    d.order_rings = order_consistent ? order_counts_[0] : 0;
    if (d.order_rings >= config_.min_order_rings && d.order_rings <= config_.max_beams &&
        assigned_table(order_ring_, d)) {
      d.source = BeamSource::kPointOrder;
      d.separable = true;
      d.note = std::to_string(d.beams()) + " rings from point order; elevations do not separate (" +
               std::to_string(d.elevation_beams) + " elevation clusters, fit " +
               std::to_string(d.elevation_fit_fraction) + ")";
      return d;
    }

    // 4. Not separable: uniform elevation bands.
    const auto pct = [&](double q) {
      return sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1))];
    };
    const double lo = pct(0.01);
    const double hi = pct(0.99);
    const auto bands = static_cast<std::size_t>(std::clamp(
        std::floor((hi - lo) / config_.fallback_spacing_rad) + 1.0, 1.0, static_cast<double>(config_.max_beams)));
    const double step = bands > 1 ? (hi - lo) / static_cast<double>(bands - 1) : 0.0;
    d.elevations_rad.clear();
    for (std::size_t k = 0; k < bands; ++k) d.elevations_rad.push_back(lo + step * static_cast<double>(k));
    detail::make_strictly_ascending(d.elevations_rad);
    d.source = BeamSource::kUniformFallback;
    d.separable = false;
    fit(sorted, d);
    d.note = "beams not separable (" + std::to_string(d.elevation_beams) + " elevation clusters fit " +
             std::to_string(d.elevation_fit_fraction) + ", point order " + std::to_string(d.order_rings) +
             " rings): " + std::to_string(d.beams()) + " uniform elevation bands";
    return d;
  }

  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  struct RingSample {
    std::size_t scan;
    std::uint32_t ring;
    double elevation_rad;
  };

  // Peaks of the elevation histogram; returns the beam table and fills the
  // elevation_* fields of d (file comment).
  std::vector<double> elevation_clusters(const std::vector<double>& sorted, BeamDetection& d) const {
    const double bin = config_.bin_rad;
    const double lo = sorted.front() - 10.0 * bin;
    const double span = sorted.back() + 10.0 * bin - lo;
    if (!(span > 0.0) || !std::isfinite(span)) return {};
    const auto n = static_cast<std::size_t>(std::ceil(span / bin)) + 1;
    std::vector<double> raw(n, 0.0);
    for (const double e : sorted) raw[std::min(n - 1, static_cast<std::size_t>((e - lo) / bin))] += 1.0;
    // Gaussian smoothing, sigma 1.5 bins: one beam's spread becomes one hump.
    std::vector<double> h(n, 0.0);
    constexpr int kHalf = 4;
    for (std::size_t i = 0; i < n; ++i) {
      double s = 0.0;
      for (int k = -kHalf; k <= kHalf; ++k) {
        const auto j = static_cast<std::ptrdiff_t>(i) + k;
        if (j < 0 || j >= static_cast<std::ptrdiff_t>(n)) continue;
        s += raw[static_cast<std::size_t>(j)] * std::exp(-0.5 * (k * k) / 2.25);
      }
      h[i] = s;
    }
    std::vector<std::size_t> maxima;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      if (h[i] > h[i - 1] && h[i] >= h[i + 1] && h[i] > 0.0) maxima.push_back(i);
    }
    d.elevation_clusters = maxima.size();
    std::sort(maxima.begin(), maxima.end(), [&](std::size_t a, std::size_t b) { return h[a] > h[b]; });
    // Non-maximum suppression with a separation that adapts to the spacing
    // found: half the median spacing (split humps and satellites go).
    double separation = config_.min_separation_rad;
    std::vector<double> table;
    for (int pass = 0; pass < 4; ++pass) {
      std::vector<std::size_t> kept;
      for (const std::size_t i : maxima) {
        const bool clear = std::all_of(kept.begin(), kept.end(), [&](std::size_t k) {
          return std::abs(static_cast<double>(i) - static_cast<double>(k)) * bin >= separation;
        });
        if (clear) kept.push_back(i);
      }
      if (kept.empty()) return {};
      std::vector<double> heights;
      for (const std::size_t k : kept) heights.push_back(h[k]);
      std::sort(heights.begin(), heights.end());
      const double typical = heights[(3 * (heights.size() - 1)) / 4];
      table.clear();
      for (const std::size_t k : kept) {
        if (h[k] >= config_.min_beam_fraction * typical) table.push_back(lo + (static_cast<double>(k) + 0.5) * bin);
      }
      std::sort(table.begin(), table.end());
      const double next = std::max(config_.min_separation_rad, 0.5 * detail::median_spacing(table));
      if (!(next > separation * 1.05)) break;
      separation = next;
    }
    // Refine each beam to the mean of the points near its peak.
    const double half_window = 0.25 * std::max(detail::median_spacing(table), config_.min_separation_rad);
    for (double& t : table) {
      const auto b = std::lower_bound(sorted.begin(), sorted.end(), t - half_window);
      const auto e = std::upper_bound(sorted.begin(), sorted.end(), t + half_window);
      if (b == e) continue;
      double s = 0.0;
      for (auto it = b; it != e; ++it) s += *it;
      t = s / static_cast<double>(e - b);
    }
    detail::make_strictly_ascending(table);
    d.elevation_beams = table.size();
    if (table.size() > config_.max_beams) {
      d.elevation_fit_fraction = 0.0;
      return table;
    }
    BeamDetection probe;
    probe.elevations_rad = table;
    fit(sorted, probe);
    d.elevation_fit_fraction = probe.fit_fraction;
    return table;
  }

  // Tolerance of the fit: tolerance_rad, at most relative_tolerance x the
  // table's median spacing (a table of dense beams fits anything otherwise).
  [[nodiscard]] double tolerance(const BeamDetection& d) const {
    const double s = detail::median_spacing(d.elevations_rad);
    return s > 0.0 ? std::min(config_.tolerance_rad, config_.relative_tolerance * s) : config_.tolerance_rad;
  }

  // Residual of every point to the nearest beam of d's table.
  void fit(const std::vector<double>& sorted, BeamDetection& d) const {
    d.median_spacing_rad = detail::median_spacing(d.elevations_rad);
    if (d.elevations_rad.empty() || sorted.empty()) return;
    const double tol = tolerance(d);
    std::size_t within = 0;
    double sum2 = 0.0;
    std::size_t k = 0;  // sorted points: walk the table once
    for (const double e : sorted) {
      while (k + 1 < d.elevations_rad.size() &&
             std::abs(d.elevations_rad[k + 1] - e) <= std::abs(d.elevations_rad[k] - e)) {
        ++k;
      }
      const double r = e - d.elevations_rad[k];
      sum2 += r * r;
      if (std::abs(r) <= tol) ++within;
    }
    d.fit_fraction = static_cast<double>(within) / static_cast<double>(sorted.size());
    d.rms_residual_rad = std::sqrt(sum2 / static_cast<double>(sorted.size()));
  }

  // Table from points assigned to rings (per-ring median elevation), and the
  // fit of each point to its own ring. False when fewer than 2 rings.
  bool assigned_table(std::vector<RingSample> samples, BeamDetection& d) const {
    std::sort(samples.begin(), samples.end(), [](const RingSample& a, const RingSample& b) {
      return a.ring != b.ring ? a.ring < b.ring : a.elevation_rad < b.elevation_rad;
    });
    std::vector<double> table;
    std::vector<double> ring_elev;
    std::size_t within = 0;
    double sum2 = 0.0;
    for (std::size_t b = 0; b < samples.size();) {
      std::size_t e = b;
      while (e < samples.size() && samples[e].ring == samples[b].ring) ++e;
      ring_elev.clear();
      for (std::size_t i = b; i < e; ++i) ring_elev.push_back(samples[i].elevation_rad);
      const double m = detail::sorted_median(ring_elev, 0, ring_elev.size());
      table.push_back(m);
      for (const double x : ring_elev) {
        sum2 += (x - m) * (x - m);
        if (std::abs(x - m) <= config_.tolerance_rad) ++within;  // own ring: the absolute tolerance
      }
      b = e;
    }
    if (table.size() < 2 || table.size() > config_.max_beams) return false;
    detail::make_strictly_ascending(table);
    d.elevations_rad = table;
    d.median_spacing_rad = detail::median_spacing(table);
    d.fit_fraction = static_cast<double>(within) / static_cast<double>(samples.size());
    d.rms_residual_rad = std::sqrt(sum2 / static_cast<double>(samples.size()));
    return true;
  }

  Config config_;
  std::size_t scans_ = 0;
  bool all_rings_ = true;
  std::vector<double> elevations_;
  std::vector<std::size_t> scan_begin_;  // first index of each scan's elevations
  std::vector<std::size_t> order_counts_;
  std::vector<RingSample> scan_ring_;
  std::vector<RingSample> order_ring_;
};

/// Detects the beam table of the given scans (BeamDetector over all of them).
inline BeamDetection detect_beams(const std::vector<Scan>& scans, const BeamDetectionConfig& config = {}) {
  BeamDetector detector(config);
  for (const Scan& s : scans) detector.add(s);
  return detector.detect();
}

}  // namespace semlio
