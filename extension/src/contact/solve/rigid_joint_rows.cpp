#include "torsion/contact/solve/rigid_joint_rows.h"

#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "torsion/bt_conversions.h"
#include "torsion/contact/solve/node_contact_rows.h"

namespace torsion::sap {

namespace {

// One row of Bullet's joint-row layout (btConstraintInfo2 writes through strided pointers):
// the four Jacobian parts as btVector3 (aligned as Bullet's btSolverConstraint's), then the
// scalars, the whole a multiple of btScalar.
struct alignas(16) BulletJointRow {
  btVector3 j1_linear, j1_angular, j2_linear, j2_angular;
  btScalar rhs, cfm, lower, upper;
};
static_assert(sizeof(BulletJointRow) % sizeof(btScalar) == 0);

// A body put back at its step-start pose and twist for the joint's getInfo calls, restored when
// this goes.
class StartState {
 public:
  StartState(btRigidBody& body, const btTransform& pose, const std::optional<Vector6d>& twist)
      : body_(body),
        pose_(body.getWorldTransform()),
        linear_(body.getLinearVelocity()),
        angular_(body.getAngularVelocity()) {
    body_.setWorldTransform(pose);
    if (twist) {
      body_.setLinearVelocity(toBt(Eigen::Vector3d(twist->head<3>())));
      body_.setAngularVelocity(toBt(Eigen::Vector3d(twist->tail<3>())));
    }
  }
  ~StartState() {
    body_.setWorldTransform(pose_);
    body_.setLinearVelocity(linear_);
    body_.setAngularVelocity(angular_);
  }
  StartState(const StartState&) = delete;
  StartState& operator=(const StartState&) = delete;

 private:
  btRigidBody& body_;
  btTransform pose_;
  btVector3 linear_, angular_;
};

int groupIndex(const RigidContactGroup& group, const btRigidBody& body) {
  const auto found = std::find(group.bodies.begin(), group.bodies.end(), &body);
  return found == group.bodies.end() ? -1 : static_cast<int>(found - group.bodies.begin());
}

Vector6d twistOf(const btRigidBody& body) {
  return (Vector6d() << toEigen(body.getLinearVelocity()), toEigen(body.getAngularVelocity()))
      .finished();
}

// Bullet's rows of `joint` at the bodies' present state (convertJoint's call sequence).
std::vector<BulletJointRow> bulletRows(btTypedConstraint& joint, const JointLedger& ledger,
                                       double dt) {
  joint.buildJacobian();
  btTypedConstraint::btConstraintInfo1 info1;
  joint.getInfo1(&info1);
  std::vector<BulletJointRow> rows(static_cast<std::size_t>(info1.m_numConstraintRows));
  if (rows.empty()) return rows;
  for (BulletJointRow& r : rows) {
    r.j1_linear.setZero();
    r.j1_angular.setZero();
    r.j2_linear.setZero();
    r.j2_angular.setZero();
    r.rhs = 0;
    r.cfm = static_cast<btScalar>(ledger.globalCfm());
    r.lower = -SIMD_INFINITY;
    r.upper = SIMD_INFINITY;
  }
  btTypedConstraint::btConstraintInfo2 info2;
  info2.fps = static_cast<btScalar>(1 / dt);
  info2.erp = static_cast<btScalar>(ledger.erp());
  info2.m_J1linearAxis = rows[0].j1_linear;
  info2.m_J1angularAxis = rows[0].j1_angular;
  info2.m_J2linearAxis = rows[0].j2_linear;
  info2.m_J2angularAxis = rows[0].j2_angular;
  info2.rowskip = static_cast<int>(sizeof(BulletJointRow) / sizeof(btScalar));
  info2.m_constraintError = &rows[0].rhs;
  info2.cfm = &rows[0].cfm;
  info2.m_lowerLimit = &rows[0].lower;
  info2.m_upperLimit = &rows[0].upper;
  info2.m_numIterations = 10;
  info2.m_damping = static_cast<btScalar>(ledger.damping());
  joint.getInfo2(&info2);
  return rows;
}

Vector6d stacked(const btVector3& linear, const btVector3& angular) {
  return (Vector6d() << toEigen(linear), toEigen(angular)).finished();
}

}  // namespace

void addJointRows(RigidContactGroup& group, const JointLedger& ledger, const StartPose& start_pose,
                  double dt) {
  for (btTypedConstraint* joint : ledger.joints()) {
    btRigidBody& a = joint->getRigidBodyA();
    btRigidBody& b = joint->getRigidBodyB();
    const int body_a = groupIndex(group, a);
    const int body_b = groupIndex(group, b);
    if (body_a < 0 && body_b < 0) continue;
    group.joints.push_back(joint);
    std::vector<BulletJointRow> rows;
    {
      const StartState start_a(a, start_pose(a), ledger.startTwist(a));
      const StartState start_b(b, start_pose(b), ledger.startTwist(b));
      rows = bulletRows(*joint, ledger, dt);
    }
    const double breaking = static_cast<double>(joint->getBreakingImpulseThreshold());
    for (const BulletJointRow& r : rows) {
      RigidJointRow row;
      row.joint = joint;
      row.body_a = body_a;
      row.body_b = body_b;
      row.jacobian_a = stacked(r.j1_linear, r.j1_angular);
      row.jacobian_b = stacked(r.j2_linear, r.j2_angular);
      if (body_a < 0) row.prescribed_velocity += row.jacobian_a.dot(twistOf(a));
      if (body_b < 0) row.prescribed_velocity += row.jacobian_b.dot(twistOf(b));
      // Bullet's convertJoint: the target is J v = rhs, with its damping on the velocity part.
      row.target_velocity = toDouble(r.rhs);
      row.lower = std::max(toDouble(r.lower), -breaking);
      row.upper = std::min(toDouble(r.upper), breaking);
      row.cfm = std::max(0.0, toDouble(r.cfm));
      group.joint_rows.push_back(row);
    }
  }
}

void addRigidJointRows(NodeContactIsland& island, const RigidContactGroup& group,
                       const std::vector<int>& group_body) {
  island.row_face.resize(island.rows.size(), -1);
  island.row_rigid.resize(island.rows.size(), -1);
  island.row_joint.resize(island.rows.size(), -1);
  for (std::size_t i = 0; i < group.joint_rows.size(); ++i) {
    const RigidJointRow& j = group.joint_rows[i];
    ContactRow row;
    row.kind = RowKind::kJoint;
    for (const auto& [body, jacobian] :
         {std::pair{j.body_a, j.jacobian_a}, std::pair{j.body_b, j.jacobian_b}}) {
      if (body < 0) continue;
      ContactTerm term;
      term.body = group_body[static_cast<std::size_t>(body)];
      term.first_dof = 0;
      term.block = TermBlock::Zero(3, 6);
      term.block.row(2) = jacobian.transpose();
      row.terms.push_back(std::move(term));
    }
    if (row.terms.empty()) continue;  // cannot happen: a joint row has a group body
    row.velocity_offset(2) = j.prescribed_velocity;
    row.target_velocity = j.target_velocity;
    row.lower = std::min(0.0, j.lower);
    row.upper = std::max(0.0, j.upper);
    row.relative_compliance = j.cfm;
    island.rows.push_back(std::move(row));
    island.row_contact.push_back(-1);
    island.row_face.push_back(-1);
    island.row_rigid.push_back(-1);
    island.row_joint.push_back(static_cast<int>(i));
  }
}

std::vector<double> jointRowImpulses(const NodeContactIsland& island,
                                     const RigidContactGroup& group, const SapReport& report) {
  std::vector<double> lambda(group.joint_rows.size(), 0.0);
  for (std::size_t r = 0; r < island.row_joint.size(); ++r) {
    if (island.row_joint[r] >= 0)
      lambda[static_cast<std::size_t>(island.row_joint[r])] = report.impulses[r].z();
  }
  return lambda;
}

void writeBackJointImpulses(const RigidContactGroup& group, const std::vector<double>& lambda,
                            JointLedger& ledger, double dt) {
  if (lambda.size() != group.joint_rows.size()) return;  // no solve this step
  std::vector<Vector6d> on_body(group.bodies.size(), Vector6d::Zero());
  for (btTypedConstraint* joint : group.joints) {
    if (btJointFeedback* feedback = joint->getJointFeedback()) {
      feedback->m_appliedForceBodyA.setZero();
      feedback->m_appliedTorqueBodyA.setZero();
      feedback->m_appliedForceBodyB.setZero();
      feedback->m_appliedTorqueBodyB.setZero();
    }
  }
  for (std::size_t i = 0; i < group.joint_rows.size(); ++i) {
    const RigidJointRow& row = group.joint_rows[i];
    const Vector6d on_a = lambda[i] * row.jacobian_a;
    const Vector6d on_b = lambda[i] * row.jacobian_b;
    if (row.body_a >= 0) on_body[static_cast<std::size_t>(row.body_a)] += on_a;
    if (row.body_b >= 0) on_body[static_cast<std::size_t>(row.body_b)] += on_b;
    btTypedConstraint& joint = *row.joint;
    if (btJointFeedback* feedback = joint.getJointFeedback()) {
      feedback->m_appliedForceBodyA += toBt(Eigen::Vector3d(on_a.head<3>() / dt));
      feedback->m_appliedTorqueBodyA += toBt(Eigen::Vector3d(on_a.tail<3>() / dt));
      feedback->m_appliedForceBodyB += toBt(Eigen::Vector3d(on_b.head<3>() / dt));
      feedback->m_appliedTorqueBodyB += toBt(Eigen::Vector3d(on_b.tail<3>() / dt));
    }
    joint.internalSetAppliedImpulse(static_cast<btScalar>(lambda[i]));
    if (std::abs(lambda[i]) >= static_cast<double>(joint.getBreakingImpulseThreshold()))
      joint.setEnabled(false);
  }
  for (std::size_t b = 0; b < group.bodies.size(); ++b)
    ledger.setIslandImpulse(*group.bodies[b], on_body[b]);
}

}  // namespace torsion::sap
