#pragma once
// Fuzz harness bodies for the folder logic of the scan sources: a folder of
// PCD / PLY / .bin scans (io/scan_folder.hpp: plan_scan_folder,
// parse_scan_folder_ground_truth) and a KITTI raw drive
// (io/kitti_raw.hpp: plan_kitti_raw_drive). The per-file parsers have their
// own harnesses (harnesses.hpp); these fuzz what the readers decide from the
// file names and the side files: frame order, stamps, missing frames, the
// pairing with times.txt / poses.txt / OXTS packets. The readers run the same
// plan functions on what they list and read, so no file is written here.
//
// Input: parts separated by '|' bytes; a name list is one name per line.
// An empty or absent part is a file (or folder) that does not exist.

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/kitti_raw.hpp>
#include <semlio/io/scan_folder.hpp>
#include <semlio/lie/se3.hpp>

#include "fuzz_support.hpp"

namespace semlio_fuzz {

namespace folders_detail {

/// The input split at '|' (at least one part, possibly empty).
inline std::vector<std::string_view> split_parts(std::string_view text) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t bar = text.find('|', start);
    parts.push_back(text.substr(start, bar == std::string_view::npos ? std::string_view::npos : bar - start));
    if (bar == std::string_view::npos) break;
    start = bar + 1;
  }
  return parts;
}

/// Part i, nullopt when absent or empty.
inline std::optional<std::string_view> part(const std::vector<std::string_view>& parts, std::size_t i) {
  if (i >= parts.size() || parts[i].empty()) return std::nullopt;
  return parts[i];
}

/// The lines of a name list ('\r' kept: a name may hold any byte but '/').
inline std::vector<std::string> names_of(std::string_view list) {
  std::vector<std::string> names;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t nl = list.find('\n', start);
    const std::string_view name = list.substr(start, nl == std::string_view::npos ? std::string_view::npos : nl - start);
    if (!name.empty()) names.emplace_back(name);
    if (nl == std::string_view::npos) break;
    start = nl + 1;
  }
  return names;
}

/// True when `name` is a scan file of the folder rules (scan extension, not hidden).
inline bool is_scan_name(const std::string& name) {
  if (name.empty() || name.front() == '.') return false;
  const std::string ext = semlio::io::detail::lower_extension(std::filesystem::path(name));
  return ext == ".pcd" || ext == ".ply" || ext == ".bin";
}

}  // namespace folders_detail

/// A folder of scans, from memory. Parts: the file names (one per line),
/// times.txt, poses.txt. Invariants after a successful plan: one frame per
/// scan name and each name once, all of the folder's one format, frames in
/// strictly increasing name-number order, one finite stamp per frame, never
/// decreasing, the source named consistently (times.txt when given); ground
/// truth, when it parses, holds one proper pose per frame.
inline int fuzz_scan_folder(const std::uint8_t* data, std::size_t size) {
  namespace io = semlio::io;
  namespace fd = folders_detail;
  const std::vector<std::string_view> parts = fd::split_parts(as_text(data, size));
  const std::vector<std::string> names = fd::names_of(parts[0]);
  const std::optional<std::string_view> times = fd::part(parts, 1);
  io::ScanFolderPlan plan;
  try {
    plan = io::plan_scan_folder(names, times, "folder");
  } catch (const semlio::Error&) {
    return 0;
  }
  std::multiset<std::string> scan_names;
  for (const std::string& n : names) {
    if (fd::is_scan_name(n)) scan_names.insert(n);
  }
  check(!plan.files.empty());
  check(plan.files.size() == scan_names.size());  // one frame per scan file, none left out
  check(plan.stamps.size() == plan.files.size());
  const char* ext = plan.format == io::ScanFileFormat::pcd   ? ".pcd"
                    : plan.format == io::ScanFileFormat::ply ? ".ply"
                                                             : ".bin";
  std::optional<io::detail::ScanNameNumber> previous;
  for (std::size_t i = 0; i < plan.files.size(); ++i) {
    const std::string& f = plan.files[i];
    check(scan_names.count(f) == 1);  // a listed name, listed once
    check(io::detail::lower_extension(std::filesystem::path(f)) == ext);
    const auto number = io::detail::scan_name_number(std::filesystem::path(f).stem().string());
    check(number.has_value());
    if (previous) check(io::detail::compare_numbers(*previous, *number) < 0);  // strictly ordered
    previous = number;
    check(std::isfinite(plan.stamps[i]));
    if (i > 0) check(plan.stamps[i] >= plan.stamps[i - 1]);
  }
  check((plan.stamp_source == io::ScanStampSource::times_file) == times.has_value());
  if (const auto poses = fd::part(parts, 2)) {
    try {
      const std::vector<semlio::SE3d> gt = io::parse_scan_folder_ground_truth(*poses, "poses.txt", plan.files.size());
      check(gt.size() == plan.files.size());
      for (const semlio::SE3d& T : gt) {
        // harnesses.hpp's check_pose (this header comes before it).
        const Eigen::Matrix3d R = T.so3().matrix();
        check(T.translation().allFinite() && R.allFinite() && R.determinant() > 0.0);
        check((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6);
      }
    } catch (const semlio::Error&) {
    }
  }
  return 0;
}

/// A KITTI raw drive, from memory. Parts: velodyne_points/timestamps.txt,
/// timestamps_start.txt, the names in velodyne_points/data/ (one per line),
/// oxts/timestamps.txt, the names in oxts/data/. Invariants after a
/// successful plan: frames 0 .. highest scan number, each present frame's
/// stem its own number, the missing count those without a file, no more
/// frames than timestamps lines; one finite stamp per frame, never
/// decreasing, interpolated exactly where the line has no stamp; a positive
/// finite period; OXTS stamps finite and non-decreasing, and the OXTS minus
/// scan offset finite wherever both lines carry a stamp (fewer scans than
/// packets, or the reverse, included).
inline int fuzz_kitti_raw_drive(const std::uint8_t* data, std::size_t size) {
  namespace io = semlio::io;
  namespace fd = folders_detail;
  const std::vector<std::string_view> parts = fd::split_parts(as_text(data, size));
  io::KittiRawDriveListing in;
  in.timestamps = parts[0];
  in.timestamps_start = fd::part(parts, 1);
  if (const auto scans = fd::part(parts, 2)) in.scan_names = fd::names_of(*scans);
  in.oxts_timestamps = fd::part(parts, 3);
  if (const auto packets = fd::part(parts, 4)) in.oxts_names = fd::names_of(*packets);
  io::KittiRawDrivePlan plan;
  try {
    plan = io::plan_kitti_raw_drive(in, "drive");
  } catch (const semlio::Error&) {
    return 0;
  }
  const std::size_t n = plan.stems.size();
  check(n >= 1 && n <= plan.middle_lines.size());
  check(plan.stamps.size() == n && plan.interpolated.size() == n);
  check(plan.start_lines.empty() == !in.timestamps_start.has_value());
  if (!plan.start_lines.empty()) check(plan.start_lines.size() == plan.middle_lines.size());
  check(!plan.stems.back().empty());  // the highest number is a present file
  std::size_t missing = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (plan.stems[i].empty()) {
      ++missing;
    } else {
      const auto k = semlio::io::detail::to_int(plan.stems[i]);
      check(k.has_value() && *k >= 0 && static_cast<std::uint64_t>(*k) == i);
    }
    check(std::isfinite(plan.stamps[i]));
    if (i > 0) check(plan.stamps[i] >= plan.stamps[i - 1]);
    const bool stamped =
        (!plan.start_lines.empty() && plan.start_lines[i].has_value()) || plan.middle_lines[i].has_value();
    check(plan.interpolated[i] == !stamped);
  }
  check(missing == plan.missing);
  check(std::isfinite(plan.period_s) && plan.period_s > 0.0);
  std::optional<double> last;
  for (const auto& t : plan.oxts_lines) {
    if (!t) continue;
    check(std::isfinite(*t));
    if (last) check(*t >= *last);
    last = t;
  }
  for (std::size_t i = 0; i < n && i < plan.oxts_lines.size(); ++i) {
    if (plan.middle_lines[i] && plan.oxts_lines[i]) check(std::isfinite(*plan.oxts_lines[i] - *plan.middle_lines[i]));
  }
  return 0;
}

}  // namespace semlio_fuzz
