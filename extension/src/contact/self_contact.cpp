#include "torsion/contact/self_contact.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "torsion/format_number.h"

namespace torsion {

namespace {

// A projection within this of a triangle's edge (in barycentric units) still counts as inside:
// a node passing exactly over an edge is caught by both triangles (one is kept).
constexpr double kInsideTolerance = 0.05;
// Searches along the solved motion per step (each may add candidates and solves).
constexpr int kMaxRedetections = 3;
// Surface nodes (edges) per block of the parallel search: blocks are fixed, whatever the thread
// count, and their finds are added in block order.
constexpr int kSearchBlock = 64;

// Barycentric coordinates of p's projection onto the plane of (a, b, c).
Eigen::Vector3d barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1);
  const double d20 = d.dot(e0), d21 = d.dot(e1);
  const double det = d00 * d11 - d01 * d01;
  const double v = (d11 * d20 - d01 * d21) / det;
  const double w = (d00 * d21 - d01 * d20) / det;
  return {1.0 - v - w, v, w};
}

// Closest points of lines a + u (b - a) and c + v (d - c); false when (nearly) parallel.
bool closestPoints(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& d, double& u, double& v, double& distance) {
  const Eigen::Vector3d d1 = b - a, d2 = d - c, w = a - c;
  const double aa = d1.dot(d1), bb = d1.dot(d2), cc = d2.dot(d2), dd = d1.dot(w), ee = d2.dot(w);
  const double denominator = aa * cc - bb * bb;
  if (!(denominator > 1e-12 * aa * cc)) return false;
  u = (bb * ee - cc * dd) / denominator;
  v = (aa * ee - bb * dd) / denominator;
  distance = (a + u * d1 - c - v * d2).norm();
  return true;
}

}  // namespace

Status SelfContactSettings::validate() const {
  if (!(std::isfinite(friction) && friction >= 0))
    return Error{"self_contact: friction = " + formatNumber(friction) + ": must be >= 0"};
  if (!(std::isfinite(gap_tolerance) && gap_tolerance >= 0))
    return Error{"self_contact: gap_tolerance = " + formatNumber(gap_tolerance) +
                 ": must be >= 0 m (0: from the mesh)"};
  if (!(std::isfinite(margin) && margin >= 0 && margin <= 1))
    return Error{"self_contact: margin = " + formatNumber(margin) + ": must be in [0, 1]"};
  if (!(std::isfinite(max_depth) && max_depth > 0 && max_depth <= 0.5))
    return Error{"self_contact: max_depth = " + formatNumber(max_depth) + ": must be in (0, 0.5]"};
  if (!(std::isfinite(penalty_factor) && penalty_factor > 0))
    return Error{"self_contact: penalty_factor = " + formatNumber(penalty_factor) +
                 ": must be > 0"};
  if (!(std::isfinite(rough_tolerance_factor) && rough_tolerance_factor >= 1))
    return Error{"self_contact: rough_tolerance_factor = " + formatNumber(rough_tolerance_factor) +
                 ": must be >= 1"};
  if (max_iterations < 1)
    return Error{"self_contact: max_iterations = " + std::to_string(max_iterations) +
                 ": must be >= 1"};
  return Ok{};
}

SelfContactSolver::SelfContactSolver(std::shared_ptr<const FemModel> model,
                                     const SelfContactSettings& settings)
    : SelfContactSolver(std::move(model), settings, nullptr) {}

SelfContactSolver::SelfContactSolver(std::shared_ptr<const FemModel> model,
                                     const SelfContactSettings& settings, const Parallel& parallel)
    : SelfContactSolver(std::move(model), settings, &parallel) {}

SelfContactSolver::SelfContactSolver(std::shared_ptr<const FemModel> model,
                                     const SelfContactSettings& settings, const Parallel* parallel)
    : model_(std::move(model)),
      settings_(settings),
      own_parallel_(parallel != nullptr ? nullptr : std::make_unique<Parallel>(1)),
      parallel_(parallel != nullptr ? parallel : own_parallel_.get()),
      tree_(model_->mesh().surfaceTriangles()) {
  // Converged once the solved motion is within the gap tolerance of a physical one (every
  // impulse in Coulomb's cone), not once every state has stopped changing: in the plectoneme's
  // coils a few contacts switching stick and slide, or a sliding friction impulse still moving
  // with no visible effect, kept most contact steps going to max_iterations.
  set_.setConvergedWithinTolerance(true);
  const TetMesh& mesh = model_->mesh();
  const std::vector<Triangle>& triangles = mesh.surfaceTriangles();
  node_triangles_.assign(static_cast<size_t>(mesh.nodeCount()), {});
  double edges = 0;
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (size_t a = 0; a < 3; ++a) {
      node_triangles_[static_cast<size_t>(triangles[t][a])].push_back(static_cast<int>(t));
      edges += (mesh.restPositions()[static_cast<size_t>(triangles[t][a])] -
                mesh.restPositions()[static_cast<size_t>(triangles[t][(a + 1) % 3])])
                   .norm();
    }
  }
  mean_edge_ = triangles.empty() ? 0 : edges / (3.0 * static_cast<double>(triangles.size()));
  gap_tolerance_ = settings_.gap_tolerance > 0 ? settings_.gap_tolerance : 1e-3 * mean_edge_;
  node_contacts_.assign(static_cast<size_t>(mesh.nodeCount()), {});
  // Surface edges, each once, and the three of every triangle.
  std::vector<std::pair<std::array<int, 2>, int>> halves;  // (sorted corners, triangle)
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (size_t a = 0; a < 3; ++a) {
      std::array<int, 2> e = {triangles[t][a], triangles[t][(a + 1) % 3]};
      if (e[0] > e[1]) std::swap(e[0], e[1]);
      halves.emplace_back(e, static_cast<int>(t));
    }
  }
  std::sort(halves.begin(), halves.end());
  triangle_edges_.assign(triangles.size(), {});
  for (size_t k = 0; k < halves.size(); ++k) {
    if (k == 0 || halves[k].first != halves[k - 1].first) edges_.push_back(halves[k].first);
    triangle_edges_[static_cast<size_t>(halves[k].second)].push_back(
        static_cast<int>(edges_.size()) - 1);
  }
}

bool SelfContactSolver::detect(const FemState& state, const NodeConstraints& constraints,
                               double dt) {
  dt_ = dt;
  stats_ = SelfContactStats{};
  set_.beginStep();
  for (int p : touched_nodes_)
    node_contacts_[static_cast<size_t>(p)].clear();
  edge_pairs_.clear();
  touched_nodes_.clear();
  start_ = &state.positions;
  constraints_ = &constraints;
  end_ = state.positions + dt * state.velocities;  // the predicted motion, before contacts
  addCandidates(state.positions, end_);
  stats_.candidates = static_cast<int>(set_.contacts().size());
  return !set_.empty();
}

int SelfContactSolver::addCandidates(const Eigen::VectorXd& x, const Eigen::VectorXd& end) {
  ++stats_.searches;
  const auto started = std::chrono::steady_clock::now();
  tree_.refit(x, end, settings_.margin * mean_edge_);
  const size_t before = set_.contacts().size();
  // Nodes against triangles: every triangle found is kept. A node passing over an edge or a
  // corner gets a contact with each triangle there (redundant constraints share the impulse; one
  // alone would let the node cross the neighbour's plane).
  const std::vector<int>& nodes = model_->mesh().surfaceNodes();
  const int node_blocks = (static_cast<int>(nodes.size()) + kSearchBlock - 1) / kSearchBlock;
  block_finds_.resize(static_cast<size_t>(
      std::max(node_blocks, (static_cast<int>(edges_.size()) + kSearchBlock - 1) / kSearchBlock)));
  parallel_->forRange(node_blocks, 1, [&](int first, int last) {
    std::vector<int> found;
    for (int block = first; block < last; ++block) {
      std::vector<SurfaceContact>& finds = block_finds_[static_cast<size_t>(block)];
      finds.clear();
      const size_t end_node = std::min(nodes.size(), static_cast<size_t>(block + 1) * kSearchBlock);
      for (size_t k = static_cast<size_t>(block) * kSearchBlock; k < end_node; ++k) {
        const int p = nodes[k];
        const Eigen::Vector3d xp = x.segment<3>(3 * p), ep = end.segment<3>(3 * p);
        tree_.query(xp.cwiseMin(ep), xp.cwiseMax(ep), found);
        for (int t : found)
          if (std::optional<SurfaceContact> c = nodeCandidate(p, t, x, end)) finds.push_back(*c);
      }
    }
  });
  for (int block = 0; block < node_blocks; ++block) {
    for (const SurfaceContact& c : block_finds_[static_cast<size_t>(block)]) {
      std::vector<int>& kept = node_contacts_[static_cast<size_t>(c.nodes[0])];
      if (kept.empty()) touched_nodes_.push_back(c.nodes[0]);
      kept.push_back(static_cast<int>(set_.contacts().size()));
      set_.add(c);
      stats_.max_penetration = std::max(stats_.max_penetration, -c.gap);
    }
  }
  // Edges against edges, the same way, after each edge's box over the motion.
  const int edge_blocks = (static_cast<int>(edges_.size()) + kSearchBlock - 1) / kSearchBlock;
  edge_lo_.resize(edges_.size());
  edge_hi_.resize(edges_.size());
  for (size_t i = 0; i < edges_.size(); ++i) {
    const std::array<int, 2>& e = edges_[i];
    const Eigen::Vector3d p0 = x.segment<3>(3 * e[0]), q0 = x.segment<3>(3 * e[1]);
    const Eigen::Vector3d p1 = end.segment<3>(3 * e[0]), q1 = end.segment<3>(3 * e[1]);
    edge_lo_[i] = p0.cwiseMin(q0).cwiseMin(p1).cwiseMin(q1);
    edge_hi_[i] = p0.cwiseMax(q0).cwiseMax(p1).cwiseMax(q1);
  }
  parallel_->forRange(edge_blocks, 1, [&](int first, int last) {
    std::vector<int> scratch;
    for (int block = first; block < last; ++block) {
      std::vector<SurfaceContact>& finds = block_finds_[static_cast<size_t>(block)];
      finds.clear();
      const int end_edge = std::min(static_cast<int>(edges_.size()), (block + 1) * kSearchBlock);
      for (int i = block * kSearchBlock; i < end_edge; ++i)
        edgeCandidates(i, x, end, scratch, finds);
    }
  });
  for (int block = 0; block < edge_blocks; ++block) {
    for (const SurfaceContact& c : block_finds_[static_cast<size_t>(block)]) {
      edge_pairs_.insert((static_cast<std::uint64_t>(c.edge) << 32) |
                         static_cast<std::uint32_t>(c.triangle));
      set_.add(c);
    }
  }
  const NodeConstraints& constraints = *constraints_;
  set_.markDetermined(
      [&](int node) { return constraints.kind(node) == NodeConstraints::Kind::kFull; });
  stats_.search_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return static_cast<int>(set_.contacts().size() - before);
}

std::optional<SurfaceContact> SelfContactSolver::nodeCandidate(int p, int t,
                                                               const Eigen::VectorXd& x,
                                                               const Eigen::VectorXd& end) const {
  const Triangle& tri = tree_.triangles()[static_cast<size_t>(t)];
  if (tri[0] == p || tri[1] == p || tri[2] == p) return std::nullopt;  // the node's own one-ring
  for (int k : node_contacts_[static_cast<size_t>(p)])                 // a pair this step has
    if (set_.contacts()[static_cast<size_t>(k)].triangle == t) return std::nullopt;
  const double margin = settings_.margin * mean_edge_;
  const Eigen::Vector3d xp = x.segment<3>(3 * p), ep = end.segment<3>(3 * p);
  const Eigen::Vector3d a0 = x.segment<3>(3 * tri[0]), b0 = x.segment<3>(3 * tri[1]),
                        c0 = x.segment<3>(3 * tri[2]);
  Eigen::Vector3d n0 = (b0 - a0).cross(c0 - a0);
  if (!(n0.norm() > 0)) return std::nullopt;  // degenerate: no plane to stay out of
  n0.normalize();
  const double g0 = n0.dot(xp - a0);
  const double shortest = std::min({(b0 - a0).norm(), (c0 - b0).norm(), (a0 - c0).norm()});
  if (g0 < -settings_.max_depth * shortest) return std::nullopt;  // the far side of the body
  // Behind the plane beyond the tolerance: only a contact already held last step is still one
  // (it sank within its tolerance); a new pair there is a node across a sharp convex crease
  // (behind the plane, not through the surface), which a contact would throw out violently.
  if (g0 < -2 * gap_tolerance_ && !set_.wasActive(p, t)) return std::nullopt;
  const Eigen::Vector3d a1 = end.segment<3>(3 * tri[0]), b1 = end.segment<3>(3 * tri[1]),
                        c1 = end.segment<3>(3 * tri[2]);
  Eigen::Vector3d n1 = (b1 - a1).cross(c1 - a1);
  if (!(n1.norm() > 0)) n1 = n0;
  const double g1 = n1.normalized().dot(ep - a1);
  // When on the path the node meets the plane: now if it is within the margin, at the
  // crossing if it passes through, at the end if it ends within the margin.
  double s;
  if (g0 <= margin) {
    s = 0;
  } else if (g1 < 0) {
    s = g0 / (g0 - g1);
  } else if (g1 <= margin) {
    s = 1;
  } else {
    return std::nullopt;
  }
  const Eigen::Vector3d w =
      barycentric(xp + s * (ep - xp), a0 + s * (a1 - a0), b0 + s * (b1 - b0), c0 + s * (c1 - c0));
  if (!w.allFinite() || w.minCoeff() < -kInsideTolerance) return std::nullopt;
  const Eigen::Vector3d wc = w.cwiseMax(0.0) / w.cwiseMax(0.0).sum();
  SurfaceContact c;
  c.nodes = {p, tri[0], tri[1], tri[2]};
  c.beta = {1.0, -wc[0], -wc[1], -wc[2]};
  c.triangle = t;
  c.normal = n0;
  c.gap = g0;  // to the triangle's plane, at the start of the step
  c.friction = settings_.friction;
  return c;
}

Eigen::Vector3d SelfContactSolver::edgeNormal(const std::array<int, 2>& edge,
                                              const Eigen::VectorXd& x) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int t : node_triangles_[static_cast<size_t>(edge[0])]) {
    const Triangle& tri = tree_.triangles()[static_cast<size_t>(t)];
    if (tri[0] != edge[1] && tri[1] != edge[1] && tri[2] != edge[1]) continue;
    const Eigen::Vector3d a = x.segment<3>(3 * tri[0]);
    sum += (x.segment<3>(3 * tri[1]) - a).cross(x.segment<3>(3 * tri[2]) - a).normalized();
  }
  return sum.normalized();
}

void SelfContactSolver::edgeCandidates(int i, const Eigen::VectorXd& x, const Eigen::VectorXd& end,
                                       std::vector<int>& scratch,
                                       std::vector<SurfaceContact>& out) const {
  const double margin = settings_.margin * mean_edge_;
  const std::array<int, 2>& e = edges_[static_cast<size_t>(i)];
  const Eigen::Vector3d p0 = x.segment<3>(3 * e[0]), q0 = x.segment<3>(3 * e[1]);
  const Eigen::Vector3d p1 = end.segment<3>(3 * e[0]), q1 = end.segment<3>(3 * e[1]);
  std::vector<int>& triangles = scratch;
  tree_.query(edge_lo_[static_cast<size_t>(i)], edge_hi_[static_cast<size_t>(i)], triangles);
  // The later edges of the triangles found, each once, ascending.
  std::vector<int> later;
  later.reserve(3 * triangles.size());
  for (int t : triangles)
    for (int j : triangle_edges_[static_cast<size_t>(t)])
      if (j > i) later.push_back(j);
  std::sort(later.begin(), later.end());
  later.erase(std::unique(later.begin(), later.end()), later.end());
  for (int j : later) {
    const std::array<int, 2>& f = edges_[static_cast<size_t>(j)];
    if (f[0] == e[0] || f[0] == e[1] || f[1] == e[0] || f[1] == e[1]) continue;  // adjacent
    // Boxes over the motion more than the margin apart: never within it, never crossing.
    const Eigen::Vector3d& lo = edge_lo_[static_cast<size_t>(j)];
    const Eigen::Vector3d& hi = edge_hi_[static_cast<size_t>(j)];
    if (((lo.array() - margin) > edge_hi_[static_cast<size_t>(i)].array()).any() ||
        ((hi.array() + margin) < edge_lo_[static_cast<size_t>(i)].array()).any())
      continue;
    const std::uint64_t pair =
        (static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j);
    if (edge_pairs_.count(pair) != 0) continue;  // this step has it already
    const Eigen::Vector3d r0 = x.segment<3>(3 * f[0]), s0 = x.segment<3>(3 * f[1]);
    const Eigen::Vector3d r1 = end.segment<3>(3 * f[0]), s1 = end.segment<3>(3 * f[1]);
    // Normal: across both edges, pointing from edge f to edge e at the start.
    Eigen::Vector3d n0 = (q0 - p0).cross(s0 - r0);
    const double scale = (q0 - p0).norm() * (s0 - r0).norm();
    if (!(n0.norm() > 1e-3 * scale)) continue;  // nearly parallel: nodes and faces hold them
    n0.normalize();
    double g0 = n0.dot(p0 - r0);
    {
      // Cheap rejection first: apart now and at the end of the path, on the same side.
      const Eigen::Vector3d m1 = (q1 - p1).cross(s1 - r1);
      const double h1 = m1.norm() > 0 ? m1.normalized().dot(p1 - r1) : g0;
      if (std::abs(g0) > margin && std::abs(h1) > margin &&
          (g0 > 0) == (m1.dot(n0) >= 0 ? h1 > 0 : h1 < 0))
        continue;
    }
    if (std::abs(g0) <= margin) {
      // Within the margin now, whichever way the normal turns: the pair is judged at the start,
      // so its closest points can rule it out before the (dearer) orientation. Neighbouring
      // edges of one face lie in a plane and end here.
      double u, v, distance;
      if (!closestPoints(p0, q0, r0, s0, u, v, distance)) continue;
      if (!(u > 0 && u < 1 && v > 0 && v < 1) || distance > margin) continue;
    }
    SurfaceContact contact;
    contact.triangle = j;
    contact.edge = i;
    // Oriented out of f's surface into e's (the sum of each edge's triangles' outward
    // normals): the sign of the gap alone is arbitrary for edges lying in one plane, as those
    // of two faces pressed together do, and a wrong sign pushes one face into the other. A
    // pair held last step (which may have crossed within the tolerance) keeps the side its
    // impulse pushed.
    const Eigen::Vector3d* held = set_.warmStartOf(contact);
    const Eigen::Vector3d outward = edgeNormal(f, x) - edgeNormal(e, x);
    const double side = held != nullptr ? n0.dot(*held) : n0.dot(outward);
    if (held == nullptr && std::abs(side) < 0.5 * outward.norm()) continue;  // not facing
    if (side < 0) {
      n0 = -n0;
      g0 = -g0;
    }
    if (g0 < -2 * gap_tolerance_ && held == nullptr) continue;  // crossed before, or apart
    if (g0 < -settings_.max_depth * (q0 - p0).norm()) continue;
    Eigen::Vector3d n1 = (q1 - p1).cross(s1 - r1);
    if (n1.dot(n0) < 0) n1 = -n1;
    if (!(n1.norm() > 0)) n1 = n0;
    const double g1 = n1.normalized().dot(p1 - r1);
    double when;
    if (g0 <= margin) {
      when = 0;
    } else if (g1 < 0) {
      when = g0 / (g0 - g1);
    } else if (g1 <= margin) {
      when = 1;
    } else {
      continue;
    }
    // Closest points of the two lines at that moment; both must lie inside their edges.
    const Eigen::Vector3d a = p0 + when * (p1 - p0), b = q0 + when * (q1 - q0);
    const Eigen::Vector3d c = r0 + when * (r1 - r0), d = s0 + when * (s1 - s0);
    double u, v, distance;
    if (!closestPoints(a, b, c, d, u, v, distance)) continue;
    if (!(u > 0 && u < 1 && v > 0 && v < 1)) continue;
    // Closer at the start than the margin, or crossing on the path, but not closer than the
    // points: a pair whose lines pass near while the edges stay apart is no contact.
    if (when == 0 && distance > margin) continue;
    contact.nodes = {e[0], e[1], f[0], f[1]};
    contact.beta = {1.0 - u, u, -(1.0 - v), -v};
    contact.normal = n0;
    contact.gap = g0;
    contact.friction = settings_.friction;
    out.push_back(contact);
  }
}

LinearSolveReport SelfContactSolver::solve(const SystemOperator& op,
                                           const NodeConstraints& constraints,
                                           const Eigen::VectorXd& b, const SolverSettings& settings,
                                           Eigen::VectorXd& v, const InnerSolve& inner) {
  // Penalties from the system without the term (the operator includes it otherwise); its
  // diagonal blocks are only taken once there are candidates.
  penalties_ready_ = false;
  const auto set_penalties = [&] {
    if (!penalties_ready_) {
      set_.setSuspended(true);
      op.diagonalBlocks(blocks_);
      set_.setSuspended(false);
      penalties_ready_ = true;
    }
    set_.setPenalties(blocks_, settings_.penalty_factor);
  };
  if (!set_.empty()) set_penalties();
  // Activation below a tenth of the tolerance: a contact hovering at zero gap does not flip.
  const double activation = 0.1 * gap_tolerance_;

  LinearSolveReport total;
  stats_.converged = false;
  const int rounds = inner ? 1 : settings_.max_iterations;
  int redetections = 0;
  double best_error = std::numeric_limits<double>::infinity();  // no accurate round yet
  int worse = 0;
  // Rough rounds first: while the active set and the multipliers are still far from settled,
  // each CG solve stops at rough_tolerance_factor times the tolerance (its motion only steers
  // the next Uzawa update). Once a rough round settles, or three rough rounds in a row did
  // worse, or a quarter of the rounds has passed, the rounds are accurate for the rest of the
  // step: the step only ends on an accurate solve, judged by the same criteria as before. A
  // round with no contact pushing is accurate (a step with candidates but no contact solves as
  // it did without the rough rounds, to the bit).
  SolverSettings rough = settings;
  rough.tolerance = settings_.rough_tolerance_factor * settings.tolerance;
  bool rough_over = inner || !(settings_.rough_tolerance_factor > 1);
  double rough_best = -1;  // the smallest gap error of the rough rounds (-1: none yet)
  const auto any_pushing = [this] {
    for (const SurfaceContact& c : set_.contacts())
      if (!c.determined && c.state != SurfaceContact::State::kInactive) return true;
    return false;
  };
  for (int round = 0; round < rounds; ++round) {
    // Where the rough rounds cycle, the accurate ones still have three quarters to settle in.
    if (round == rounds - 1 || 4 * round >= rounds) rough_over = true;
    const bool accurate = rough_over || !any_pushing();
    b_aug_ = b;
    set_.addRightHandSide(dt_, b_aug_);
    const SolverSettings& round_settings = accurate ? settings : rough;
    const LinearSolveReport r = inner ? inner(op, constraints, b_aug_, settings, v)
                                      : cg_.solve(op, constraints, b_aug_, round_settings, v);
    total.iterations += r.iterations;
    total.relative_residual = r.relative_residual;
    total.converged = r.converged;
    total.breakdown = r.breakdown;
    total.breakdown_reason = r.breakdown_reason;
    ++stats_.iterations;
    if (r.breakdown) break;
    const bool settled = set_.update(v, dt_, activation, gap_tolerance_);
    if (!accurate) {
      // Rough: no best kept, nothing judged; worse rounds end the rough phase instead.
      const double error = set_.maxGapError();
      const bool first_rough = rough_best < 0;
      if (settled ||
          (!first_rough && error >= rough_best && error > gap_tolerance_ && ++worse >= 3)) {
        rough_over = true;
      } else if (first_rough || error < rough_best) {
        worse = 0;
      }
      rough_best = first_rough ? error : std::min(rough_best, error);
      if (rough_over) {
        // The accurate rounds start their own safeguard: the first is the best so far.
        worse = 0;
        best_error = std::numeric_limits<double>::infinity();
      }
      continue;
    }
    // Safeguard: where constraints contradict each other (crossed before, a crease) Uzawa can
    // diverge. The best solve so far is kept; three worse ones in a row, beyond the tolerance,
    // end the step with it (reported as not converged).
    // An update whose gaps are all within the tolerance is never "worse": it is kept and the
    // loop goes on to settle states and friction (stopping there left most of the plectoneme's
    // contact steps unconverged with their gaps already within the tolerance).
    const double error = set_.maxGapError();
    if (round == 0 || error < best_error || error <= gap_tolerance_) {
      best_error = error;
      best_v_ = v;
      best_contacts_ = set_.contacts();
      worse = 0;
    } else if (++worse >= 3) {
      v = best_v_;
      set_.contacts() = best_contacts_;
      break;
    }
    if (!settled) continue;
    // Converged on these candidates. The solved motion can differ from the predicted one the
    // candidates were found along (a kink snapping through): look again along x + dt v.
    // Unless every node ends within half the margin of its predicted end: then any pair the
    // solved path meets was found along the predicted one (within the margin at its end).
    const double margin = settings_.margin * mean_edge_;
    const double moved = (dt_ * v - (end_ - *start_)).lpNorm<Eigen::Infinity>();
    end_ = *start_ + dt_ * v;
    if (moved > 0.5 * margin / std::sqrt(3.0) && redetections < kMaxRedetections &&
        addCandidates(*start_, end_) > 0) {
      ++redetections;
      set_penalties();
      set_.update(v, dt_, activation, gap_tolerance_);  // activates the new ones
      continue;
    }
    stats_.converged = true;
    break;
  }
  stats_.candidates = static_cast<int>(set_.contacts().size());

  for (const SurfaceContact& c : set_.contacts()) {
    if (c.determined || c.state == SurfaceContact::State::kInactive) continue;
    ++stats_.active;
    if (c.state == SurfaceContact::State::kStick) ++stats_.sticking;
    stats_.normal_impulse += c.normal.dot(c.multiplier);
  }
  stats_.max_end_penetration = set_.maxEndPenetration();
  return total;
}

}  // namespace torsion
