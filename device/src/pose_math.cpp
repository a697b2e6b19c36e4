#include "torsion/device/pose_math.h"

#include <algorithm>
#include <cmath>

namespace torsion::device {

Vec3 operator+(const Vec3& a, const Vec3& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
Vec3 operator-(const Vec3& a, const Vec3& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Vec3 operator*(double s, const Vec3& v) {
  return {s * v.x, s * v.y, s * v.z};
}
double dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double norm(const Vec3& v) {
  return std::sqrt(dot(v, v));
}
bool isFinite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
Vec3 clampNorm(const Vec3& v, double limit) {
  if (!(limit > 0) || !isFinite(v)) return {};
  const double n = norm(v);
  if (n <= limit) return v;
  // n may overflow to infinity for finite components near the double range: then zero, too.
  const double s = limit / n;
  return {s * v.x, s * v.y, s * v.z};
}
Vec3 approach(const Vec3& from, const Vec3& to, double step) {
  const Vec3 delta = to - from;
  if (!(step > 0) || !isFinite(delta)) return from;
  if (norm(delta) <= step * (1 + 1e-9)) return to;
  return from + clampNorm(delta, step);
}

Quat operator*(const Quat& a, const Quat& b) {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
Quat conjugate(const Quat& q) {
  return {q.w, -q.x, -q.y, -q.z};
}
Quat normalized(const Quat& q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(n > 0) || !std::isfinite(n)) return Quat{};
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}
Vec3 rotate(const Quat& q, const Vec3& v) {
  const Quat r = q * Quat{0, v.x, v.y, v.z} * conjugate(q);
  return {r.x, r.y, r.z};
}
Quat fromRotationVector(const Vec3& v) {
  const double angle = norm(v);
  if (angle < 1e-12) return normalized(Quat{1, 0.5 * v.x, 0.5 * v.y, 0.5 * v.z});
  const double s = std::sin(0.5 * angle) / angle;
  return {std::cos(0.5 * angle), s * v.x, s * v.y, s * v.z};
}
Vec3 toRotationVector(const Quat& q_in) {
  Quat q = normalized(q_in);
  if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};  // the shorter of the two equivalent rotations
  const Vec3 axis{q.x, q.y, q.z};
  const double s = norm(axis);
  if (s < 1e-12) return 2.0 * axis;
  const double angle = 2 * std::atan2(s, q.w);
  return (angle / s) * axis;
}
Quat slerp(const Quat& a, const Quat& b_in, double u) {
  Quat b = b_in;
  if (a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z < 0) b = {-b.w, -b.x, -b.y, -b.z};
  const Vec3 step = toRotationVector(b * conjugate(a));
  return normalized(fromRotationVector(std::clamp(u, 0.0, 1.0) * step) * a);
}

void poseDifference(const Pose& from, const Pose& to, double out[6]) {
  const Vec3 t = to.position - from.position;
  const Vec3 r = toRotationVector(to.orientation * conjugate(from.orientation));
  out[0] = t.x, out[1] = t.y, out[2] = t.z;
  out[3] = r.x, out[4] = r.y, out[5] = r.z;
}

Wrench operator+(const Wrench& a, const Wrench& b) {
  return {a.force + b.force, a.torque + b.torque};
}
Wrench operator*(double s, const Wrench& w) {
  return {s * w.force, s * w.torque};
}

}  // namespace torsion::device
