#pragma once
// What summary.json says about the program that wrote it and the state it ended in, so two runs
// can be told apart or matched (`torsion check`, docs/outputs.md):
//   "schema_version"    the layout of summary.json (kSummarySchemaVersion)
//   "torsion_version"   the project version; "git_commit" the source commit (build_info.h)
//   "bullet_precision"  "double" or "float"
//   "final_state_hash"  FNV-1a (64 bits, 16 hex digits) of the bytes of the final node positions
//                       of every body (those written to <body>.vtk) and every rigid body's
//                       position and orientation, in scene order: equal hashes mean bit-identical
//                       final states; a hash says nothing about how close two different ones are.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scene_builder.h"

namespace torsion::scene {

/// Bumped whenever a key of summary.json changes meaning or is removed (adding keys does not).
inline constexpr int kSummarySchemaVersion = 1;

/// Adds schema_version, torsion_version, git_commit and bullet_precision to `summary`.
void addProvenance(nlohmann::json& summary);

/// The final_state_hash of the scene with these final FEM positions (one vector per body).
std::string finalStateHash(const BuiltScene& scene,
                           const std::vector<Eigen::VectorXd>& final_positions);

}  // namespace torsion::scene
