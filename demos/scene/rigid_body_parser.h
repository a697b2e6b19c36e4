#pragma once
// The rigid-body part of scene files (docs/scene-format.md, rigid_bodies[] and ground): shapes,
// mass, pose, initial velocity, friction, restitution, kinematic motion. Kept apart from
// scene_parser.cpp, which calls it; both share the pose and motion readers declared here.

#include <string>
#include <vector>

#include "json_reader.h"
#include "scene_spec.h"

namespace torsion::scene {

/// rigid_bodies[i]; `earlier` are the entries already read (names must be unique). A device's
/// relative paths are resolved against `base_directory`.
RigidBodySpec readRigidBody(const JsonObject& r, const std::vector<RigidBodySpec>& earlier,
                            const std::string& base_directory);
/// "ground": {"height", "friction", "restitution"}: a static plane z = height.
RigidBodySpec readGround(const JsonObject& g);

// Defined in scene_parser.cpp: the readers every scene entry shares.
Frame parsePose(const JsonObject& parent, const std::string& key);
MotionSpec parseMotion(const JsonObject& m);

}  // namespace torsion::scene
