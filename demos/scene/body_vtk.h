#pragma once
// A body as `torsion run` writes <body>.vtk and Python's World.write_vtk: its mesh at given node
// positions with the displacement from rest, legacy VTK, in the numbering of the body's mesh file
// (torsion/mesh/input_numbering.h).

#include <Eigen/Core>
#include <string>

#include "torsion/bullet/fem_body.h"

namespace torsion::scene {

/// `positions`: 3n, in the body's own numbering (FemBody::state()).
std::string bodyVtkText(const FemBody& body, const Eigen::VectorXd& positions);

}  // namespace torsion::scene
