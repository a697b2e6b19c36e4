#pragma once
// What the checkpoint tests' rigs (checkpoint_test.cpp, checkpoint_io_test.cpp) share: their world
// settings, a body held by its base, and a world with its hands saved as checkpoint bytes
// (bullet/checkpoint_io.h) and read back.

#include <string>
#include <vector>

#include "torsion/bullet/checkpoint_io.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"

namespace torsion::test {

/// dt = 10 ms, everything else as default.
inline WorldSettings checkpointWorldSettings() {
  WorldSettings s;
  s.solver.time_step = 0.01;
  return s;
}

/// Holds the nodes of `body` whose rest position has z < 1e-9 (its base) where they are.
inline void holdBase(FemBody& body) {
  std::vector<int> base;
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    if (body.model().mesh().restPositions()[static_cast<size_t>(i)].z() < 1e-9) base.push_back(i);
  }
  body.carryNodes(
      "base", base, [](double) { return Frame{}; }, 0.0);
}

/// The bytes of `world` and `hands` as they are now, with `extra` (writeCheckpoint).
inline std::string saveBytes(FemWorld& world, const std::vector<Hand*>& hands,
                             const std::string& extra = "") {
  std::vector<HandCheckpoint> hand_checkpoints;
  for (Hand* hand : hands)
    hand_checkpoints.push_back(hand->checkpoint());
  return writeCheckpoint(world, world.checkpoint(), hands, hand_checkpoints, extra);
}

/// Reads `bytes` (readCheckpoint) and restores `world` and `hands` from them; on an error nothing
/// is restored.
inline Status loadBytes(const std::string& bytes, FemWorld& world,
                        const std::vector<Hand*>& hands) {
  Result<StoredCheckpoint> stored = readCheckpoint(bytes, world, hands);
  if (!stored) return stored.error();
  if (Status s = world.restore(stored.value().world); !s) return s;
  for (size_t h = 0; h < hands.size(); ++h)
    hands[h]->restore(stored.value().hands[h]);
  return Ok{};
}

}  // namespace torsion::test
