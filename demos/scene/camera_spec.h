#pragma once
// The optional "camera" entry of a scene file: how its pictures look at it by default
// (docs/scene-format.md). Every field is optional; the picture is always fitted to the scene's
// bounds, these only choose the direction and the closeness. Kept apart from scene_parser.cpp so
// the picture options grow without touching the physics keys.

#include <Eigen/Core>
#include <optional>

namespace torsion::scene {

class JsonObject;

struct CameraSpec {
  std::optional<Eigen::Vector3d> up;  ///< unit; the screen's vertical (default: against gravity)
  std::optional<double> yaw;          ///< rad, about up (default: across the longest extent)
  std::optional<double> pitch;        ///< rad above the horizon, in (-1.5, 1.5)
  double zoom = 1;                    ///< > 0; 2 is twice as close as the fitted distance
};

/// Reads root["camera"] if present (throws JsonFault naming the key, like the other readers).
CameraSpec readCameraSpec(const JsonObject& root);

}  // namespace torsion::scene
