#pragma once
// Conversions between Bullet's (double-precision) vector types and Eigen's, in one place.

#include <LinearMath/btMatrix3x3.h>
#include <LinearMath/btVector3.h>

#include <Eigen/Core>

namespace torsion {

inline Eigen::Vector3d toEigen(const btVector3& v) {
  return Eigen::Vector3d(v.x(), v.y(), v.z());
}

inline btVector3 toBt(const Eigen::Vector3d& v) {
  return btVector3(v.x(), v.y(), v.z());
}

inline Eigen::Matrix3d toEigen(const btMatrix3x3& m) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      out(r, c) = m[r][c];
  return out;
}

}  // namespace torsion
