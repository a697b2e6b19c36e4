#include "torsion/bullet/fem_contact_islands.h"

#include <algorithm>
#include <numeric>
#include <sstream>

namespace torsion {

namespace {

int findRoot(std::vector<int>& parent, int i) {
  while (parent[static_cast<size_t>(i)] != i) {
    parent[static_cast<size_t>(i)] = parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
    i = parent[static_cast<size_t>(i)];
  }
  return i;
}

}  // namespace

void FemContactIslands::notePair(FemBody* a, FemBody* b) {
  if (a != b) touching_.emplace_back(a, b);
}

void FemContactIslands::forget(const FemBody* body) {
  for (auto it = pairs_.begin(); it != pairs_.end();) {
    it = it->first.first == body || it->first.second == body ? pairs_.erase(it) : std::next(it);
  }
  touching_.erase(
      std::remove_if(touching_.begin(), touching_.end(),
                     [body](const auto& p) { return p.first == body || p.second == body; }),
      touching_.end());
}

std::vector<FemPairCheckpoint> FemContactIslands::checkpoint() const {
  std::vector<FemPairCheckpoint> saved;
  for (const auto& [key, contact] : pairs_)
    saved.push_back({key.first, key.second, contact->set().warmStarts()});
  return saved;
}

void FemContactIslands::restore(const std::vector<FemPairCheckpoint>& pairs) {
  // A pair's candidates are found afresh each step (its tree's queries come back sorted), so the
  // multipliers are all a pair carries from one step to the next.
  pairs_.clear();
  live_.clear();
  touching_.clear();
  for (const FemPairCheckpoint& saved : pairs) {
    auto contact = std::make_unique<BodyPairContact>(saved.a->modelPointer(),
                                                     saved.b->modelPointer(), settings_);
    contact->set().setWarmStarts(saved.warm_starts);
    pairs_.emplace(Key{saved.a, saved.b}, std::move(contact));
  }
}

const BodyPairContact* FemContactIslands::pair(const FemBody* a, const FemBody* b) const {
  for (const Key& key : {Key{a, b}, Key{b, a}}) {
    const auto it = pairs_.find(key);
    if (it != pairs_.end()) return it->second.get();
  }
  return nullptr;
}

std::vector<std::vector<FemBody*>> FemContactIslands::plan(const std::vector<FemBody*>& bodies,
                                                           const StepContext& ctx) {
  stats_ = FemContactStats{};
  live_.clear();
  // The broadphase's pairs by body index (Bullet's order is its own), each once.
  std::map<const FemBody*, int> index;
  for (size_t i = 0; i < bodies.size(); ++i)
    index[bodies[i]] = static_cast<int>(i);
  std::vector<std::pair<int, int>> pairs;
  for (const auto& [a, b] : touching_) {
    const auto ia = index.find(a), ib = index.find(b);
    if (ia == index.end() || ib == index.end()) continue;
    pairs.emplace_back(std::min(ia->second, ib->second), std::max(ia->second, ib->second));
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  stats_.touching_pairs = static_cast<int>(pairs.size());

  // Pairs no longer touching lose their multipliers.
  std::map<Key, std::unique_ptr<BodyPairContact>> kept;
  std::vector<int> parent(bodies.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [i, j] : pairs) {
    FemBody* a = bodies[static_cast<size_t>(i)];
    FemBody* b = bodies[static_cast<size_t>(j)];
    const Key key{a, b};
    auto found = pairs_.find(key);
    std::unique_ptr<BodyPairContact> contact =
        found != pairs_.end()
            ? std::move(found->second)
            : std::make_unique<BodyPairContact>(a->modelPointer(), b->modelPointer(), settings_);
    const bool candidates = contact->detect(a->state().positions, a->state().velocities,
                                            b->state().positions, b->state().velocities, ctx.dt);
    if (candidates) {
      live_.emplace_back(key, contact.get());
      parent[static_cast<size_t>(findRoot(parent, i))] = findRoot(parent, j);
    }
    kept.emplace(key, std::move(contact));
  }
  pairs_ = std::move(kept);

  // Groups in the order of their first body, bodies in order within each.
  std::vector<std::vector<FemBody*>> groups;
  std::map<int, size_t> group_of_root;
  for (size_t i = 0; i < bodies.size(); ++i) {
    const int root = findRoot(parent, static_cast<int>(i));
    auto [it, added] = group_of_root.emplace(root, groups.size());
    if (added) groups.emplace_back();
    groups[it->second].push_back(bodies[i]);
  }
  return groups;
}

void FemContactIslands::advance(const std::vector<FemBody*>& group, const StepContext& ctx) {
  if (group.size() == 1) {
    group.front()->advance(ctx);
    return;
  }
  setUpIsland(group);
  if (convexIsland(group)) {
    const bool solved = advanceConvex(group, ctx);
    addStats(group, solved);
    return;
  }
  // Every body up to its solve; one that stops there (non-finite forces) leaves the island, and
  // its pairs sit the step out.
  bool any = false;
  for (size_t k = 0; k < group.size(); ++k) {
    if (!group[k]->prepare(ctx, &terms_[k])) continue;
    enter(k, group[k]);
    any = true;
  }
  island_stats_ = any ? solver_.solve(slots_, island_pairs_, ctx.dt) : IslandContactStats{};
  // Last body first: a dynamic rigid body touching several bodies of the island takes their
  // corrections (RigidContactSolver::finish) in this fixed order, the first body's last.
  for (size_t k = group.size(); k-- > 0;) {
    if (slots_[k].present) group[k]->finish(*slots_[k].v, slots_[k].report);
  }
  addStats(group, any);
}

bool FemContactIslands::convexIsland(const std::vector<FemBody*>& group) {
  return std::all_of(group.begin(), group.end(), [](const FemBody* body) {
    return body->contacts().settings().friction_solve == ContactSettings::FrictionSolve::kConvex &&
           body->selfContact() == nullptr && !body->model().material().hyperelastic();
  });
}

void FemContactIslands::setUpIsland(const std::vector<FemBody*>& group) {
  const size_t n = group.size();
  slots_.assign(n, IslandContactSolve::Body{});
  terms_.assign(n, PairContactTerm{});
  island_pairs_.clear();
  auto slot = [&](const FemBody* body) {
    return static_cast<int>(std::find(group.begin(), group.end(), body) - group.begin());
  };
  for (const auto& [key, contact] : live_) {
    const int first = slot(key.first), second = slot(key.second);
    if (first == static_cast<int>(n) || second == static_cast<int>(n)) continue;
    island_pairs_.push_back({contact, first, second});
    const int na = contact->nodeCountA();
    terms_[static_cast<size_t>(first)].addSide({&contact->set(), 0, na});
    terms_[static_cast<size_t>(second)].addSide(
        {&contact->set(), na, key.second->model().nodeCount()});
  }
}

void FemContactIslands::enter(size_t k, FemBody* body) {
  const PreparedSystem system = body->preparedSystem();
  IslandContactSolve::Body& s = slots_[k];
  s.op = system.op;
  s.constraints = system.constraints;
  s.b = system.b;
  s.settings = system.settings;
  s.v = system.v;
  // Node contacts with prescribed rigid partners (the ground) join the island's joint solve; a
  // body with self-contact or a dynamic rigid partner keeps its own solve.
  s.rigid = nullptr;
  s.solve = nullptr;
  if (body->hasContactSolve()) {
    if (body->selfContact() == nullptr && body->contacts().joinsIsland()) {
      s.rigid = &body->contacts();
    } else {
      s.solve = [body](const SystemOperator& op, const NodeConstraints& constraints,
                       const Eigen::VectorXd& b, const SolverSettings& settings,
                       Eigen::VectorXd& v) {
        return body->solveContacts(op, constraints, b, settings, v);
      };
    }
  }
  s.term = &terms_[k];
  s.present = true;
}

void FemContactIslands::addStats(const std::vector<FemBody*>& group, bool solved) {
  ++stats_.islands;
  stats_.candidates += island_stats_.candidates;
  stats_.active += island_stats_.active;
  stats_.sticking += island_stats_.sticking;
  stats_.iterations = std::max(stats_.iterations, island_stats_.iterations);
  stats_.normal_impulse += island_stats_.normal_impulse;
  stats_.max_end_penetration =
      std::max(stats_.max_end_penetration, island_stats_.max_end_penetration);
  if (!solved || island_stats_.converged) return;
  // Reported per step, never accepted silently (a warning: the step is usable).
  stats_.converged = false;
  std::ostringstream s;
  s << "contact between FEM bodies did not converge in " << island_stats_.iterations
    << " updates (end penetration " << island_stats_.max_end_penetration << " m, tolerance "
    << island_stats_.gap_tolerance << " m)";
  for (size_t k = 0; k < group.size(); ++k) {
    if (slots_[k].present && !isFatal(group[k]->lastReport().health))
      group[k]->noteContactNotConverged(s.str());
  }
}

}  // namespace torsion
