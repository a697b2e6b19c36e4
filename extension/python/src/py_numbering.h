#pragma once
// Python speaks the node and tet numbers of a body's mesh file (or arrays), FemBody its own, which
// differ when the body was renumbered for cache locality (torsion/mesh/input_numbering.h). These
// translate what crosses between them; errors name the caller's numbers.

#include <pybind11/numpy.h>

#include <string>
#include <vector>

#include "torsion/bullet/fem_body.h"

namespace torsion::python {

namespace py = pybind11;

/// The body's numbers of the caller's `nodes`: ValueError ("<where>node N out of range [0, n)",
/// "... listed twice", and with `anchoring` "... is anchored already") in the caller's numbers.
std::vector<int> bodyNodes(const FemBody& body, std::vector<int> nodes, const std::string& where,
                           bool anchoring = false);
/// (k,) int32, ascending: the caller's numbers of the body's `nodes`.
py::array_t<int> inputNodeArray(const FemBody& body, const std::vector<int>& nodes);
/// (m, 4) or (m, 10) int32, read-only: the body's elements as the caller numbers them.
py::array_t<int> inputElementArray(const FemBody& body);

}  // namespace torsion::python
