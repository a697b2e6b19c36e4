#include "twist_protocol.h"

#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "torsion/analysis/twist_profile.h"

namespace torsion::bench {

double TwistProtocol::angle(double t) const {
  if (oscillation_hz > 0) return final_angle * std::sin(2 * 3.141592653589793 * oscillation_hz * t);
  const double ramp = ramp_steps * time_step;
  return final_angle * std::min(t / ramp, 1.0);
}

TwistScene classifyNodes(const TetMesh& mesh) {
  TwistScene scene;
  scene.z_min = mesh.boundsMin().z();
  scene.z_max = mesh.boundsMax().z();
  const double tol = 1e-6;
  scene.roles.assign(static_cast<size_t>(mesh.nodeCount()), NodeRole::kFree);
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    const double z = mesh.restPositions()[static_cast<size_t>(i)].z();
    NodeRole& role = scene.roles[static_cast<size_t>(i)];
    if (z < tol) {
      role = NodeRole::kFixed;
      ++scene.fixed;
    } else if (z > scene.z_max - tol) {
      role = NodeRole::kDriven;
      ++scene.driven;
    }
  }
  return scene;
}

double drivenTorqueZ(const Eigen::VectorXd& positions, const Eigen::VectorXd& internal_forces,
                     const std::vector<int>& driven) {
  double torque = 0;
  for (int i : driven) {
    const Eigen::Vector3d x = positions.segment<3>(3 * i);
    const Eigen::Vector3d f = internal_forces.segment<3>(3 * i);
    torque -= x.x() * f.y() - x.y() * f.x();
  }
  return torque;
}

double stVenantTorque(const TwistProtocol& protocol, double radius, double length, double angle) {
  const double mu = protocol.youngs_modulus / (2 * (1 + protocol.poisson_ratio));
  const double polar_moment = 3.141592653589793 / 2 * std::pow(radius, 4);
  return mu * polar_moment * angle / length;
}

Eigen::Vector3d turnedAboutZ(const Eigen::Vector3d& rest, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * rest.x() - s * rest.y(), s * rest.x() + c * rest.y(), rest.z()};
}

const char* toString(RunStatus status) {
  switch (status) {
    case RunStatus::kOk:
      return "ok";
    case RunStatus::kNonFinite:
      return "nan";
    case RunStatus::kBlowUp:
      return "blowup";
    case RunStatus::kSolverFailed:
      return "solver-failed";
    case RunStatus::kSetupFailed:
      return "setup-failed";
  }
  return "?";
}

void measureTwist(const TwistProtocol& protocol, const TetMesh& mesh, const TwistScene& scene,
                  const Eigen::VectorXd& positions, TwistResult& result) {
  const double length = scene.length();
  result.slice_z.clear();
  for (double f : protocol.slice_fractions)
    result.slice_z.push_back(f * length);
  const double final_angle = protocol.angle(protocol.total_steps * protocol.time_step);
  const std::vector<SliceRotation> profile =
      twistProfile(mesh.restPositions(), positions, result.slice_z, protocol.slice_half_thickness);
  result.slice_angle.clear();
  result.slice_expected.clear();
  result.slice_error.clear();
  result.slice_nodes.clear();
  for (const SliceRotation& s : profile) {
    const double expected = final_angle * s.z / length;
    result.slice_angle.push_back(s.angle);
    result.slice_expected.push_back(expected);
    result.slice_error.push_back(std::abs(s.angle - expected) / std::abs(expected));
    result.slice_nodes.push_back(s.nodes);
  }
  // Tip: the driven nodes themselves (a check that the prescription was followed).
  double max_error = 0;
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    if (scene.roles[static_cast<size_t>(i)] != NodeRole::kDriven) continue;
    const Eigen::Vector3d target =
        turnedAboutZ(mesh.restPositions()[static_cast<size_t>(i)], final_angle);
    max_error = std::max(max_error, (positions.segment<3>(3 * i) - target).norm());
  }
  result.driven_error = max_error;
  const std::vector<SliceRotation> tip =
      twistProfile(mesh.restPositions(), positions, {length}, 1e-6);
  result.tip_angle = tip.front().angle;
}

long peakRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;  // kB on Linux
}

double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double position = q * static_cast<double>(values.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(position));
  const size_t above = std::min(below + 1, values.size() - 1);
  const double fraction = position - static_cast<double>(below);
  return values[below] + fraction * (values[above] - values[below]);
}

}  // namespace torsion::bench
