#pragma once
/// \file
/// RangeProjection: a scan as RangeNet++'s spherical range image and back.
///
/// Forward (RangeNet++ `laserscan.py`, `do_range_projection`): a point at
/// range r = |p| gets yaw = -atan2(y, x) and pitch = asin(z / r);
///   column = floor(0.5 (yaw / pi + 1) W),
///   row    = floor((1 - (pitch - fov_down) / (fov_up - fov_down)) H),
/// both clamped into the image (points above or below the field of view land
/// on the top or bottom row, as RangeNet++ clamps them). Column 0 faces
/// backwards (-x) and columns grow clockwise seen from above: +y (left) is
/// column W/4, +x (ahead) W/2, -y (right) 3W/4. The nearest point wins a
/// pixel; of two at the same range the lower index (RangeNet++ sorts by
/// range with an unstable sort, so its ties are arbitrary).
/// Each pixel's input channels (range, x, y, z, intensity in the configured
/// order) are normalised by the channel's mean and standard deviation; empty
/// pixels hold 0 in every channel (RangeNet++ multiplies by the mask after
/// normalising).
///
/// Backward (RangeNet++ `postproc/KNN.py`): every point, including points
/// hidden behind a nearer one in their pixel, takes the label voted by the k
/// nearest-in-range of the `search_px` x `search_px` pixels around its
/// pixel. The distance to a neighbour pixel is |r_pixel - r_point| (1 - g),
/// g the normalised Gaussian kernel (sigma_px) at the neighbour's offset; the
/// centre pixel counts with the point's own range (distance 0, so a point
/// always votes for its own pixel's label). Pixels outside the image count as
/// range 0 and unlabeled (RangeNet++'s zero padding: no wrap-around at the
/// image's left and right edges); empty pixels never vote. Of the k nearest,
/// only those within `cutoff_m` vote, and unlabeled pixels never do. The
/// class with the most votes wins, a tie goes to the lowest class id.
/// Deviations from RangeNet++, both for determinism or sense: k-nearest ties
/// go to the earlier pixel of the window in row-major order (torch.topk's
/// order is unspecified), and a point with no vote is kUnlabeled (RangeNet++
/// then returns class 1 by accident of its argmax over an all-zero histogram).
///
/// Computed in double from the float points. Deterministic; after the first
/// scans no allocation as long as scans do not grow. Not thread-safe (the
/// buffers are state); copies are independent.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>

namespace semlio {

/// Size and vertical field of view of a range image (defaults: RangeNet++'s
/// KITTI HDL-64E card, 64 x 2048 pixels, +3 deg / -25 deg).
struct RangeImageConfig {
  int height_px = 64;                                       ///< rows (one per beam for a 64-beam lidar)
  int width_px = 2048;                                      ///< columns over the full 360 deg
  double fov_up_rad = 3.0 * std::numbers::pi / 180.0;       ///< elevation of the top edge of row 0 [rad]
  double fov_down_rad = -25.0 * std::numbers::pi / 180.0;   ///< elevation of the bottom edge of the last row [rad]
};

/// One input channel of the range image.
enum class RangeChannel : std::uint8_t {
  kRange = 0,      ///< |p| [m]
  kX = 1,          ///< x in the sensor frame [m]
  kY = 2,          ///< y in the sensor frame [m]
  kZ = 3,          ///< z in the sensor frame [m]
  kIntensity = 4,  ///< reflectance as the scan holds it
};

/// The channel's name as model cards spell it: range, x, y, z, intensity.
constexpr std::string_view range_channel_name(RangeChannel c) noexcept {
  switch (c) {
    case RangeChannel::kRange: return "range";
    case RangeChannel::kX: return "x";
    case RangeChannel::kY: return "y";
    case RangeChannel::kZ: return "z";
    case RangeChannel::kIntensity: return "intensity";
  }
  return "?";
}

/// RangeNet++'s k-nearest-neighbour back-projection (defaults: its KITTI
/// post-processing config: knn 5, search 5, sigma 1, cutoff 1).
struct RangeKnnConfig {
  bool enabled = true;     ///< false: every point takes its pixel's label (no vote)
  int search_px = 5;       ///< side of the square window searched (odd)
  int k = 5;               ///< neighbours that may vote (the centre included)
  double sigma_px = 1.0;   ///< Gaussian of the in-window distance weighting [pixels]
  double cutoff_m = 1.0;   ///< neighbours farther than this in weighted range do not vote [m]
};

/// Everything RangeProjection needs: image geometry, input channels with
/// their normalisation, back-projection. Defaults: RangeNet++'s KITTI card
/// (channels range, x, y, z, intensity; its img_means / img_stds).
struct RangeProjectionConfig {
  RangeImageConfig image;   ///< size and field of view
  /// Input channels in the order the network expects them.
  std::vector<RangeChannel> channels{RangeChannel::kRange, RangeChannel::kX, RangeChannel::kY, RangeChannel::kZ,
                                     RangeChannel::kIntensity};
  std::vector<double> channel_mean{12.12, 10.88, 0.23, -1.04, 0.21};   ///< per channel, subtracted first
  std::vector<double> channel_std{12.32, 11.47, 6.91, 0.86, 0.16};     ///< per channel, divided by (> 0)
  RangeKnnConfig knn;       ///< back-projection
};

/// Scan -> normalised range image (C x H x W) -> per-point labels, as RangeNet++ does.
class RangeProjection {
 public:
  using Config = RangeProjectionConfig;

  /// Uses the default configuration (RangeNet++'s KITTI card).
  RangeProjection() : RangeProjection(RangeProjectionConfig{}) {}
  /// Uses `config`; throws ConfigError naming the field and value when it is invalid.
  explicit RangeProjection(RangeProjectionConfig config) : config_(std::move(config)) {
    validate(config_);
    const RangeImageConfig& im = config_.image;
    pixels_ = static_cast<std::size_t>(im.height_px) * static_cast<std::size_t>(im.width_px);
    fov_rad_ = im.fov_up_rad - im.fov_down_rad;
    // 1 - the normalised Gaussian over the window (RangeNet++'s
    // get_gaussian_kernel): close pixels weigh range differences less.
    const int s = config_.knn.search_px;
    const double mid = (s - 1) / 2.0;
    const double var = config_.knn.sigma_px * config_.knn.sigma_px;
    inv_gauss_.assign(static_cast<std::size_t>(s) * static_cast<std::size_t>(s), 0.0);
    double sum = 0.0;
    for (int r = 0; r < s; ++r) {
      for (int c = 0; c < s; ++c) {
        const double g = std::exp(-((r - mid) * (r - mid) + (c - mid) * (c - mid)) / (2.0 * var));
        inv_gauss_[static_cast<std::size_t>(r * s + c)] = g;
        sum += g;
      }
    }
    for (double& w : inv_gauss_) w = 1.0 - w / sum;
    window_.resize(static_cast<std::size_t>(config_.knn.k));
  }

  /// Throws ConfigError naming the field and value when `c` is unusable.
  static void validate(const RangeProjectionConfig& c) {
    const auto fail = [](const std::string& field, const std::string& value, const char* must) {
      throw ConfigError("RangeProjectionConfig." + field + " " + must + ", got " + value);
    };
    const RangeImageConfig& im = c.image;
    // 2^15 x 2^15 keeps H * W * channels far inside size_t and int32 pixel ids.
    if (im.height_px < 1 || im.height_px > 32768) fail("image.height_px", std::to_string(im.height_px), "must be in 1..32768");
    if (im.width_px < 1 || im.width_px > 32768) fail("image.width_px", std::to_string(im.width_px), "must be in 1..32768");
    const double half_pi = std::numbers::pi / 2.0;
    if (!(std::isfinite(im.fov_up_rad) && std::abs(im.fov_up_rad) <= half_pi)) {
      fail("image.fov_up_rad", std::to_string(im.fov_up_rad), "must be finite and within +-pi/2");
    }
    if (!(std::isfinite(im.fov_down_rad) && std::abs(im.fov_down_rad) <= half_pi)) {
      fail("image.fov_down_rad", std::to_string(im.fov_down_rad), "must be finite and within +-pi/2");
    }
    if (!(im.fov_up_rad > im.fov_down_rad)) {
      fail("image.fov_up_rad", std::to_string(im.fov_up_rad) + " (fov_down_rad " + std::to_string(im.fov_down_rad) + ")",
           "must be above fov_down_rad");
    }
    if (c.channels.empty() || c.channels.size() > 16) {
      fail("channels", std::to_string(c.channels.size()) + " channels", "must list 1..16 channels");
    }
    for (std::size_t i = 0; i < c.channels.size(); ++i) {
      if (static_cast<int>(c.channels[i]) > static_cast<int>(RangeChannel::kIntensity)) {
        fail("channels[" + std::to_string(i) + "]", std::to_string(static_cast<int>(c.channels[i])),
             "must be range, x, y, z or intensity");
      }
    }
    if (c.channel_mean.size() != c.channels.size()) {
      fail("channel_mean", std::to_string(c.channel_mean.size()) + " values for " + std::to_string(c.channels.size()) +
           " channels", "must have one value per channel");
    }
    if (c.channel_std.size() != c.channels.size()) {
      fail("channel_std", std::to_string(c.channel_std.size()) + " values for " + std::to_string(c.channels.size()) +
           " channels", "must have one value per channel");
    }
    for (std::size_t i = 0; i < c.channels.size(); ++i) {
      if (!std::isfinite(c.channel_mean[i])) {
        fail("channel_mean[" + std::to_string(i) + "]", std::to_string(c.channel_mean[i]), "must be finite");
      }
      if (!(std::isfinite(c.channel_std[i]) && c.channel_std[i] > 0.0)) {
        fail("channel_std[" + std::to_string(i) + "]", std::to_string(c.channel_std[i]), "must be > 0 and finite");
      }
    }
    const RangeKnnConfig& k = c.knn;
    if (k.search_px < 1 || k.search_px > 15 || k.search_px % 2 == 0) {
      fail("knn.search_px", std::to_string(k.search_px), "must be odd and in 1..15");
    }
    if (k.k < 1 || k.k > k.search_px * k.search_px) {
      fail("knn.k", std::to_string(k.k), "must be in 1..search_px^2");
    }
    if (!(std::isfinite(k.sigma_px) && k.sigma_px > 0.0)) fail("knn.sigma_px", std::to_string(k.sigma_px), "must be > 0 and finite");
    if (!(k.cutoff_m > 0.0)) fail("knn.cutoff_m", std::to_string(k.cutoff_m), "must be > 0 (inf: no cutoff)");
  }

  /// The configuration.
  [[nodiscard]] const RangeProjectionConfig& config() const noexcept { return config_; }
  /// Rows of the image.
  [[nodiscard]] int height_px() const noexcept { return config_.image.height_px; }
  /// Columns of the image.
  [[nodiscard]] int width_px() const noexcept { return config_.image.width_px; }
  /// Input channels.
  [[nodiscard]] int channel_count() const noexcept { return static_cast<int>(config_.channels.size()); }
  /// Pixels of the image (H x W).
  [[nodiscard]] std::size_t pixel_count() const noexcept { return pixels_; }

  /// The pixel (row, column) a direction falls in, clamped into the image;
  /// for a point of range r > 0 (RangeNet++'s formulas, in double).
  [[nodiscard]] std::array<int, 2> pixel_of(const Point3f& p, double range_m) const noexcept {
    const double x = static_cast<double>(p.x()), y = static_cast<double>(p.y()), z = static_cast<double>(p.z());
    const double yaw = -std::atan2(y, x);
    const double pitch = std::asin(std::clamp(z / range_m, -1.0, 1.0));
    const double u = 0.5 * (yaw / std::numbers::pi + 1.0) * config_.image.width_px;
    const double v = (1.0 - (pitch - config_.image.fov_down_rad) / fov_rad_) * config_.image.height_px;
    const int col = static_cast<int>(std::clamp(std::floor(u), 0.0, static_cast<double>(config_.image.width_px - 1)));
    const int row = static_cast<int>(std::clamp(std::floor(v), 0.0, static_cast<double>(config_.image.height_px - 1)));
    return {row, col};
  }

  /// Projects `scan` and fills the input image. A point with a non-finite
  /// coordinate or at the origin gets no pixel. Throws ValueError when a
  /// channel needs intensity the non-empty scan lacks, or the scan has more
  /// than 2^31 - 1 points.
  void project(const Scan& scan) {
    const std::size_t n = scan.points.size();
    if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
      throw ValueError("RangeProjection: scan has " + std::to_string(n) + " points, at most 2^31 - 1 are supported");
    }
    if (n > 0 && scan.intensity.size() != n) {
      for (const RangeChannel c : config_.channels) {
        if (c == RangeChannel::kIntensity) {
          throw ValueError("RangeProjection: the channels include intensity but the scan has " +
                           std::to_string(scan.intensity.size()) + " intensities for " + std::to_string(n) + " points");
        }
      }
    }
    point_pixel_.resize(n);
    point_range_.resize(n);
    pixel_point_.assign(pixels_, -1);
    pixel_range_.assign(pixels_, -1.0f);
    const std::size_t w = static_cast<std::size_t>(config_.image.width_px);
    for (std::size_t i = 0; i < n; ++i) {
      const Point3f& p = scan.points[i];
      const double r = p.cast<double>().norm();
      point_range_[i] = static_cast<float>(r);
      if (!(std::isfinite(r) && r > 0.0)) {
        point_pixel_[i] = -1;
        continue;
      }
      const auto [row, col] = pixel_of(p, r);
      const std::size_t pix = static_cast<std::size_t>(row) * w + static_cast<std::size_t>(col);
      point_pixel_[i] = static_cast<std::int32_t>(pix);
      // Nearest wins; points come in index order, so of equal ranges the first stays.
      if (pixel_point_[pix] < 0 || point_range_[i] < pixel_range_[pix]) {
        pixel_point_[pix] = static_cast<std::int32_t>(i);
        pixel_range_[pix] = point_range_[i];
      }
    }
    fill_input(scan);
  }

  /// The normalised input image of the last projected scan: channel-major
  /// (C x H x W, row-major within a channel), 0 at empty pixels.
  [[nodiscard]] std::span<const float> input() const noexcept { return input_; }
  /// Per point of the last scan: its pixel (row * W + column), -1 when it has none.
  [[nodiscard]] std::span<const std::int32_t> point_pixels() const noexcept { return point_pixel_; }
  /// Per pixel: the index of the point that won it, -1 when empty.
  [[nodiscard]] std::span<const std::int32_t> pixel_points() const noexcept { return pixel_point_; }
  /// Per pixel: the range of the point that won it [m], -1 when empty.
  [[nodiscard]] std::span<const float> pixel_ranges() const noexcept { return pixel_range_; }

  /// Labels every point of the last projected scan from per-pixel labels
  /// (H x W, row-major) with the kNN vote (or its pixel's label when knn is
  /// off); points without a pixel get kUnlabeled. Throws ValueError when a
  /// span's size does not match the image or the scan.
  void back_project(std::span<const Class> pixel_labels, std::span<Class> point_labels) const {
    if (pixel_labels.size() != pixels_) {
      throw ValueError("RangeProjection::back_project: " + std::to_string(pixel_labels.size()) +
                       " pixel labels for an image of " + std::to_string(pixels_) + " pixels");
    }
    if (point_labels.size() != point_pixel_.size()) {
      throw ValueError("RangeProjection::back_project: " + std::to_string(point_labels.size()) +
                       " point labels for a scan of " + std::to_string(point_pixel_.size()) + " points");
    }
    if (config_.knn.enabled) {
      for (std::size_t q = 0; q < pixel_labels.size(); ++q) {
        if (static_cast<int>(pixel_labels[q]) >= kNumClasses) {
          throw ValueError("RangeProjection::back_project: pixel " + std::to_string(q) + " has class id " +
                           std::to_string(static_cast<int>(pixel_labels[q])) + ", learning classes are 0.." +
                           std::to_string(kNumClasses - 1));
        }
      }
    }
    for (std::size_t i = 0; i < point_pixel_.size(); ++i) {
      const std::int32_t pix = point_pixel_[i];
      if (pix < 0) {
        point_labels[i] = Class::kUnlabeled;
      } else if (!config_.knn.enabled) {
        point_labels[i] = pixel_labels[static_cast<std::size_t>(pix)];
      } else {
        point_labels[i] = vote(pixel_labels, pix, point_range_[i]);
      }
    }
  }

 private:
  struct Neighbour {
    double distance;
    int slot;  // row-major position in the window: the tie-break
    Class label;
  };

  void fill_input(const Scan& scan) {
    const std::size_t nc = config_.channels.size();
    input_.assign(nc * pixels_, 0.0f);
    for (std::size_t pix = 0; pix < pixels_; ++pix) {
      const std::int32_t owner = pixel_point_[pix];
      if (owner < 0) continue;
      const auto i = static_cast<std::size_t>(owner);
      const Point3f& p = scan.points[i];
      for (std::size_t c = 0; c < nc; ++c) {
        double v = 0.0;
        switch (config_.channels[c]) {
          case RangeChannel::kRange: v = static_cast<double>(point_range_[i]); break;
          case RangeChannel::kX: v = static_cast<double>(p.x()); break;
          case RangeChannel::kY: v = static_cast<double>(p.y()); break;
          case RangeChannel::kZ: v = static_cast<double>(p.z()); break;
          case RangeChannel::kIntensity: v = static_cast<double>(scan.intensity[i]); break;
        }
        input_[c * pixels_ + pix] = static_cast<float>((v - config_.channel_mean[c]) / config_.channel_std[c]);
      }
    }
  }

  // RangeNet++'s KNN.forward for one point whose pixel is `pix` (labels checked by back_project).
  Class vote(std::span<const Class> pixel_labels, std::int32_t pix, float range_m) const {
    const int s = config_.knn.search_px;
    const int pad = (s - 1) / 2;
    const int w = config_.image.width_px;
    const int h = config_.image.height_px;
    const int row = pix / w;
    const int col = pix % w;
    const double r = static_cast<double>(range_m);
    const double cutoff = config_.knn.cutoff_m;
    const auto k_max = static_cast<std::size_t>(config_.knn.k);
    std::size_t count = 0;
    for (int dy = -pad; dy <= pad; ++dy) {
      const int nr = row + dy;
      for (int dx = -pad; dx <= pad; ++dx) {
        const int slot = (dy + pad) * s + (dx + pad);
        const int nc = col + dx;
        double neighbour_range = 0.0;  // outside the image: RangeNet++'s zero padding
        Class label = Class::kUnlabeled;
        if (nr >= 0 && nr < h && nc >= 0 && nc < w) {
          const std::size_t q = static_cast<std::size_t>(nr) * static_cast<std::size_t>(w) + static_cast<std::size_t>(nc);
          if (dy == 0 && dx == 0) {
            neighbour_range = r;  // the centre counts with the point's own range
          } else {
            const float pr = pixel_range_[q];
            if (pr < 0.0f) continue;  // empty pixel: infinitely far, never votes
            neighbour_range = static_cast<double>(pr);
          }
          label = pixel_labels[q];
        }
        const double d = std::abs(neighbour_range - r) * inv_gauss_[static_cast<std::size_t>(slot)];
        // Beyond the cutoff a neighbour never votes, and every neighbour
        // nearer than it ranks before it: the voters are the k nearest of
        // those within the cutoff.
        if (d > cutoff) continue;
        // Keep the k nearest sorted by (distance, slot) as they come: slots
        // arrive in increasing order, so an equal distance goes behind.
        if (count == k_max && !(d < window_[k_max - 1].distance)) continue;
        std::size_t j = count < k_max ? count++ : k_max - 1;
        for (; j > 0 && window_[j - 1].distance > d; --j) window_[j] = window_[j - 1];
        window_[j] = {d, slot, label};
      }
    }
    const std::size_t k = count;
    std::array<int, kNumClasses> votes{};
    for (std::size_t j = 0; j < k; ++j) ++votes[static_cast<std::size_t>(window_[j].label)];
    votes[0] = 0;  // unlabeled never votes
    std::size_t best = 0;
    for (std::size_t c = 1; c < votes.size(); ++c) {
      if (votes[c] > votes[best]) best = c;
    }
    return static_cast<Class>(best);  // 0 (unlabeled) when nobody voted
  }

  RangeProjectionConfig config_;
  std::size_t pixels_ = 0;
  double fov_rad_ = 0.0;
  std::vector<double> inv_gauss_;             // 1 - normalised Gaussian, per window slot
  mutable std::vector<Neighbour> window_;     // vote()'s k nearest so far (back_project is const)
  std::vector<std::int32_t> point_pixel_;     // per point
  std::vector<float> point_range_;            // per point [m]
  std::vector<std::int32_t> pixel_point_;     // per pixel
  std::vector<float> pixel_range_;            // per pixel [m], -1 empty
  std::vector<float> input_;                  // C x H x W
};

}  // namespace semlio
