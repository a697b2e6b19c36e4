#include "camera_spec.h"

#include <cmath>

#include "json_reader.h"

namespace torsion::scene {

CameraSpec readCameraSpec(const JsonObject& root) {
  CameraSpec camera;
  if (!root.has("camera")) return camera;
  const JsonObject c = root.object("camera");
  if (c.has("up")) {
    const Eigen::Vector3d up = c.vector3("up");
    if (!(up.allFinite() && up.norm() > 1e-12)) c.fail("up", "must be a non-zero vector");
    camera.up = up.normalized();
  }
  if (c.has("yaw")) {
    camera.yaw = c.number("yaw");
    if (!std::isfinite(*camera.yaw)) c.fail("yaw", "must be finite (rad)");
  }
  if (c.has("pitch")) {
    camera.pitch = c.number("pitch");
    if (!(std::abs(*camera.pitch) < 1.5)) c.fail("pitch", "must be in (-1.5, 1.5) rad");
  }
  camera.zoom = c.number("zoom", 1.0);
  if (!(std::isfinite(camera.zoom) && camera.zoom > 0)) c.fail("zoom", "must be > 0");
  c.finish();
  return camera;
}

}  // namespace torsion::scene
