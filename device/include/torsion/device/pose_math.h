#pragma once
// The little rigid-body algebra the device layer needs, on its own plain types (it knows nothing
// of Eigen, Bullet or GL). Rotation vectors are axis * angle, in radians.

#include "torsion/device/device_types.h"

namespace torsion::device {

Vec3 operator+(const Vec3& a, const Vec3& b);
Vec3 operator-(const Vec3& a, const Vec3& b);
Vec3 operator*(double s, const Vec3& v);
double dot(const Vec3& a, const Vec3& b);
Vec3 cross(const Vec3& a, const Vec3& b);
double norm(const Vec3& v);
bool isFinite(const Vec3& v);
/// v scaled down to norm `limit` where it is longer, its direction kept (v itself, bit for bit,
/// where it is not). The safe answer elsewhere: zero for a limit that is not positive (0,
/// negative or NaN) and for a vector that is not finite. The one limiter of the device layer's
/// force, torque and rate limits.
Vec3 clampNorm(const Vec3& v, double limit);
/// `from` moved toward `to` by at most `step` (as a vector): `to` itself, exactly, when it lies
/// within `step` (a 1e-9 relative slack, so rounding over hundreds of ticks cannot leave a
/// hair short of it); `from` when the move is not finite or `step` is not positive.
Vec3 approach(const Vec3& from, const Vec3& to, double step);

Quat operator*(const Quat& a, const Quat& b);
Quat conjugate(const Quat& q);
Quat normalized(const Quat& q);
Vec3 rotate(const Quat& q, const Vec3& v);
/// The rotation by |v| radians about v / |v| (identity for v = 0).
Quat fromRotationVector(const Vec3& v);
/// The inverse of fromRotationVector, angle in [0, pi].
Vec3 toRotationVector(const Quat& q);
/// Spherical interpolation along the shorter arc, u in [0, 1].
Quat slerp(const Quat& a, const Quat& b, double u);

/// The small motion that takes `from` to `to`, as 6 numbers: translation (m) then rotation
/// vector of to * from^-1 (rad), both in the fixed (device) frame.
void poseDifference(const Pose& from, const Pose& to, double out[6]);

Wrench operator+(const Wrench& a, const Wrench& b);
Wrench operator*(double s, const Wrench& w);

}  // namespace torsion::device
