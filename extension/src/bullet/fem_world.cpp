#include "torsion/bullet/fem_world.h"

#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>

#include "torsion/bullet/bt_conversions.h"
#include "torsion/bullet/fem_soft_body_solver.h"

namespace torsion {

Status WorldSettings::validate() const {
  if (!gravity.allFinite()) return Error{"world: gravity must be finite"};
  return solver.validate();
}

FemWorld::FemWorld(const WorldSettings& settings)
    : settings_(settings),
      parallel_(settings.solver.threads),
      collision_configuration_(std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>()),
      dispatcher_(std::make_unique<btCollisionDispatcher>(collision_configuration_.get())),
      broadphase_(std::make_unique<btDbvtBroadphase>()),
      constraint_solver_(std::make_unique<btSequentialImpulseConstraintSolver>()),
      soft_solver_(std::make_unique<FemSoftBodySolver>(settings.solver.time_step)) {
  world_ = std::make_unique<btSoftRigidDynamicsWorld>(
      dispatcher_.get(), broadphase_.get(), constraint_solver_.get(),
      collision_configuration_.get(), soft_solver_.get());
  const btVector3 g = toBt(settings.gravity);
  world_->setGravity(g);
  btSoftBodyWorldInfo& info = world_->getWorldInfo();
  info.m_gravity = g;
  info.m_sparsesdf.Initialize();
}

FemWorld::~FemWorld() {
  for (auto& body : bodies_)
    world_->removeSoftBody(body->softBody());
  for (btRigidBody* rigid : rigid_bodies_) {
    world_->removeRigidBody(rigid);
    delete rigid;
  }
  world_.reset();
}

Result<FemBody*> FemWorld::addBody(const std::string& name, const TetMesh& mesh,
                                   const Material& material, const Frame& pose,
                                   ElementKind element) {
  if (body(name) != nullptr) return Error{"body '" + name + "' already exists"};
  std::vector<Eigen::Vector3d> placed = mesh.restPositions();
  for (Eigen::Vector3d& p : placed)
    p = pose.toWorld(p);
  auto placed_mesh = std::make_shared<const TetMesh>(std::move(placed), mesh.tets());
  Result<std::shared_ptr<const FemModel>> model = FemModel::create(placed_mesh, material, element);
  if (!model) return Error{"body '" + name + "': " + model.error().message};
  auto body = std::make_unique<FemBody>(name, std::move(model).value(), settings_.solver, parallel_,
                                        world_->getWorldInfo());
  body->setGravity(settings_.gravity);
  world_->addSoftBody(body->softBody());
  soft_solver_->registerBody(body.get());
  bodies_.push_back(std::move(body));
  return bodies_.back().get();
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
  rigid_bodies_.push_back(rigid);
  return rigid;
}

FemBody* FemWorld::body(const std::string& name) const {
  for (const auto& b : bodies_) {
    if (b->name() == name) return b.get();
  }
  return nullptr;
}

WorldStepReport FemWorld::step() {
  WorldStepReport report;
  soft_solver_->setTime(time_);
  // Exactly one internal step of dt (maxSubSteps 0: Bullet steps by the time given).
  world_->stepSimulation(toBtScalar(settings_.solver.time_step), 0);
  time_ += settings_.solver.time_step;
  report.step = ++steps_;
  for (const auto& body : bodies_) {
    const StepReport& r = body->lastReport();
    if (isFatal(r.health)) {
      report.ok = false;
      report.message = "body '" + body->name() + "', step " + std::to_string(steps_) + ": " +
                       toString(r.health) + ": " + r.message;
      break;
    }
  }
  return report;
}

Status FemWorld::setSolverSettings(const SolverSettings& solver) {
  if (Status valid = solver.validate(); !valid) return valid;
  if (solver.threads != settings_.solver.threads) {
    return Error{"solver: threads = " + std::to_string(solver.threads) +
                 ": cannot change while the world runs (it has " +
                 std::to_string(settings_.solver.threads) + "); build a new world"};
  }
  settings_.solver = solver;
  soft_solver_->setTimeStep(solver.time_step);
  for (const auto& body : bodies_)
    body->stepper().setSettings(solver);
  return Ok{};
}

}  // namespace torsion
