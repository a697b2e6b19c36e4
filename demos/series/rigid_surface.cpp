#include "rigid_surface.h"

#include <cmath>

namespace torsion::series {

namespace {

void addBox(const Eigen::Vector3d& h, RigidSurface& s) {
  for (int k = 0; k < 8; ++k)
    s.vertices.emplace_back((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(),
                            (k & 4) ? h.z() : -h.z());
  // Two triangles per face, counter-clockwise from outside.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    s.triangles.push_back({f[0], f[1], f[2]});
    s.triangles.push_back({f[0], f[2], f[3]});
  }
}

// A sphere of `radius` whose upper half is moved by +half_height and lower half by -half_height
// along `axis` (a capsule; a sphere when half_height is 0).
void addRoundedShape(double radius, double half_height, int axis, RigidSurface& s) {
  constexpr int kAround = 16, kHalfStacks = 4;
  const double pi = std::acos(-1.0);
  auto place = [&](double polar, double azimuth, double shift) {
    Eigen::Vector3d local(radius * std::sin(polar) * std::cos(azimuth),
                          radius * std::sin(polar) * std::sin(azimuth),
                          radius * std::cos(polar) + shift);
    // The shape's axis is local z here; rotate it onto `axis` by a cyclic permutation.
    Eigen::Vector3d out;
    out[axis] = local.z();
    out[(axis + 1) % 3] = local.x();
    out[(axis + 2) % 3] = local.y();
    return out;
  };
  // Rings from the top pole to the bottom; the equator twice when the halves are apart.
  std::vector<std::pair<double, double>> rings;  // (polar angle, shift)
  for (int i = 1; i <= kHalfStacks; ++i)
    rings.emplace_back(pi / 2 * i / kHalfStacks, half_height);
  for (int i = half_height > 0 ? 0 : 1; i < kHalfStacks; ++i)
    rings.emplace_back(pi / 2 + pi / 2 * i / kHalfStacks, -half_height);
  const int top = static_cast<int>(s.vertices.size());
  s.vertices.push_back(place(0, 0, half_height));
  for (const auto& [polar, shift] : rings) {
    for (int j = 0; j < kAround; ++j)
      s.vertices.push_back(place(polar, 2 * pi * j / kAround, shift));
  }
  const int bottom = static_cast<int>(s.vertices.size());
  s.vertices.push_back(place(pi, 0, -half_height));
  auto ring_vertex = [&](int ring, int j) { return top + 1 + ring * kAround + (j % kAround); };
  const int ring_count = static_cast<int>(rings.size());
  for (int j = 0; j < kAround; ++j) {
    s.triangles.push_back({top, ring_vertex(0, j), ring_vertex(0, j + 1)});
    for (int r = 0; r + 1 < ring_count; ++r) {
      s.triangles.push_back({ring_vertex(r, j), ring_vertex(r + 1, j), ring_vertex(r + 1, j + 1)});
      s.triangles.push_back({ring_vertex(r, j), ring_vertex(r + 1, j + 1), ring_vertex(r, j + 1)});
    }
    s.triangles.push_back(
        {bottom, ring_vertex(ring_count - 1, j + 1), ring_vertex(ring_count - 1, j)});
  }
}

}  // namespace

RigidSurface rigidSurface(const render::RigidDrawData& rigid) {
  using Shape = render::RigidDrawData::Shape;
  RigidSurface s;
  switch (rigid.shape) {
    case Shape::kBox:
    case Shape::kOther:
      addBox(rigid.half_extents, s);
      break;
    case Shape::kSphere:
      addRoundedShape(rigid.radius, 0, 2, s);
      break;
    case Shape::kCapsule:
      addRoundedShape(rigid.radius, rigid.half_height, rigid.axis, s);
      break;
    case Shape::kTriangles:
      s.vertices = rigid.vertices;
      s.triangles = rigid.triangles;
      break;
    case Shape::kPlane:
      return s;
  }
  for (Eigen::Vector3d& v : s.vertices)
    v = rigid.pose * v;
  return s;
}

}  // namespace torsion::series
