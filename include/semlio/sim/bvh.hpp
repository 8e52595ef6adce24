#pragma once
/// \file
/// Bounding volume hierarchy over simulator primitives: binned-SAH build,
/// closest-hit ray casting with float node boxes (conservatively rounded) and
/// exact double-precision primitive tests, so a hit distance equals the
/// analytic one.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include <semlio/sim/geometry.hpp>

namespace semlio::sim {

/// Closest hit of a ray: distance along the unit direction [m] and the index
/// of the primitive in `Bvh::primitives()`.
struct Hit {
  double t_m = std::numeric_limits<double>::infinity();
  std::uint32_t primitive = 0;
};

/// Static BVH; owns a reordered copy of its primitives. Build once, then
/// `cast` is const and safe to call from several threads at once.
class Bvh {
 public:
  Bvh() = default;
  /// Builds over a copy of `prims` (any order; reordered internally).
  explicit Bvh(std::vector<Primitive> prims) { build(std::move(prims)); }

  /// (Re)builds over `prims`.
  void build(std::vector<Primitive> prims) {
    prims_ = std::move(prims);
    nodes_.clear();
    const std::size_t n = prims_.size();
    if (n == 0) return;
    std::vector<Aabb> boxes(n);
    std::vector<Eigen::Vector3d> centres(n);
    for (std::size_t i = 0; i < n; ++i) {
      boxes[i] = bounds(prims_[i]);
      centres[i] = boxes[i].centre();
    }
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0U);
    nodes_.reserve(2 * n);
    nodes_.emplace_back();
    build_node(0, 0, static_cast<std::uint32_t>(n), order, boxes, centres);
    std::vector<Primitive> sorted;
    sorted.reserve(n);
    for (const std::uint32_t i : order) sorted.push_back(prims_[i]);
    prims_ = std::move(sorted);
  }

  /// Closest hit with distance in (t_min, t_max); false when nothing is hit.
  bool cast(const Ray& ray, double t_min, double t_max, Hit& hit) const {
    if (nodes_.empty()) return false;
    const float ox = static_cast<float>(ray.origin.x());
    const float oy = static_cast<float>(ray.origin.y());
    const float oz = static_cast<float>(ray.origin.z());
    const float ix = static_cast<float>(ray.inv_dir.x());
    const float iy = static_cast<float>(ray.inv_dir.y());
    const float iz = static_cast<float>(ray.inv_dir.z());
    double best = t_max;
    bool found = false;
    // Stack entries carry the entry distance of their box, so a node popped
    // after a closer hit was found is skipped without a second slab test.
    // Uninitialised: only pushed entries are read (no 512-byte zeroing per ray).
    std::array<std::uint32_t, 64> stack;
    std::array<float, 64> stack_t;
    std::size_t top = 0;
    float t_root = 0.0F;
    if (!slab(nodes_[0], ox, oy, oz, ix, iy, iz, static_cast<float>(best), t_root)) return false;
    stack[top] = 0;
    stack_t[top++] = t_root;
    while (top > 0) {
      --top;
      if (static_cast<double>(stack_t[top]) > best) continue;
      const Node& node = nodes_[stack[top]];
      if (node.count > 0) {
        for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
          if (intersect(prims_[k], ray, t_min, best)) {
            hit.primitive = k;
            found = true;
          }
        }
        continue;
      }
      // Visit the nearer child first: push the farther one below it.
      const Node& l = nodes_[node.first];
      const Node& r = nodes_[node.first + 1];
      float tl = 0.0F;
      float tr = 0.0F;
      const auto limit = static_cast<float>(best);
      const bool hl = slab(l, ox, oy, oz, ix, iy, iz, limit, tl);
      const bool hr = slab(r, ox, oy, oz, ix, iy, iz, limit, tr);
      if (hl && hr && top + 2 <= stack.size()) {
        const bool left_first = tl <= tr;
        stack[top] = left_first ? node.first + 1 : node.first;
        stack_t[top++] = left_first ? tr : tl;
        stack[top] = left_first ? node.first : node.first + 1;
        stack_t[top++] = left_first ? tl : tr;
      } else if (hl && top < stack.size()) {
        stack[top] = node.first;
        stack_t[top++] = tl;
      } else if (hr && top < stack.size()) {
        stack[top] = node.first + 1;
        stack_t[top++] = tr;
      }
    }
    if (found) hit.t_m = best;
    return found;
  }

  /// The primitives in BVH order (indices of `Hit::primitive`).
  [[nodiscard]] const std::vector<Primitive>& primitives() const noexcept { return prims_; }
  /// Number of nodes (for tests and statistics).
  [[nodiscard]] std::size_t node_count() const noexcept { return nodes_.size(); }

 private:
  struct Node {
    std::array<float, 3> lo{};
    std::array<float, 3> hi{};
    std::uint32_t first = 0;  // leaf: first primitive; inner: left child (right = first + 1)
    std::uint32_t count = 0;  // leaf: primitive count; inner: 0
  };

  static constexpr std::uint32_t kLeafSize = 4;
  static constexpr int kBins = 16;

  static bool slab(const Node& n, float ox, float oy, float oz, float ix, float iy, float iz,
                   float t_max, float& t_near) {
    float tx0 = (n.lo[0] - ox) * ix;
    float tx1 = (n.hi[0] - ox) * ix;
    if (tx0 > tx1) std::swap(tx0, tx1);
    float ty0 = (n.lo[1] - oy) * iy;
    float ty1 = (n.hi[1] - oy) * iy;
    if (ty0 > ty1) std::swap(ty0, ty1);
    float tz0 = (n.lo[2] - oz) * iz;
    float tz1 = (n.hi[2] - oz) * iz;
    if (tz0 > tz1) std::swap(tz0, tz1);
    // NaN (0 * inf on a face) compares false and is ignored by max/min order.
    const float t0 = std::max(std::max(tx0, ty0), std::max(tz0, 0.0F));
    const float t1 = std::min(std::min(tx1, ty1), std::min(tz1, t_max));
    t_near = t0;
    return t0 <= t1;
  }

  static void set_box(Node& node, const Aabb& b) {
    for (int k = 0; k < 3; ++k) {
      // Round outward so float boxes always contain the double geometry.
      const double margin = 1e-5 * (1.0 + std::abs(b.lo[k]) + std::abs(b.hi[k]));
      node.lo[static_cast<std::size_t>(k)] = static_cast<float>(b.lo[k] - margin);
      node.hi[static_cast<std::size_t>(k)] = static_cast<float>(b.hi[k] + margin);
    }
  }

  void build_node(std::uint32_t index, std::uint32_t begin, std::uint32_t end,
                  std::vector<std::uint32_t>& order, const std::vector<Aabb>& boxes,
                  const std::vector<Eigen::Vector3d>& centres) {
    Aabb box;
    Aabb cbox;
    for (std::uint32_t i = begin; i < end; ++i) {
      box.extend(boxes[order[i]]);
      cbox.extend(centres[order[i]]);
    }
    set_box(nodes_[index], box);
    const std::uint32_t count = end - begin;
    if (count <= kLeafSize) {
      nodes_[index].first = begin;
      nodes_[index].count = count;
      return;
    }
    // Binned SAH over the widest centroid axis.
    const Eigen::Vector3d ext = cbox.hi - cbox.lo;
    int axis = 0;
    if (ext.y() > ext[axis]) axis = 1;
    if (ext.z() > ext[axis]) axis = 2;
    std::uint32_t mid = begin + count / 2;
    if (ext[axis] > 0.0) {
      std::array<Aabb, kBins> bin_box{};
      std::array<std::uint32_t, kBins> bin_count{};
      const double scale = kBins / ext[axis];
      const auto bin_of = [&](std::uint32_t prim) {
        const int b = static_cast<int>((centres[prim][axis] - cbox.lo[axis]) * scale);
        return std::clamp(b, 0, kBins - 1);
      };
      for (std::uint32_t i = begin; i < end; ++i) {
        const auto b = static_cast<std::size_t>(bin_of(order[i]));
        bin_box[b].extend(boxes[order[i]]);
        ++bin_count[b];
      }
      std::array<double, kBins> right_cost{};
      Aabb acc;
      std::uint32_t acc_n = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.extend(bin_box[static_cast<std::size_t>(b)]);
        acc_n += bin_count[static_cast<std::size_t>(b)];
        right_cost[static_cast<std::size_t>(b)] = acc.half_area() * acc_n;
      }
      Aabb left;
      std::uint32_t left_n = 0;
      double best_cost = std::numeric_limits<double>::infinity();
      int best_split = -1;
      for (int b = 1; b < kBins; ++b) {
        left.extend(bin_box[static_cast<std::size_t>(b - 1)]);
        left_n += bin_count[static_cast<std::size_t>(b - 1)];
        if (left_n == 0 || left_n == count) continue;
        const double cost = left.half_area() * left_n + right_cost[static_cast<std::size_t>(b)];
        if (cost < best_cost) {
          best_cost = cost;
          best_split = b;
        }
      }
      if (best_split > 0) {
        const auto it = std::partition(order.begin() + begin, order.begin() + end,
                                       [&](std::uint32_t p) { return bin_of(p) < best_split; });
        mid = static_cast<std::uint32_t>(it - order.begin());
      } else {
        std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                         [&](std::uint32_t p, std::uint32_t q) {
                           return centres[p][axis] < centres[q][axis];
                         });
      }
    }
    if (mid == begin || mid == end) mid = begin + count / 2;
    const auto left_index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    nodes_.emplace_back();
    nodes_[index].first = left_index;
    nodes_[index].count = 0;
    build_node(left_index, begin, mid, order, boxes, centres);
    build_node(left_index + 1, mid, end, order, boxes, centres);
  }

  std::vector<Primitive> prims_;
  std::vector<Node> nodes_;
};

}  // namespace semlio::sim
