#include "py_convert.h"

#include <cmath>

namespace torsion::python {

void raise(FailureKind kind, const std::string& message) {
  if (kind == FailureKind::kValue) throw py::value_error(message);
  const char* name = kind == FailureKind::kScene  ? "SceneError"
                     : kind == FailureKind::kMesh ? "MeshError"
                                                  : "UnstableError";
  py::object cls = py::module_::import("torsion.errors").attr(name);
  PyErr_SetObject(cls.ptr(), py::str(message).ptr());
  throw py::error_already_set();
}

py::array_t<double> vectorArray(const double* data, py::ssize_t size) {
  py::array_t<double> out(size);
  std::copy(data, data + size, out.mutable_data());
  return out;
}

py::array_t<double> wrenchArray(const Wrench& wrench) {
  const double values[6] = {wrench.force.x(),  wrench.force.y(),  wrench.force.z(),
                            wrench.torque.x(), wrench.torque.y(), wrench.torque.z()};
  return vectorArray(values, 6);
}

Eigen::Vector3d toVector3(py::handle value, const char* what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.size() != 3) throw py::value_error(std::string(what) + ": expected 3 numbers");
  return Eigen::Vector3d(a.data()[0], a.data()[1], a.data()[2]);
}

Eigen::VectorXd toNodeVectors(py::handle value, py::ssize_t expected, const char* what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 2 || a.shape(1) != 3 || (expected >= 0 && a.shape(0) != expected)) {
    throw py::value_error(std::string(what) + ": expected an array of shape (" +
                          (expected >= 0 ? std::to_string(expected) : std::string("n")) + ", 3)");
  }
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.size());
}

Frame toFrame(py::handle value, const char* what) {
  if (py::isinstance<Frame>(value)) return value.cast<Frame>();
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    throw py::value_error(std::string(what) + ": expected a torsion.Frame or a 4x4 matrix");
  }
  Eigen::Matrix4d m = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(a.data());
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if (!((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-6) ||
      !(r.determinant() > 0)) {
    throw py::value_error(std::string(what) + ": the 4x4 matrix's rotation part is not a rotation");
  }
  Frame frame;
  frame.origin = m.topRightCorner<3, 1>();
  frame.rotation = Eigen::Quaterniond(r).normalized();
  return frame;
}

}  // namespace torsion::python
