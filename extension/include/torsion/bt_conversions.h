#pragma once
// Conversions between Bullet's types and Eigen's, in one place: the seam between the two.
//
// Torsion's FEM is double everywhere; Bullet's btScalar is float or double depending on which
// Bullet the build links (TORSION_BULLET_PRECISION, docs/bullet-integration.md). Bullet -> Eigen
// widens and is exact; Eigen -> Bullet rounds to float on float Bullet (about 7 significant
// digits: 0.1 um at 1 m). Every crossing goes through these functions so the rounding is visible
// and happens only here.
//
// Points of the FEM (double) are moved into and out of a rigid body's frame in double by the
// *Point / *Direction functions below, never by rounding them to btScalar first: on float Bullet
// a node 10 m from the origin would otherwise move by up to 0.5 um before its contact gap is
// measured. They use Bullet's own order of operations, so on double Bullet they give exactly
// what btTransform gives.

#include <LinearMath/btMatrix3x3.h>
#include <LinearMath/btQuaternion.h>
#include <LinearMath/btScalar.h>
#include <LinearMath/btTransform.h>
#include <LinearMath/btVector3.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>

namespace torsion {

/// True when Bullet's btScalar is double (BT_USE_DOUBLE_PRECISION), false on float Bullet.
inline constexpr bool kBulletIsDouble = sizeof(btScalar) == sizeof(double);

/// btScalar's machine epsilon: 2.2e-16 on double Bullet, 1.2e-7 on float Bullet. What Bullet keeps
/// of a size L (a rigid body's position, a shape's half extent) is known to about L times this.
inline constexpr double kBulletEpsilon =
    static_cast<double>(std::numeric_limits<btScalar>::epsilon());

/// A Bullet scalar as the FEM's double (exact).
inline double toDouble(btScalar s) {
  return static_cast<double>(s);
}

/// A double as Bullet's scalar (rounds to nearest on float Bullet).
inline btScalar toBtScalar(double s) {
  return static_cast<btScalar>(s);
}

inline Eigen::Vector3d toEigen(const btVector3& v) {
  return Eigen::Vector3d(toDouble(v.x()), toDouble(v.y()), toDouble(v.z()));
}

inline btVector3 toBt(const Eigen::Vector3d& v) {
  return btVector3(toBtScalar(v.x()), toBtScalar(v.y()), toBtScalar(v.z()));
}

inline Eigen::Quaterniond toEigen(const btQuaternion& q) {
  return Eigen::Quaterniond(toDouble(q.w()), toDouble(q.x()), toDouble(q.y()), toDouble(q.z()));
}

inline btQuaternion toBt(const Eigen::Quaterniond& q) {
  return btQuaternion(toBtScalar(q.x()), toBtScalar(q.y()), toBtScalar(q.z()), toBtScalar(q.w()));
}

inline Eigen::Matrix3d toEigen(const btMatrix3x3& m) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      out(r, c) = toDouble(m[r][c]);
  return out;
}

/// basis * v, in double (btMatrix3x3 * btVector3).
inline Eigen::Vector3d worldDirection(const btMatrix3x3& basis, const Eigen::Vector3d& v) {
  Eigen::Vector3d out;
  for (int r = 0; r < 3; ++r)
    out[r] =
        toDouble(basis[r][0]) * v[0] + toDouble(basis[r][1]) * v[1] + toDouble(basis[r][2]) * v[2];
  return out;
}

/// basis^T * v, in double (btMatrix3x3::transpose() * btVector3).
inline Eigen::Vector3d localDirection(const btMatrix3x3& basis, const Eigen::Vector3d& v) {
  Eigen::Vector3d out;
  for (int c = 0; c < 3; ++c)
    out[c] =
        toDouble(basis[0][c]) * v[0] + toDouble(basis[1][c]) * v[1] + toDouble(basis[2][c]) * v[2];
  return out;
}

/// A point of the transform's frame in world coordinates, in double (btTransform * btVector3).
inline Eigen::Vector3d worldPoint(const btTransform& t, const Eigen::Vector3d& local) {
  return worldDirection(t.getBasis(), local) + toEigen(t.getOrigin());
}

/// A world point in the transform's frame, in double (btTransform::invXform).
inline Eigen::Vector3d localPoint(const btTransform& t, const Eigen::Vector3d& world) {
  return localDirection(t.getBasis(), world - toEigen(t.getOrigin()));
}

}  // namespace torsion
