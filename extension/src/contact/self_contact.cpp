#include "torsion/contact/self_contact.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "torsion/contact/solve/node_contact_rows.h"
#include "torsion/contact/surface_candidates.h"
#include "torsion/format_number.h"

namespace torsion {

namespace {

// Searches along the solved motion per step (each may add candidates and a solve).
constexpr int kMaxRedetections = 3;
// Surface nodes (edges) per block of the parallel search: blocks are fixed, whatever the thread
// count, and their finds are added in block order.
constexpr int kSearchBlock = 64;

}  // namespace

Status SelfContactSettings::validate() const {
  if (!(std::isfinite(friction) && friction >= 0))
    return Error{"self_contact: friction = " + formatNumber(friction) + ": must be >= 0"};
  if (!(std::isfinite(gap_tolerance) && gap_tolerance >= 0))
    return Error{"self_contact: gap_tolerance = " + formatNumber(gap_tolerance) +
                 ": must be >= 0 m (0: from the mesh)"};
  if (!(std::isfinite(thickness_factor) && thickness_factor >= 0))
    return Error{"self_contact: thickness_factor = " + formatNumber(thickness_factor) +
                 ": must be >= 0 (times gap_tolerance)"};
  if (!(std::isfinite(margin) && margin >= 0 && margin <= 1))
    return Error{"self_contact: margin = " + formatNumber(margin) + ": must be in [0, 1]"};
  if (!(std::isfinite(max_depth) && max_depth > 0 && max_depth <= 0.5))
    return Error{"self_contact: max_depth = " + formatNumber(max_depth) + ": must be in (0, 0.5]"};
  if (!(std::isfinite(search_skin) && search_skin >= 0))
    return Error{"self_contact: search_skin = " + formatNumber(search_skin) + ": must be >= 0"};
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
      surface_edges_(model_->mesh().surfaceTriangles()),
      pairs_(model_->mesh().surfaceTriangles(), surface_edges_, model_->mesh().surfaceNodes()) {
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
}

bool SelfContactSolver::detect(const FemState& state, const NodeConstraints& constraints,
                               double dt) {
  dt_ = dt;
  redetections_ = 0;
  stats_ = SelfContactStats{};
  set_.beginStep();
  for (int p : touched_nodes_)
    node_contacts_[static_cast<size_t>(p)].clear();
  edge_pairs_.clear();
  touched_nodes_.clear();
  start_ = &state.positions;
  constraints_ = &constraints;
  // The predicted motion, before contacts, over the rows' reach: a row engages where its gap
  // closes within dt + tau_d (sap::RowDefaults).
  end_ = state.positions + dt * (1 + sap::RowDefaults{}.dissipation_steps) * state.velocities;
  addCandidates(state.positions, end_);
  stats_.candidates = static_cast<int>(set_.contacts().size());
  return !set_.empty();
}

int SelfContactSolver::addCandidates(const Eigen::VectorXd& x, const Eigen::VectorXd& end) {
  ++stats_.searches;
  const auto started = std::chrono::steady_clock::now();
  if (pairs_.prepare(x, end, settings_.margin * mean_edge_, settings_.search_skin * mean_edge_,
                     *parallel_))
    ++stats_.search_builds;
  const size_t before = set_.contacts().size();
  // Nodes against triangles: every triangle found is kept. A node passing over an edge or a
  // corner gets a contact with each triangle there (redundant constraints share the impulse; one
  // alone would let the node cross the neighbour's plane).
  const std::vector<int>& nodes = model_->mesh().surfaceNodes();
  const int node_blocks = (static_cast<int>(nodes.size()) + kSearchBlock - 1) / kSearchBlock;
  block_finds_.resize(static_cast<size_t>(
      std::max(node_blocks,
               (static_cast<int>(surface_edges_.edges.size()) + kSearchBlock - 1) / kSearchBlock)));
  parallel_->forRange(node_blocks, 1, [&](int first, int last) {
    std::vector<int> found;
    for (int block = first; block < last; ++block) {
      std::vector<SurfaceContact>& finds = block_finds_[static_cast<size_t>(block)];
      finds.clear();
      const size_t end_node = std::min(nodes.size(), static_cast<size_t>(block + 1) * kSearchBlock);
      for (size_t k = static_cast<size_t>(block) * kSearchBlock; k < end_node; ++k) {
        const int p = nodes[k];
        const Eigen::Vector3d xp = x.segment<3>(3 * p), ep = end.segment<3>(3 * p);
        pairs_.nodeTriangles(static_cast<int>(k), xp.cwiseMin(ep), xp.cwiseMax(ep), found);
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
  const int edge_blocks =
      (static_cast<int>(surface_edges_.edges.size()) + kSearchBlock - 1) / kSearchBlock;
  edge_lo_.resize(surface_edges_.edges.size());
  edge_hi_.resize(surface_edges_.edges.size());
  for (size_t i = 0; i < surface_edges_.edges.size(); ++i) {
    const std::array<int, 2>& e = surface_edges_.edges[i];
    const Eigen::Vector3d p0 = x.segment<3>(3 * e[0]), q0 = x.segment<3>(3 * e[1]);
    const Eigen::Vector3d p1 = end.segment<3>(3 * e[0]), q1 = end.segment<3>(3 * e[1]);
    edge_lo_[i] = p0.cwiseMin(q0).cwiseMin(p1).cwiseMin(q1);
    edge_hi_[i] = p0.cwiseMax(q0).cwiseMax(p1).cwiseMax(q1);
  }
  parallel_->forRange(edge_blocks, 1, [&](int first, int last) {
    std::array<std::vector<int>, 2> scratch;
    for (int block = first; block < last; ++block) {
      std::vector<SurfaceContact>& finds = block_finds_[static_cast<size_t>(block)];
      finds.clear();
      const int end_edge =
          std::min(static_cast<int>(surface_edges_.edges.size()), (block + 1) * kSearchBlock);
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
  const Triangle& tri = pairs_.triangles()[static_cast<size_t>(t)];
  if (tri[0] == p || tri[1] == p || tri[2] == p) return std::nullopt;  // the node's own one-ring
  for (int k : node_contacts_[static_cast<size_t>(p)])                 // a pair this step has
    if (set_.contacts()[static_cast<size_t>(k)].triangle == t) return std::nullopt;
  auto at = [](const Eigen::VectorXd& positions, int node) -> Eigen::Vector3d {
    return positions.segment<3>(3 * node);
  };
  const std::optional<NodeTriangleHit> hit = nodeTriangleCandidate(
      {at(x, p), at(end, p)}, {at(x, tri[0]), at(x, tri[1]), at(x, tri[2])},
      {at(end, tri[0]), at(end, tri[1]), at(end, tri[2])}, rules(), set_.wasActive(p, t), {});
  if (!hit) return std::nullopt;
  const Eigen::Vector3d wc = hit->weights.cwiseMax(0.0) / hit->weights.cwiseMax(0.0).sum();
  SurfaceContact c;
  c.nodes = {p, tri[0], tri[1], tri[2]};
  c.beta = {1.0, -wc[0], -wc[1], -wc[2]};
  c.triangle = t;
  c.normal = hit->normal;
  c.gap = hit->gap;  // to the triangle's plane, at the start of the step
  c.target_gap = thickness();
  c.friction = settings_.friction;
  return c;
}

void SelfContactSolver::edgeCandidates(int i, const Eigen::VectorXd& x, const Eigen::VectorXd& end,
                                       std::array<std::vector<int>, 2>& scratch,
                                       std::vector<SurfaceContact>& out) const {
  const double margin = settings_.margin * mean_edge_;
  const std::vector<std::array<int, 2>>& edges = surface_edges_.edges;
  const std::array<int, 2>& e = edges[static_cast<size_t>(i)];
  auto at = [](const Eigen::VectorXd& positions, int node) -> Eigen::Vector3d {
    return positions.segment<3>(3 * node);
  };
  const std::array<std::array<Eigen::Vector3d, 2>, 2> edge_e = {
      {{at(x, e[0]), at(x, e[1])}, {at(end, e[0]), at(end, e[1])}}};
  // The later edges of the triangles whose boxes the edge's meets, each once, ascending (and
  // possibly some the box test below drops: surface_pair_cache.h).
  const std::vector<int>& later =
      pairs_.laterEdges(i, edge_lo_[static_cast<size_t>(i)], edge_hi_[static_cast<size_t>(i)],
                        scratch[0], scratch[1]);
  // Asked only for pairs that pass the cheap tests (made once per edge, for the current pair).
  SurfaceContact contact;
  contact.edge = i;
  const std::function<const Eigen::Vector3d*()> held = [&] { return set_.warmStartOf(contact); };
  const std::function<Eigen::Vector3d()> outward = [&]() -> Eigen::Vector3d {
    return surface_edges_.outwardNormal(contact.triangle, pairs_.triangles(), x) -
           surface_edges_.outwardNormal(i, pairs_.triangles(), x);
  };
  for (int j : later) {
    const std::array<int, 2>& f = edges[static_cast<size_t>(j)];
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
    contact.triangle = j;
    const std::optional<EdgeEdgeHit> hit =
        edgeEdgeCandidate(edge_e, {{{at(x, f[0]), at(x, f[1])}, {at(end, f[0]), at(end, f[1])}}},
                          rules(), held, outward, {});
    if (!hit) continue;
    SurfaceContact c = contact;
    c.nodes = {e[0], e[1], f[0], f[1]};
    c.beta = {1.0 - hit->u, hit->u, -(1.0 - hit->v), -hit->v};
    c.normal = hit->normal;
    c.gap = hit->gap;
    c.target_gap = thickness();
    c.friction = settings_.friction;
    out.push_back(c);
  }
}

int SelfContactSolver::correctGaps(const Eigen::VectorXd& v) {
  const Eigen::VectorXd& x = *start_;
  auto end = [&](int node) -> Eigen::Vector3d {
    return x.segment<3>(3 * node) + dt_ * v.segment<3>(3 * node);
  };
  int shifted = 0;
  for (SurfaceContact& c : set_.contacts()) {
    if (c.determined) continue;
    const Eigen::Vector3d p = end(c.nodes[0]), q = end(c.nodes[1]), r = end(c.nodes[2]),
                          t = end(c.nodes[3]);
    double true_gap = 0;
    if (c.edge < 0) {
      Eigen::Vector3d n = (r - q).cross(t - q);
      if (!(n.norm() > 0)) continue;
      n.normalize();
      const Eigen::Vector3d w = projectionWeights(p, q, r, t);
      if (!w.allFinite() || w.minCoeff() < -kFaceInsideTolerance) continue;  // slid off this face
      true_gap = n.dot(p - q);
    } else {
      double u = 0, s = 0, distance = 0;
      if (!closestPointsOfLines(p, q, r, t, u, s, distance)) continue;  // parallel at the end
      if (u < 0 || u > 1 || s < 0 || s > 1) continue;  // the edges slid past each other
      Eigen::Vector3d n = (q - p).cross(t - r);
      if (!(n.norm() > 0)) continue;
      n.normalize();
      if (n.dot(c.normal) < 0) n = -n;  // the side the contact keeps its edges on
      true_gap = n.dot((p + u * (q - p)) - (r + s * (t - r)));
    }
    double linear_gap = c.gap;
    for (size_t k = 0; k < c.nodes.size(); ++k)
      linear_gap += dt_ * c.beta[k] * c.normal.dot(v.segment<3>(3 * c.nodes[k]));
    if (true_gap >= c.target_gap - gap_tolerance_ || true_gap >= linear_gap) continue;
    c.gap += true_gap - linear_gap;
    ++shifted;
  }
  return shifted;
}

CandidateRules SelfContactSolver::rules() const {
  CandidateRules rules;
  rules.margin = settings_.margin * mean_edge_;
  rules.max_depth = settings_.max_depth;
  rules.crease_depth = 2 * gap_tolerance_;
  return rules;
}

int SelfContactSolver::searchAlong(const Eigen::VectorXd& v) {
  const double margin = settings_.margin * mean_edge_;
  const double moved = (dt_ * v - (end_ - *start_)).lpNorm<Eigen::Infinity>();
  if (!(moved > 0.5 * margin / std::sqrt(3.0)) || redetections_ >= kMaxRedetections) return 0;
  ++redetections_;
  end_ = *start_ + dt_ * v;
  return addCandidates(*start_, end_);
}

void SelfContactSolver::finishStep(int iterations, bool converged) {
  stats_.iterations = iterations;
  stats_.converged = converged;
  stats_.candidates = static_cast<int>(set_.contacts().size());
  stats_.active = stats_.sticking = 0;
  stats_.normal_impulse = 0;
  for (const SurfaceContact& c : set_.contacts()) {
    if (c.determined || c.state == SurfaceContact::State::kInactive) continue;
    ++stats_.active;
    if (c.state == SurfaceContact::State::kStick) ++stats_.sticking;
    stats_.normal_impulse += c.normal.dot(c.multiplier);
  }
  stats_.max_end_penetration = set_.maxEndPenetration();
}

}  // namespace torsion
