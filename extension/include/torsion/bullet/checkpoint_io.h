#pragma once
// A world's checkpoint and its hands' as bytes, to store or send and read back into the same
// world or one built the same way (same scene, same bodies, meshes, hands and node sets in the
// same order). Pointers become names and indices: bodies by name, rigid objects by their index in
// the Bullet world, node groups by index, a hand's grabbed patch by the hand's index.
//
// Layout: "TRSNCKPT", u32 version, u64 payload length, u64 FNV-1a hash of the payload, payload.
// Numbers are little-endian; btScalar values are stored as double. What leaves memory: FEM bodies
// (state, warm starts, node groups, material, rigid-contact and self-contact warm starts, last
// step's report), the multipliers of FEM bodies touching each other (their pairs by the bodies'
// names), the clock and health, the rigid bodies' poses and velocities, the hands. The contact
// memory is already bytes in memory (FemBodyCheckpoint::contacts, FemPairCheckpoint::multipliers,
// written by the solvers' own save(): torsion/checkpoint_stream.h), stored here as they are. Not
// in it, as in a checkpoint in memory: Bullet's manifolds between rigid bodies, and the
// statistics of the last contact step.

#include <string>
#include <string_view>
#include <vector>

#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/result.h"

namespace torsion {

/// A checkpoint read back (readCheckpoint), ready for FemWorld::restore and Hand::restore.
struct StoredCheckpoint {
  WorldCheckpoint world;
  std::vector<HandCheckpoint> hands;  ///< in the order of the hands given to readCheckpoint
  std::string extra;                  ///< the caller's bytes given to writeCheckpoint
};

/// The bytes of `checkpoint` (taken from `world`) and of `hand_checkpoints` (taken from `hands`,
/// same order), with `extra`, opaque bytes of the caller's (e.g. its own flags).
std::string writeCheckpoint(FemWorld& world, const WorldCheckpoint& checkpoint,
                            const std::vector<Hand*>& hands,
                            const std::vector<HandCheckpoint>& hand_checkpoints,
                            std::string_view extra);

/// Reads `bytes` for `world` and its `hands` (the same hands, in the order they were written).
/// Changes nothing. Errors: not a checkpoint ("not a torsion checkpoint"), another version,
/// truncated or corrupted bytes (naming the part being read: "... (reading body 'cube': its
/// rigid contacts)"), or a world that differs from the one saved ("... saved from another world:
/// ...": other bodies, meshes, hands, node sets or rigid bodies).
Result<StoredCheckpoint> readCheckpoint(std::string_view bytes, FemWorld& world,
                                        const std::vector<Hand*>& hands);

/// The world time (s) of the checkpoint in `bytes`, after checking its header, length and hash.
Result<double> checkpointTime(std::string_view bytes);

}  // namespace torsion
