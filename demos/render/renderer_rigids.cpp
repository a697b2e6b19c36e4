// The rigid bodies of a frame, lit, in their poses: boxes, spheres, capsules (a cylinder between
// two hemispheres), and the triangles of convex hulls and triangle meshes (flat-shaded: a hull's
// faces are planes). Static bodies grey, dynamic ones brick red. Planes are the ground
// (renderer.cpp).

#include <cmath>

#include "renderer.h"

namespace torsion::render {

namespace {

// Tessellation of round shapes: fine enough that a capsule or ball 1/3 of the picture high shows
// no facets in the shading at 800x600.
constexpr int kStacks = 16, kSlices = 24;

}  // namespace

void Renderer::drawRigids(const FrameData& frame) {
  const GlApi& gl = gl_;
  gl.Enable(GL_LIGHTING);
  gl.Enable(GL_COLOR_MATERIAL);
  for (const RigidDrawData& r : frame.rigids) {
    if (r.shape == RigidDrawData::Shape::kPlane) continue;
    if (r.is_static) {
      gl.Color4d(0.55, 0.55, 0.58, 1);
    } else {
      gl.Color4d(0.78, 0.42, 0.36, 1);  // brick red: clearly not a stress colour
    }
    switch (r.shape) {
      case RigidDrawData::Shape::kSphere:
        drawRound(r.pose, r.radius, 0, 2);
        break;
      case RigidDrawData::Shape::kCapsule:
        drawRound(r.pose, r.radius, r.half_height, r.axis);
        break;
      case RigidDrawData::Shape::kTriangles:
        drawTriangles(r);
        break;
      default:
        drawBox(r.pose, r.half_extents);
        break;
    }
  }
  gl.Disable(GL_LIGHTING);
}

void Renderer::drawRound(const Eigen::Isometry3d& pose, double radius, double half_height,
                         int axis) {
  const GlApi& gl = gl_;
  const Eigen::Vector3d a = Eigen::Vector3d::Unit(axis), b = Eigen::Vector3d::Unit((axis + 1) % 3),
                        c = Eigen::Vector3d::Unit((axis + 2) % 3);
  // Latitude t from -pi/2 (the cap at -half_height) to pi/2; the lower half of the stacks sits
  // on the lower cap's centre, the upper half on the upper one's.
  auto vertex = [&](double t, double phi, double centre) {
    const Eigen::Vector3d n =
        std::cos(t) * (std::cos(phi) * b + std::sin(phi) * c) + std::sin(t) * a;
    const Eigen::Vector3d wn = pose.linear() * n;
    const Eigen::Vector3d p = pose * (centre * a + radius * n);
    gl.Normal3d(wn.x(), wn.y(), wn.z());
    gl.Vertex3d(p.x(), p.y(), p.z());
  };
  for (int i = 0; i < kStacks; ++i) {
    const double t0 = M_PI * i / kStacks - M_PI / 2, t1 = M_PI * (i + 1) / kStacks - M_PI / 2;
    const double centre = 2 * i < kStacks ? -half_height : half_height;
    gl.Begin(GL_QUAD_STRIP);
    for (int j = 0; j <= kSlices; ++j) {
      const double phi = 2 * M_PI * j / kSlices;
      vertex(t1, phi, centre);
      vertex(t0, phi, centre);
    }
    gl.End();
  }
  if (half_height <= 0) return;  // a sphere
  gl.Begin(GL_QUAD_STRIP);       // the cylinder between the caps' equators
  for (int j = 0; j <= kSlices; ++j) {
    const double phi = 2 * M_PI * j / kSlices;
    vertex(0, phi, half_height);
    vertex(0, phi, -half_height);
  }
  gl.End();
}

void Renderer::drawBox(const Eigen::Isometry3d& pose, const Eigen::Vector3d& half_extents) {
  const GlApi& gl = gl_;
  gl.Begin(GL_QUADS);
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {-1, 1}) {
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = sign;
      const Eigen::Vector3d u = Eigen::Vector3d::Unit((axis + 1) % 3),
                            v = Eigen::Vector3d::Unit((axis + 2) % 3);
      const Eigen::Vector3d wn = pose.linear() * n;
      gl.Normal3d(wn.x(), wn.y(), wn.z());
      // Counter-clockwise seen from outside: u x v = +axis, so flip the order for -axis.
      const double s = sign;
      for (const auto& [cu, cv] :
           {std::pair(-1.0, -1.0), std::pair(s, -s), std::pair(1.0, 1.0), std::pair(-s, s)}) {
        const Eigen::Vector3d local = n + cu * u + cv * v;
        const Eigen::Vector3d p = pose * local.cwiseProduct(half_extents);
        gl.Vertex3d(p.x(), p.y(), p.z());
      }
    }
  }
  gl.End();
}

void Renderer::drawTriangles(const RigidDrawData& r) {
  const GlApi& gl = gl_;
  gl.Begin(GL_TRIANGLES);
  for (const std::array<int, 3>& tri : r.triangles) {
    const Eigen::Vector3d p0 = r.pose * r.vertices[static_cast<size_t>(tri[0])],
                          p1 = r.pose * r.vertices[static_cast<size_t>(tri[1])],
                          p2 = r.pose * r.vertices[static_cast<size_t>(tri[2])];
    // The face's own normal, by the right-hand rule: a triangle wound the wrong way faces away
    // from the light and shows dark (lighting is one-sided), as a flipped FEM surface does.
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    if (!(n.squaredNorm() > 0)) continue;  // degenerate: no face to show
    gl.Normal3d(n.x(), n.y(), n.z());      // GL_NORMALIZE is on
    for (const Eigen::Vector3d& p : {p0, p1, p2})
      gl.Vertex3d(p.x(), p.y(), p.z());
  }
  gl.End();
}

}  // namespace torsion::render
