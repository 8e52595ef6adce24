#include <semlio/semlio.hpp>

#include <cstdio>

int main() {
  const semlio::SE3d T = semlio::SE3d::exp((semlio::SE3d::Vector6() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const double err = (T * T.inverse()).log().norm();
  std::printf("semlio consumer: |log(T T^-1)| = %g\n", err);
  return err < 1e-12 ? 0 : 1;
}
