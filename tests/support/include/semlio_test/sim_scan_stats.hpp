#pragma once
// Simple statistics for comparing simulated and real HDL-64E sweeps: points
// per ring (ring inferred from elevation), range histogram, fraction of points
// below -1.3 m (ground), mean intensity.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include <semlio/core/scan.hpp>

namespace semlio_test {

/// Range histogram bin edges [m].
inline constexpr std::array<double, 9> kRangeEdges{0.0, 5.0, 10.0, 20.0, 30.0, 40.0, 60.0, 80.0, 120.0};

struct ScanStats {
  std::size_t points = 0;
  std::array<std::size_t, 64> per_ring{};         // by nearest nominal KITTI beam elevation
  std::array<double, 8> range_fraction{};         // fraction of points per kRangeEdges bin
  double ground_fraction = 0.0;                   // z < -1.3 m
  double mean_intensity = 0.0;
  double median_ring_count = 0.0;                 // median over the rings of per_ring
  std::size_t upper_block = 0;                    // points with elevation above -8.58 deg
};

/// Nominal KITTI HDL-64E beam elevations [deg], ring 0 lowest.
inline std::array<double, 64> kitti_beam_elevations_deg() {
  std::array<double, 64> el{};
  for (int r = 0; r < 32; ++r) el[static_cast<std::size_t>(r)] = -24.9 + (-8.83 + 24.9) * r / 31.0;
  for (int r = 0; r < 32; ++r) el[static_cast<std::size_t>(32 + r)] = -8.33 + (2.0 + 8.33) * r / 31.0;
  return el;
}

inline ScanStats scan_stats(const semlio::Scan& scan) {
  ScanStats s;
  s.points = scan.size();
  const auto beams = kitti_beam_elevations_deg();
  double intensity = 0.0;
  std::size_t ground = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const Eigen::Vector3f& p = scan.points[i];
    const auto x = static_cast<double>(p.x());
    const auto y = static_cast<double>(p.y());
    const auto z = static_cast<double>(p.z());
    const double r = std::sqrt(x * x + y * y + z * z);
    const double el = std::atan2(z, std::hypot(x, y)) * 180.0 / std::numbers::pi;
    std::size_t best = 0;
    for (std::size_t b = 1; b < 64; ++b) {
      if (std::abs(beams[b] - el) < std::abs(beams[best] - el)) best = b;
    }
    ++s.per_ring[best];
    if (el > -8.58) ++s.upper_block;
    for (std::size_t b = 0; b + 1 < kRangeEdges.size(); ++b) {
      if (r >= kRangeEdges[b] && r < kRangeEdges[b + 1]) s.range_fraction[b] += 1.0;
    }
    if (z < -1.3) ++ground;
    if (scan.has_intensity()) intensity += static_cast<double>(scan.intensity[i]);
  }
  const double n = std::max<double>(1.0, static_cast<double>(scan.size()));
  for (double& f : s.range_fraction) f /= n;
  s.ground_fraction = static_cast<double>(ground) / n;
  s.mean_intensity = intensity / n;
  std::array<std::size_t, 64> sorted = s.per_ring;
  std::sort(sorted.begin(), sorted.end());
  s.median_ring_count = 0.5 * static_cast<double>(sorted[31] + sorted[32]);
  return s;
}

/// L1 distance between two range histograms (0 = identical, 2 = disjoint).
inline double range_l1(const ScanStats& a, const ScanStats& b) {
  double d = 0.0;
  for (std::size_t k = 0; k < a.range_fraction.size(); ++k) d += std::abs(a.range_fraction[k] - b.range_fraction[k]);
  return d;
}

}  // namespace semlio_test
