#include "simulated_arm.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace torsion::simulated {

namespace {

void multiply(const double a[4], const double b[4], double out[4]) {
  const double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  const double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  const double y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  const double z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
  out[0] = w, out[1] = x, out[2] = y, out[3] = z;
}

// Rotation vector (axis * angle, angle in [0, pi]) of a unit quaternion.
void rotationVector(const double q[4], double out[3]) {
  const double sign = q[0] < 0 ? -1 : 1;
  const double s = std::sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  const double angle = 2 * std::atan2(s, sign * q[0]);
  const double k = s > 1e-12 ? sign * angle / s : 2 * sign;
  for (int i = 0; i < 3; ++i)
    out[i] = k * q[i + 1];
}

double clampNorm(double v[3], double limit) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (n > limit && n > 0)
    for (int i = 0; i < 3; ++i)
      v[i] *= limit / n;
  return n;
}

}  // namespace

std::string SimulatedArmSettings::validate() const {
  if (!(device_mass > 0) || !(device_inertia > 0)) return "device_mass and device_inertia > 0";
  if (!(arm_mass >= 0) || !(arm_inertia >= 0)) return "arm_mass and arm_inertia >= 0";
  if (!(motor_bandwidth_hz > 0)) return "motor_bandwidth_hz must be > 0";
  if (!(max_force >= 0) || !(max_torque >= 0)) return "max_force and max_torque must be >= 0";
  if (!(delay >= 0 && delay <= 1)) return "delay must be in [0, 1] s";
  if (!(arm_stiffness >= 0) || !(arm_damping >= 0) || !(wrist_stiffness >= 0) ||
      !(wrist_damping >= 0))
    return "arm and wrist stiffness and damping must be >= 0";
  if (!(intent_time >= 0)) return "intent_time must be >= 0";
  if (!(substep > 0 && substep <= 1e-3)) return "substep must be in (0, 1e-3] s";
  return {};
}

std::string SimulatedArmSettings::parse(const std::string& config) {
  std::istringstream items(config);
  std::string item;
  while (std::getline(items, item, ',')) {
    if (item.empty()) continue;
    const size_t eq = item.find('=');
    if (eq == std::string::npos) return "'" + item + "': expected key=value";
    const std::string key = item.substr(0, eq);
    const std::string text = item.substr(eq + 1);
    if (key == "intent") {
      if (text == "hold")
        intent = Intent::kHold;
      else if (text == "twist")
        intent = Intent::kTwist;
      else if (text == "push")
        intent = Intent::kPush;
      else
        return "intent '" + text + "': expected hold, twist or push";
      continue;
    }
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
      return std::string(key).append(": '").append(text).append("' is not a number");
    double* field = nullptr;
    const std::pair<const char*, double*> fields[] = {{"device_mass", &device_mass},
                                                      {"device_inertia", &device_inertia},
                                                      {"motor_bandwidth_hz", &motor_bandwidth_hz},
                                                      {"max_force", &max_force},
                                                      {"max_torque", &max_torque},
                                                      {"delay", &delay},
                                                      {"arm_mass", &arm_mass},
                                                      {"arm_inertia", &arm_inertia},
                                                      {"arm_stiffness", &arm_stiffness},
                                                      {"arm_damping", &arm_damping},
                                                      {"wrist_stiffness", &wrist_stiffness},
                                                      {"wrist_damping", &wrist_damping},
                                                      {"wrist_tilt_damping", &wrist_tilt_damping},
                                                      {"intent_rate", &intent_rate},
                                                      {"intent_start", &intent_start},
                                                      {"intent_time", &intent_time},
                                                      {"grab_time", &grab_time},
                                                      {"release_time", &release_time},
                                                      {"substep", &substep}};
    for (const auto& [name, address] : fields)
      if (key == name) field = address;
    if (field == nullptr) return "unknown key '" + key + "'";
    *field = v;
  }
  return validate();
}

SimulatedArm::SimulatedArm(const SimulatedArmSettings& settings) : settings_(settings) {
  history_.push_back({0, state_});
}

double SimulatedArm::intentAt(double t) const {
  const double moving = std::clamp(t - settings_.intent_start, 0.0, settings_.intent_time);
  return settings_.intent == SimulatedArmSettings::Intent::kHold ? 0
                                                                 : settings_.intent_rate * moving;
}

void SimulatedArm::advance(double dt) {
  const SimulatedArmSettings& s = settings_;
  // Commands that have crossed the link are what the motors chase.
  while (!commands_.empty() && commands_.front().time + s.delay <= time_ + 1e-12) {
    std::copy(commands_.front().values, commands_.front().values + 6, command_);
    commands_.pop_front();
  }
  double target[6];
  std::copy(command_, command_ + 6, target);
  clampNorm(target, s.max_force);
  clampNorm(target + 3, s.max_torque);
  const double lag = 1 - std::exp(-2 * M_PI * s.motor_bandwidth_hz * dt);
  for (int i = 0; i < 6; ++i)
    motor_[i] += lag * (target[i] - motor_[i]);

  // The operator's pull toward the intent.
  const double goal = intentAt(time_);
  double intended_position[3] = {0, 0, 0};
  double intended_rotation[4] = {1, 0, 0, 0};
  if (s.intent == SimulatedArmSettings::Intent::kPush) intended_position[0] = goal;
  if (s.intent == SimulatedArmSettings::Intent::kTwist) {
    intended_rotation[0] = std::cos(goal / 2);
    intended_rotation[3] = std::sin(goal / 2);
  }
  const double conj[4] = {state_.orientation[0], -state_.orientation[1], -state_.orientation[2],
                          -state_.orientation[3]};
  double error_q[4], error[3];
  multiply(intended_rotation, conj, error_q);
  rotationVector(error_q, error);

  const double mass = s.device_mass + s.arm_mass;
  const double inertia = s.device_inertia + s.arm_inertia;
  for (int i = 0; i < 3; ++i) {
    const double force = motor_[i] + s.arm_stiffness * (intended_position[i] - state_.position[i]) -
                         s.arm_damping * state_.velocity[i];
    // About x and y the whole grip resists tilting the handle; about z the fingers twist it.
    const double damping =
        i < 2 && s.wrist_tilt_damping >= 0 ? s.wrist_tilt_damping : s.wrist_damping;
    const double torque =
        motor_[3 + i] + s.wrist_stiffness * error[i] - damping * state_.angular_velocity[i];
    state_.velocity[i] += dt * force / mass;
    state_.angular_velocity[i] += dt * torque / inertia;
    state_.position[i] += dt * state_.velocity[i];
  }
  // q <- exp(omega dt) q, omega in the base frame.
  const double* w = state_.angular_velocity;
  const double angle = dt * std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  if (angle > 0) {
    const double k = std::sin(angle / 2) / (angle / dt);
    const double step[4] = {std::cos(angle / 2), k * w[0], k * w[1], k * w[2]};
    double q[4];
    multiply(step, state_.orientation, q);
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int i = 0; i < 4; ++i)
      state_.orientation[i] = q[i] / n;
  }
  time_ += dt;
  auto held = [&](double at) { return at >= 0 && time_ >= at && time_ < at + 0.05; };
  state_.buttons = (held(s.grab_time) ? 1u : 0u) | (held(s.release_time) ? 2u : 0u);
}

ArmState SimulatedArm::read(double time) {
  while (time_ < time - 1e-12) {
    advance(std::min(settings_.substep, time - time_));
    history_.push_back({time_, state_});
  }
  // Keep what a delayed reading may still ask for.
  while (history_.size() > 1 && history_[1].time <= time_ - settings_.delay + 1e-12)
    history_.pop_front();
  return history_.front().state;
}

void SimulatedArm::write(const double wrench[6]) {
  Timed t{time_, {}};
  std::copy(wrench, wrench + 6, t.values);
  commands_.push_back(t);
}

}  // namespace torsion::simulated
