#pragma once
// A group of nodes carried rigidly by a moving frame: fixed nodes (a frame that never moves),
// a scripted rigid motion of an end of the body, and the hand plane's grabbed patch all are one.
// Each step, node l is prescribed to R(t+dt) p_hat_l + O(t+dt) in position and velocity through the
// solver's projection; the implicit solve sees it (positions are never snapped afterwards).

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "torsion/constraints/frame.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/node_constraints.h"

namespace torsion {

/// Force and torque (N, N m).
struct Wrench {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
};

class CarriedNodes {
 public:
  /// Captures p_hat = R^T (x - O) for each node at its current position, with `motion` evaluated
  /// at `time`.
  CarriedNodes(std::string name, std::vector<int> nodes, FrameMotion motion, const FemState& state,
               double time);
  /// A group as it was (checkpoints read back from bytes, bullet/checkpoint_io.h): `local` are
  /// the nodes' p_hat as localCoordinates() gave them.
  CarriedNodes(std::string name, std::vector<int> nodes, std::vector<Eigen::Vector3d> local,
               FrameMotion motion);

  const std::string& name() const { return name_; }
  const std::vector<int>& nodes() const { return nodes_; }
  const std::vector<Eigen::Vector3d>& localCoordinates() const { return local_; }
  Frame frameAt(double time) const { return motion_(time); }
  const FrameMotion& motion() const { return motion_; }
  /// Hands the group to another motion from the next prescribe() on (a program that drives a set
  /// the scene held): the nodes and their p_hat stay, so `motion` is the same kind of frame, the
  /// map from where the nodes were at construction to where they go.
  void setMotion(FrameMotion motion) { motion_ = std::move(motion); }

  /// Prescribes each node's velocity so it reaches R(t_next) p_hat + O(t_next) after dt.
  void prescribe(double time_next, double dt, const FemState& state,
                 NodeConstraints& constraints) const;

  /// The wrench the body exerts on the group: F = sum f_l, tau = sum (x_l - point) x f_l, for
  /// per-node forces `forces` (3n, e.g. ImplicitStepper::internalForces()).
  Wrench wrenchOn(const Eigen::VectorXd& forces, const FemState& state,
                  const Eigen::Vector3d& point) const;

 private:
  std::string name_;
  std::vector<int> nodes_;
  std::vector<Eigen::Vector3d> local_;
  FrameMotion motion_;
};

}  // namespace torsion
