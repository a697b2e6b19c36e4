#pragma once
// A force-feedback device held by a simulated operator, for tests and for the example plug-in
// (docs/haptic-devices.md, "The example: a simulated device and operator"). One rigid body
// carries the device's moving mass and the operator's arm (the hand holds the handle firmly):
//   (m_d + m_a) a = F_motor + K_a (x_intent - x) - B_a v
//   (I_d + I_a) alpha = tau_motor + K_w theta(q_intent q^-1) - B_w omega
// The operator is a spring-damper pulling toward a scripted intent (a twist about z, a push
// along x, or holding still), the arm's own mass added to the device's. The motors render the
// commanded wrench through a first-order lag of `motor_bandwidth_hz`, saturated at the device's
// limits. A one-way `delay` sits on the link both ways: a reading returns the pose of `delay`
// ago, a written wrench reaches the motors `delay` later. Integration: semi-implicit Euler in
// substeps of at most `substep` seconds. Plain C++, no dependency, deterministic.

#include <deque>
#include <string>

namespace torsion::simulated {

struct SimulatedArmSettings {
  // device
  double device_mass = 0.3;         ///< kg, moving mass of the handle and links
  double device_inertia = 5e-4;     ///< kg m^2, about each axis
  double motor_bandwidth_hz = 200;  ///< Hz, first-order lag from command to motor wrench
  double max_force = 10;            ///< N
  double max_torque = 1;            ///< N m
  double delay = 0;                 ///< s, one way, each direction (0-0.05 in the tests)
  // operator
  double arm_mass = 1.0;       ///< kg
  double arm_inertia = 5e-3;   ///< kg m^2
  double arm_stiffness = 300;  ///< N/m toward the intended position
  double arm_damping = 8;      ///< N s/m
  double wrist_stiffness = 3;  ///< N m/rad toward the intended orientation
  double wrist_damping = 0.1;  ///< N m s/rad
  /// N m s/rad about x and y (tilting the handle); negative: wrist_damping about all three axes
  double wrist_tilt_damping = -1;
  // intent
  enum class Intent { kHold, kTwist, kPush } intent = Intent::kTwist;
  double intent_rate = 0.5;   ///< rad/s (twist about z) or m/s (push along x)
  double intent_start = 0.1;  ///< s, the motion starts
  double intent_time = 0.4;   ///< s the motion lasts; then the intent holds where it got to
  double grab_time = 0.05;    ///< s, button 1 pressed (held 50 ms); negative: never
  double release_time = -1;   ///< s, button 2 pressed (held 50 ms); negative: never
  double substep = 1e-4;      ///< s, integration step

  /// Empty when valid, else the message naming the field.
  std::string validate() const;
  /// Sets fields from "key=value,key=value" (keys as the field names; intent=hold|twist|push).
  /// Empty when every key was known and every value a number, else the message.
  std::string parse(const std::string& config);
};

struct ArmState {
  double position[3] = {0, 0, 0};          ///< m
  double orientation[4] = {1, 0, 0, 0};    ///< w x y z
  double velocity[3] = {0, 0, 0};          ///< m/s
  double angular_velocity[3] = {0, 0, 0};  ///< rad/s, base frame
  unsigned buttons = 0;
};

class SimulatedArm {
 public:
  explicit SimulatedArm(const SimulatedArmSettings& settings);

  /// Advances to `time` (s; earlier times are ignored) and returns what the device's link
  /// reports then: the state of `delay` ago.
  ArmState read(double time);
  /// Commands a wrench (fx fy fz tx ty tz, N and N m) at the current time; the motors see it
  /// `delay` later, through their lag and limits.
  void write(const double wrench[6]);

  /// The true state now (no delay).
  const ArmState& state() const { return state_; }
  double time() const { return time_; }
  /// The wrench the motors apply now (after delay, lag and limits).
  const double* motorWrench() const { return motor_; }
  /// The operator's intended rotation angle about z (twist) or position along x (push) at t.
  double intentAt(double t) const;
  const SimulatedArmSettings& settings() const { return settings_; }

 private:
  void advance(double dt);

  SimulatedArmSettings settings_;
  double time_ = 0;
  ArmState state_;
  double motor_[6] = {};
  struct Timed {
    double time;
    double values[6];
  };
  std::deque<Timed> commands_;  // written wrenches not yet due at the motors
  double command_[6] = {};      // the wrench the motors are chasing
  struct Past {
    double time;
    ArmState state;
  };
  std::deque<Past> history_;  // states within `delay` of now, for delayed readings
};

}  // namespace torsion::simulated
