#include "torsion/device/wrench_safety.h"

#include <cmath>

namespace torsion::device {

namespace {

double norm(const Vec3& v) {
  return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
}

Vec3 clampNorm(const Vec3& v, double max_norm) {
  const double n = norm(v);
  if (n <= max_norm) return v;
  const double scale = max_norm > 0 ? max_norm / n : 0.0;
  return {v.x * scale, v.y * scale, v.z * scale};
}

bool isFinite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

bool isFinite(const Wrench& wrench) {
  return isFinite(wrench.force) && isFinite(wrench.torque);
}

Wrench saturate(const Wrench& wrench, const DeviceLimits& limits) {
  if (!isFinite(wrench)) return Wrench{};
  return {clampNorm(wrench.force, limits.max_force), clampNorm(wrench.torque, limits.max_torque)};
}

}  // namespace torsion::device
