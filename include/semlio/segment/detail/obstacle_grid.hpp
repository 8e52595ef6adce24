#pragma once
/// \file
/// A square 2D grid of the above-ground points around the sensor with
/// per-cell height statistics and 8-connected components of occupied cells.
/// Buffers are reused between scans; only touched cells are reset.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace semlio::detail {

/// Height statistics of one occupied cell (heights above the local ground).
struct GridCell {
  float h_min_m = std::numeric_limits<float>::infinity();  ///< lowest point [m]
  float h_max_m = -std::numeric_limits<float>::infinity(); ///< highest point [m]
  float z_max_m = -std::numeric_limits<float>::infinity(); ///< highest point in the sensor frame [m]
  float t_min_m = std::numeric_limits<float>::infinity();  ///< lowest offset across the line of sight [m]
  float t_max_m = -std::numeric_limits<float>::infinity(); ///< highest offset across the line of sight [m]
  float sx_m = 0.0F;    ///< sum of the points' x offsets from the cell centre [m]
  float sy_m = 0.0F;    ///< sum of the points' y offsets from the cell centre [m]
  float sxx_m2 = 0.0F;  ///< sum of squared x offsets [m^2]
  float syy_m2 = 0.0F;  ///< sum of squared y offsets [m^2]
  float sxy_m2 = 0.0F;  ///< sum of x offset times y offset [m^2]
  std::uint32_t count = 0;                                 ///< points in the cell
  std::uint32_t road_count = 0;                            ///< of which stand over ground the walk found to be road
  std::int32_t component = -1;                             ///< component id (-1: none)
  std::int32_t mark = -1;                                  ///< scratch id for sub-components
  std::uint8_t label = 0;                                  ///< class id given to the cell's points
  std::uint8_t upper_label = 0;                            ///< class id of points above split_m
  float split_m = std::numeric_limits<float>::infinity();  ///< points higher than this get upper_label [m]
};

/// The occupied cells of one component are order[begin, end).
struct GridComponent {
  std::uint32_t begin = 0;
  std::uint32_t end = 0;
};

/// Grid over [-radius, radius]^2 in the sensor frame. Not thread-safe.
class ObstacleGrid {
 public:
  /// Resizes for a cell size and radius [m] (allocates only when growing).
  void configure(float cell_size_m, float radius_m) {
    cell_m_ = cell_size_m;
    side_ = std::max(1, static_cast<int>(std::ceil(2.0F * radius_m / cell_size_m)));
    half_ = 0.5F * static_cast<float>(side_) * cell_size_m;
    const std::size_t total = static_cast<std::size_t>(side_) * static_cast<std::size_t>(side_);
    if (cells_.size() != total) {
      cells_.assign(total, GridCell{});
    } else {
      for (const std::uint32_t c : touched_) cells_[c] = GridCell{};
    }
    touched_.clear();
    order_.clear();
    components_.clear();
  }

  /// Cell index of (x, y) [m], or -1 outside the grid.
  [[nodiscard]] std::int32_t cell_of(float x, float y) const noexcept {
    const float fx = (x + half_) / cell_m_;
    const float fy = (y + half_) / cell_m_;
    if (!(fx >= 0.0F && fy >= 0.0F)) return -1;
    const int ix = static_cast<int>(fx);
    const int iy = static_cast<int>(fy);
    if (ix >= side_ || iy >= side_) return -1;
    return iy * side_ + ix;
  }

  /// Adds a point (x, y, z) [m] in the sensor frame of height h [m] above
  /// ground to cell c (from cell_of); `over_road`: its ground is road.
  void add(std::int32_t c, float x_m, float y_m, float z_m, float h_m, bool over_road) {
    GridCell& g = cells_[static_cast<std::size_t>(c)];
    if (g.count == 0) touched_.push_back(static_cast<std::uint32_t>(c));
    ++g.count;
    g.road_count += over_road ? 1U : 0U;
    g.h_min_m = std::min(g.h_min_m, h_m);
    g.h_max_m = std::max(g.h_max_m, h_m);
    g.z_max_m = std::max(g.z_max_m, z_m);
    // Horizontal spread (moments about the cell centre, small numbers in
    // float): how planar the surface through this cell is.
    const Eigen::Vector2f mid = centre(static_cast<std::uint32_t>(c));
    const float dx = x_m - mid.x();
    const float dy = y_m - mid.y();
    g.sx_m += dx;
    g.sy_m += dy;
    g.sxx_m2 += dx * dx;
    g.syy_m2 += dy * dy;
    g.sxy_m2 += dx * dy;
    // Offset across the line of sight through the cell centre: the visible
    // width of a column (a trunk looks wider than a pole).
    const Eigen::Vector2f u = mid.normalized();
    const float t = u.x() * y_m - u.y() * x_m;
    g.t_min_m = std::min(g.t_min_m, t);
    g.t_max_m = std::max(g.t_max_m, t);
  }

  /// Cells touched since configure(), in first-touch order.
  [[nodiscard]] const std::vector<std::uint32_t>& touched() const noexcept { return touched_; }

  /// Labels the 8-connected components of the occupied cells. Deterministic:
  /// seeds are taken in the order cells were first touched.
  void connect() {
    components_.clear();
    order_.clear();
    for (const std::uint32_t seed : touched_) {
      if (cells_[seed].component >= 0) continue;
      const auto id = static_cast<std::int32_t>(components_.size());
      GridComponent comp;
      comp.begin = static_cast<std::uint32_t>(order_.size());
      cells_[seed].component = id;
      order_.push_back(seed);
      for (std::size_t k = comp.begin; k < order_.size(); ++k) {
        const std::uint32_t c = order_[k];
        const int ix = static_cast<int>(c) % side_;
        const int iy = static_cast<int>(c) / side_;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = ix + dx;
            const int ny = iy + dy;
            if (nx < 0 || ny < 0 || nx >= side_ || ny >= side_) continue;
            const auto nc = static_cast<std::uint32_t>(ny * side_ + nx);
            GridCell& g = cells_[nc];
            if (g.count == 0 || g.component >= 0) continue;
            g.component = id;
            order_.push_back(nc);
          }
        }
      }
      comp.end = static_cast<std::uint32_t>(order_.size());
      components_.push_back(comp);
    }
  }

  /// Cell by index.
  [[nodiscard]] GridCell& cell(std::uint32_t c) { return cells_[c]; }
  /// Cell by index.
  [[nodiscard]] const GridCell& cell(std::uint32_t c) const { return cells_[c]; }
  /// Components found by connect().
  [[nodiscard]] const std::vector<GridComponent>& components() const noexcept { return components_; }
  /// Cells of all components, grouped by component.
  [[nodiscard]] const std::vector<std::uint32_t>& order() const noexcept { return order_; }
  /// Cells per side.
  [[nodiscard]] int side() const noexcept { return side_; }
  /// Cell size [m].
  [[nodiscard]] float cell_size_m() const noexcept { return cell_m_; }
  /// Centre of cell c in the sensor frame (x, y) [m].
  [[nodiscard]] Eigen::Vector2f centre(std::uint32_t c) const noexcept {
    const int ix = static_cast<int>(c) % side_;
    const int iy = static_cast<int>(c) / side_;
    return {(static_cast<float>(ix) + 0.5F) * cell_m_ - half_, (static_cast<float>(iy) + 0.5F) * cell_m_ - half_};
  }

 private:
  std::vector<GridCell> cells_;
  std::vector<std::uint32_t> touched_;
  std::vector<std::uint32_t> order_;
  std::vector<GridComponent> components_;
  float cell_m_ = 0.4F;
  float half_ = 0.0F;
  int side_ = 0;
};

}  // namespace semlio::detail
