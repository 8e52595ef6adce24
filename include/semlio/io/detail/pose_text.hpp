#pragma once
/// \file
/// Internal: the 3x4 row-major pose text shared by KITTI poses and calib.txt
/// (validation of the rotation block, formatting back).

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <string>

#include <semlio/core/error.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::io {

/// Largest accepted |(R^T R - I)_jk| for a rotation read from text. The real
/// KITTI ground truth (printed with 7 significant digits) reaches 2.8e-7
/// (sequence 03), the calib `Tr` blocks 9.4e-8; 1e-5 leaves a wide margin
/// while rejecting any real scale or shear (1e-3 and more).
inline constexpr double kRotationTolerance = 1e-5;

namespace detail {

/// Builds a pose from 12 row-major 3x4 values `v`, checking that every value is
/// finite, R^T R = I within kRotationTolerance and det R > 0. Throws
/// ValueError "path:line: <what> ..." naming the offending value.
inline SE3d pose_from_3x4(const double* v, const std::string& path, long line, const std::string& what) {
  for (std::size_t i = 0; i < 12; ++i) {
    if (!std::isfinite(v[i])) {
      throw ValueError(detail::where(
          path, line,
          what + " field " + std::to_string(i + 1) + " is not finite (" + (std::isnan(v[i]) ? "NaN" : "infinite") + ")"));
    }
  }
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = v[4 * r + c];
    t(r) = v[4 * r + 3];
  }
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(err <= kRotationTolerance)) {
    throw ValueError(detail::where(path, line,
                                   what + " rotation is not orthonormal: max |R^T R - I| = " + std::to_string(err) +
                                       " > tolerance " + std::to_string(kRotationTolerance)));
  }
  const double det = R.determinant();
  if (!(det > 0.0)) {
    throw ValueError(
        detail::where(path, line, what + " rotation is a reflection (det R = " + std::to_string(det) + ")"));
  }
  return SE3d(SO3d(R), t);
}

/// Appends the 12 row-major 3x4 values of `T` separated by spaces (shortest
/// round-trip decimal text), without a newline.
inline void append_3x4(std::string& out, const SE3d& T) {
  const Eigen::Matrix4d M = T.matrix();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      if (r != 0 || c != 0) out.push_back(' ');
      append_double(out, M(r, c));
    }
  }
}

}  // namespace detail
}  // namespace semlio::io
