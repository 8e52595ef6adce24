#include <semlio/lie/se3.hpp>
#include <semlio/search/kdtree.hpp>

#include <cstdint>
#include <cstdio>
#include <vector>

int main() {
  // Eigen through semlio: exp / log / inverse of SE3 round-trip.
  const semlio::SE3d T = semlio::SE3d::exp((semlio::SE3d::Vector6() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const double err = (T * T.inverse()).log().norm();
  // nanoflann through semlio: the nearest of three points.
  const std::vector<Eigen::Vector3f> pts{{0.0F, 0.0F, 0.0F}, {1.0F, 0.0F, 0.0F}, {0.0F, 2.0F, 0.0F}};
  const semlio::KdTree3f tree(pts);
  std::uint32_t idx = 99;
  float sq_dist = -1.0F;
  const std::size_t found = tree.knn(Eigen::Vector3f(0.9F, 0.1F, 0.0F), 1, &idx, &sq_dist);
  std::printf("semlio consumer: |log(T T^-1)| = %g, nearest = %u\n", err, static_cast<unsigned>(idx));
  return err < 1e-12 && found == 1 && idx == 1 ? 0 : 1;
}
