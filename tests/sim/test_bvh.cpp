// The BVH returns exactly the closest hit a brute-force scan finds.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include <semlio/sim/bvh.hpp>
#include <semlio/sim/random.hpp>

namespace test_bvh {  // one namespace per test file: the area compiles as one TU

using Eigen::Vector3d;
using semlio::sim::Primitive;
using semlio::sim::Ray;

TEST_CASE("BVH closest hit equals brute force on a random scene", "[sim]") {
  semlio::sim::Rng rng(42);
  std::vector<Primitive> prims;
  for (int k = 0; k < 600; ++k) {
    const Vector3d c(rng.uniform(-60, 60), rng.uniform(-60, 60), rng.uniform(0, 10));
    const semlio::sim::Surface s{50, static_cast<std::uint16_t>(k), 0.3F};
    switch (k % 4) {
      case 0: prims.push_back(semlio::sim::make_box(c, {rng.uniform(0.2, 4), rng.uniform(0.2, 4), rng.uniform(0.2, 4)}, rng.uniform(0, 3), s)); break;
      case 1: prims.push_back(semlio::sim::make_cylinder(c, rng.uniform(0.05, 1), rng.uniform(0.5, 8), s)); break;
      case 2: prims.push_back(semlio::sim::make_ellipsoid(c, {rng.uniform(0.3, 3), rng.uniform(0.3, 3), rng.uniform(0.3, 3)}, s)); break;
      default: prims.push_back(semlio::sim::make_triangle(c, c + Vector3d(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-2, 2)), c + Vector3d(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-2, 2)), s));
    }
  }
  prims.push_back(semlio::sim::make_triangle({-1000, -1000, 0}, {1000, -1000, 0}, {0, 1000, 0}, {40, 0, 0.2F}));
  const semlio::sim::Bvh bvh(prims);
  REQUIRE(bvh.primitives().size() == prims.size());
  int hits = 0;
  for (int k = 0; k < 3000; ++k) {
    const Vector3d o(rng.uniform(-20, 20), rng.uniform(-20, 20), rng.uniform(0.5, 3));
    const Vector3d d(rng.normal(), rng.normal(), rng.normal() * 0.3);
    const Ray ray = Ray::make(o, d);
    double best = 120.0;
    std::uint16_t best_id = 0xFFFF;
    for (const auto& p : prims) {
      if (semlio::sim::intersect(p, ray, 0.0, best)) best_id = p.surface.instance;
    }
    semlio::sim::Hit hit;
    const bool got = bvh.cast(ray, 0.0, 120.0, hit);
    REQUIRE(got == (best_id != 0xFFFF));
    if (got) {
      ++hits;
      CHECK(hit.t_m == best);
      CHECK(bvh.primitives()[hit.primitive].surface.instance == best_id);
    }
  }
  CHECK(hits > 1000);
}

TEST_CASE("BVH over an empty scene hits nothing", "[sim]") {
  const semlio::sim::Bvh bvh(std::vector<Primitive>{});
  semlio::sim::Hit hit;
  CHECK_FALSE(bvh.cast(Ray::make({0, 0, 0}, {1, 0, 0}), 0.0, 100.0, hit));
}

}  // namespace test_bvh
