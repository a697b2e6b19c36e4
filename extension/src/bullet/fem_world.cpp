#include "torsion/bullet/fem_world.h"

#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>

#include <algorithm>

#include "torsion/bt_conversions.h"

namespace torsion {

Status WorldSettings::validate() const {
  if (!gravity.allFinite()) return Error{"world: gravity must be finite"};
  return solver.validate();
}

FemWorld::FemWorld(const WorldSettings& settings)
    : settings_(settings),
      collision_configuration_(std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>()),
      dispatcher_(std::make_unique<btCollisionDispatcher>(collision_configuration_.get())),
      broadphase_(std::make_unique<btDbvtBroadphase>()),
      constraint_solver_(std::make_unique<btSequentialImpulseConstraintSolver>()),
      soft_solver_(std::make_unique<FemSoftBodySolver>(settings.solver)) {
  world_ = std::make_unique<btSoftRigidDynamicsWorld>(
      dispatcher_.get(), broadphase_.get(), constraint_solver_.get(),
      collision_configuration_.get(), soft_solver_.get());
  const btVector3 g = toBt(settings.gravity);
  world_->setGravity(g);
  btSoftBodyWorldInfo& info = world_->getWorldInfo();
  info.m_gravity = g;
  info.m_sparsesdf.Initialize();
  Status attached = soft_solver_->bind(*world_);
  (void)attached;  // cannot fail: the world was built with this solver a line above
}

FemWorld::~FemWorld() {
  for (btRigidBody* rigid : rigid_bodies_) {
    if (std::find(tracked_.begin(), tracked_.end(), rigid) != tracked_.end()) continue;
    world_->removeRigidBody(rigid);
    delete rigid;
  }
  world_.reset();  // before the solver, which Bullet calls until then
}

Result<FemBody*> FemWorld::addBody(const std::string& name, const TetMesh& mesh,
                                   const Material& material, const Frame& pose, ElementKind element,
                                   NodeNumbering numbering) {
  return soft_solver_->addBody(name, mesh, material, pose, element, numbering);
}

btRigidBody* FemWorld::addRigidBody(std::unique_ptr<btCollisionShape> shape, double mass,
                                    const btTransform& transform) {
  btVector3 inertia(0, 0, 0);
  if (mass > 0) shape->calculateLocalInertia(toBtScalar(mass), inertia);
  auto motion = std::make_unique<btDefaultMotionState>(transform);
  btRigidBody::btRigidBodyConstructionInfo info(toBtScalar(mass), motion.get(), shape.get(),
                                                inertia);
  auto* rigid = new btRigidBody(info);
  world_->addRigidBody(rigid);
  shapes_.push_back(std::move(shape));
  motion_states_.push_back(std::move(motion));
  owned_.push_back(rigid);
  rigid_bodies_.push_back(rigid);
  return rigid;
}

WorldCheckpoint FemWorld::checkpoint() {
  WorldCheckpoint c;
  c.fem = soft_solver_->checkpoint();
  for (const btRigidBody* rigid : rigid_bodies_) {
    c.rigid.push_back(WorldCheckpoint::RigidState{
        rigid->getWorldTransform(), rigid->getLinearVelocity(), rigid->getAngularVelocity()});
  }
  return c;
}

Status FemWorld::restore(const WorldCheckpoint& c) {
  if (c.rigid.size() != rigid_bodies_.size()) {
    return Error{"restore: the world has " + std::to_string(rigid_bodies_.size()) +
                 " rigid bodies, the checkpoint " + std::to_string(c.rigid.size())};
  }
  if (Status restored = soft_solver_->restore(c.fem); !restored) return restored;
  for (size_t k = 0; k < rigid_bodies_.size(); ++k) {
    btRigidBody* rigid = rigid_bodies_[k];
    const WorldCheckpoint::RigidState& r = c.rigid[k];
    rigid->setWorldTransform(r.pose);
    rigid->setInterpolationWorldTransform(r.pose);
    rigid->setLinearVelocity(r.linear_velocity);
    rigid->setAngularVelocity(r.angular_velocity);
    rigid->setInterpolationLinearVelocity(r.linear_velocity);
    rigid->setInterpolationAngularVelocity(r.angular_velocity);
    rigid->clearForces();
    if (rigid->getMotionState() != nullptr) rigid->getMotionState()->setWorldTransform(r.pose);
  }
  return Ok{};
}

Status FemWorld::removeRigidBody(btRigidBody* body) {
  const auto listed = std::find(rigid_bodies_.begin(), rigid_bodies_.end(), body);
  if (body == nullptr || listed == rigid_bodies_.end())
    return Error{"remove rigid body: not a rigid body of this world"};
  for (const auto& fem : bodies()) {
    const std::vector<int> anchors = fem->anchorsOn(body);
    if (anchors.empty()) continue;
    std::string ids;
    for (int id : anchors)
      ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    return Error{"remove rigid body: FEM body '" + fem->name() + "' anchors nodes to it (anchor" +
                 (anchors.size() > 1 ? "s " : " ") + ids + "); remove the anchors first"};
  }
  if (body->getNumConstraintRefs() > 0) {
    return Error{"remove rigid body: " + std::to_string(body->getNumConstraintRefs()) +
                 " Bullet constraint(s) refer to it; remove them from the world first"};
  }
  world_->removeRigidBody(body);
  for (const auto& fem : bodies())
    fem->forgetObject(body);
  rigid_bodies_.erase(listed);
  const auto tracked = std::find(tracked_.begin(), tracked_.end(), body);
  if (tracked != tracked_.end()) {
    tracked_.erase(tracked);
    return Ok{};
  }
  // Its shape and motion state go with it (a scene's script may have replaced the motion state
  // the body was made with: the one made here is the one freed here).
  const auto owned = std::find(owned_.begin(), owned_.end(), body);
  const auto k = owned - owned_.begin();
  delete body;
  owned_.erase(owned);
  shapes_.erase(shapes_.begin() + k);
  motion_states_.erase(motion_states_.begin() + k);
  return Ok{};
}

void FemWorld::trackRigidBody(btRigidBody* body) {
  rigid_bodies_.push_back(body);
  tracked_.push_back(body);
}

double FemWorld::time() const {
  return soft_solver_->time();
}

int FemWorld::stepCount() const {
  return static_cast<int>(soft_solver_->stepCount());
}

const std::vector<std::unique_ptr<FemBody>>& FemWorld::bodies() const {
  return soft_solver_->bodies();
}

FemBody* FemWorld::body(const std::string& name) const {
  return soft_solver_->body(name);
}

WorldStepReport FemWorld::step() {
  WorldStepReport report;
  if (soft_solver_->status().ok) {
    // One variable step: Bullet makes exactly one internal substep of dt, the FEM step.
    world_->stepSimulation(static_cast<btScalar>(settings_.solver.time_step), 0);
  }
  report.step = stepCount();
  const FemSolverStatus& status = soft_solver_->status();
  // The solver's status covers the rigid bodies too (a NaN or overflowing one fails the step).
  if (!status.ok) {
    report.ok = false;
    report.step = static_cast<int>(status.failed_step);
    report.message = status.message;
  }
  return report;
}

Status FemWorld::setSolverSettings(const SolverSettings& solver) {
  if (Status applied = soft_solver_->setSolverSettings(solver); !applied) return applied;
  settings_.solver = solver;
  return Ok{};
}

Status FemWorld::setGravity(const Eigen::Vector3d& gravity) {
  const btVector3 g = toBt(gravity);
  if (!gravity.allFinite() || !toEigen(g).allFinite())
    return Error{"world: gravity must be finite"};
  settings_.gravity = gravity;
  // btDiscreteDynamicsWorld::setGravity skips bodies asleep, which would wake up under the old
  // gravity: every dynamic body gets it here, and wakes to feel it.
  world_->setGravity(g);
  world_->getWorldInfo().m_gravity = g;
  btCollisionObjectArray& objects = world_->getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    btRigidBody* rigid = btRigidBody::upcast(objects[i]);
    if (rigid == nullptr || rigid->isStaticOrKinematicObject() ||
        (rigid->getFlags() & BT_DISABLE_WORLD_GRAVITY) != 0) {
      continue;
    }
    rigid->setGravity(g);
    rigid->activate(true);
  }
  return Ok{};
}

}  // namespace torsion
