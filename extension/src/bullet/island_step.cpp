// One contact island's step as one convex problem (island_step.h, docs/contact-solve.md).

#include "torsion/bullet/island_step.h"

#include <algorithm>
#include <cstddef>
#include <map>
#include <memory>
#include <sstream>
#include <utility>

#include "torsion/contact/solve/convex_rows.h"
#include "torsion/contact/solve/fem_island_body.h"
#include "torsion/contact/solve/surface_contact_rows.h"

namespace torsion {

namespace {

// Passes that move the surface rows' linearised gaps onto the true end-of-step surface (and let
// self-contact look along the solved motion), each followed by a solve.
constexpr int kMaxSurfaceCorrections = 4;

// The island's bodies and rows, merged from the shares: FEM bodies first (in the group's order),
// then each dynamic rigid body once, in the order the shares first name them.
struct MergedIsland {
  std::vector<std::unique_ptr<sap::FemIslandBody>> fem;
  std::vector<const sap::IslandBody*> bodies;
  std::vector<sap::ContactRow> rows;
  std::vector<int> row_group;
  int next_group = 0;  // the next free friction-bound group
  // Per share: per row, its island row; per rigid body, its island body and whether the share
  // owns it (applies its twist).
  std::vector<std::vector<int>> share_rows;
  std::vector<std::vector<int>> share_bodies;
  std::vector<std::vector<char>> share_owns;
  std::vector<Vector6d> rigid_start;  // per rigid island body (after the FEM bodies)
  std::map<const btCollisionObject*, int> rigid_of;
  std::map<std::pair<const void*, int>, int> shared_row;
};

void mergeShare(MergedIsland& m, sap::ConvexRows& share, int fem_body) {
  std::vector<int> bodies(share.body_objects.size());
  std::vector<char> owns(share.body_objects.size(), 0);
  for (std::size_t j = 0; j < share.body_objects.size(); ++j) {
    const auto [it, added] =
        m.rigid_of.emplace(share.body_objects[j], static_cast<int>(m.bodies.size()));
    if (added) {
      m.bodies.push_back(share.island.rigid_bodies[j].get());
      m.rigid_start.push_back(share.start_twists[j]);
      owns[j] = 1;
    }
    bodies[j] = it->second;
  }
  const int group_offset = m.next_group;
  std::vector<int> rows(share.island.rows.size());
  for (std::size_t r = 0; r < share.island.rows.size(); ++r) {
    const void* key = share.row_key[r];
    if (key != nullptr) {
      const auto [it, added] = m.shared_row.emplace(std::pair{key, share.row_key_index[r]},
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
    m.next_group = std::max(m.next_group, group_offset + share.row_group[r] + 1);
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

// A surface contact set's rows in the island: the set, the island bodies its two sides are on,
// the first side's node count, and its first row (-1: none yet).
struct SurfaceRows {
  SurfaceContactSet* set = nullptr;
  int body_a = 0, body_b = 0;
  int node_count_a = 0;
  int first_row = -1;
  int rows = 0;                       // how many of the set's candidates have rows
  BodyPairContact* pair = nullptr;    // a pair's, or
  SelfContactSolver* self = nullptr;  // a body's own
};

// Rows for the candidates of `s` that have none yet, in the set's order, one friction group for
// the set (a set's candidates added later join the rows already there, in order: a set's rows
// stay contiguous only while it is the last to add, so the rows of each set are kept per row).
void addSurfaceRows(MergedIsland& m, SurfaceRows& s, std::vector<std::vector<int>>& rows_of,
                    std::size_t index, int group, double dt) {
  const sap::RowDefaults defaults;
  const std::size_t before = m.rows.size();
  SurfaceContactSet only_new;
  const std::vector<SurfaceContact>& all = s.set->contacts();
  for (std::size_t c = static_cast<std::size_t>(s.rows); c < all.size(); ++c)
    only_new.contacts().push_back(all[c]);
  sap::addSurfaceContactRows(m.rows, only_new, s.node_count_a, s.body_a, s.body_b, defaults, dt);
  for (std::size_t r = before; r < m.rows.size(); ++r) {
    rows_of[index].push_back(static_cast<int>(r));
    m.row_group.push_back(group);
  }
  s.rows = static_cast<int>(all.size());
}

}  // namespace

IslandPairStats stepIsland(const std::vector<FemBody*>& group, const std::vector<IslandPair>& pairs,
                           const StepContext& ctx) {
  IslandPairStats stats;
  // Prepare: a body that stops there leaves the island, and its pairs sit the step out.
  std::vector<int> island_body(group.size(), -1);  // per group body: its island body, or -1
  std::vector<PreparedSystem> systems(group.size());
  int present = 0;
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (!group[k]->prepare(ctx, group.size() > 1)) continue;
    systems[k] = group[k]->preparedSystem();
    island_body[k] = present++;
  }
  if (present == 0) return stats;
  bool any_pair = false;
  for (const IslandPair& pair : pairs)
    any_pair = any_pair || (island_body[static_cast<std::size_t>(pair.first)] >= 0 &&
                            island_body[static_cast<std::size_t>(pair.second)] >= 0);

  // A lone body without contact rows solves alone; with self-contact on it then looks along the
  // solved motion, and only a motion that meets its own surface makes it an island.
  if (group.size() == 1 && !any_pair && !group[0]->touchesRigid()) {
    FemBody& body = *group[0];
    SelfContactSolver* self = body.selfContact();
    if (self == nullptr || self->set().empty()) {
      const LinearSolveReport solve = body.solveAlone();
      if (self == nullptr || self->searchAlong(*systems[0].v) == 0) {
        if (self != nullptr) self->finishStep(0, true);
        body.finish(*systems[0].v, solve);
        return stats;
      }
    }
  }

  MergedIsland m;
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (island_body[k] < 0) continue;
    m.fem.push_back(std::make_unique<sap::FemIslandBody>(*systems[k].op, *systems[k].constraints,
                                                         *systems[k].b));
    m.bodies.push_back(m.fem.back().get());
  }
  // Each present body's share, its rigid bodies after all the FEM bodies.
  std::vector<sap::ConvexRows> shares(group.size());
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (island_body[k] < 0) continue;
    shares[k] = group[k]->contacts().convexRows();
    mergeShare(m, shares[k], island_body[k]);
  }
  // The surface sets: every body's self-contact, then the pairs, each its own friction group.
  std::vector<SurfaceRows> surfaces;
  for (std::size_t k = 0; k < group.size(); ++k) {
    SelfContactSolver* self = group[k]->selfContact();
    if (island_body[k] < 0 || self == nullptr) continue;
    SurfaceRows s;
    s.set = &self->set();
    s.body_a = s.body_b = island_body[k];
    s.node_count_a = group[k]->model().nodeCount();
    s.self = self;
    surfaces.push_back(s);
  }
  for (const IslandPair& pair : pairs) {
    const int a = island_body[static_cast<std::size_t>(pair.first)];
    const int b = island_body[static_cast<std::size_t>(pair.second)];
    if (a < 0 || b < 0) continue;
    SurfaceRows s;
    s.set = &pair.contact->set();
    s.body_a = a;
    s.body_b = b;
    s.node_count_a = pair.contact->nodeCountA();
    s.pair = pair.contact;
    surfaces.push_back(s);
    stats.gap_tolerance = std::max(stats.gap_tolerance, pair.contact->gapTolerance());
  }
  std::vector<std::vector<int>> rows_of(surfaces.size());
  std::vector<int> surface_group(surfaces.size());
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    surface_group[i] = m.next_group++;
    addSurfaceRows(m, surfaces[i], rows_of, i, surface_group[i], ctx.dt);
  }

  // Each island body's first dof, and the warm start: each FEM body's velocities (the
  // stepper's, or its solve alone), each rigid body's twist at the step's start.
  const int fem_count = static_cast<int>(m.fem.size());
  std::vector<Eigen::Index> offset(m.bodies.size() + 1, 0);
  for (std::size_t b = 0; b < m.bodies.size(); ++b)
    offset[b + 1] = offset[b] + m.bodies[b]->dofs();
  auto velocities_of = [&](Eigen::VectorXd& x, int body) {
    return x.segment(offset[static_cast<std::size_t>(body)],
                     m.bodies[static_cast<std::size_t>(body)]->dofs());
  };
  Eigen::VectorXd x(offset.back());
  for (std::size_t k = 0; k < group.size(); ++k)
    if (island_body[k] >= 0) velocities_of(x, island_body[k]) = *systems[k].v;
  for (std::size_t j = 0; j < m.rigid_start.size(); ++j)
    velocities_of(x, fem_count + static_cast<int>(j)) = m.rigid_start[j];

  auto report_failure = [&](const std::string& message) {
    for (std::size_t k = 0; k < group.size(); ++k)
      if (island_body[k] >= 0 && !isFatal(group[k]->lastReport().health))
        group[k]->noteContactNotConverged(message);
  };
  Result<sap::SapProblem> created = sap::SapProblem::create(m.bodies, m.rows, ctx.dt);
  if (!created) {
    // Cannot happen with rows built from the bodies' own data; reported, never skipped silently.
    report_failure(created.error().message);
    stats.converged = false;
    return stats;
  }
  sap::SapReport report = sap::solveWithMatchedFrictionBounds(created.value(), m.row_group, x);
  int newton = report.newton_iterations, cg = report.cg_iterations;
  // The surface rows' gaps moved onto the true end-of-step surface, self-contact's search along
  // the solved motion, and solved again, until nothing moves. The rows are linearised at the
  // step's start; at 15 m/s a node ended 9.6 mm inside the other cube without the correction
  // (bullet_collide_soft), and a closing loop of the Greenhill rod meets pairs its predicted
  // motion did not.
  for (int round = 0; round < kMaxSurfaceCorrections && report.converged; ++round) {
    sap::SapProblem& problem = created.value();
    int changed = 0;
    bool added = false;
    for (std::size_t i = 0; i < surfaces.size(); ++i) {
      SurfaceRows& s = surfaces[i];
      if (s.self != nullptr) {
        const Eigen::VectorXd v = velocities_of(x, s.body_a);
        changed += s.self->correctGaps(v);
        if (s.self->searchAlong(v) > 0) added = true;
      } else {
        const Eigen::Index na = m.bodies[static_cast<std::size_t>(s.body_a)]->dofs();
        Eigen::VectorXd pair_v(na + m.bodies[static_cast<std::size_t>(s.body_b)]->dofs());
        pair_v << velocities_of(x, s.body_a), velocities_of(x, s.body_b);
        changed += s.pair->correctGaps(pair_v, ctx.dt, s.pair->gapTolerance());
      }
      // The rows' gaps as the candidates now say.
      const std::vector<SurfaceContact>& candidates = s.set->contacts();
      for (std::size_t c = 0; c < rows_of[i].size(); ++c) {
        const double gap = candidates[c].gap - candidates[c].target_gap;
        problem.setGap(rows_of[i][c], gap);
      }
    }
    if (added) {
      // New candidates: new rows, and a problem made again from the rows as they stand.
      std::vector<sap::ContactRow> rows;
      for (int r = 0; r < problem.rowCount(); ++r)
        rows.push_back(problem.row(r));
      m.rows = std::move(rows);
      for (std::size_t i = 0; i < surfaces.size(); ++i)
        addSurfaceRows(m, surfaces[i], rows_of, i, surface_group[i], ctx.dt);
      created = sap::SapProblem::create(m.bodies, m.rows, ctx.dt);
      if (!created) {
        report_failure(created.error().message);
        stats.converged = false;
        return stats;
      }
    } else if (changed == 0) {
      break;
    }
    report = sap::solveWithMatchedFrictionBounds(created.value(), m.row_group, x);
    newton += report.newton_iterations;
    cg += report.cg_iterations;
  }
  report.newton_iterations = newton;
  report.cg_iterations = cg;
  const sap::SapProblem& problem = created.value();
  const std::vector<Vector6d> twists = sap::solvedTwists(problem, report, fem_count);

  // Every share takes its answer; the surface sets keep their impulses for the next step.
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (island_body[k] < 0) continue;
    const auto s = static_cast<std::size_t>(island_body[k]);
    std::vector<sap::SolvedBody> solved(m.share_bodies[s].size());
    for (std::size_t j = 0; j < solved.size(); ++j) {
      solved[j].twist = twists[static_cast<std::size_t>(m.share_bodies[s][j] - fem_count)];
      solved[j].applies = m.share_owns[s][j] != 0;
    }
    group[k]->contacts().takeConvexSolution(shares[k], shareReport(report, m.share_rows[s]),
                                            solved);
    *systems[k].v = velocities_of(x, island_body[k]);
  }
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    SurfaceRows& s = surfaces[i];
    sap::takeSurfaceContactImpulses(*s.set, problem, rows_of[i], report, ctx.dt);
    if (s.self != nullptr) {
      s.self->finishStep(report.newton_iterations, report.converged);
      continue;
    }
    stats.candidates += static_cast<int>(s.set->contacts().size());
    for (const SurfaceContact& c : s.set->contacts()) {
      stats.max_end_penetration = std::max(stats.max_end_penetration, -c.end_gap);
      if (c.state == SurfaceContact::State::kInactive) continue;
      ++stats.active;
      if (c.state == SurfaceContact::State::kStick) ++stats.sticking;
      stats.normal_impulse += std::max(0.0, c.normal.dot(c.multiplier));
    }
  }
  stats.iterations = report.newton_iterations;
  stats.converged = report.converged;
  LinearSolveReport solve;
  solve.iterations = report.cg_iterations;
  solve.converged = true;  // the island's own verdict: report.converged, noted below
  // Last body first: a dynamic rigid body shared by several bodies takes its twist from the
  // share that owns it, whatever the order.
  for (std::size_t k = group.size(); k-- > 0;) {
    if (island_body[k] >= 0) group[k]->finish(*systems[k].v, solve);
  }
  if (!report.converged) {
    // Reported per step, never accepted silently (a warning: the step is usable).
    std::ostringstream s;
    s << "the contact island did not converge in " << report.newton_iterations
      << " Newton iterations (" << report.message << ")";
    report_failure(s.str());
  }
  return stats;
}

}  // namespace torsion
