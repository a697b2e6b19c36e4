#include "camera.h"

#include <algorithm>
#include <cmath>

namespace torsion::render {

namespace {

// Two unit vectors a, b with a x b = up.
void horizontalBasis(const Eigen::Vector3d& up, Eigen::Vector3d& a, Eigen::Vector3d& b) {
  const Eigen::Vector3d seed =
      std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  a = (seed - seed.dot(up) * up).normalized();
  b = up.cross(a);
}

}  // namespace

Eigen::Vector3d Camera::eye() const {
  Eigen::Vector3d a, b;
  horizontalBasis(up, a, b);
  const Eigen::Vector3d dir =
      std::cos(pitch) * (std::cos(yaw) * a + std::sin(yaw) * b) + std::sin(pitch) * up;
  return target + distance * dir;
}

Eigen::Matrix4d Camera::view() const {
  const Eigen::Vector3d e = eye();
  const Eigen::Vector3d f = (target - e).normalized();
  Eigen::Vector3d s = f.cross(up);
  if (s.norm() < 1e-9) s = f.unitOrthogonal();
  s.normalize();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(e);
  m(1, 3) = -u.dot(e);
  m(2, 3) = f.dot(e);
  return m;
}

Eigen::Matrix4d Camera::projection(double aspect) const {
  const double near_plane = std::max(1e-3, distance * 0.01), far_plane = distance * 100;
  const double f = 1 / std::tan(fov_y / 2);
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = f / aspect;
  p(1, 1) = f;
  p(2, 2) = (far_plane + near_plane) / (near_plane - far_plane);
  p(2, 3) = 2 * far_plane * near_plane / (near_plane - far_plane);
  p(3, 2) = -1;
  return p;
}

void Camera::orbit(double dyaw, double dpitch) {
  yaw += dyaw;
  pitch = std::clamp(pitch + dpitch, -1.5, 1.5);
}

void Camera::pan(double dx, double dy) {
  const Eigen::Matrix4d v = view();
  const double visible = 2 * distance * std::tan(fov_y / 2);
  target += visible * (dx * v.block<1, 3>(0, 0).transpose() + dy * v.block<1, 3>(1, 0).transpose());
}

void Camera::zoom(double factor) {
  distance = std::clamp(distance * factor, 1e-3, 1e6);
}

Camera frameCamera(const FrameData& frame, double aspect, double top_reserved) {
  Camera camera;
  // The bounds reach down to the ground, if any (the foot of their centre on each plane): a body
  // dropped from above lands in the picture.
  Eigen::AlignedBox3d bounds = frame.bounds;
  for (const RigidDrawData& r : frame.rigids) {
    if (r.shape != RigidDrawData::Shape::kPlane || frame.bounds.isEmpty()) continue;
    const Eigen::Vector3d n = r.normal.normalized(), c = frame.bounds.center();
    bounds.extend(c - (n.dot(c) - r.offset) * n);
  }
  const Eigen::Vector3d extent = bounds.sizes();
  const double free_height = 1 - std::clamp(top_reserved, 0.0, 0.5);
  if (frame.camera.up) {
    camera.up = *frame.camera.up;
  } else if (frame.gravity.norm() > 1e-12) {
    camera.up = -frame.gravity.normalized();
  } else {
    int longest = 0;
    extent.maxCoeff(&longest);
    camera.up = longest == 2 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  }
  Eigen::Vector3d a, b;
  horizontalBasis(camera.up, a, b);
  const double along_a = std::abs(a.dot(extent.cwiseProduct(a.cwiseSign()))),
               along_b = std::abs(b.dot(extent.cwiseProduct(b.cwiseSign())));
  // Look mostly across the longer horizontal extent, a little along it.
  camera.yaw = frame.camera.yaw.value_or(along_a >= along_b ? 1.2 : 0.37);
  camera.pitch = frame.camera.pitch.value_or(0.38);
  camera.target = bounds.center();
  // Distance: each bounding-box corner must fit in both fields of view.
  camera.distance = 1;
  const Eigen::Matrix4d v = camera.view();
  const Eigen::Matrix3d rot = v.block<3, 3>(0, 0);
  const double tan_y = std::tan(camera.fov_y / 2) * free_height,
               tan_x = std::tan(camera.fov_y / 2) * aspect;
  double needed = 1e-3;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? bounds.max().x() : bounds.min().x(),
                                 (c & 2) ? bounds.max().y() : bounds.min().y(),
                                 (c & 4) ? bounds.max().z() : bounds.min().z());
    const Eigen::Vector3d q = rot * (corner - camera.target);  // camera looks down -z
    needed = std::max(needed, std::abs(q.x()) / tan_x + q.z());
    needed = std::max(needed, std::abs(q.y()) / tan_y + q.z());
  }
  camera.distance = 1.12 * needed / frame.camera.zoom;
  // Look above the scene's centre so that it sits in the middle of the free part of the picture.
  const Eigen::Vector3d screen_up = rot.row(1).transpose();
  camera.target += screen_up * ((1 - free_height) * std::tan(camera.fov_y / 2) * camera.distance);
  return camera;
}

}  // namespace torsion::render
