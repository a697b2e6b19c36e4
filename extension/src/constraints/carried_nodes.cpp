#include "torsion/constraints/carried_nodes.h"

namespace torsion {

CarriedNodes::CarriedNodes(std::string name, std::vector<int> nodes, FrameMotion motion,
                           const FemState& state, double time)
    : name_(std::move(name)), nodes_(std::move(nodes)), motion_(std::move(motion)) {
  const Frame frame = motion_(time);
  local_.reserve(nodes_.size());
  for (int node : nodes_)
    local_.push_back(frame.toLocal(state.position(node)));
}

CarriedNodes::CarriedNodes(std::string name, std::vector<int> nodes,
                           std::vector<Eigen::Vector3d> local, FrameMotion motion)
    : name_(std::move(name)),
      nodes_(std::move(nodes)),
      local_(std::move(local)),
      motion_(std::move(motion)) {}

void CarriedNodes::prescribe(double time_next, double dt, const FemState& state,
                             NodeConstraints& constraints) const {
  const Frame frame = motion_(time_next);
  for (size_t k = 0; k < nodes_.size(); ++k) {
    const Eigen::Vector3d target = frame.toWorld(local_[k]);
    constraints.prescribeVelocity(nodes_[k], (target - state.position(nodes_[k])) / dt);
  }
}

Wrench CarriedNodes::wrenchOn(const Eigen::VectorXd& forces, const FemState& state,
                              const Eigen::Vector3d& point) const {
  Wrench w;
  for (int node : nodes_) {
    const Eigen::Vector3d f = forces.segment<3>(3 * node);
    w.force += f;
    w.torque += (state.position(node) - point).cross(f);
  }
  return w;
}

}  // namespace torsion
