#pragma once
/// \file
/// sensor_msgs/PointCloud2 -> Scan for the field layouts lidar drivers
/// publish, without ROS. The same decoder serves ROS 1 bags, MCAP and rosbag2
/// (their deserialisers fill a PointCloud2Msg, io/ros_msgs.hpp).
///
/// Layouts it is written against (field name: datatype, as each driver
/// registers its PCL point type):
///   - Velodyne (ros-drivers/velodyne, velodyne_pointcloud PointXYZIRT; the
///     layout LIO-SAM expects): x y z f32 (+4 pad), intensity f32, ring u16,
///     time f32 = seconds relative to the header stamp (negative when the
///     stamp is the sweep's end).
///   - Ouster (ouster-lidar/ouster_ros point.h): x y z f32, intensity f32,
///     t u32 = nanoseconds since the header stamp, reflectivity u16, ring u8
///     (older drivers) or u16, ambient u16, range u32; organised clouds
///     (height = beams) with (0,0,0) for no return.
///   - Hesai (HesaiLidar_General_ROS PointXYZIT): intensity f32,
///     timestamp f64 = absolute seconds, ring u16.
///   - Robosense (rslidar_sdk PointXYZIRT): intensity u8 (or f32),
///     ring u16, timestamp f64 = absolute seconds.
///   - Livox (livox_ros_driver CustomMsg points, CustomPoint::offset_time u32
///     = nanoseconds since the message's timebase, as repacked into
///     PointCloud2 by the usual converters); livox_ros_driver2's own
///     PointCloud2 carries timestamp f64 = absolute NANOseconds (handled by
///     the > 1e14 rule of PointCloud2Config::time_mode).
/// PointField has no 64-bit integer datatype (codes 1-8 in ROS 1 and ROS 2),
/// so 64-bit nanosecond stamps arrive as float64 and take the same rule. An
/// old ouster_ros `t` in float32 NANOseconds needs time_mode =
/// kRelativeNanoseconds: kAuto reads float32 as seconds (Velodyne).
///
/// Conventions: each point's absolute time is computed (header stamp +
/// relative time, or the absolute value); `Scan::stamp_s` is the EARLIEST
/// kept point's time and `Scan::times_s` the time since it. Without a time
/// field `stamp_s` is the header stamp and `times_s` stays empty. Points
/// with a non-finite x, y, z (or intensity/time), and points exactly at
/// (0,0,0), are dropped in every field at once and counted in ReadStats.
/// A finite time more than kMaxPointTimeOffset_s from the reference (a
/// corrupt value) is a FormatError.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/io/ros_msgs.hpp>

namespace semlio::io {

/// How the values of the per-point time field are read.
enum class PointTimeMode : std::uint8_t {
  kAuto,                 ///< decide from the datatype and the values (see PointCloud2Config)
  kRelativeSeconds,      ///< seconds since the header stamp
  kRelativeNanoseconds,  ///< nanoseconds since the header stamp
  kAbsoluteSeconds,      ///< seconds since the epoch
  kAbsoluteNanoseconds,  ///< nanoseconds since the epoch
};

/// Largest |time| of a point relative to the cloud's reference (the header
/// stamp, or the first kept point's absolute time) [s]. No sweep lasts 11.6
/// days (the same bound as kAuto's absolute-time rule); a larger offset is a
/// corrupt value, and would not fit the float Scan::times_s (3.4e38 s).
inline constexpr double kMaxPointTimeOffset_s = 1e6;

/// Which fields pointcloud2_to_scan() reads; the first present name of each list wins.
struct PointCloud2Config {
  std::vector<std::string> intensity_fields = {"intensity", "reflectivity"};  ///< any numeric type
  std::vector<std::string> ring_fields = {"ring"};                            ///< any integer type
  std::vector<std::string> time_fields = {"time", "t", "timestamp", "offset_time"};
  /// kAuto: float32 -> relative s; (u)int32 -> relative ns; float64 -> absolute
  /// when the largest value exceeds 1e6 (no sweep lasts 11 days, every epoch
  /// stamp since 1970-01-12 is larger), absolute ns when it exceeds 1e14,
  /// else relative s. Other datatypes need an explicit mode.
  PointTimeMode time_mode = PointTimeMode::kAuto;
  bool drop_zero_points = true;  ///< drop points exactly at (0,0,0) (no return)
};

/// What pointcloud2_to_scan() found in a cloud (datatype 0 = field absent).
/// (Not named CloudLayout: io/bag/ros_writer_msgs.hpp's enum of written
/// layouts has that name in this namespace.)
struct PointCloud2Layout {
  std::uint8_t coordinate_type = 0;    ///< PointFieldType of x, y, z
  std::string intensity_field;         ///< name used for Scan::intensity ("" = none)
  std::uint8_t intensity_type = 0;     ///< its PointFieldType code
  std::string ring_field;              ///< name used for Scan::rings ("" = none)
  std::uint8_t ring_type = 0;          ///< its PointFieldType code
  std::string time_field;              ///< name used for Scan::times_s ("" = none)
  std::uint8_t time_type = 0;          ///< its PointFieldType code
  PointTimeMode time_mode = PointTimeMode::kAuto;  ///< interpretation used (kAuto = no time field)
  double header_minus_earliest_s = 0.0;  ///< header stamp - earliest point time [s] (0 without times)
  std::size_t points_in = 0;           ///< height * width
  std::size_t points_out = 0;          ///< points kept
};

/// Name of a PointFieldType code ("float32", ...; "invalid(N)" otherwise).
inline std::string point_field_type_name(std::uint8_t datatype) {
  switch (datatype) {
    case 1: return "int8";
    case 2: return "uint8";
    case 3: return "int16";
    case 4: return "uint16";
    case 5: return "int32";
    case 6: return "uint32";
    case 7: return "float32";
    case 8: return "float64";
    default: return "invalid(" + std::to_string(datatype) + ")";
  }
}

/// Bytes of one element of a PointFieldType code (0 for an invalid code).
inline constexpr std::size_t point_field_type_size(std::uint8_t datatype) noexcept {
  switch (datatype) {
    case 1:
    case 2: return 1;
    case 3:
    case 4: return 2;
    case 5:
    case 6:
    case 7: return 4;
    case 8: return 8;
    default: return 0;
  }
}

namespace detail::pc2 {

/// Byte-reverses an unsigned integer (std::byteswap is C++23).
template <typename U>
constexpr U byteswap(U v) noexcept {
  U out = 0;
  for (std::size_t i = 0; i < sizeof(U); ++i) {
    out = static_cast<U>((out << 8) | (v & 0xFFu));
    v = static_cast<U>(v >> 8);
  }
  return out;
}

/// Unsigned integer type of N bytes.
template <std::size_t N>
struct UintOf;
template <>
struct UintOf<1> { using type = std::uint8_t; };
template <>
struct UintOf<2> { using type = std::uint16_t; };
template <>
struct UintOf<4> { using type = std::uint32_t; };
template <>
struct UintOf<8> { using type = std::uint64_t; };

/// Loads a T from unaligned bytes, swapping its byte order when `swap`.
template <typename T>
inline T load(const std::uint8_t* p, bool swap) noexcept {
  using U = typename UintOf<sizeof(T)>::type;
  U u;
  std::memcpy(&u, p, sizeof(U));
  if constexpr (sizeof(U) > 1) {
    if (swap) u = byteswap(u);
  }
  return std::bit_cast<T>(u);
}

/// Any numeric field as double (datatype already validated).
inline double load_number(const std::uint8_t* p, std::uint8_t dt, bool swap) noexcept {
  switch (dt) {
    case 1: return load<std::int8_t>(p, swap);
    case 2: return load<std::uint8_t>(p, swap);
    case 3: return load<std::int16_t>(p, swap);
    case 4: return load<std::uint16_t>(p, swap);
    case 5: return load<std::int32_t>(p, swap);
    case 6: return load<std::uint32_t>(p, swap);
    case 7: return static_cast<double>(load<float>(p, swap));
    default: return load<double>(p, swap);
  }
}

/// An integer field as int64 (datatype already validated as integer).
inline std::int64_t load_integer(const std::uint8_t* p, std::uint8_t dt, bool swap) noexcept {
  switch (dt) {
    case 1: return load<std::int8_t>(p, swap);
    case 2: return load<std::uint8_t>(p, swap);
    case 3: return load<std::int16_t>(p, swap);
    case 4: return load<std::uint16_t>(p, swap);
    case 5: return load<std::int32_t>(p, swap);
    default: return load<std::uint32_t>(p, swap);
  }
}

inline bool is_integer_type(std::uint8_t dt) noexcept { return dt >= 1 && dt <= 6; }

/// A used field: byte offset and datatype (datatype 0 = absent).
struct Slot {
  std::size_t offset = 0;
  std::uint8_t type = 0;
  std::string name;
};

/// "PointCloud2 (frame 'f', stamp s): what" -- the decoder does not know the file.
inline std::string where(const PointCloud2Msg& msg, const std::string& what) {
  std::string out = "PointCloud2 (frame '" + msg.frame_id + "', stamp " + std::to_string(msg.stamp_s) + " s): ";
  out += what;
  return out;
}

/// Index of the field named `name`, or npos (size_t(-1)).
inline std::size_t find_field(const PointCloud2Msg& msg, const std::string& name) {
  for (std::size_t i = 0; i < msg.fields.size(); ++i) {
    if (msg.fields[i].name == name) return i;
  }
  return static_cast<std::size_t>(-1);
}

/// Throws FormatError unless the layout is consistent and every read stays in `data`.
inline void validate(const PointCloud2Msg& msg, std::size_t data_size) {
  const auto fail = [&](const std::string& what) { throw FormatError(where(msg, what)); };
  for (std::size_t i = 0; i < msg.fields.size(); ++i) {
    const PointField& f = msg.fields[i];
    const std::size_t size = point_field_type_size(f.datatype);
    if (size == 0) fail("field '" + f.name + "' has unknown datatype " + std::to_string(f.datatype));
    for (std::size_t k = 0; k < i; ++k) {
      if (msg.fields[k].name == f.name) fail("field name '" + f.name + "' appears twice");
    }
    // count 0 is read as 1: some writers leave it unset, and one element is all semlio reads.
    const std::uint64_t end = std::uint64_t{f.offset} + std::uint64_t{size} * std::max<std::uint64_t>(f.count, 1);
    if (end > msg.point_step) {
      fail("field '" + f.name + "' (offset " + std::to_string(f.offset) + ", " + point_field_type_name(f.datatype) +
           " x " + std::to_string(f.count) + ") ends at byte " + std::to_string(end) + ", beyond point_step " +
           std::to_string(msg.point_step));
    }
  }
  const std::uint64_t points = std::uint64_t{msg.height} * msg.width;  // both < 2^32: no overflow
  if (points > std::numeric_limits<std::size_t>::max() / 16) fail("height * width overflows");
  if (points == 0) return;
  const std::uint64_t row_bytes = std::uint64_t{msg.width} * msg.point_step;
  if (row_bytes > msg.row_step) {
    fail("point_step " + std::to_string(msg.point_step) + " * width " + std::to_string(msg.width) + " = " +
         std::to_string(row_bytes) + " exceeds row_step " + std::to_string(msg.row_step));
  }
  const std::uint64_t total = std::uint64_t{msg.height} * msg.row_step;
  if (total > data_size) {
    fail("data holds " + std::to_string(data_size) + " bytes, shorter than height " +
         std::to_string(msg.height) + " * row_step " + std::to_string(msg.row_step) + " = " + std::to_string(total));
  }
}

/// Picks the first present name of `names`; checks its datatype with `ok`.
template <typename Ok>
Slot pick(const PointCloud2Msg& msg, const std::vector<std::string>& names, const char* role, Ok ok,
          const char* expected) {
  for (const std::string& n : names) {
    const std::size_t i = find_field(msg, n);
    if (i == static_cast<std::size_t>(-1)) continue;
    const PointField& f = msg.fields[i];
    if (!ok(f.datatype)) {
      throw FormatError(where(msg, std::string(role) + " field '" + n + "' has datatype " +
                                       point_field_type_name(f.datatype) + ", expected " + expected));
    }
    return Slot{f.offset, f.datatype, n};
  }
  return Slot{};
}

/// The decision of PointTimeMode::kAuto for a time field (see PointCloud2Config).
inline PointTimeMode auto_time_mode(const PointCloud2Msg& msg, const std::uint8_t* data, const Slot& t, bool swap) {
  switch (t.type) {
    case 7: return PointTimeMode::kRelativeSeconds;
    case 5:
    case 6: return PointTimeMode::kRelativeNanoseconds;
    case 8: break;
    default:
      throw FormatError(where(msg, "time field '" + t.name + "' has datatype " + point_field_type_name(t.type) +
                                       ": too narrow for a time (expected float32, float64 or a 32/64-bit integer)"));
  }
  // float64: absolute when the largest finite value exceeds 1e6 (relative
  // sweep times are below a second; epoch stamps are ~1.7e9 s or ~1.7e18 ns).
  double largest = 0.0;
  // Width 0: no points, whatever the height says (up to 2^32 - 1 empty rows
  // to walk, and rows validate() did not check against the data).
  const std::size_t rows = msg.width == 0 ? 0 : msg.height;
  for (std::size_t r = 0; r < rows; ++r) {
    const std::uint8_t* row = data + r * std::size_t{msg.row_step};
    for (std::size_t c = 0; c < msg.width; ++c) {
      const double v = load<double>(row + c * std::size_t{msg.point_step} + t.offset, swap);
      if (std::isfinite(v)) largest = std::max(largest, std::abs(v));
    }
  }
  if (largest > 1e14) return PointTimeMode::kAbsoluteNanoseconds;
  if (largest > 1e6) return PointTimeMode::kAbsoluteSeconds;
  return PointTimeMode::kRelativeSeconds;
}

/// Seconds of an epoch time in ns, as double(sec) + double(nsec) / 1e9.
inline double ns_to_stamp_s(std::int64_t ns) noexcept {
  std::int64_t sec = ns / 1'000'000'000;
  std::int64_t nsec = ns % 1'000'000'000;
  if (nsec < 0) {
    nsec += 1'000'000'000;
    --sec;
  }
  return static_cast<double>(sec) + static_cast<double>(nsec) / 1e9;
}

}  // namespace detail::pc2

/// Decodes the cloud whose layout `msg` describes and whose packed points are
/// the `data_size` bytes at `data` (msg.data is not read), into `out`: lets a
/// deserialiser decode straight from the message bytes without copying them
/// into PointCloud2Msg::data (one 1.9 MB copy per 120k-point scan). Same
/// conventions and errors as pointcloud2_to_scan().
inline void pointcloud2_data_to_scan(const PointCloud2Msg& msg, const std::uint8_t* data, std::size_t data_size,
                                     Scan& out, const PointCloud2Config& config = {},
                                     PointCloud2Layout* layout = nullptr, ReadStats* stats = nullptr) {
  using namespace detail::pc2;
  validate(msg, data_size);
  out.clear();
  const bool swap = msg.is_bigendian != (std::endian::native == std::endian::big);

  // Coordinates: x, y, z of one floating type.
  Slot xyz[3];
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    const std::size_t i = find_field(msg, names[a]);
    if (i == static_cast<std::size_t>(-1)) throw FormatError(where(msg, std::string("has no '") + names[a] + "' field"));
    xyz[a] = Slot{msg.fields[i].offset, msg.fields[i].datatype, names[a]};
    if (xyz[a].type != 7 && xyz[a].type != 8) {
      throw FormatError(where(msg, std::string("field '") + names[a] + "' has datatype " +
                                       point_field_type_name(xyz[a].type) + ", expected float32 or float64"));
    }
  }
  if (xyz[1].type != xyz[0].type || xyz[2].type != xyz[0].type) {
    throw FormatError(where(msg, "fields x, y, z have different datatypes"));
  }
  const Slot inten = pick(msg, config.intensity_fields, "intensity", [](std::uint8_t) { return true; }, "a number");
  const Slot ring = pick(msg, config.ring_fields, "ring", is_integer_type, "an integer type of at most 32 bits");
  Slot time = pick(msg, config.time_fields, "time", [](std::uint8_t) { return true; }, "a number");

  PointTimeMode mode = config.time_mode;
  if (time.type != 0 && mode == PointTimeMode::kAuto) mode = auto_time_mode(msg, data, time, swap);
  if (time.type == 0) mode = PointTimeMode::kAuto;
  const bool absolute = mode == PointTimeMode::kAbsoluteSeconds || mode == PointTimeMode::kAbsoluteNanoseconds;
  const bool nanoseconds = mode == PointTimeMode::kRelativeNanoseconds || mode == PointTimeMode::kAbsoluteNanoseconds;

  const std::size_t n = std::size_t{msg.height} * msg.width;
  out.points.resize(n);
  if (inten.type != 0) out.intensity.resize(n);
  if (ring.type != 0) out.rings.resize(n);
  if (time.type != 0) out.times_s.resize(n);
  // Per-point times are kept relative to `ref_s` while decoding, so no
  // precision is lost to the ~1.7e9 s magnitude of epoch stamps: the header
  // stamp for relative times, the first kept point's value for absolute ones.
  double ref_s = msg.stamp_s;
  double ref_value = 0.0;  // absolute: raw value of the reference point
  bool have_ref = !absolute;
  double min_rel = std::numeric_limits<double>::infinity();

  std::size_t kept = 0;
  std::size_t nonfinite = 0;
  std::size_t zero = 0;
  const std::size_t ox = xyz[0].offset, oy = xyz[1].offset, oz = xyz[2].offset;
  // The loop is compiled per coordinate type, byte order and float32-or-other
  // intensity, so the common layouts (every driver above: float32 x y z
  // intensity, host order) read their fields without per-point dispatch.
  // Time and ring keep a runtime switch: their types vary by driver.
  const auto loop = [&]<typename Coord, bool Swap, int InT>() {
    // Locals, not captured references: with references GCC reloaded the
    // steps, offsets and counters from memory at every point (perf annotate).
    // What remains is bound by memory traffic: ~1.9 MB read + written per
    // 120k-point scan.
    const std::uint8_t* const base = data;
    const std::size_t height = msg.height, width = msg.width;
    const std::size_t row_step = msg.row_step, point_step = msg.point_step;
    const std::size_t oi = inten.offset, ot = time.offset, orr = ring.offset;
    const std::uint8_t time_type = time.type, ring_type = ring.type;
    const bool drop_zero = config.drop_zero_points;
    Point3f* const pts = out.points.data();
    float* const inten_out = out.intensity.data();
    std::uint16_t* const ring_out = out.rings.data();
    float* const time_out = out.times_s.data();
    std::size_t k = 0, bad = 0, zeros = 0;
    double lo = min_rel;
    for (std::size_t r = 0; r < height; ++r) {
      const std::uint8_t* row = base + r * row_step;
      for (std::size_t c = 0; c < width; ++c) {
        const std::uint8_t* p = row + c * point_step;
        const auto x = static_cast<float>(load<Coord>(p + ox, Swap));
        const auto y = static_cast<float>(load<Coord>(p + oy, Swap));
        const auto z = static_cast<float>(load<Coord>(p + oz, Swap));
        // A float64 coordinate beyond float's range becomes Inf here and is dropped as non-finite.
        if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
          ++bad;
          continue;
        }
        if (drop_zero && x == 0.0F && y == 0.0F && z == 0.0F) {
          ++zeros;
          continue;
        }
        float intensity = 0.0F;
        if constexpr (InT != 0) {
          if constexpr (InT == 7) {
            intensity = load<float>(p + oi, Swap);
          } else {
            intensity = static_cast<float>(load_number(p + oi, inten.type, Swap));
          }
          if (!std::isfinite(intensity)) {
            ++bad;
            continue;
          }
        }
        double rel = 0.0;
        if (time_type != 0) {
          const double v = load_number(p + ot, time_type, Swap);
          if (!std::isfinite(v)) {
            ++bad;
            continue;
          }
          if (absolute && !have_ref) {
            // int64 holds epoch ns until 2262; a larger value is not a time.
            if (nanoseconds && !(std::abs(v) < 9.2e18)) {
              throw FormatError(where(msg, "time field '" + time.name + "' holds " + std::to_string(v) +
                                               " ns at point " + std::to_string(r * msg.width + c) +
                                               ", not an epoch time"));
            }
            ref_value = v;
            // The reference as a stamp: ns values split into sec + nsec first.
            ref_s = nanoseconds ? ns_to_stamp_s(static_cast<std::int64_t>(v)) : v;
            have_ref = true;
          }
          rel = absolute ? v - ref_value : v;
          if (nanoseconds) rel *= 1e-9;
          if (!(std::abs(rel) <= kMaxPointTimeOffset_s)) {
            throw FormatError(where(msg, "time field '" + time.name + "' holds " + std::to_string(v) + " at point " +
                                             std::to_string(r * msg.width + c) + ", " + std::to_string(rel) +
                                             " s from the cloud's reference time (limit " +
                                             std::to_string(kMaxPointTimeOffset_s) + " s)"));
          }
        }
        std::uint16_t ring_value = 0;
        if (ring_type != 0) {
          const std::int64_t rv = load_integer(p + orr, ring_type, Swap);
          if (rv < 0 || rv > std::numeric_limits<std::uint16_t>::max()) {
            throw FormatError(where(msg, "ring field '" + ring.name + "' holds " + std::to_string(rv) + " at point " +
                                             std::to_string(r * msg.width + c) + " (outside 0..65535)"));
          }
          ring_value = static_cast<std::uint16_t>(rv);
        }
        pts[k] = Point3f(x, y, z);
        if constexpr (InT != 0) inten_out[k] = intensity;
        if (ring_type != 0) ring_out[k] = ring_value;
        if (time_type != 0) {
          // Relative to ref_s, in float: |rel| is a sweep's length, so float's
          // 24 bits give ~10 ns; the subtraction of the minimum below is exact
          // enough for deskewing (it is re-rounded once).
          time_out[k] = static_cast<float>(rel);
          lo = std::min(lo, rel);
        }
        ++k;
      }
    }
    kept = k;
    nonfinite = bad;
    zero = zeros;
    min_rel = lo;
  };
  const auto by_intensity = [&]<typename Coord, bool Swap>() {
    if (inten.type == 0) {
      loop.template operator()<Coord, Swap, 0>();
    } else if (inten.type == 7) {
      loop.template operator()<Coord, Swap, 7>();
    } else {
      loop.template operator()<Coord, Swap, 1>();
    }
  };
  // An empty cloud skips the loop: with width 0 its height may still be
  // 2^32 - 1 (a corrupt message), rows of nothing to walk for seconds.
  if (n == 0) {
  } else if (xyz[0].type == 8) {
    if (swap) {
      by_intensity.template operator()<double, true>();
    } else {
      by_intensity.template operator()<double, false>();
    }
  } else if (swap) {
    by_intensity.template operator()<float, true>();
  } else {
    by_intensity.template operator()<float, false>();
  }
  out.points.resize(kept);
  if (inten.type != 0) out.intensity.resize(kept);
  if (ring.type != 0) out.rings.resize(kept);
  out.stamp_s = msg.stamp_s;
  if (time.type != 0) {
    out.times_s.resize(kept);
    if (kept > 0) {
      const float min_f = static_cast<float>(min_rel);
      for (float& t : out.times_s) t = static_cast<float>(static_cast<double>(t) - static_cast<double>(min_f));
      out.stamp_s = ref_s + static_cast<double>(min_f);
    }
  }
  if (stats != nullptr) {
    stats->dropped_nonfinite += nonfinite;
    stats->dropped_zero += zero;
  }
  if (layout != nullptr) {
    layout->coordinate_type = xyz[0].type;
    layout->intensity_field = inten.name;
    layout->intensity_type = inten.type;
    layout->ring_field = ring.name;
    layout->ring_type = ring.type;
    layout->time_field = time.name;
    layout->time_type = time.type;
    layout->time_mode = mode;
    layout->header_minus_earliest_s = time.type != 0 && kept > 0 ? msg.stamp_s - out.stamp_s : 0.0;
    layout->points_in = n;
    layout->points_out = kept;
  }
}

/// Decodes `msg` into `out` (reusing its capacity); see the file comment for
/// the conventions. Throws FormatError on any inconsistency in the message.
/// `layout` (optional) receives what was found; `stats` (optional) counts the
/// dropped points. Thread-safe for distinct outputs.
inline void pointcloud2_to_scan(const PointCloud2Msg& msg, Scan& out, const PointCloud2Config& config = {},
                                PointCloud2Layout* layout = nullptr, ReadStats* stats = nullptr) {
  pointcloud2_data_to_scan(msg, msg.data.data(), msg.data.size(), out, config, layout, stats);
}

/// Decodes `msg` into a new Scan; see the overload above.
inline Scan pointcloud2_to_scan(const PointCloud2Msg& msg, const PointCloud2Config& config = {},
                                PointCloud2Layout* layout = nullptr, ReadStats* stats = nullptr) {
  Scan scan;
  pointcloud2_to_scan(msg, scan, config, layout, stats);
  return scan;
}

}  // namespace semlio::io
