#pragma once
// An orbit camera: it looks at `target` from `distance`, at `yaw` about the scene's up axis and
// `pitch` above the horizon. frameCamera fits a scene into the picture.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "frame_data.h"

namespace torsion::render {

struct Camera {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  ///< unit; the screen's vertical
  double distance = 10;                           ///< m
  double yaw = 0.5;                               ///< rad, about up
  double pitch = 0.35;                            ///< rad, above the plane normal to up
  double fov_y = 0.52;                            ///< rad, vertical field of view

  Eigen::Vector3d eye() const;
  /// World to eye coordinates (OpenGL convention: looking down -z).
  Eigen::Matrix4d view() const;
  Eigen::Matrix4d projection(double aspect) const;

  void orbit(double dyaw, double dpitch);
  /// Moves the target by fractions of the visible height, along the screen's axes.
  void pan(double dx, double dy);
  void zoom(double factor);
};

/// The scene's `camera` entry (frame.camera) chooses up, yaw, pitch and zoom; by default up is
/// against gravity, and without gravity z unless z is the scene's longest extent (a standing
/// cylinder is then shown lying across the picture), and the view is oblique, looking across the
/// longest horizontal extent. The distance fits the bounds (down to the ground plane, when the
/// scene has one) with a margin into the picture's
/// height minus the top `top_reserved` fraction (the HUD, hudHeightFraction), and the view is
/// shifted so the scene sits centred below it.
Camera frameCamera(const FrameData& frame, double aspect, double top_reserved = 0);

}  // namespace torsion::render
