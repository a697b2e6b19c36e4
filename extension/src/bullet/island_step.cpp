// One contact island's step as one convex problem (island_step.h, docs/contact-solve.md).

#include "torsion/bullet/island_step.h"

#include <algorithm>
#include <cstddef>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>

#include "torsion/contact/solve/convex_rows.h"
#include "torsion/contact/solve/fem_island_body.h"
#include "torsion/contact/solve/surface_contact_rows.h"

namespace torsion {

namespace {

// Passes that move the surface rows' linearised gaps onto the true end-of-step surface (and let
// self-contact look along the solved motion), each followed by a solve.
constexpr int kMaxSurfaceCorrections = 4;

// A surface contact set's rows in the island: a body's self-contact, or a pair's candidates.
struct SurfaceRows {
  SurfaceContactSet* set = nullptr;
  int body_a = 0, body_b = 0;         // the island bodies of its two sides
  int node_count_a = 0;               // the first side's nodes in the set's index space
  int group = 0;                      // its friction-bound group
  std::vector<int> rows;              // candidate c is island row rows[c]
  BodyPairContact* pair = nullptr;    // a pair's, or
  SelfContactSolver* self = nullptr;  // a body's own
};

// `report` restricted to some rows, in their order.
sap::SapReport restrictedReport(const sap::SapReport& report, const std::vector<int>& rows) {
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

// The island of one step: its bodies, its rows, its velocities. Every stage is one method, run
// in the order stepIsland lists them; nothing outlives the step.
class Island {
 public:
  Island(const std::vector<FemBody*>& group, const std::vector<IslandPair>& pairs,
         const StepContext& ctx, IslandWorkspace& workspace)
      : group_(group), pairs_(pairs), ctx_(ctx), workspace_(workspace) {}
  // The workspace's problem refers to this island's bodies: it is emptied with them.
  ~Island() { workspace_.problem.clear(); }
  Island(const Island&) = delete;
  Island& operator=(const Island&) = delete;

  // Every body up to its solve; false when none got there.
  bool prepare();
  // A lone body without rows: solved alone, and finished unless its solved motion meets its own
  // surface (then true is returned with the new candidates in its self-contact set).
  bool solvesAlone();
  // The shares' rows, the surface rows and the warm start.
  void gatherRows();
  // The solve, its corrections, the answers taken back, the bodies finished.
  IslandPairStats solveAndFinish();

 private:
  void mergeShare(std::size_t k);
  void addSurfaceRows(SurfaceRows& s);
  // The surface rows' gaps moved onto the solved motion's end surface, self-contact's search
  // along it; returns whether anything moved (`added`: new candidates, now rows).
  bool correctSurfaces(sap::SapProblem& problem, bool& added);
  void takeAnswers(const sap::SapProblem& problem, const sap::SapReport& report,
                   IslandPairStats& stats);
  void reportFailure(const std::string& message);
  sap::SapSolverSettings solverSettings() const;
  // The problem made from rows_ (moved into it) in the workspace's storage; false (reported) on
  // failure.
  bool makeProblem();
  Eigen::VectorBlock<Eigen::VectorXd> velocitiesOf(int body) {
    const auto b = static_cast<std::size_t>(body);
    return x_.segment(offset_[b], offset_[b + 1] - offset_[b]);
  }

  const std::vector<FemBody*>& group_;
  const std::vector<IslandPair>& pairs_;
  const StepContext& ctx_;
  IslandWorkspace& workspace_;
  std::vector<int> island_body_;  // per group body: its island body, or -1 (left the island)
  std::vector<PreparedSystem> systems_;
  int fem_count_ = 0;
  // The island's bodies: FEM bodies first (in the group's order), then each dynamic rigid body
  // once, in the order the shares first name them; their first dofs.
  std::vector<const sap::IslandBody*> bodies_;
  std::vector<Eigen::Index> offset_;
  std::vector<Vector6d> rigid_start_;  // per rigid island body
  std::map<const btCollisionObject*, int> rigid_of_;
  // The rows, their friction-bound groups, and each share's rows and rigid bodies.
  std::vector<sap::ContactRow> rows_;
  std::vector<int> row_group_;
  int next_group_ = 0;
  std::map<std::pair<const void*, int>, int> shared_row_;
  std::vector<sap::ConvexRows> shares_;
  std::vector<std::vector<int>> share_rows_;  // per island FEM body
  std::vector<std::vector<int>> share_bodies_;
  std::vector<std::vector<char>> share_owns_;  // whether the share applies the body's twist
  std::vector<SurfaceRows> surfaces_;
  Eigen::VectorXd x_;  // the island's velocities
};

bool Island::prepare() {
  island_body_.assign(group_.size(), -1);
  systems_.resize(group_.size());
  for (std::size_t k = 0; k < group_.size(); ++k) {
    // A body that stops here leaves the island, and its pairs sit the step out.
    if (!group_[k]->prepare(ctx_, group_.size() > 1)) continue;
    systems_[k] = group_[k]->preparedSystem();
    island_body_[k] = fem_count_++;
  }
  return fem_count_ > 0;
}

bool Island::solvesAlone() {
  if (group_.size() != 1 || group_[0]->touchesRigid()) return false;
  FemBody& body = *group_[0];
  SelfContactSolver* self = body.selfContact();
  if (self != nullptr && !self->set().empty()) return false;
  const LinearSolveReport solve = body.solveAlone();
  if (self != nullptr && self->searchAlong(*systems_[0].v) > 0) return false;
  if (self != nullptr) self->finishStep(0, true);
  body.finish(*systems_[0].v, solve);
  return true;
}

void Island::mergeShare(std::size_t k) {
  sap::ConvexRows& share = shares_[k];
  const int fem_body = island_body_[k];
  std::vector<int> bodies(share.body_objects.size());
  std::vector<char> owns(share.body_objects.size(), 0);
  for (std::size_t j = 0; j < share.body_objects.size(); ++j) {
    const auto [it, added] =
        rigid_of_.emplace(share.body_objects[j], static_cast<int>(bodies_.size()));
    if (added) {
      bodies_.push_back(share.island.rigid_bodies[j].get());
      rigid_start_.push_back(share.start_twists[j]);
      owns[j] = 1;
    }
    bodies[j] = it->second;
  }
  const int group_offset = next_group_;
  std::vector<int> rows(share.island.rows.size());
  for (std::size_t r = 0; r < share.island.rows.size(); ++r) {
    if (const void* key = share.row_key[r]; key != nullptr) {
      const auto [it, added] = shared_row_.emplace(std::pair{key, share.row_key_index[r]},
                                                   static_cast<int>(rows_.size()));
      if (!added) {  // held by an earlier share: the same row, solved once
        rows[r] = it->second;
        continue;
      }
    }
    sap::ContactRow row = share.island.rows[r];
    for (sap::ContactTerm& term : row.terms)
      term.body = term.body == 0 ? fem_body : bodies[static_cast<std::size_t>(term.body - 1)];
    rows[r] = static_cast<int>(rows_.size());
    rows_.push_back(std::move(row));
    row_group_.push_back(group_offset + share.row_group[r]);
    next_group_ = std::max(next_group_, group_offset + share.row_group[r] + 1);
  }
  share_rows_.push_back(std::move(rows));
  share_bodies_.push_back(std::move(bodies));
  share_owns_.push_back(std::move(owns));
}

void Island::addSurfaceRows(SurfaceRows& s) {
  // Only the candidates without a row yet (those a search along the solved motion added).
  SurfaceContactSet added;
  const std::vector<SurfaceContact>& all = s.set->contacts();
  added.contacts().assign(all.begin() + static_cast<std::ptrdiff_t>(s.rows.size()), all.end());
  const std::size_t before = rows_.size();
  sap::addSurfaceContactRows(rows_, added, s.node_count_a, s.body_a, s.body_b, sap::RowDefaults{},
                             ctx_.dt);
  for (std::size_t r = before; r < rows_.size(); ++r) {
    s.rows.push_back(static_cast<int>(r));
    row_group_.push_back(s.group);
  }
}

void Island::gatherRows() {
  for (std::size_t k = 0; k < group_.size(); ++k) {
    if (island_body_[k] < 0) continue;
    sap::FemIslandBody& body = group_[k]->islandBody();
    body.useCoarseSpace(group_[k]->state().positions);
    bodies_.push_back(&body);
  }
  // Each present body's share, its rigid bodies after all the FEM bodies.
  shares_.resize(group_.size());
  for (std::size_t k = 0; k < group_.size(); ++k) {
    if (island_body_[k] < 0) continue;
    shares_[k] = group_[k]->contacts().convexRows();
    mergeShare(k);
  }
  // The surface sets: every body's self-contact, then the pairs, each its own friction group.
  for (std::size_t k = 0; k < group_.size(); ++k) {
    SelfContactSolver* self = group_[k]->selfContact();
    if (island_body_[k] < 0 || self == nullptr) continue;
    SurfaceRows s;
    s.set = &self->set();
    s.body_a = s.body_b = island_body_[k];
    s.node_count_a = group_[k]->model().nodeCount();
    s.self = self;
    surfaces_.push_back(std::move(s));
  }
  for (const IslandPair& pair : pairs_) {
    const int a = island_body_[static_cast<std::size_t>(pair.first)];
    const int b = island_body_[static_cast<std::size_t>(pair.second)];
    if (a < 0 || b < 0) continue;
    SurfaceRows s;
    s.set = &pair.contact->set();
    s.body_a = a;
    s.body_b = b;
    s.node_count_a = pair.contact->nodeCountA();
    s.pair = pair.contact;
    surfaces_.push_back(std::move(s));
  }
  for (SurfaceRows& s : surfaces_) {
    s.group = next_group_++;
    addSurfaceRows(s);
  }
  // The warm start: each FEM body's velocities (the stepper's guess, or its solve alone), each
  // rigid body's twist at the step's start.
  offset_.assign(bodies_.size() + 1, 0);
  for (std::size_t b = 0; b < bodies_.size(); ++b)
    offset_[b + 1] = offset_[b] + bodies_[b]->dofs();
  x_.resize(offset_.back());
  for (std::size_t k = 0; k < group_.size(); ++k)
    if (island_body_[k] >= 0) velocitiesOf(island_body_[k]) = *systems_[k].v;
  for (std::size_t j = 0; j < rigid_start_.size(); ++j)
    velocitiesOf(fem_count_ + static_cast<int>(j)) = rigid_start_[j];
}

bool Island::correctSurfaces(sap::SapProblem& problem, bool& added) {
  int changed = 0;
  for (SurfaceRows& s : surfaces_) {
    if (s.self != nullptr) {
      const Eigen::VectorXd v = velocitiesOf(s.body_a);
      changed += s.self->correctGaps(v);
      if (s.self->searchAlong(v) > 0) added = true;
    } else {
      const Eigen::VectorXd va = velocitiesOf(s.body_a), vb = velocitiesOf(s.body_b);
      Eigen::VectorXd pair_v(va.size() + vb.size());
      pair_v << va, vb;
      changed += s.pair->correctGaps(pair_v, ctx_.dt, s.pair->gapTolerance());
    }
    const std::vector<SurfaceContact>& candidates = s.set->contacts();
    for (std::size_t c = 0; c < s.rows.size(); ++c)
      problem.setGap(s.rows[c], candidates[c].gap - candidates[c].target_gap);
  }
  return changed > 0 || added;
}

void Island::takeAnswers(const sap::SapProblem& problem, const sap::SapReport& report,
                         IslandPairStats& stats) {
  const std::vector<Vector6d> twists = sap::solvedTwists(problem, report, fem_count_);
  for (std::size_t k = 0; k < group_.size(); ++k) {
    if (island_body_[k] < 0) continue;
    const auto s = static_cast<std::size_t>(island_body_[k]);
    std::vector<sap::SolvedBody> solved(share_bodies_[s].size());
    for (std::size_t j = 0; j < solved.size(); ++j) {
      solved[j].twist = twists[static_cast<std::size_t>(share_bodies_[s][j] - fem_count_)];
      solved[j].applies = share_owns_[s][j] != 0;
    }
    group_[k]->contacts().takeConvexSolution(shares_[k], restrictedReport(report, share_rows_[s]),
                                             solved);
    *systems_[k].v = velocitiesOf(island_body_[k]);
  }
  for (SurfaceRows& s : surfaces_) {
    sap::takeSurfaceContactImpulses(*s.set, problem, s.rows, report, ctx_.dt);
    if (s.self != nullptr) {
      s.self->finishStep(report.newton_iterations, report.converged);
      continue;
    }
    stats.candidates += static_cast<int>(s.set->contacts().size());
    stats.gap_tolerance = std::max(stats.gap_tolerance, s.pair->gapTolerance());
    for (const SurfaceContact& c : s.set->contacts()) {
      stats.max_end_penetration = std::max(stats.max_end_penetration, -c.end_gap);
      if (c.state == SurfaceContact::State::kInactive) continue;
      ++stats.active;
      if (c.state == SurfaceContact::State::kStick) ++stats.sticking;
      stats.normal_impulse += std::max(0.0, c.normal.dot(c.multiplier));
    }
  }
}

void Island::reportFailure(const std::string& message) {
  for (std::size_t k = 0; k < group_.size(); ++k)
    if (island_body_[k] >= 0 && !isFatal(group_[k]->lastReport().health))
      group_[k]->noteContactNotConverged(message);
}

sap::SapSolverSettings Island::solverSettings() const {
  // The island is solved as accurately as its bodies' own steps: a CG body stops its solve at
  // `tolerance` of its right-hand side, and the island's optimality criterion at the same
  // fraction of its momenta (both relative residuals of the step's momentum balance). A body
  // solved by Cholesky is exact: the SAP default then (1e-6), cheap with exact preconditioners (a
  // few Newton iterations of one or two CG iterations each). So is an island whose rows hold a
  // rigid body or a link to it (anchors, Bullet's joints): measured, a FEM bar hinged to a rigid
  // bob gains 4.2 % of its energy in 10 s solved at 1e-4 of the bob's momentum, 0.5 % at 3e-5 and
  // below, as Bullet alone. Rigid bodies that only touch (contact rows) take the bodies'
  // accuracy: resting, sliding and pushed boxes keep their bounds (tests/contact,
  // tests/physics/sliding*), at a third of the CG iterations of a box resting on a held cylinder.
  sap::SapSolverSettings settings;
  if (bodies_.size() > static_cast<std::size_t>(fem_count_)) {
    for (const sap::ContactRow& row : rows_)
      if (row.kind != sap::RowKind::kContact) return settings;
  }
  const double exact = settings.relative_tolerance;
  settings.relative_tolerance = 1;
  for (std::size_t k = 0; k < group_.size(); ++k) {
    if (island_body_[k] < 0) continue;
    const SolverSettings& body = *systems_[k].settings;
    settings.relative_tolerance = std::min(
        settings.relative_tolerance,
        body.linear_solver == LinearSolverKind::kConjugateGradient ? body.tolerance : exact);
  }
  return settings;
}

bool Island::makeProblem() {
  // The rows move into the problem (problem.row() from then on); rows_ is empty after.
  const Status made = workspace_.problem.reset(bodies_, std::move(rows_), ctx_.dt);
  rows_.clear();
  // Cannot fail with rows built from the bodies' own data; reported, never skipped silently.
  if (!made) reportFailure(made.error().message);
  return static_cast<bool>(made);
}

IslandPairStats Island::solveAndFinish() {
  IslandPairStats stats;
  sap::SapProblem& problem = workspace_.problem;
  sap::SapSolver& solver = workspace_.solver;
  solver.setSettings(solverSettings());
  if (!makeProblem()) {
    stats.converged = false;
    return stats;
  }
  sap::SapReport report = sap::solveWithMatchedFrictionBounds(solver, problem, row_group_, x_);
  int newton = report.newton_iterations, cg = report.cg_iterations;
  // The rows are linearised at the step's start: at 15 m/s a node ended 9.6 mm inside the other
  // cube without the gaps moved onto the end surface (bullet_collide_soft), and a closing loop of
  // the Greenhill rod meets pairs its predicted motion did not.
  for (int round = 0; round < kMaxSurfaceCorrections && report.converged; ++round) {
    bool added = false;
    if (!correctSurfaces(problem, added)) break;
    if (added) {
      // New candidates: new rows, and the problem made again from the rows as they stand.
      for (int r = 0; r < problem.rowCount(); ++r)
        rows_.push_back(problem.row(r));
      for (SurfaceRows& s : surfaces_)
        addSurfaceRows(s);
      if (!makeProblem()) {
        stats.converged = false;
        return stats;
      }
    }
    report = sap::solveWithMatchedFrictionBounds(solver, problem, row_group_, x_);
    newton += report.newton_iterations;
    cg += report.cg_iterations;
  }
  report.newton_iterations = newton;
  report.cg_iterations = cg;
  takeAnswers(problem, report, stats);
  stats.iterations = report.newton_iterations;
  stats.converged = report.converged;
  LinearSolveReport solve;
  solve.iterations = report.cg_iterations;
  solve.converged = true;  // the island's own verdict: report.converged, noted below
  // Last body first: a dynamic rigid body shared by several bodies takes its twist from the
  // share that owns it, whatever the order.
  for (std::size_t k = group_.size(); k-- > 0;)
    if (island_body_[k] >= 0) group_[k]->finish(*systems_[k].v, solve);
  if (!report.converged) {
    // Reported per step, never accepted silently (a warning: the step is usable).
    std::ostringstream s;
    s << "the contact island did not converge in " << report.newton_iterations
      << " Newton iterations (" << report.message << ")";
    reportFailure(s.str());
  }
  return stats;
}

}  // namespace

IslandPairStats stepIsland(const std::vector<FemBody*>& group, const std::vector<IslandPair>& pairs,
                           const StepContext& ctx, IslandWorkspace& workspace) {
  Island island(group, pairs, ctx, workspace);
  if (!island.prepare()) return {};
  if (pairs.empty() && island.solvesAlone()) return {};
  island.gatherRows();
  return island.solveAndFinish();
}

}  // namespace torsion
