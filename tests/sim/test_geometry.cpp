// Exact ray-primitive intersections against hand-derived distances.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include <semlio/sim/geometry.hpp>

namespace test_geometry {  // one namespace per test file: the area compiles as one TU

using semlio::sim::Primitive;
using semlio::sim::Ray;
using semlio::sim::Surface;
using Eigen::Vector3d;

namespace {
double cast(const Primitive& p, const Vector3d& o, const Vector3d& d) {
  double t = 1e9;
  return semlio::sim::intersect(p, Ray::make(o, d), 0.0, t) ? t : -1.0;
}
}  // namespace

TEST_CASE("triangle (plane) distance is h / sin(elevation)", "[sim]") {
  const Surface s{40, 0, 0.2F};
  const auto tri = semlio::sim::make_triangle({-100, -100, 0}, {100, -100, 0}, {0, 100, 0}, s);
  for (const double el_deg : {-2.0, -8.33, -15.0, -24.9}) {
    const double el = el_deg * std::numbers::pi / 180.0;
    const Vector3d d(std::cos(el), 0.0, std::sin(el));
    CHECK(cast(tri, {0, 0, 1.73}, d) == Approx(1.73 / std::sin(-el)).epsilon(1e-12));
  }
  CHECK(cast(tri, {0, 0, 1.73}, {1, 0, 0.01}) < 0.0);  // upward ray misses
  CHECK(cast(tri, {500, 0, 1.0}, {0, 0, -1}) < 0.0);   // outside the triangle
  const Vector3d n = semlio::sim::surface_normal(tri, {0, 0, 0}, {0, 0, 5});
  CHECK(n.z() == Approx(1.0));
}

TEST_CASE("box distance: axis-aligned and rotated faces", "[sim]") {
  const Surface s{50, 3, 0.3F};
  const auto box = semlio::sim::make_box({10, 0, 2}, {1, 2, 2}, 0.0, s);
  CHECK(cast(box, {0, 0, 2}, {1, 0, 0}) == Approx(9.0).epsilon(1e-12));
  CHECK(cast(box, {10, -10, 1}, {0, 1, 0}) == Approx(8.0).epsilon(1e-12));
  CHECK(cast(box, {0, 5, 2}, {1, 0, 0}) < 0.0);
  // Rotated 45 deg about z: the corner points at the ray; distance to the
  // corner is 10 - sqrt(2) * half extent.
  const auto rot = semlio::sim::make_box({10, 0, 0}, {1, 1, 1}, std::numbers::pi / 4.0, s);
  CHECK(cast(rot, {0, 0, 0}, {1, 0, 0}) == Approx(10.0 - std::sqrt(2.0)).epsilon(1e-12));
  // Normal of the face hit.
  const Vector3d hit(9.0, 0.0, 2.0);
  CHECK(semlio::sim::surface_normal(box, hit, {0, 0, 2}).x() == Approx(-1.0));
  CHECK(semlio::sim::bounds(rot).hi.x() == Approx(10.0 + std::sqrt(2.0)));
}

TEST_CASE("vertical cylinder: side, cap and height limits", "[sim]") {
  const Surface s{80, 7, 0.4F};
  const auto cyl = semlio::sim::make_cylinder({5, 0, 0}, 0.5, 3.0, s);
  CHECK(cast(cyl, {0, 0, 1}, {1, 0, 0}) == Approx(4.5).epsilon(1e-12));
  // Off-centre: chord at lateral offset 0.3 -> 5 - sqrt(0.25 - 0.09).
  CHECK(cast(cyl, {0, 0.3, 1}, {1, 0, 0}) == Approx(5.0 - std::sqrt(0.16)).epsilon(1e-12));
  CHECK(cast(cyl, {0, 0, 3.5}, {1, 0, 0}) < 0.0);  // above the top
  CHECK(cast(cyl, {5, 0, 10}, {0, 0, -1}) == Approx(7.0).epsilon(1e-12));  // top cap
  const Vector3d n = semlio::sim::surface_normal(cyl, {4.5, 0, 1}, {0, 0, 1});
  CHECK(n.x() == Approx(-1.0));
}

TEST_CASE("ellipsoid distance", "[sim]") {
  const Surface s{70, 9, 0.4F};
  const auto sphere = semlio::sim::make_ellipsoid({0, 0, 0}, {2, 2, 2}, s);
  CHECK(cast(sphere, {-10, 0, 0}, {1, 0, 0}) == Approx(8.0).epsilon(1e-12));
  CHECK(cast(sphere, {-10, 1, 0}, {1, 0, 0}) == Approx(10.0 - std::sqrt(3.0)).epsilon(1e-12));
  const auto ell = semlio::sim::make_ellipsoid({0, 0, 5}, {3, 3, 1}, s);
  CHECK(cast(ell, {0, 0, 0}, {0, 0, 1}) == Approx(4.0).epsilon(1e-12));
  CHECK(cast(ell, {-10, 0, 5}, {1, 0, 0}) == Approx(7.0).epsilon(1e-12));
  // From inside, the exit point is returned.
  CHECK(cast(sphere, {0, 0, 0}, {0, 1, 0}) == Approx(2.0).epsilon(1e-12));
}

}  // namespace test_geometry
