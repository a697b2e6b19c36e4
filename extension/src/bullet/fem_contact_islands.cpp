#include "torsion/bullet/fem_contact_islands.h"

#include <algorithm>
#include <cassert>
#include <numeric>

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

namespace {

// Reads the multipliers' bytes of `saved` onto `set` (restore and checkRestore alike).
Status readMultipliers(const FemPairCheckpoint& saved, SurfaceContactSet& set) {
  CheckpointReader in(saved.multipliers);
  in.section("the multipliers of bodies '" + saved.a->name() + "' and '" + saved.b->name() +
             "' touching");
  if (Status read = set.restore(in); !read) return read;
  if (!in.atEnd()) in.refuse("bytes after the multipliers");
  return in.status();
}

}  // namespace

std::vector<FemPairCheckpoint> FemContactIslands::checkpoint() const {
  std::vector<FemPairCheckpoint> saved;
  for (const auto& [key, contact] : pairs_) {
    CheckpointWriter multipliers;
    contact->set().save(multipliers);
    saved.push_back({key.first, key.second, std::move(multipliers.bytes())});
  }
  return saved;
}

Status FemContactIslands::checkRestore(const std::vector<FemPairCheckpoint>& pairs) {
  for (const FemPairCheckpoint& saved : pairs) {
    SurfaceContactSet scratch;
    if (Status read = readMultipliers(saved, scratch); !read) return read;
  }
  return Ok{};
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
    // Checked before (checkRestore): bytes edited by hand leave the pair cold.
    const Status read = readMultipliers(saved, contact->set());
    assert(read.ok());
    (void)read;
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

void FemContactIslands::advance(const std::vector<FemBody*>& group, const StepContext& ctx,
                                IslandWorkspace& workspace) {
  auto slot = [&](const FemBody* body) {
    return static_cast<int>(std::find(group.begin(), group.end(), body) - group.begin());
  };
  std::vector<IslandPair> pairs;
  for (const auto& [key, contact] : live_) {
    const int first = slot(key.first), second = slot(key.second);
    if (first == static_cast<int>(group.size()) || second == static_cast<int>(group.size()))
      continue;
    pairs.push_back({contact, first, second});
  }
  const IslandPairStats island = stepIsland(group, pairs, ctx, workspace);
  if (pairs.empty()) return;
  ++stats_.islands;
  stats_.candidates += island.candidates;
  stats_.active += island.active;
  stats_.sticking += island.sticking;
  stats_.iterations = std::max(stats_.iterations, island.iterations);
  stats_.normal_impulse += island.normal_impulse;
  stats_.max_end_penetration = std::max(stats_.max_end_penetration, island.max_end_penetration);
  stats_.converged = stats_.converged && island.converged;
}

}  // namespace torsion
