#pragma once
/// \file
/// Internal: proleptic Gregorian calendar arithmetic (days since 1970-01-01)
/// for the OXTS date-time strings; exact integer maths, no time zones.

#include <cstdint>
#include <string_view>

namespace semlio::io::detail {

/// Days since 1970-01-01 of a proleptic Gregorian date (exact integer arithmetic).
constexpr std::int64_t days_from_civil(std::int64_t y, int m, int d) noexcept {
  y -= m <= 2 ? 1 : 0;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const std::int64_t yoe = y - era * 400;                                    // [0, 399]
  const std::int64_t doy = (153 * (m > 2 ? m - 3 : m + 9) + 2) / 5 + d - 1;  // [0, 365]
  const std::int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;            // [0, 146096]
  return era * 146097 + doe - 719468;
}

/// Calendar date of a day count since 1970-01-01 (inverse of days_from_civil).
struct CivilDate {
  std::int64_t year;
  int month;
  int day;
};

/// Inverse of days_from_civil.
constexpr CivilDate civil_from_days(std::int64_t z) noexcept {
  z += 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const std::int64_t doe = z - era * 146097;
  const std::int64_t yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const std::int64_t doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const std::int64_t mp = (5 * doy + 2) / 153;
  const auto day = static_cast<int>(doy - (153 * mp + 2) / 5 + 1);
  const auto month = static_cast<int>(mp < 10 ? mp + 3 : mp - 9);
  return {yoe + era * 400 + (month <= 2 ? 1 : 0), month, day};
}

/// True for Gregorian leap years.
inline bool is_leap_year(std::int64_t y) noexcept { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

/// Days of month m (1-12) in year y.
inline int days_in_month(std::int64_t y, int m) noexcept {
  constexpr int kDays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return (m == 2 && is_leap_year(y)) ? 29 : kDays[m - 1];
}

/// True when `s` is non-empty and holds only the digits 0-9 (any length).
inline bool all_digits(std::string_view s) noexcept {
  if (s.empty()) return false;
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

/// Parses a fixed-width unsigned decimal field; -1 when not all digits or
/// longer than 18 digits (the most an int64 holds without overflow, so no
/// input can make the accumulation undefined behaviour).
inline std::int64_t digits_value(std::string_view s) noexcept {
  if (!all_digits(s) || s.size() > 18) return -1;
  std::int64_t v = 0;
  for (const char c : s) v = v * 10 + (c - '0');
  return v;
}

}  // namespace semlio::io::detail
