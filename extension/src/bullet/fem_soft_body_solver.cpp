#include "torsion/bullet/fem_soft_body_solver.h"

#include <BulletSoftBody/btSoftMultiBodyDynamicsWorld.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "soft_body_touch.h"
#include "torsion/bt_conversions.h"
#include "torsion/bullet/rigid_health.h"
#include "torsion/mesh/node_ordering.h"
#include "torsion/mesh/quadratic_tet_mesh.h"

namespace torsion {

namespace {

// Whether two FEM bodies' broadphase pair really touches: some node of one within both bodies'
// margins of a node of the other (their node trees, rebuilt by FemBody::predict each step, whose
// leaves are the nodes' boxes grown by the margin). Bounding boxes alone overlap long before bodies
// touch (a ball over a slab's corner). Not for Bullet's own soft bodies: their node boxes are
// updated lazily (a cloth's keep the 0.25 m default margin they were made with until its nodes move
// out of them), and a cloth node can land on a coarse FEM face far from every FEM node
// (SoftBodyTouch).
bool nodesTouch(btSoftBody& a, btSoftBody& b) {
  struct Probe : btDbvt::ICollide {
    bool hit = false;
    void Process(const btDbvtNode* /*na*/, const btDbvtNode* /*nb*/) override { hit = true; }
    bool Descent(const btDbvtNode* /*node*/) override { return !hit; }
  } probe;
  if (a.m_ndbvt.m_root == nullptr || b.m_ndbvt.m_root == nullptr) return false;
  a.m_ndbvt.collideTT(a.m_ndbvt.m_root, b.m_ndbvt.m_root, probe);
  return probe.hit;
}

// How the body made of `renumbered` (from `input`) numbers its nodes and tets against `input`. A
// tet10 body's mid-edge nodes and sub-tets (FemModel::mesh()) get the numbers the same body made
// of `input` would give them: the element's node and sub-tet k of body element e are those of
// input element old_tet[e] (renumbering keeps each tet's own node order).
InputNumbering inputNumberingOf(const FemModel& body, const TetMesh& input,
                                const RenumberedMesh& renumbered) {
  if (body.elementKind() == ElementKind::kTet4)
    return InputNumbering(renumbered.old_node, renumbered.old_tet, body.mesh());
  const QuadraticTetMesh input_p2 = buildQuadraticTetMesh(input);
  std::vector<int> input_node(static_cast<size_t>(body.nodeCount()), -1);
  std::vector<int> input_tet(static_cast<size_t>(body.mesh().tetCount()), -1);
  const std::vector<int>& elements = body.elementNodes();
  for (int e = 0; e < body.elementCount(); ++e) {
    const int old = renumbered.old_tet[static_cast<size_t>(e)];
    const Tet10& in = input_p2.elements[static_cast<size_t>(old)];
    for (int a = 0; a < 10; ++a)
      input_node[static_cast<size_t>(elements[static_cast<size_t>(10 * e + a)])] =
          in[static_cast<size_t>(a)];
    for (int k = 0; k < 8; ++k)
      input_tet[static_cast<size_t>(8 * e + k)] = 8 * old + k;
  }
  return InputNumbering(std::move(input_node), std::move(input_tet), body.mesh());
}

// A body's pose (constraints/frame.h), its faults named with the body.
Result<Frame> checkedPose(const std::string& name, const Frame& pose) {
  return checkedFrame(pose, "body '" + name + "': the pose");
}

const char* const kNotOurSolver =
    "the world steps its soft bodies with another solver: construct it with a "
    "torsion::FemSoftBodySolver as its last argument (Bullet takes the soft-body solver only at "
    "construction), e.g. btSoftRigidDynamicsWorld world(&dispatcher, &broadphase, &solver, "
    "&config, &fem)";

// Bullet's worlds do not say which soft-body solver they were built with, but they hand it to
// every soft body they take in: ask with a one-node probe, added and removed at once.
template <class World>
btSoftBodySolver* softBodySolverOf(World& world) {
  btVector3 origin(0, 0, 0);
  btScalar mass = 0;
  btSoftBody probe(&world.getWorldInfo(), 1, &origin, &mass);
  world.addSoftBody(&probe);
  btSoftBodySolver* solver = probe.getSoftBodySolver();
  world.removeSoftBody(&probe);
  return solver;
}

template <class World>
Result<FemSoftBodySolver*> attachTo(World& world) {
  auto* fem = dynamic_cast<FemSoftBodySolver*>(softBodySolverOf(world));
  if (fem == nullptr) return Error{kNotOurSolver};
  if (Status bound = fem->bind(world); !bound) return bound.error();
  return fem;
}

}  // namespace

FemSoftBodySolver::FemSoftBodySolver(const SolverSettings& settings)
    : settings_(settings),
      parallel_(settings.threads),
      fem_contact_(std::make_unique<FemContactIslands>(BodyContactSettings{})),
      soft_touch_(std::make_unique<SoftBodyTouch>()) {}

// The world uses this solver until it is destroyed, and destroys its collision objects' broadphase
// proxies then: the world must go first (documented), so here the bodies are only freed.
FemSoftBodySolver::~FemSoftBodySolver() = default;

Status FemSoftBodySolver::bind(btSoftRigidDynamicsWorld& world) {
  if (world_ != &world && softBodySolverOf(world) != this) return Error{kNotOurSolver};
  return bindWorld(
      &world, &world.getWorldInfo(), [&world](btSoftBody* soft) { world.addSoftBody(soft); },
      [&world](btSoftBody* soft) { world.removeSoftBody(soft); });
}

Status FemSoftBodySolver::bind(btSoftMultiBodyDynamicsWorld& world) {
  if (world_ != &world && softBodySolverOf(world) != this) return Error{kNotOurSolver};
  return bindWorld(
      &world, &world.getWorldInfo(), [&world](btSoftBody* soft) { world.addSoftBody(soft); },
      [&world](btSoftBody* soft) { world.removeSoftBody(soft); });
}

Status FemSoftBodySolver::bindWorld(btDiscreteDynamicsWorld* world, btSoftBodyWorldInfo* info,
                                    std::function<void(btSoftBody*)> add,
                                    std::function<void(btSoftBody*)> remove) {
  if (world_ == world) return Ok{};
  if (world_ != nullptr) {
    return Error{
        "this FemSoftBodySolver is already attached to another world: a world needs its own "
        "solver"};
  }
  world_ = world;
  world_info_ = info;
  add_to_world_ = std::move(add);
  remove_from_world_ = std::move(remove);
  return Ok{};
}

Result<FemBody*> FemSoftBodySolver::addBody(const std::string& name, const TetMesh& mesh,
                                            const Material& material, const Frame& pose,
                                            ElementKind element, NodeNumbering numbering) {
  if (!bound()) {
    return Error{"body '" + name +
                 "': the solver is not attached to a world yet (torsion::attach(world) first)"};
  }
  if (body(name) != nullptr) return Error{"body '" + name + "' already exists"};
  if (mesh.tetCount() == 0 || mesh.nodeCount() == 0) {
    return Error{"body '" + name + "': the mesh has no tets (" + std::to_string(mesh.nodeCount()) +
                 " nodes, " + std::to_string(mesh.tetCount()) + " tets)"};
  }
  Result<Frame> placement = checkedPose(name, pose);
  if (!placement) return placement.error();
  std::optional<RenumberedMesh> renumbered;
  if (numbering == NodeNumbering::kCacheFriendly) renumbered = cacheFriendlyRenumbering(mesh);
  const TetMesh& body_mesh = renumbered ? renumbered->mesh : mesh;
  std::vector<Eigen::Vector3d> placed = body_mesh.restPositions();
  for (Eigen::Vector3d& p : placed)
    p = placement.value().toWorld(p);
  auto placed_mesh = std::make_shared<const TetMesh>(std::move(placed), body_mesh.tets());
  Result<std::shared_ptr<const FemModel>> model = FemModel::create(placed_mesh, material, element);
  if (!model) return Error{"body '" + name + "': " + model.error().message};
  InputNumbering input_numbering;
  if (renumbered) input_numbering = inputNumberingOf(*model.value(), mesh, *renumbered);
  auto body =
      std::make_unique<FemBody>(name, std::move(model).value(), settings_, parallel_, *world_info_,
                                world_->getCollisionObjectArray(), std::move(input_numbering));
  add_to_world_(body->softBody());
  bodies_.push_back(std::move(body));
  return bodies_.back().get();
}

void FemSoftBodySolver::removeBody(FemBody* body) {
  auto it = std::find_if(bodies_.begin(), bodies_.end(),
                         [body](const std::unique_ptr<FemBody>& b) { return b.get() == body; });
  if (it == bodies_.end()) return;
  remove_from_world_((*it)->softBody());
  if (fem_contact_) fem_contact_->forget(body);
  soft_touch_->forget(body);
  bodies_.erase(it);
}

FemBody* FemSoftBodySolver::body(const std::string& name) const {
  for (const auto& b : bodies_) {
    if (b->name() == name) return b.get();
  }
  return nullptr;
}

FemBody* FemSoftBodySolver::femBodyOf(const btSoftBody* soft) const {
  for (const auto& b : bodies_) {
    if (b->softBody() == soft) return b.get();
  }
  return nullptr;
}

FemCheckpoint FemSoftBodySolver::checkpoint() {
  FemCheckpoint c;
  c.time = time_;
  c.steps = steps_;
  c.last_dt = last_dt_;
  c.status = status_;
  for (const auto& body : bodies_)
    c.bodies.emplace_back(body.get(), body->checkpoint());
  if (fem_contact_) c.fem_pairs = fem_contact_->checkpoint();
  return c;
}

Status FemSoftBodySolver::restore(const FemCheckpoint& c) {
  for (const auto& [body, saved] : c.bodies) {
    if (std::none_of(bodies_.begin(), bodies_.end(),
                     [body = body](const std::unique_ptr<FemBody>& b) { return b.get() == body; }))
      return Error{
          "restore: a body of the checkpoint is not in this world (removed since, or the "
          "checkpoint is another world's; readCheckpoint reads its bytes for this world, naming "
          "what differs)"};
  }
  // The contact bytes are read before anything changes (a checkpoint's bytes edited by hand).
  for (const auto& [body, saved] : c.bodies) {
    if (Status read = body->checkRestore(saved); !read)
      return Error{"restore: " + read.error().message};
  }
  if (fem_contact_) {
    if (Status read = FemContactIslands::checkRestore(c.fem_pairs); !read)
      return Error{"restore: " + read.error().message};
  }
  for (const auto& [body, saved] : c.bodies)
    const_cast<FemBody*>(body)->restore(saved);
  if (fem_contact_) fem_contact_->restore(c.fem_pairs);
  time_ = c.time;
  steps_ = c.steps;
  last_dt_ = c.last_dt;
  status_ = c.status;
  return Ok{};
}

Status FemSoftBodySolver::setSolverSettings(const SolverSettings& settings) {
  if (Status valid = settings.validate(); !valid) return valid;
  if (settings.threads != settings_.threads) {
    return Error{"solver: threads = " + std::to_string(settings.threads) +
                 ": cannot change while the world runs (it has " +
                 std::to_string(settings_.threads) + "); build a new world"};
  }
  settings_ = settings;
  for (const auto& body : bodies_)
    body->stepper().setSettings(settings);
  return Ok{};
}

Status FemSoftBodySolver::setFemContact(const std::optional<BodyContactSettings>& settings) {
  if (!settings) {
    fem_contact_.reset();
    return Ok{};
  }
  if (Status valid = settings->validate(); !valid) return valid;
  fem_contact_ = std::make_unique<FemContactIslands>(*settings);
  return Ok{};
}

void FemSoftBodySolver::addStepListener(StepListener* listener) {
  listeners_.push_back(listener);
}

void FemSoftBodySolver::removeStepListener(StepListener* listener) {
  listeners_.erase(std::remove(listeners_.begin(), listeners_.end(), listener), listeners_.end());
}

void FemSoftBodySolver::fail(std::string message) {
  if (!status_.ok) return;  // the first failure is the one to read
  status_.ok = false;
  status_.failed_step = steps_ + 1;
  status_.message = std::move(message);
}

// ---- Bullet's calls, in the order of one substep ----

void FemSoftBodySolver::optimize(btAlignedObjectArray<btSoftBody*>& soft_bodies,
                                 bool force_update) {
  // Bullet's own soft bodies go to Bullet's default solver; ours are stepped below.
  bullet_bodies_.resize(0);
  for (int i = 0; i < soft_bodies.size(); ++i) {
    if (femBodyOf(soft_bodies[i]) == nullptr) bullet_bodies_.push_back(soft_bodies[i]);
  }
  soft_touch_->keepOnly(bullet_bodies_);
  bullet_solver_.optimize(bullet_bodies_, force_update);
}

StepContext FemSoftBodySolver::substepContext(double dt) const {
  StepContext ctx;
  ctx.time = time_;
  ctx.dt = dt;
  ctx.index = steps_ + 1;
  if (world_ != nullptr) ctx.gravity = toEigen(world_->getGravity());
  return ctx;
}

void FemSoftBodySolver::predictMotion(btScalar solver_dt) {
  // Bullet's worlds pass float(dt) here (the exact dt arrives in solveConstraints): it only
  // predicts the motion that collision detection looks along.
  const double dt = static_cast<double>(solver_dt);
  if (status_.ok && !listeners_.empty()) {
    rigid_step_announced_ = true;
    const StepContext ctx = substepContext(dt);
    for (StepListener* listener : listeners_)
      listener->beforeRigidStep(ctx);
  }
  if (status_.ok) {
    // A body alone in the world, without anchors, cannot touch anything this step: its node tree
    // (read only by contact detection) waits until something can.
    const bool alone = bodies_.size() == 1 && world_ != nullptr &&
                       world_->getNumCollisionObjects() == 1 &&
                       bodies_.front()->contacts().anchors().empty();
    for (const auto& body : bodies_)
      body->predict(dt, !alone);
  }
  // Bullet's rigid solve comes next: each jointed body's twist before it (joint_ledger.h).
  if (world_ != nullptr) joint_ledger_.begin(*world_, dt);
  if (fem_contact_) fem_contact_->beginSubstep();
  soft_touch_->beginSubstep();
  bullet_solver_.predictMotion(solver_dt);
}

void FemSoftBodySolver::solveConstraints(btScalar solver_dt) {
  bullet_solver_.solveConstraints(solver_dt);
  StepContext ctx = substepContext(static_cast<double>(solver_dt));
  const bool announced = std::exchange(rigid_step_announced_, false);
  // A substep without FEM bodies is still a step of the FEM clock (stepCount() counts substeps).
  if (!status_.ok || !(solver_dt > 0)) {
    if (announced) {  // the detection failed the substep: listeners get back what they lent
      for (StepListener* listener : listeners_)
        listener->afterFemStep(ctx, false);
    }
    return;
  }
  joint_ledger_.refresh(*world_);
  ctx.joints = &joint_ledger_;

  for (StepListener* listener : listeners_)
    listener->beforeFemStep(ctx);
  bool ok = status_.ok;  // an unsupported contact found in this substep's detection fails it
  // Touching FEM bodies step together as islands, the others alone, in body order.
  std::vector<FemBody*> bodies;
  for (const auto& body : bodies_)
    bodies.push_back(body.get());
  std::vector<std::vector<FemBody*>> groups;
  if (fem_contact_ && ok) {
    groups = fem_contact_->plan(bodies, ctx);
  } else {
    for (FemBody* body : bodies)
      groups.push_back({body});
  }
  for (const std::vector<FemBody*>& group : groups) {
    if (!ok) break;
    if (fem_contact_) {
      fem_contact_->advance(group, ctx, island_workspace_);
    } else {
      stepIsland(group, {}, ctx, island_workspace_);
    }
    for (FemBody* body : group) {
      const StepReport& report = body->lastReport();
      if (!isFatal(report.health)) continue;
      std::ostringstream s;
      s << "body '" << body->name() << "', step " << ctx.index << ": " << toString(report.health)
        << ": " << report.message;
      fail(s.str());
      ok = false;
      break;
    }
  }
  // Bullet integrates an overflowing rigid body into NaN without complaint, and the FEM contacts
  // above may just have taken impulses from one: the substep is only good if every rigid body of
  // the world is still a number (its final state: Bullet's integration and the FEM corrections).
  if (ok) {
    if (auto fault = findUnhealthyRigidBody(*world_)) {
      fail("step " + std::to_string(ctx.index) + ": " + fault->message);
      ok = false;
    }
  }
  time_ += ctx.dt;
  last_dt_ = ctx.dt;
  ++steps_;
  for (StepListener* listener : listeners_)
    listener->afterFemStep(ctx, ok);
}

void FemSoftBodySolver::updateSoftBodies() {
  for (const auto& body : bodies_)
    body->refreshSurface();
  bullet_solver_.updateSoftBodies();
}

void FemSoftBodySolver::processCollision(btSoftBody* soft, const btCollisionObjectWrapper* other) {
  // A broadphase pair: our narrow phase runs in FemBody::prepare, at the rigid body's pose after
  // Bullet's rigid integration (docs/contact.md). Bullet's soft bodies collide as Bullet does.
  if (FemBody* body = femBodyOf(soft)) {
    body->contacts().addCandidate(other->getCollisionObject());
  } else {
    soft->defaultCollisionHandler(other);
  }
}

void FemSoftBodySolver::processCollision(btSoftBody* a, btSoftBody* b) {
  const bool a_fem = femBodyOf(a) != nullptr;
  const bool b_fem = femBodyOf(b) != nullptr;
  if (!a_fem && !b_fem) {
    a->defaultCollisionHandler(b);
    return;
  }
  if (a_fem && b_fem && fem_contact_) {
    // Their boxes overlap: the pair looks for contact before the FEM step (FemContactIslands).
    fem_contact_->notePair(femBodyOf(a), femBodyOf(b));
    return;
  }
  if (a == b || reported_pairs_.count(std::minmax<const btSoftBody*>(a, b)) != 0) return;
  if (a_fem && b_fem) {
    if (nodesTouch(*a, *b)) unsupportedPair(a, b);
    return;
  }
  // One of Bullet's soft bodies: the geometric test (soft_body_touch.h), after Bullet's own
  // prediction of its motion (m_q -> m_x) and FemBody::predict's of ours.
  FemBody* fem = a_fem ? femBodyOf(a) : femBodyOf(b);
  if (soft_touch_->touches(*fem, a_fem ? *b : *a)) unsupportedPair(a, b);
}

std::string FemSoftBodySolver::describe(const btSoftBody* soft) const {
  if (FemBody* body = femBodyOf(soft)) return "FEM body '" + body->name() + "'";
  std::ostringstream s;
  s << "Bullet soft body at " << static_cast<const void*>(soft) << " (" << soft->m_nodes.size()
    << " nodes)";
  return s.str();
}

void FemSoftBodySolver::unsupportedPair(const btSoftBody* a, const btSoftBody* b) {
  const auto key = std::minmax(a, b);
  if (!reported_pairs_.insert(key).second) return;
  const bool both_fem = femBodyOf(a) != nullptr && femBodyOf(b) != nullptr;
  std::ostringstream s;
  s << describe(a) << " and " << describe(b) << " touch at step " << steps_ + 1 << " (t = " << time_
    << " s): "
    << (both_fem ? "contact between FEM bodies is off (FemSoftBodySolver::setFemContact; scene key "
                   "\"fem_contact\"): they would pass through each other"
                 : "Torsion's FEM bodies do not collide with Bullet's soft bodies: they would pass "
                   "through each other")
    << ". To let them, put them in collision filter groups that do not collide, or set "
       "UnsupportedContact::kWarn";
  if (unsupported_contact_ == UnsupportedContact::kError) {
    fail(s.str());
  } else {
    warnings_.push_back(s.str());
  }
}

Result<FemSoftBodySolver*> attach(btSoftRigidDynamicsWorld& world) {
  return attachTo(world);
}

Result<FemSoftBodySolver*> attach(btSoftMultiBodyDynamicsWorld& world) {
  return attachTo(world);
}

}  // namespace torsion
