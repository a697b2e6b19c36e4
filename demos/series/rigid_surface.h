#pragma once
// A rigid body's surface as triangles in the world, for files (the renderer draws the same
// shapes from their parameters): boxes by their 12 triangles, spheres and capsules tessellated
// (16 around, 8 from pole to pole; exact at the vertices), hulls and meshes as they are, anything
// else as its bounding box. Planes are unbounded and have none.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "rigid_geometry.h"

namespace torsion::series {

struct RigidSurface {
  std::vector<Eigen::Vector3d> vertices;  ///< world coordinates, m
  std::vector<std::array<int, 3>> triangles;
};

RigidSurface rigidSurface(const render::RigidDrawData& rigid);

}  // namespace torsion::series
