// Bullet's side of the cylinder twist: btDeformableMultiBodyDynamicsWorld (Bullet 3.24, double
// precision) on the same mesh and protocol. The only file of the benchmark that includes the
// BulletSoftBody deformable headers. Set-up follows /work/notes/bullet_integration.md sections 3-4:
//
// - Nodes from our TetMesh in the same order (double coordinates; CreateFromTetGenData would read
//   them as float), lumped masses rho V / 4 (setVolumeDensity would give 4 rho V), mass 0 for the
//   fixed and driven nodes (btDeformableStaticConstraint: their dv is projected to 0).
// - Tets (positively oriented by TetMesh), the unique tet edges as links (deduplicated here:
//   appendLink's own check is O(links) per call), outward boundary faces. initializeDmInverse and
//   the tet scratch arrays as btSoftBodyHelpers does. collisions = 0 (nothing to collide with;
//   keeps the contact and face-tree machinery out of the timing), DISABLE_DEACTIVATION.
// - A zero btDeformableGravityForce is always added (implicit mode reads an uninitialised gravity
//   otherwise, memo section 4.8).
// - Driven nodes: both m_v and m_vn set to (target(t + h) - x) / h before every stepSimulation(h,
// 0)
//   (implicit mode keeps m_vn as the velocity backup; memo section 3, run t4).
//
// Implicit: btDeformableLinearElasticityForce(mu, lambda, alpha = 0, beta), setImplicit(true),
// setUseProjection(true), no line search, one Newton iteration (Bullet's default). Its damping:
// addScaledDampingForce applies the damping stress beta (2 mu eps(dF) + lambda tr(dF) I) with
// dF = R^T grad(v) (rotated into the element frame with the same lagged corotation as the
// elastic force), i.e. the force -beta K v, plus -alpha M v on free nodes. Its implicit system
// (btDeformableBackwardEulerObjective::multiply) is M dv + dt D dv + dt^2 K dv with D = alpha M +
// beta K. So alpha = 0, beta = 0.01 s is exactly our Rayleigh damping (mass_damping = 0,
// stiffness_damping = 0.01 s, system M + (dt^2 + dt beta) K).
//
// Explicit: btDeformableCorotatedForce(mu, lambda) (no damping, no stiffness differential),
// setImplicit(false), setUseProjection(false) (one conjugate-residual multiply per substep; with
// projection it is one 0-iteration CG, same result, memo run t7); `substeps` stepSimulation calls
// of dt / substeps per benchmark step.
//
// Iterations: BT_PROFILE zones are routed to our counters (btSetCustomEnterProfileZoneFunc);
// CG/CR iterations = #"multiply" - #"CGSolve" - #"CRSolve" (each solve does one multiply before
// its loop). Installing the hook also replaces Bullet's default profiler bookkeeping, which makes
// Bullet marginally faster than stock, not slower.

#include <chrono>
#include <cmath>
#include <cstring>
#include <set>
#include <sstream>
#include <utility>

#include "bullet_deformable_world.h"
#include "twist_protocol.h"

namespace torsion::bench {
namespace {

long g_multiplies = 0;
long g_solves = 0;

void enterZone(const char* name) {
  // Zone names are string literals; compare the few we count.
  if (std::strcmp(name, "multiply") == 0) {
    ++g_multiplies;
  } else if (std::strcmp(name, "CGSolve") == 0 || std::strcmp(name, "CRSolve") == 0) {
    ++g_solves;
  }
}
void leaveZone() {}

// m_cg is protected in btDeformableBodySolver.
class BenchDeformableSolver : public btDeformableBodySolver {
 public:
  void setCg(int max_iterations, btScalar tolerance) {
    m_cg.m_maxIterations = max_iterations;
    m_cg.setTolerance(tolerance);
  }
  btScalar cgTolerance() const { return m_cg.m_tolerance; }
  int cgMaxIterations() const { return m_cg.m_maxIterations; }
};

btVector3 toBt(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

}  // namespace

TwistResult runBulletTwist(const TwistProtocol& protocol, const TetMesh& mesh,
                           const BulletOptions& options) {
  using Clock = std::chrono::steady_clock;
  TwistResult result;
  const Clock::time_point setup_start = Clock::now();
  if (options.substeps < 1) {
    result.status = RunStatus::kSetupFailed;
    result.message = "substeps must be >= 1";
    return result;
  }
  btEnterProfileZoneFunc* const previous_enter = btGetCurrentEnterProfileZoneFunc();
  btLeaveProfileZoneFunc* const previous_leave = btGetCurrentLeaveProfileZoneFunc();
  btSetCustomEnterProfileZoneFunc(enterZone);
  btSetCustomLeaveProfileZoneFunc(leaveZone);

  const TwistScene scene = classifyNodes(mesh);
  const int n = mesh.nodeCount();
  const std::vector<Eigen::Vector3d>& rest = mesh.restPositions();

  // World (the 3.24 demos' set-up; there is no btDeformableCollisionConfiguration in 3.24).
  auto collision_config = std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>();
  auto dispatcher = std::make_unique<btCollisionDispatcher>(collision_config.get());
  auto broadphase = std::make_unique<btDbvtBroadphase>();
  auto deformable_solver = std::make_unique<BenchDeformableSolver>();
  auto constraint_solver = std::make_unique<btDeformableMultiBodyConstraintSolver>();
  constraint_solver->setDeformableSolver(deformable_solver.get());
  // Forces outlive the world (it never deletes them); the body dies first (declared last).
  const btVector3 zero(0, 0, 0);
  auto gravity_force = std::make_unique<btDeformableGravityForce>(zero);
  std::unique_ptr<btDeformableLagrangianForce> elastic;
  auto world = std::make_unique<btDeformableMultiBodyDynamicsWorld>(
      dispatcher.get(), broadphase.get(), constraint_solver.get(), collision_config.get(),
      deformable_solver.get());
  world->setGravity(zero);
  world->getWorldInfo().m_gravity = zero;

  // Body.
  std::vector<btVector3> x(static_cast<size_t>(n));
  std::vector<btScalar> mass(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i)
    x[static_cast<size_t>(i)] = toBt(rest[static_cast<size_t>(i)]);
  std::set<std::pair<int, int>> edges;
  for (int t = 0; t < mesh.tetCount(); ++t) {
    const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
    const double volume = mesh.restVolume(t);
    for (int a = 0; a < 4; ++a) {
      const int node = tet[static_cast<size_t>(a)];
      if (scene.roles[static_cast<size_t>(node)] == NodeRole::kFree) {
        mass[static_cast<size_t>(node)] += protocol.density * volume / 4;
      }
      for (int b = a + 1; b < 4; ++b) {
        const int other = tet[static_cast<size_t>(b)];
        edges.emplace(std::min(node, other), std::max(node, other));
      }
    }
  }
  auto body = std::make_unique<btSoftBody>(&world->getWorldInfo(), n, x.data(), mass.data());
  for (const Tet& tet : mesh.tets())
    body->appendTetra(tet[0], tet[1], tet[2], tet[3]);
  for (const auto& [a, b] : edges)
    body->appendLink(a, b, nullptr, false);
  for (const Triangle& f : mesh.surfaceTriangles())
    body->appendFace(f[0], f[1], f[2]);
  body->initializeDmInverse();
  btSoftBody::TetraScratch rest_scratch;  // what updateDeformation writes for an undeformed tet
  rest_scratch.m_F.setIdentity();
  rest_scratch.m_trace = 3;
  rest_scratch.m_J = 1;
  rest_scratch.m_cofF.setIdentity();
  rest_scratch.m_corotation.setIdentity();
  body->m_tetraScratches.resize(body->m_tetras.size(), rest_scratch);
  body->m_tetraScratchesTn.resize(body->m_tetras.size(), rest_scratch);
  body->m_cfg.collisions = 0;
  body->getCollisionShape()->setMargin(0.01);
  body->updateNodeTree(false, false);
  body->setActivationState(DISABLE_DEACTIVATION);
  body->m_sleepingThreshold = 0;
  world->addSoftBody(body.get());

  const double mu = protocol.youngs_modulus / (2 * (1 + protocol.poisson_ratio));
  const double lambda = protocol.youngs_modulus * protocol.poisson_ratio /
                        ((1 + protocol.poisson_ratio) * (1 - 2 * protocol.poisson_ratio));
  world->addForce(body.get(), gravity_force.get());
  std::ostringstream detail;
  if (options.implicit) {
    elastic = std::make_unique<btDeformableLinearElasticityForce>(mu, lambda, 0.0,
                                                                  protocol.stiffness_damping);
    world->addForce(body.get(), elastic.get());
    world->setImplicit(true);
    world->setUseProjection(true);
    world->setLineSearch(false);
    if (options.cg_tolerance > 0) {
      deformable_solver->setCg(options.cg_max_iterations, options.cg_tolerance);
    } else {
      deformable_solver->setCg(options.cg_max_iterations, SIMD_EPSILON);
    }
    detail << "implicit linear-elasticity, cg tol " << deformable_solver->cgTolerance()
           << (options.cg_tolerance > 0 ? "" : " (default)") << ", max it "
           << deformable_solver->cgMaxIterations() << ", preconditioner "
           << (options.mass_preconditioner ? "mass (initialised)" : "identity (Bullet default)")
           << ", beta " << protocol.stiffness_damping;
  } else {
    elastic = std::make_unique<btDeformableCorotatedForce>(mu, lambda);
    world->addForce(body.get(), elastic.get());
    world->setImplicit(false);
    world->setUseProjection(false);
    detail << "explicit corotated, substeps " << options.substeps;
  }
  result.solver_detail = detail.str();

  std::vector<int> driven;
  for (int i = 0; i < n; ++i) {
    if (scene.roles[static_cast<size_t>(i)] == NodeRole::kDriven) driven.push_back(i);
  }
  const double dt = protocol.time_step;
  const double h = dt / options.substeps;
  result.setup_seconds = std::chrono::duration<double>(Clock::now() - setup_start).count();
  result.setup_rss_kb = peakRssKb();

  btAlignedObjectArray<btSoftBody::Node>& nodes = body->m_nodes;
  result.step_ms.reserve(static_cast<size_t>(protocol.total_steps));
  result.step_iterations.reserve(static_cast<size_t>(protocol.total_steps));
  const double cpu_start = processCpuSeconds();
  bool preconditioner_ready = !options.mass_preconditioner;
  for (int k = 0; k < protocol.total_steps; ++k) {
    const long multiplies0 = g_multiplies, solves0 = g_solves;
    const Clock::time_point t0 = Clock::now();
    for (int s = 0; s < options.substeps; ++s) {
      const double angle = protocol.angle(k * dt + (s + 1) * h);
      for (int i : driven) {
        btSoftBody::Node& node = nodes[i];
        const btVector3 target = toBt(turnedAboutZ(rest[static_cast<size_t>(i)], angle));
        node.m_v = (target - node.m_x) / h;
        node.m_vn = node.m_v;
      }
      world->stepSimulation(h, 0);
      if (!preconditioner_ready) {
        // The world selects the mass preconditioner in projection mode but never initialises
        // it (identity); its node list exists only after the first step. Memo section 3, t6.
        deformable_solver->m_objective->m_massPreconditioner->reinitialize(true);
        preconditioner_ready = true;
      }
    }
    const Clock::time_point t1 = Clock::now();
    result.step_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    result.step_iterations.push_back(
        static_cast<int>((g_multiplies - multiplies0) - (g_solves - solves0)));
    result.steps_done = k + 1;

    // Harness health check, outside the timing (ours does the same inside its step).
    double max_speed_sq = 0;
    bool finite = true;
    for (int i = 0; i < n; ++i) {
      const btSoftBody::Node& node = nodes[i];
      if (!std::isfinite(node.m_x.x()) || !std::isfinite(node.m_x.y()) ||
          !std::isfinite(node.m_x.z()) || !std::isfinite(node.m_v.length2())) {
        finite = false;
        break;
      }
      max_speed_sq = std::max(max_speed_sq, static_cast<double>(node.m_v.length2()));
    }
    result.max_speed = std::max(result.max_speed, std::sqrt(max_speed_sq));
    if (!finite) {
      result.status = RunStatus::kNonFinite;
      result.message = "step " + std::to_string(k) + ": non-finite positions or velocities";
      break;
    }
    if (std::sqrt(max_speed_sq) > protocol.max_speed) {
      std::ostringstream s;
      s << "step " << k << ": a node moves at " << std::sqrt(max_speed_sq) << " m/s > "
        << protocol.max_speed << " m/s";
      result.status = RunStatus::kBlowUp;
      result.message = s.str();
      break;
    }
  }
  result.loop_cpu_seconds = processCpuSeconds() - cpu_start;
  result.peak_rss_kb = peakRssKb();

  Eigen::VectorXd positions(3 * n);
  for (int i = 0; i < n; ++i) {
    const btVector3& p = nodes[i].m_x;
    positions.segment<3>(3 * i) = Eigen::Vector3d(p.x(), p.y(), p.z());
  }
  result.final_positions = positions;
  measureTwist(protocol, mesh, scene, positions, result);

  world->removeSoftBody(body.get());
  btSetCustomEnterProfileZoneFunc(previous_enter);
  btSetCustomLeaveProfileZoneFunc(previous_leave);
  return result;
}

}  // namespace torsion::bench
