// Bullet 3.24's deformable world on a scene file (see bullet_twist_runner.cpp for the body set-up
// and its reasons: our node order and double coordinates, lumped masses rho V / 4, mass 0 for
// held and driven nodes, driven nodes given m_v = m_vn = (target - x) / dt before each step).
// Contact as Bullet's DeformableRigid demo sets it up: collisions SDF_RD | SDF_RDN (nodes against
// rigid bodies through the sparse signed-distance field), kCHR = kKHR = 1, the world's implicit
// linear-elasticity solve with projection (the contact constraints' way into its CG). Between FEM
// bodies (two or more, the scene's fem_contact on) VF_DD as Bullet's DeformableContact and
// PinchFriction demos set it up; the world then also runs its node-face CCD between soft bodies.
//
// Detection and solve times come from Bullet's own profile zones (BT_PROFILE), routed to our
// hooks for the run (btSetCustomEnterProfileZoneFunc, as bullet_twist_runner.cpp does).

#include "bullet_rigid_mix_runner.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <set>
#include <sstream>

#include "bullet_deformable_world.h"
#include "rigid_body_builder.h"
#include "scene_builder.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion::bench {

namespace {

MixRun failed(const std::string& message) {
  MixRun run;
  run.ok = false;
  run.message = message;
  return run;
}

btVector3 toBtV(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// A kinematic scene body's script, as Torsion's scene builder runs it: Bullet asks the motion state
// once per step (saveKinematicState, before the step) and takes (that pose - the last) / dt as the
// body's velocity, so it answers with the pose at the end of the coming step.
class ScriptedMotionState : public btMotionState {
 public:
  ScriptedMotionState(const scene::RigidBodySpec& spec, const double& next_time)
      : spec_(spec), next_time_(next_time) {}
  void getWorldTransform(btTransform& transform) const override {
    const Frame f = spec_.poseAt(next_time_);
    transform.setOrigin(toBtV(f.origin));
    transform.setRotation(
        btQuaternion(f.rotation.x(), f.rotation.y(), f.rotation.z(), f.rotation.w()));
  }
  void setWorldTransform(const btTransform& /*transform*/) override {}

 private:
  const scene::RigidBodySpec& spec_;
  const double& next_time_;
};

double processCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// The profile zones' clock: CPU time inside detection zones (the outermost one only, so a zone
// nested in another is not counted twice) and inside the solve zone. Bullet steps on this thread
// only; the hooks are global, as Bullet's are.
enum class Zone { kOther, kDetection, kNestedDetection, kSolve };

struct ZoneClock {
  std::vector<Zone> open;  // the zones entered and not yet left, innermost last
  std::vector<double> started;
  int open_detection = 0;
  double detect_ms = 0, solve_ms = 0;
};
ZoneClock g_zones;

Zone zoneOf(const char* name) {
  if (std::strcmp(name, "performDiscreteCollisionDetection") == 0 ||
      std::strcmp(name, "Deformable Collision") == 0 ||
      std::strcmp(name, "btDeformableMultiBodyDynamicsWorld::performGeometricCollisions") == 0)
    return g_zones.open_detection > 0 ? Zone::kNestedDetection : Zone::kDetection;
  if (std::strcmp(name, "btDeformableMultiBodyDynamicsWorld::solveConstraints") == 0)
    return Zone::kSolve;
  return Zone::kOther;
}

void enterZone(const char* name) {
  const Zone zone = zoneOf(name);
  if (zone == Zone::kDetection || zone == Zone::kNestedDetection) ++g_zones.open_detection;
  g_zones.open.push_back(zone);
  g_zones.started.push_back(zone == Zone::kDetection || zone == Zone::kSolve ? processCpuMs() : 0);
}

void leaveZone() {
  if (g_zones.open.empty()) return;
  const Zone zone = g_zones.open.back();
  if (zone == Zone::kDetection) g_zones.detect_ms += processCpuMs() - g_zones.started.back();
  if (zone == Zone::kSolve) g_zones.solve_ms += processCpuMs() - g_zones.started.back();
  if (zone == Zone::kDetection || zone == Zone::kNestedDetection) --g_zones.open_detection;
  g_zones.open.pop_back();
  g_zones.started.pop_back();
}

struct DrivenNode {
  btSoftBody* body;
  int node;
  Eigen::Vector3d rest;
  const scene::MotionSpec* motion;
};

NodeFrames nodePositions(const std::vector<std::unique_ptr<btSoftBody>>& bodies) {
  NodeFrames frames;
  for (const auto& body : bodies) {
    std::vector<Eigen::Vector3d> nodes;
    for (int i = 0; i < body->m_nodes.size(); ++i) {
      const btVector3& x = body->m_nodes[i].m_x;
      nodes.emplace_back(x.x(), x.y(), x.z());
    }
    frames.push_back(std::move(nodes));
  }
  return frames;
}

// Every free node of `body` moves at linear + angular x (x - c), c its centre of mass (what
// FemBody::setRigidVelocity does for Torsion).
void setRigidVelocity(btSoftBody& body, const Eigen::Vector3d& linear,
                      const Eigen::Vector3d& angular) {
  btVector3 weighted(0, 0, 0);
  btScalar total = 0;
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    if (body.m_nodes[i].m_im <= 0) continue;
    const btScalar m = 1 / body.m_nodes[i].m_im;
    weighted += m * body.m_nodes[i].m_x;
    total += m;
  }
  if (total <= 0) return;
  const btVector3 c = weighted / total;
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    btSoftBody::Node& node = body.m_nodes[i];
    if (node.m_im <= 0) continue;
    node.m_v = toBtV(linear) + toBtV(angular).cross(node.m_x - c);
    node.m_vn = node.m_v;
  }
}

}  // namespace

MixRun runBulletMix(const scene::SceneSpec& spec, int steps, const MixOptions& options) {
  MixRun run;
  const double dt = spec.world.solver.time_step;
  const int substeps = std::max(1, options.substeps);
  const double h = dt / substeps;  // Bullet's step
  const btVector3 g = toBtV(spec.world.gravity);
  auto config = std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>();
  auto dispatcher = std::make_unique<btCollisionDispatcher>(config.get());
  auto broadphase = std::make_unique<btDbvtBroadphase>();
  auto deformable_solver = std::make_unique<btDeformableBodySolver>();
  auto constraint_solver = std::make_unique<btDeformableMultiBodyConstraintSolver>();
  constraint_solver->setDeformableSolver(deformable_solver.get());
  auto world = std::make_unique<btDeformableMultiBodyDynamicsWorld>(
      dispatcher.get(), broadphase.get(), constraint_solver.get(), config.get(),
      deformable_solver.get());
  world->setGravity(g);
  world->getWorldInfo().m_gravity = g;
  world->getWorldInfo().m_sparsesdf.Initialize();

  std::vector<std::unique_ptr<btDeformableLagrangianForce>> forces;
  std::vector<std::unique_ptr<btSoftBody>> bodies;
  std::vector<DrivenNode> driven;
  // Contact between FEM bodies and its friction (see the header).
  const bool soft_contact = spec.bodies.size() >= 2 && spec.fem_contact.has_value();
  const double pair_friction_root = soft_contact ? std::sqrt(spec.fem_contact->friction) : 1.0;
  for (const scene::BodySpec& b : spec.bodies) {
    Result<LoadedMesh> loaded = readMesh(b.mesh_path);
    if (!loaded) return failed(loaded.error().message);
    std::vector<Eigen::Vector3d> placed = loaded.value().mesh.restPositions();
    for (Eigen::Vector3d& p : placed)
      p = b.pose.toWorld(p);
    const TetMesh mesh(std::move(placed), loaded.value().mesh.tets());
    const int n = mesh.nodeCount();
    std::vector<char> held(static_cast<size_t>(n), 0);
    for (const scene::NodeSetSpec& set : spec.node_sets) {
      if (set.body != b.name) continue;
      for (int i : scene::selectNodes(mesh, set.selection)) {
        held[static_cast<size_t>(i)] = 1;
        if (!set.fixed)
          driven.push_back({nullptr, i, mesh.restPositions()[size_t(i)], &set.motion});
      }
    }
    std::vector<btVector3> x(static_cast<size_t>(n));
    std::vector<btScalar> mass(static_cast<size_t>(n), 0);
    for (int i = 0; i < n; ++i)
      x[static_cast<size_t>(i)] = toBtV(mesh.restPositions()[static_cast<size_t>(i)]);
    std::set<std::pair<int, int>> edges;
    for (int t = 0; t < mesh.tetCount(); ++t) {
      const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
      for (int a = 0; a < 4; ++a) {
        const int node = tet[static_cast<size_t>(a)];
        if (!held[static_cast<size_t>(node)])
          mass[static_cast<size_t>(node)] += b.material.density * mesh.restVolume(t) / 4;
        for (int c = a + 1; c < 4; ++c) {
          const int other = tet[static_cast<size_t>(c)];
          edges.emplace(std::min(node, other), std::max(node, other));
        }
      }
    }
    auto body = std::make_unique<btSoftBody>(&world->getWorldInfo(), n, x.data(), mass.data());
    for (const Tet& tet : mesh.tets())
      body->appendTetra(tet[0], tet[1], tet[2], tet[3]);
    for (const auto& [a, c] : edges)
      body->appendLink(a, c, nullptr, false);
    for (const Triangle& f : mesh.surfaceTriangles())
      body->appendFace(f[0], f[1], f[2]);
    body->initializeDmInverse();
    btSoftBody::TetraScratch rest;
    rest.m_F.setIdentity();
    rest.m_trace = 3;
    rest.m_J = 1;
    rest.m_cofF.setIdentity();
    rest.m_corotation.setIdentity();
    body->m_tetraScratches.resize(body->m_tetras.size(), rest);
    body->m_tetraScratchesTn.resize(body->m_tetras.size(), rest);
    body->m_cfg.collisions = btSoftBody::fCollision::SDF_RD | btSoftBody::fCollision::SDF_RDN;
    if (soft_contact) body->m_cfg.collisions |= btSoftBody::fCollision::VF_DD;
    body->m_cfg.kCHR = 1;
    body->m_cfg.kKHR = 1;
    // A pair's friction is this times the rigid body's, or times the other soft body's kDF.
    body->m_cfg.kDF = pair_friction_root;
    body->getCollisionShape()->setMargin(options.margin);
    body->setActivationState(DISABLE_DEACTIVATION);
    body->updateNodeTree(false, false);
    world->addSoftBody(body.get());
    const Material& m = b.material;
    const double mu = m.youngs_modulus / (2 * (1 + m.poisson_ratio));
    const double lambda =
        m.youngs_modulus * m.poisson_ratio / ((1 + m.poisson_ratio) * (1 - 2 * m.poisson_ratio));
    forces.push_back(std::make_unique<btDeformableGravityForce>(g));
    world->addForce(body.get(), forces.back().get());
    forces.push_back(std::make_unique<btDeformableLinearElasticityForce>(mu, lambda, m.mass_damping,
                                                                         m.stiffness_damping));
    world->addForce(body.get(), forces.back().get());
    if (b.linear_velocity != Eigen::Vector3d::Zero() ||
        b.angular_velocity != Eigen::Vector3d::Zero())
      setRigidVelocity(*body, b.linear_velocity, b.angular_velocity);
    for (DrivenNode& d : driven) {
      if (d.body == nullptr) d.body = body.get();
    }
    bodies.push_back(std::move(body));
  }
  world->setImplicit(true);
  world->setUseProjection(true);
  world->setLineSearch(false);

  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> rigids;
  double next_time = 0;  // the kinematic scripts' clock: the end time of the coming step
  auto add_rigid = [&](const scene::RigidBodySpec& r) {
    shapes.push_back(scene::makeRigidShape(r));
    btVector3 inertia(0, 0, 0);
    if (r.mass > 0) shapes.back()->calculateLocalInertia(r.mass, inertia);
    btTransform t;
    t.setOrigin(toBtV(r.pose.origin));
    t.setRotation(btQuaternion(r.pose.rotation.x(), r.pose.rotation.y(), r.pose.rotation.z(),
                               r.pose.rotation.w()));
    states.push_back(std::make_unique<btDefaultMotionState>(t));
    btRigidBody::btRigidBodyConstructionInfo info(r.mass, states.back().get(), shapes.back().get(),
                                                  inertia);
    if (r.isKinematic()) states.back() = std::make_unique<ScriptedMotionState>(r, next_time);
    info.m_motionState = states.back().get();
    rigids.push_back(std::make_unique<btRigidBody>(info));
    if (r.isKinematic()) {
      rigids.back()->setCollisionFlags(rigids.back()->getCollisionFlags() |
                                       btCollisionObject::CF_KINEMATIC_OBJECT);
      rigids.back()->setActivationState(DISABLE_DEACTIVATION);
    }
    // Node-rigid pairs keep the scene's coefficient whatever kDF the FEM pairs need.
    rigids.back()->setFriction(pair_friction_root > 0 ? r.friction / pair_friction_root
                                                      : r.friction);
    rigids.back()->setRestitution(r.restitution);
    rigids.back()->setLinearVelocity(toBtV(r.linear_velocity));
    rigids.back()->setAngularVelocity(toBtV(r.angular_velocity));
    world->addRigidBody(rigids.back().get());
  };
  for (const scene::RigidBodySpec& r : spec.rigid_bodies) {
    add_rigid(r);
  }
  if (spec.ground && options.ground_as_box &&
      spec.ground->plane_normal.isApprox(Eigen::Vector3d::UnitZ())) {
    // Bullet's demos stand their bodies on a big box, not on a plane (its sparse signed distance
    // field is sampled in cells around the body; a plane's has no inside to speak of).
    scene::RigidBodySpec box = *spec.ground;
    box.shape = scene::RigidBodySpec::Shape::kBox;
    box.half_extents = {50, 50, 5};
    box.pose = Frame{};
    box.pose.origin = {0, 0, spec.ground->plane_offset - 5};
    add_rigid(box);
  } else if (spec.ground) {
    add_rigid(*spec.ground);
  }
  std::ostringstream detail;
  detail << "btDeformableMultiBodyDynamicsWorld, implicit linear elasticity + projection, "
            "SDF_RD|SDF_RDN"
         << (soft_contact ? "|VF_DD + soft-soft CCD, kDF " + std::to_string(pair_friction_root)
                          : std::string())
         << ", margin " << options.margin << " m, " << substeps
         << " substep(s) per step, one Newton iteration, CG defaults";
  run.detail = detail.str();

  using Clock = std::chrono::steady_clock;
  btEnterProfileZoneFunc* const previous_enter = btGetCurrentEnterProfileZoneFunc();
  btLeaveProfileZoneFunc* const previous_leave = btGetCurrentLeaveProfileZoneFunc();
  btSetCustomEnterProfileZoneFunc(enterZone);
  btSetCustomLeaveProfileZoneFunc(leaveZone);
  for (int k = 0; k < steps; ++k) {
    g_zones = ZoneClock{};
    const double cpu0 = processCpuMs();
    const Clock::time_point t0 = Clock::now();
    for (int sub = 0; sub < substeps; ++sub) {
      const double t_next =
          (k + static_cast<double>(sub + 1) / substeps) * dt;  // (k + 1) dt for one
      next_time = t_next;
      for (const DrivenNode& d : driven) {
        btSoftBody::Node& node = d.body->m_nodes[d.node];
        node.m_v = (toBtV(d.motion->frameAt(t_next).toWorld(d.rest)) - node.m_x) / h;
        node.m_vn = node.m_v;
      }
      world->stepSimulation(h, 0);
    }
    run.step_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    run.step_cpu_ms.push_back(processCpuMs() - cpu0);
    run.detect_cpu_ms.push_back(g_zones.detect_ms);
    run.solve_cpu_ms.push_back(g_zones.solve_ms);
    run.steps = k + 1;
    for (const auto& body : bodies) {
      for (int i = 0; i < body->m_nodes.size(); ++i) {
        const double speed = body->m_nodes[i].m_v.length();
        if (!std::isfinite(speed)) {
          run.ok = false;
          run.message = "step " + std::to_string(k) + ": non-finite node velocity";
        }
        run.max_node_speed = std::max(run.max_node_speed, speed);
      }
    }
    if (!run.ok) break;
    if (options.after_step) options.after_step(k, nodePositions(bodies));
  }
  btSetCustomEnterProfileZoneFunc(previous_enter);
  btSetCustomLeaveProfileZoneFunc(previous_leave);
  for (size_t r = 0; r < spec.rigid_bodies.size(); ++r) {
    const btTransform& t = rigids[r]->getWorldTransform();
    run.rigid_final_z.push_back(t.getOrigin().z());
    Frame pose;
    pose.origin = {t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z()};
    const btQuaternion q = t.getRotation();
    pose.rotation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
    run.rigid_final_pose.push_back(pose);
  }
  run.final_nodes = nodePositions(bodies);
  for (const auto& body : bodies) {
    std::vector<Eigen::Vector3d> velocities;
    for (int i = 0; i < body->m_nodes.size(); ++i) {
      const btVector3& v = body->m_nodes[i].m_v;
      velocities.emplace_back(v.x(), v.y(), v.z());
    }
    run.final_velocities.push_back(std::move(velocities));
  }
  for (const auto& body : bodies)
    world->removeSoftBody(body.get());
  for (const auto& rigid : rigids)
    world->removeRigidBody(rigid.get());
  return run;
}

}  // namespace torsion::bench
