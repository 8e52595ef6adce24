#pragma once
/// \file
/// Which named sensor profile (sensor_profiles.hpp) a detected beam table
/// (beam_detection.hpp) belongs to, so `--sensor auto` on a cloud without a
/// ring field gets the sensor's ranges, stamp meaning, spin and the beams the
/// first scans did not see, instead of generic defaults.
///
/// Two ways to match, by how many beams were detected:
/// - as many as the profile has: beam i against the profile's beam i, every
///   one within `index_tolerance_fov_fraction` of the profile's vertical
///   field of view. A real unit's table is not the datasheet's (the BALM OS0
///   recording: spacing alternating 1.3 / 1.7 deg around the nominal 1.43,
///   up to 0.98 deg from the nominal angle, 1.1 % of its 90 deg; the
///   simulator's HDL-64E lower block ends at the datasheet's -24.9 deg where
///   SensorModel::hdl64e() ends at -24.33: 2.1 % of 26.9 deg), while two
///   profiles with the same beam count differ by 18 % of the field of view
///   or more at some beam (hdl32e and os1-32 at the lowest beam, pandar64 and
///   hdl64e at the second), so 5 % separates them with margin both ways.
/// - fewer (the upper beams of a 90 deg OS0 see sky in a street; those beams
///   exist all the same): every detected beam near a distinct beam of the
///   profile's table -- within `spacing_fraction` of that beam's local
///   spacing (its smaller gap to a neighbour), at most `max_tolerance_rad` --
///   and at least `min_matched_fraction` of the profile's beams seen. A
///   detected beam with no counterpart rules the profile out.
/// More detected beams than the profile has: not that profile. Of the
/// profiles that match, the one whose beams are explained best (highest
/// matched fraction, then lowest RMS) wins; the fraction decides first so
/// that a VLP-16's -15 .. +15 by 2 table is a VLP-16 (16 of 16) and not half
/// a PandarXT-32 (16 of 32, the same angles).
///

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/features/beam_detection.hpp>
#include <semlio/features/sensor_profiles.hpp>

namespace semlio {

/// Settings of match_sensor_profile() (defaults: see the file comment).
struct ProfileMatchConfig {
  double index_tolerance_fov_fraction = 0.05;                ///< same count: |beam i - profile beam i| within this x FOV
  double spacing_fraction = 0.3;                             ///< fewer: tolerance as a fraction of the local spacing
  double max_tolerance_rad = 0.5 * std::numbers::pi / 180.0;  ///< fewer: tolerance at most this [rad]
  double min_matched_fraction = 0.6;                         ///< fewer: of the profile's beams the detected ones must be

  /// Throws ConfigError naming the bad field and value.
  void validate() const {
    const auto fail = [](const char* field, double v) {
      throw ConfigError(std::string("ProfileMatchConfig.") + field + " is invalid: " + std::to_string(v));
    };
    if (!(index_tolerance_fov_fraction > 0.0 && index_tolerance_fov_fraction < 1.0)) {
      fail("index_tolerance_fov_fraction", index_tolerance_fov_fraction);
    }
    if (!(spacing_fraction > 0.0 && spacing_fraction < 0.5)) fail("spacing_fraction", spacing_fraction);
    if (!(max_tolerance_rad > 0.0) || !std::isfinite(max_tolerance_rad)) fail("max_tolerance_rad", max_tolerance_rad);
    if (!(min_matched_fraction > 0.0 && min_matched_fraction <= 1.0)) {
      fail("min_matched_fraction", min_matched_fraction);
    }
  }
};

/// How a detected table compares with one profile's table.
struct ProfileMatch {
  std::string profile;                  ///< the profile's name
  bool matches = false;                 ///< every detected beam has a distinct counterpart, enough of them
  std::size_t detected_beams = 0;       ///< beams of the detected table
  std::size_t profile_beams = 0;        ///< beams of the profile's table
  std::size_t matched = 0;              ///< detected beams with a counterpart
  double rms_rad = 0.0;                 ///< RMS detected - profile elevation over the matched beams [rad]
  double max_rad = 0.0;                 ///< largest |detected - profile| over the matched beams [rad]
  std::vector<std::size_t> counterpart;  ///< profile beam of each detected beam (profile_beams = none)

  /// Fraction of the profile's beams the detected table explains.
  [[nodiscard]] double matched_fraction() const noexcept {
    return profile_beams == 0 ? 0.0 : static_cast<double>(matched) / static_cast<double>(profile_beams);
  }

  /// The profile's table with every matched beam moved to its detected
  /// elevation: the unit's own angles where the data showed them, the
  /// datasheet's elsewhere. Ascending because no beam moves by half a
  /// spacing. Throws ValueError when the match does not hold.
  [[nodiscard]] SensorModel completed_table(const SensorModel& profile_table,
                                            const std::vector<double>& detected_rad) const {
    if (!matches || counterpart.size() != detected_rad.size() || profile_table.beams() != profile_beams) {
      throw ValueError("ProfileMatch::completed_table: the detected table does not match profile '" + profile + "'");
    }
    SensorModel out = profile_table;
    for (std::size_t i = 0; i < detected_rad.size(); ++i) out.elevations_rad[counterpart[i]] = detected_rad[i];
    detail::make_strictly_ascending(out.elevations_rad);
    return out;
  }
};

/// Compares an ascending detected table with `profile`'s (file comment).
inline ProfileMatch match_profile(const std::vector<double>& detected_rad, const SensorProfile& profile,
                                  const ProfileMatchConfig& config = {}) {
  config.validate();
  const std::vector<double>& table = profile.beams.elevations_rad;
  ProfileMatch m;
  m.profile = profile.name;
  m.detected_beams = detected_rad.size();
  m.profile_beams = table.size();
  m.counterpart.assign(detected_rad.size(), table.size());
  if (detected_rad.empty() || table.size() < 2 || detected_rad.size() > table.size()) return m;
  if (detected_rad.size() == table.size()) {
    const double tol = config.index_tolerance_fov_fraction * (table.back() - table.front());
    double sum2 = 0.0;
    for (std::size_t i = 0; i < table.size(); ++i) {
      const double r = detected_rad[i] - table[i];
      if (!(std::abs(r) <= tol)) return m;
      sum2 += r * r;
      m.max_rad = std::max(m.max_rad, std::abs(r));
      m.counterpart[i] = i;
    }
    m.matched = table.size();
    m.rms_rad = std::sqrt(sum2 / static_cast<double>(m.matched));
    m.matches = true;
    return m;
  }
  // Fewer beams. Both tables ascend and no tolerance reaches half a spacing, so the
  // nearest profile beam of each detected beam is its only candidate and a
  // second detected beam on the same profile beam means no match.
  double sum2 = 0.0;
  std::size_t j = 0;
  std::size_t last = table.size();
  for (std::size_t i = 0; i < detected_rad.size(); ++i) {
    const double e = detected_rad[i];
    while (j + 1 < table.size() && std::abs(table[j + 1] - e) <= std::abs(table[j] - e)) ++j;
    const double below = j > 0 ? table[j] - table[j - 1] : std::numeric_limits<double>::infinity();
    const double above = j + 1 < table.size() ? table[j + 1] - table[j] : std::numeric_limits<double>::infinity();
    const double tol = std::min(config.max_tolerance_rad, config.spacing_fraction * std::min(below, above));
    const double r = e - table[j];
    if (!(std::abs(r) <= tol) || j == last) return m;  // no counterpart, or a taken one
    m.counterpart[i] = j;
    last = j;
    ++m.matched;
    sum2 += r * r;
    m.max_rad = std::max(m.max_rad, std::abs(r));
  }
  m.rms_rad = std::sqrt(sum2 / static_cast<double>(m.matched));
  m.matches = m.matched_fraction() >= config.min_matched_fraction;
  return m;
}

/// The named profile that explains a detected table best, if any matches
/// (file comment). Ties in matched fraction go to the lower RMS, then to the
/// earlier name of sensor_profile_names() (deterministic).
inline std::optional<ProfileMatch> match_sensor_profile(const std::vector<double>& detected_rad,
                                                        const ProfileMatchConfig& config = {}) {
  std::optional<ProfileMatch> best;
  for (const std::string& name : sensor_profile_names()) {
    ProfileMatch m = match_profile(detected_rad, sensor_profile(name), config);
    if (!m.matches) continue;
    const bool better = !best || m.matched_fraction() > best->matched_fraction() ||
                        (m.matched_fraction() == best->matched_fraction() && m.rms_rad < best->rms_rad);
    if (better) best = std::move(m);
  }
  return best;
}

}  // namespace semlio
