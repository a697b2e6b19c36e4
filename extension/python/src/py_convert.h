#pragma once
// Conversions between the library's types and Python: numpy views and copies, frames, and the
// package's exceptions (torsion/errors.py). Shared by the bind_*.cpp files.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "py_world.h"
#include "torsion/constraints/carried_nodes.h"
#include "torsion/constraints/frame.h"

namespace torsion::python {

namespace py = pybind11;

/// Raises torsion.SceneError / MeshError / UnstableError, ValueError for kValue, OSError for
/// kOutput.
[[noreturn]] void raise(FailureKind kind, const std::string& message);

/// A read-only (rows, cols) numpy view of row-major storage owned by C++; `owner` (the Python
/// object whose lifetime covers the storage) is kept alive by the array.
template <class T>
py::array readOnlyView(const T* data, py::ssize_t rows, py::ssize_t cols, py::handle owner) {
  py::array_t<T> view(
      {rows, cols},
      {static_cast<py::ssize_t>(sizeof(T)) * cols, static_cast<py::ssize_t>(sizeof(T))}, data,
      owner);
  view.attr("setflags")(py::arg("write") = false);
  return std::move(view);
}

/// A fresh (rows, cols) array holding a copy of row-major `data`.
template <class T>
py::array_t<T> copyArray(const T* data, py::ssize_t rows, py::ssize_t cols) {
  py::array_t<T> out({rows, cols});
  std::copy(data, data + rows * cols, out.mutable_data());
  return out;
}

/// A fresh 1-D array.
py::array_t<double> vectorArray(const double* data, py::ssize_t size);
/// [fx, fy, fz, tx, ty, tz]: N and N m.
py::array_t<double> wrenchArray(const Wrench& wrench);

/// `value` as a float64 array (numpy's own conversion), refusing what would lose information:
/// TypeError naming `what` for complex values (numpy would drop the imaginary part) and for
/// anything that is not numbers.
py::array_t<double, py::array::c_style | py::array::forcecast> toFloatArray(py::handle value,
                                                                            const char* what);
/// `value` as int32 indices: integers, or floats with whole values, all within int32. Refuses
/// (naming `what` and the value) what numpy's cast would wrap or truncate: TypeError for bool,
/// complex or non-numeric arrays, ValueError for a fractional, non-finite or out-of-range value.
/// The caller checks the returned shape.
struct IndexArray {
  std::vector<int> values;  ///< row-major
  std::vector<py::ssize_t> shape;
};
IndexArray toIndexArray(py::handle value, const char* what);

/// A finite float: ValueError naming `what` and the value otherwise.
double finite(double value, const char* what);

/// A 3-vector from any sequence of three finite numbers; ValueError naming `what` otherwise.
Eigen::Vector3d toVector3(py::handle value, const char* what);
/// A rotation from four finite numbers (x, y, z, w), not all zero, normalised; ValueError naming
/// `what` otherwise.
Eigen::Quaterniond toQuaternion(py::handle value, const char* what);
/// An (n, 3) array of finite floats from `value`, with n rows checked when expected >= 0.
Eigen::VectorXd toNodeVectors(py::handle value, py::ssize_t expected, const char* what);

/// A torsion.Frame, or a 4x4 homogeneous matrix (rotation part orthonormal).
Frame toFrame(py::handle value, const char* what);

}  // namespace torsion::python
