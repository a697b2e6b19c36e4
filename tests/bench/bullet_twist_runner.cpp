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
// Neo-Hookean (TwistProtocol::Law::kNeoHookean): btDeformableNeoHookeanForce, implicit or
// explicit as above. In Bullet 3.24 its constructor is (mu, lambda, damping = 0.05), not (mu,
// lambda, alpha, beta) as the linear-elasticity force's: there is no mass damping (alpha = 0, as
// ours) and `damping` scales both Lame parameters into the damping ones (m_mu_damp, m_lambda_damp).
// - Energy (elasticEnergyDensity): mu/2 (I_C - 3) + lambda/2 (J - 1 - 3 mu / (4 lambda))^2
//   - mu/2 log(I_C + 1): Smith, de Goes & Kim's law WITH the log term, whose parameters are used
//   as given. Its expansion at F = I is linear elasticity with shear modulus 3/4 mu and first Lame
//   parameter lambda - 5/8 mu, so it needs the shift of docs/materials.md ("with the log term"):
//   we pass mu_B = 4/3 mu, lambda_B = lambda + 5/6 mu, which makes its small-strain moduli those
//   of (E, nu) exactly (Bullet's own setYoungsModulus / setPoissonRatio do not shift, and would
//   give a body 25 % softer in shear). Ours is the law without the log term (mu' = mu, l' = lambda
//   + mu): the two agree to second order at F = I and differ at finite strain by the log term
//   (simple shear: sigma_12 = mu gamma (1 + gamma^2 / (3 (4 + gamma^2))) against mu gamma, +0.2 %
//   at this twist's largest surface shear, 0.157).
// - Damping (addScaledDampingForce): the stress m_mu_damp (dF + dF^T) + m_lambda_damp tr(dF) I
//   with dF = grad(v) in the rest frame, i.e. the force -K_0 v with K_0 the stiffness at REST
//   (its damping differential is the same K_0; firstPiolaDampingDifferential is commented out).
//   It is NOT rotation-compensated: an element turned by theta about z and spinning rigidly at
//   omega sees sym(grad v) = -omega sin(theta) in the xy plane, a spurious in-plane compression
//   rate from its rigid motion alone, where the corotated linear-elasticity force rotates dF back
//   (R^T dF) and ours uses the stiffness of the current configuration (K_n, projected, at the
//   step's start: rotation covariant). Its damping stress, 2 beta (mu + lambda) omega sin(theta),
//   pushes the surface nodes along their REST normals, which are turned by theta from the current
//   ones: a distributed torque against the turn. Here the sections turn at up to 0.52 rad/s by up
//   to pi/2 during the ramp: about 1 kPa near the driven end, a drag of 2 pi a^2 |stress|
//   sin(theta) per metre, estimated at 20 kN m over the bar at the end of the ramp if the
//   sections turned rigidly, twice the elastic torque (St-Venant 9.5 kN m). Bullet's
//   neo-Hookean bar is therefore dragged during the ramp (the --curve torque shows it); the drag
//   vanishes with the velocities in the hold phase, so the end-of-run profile is far less
//   affected. We pass damping = beta = protocol.stiffness_damping (0.01 s, as the linear case)
//   and then set m_mu_damp = beta mu, m_lambda_damp = beta lambda (the public members), so that
//   K_0 is the small-strain stiffness of (E, nu) (the constructor would scale the shifted mu_B,
//   lambda_B): beta K_0 equals our beta K_n at rest.
// - Newton: Bullet's implicit step is BulletOptions::newton_iterations linearised solves
//   (m_maxNewtonIterations, default 1, no line search), the first one linearised at the
//   predicted x_n + dt v_n, each with the exact (unprojected) tangent; its stop test compares the
//   absolute norm of a residual that includes the held nodes' forces with 1e-4 and never fires
//   here. Ours iterates to newton_tolerance 1e-6 (about 2 solves per step in this protocol).
//
// End torque (TwistResult::end_torque, curve): drivenTorqueZ of the forces the elastic force
// object exerts on the driven nodes at the end of a step, computed here outside the timing from
// the nodes' m_x and m_v by the force's own stress function (firstPiola) on every tet that touches
// a driven node, plus its damping stress, the same sums as its addScaledForces (the world's
// scratches are at the last Newton iterate's predicted positions, not the end state, so they are
// not reused). For the linear-elasticity force the corotation is the polar rotation of F
// (polarDecompose; Bullet's own extractRotation of the same tet converges to it). Not measured
// for the explicit corotated force.
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
  void setNewtonIterations(int iterations) { m_maxNewtonIterations = iterations; }
  int newtonIterations() const { return m_maxNewtonIterations; }
};

btVector3 toBt(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// Columns c1..c3 of a node difference matrix: rows of the returned matrix are x, y, z.
btMatrix3x3 differences(const btVector3& a0, const btVector3& a1, const btVector3& a2,
                        const btVector3& a3) {
  return btMatrix3x3(a1 - a0, a2 - a0, a3 - a0).transpose();
}

// Forces the elastic force object (`neo` or `linear`, one of them) exerts on the nodes of `tets`
// at the current m_x, m_v, added into `forces` (3n): what its addScaledForces(1, .) sums for those
// tets, evaluated at the end state (see the top of the file).
void addEndForces(const btSoftBody& body, const std::vector<int>& tets,
                  btDeformableNeoHookeanForce* neo, btDeformableLinearElasticityForce* linear,
                  Eigen::VectorXd& forces) {
  const btVector3 first_column(-1, -1, -1);
  for (int j : tets) {
    const btSoftBody::Tetra& tetra = body.m_tetras[j];
    const btSoftBody::Node* n[4] = {tetra.m_n[0], tetra.m_n[1], tetra.m_n[2], tetra.m_n[3]};
    btSoftBody::TetraScratch s;
    s.m_F = differences(n[0]->m_x, n[1]->m_x, n[2]->m_x, n[3]->m_x) * tetra.m_Dm_inverse;
    s.m_J = s.m_F.determinant();
    const btMatrix3x3 C = s.m_F.transpose() * s.m_F;
    s.m_trace = C[0][0] + C[1][1] + C[2][2];
    s.m_cofF = s.m_F.adjoint().transpose();
    btMatrix3x3 dF = differences(n[0]->m_v, n[1]->m_v, n[2]->m_v, n[3]->m_v) * tetra.m_Dm_inverse;
    const btMatrix3x3 I = btMatrix3x3::getIdentity();
    btMatrix3x3 per_node;  // columns: force on nodes 1..3 over -V
    if (neo != nullptr) {
      btMatrix3x3 P;
      neo->firstPiola(s, P);
      const btMatrix3x3 dP = (dF + dF.transpose()) * neo->m_mu_damp +
                             I * ((dF[0][0] + dF[1][1] + dF[2][2]) * neo->m_lambda_damp);
      per_node = (P + dP) * tetra.m_Dm_inverse.transpose();
    } else {
      btMatrix3x3 stretch;
      polarDecompose(s.m_F, s.m_corotation, stretch);
      btMatrix3x3 P;
      linear->firstPiola(s, P);
      dF = s.m_corotation.transpose() * dF;
      const btMatrix3x3 dP = ((dF + dF.transpose()) * linear->m_mu +
                              I * ((dF[0][0] + dF[1][1] + dF[2][2]) * linear->m_lambda)) *
                             linear->m_damping_beta;
      per_node = s.m_corotation * (P + dP) * tetra.m_Dm_inverse.transpose();
    }
    const btScalar volume = tetra.m_element_measure;
    const btVector3 f[4] = {-volume * (per_node * first_column), -volume * per_node.getColumn(0),
                            -volume * per_node.getColumn(1), -volume * per_node.getColumn(2)};
    for (int a = 0; a < 4; ++a) {
      const int id = static_cast<int>(n[a] - &body.m_nodes[0]);
      forces.segment<3>(3 * id) += Eigen::Vector3d(f[a].x(), f[a].y(), f[a].z());
    }
  }
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
  const bool neo_hookean = protocol.law == TwistProtocol::Law::kNeoHookean;
  btDeformableNeoHookeanForce* neo = nullptr;
  btDeformableLinearElasticityForce* linear = nullptr;
  if (neo_hookean) {
    // The shift that makes Bullet's log-term energy's small-strain moduli (mu, lambda); damping
    // K_0 with the unshifted ones (top of the file).
    auto force = std::make_unique<btDeformableNeoHookeanForce>(
        4.0 / 3.0 * mu, lambda + 5.0 / 6.0 * mu, protocol.stiffness_damping);
    force->m_mu_damp = protocol.stiffness_damping * mu;
    force->m_lambda_damp = protocol.stiffness_damping * lambda;
    neo = force.get();
    elastic = std::move(force);
  }
  if (options.implicit) {
    if (!neo_hookean) {
      auto force = std::make_unique<btDeformableLinearElasticityForce>(mu, lambda, 0.0,
                                                                       protocol.stiffness_damping);
      linear = force.get();
      elastic = std::move(force);
    }
    world->addForce(body.get(), elastic.get());
    world->setImplicit(true);
    world->setUseProjection(true);
    world->setLineSearch(false);
    if (options.cg_tolerance > 0) {
      deformable_solver->setCg(options.cg_max_iterations, options.cg_tolerance);
    } else {
      deformable_solver->setCg(options.cg_max_iterations, SIMD_EPSILON);
    }
    if (options.newton_iterations < 1) {
      result.status = RunStatus::kSetupFailed;
      result.message = "newton iterations must be >= 1";
      world->removeSoftBody(body.get());
      btSetCustomEnterProfileZoneFunc(previous_enter);
      btSetCustomLeaveProfileZoneFunc(previous_leave);
      return result;
    }
    deformable_solver->setNewtonIterations(options.newton_iterations);
    detail << "implicit " << (neo_hookean ? "neo-hookean" : "linear-elasticity") << ", newton "
           << deformable_solver->newtonIterations() << ", cg tol "
           << deformable_solver->cgTolerance() << (options.cg_tolerance > 0 ? "" : " (default)")
           << ", max it " << deformable_solver->cgMaxIterations() << ", preconditioner "
           << (options.mass_preconditioner ? "mass (initialised)" : "identity (Bullet default)")
           << ", beta " << protocol.stiffness_damping;
  } else {
    if (!neo_hookean) elastic = std::make_unique<btDeformableCorotatedForce>(mu, lambda);
    world->addForce(body.get(), elastic.get());
    world->setImplicit(false);
    world->setUseProjection(false);
    detail << "explicit " << (neo_hookean ? "neo-hookean" : "corotated") << ", substeps "
           << options.substeps;
  }
  result.solver_detail = detail.str();

  std::vector<int> driven;
  for (int i = 0; i < n; ++i) {
    if (scene.roles[static_cast<size_t>(i)] == NodeRole::kDriven) driven.push_back(i);
  }
  // Tets touching a driven node: the end torque's forces (measured where a force object allows).
  std::vector<int> driven_tets;
  const bool torque_measured = neo != nullptr || linear != nullptr;
  for (int t = 0; t < mesh.tetCount() && torque_measured; ++t) {
    for (int node : mesh.tets()[static_cast<size_t>(t)]) {
      if (scene.roles[static_cast<size_t>(node)] == NodeRole::kDriven) {
        driven_tets.push_back(t);
        break;
      }
    }
  }
  Eigen::VectorXd end_positions = Eigen::VectorXd::Zero(3 * n);
  Eigen::VectorXd end_forces = Eigen::VectorXd::Zero(3 * n);
  auto endTorque = [&]() {
    for (int i : driven) {
      const btVector3& p = body->m_nodes[i].m_x;
      end_positions.segment<3>(3 * i) = Eigen::Vector3d(p.x(), p.y(), p.z());
    }
    end_forces.setZero();
    addEndForces(*body, driven_tets, neo, linear, end_forces);
    return drivenTorqueZ(end_positions, end_forces, driven);
  };
  double outside_cpu = 0;  // CPU seconds of the torque curve, taken out of the loop's CPU time

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
    if (options.implicit) result.step_newton.push_back(static_cast<int>(g_solves - solves0));
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
    if (protocol.record_curve && torque_measured) {
      const double c0 = processCpuSeconds();
      result.curve.push_back({k + 1, protocol.angle((k + 1) * dt), endTorque()});
      outside_cpu += processCpuSeconds() - c0;
    }
  }
  result.loop_cpu_seconds = processCpuSeconds() - cpu_start - outside_cpu;
  if (torque_measured && result.status == RunStatus::kOk) result.end_torque = endTorque();
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
