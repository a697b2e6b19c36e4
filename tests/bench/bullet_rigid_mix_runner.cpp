// Bullet 3.24's deformable world on a scene file (see bullet_twist_runner.cpp for the body set-up
// and its reasons: our node order and double coordinates, lumped masses rho V / 4, mass 0 for
// held and driven nodes, driven nodes given m_v = m_vn = (target - x) / dt before each step).
// Contact as Bullet's DeformableRigid demo sets it up: collisions SDF_RD | SDF_RDN (nodes against
// rigid bodies through the sparse signed-distance field), kCHR = kKHR = 1, the world's implicit
// linear-elasticity solve with projection (the contact constraints' way into its CG).

#include "bullet_rigid_mix_runner.h"

#include <chrono>
#include <cmath>
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

struct DrivenNode {
  btSoftBody* body;
  int node;
  Eigen::Vector3d rest;
  const scene::MotionSpec* motion;
};

}  // namespace

MixRun runBulletMix(const scene::SceneSpec& spec, int steps) {
  MixRun run;
  const double dt = spec.world.solver.time_step;
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
    body->m_cfg.kCHR = 1;
    body->m_cfg.kKHR = 1;
    body->m_cfg.kDF = 1;  // a pair's friction is this times the rigid body's
    body->getCollisionShape()->setMargin(0.01);
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
    rigids.back()->setFriction(r.friction);
    rigids.back()->setRestitution(r.restitution);
    rigids.back()->setLinearVelocity(toBtV(r.linear_velocity));
    rigids.back()->setAngularVelocity(toBtV(r.angular_velocity));
    world->addRigidBody(rigids.back().get());
  };
  for (const scene::RigidBodySpec& r : spec.rigid_bodies) {
    add_rigid(r);
  }
  if (spec.ground) add_rigid(*spec.ground);
  std::ostringstream detail;
  detail << "btDeformableMultiBodyDynamicsWorld, implicit linear elasticity + projection, "
            "SDF_RD|SDF_RDN, one Newton iteration, CG defaults";
  run.detail = detail.str();

  using Clock = std::chrono::steady_clock;
  for (int k = 0; k < steps; ++k) {
    const double t_next = (k + 1) * dt;
    next_time = t_next;
    const Clock::time_point t0 = Clock::now();
    for (const DrivenNode& d : driven) {
      btSoftBody::Node& node = d.body->m_nodes[d.node];
      node.m_v = (toBtV(d.motion->frameAt(t_next).toWorld(d.rest)) - node.m_x) / dt;
      node.m_vn = node.m_v;
    }
    world->stepSimulation(dt, 0);
    run.step_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
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
  }
  for (size_t r = 0; r < spec.rigid_bodies.size(); ++r) {
    const btTransform& t = rigids[r]->getWorldTransform();
    run.rigid_final_z.push_back(t.getOrigin().z());
    Frame pose;
    pose.origin = {t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z()};
    const btQuaternion q = t.getRotation();
    pose.rotation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
    run.rigid_final_pose.push_back(pose);
  }
  for (const auto& body : bodies) {
    std::vector<Eigen::Vector3d> nodes;
    for (int i = 0; i < body->m_nodes.size(); ++i) {
      const btVector3& x = body->m_nodes[i].m_x;
      nodes.emplace_back(x.x(), x.y(), x.z());
    }
    run.final_nodes.push_back(std::move(nodes));
  }
  for (const auto& body : bodies)
    world->removeSoftBody(body.get());
  for (const auto& rigid : rigids)
    world->removeRigidBody(rigid.get());
  return run;
}

}  // namespace torsion::bench
