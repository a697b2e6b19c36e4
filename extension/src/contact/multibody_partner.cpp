#include "torsion/contact/multibody_partner.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "torsion/bt_conversions.h"

namespace torsion {

namespace {

// A locked direction of a link (J M^-1 J^T singular there) yields within the solve as a body this
// many times the link's own mass and inertia would.
constexpr double kLockedMassFactor = 1e6;

btMultiBody& multibodyOf(const btMultiBodyLinkCollider& link) {
  return *link.m_multiBody;
}

// The link's own mass and largest principal inertia (the base's for link -1).
std::pair<double, double> ownInertia(const btMultiBodyLinkCollider& link) {
  const btMultiBody& body = *link.m_multiBody;
  const double mass = link.m_link < 0 ? body.getBaseMass() : body.getLinkMass(link.m_link);
  const btVector3 inertia =
      link.m_link < 0 ? body.getBaseInertia() : body.getLinkInertia(link.m_link);
  return {mass, std::max({inertia.x(), inertia.y(), inertia.z()})};
}

bool canMove(const btMultiBodyLinkCollider& link) {
  const btMultiBody& body = *link.m_multiBody;
  if (link.m_link < 0) return !body.isBaseStaticOrKinematic();
  return !body.isLinkAndAllAncestorsStaticOrKinematic(link.m_link);
}

}  // namespace

btMultiBodyLinkCollider* asMultibodyLink(const btCollisionObject* object) {
  if (object == nullptr || object->getInternalType() != btCollisionObject::CO_FEATHERSTONE_LINK)
    return nullptr;
  return const_cast<btMultiBodyLinkCollider*>(static_cast<const btMultiBodyLinkCollider*>(object));
}

Eigen::MatrixXd linkJacobian(const btMultiBodyLinkCollider& link, const Eigen::Vector3d& point) {
  const btMultiBody& body = *link.m_multiBody;
  const int columns = 6 + body.getNumDofs();
  Eigen::MatrixXd J(6, columns);
  btAlignedObjectArray<btScalar> row, scratch_r;
  btAlignedObjectArray<btVector3> scratch_v;
  btAlignedObjectArray<btMatrix3x3> scratch_m;
  row.resize(columns);
  const btVector3 zero(0, 0, 0);
  for (int a = 0; a < 6; ++a) {
    btVector3 axis(0, 0, 0);
    axis[a % 3] = 1;
    // Rows 0-2: the point's velocity along x, y, z; rows 3-5: the link's angular velocity.
    body.fillConstraintJacobianMultiDof(link.m_link, toBt(point), a < 3 ? zero : axis,
                                        a < 3 ? axis : zero, &row[0], scratch_r, scratch_v,
                                        scratch_m);
    for (int c = 0; c < columns; ++c)
      J(a, c) = row[c];
  }
  return J;
}

Eigen::VectorXd multibodyResponse(const btMultiBody& body, const Eigen::VectorXd& impulse) {
  const int columns = 6 + body.getNumDofs();
  btAlignedObjectArray<btScalar> in, out, scratch_r;
  btAlignedObjectArray<btVector3> scratch_v;
  in.resize(columns);
  out.resize(columns);
  for (int c = 0; c < columns; ++c)
    in[c] = toBtScalar(impulse[c]);
  body.calcAccelerationDeltasMultiDof(&in[0], &out[0], scratch_r, scratch_v);
  Eigen::VectorXd dv(columns);
  for (int c = 0; c < columns; ++c)
    dv[c] = out[c];
  // A fixed base takes no velocity (Bullet's own contacts rely on the same zero rows).
  if (body.isBaseStaticOrKinematic()) dv.head<6>().setZero();
  return dv;
}

void MultibodyLinks::recordStartPose(const btCollisionObject* object) {
  if (asMultibodyLink(object) != nullptr) start_poses_[object] = object->getWorldTransform();
}

std::optional<btTransform> MultibodyLinks::startPose(const btCollisionObject& object) const {
  const auto found = start_poses_.find(&object);
  if (found == start_poses_.end()) return std::nullopt;
  return found->second;
}

double MultibodyLinks::speedBound(const btCollisionObject& object, double radius) {
  const btMultiBodyLinkCollider* link = asMultibodyLink(&object);
  if (link == nullptr) return 0;
  const Eigen::Vector3d point = toEigen(object.getWorldTransform().getOrigin());
  const Eigen::MatrixXd J = linkJacobian(*link, point);
  const btMultiBody& body = *link->m_multiBody;
  Eigen::VectorXd qdot(J.cols());
  for (int c = 0; c < J.cols(); ++c)
    qdot[c] = body.getVelocityVector()[c];
  const Vector6d V = J * qdot;
  return V.head<3>().norm() + V.tail<3>().norm() * std::min(radius, 1e6);
}

bool MultibodyLinks::describe(const btCollisionObject* object, RigidPartner& partner) const {
  btMultiBodyLinkCollider* link = asMultibodyLink(object);
  if (link == nullptr) return false;
  btMultiBody& body = multibodyOf(*link);
  partner.link = link;
  const Eigen::MatrixXd J = linkJacobian(*link, partner.com);
  Eigen::VectorXd qdot(J.cols());
  for (int c = 0; c < J.cols(); ++c)
    qdot[c] = body.getVelocityVector()[c];
  partner.entry_velocity = J * qdot;
  partner.dynamic = canMove(*link);
  partner.velocity = partner.entry_velocity;
  if (!partner.dynamic) return true;
  // The other links' impulses of the last step, as this step's estimate of theirs.
  Eigen::VectorXd others = Eigen::VectorXd::Zero(J.cols());
  bool coupled = false;
  for (const LinkImpulse& l : last_impulses_) {
    if (l.link == link || l.link->m_multiBody != link->m_multiBody) continue;
    others += linkJacobian(*l.link, l.point).transpose() * l.impulse;
    coupled = true;
  }
  if (coupled) partner.entry_velocity += J * multibodyResponse(body, others);
  partner.velocity = partner.entry_velocity;

  // W = J M^-1 J^T, column by column from the response to each row of J.
  Matrix6d W;
  for (int a = 0; a < 6; ++a)
    W.col(a) = J * multibodyResponse(body, J.row(a).transpose());
  W = (0.5 * (W + W.transpose())).eval();
  const auto [mass, inertia] = ownInertia(*link);
  if (!(W.norm() > 0) || !(mass > 0)) {
    partner.dynamic = false;  // nothing behind the link can move: a prescribed surface
    return true;
  }
  Matrix6d regular = W;
  regular.topLeftCorner<3, 3>().diagonal().array() += 1 / (kLockedMassFactor * mass);
  regular.bottomRightCorner<3, 3>().diagonal().array() +=
      1 / (kLockedMassFactor * std::max(inertia, 1e-12 * mass));
  partner.inverse_mass_matrix = regular;
  partner.mass_matrix = regular.inverse();
  partner.mass = mass;
  return true;
}

void MultibodyLinks::applyImpulses(const std::vector<RigidPartner>& partners, double dt) {
  last_impulses_.clear();
  for (const RigidPartner& partner : partners) {
    if (partner.link == nullptr || !partner.dynamic || partner.impulse.isZero(0)) continue;
    last_impulses_.push_back({partner.link, partner.com, partner.impulse});
  }
  for (const LinkImpulse& l : last_impulses_)
    applyImpulse(l, dt);
}

void MultibodyLinks::applyImpulse(const LinkImpulse& l, double dt) {
  btMultiBody& body = multibodyOf(*l.link);
  // F = (force, torque about com) x dt; its generalised impulse is J^T F (virtual power).
  const Eigen::MatrixXd J = linkJacobian(*l.link, l.point);
  const Eigen::VectorXd dv = multibodyResponse(body, J.transpose() * l.impulse);
  btAlignedObjectArray<btScalar> delta;
  delta.resize(static_cast<int>(dv.size()));
  for (int c = 0; c < dv.size(); ++c)
    delta[c] = toBtScalar(dv[c]);
  body.applyDeltaVeeMultiDof(&delta[0], 1);
  // Bullet integrated the positions with the velocities before the impulse; take the step with
  // them (symplectic Euler with the contact impulse inside the step, as for rigid bodies).
  body.stepPositionsMultiDof(toBtScalar(dt), nullptr, &delta[0]);
  btAlignedObjectArray<btQuaternion> world_to_local;
  btAlignedObjectArray<btVector3> local_origin;
  world_to_local.resize(body.getNumLinks() + 1);
  local_origin.resize(body.getNumLinks() + 1);
  body.updateCollisionObjectWorldTransforms(world_to_local, local_origin);
  body.wakeUp();
}

}  // namespace torsion
