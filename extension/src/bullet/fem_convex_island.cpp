// An island of touching FEM bodies stepped as one convex problem (docs/contact-solve.md, "FEM
// bodies in one island"): every body prepares its step, each hands out its share of rows (its
// contacts with rigid objects, the rigid bodies' contacts and joints it took from Bullet), the
// pairs add their rows between the bodies, one SAP problem holds them all, and every body takes
// its answer back and finishes its step.

#include <algorithm>
#include <cstddef>
#include <map>
#include <memory>
#include <utility>

#include "torsion/bullet/fem_contact_islands.h"
#include "torsion/contact/solve/convex_rows.h"
#include "torsion/contact/solve/fem_island_body.h"
#include "torsion/contact/solve/surface_contact_rows.h"

namespace torsion {

namespace {

// Passes that move the pairs' linearised gaps onto the true end-of-step surface, as the older
// island solve makes them (island_contact.cpp).
constexpr int kMaxPairGapCorrections = 4;

// The island's bodies and rows, merged from the shares: FEM bodies first (in the group's order),
// then each dynamic rigid body once, in the order the shares first name them.
struct MergedIsland {
  std::vector<std::unique_ptr<sap::FemIslandBody>> fem;
  std::vector<const sap::IslandBody*> bodies;
  std::vector<sap::ContactRow> rows;
  std::vector<int> row_group;
  // Per share: per row, its island row; per rigid body, its island body and whether the share
  // owns it (applies its twist).
  std::vector<std::vector<int>> share_rows;
  std::vector<std::vector<int>> share_bodies;
  std::vector<std::vector<char>> share_owns;
  std::vector<Vector6d> rigid_start;  // per rigid island body (after the FEM bodies)
};

void mergeShare(MergedIsland& m, sap::ConvexRows& share, int fem_body, int& next_group,
                std::map<const btCollisionObject*, int>& rigid_of,
                std::map<std::pair<const void*, int>, int>& shared_row) {
  std::vector<int> bodies(share.body_objects.size());
  std::vector<char> owns(share.body_objects.size(), 0);
  for (std::size_t j = 0; j < share.body_objects.size(); ++j) {
    const auto [it, added] =
        rigid_of.emplace(share.body_objects[j], static_cast<int>(m.bodies.size()));
    if (added) {
      m.bodies.push_back(share.island.rigid_bodies[j].get());
      m.rigid_start.push_back(share.start_twists[j]);
      owns[j] = 1;
    }
    bodies[j] = it->second;
  }
  const int group_offset = next_group;
  std::vector<int> rows(share.island.rows.size());
  for (std::size_t r = 0; r < share.island.rows.size(); ++r) {
    const void* key = share.row_key[r];
    if (key != nullptr) {
      const auto [it, added] = shared_row.emplace(std::pair{key, share.row_key_index[r]},
                                                  static_cast<int>(m.rows.size()));
      if (!added) {  // held by an earlier share: the same row, solved once
        rows[r] = it->second;
        continue;
      }
    }
    sap::ContactRow row = share.island.rows[r];
    for (sap::ContactTerm& term : row.terms)
      term.body = term.body == 0 ? fem_body : bodies[static_cast<std::size_t>(term.body - 1)];
    rows[r] = static_cast<int>(m.rows.size());
    m.rows.push_back(std::move(row));
    m.row_group.push_back(group_offset + share.row_group[r]);
    next_group = std::max(next_group, group_offset + share.row_group[r] + 1);
  }
  m.share_rows.push_back(std::move(rows));
  m.share_bodies.push_back(std::move(bodies));
  m.share_owns.push_back(std::move(owns));
}

// `report` restricted to one share's rows, in their order.
sap::SapReport shareReport(const sap::SapReport& report, const std::vector<int>& rows) {
  sap::SapReport out;
  out.converged = report.converged;
  out.message = report.message;
  out.newton_iterations = report.newton_iterations;
  out.cg_iterations = report.cg_iterations;
  for (int r : rows) {
    const auto k = static_cast<std::size_t>(r);
    out.impulses.push_back(report.impulses[k]);
    out.contact_velocities.push_back(report.contact_velocities[k]);
    out.states.push_back(report.states[k]);
  }
  return out;
}

}  // namespace

int FemContactIslands::correctPairGaps(sap::SapProblem& problem, const Eigen::VectorXd& x,
                                       const std::vector<int>& island_body,
                                       const std::vector<int>& pair_first, double dt) {
  int shifted = 0;
  Eigen::VectorXd pair_v;
  for (std::size_t p = 0; p < island_pairs_.size(); ++p) {
    if (pair_first[p] < 0) continue;
    const IslandContactSolve::Pair& pair = island_pairs_[p];
    const int a = island_body[static_cast<std::size_t>(pair.first)];
    const int b = island_body[static_cast<std::size_t>(pair.second)];
    const Eigen::Index na = problem.body(a).dofs(), nb = problem.body(b).dofs();
    pair_v.resize(na + nb);
    pair_v.head(na) = x.segment(problem.bodyOffset(a), na);
    pair_v.tail(nb) = x.segment(problem.bodyOffset(b), nb);
    BodyPairContact& contact = *pair.contact;
    if (contact.correctGaps(pair_v, dt, contact.gapTolerance()) == 0) continue;
    const std::vector<SurfaceContact>& candidates = contact.set().contacts();
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const int row = pair_first[p] + static_cast<int>(c);
      const double gap = candidates[c].gap - candidates[c].target_gap;  // as the row was made
      if (gap != problem.row(row).gap) {
        problem.setGap(row, gap);
        ++shifted;
      }
    }
  }
  return shifted;
}

bool FemContactIslands::advanceConvex(const std::vector<FemBody*>& group, const StepContext& ctx) {
  const sap::RowDefaults defaults;
  MergedIsland m;
  std::vector<int> island_body(group.size(), -1);  // per group body: its island body, or -1
  std::vector<PreparedSystem> systems(group.size());
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (!group[k]->prepare(ctx)) continue;  // it leaves the island; its pairs sit the step out
    slots_[k].present = true;  // addStats notes an unconverged solve on the bodies present
    systems[k] = group[k]->preparedSystem();
    island_body[k] = static_cast<int>(m.fem.size());
    m.fem.push_back(std::make_unique<sap::FemIslandBody>(*systems[k].op, *systems[k].constraints,
                                                         *systems[k].b));
    m.bodies.push_back(m.fem.back().get());
  }
  if (m.fem.empty()) {
    island_stats_ = IslandContactStats{};
    return false;
  }
  // Each present body's share, its rigid bodies after all the FEM bodies.
  std::vector<sap::ConvexRows> shares(group.size());
  std::map<const btCollisionObject*, int> rigid_of;
  std::map<std::pair<const void*, int>, int> shared_row;
  int next_group = 0;
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (island_body[k] < 0) continue;
    shares[k] = group[k]->contacts().convexRows();
    mergeShare(m, shares[k], island_body[k], next_group, rigid_of, shared_row);
  }
  // The pairs' rows, each pair its own friction-bound group.
  std::vector<int> pair_first(island_pairs_.size(), -1);
  island_stats_ = IslandContactStats{};
  for (std::size_t p = 0; p < island_pairs_.size(); ++p) {
    const IslandContactSolve::Pair& pair = island_pairs_[p];
    const int a = island_body[static_cast<std::size_t>(pair.first)];
    const int b = island_body[static_cast<std::size_t>(pair.second)];
    if (a < 0 || b < 0) continue;
    pair_first[p] = sap::addSurfaceContactRows(m.rows, pair.contact->set(),
                                               pair.contact->nodeCountA(), a, b, defaults, ctx.dt);
    m.row_group.resize(m.rows.size(), next_group++);
    island_stats_.candidates += static_cast<int>(pair.contact->set().contacts().size());
    island_stats_.gap_tolerance =
        std::max(island_stats_.gap_tolerance, pair.contact->gapTolerance());
  }
  Result<sap::SapProblem> created = sap::SapProblem::create(m.bodies, std::move(m.rows), ctx.dt);
  if (!created) {
    // Cannot happen with rows built from the bodies' own data; reported, never skipped silently.
    for (std::size_t k = 0; k < group.size(); ++k)
      if (island_body[k] >= 0) group[k]->noteContactNotConverged(created.error().message);
    island_stats_.converged = false;
    return true;
  }
  sap::SapProblem& problem = created.value();
  Eigen::VectorXd x(problem.dofs());
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (island_body[k] < 0) continue;
    const int body = island_body[k];
    x.segment(problem.bodyOffset(body), systems[k].v->size()) = *systems[k].v;
  }
  const int fem_count = static_cast<int>(m.fem.size());
  for (std::size_t j = 0; j < m.rigid_start.size(); ++j)
    x.segment<6>(problem.bodyOffset(fem_count + static_cast<int>(j))) = m.rigid_start[j];
  sap::SapReport report = sap::solveWithMatchedFrictionBounds(problem, m.row_group, x);
  // The pairs' gaps moved onto the true end-of-step surface, and solved again, until none moves
  // (BodyPairContact::correctGaps: a secant step of each gap with its detection normal as the
  // slope). The rows are linearised at the step's start; at 15 m/s a node ended 9.6 mm inside
  // the other cube without this (bullet_collide_soft).
  int newton = report.newton_iterations, cg = report.cg_iterations;
  for (int round = 0; round < kMaxPairGapCorrections && report.converged; ++round) {
    if (correctPairGaps(problem, x, island_body, pair_first, ctx.dt) == 0) break;
    report = sap::solveWithMatchedFrictionBounds(problem, m.row_group, x);
    newton += report.newton_iterations;
    cg += report.cg_iterations;
  }
  report.newton_iterations = newton;
  report.cg_iterations = cg;
  const std::vector<Vector6d> twists = sap::solvedTwists(problem, report, fem_count);

  // Every share takes its answer; the pairs keep their impulses for the next step's bounds.
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (island_body[k] < 0) continue;
    const std::size_t s = static_cast<std::size_t>(island_body[k]);
    std::vector<sap::SolvedBody> solved(m.share_bodies[s].size());
    for (std::size_t j = 0; j < solved.size(); ++j) {
      solved[j].twist = twists[static_cast<std::size_t>(m.share_bodies[s][j] - fem_count)];
      solved[j].applies = m.share_owns[s][j] != 0;
    }
    group[k]->contacts().takeConvexSolution(shares[k], shareReport(report, m.share_rows[s]),
                                            solved);
    *systems[k].v = x.segment(problem.bodyOffset(island_body[k]), systems[k].v->size());
  }
  for (std::size_t p = 0; p < island_pairs_.size(); ++p) {
    if (pair_first[p] < 0) continue;
    SurfaceContactSet& set = island_pairs_[p].contact->set();
    sap::takeSurfaceContactImpulses(set, problem, pair_first[p], report, ctx.dt);
    for (const SurfaceContact& c : set.contacts()) {
      island_stats_.max_end_penetration = std::max(island_stats_.max_end_penetration, -c.end_gap);
      if (c.state == SurfaceContact::State::kInactive) continue;
      ++island_stats_.active;
      if (c.state == SurfaceContact::State::kStick) ++island_stats_.sticking;
      island_stats_.normal_impulse += std::max(0.0, c.normal.dot(c.multiplier));
    }
  }
  island_stats_.iterations = report.newton_iterations;
  island_stats_.converged = report.converged;
  LinearSolveReport solve;
  solve.iterations = report.cg_iterations;
  solve.converged = true;  // the island's own verdict: island_stats_.converged
  // Last body first, as the older island solve finishes them.
  for (std::size_t k = group.size(); k-- > 0;) {
    if (island_body[k] >= 0) group[k]->finish(*systems[k].v, solve);
  }
  return true;
}

}  // namespace torsion
