#include "py_convert.h"

#include <cmath>
#include <cstdint>
#include <limits>

#include "torsion/format_number.h"

namespace torsion::python {

void raise(FailureKind kind, const std::string& message) {
  if (kind == FailureKind::kValue) throw py::value_error(message);
  if (kind == FailureKind::kOutput) {
    PyErr_SetString(PyExc_OSError, message.c_str());
    throw py::error_already_set();
  }
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

namespace {

// numpy's dtype kind of `value` as it would become an array: 'f', 'i', 'u', 'b', 'c', 'O', ...
char dtypeKind(py::handle value, const char* what) {
  py::array a;
  try {
    a = py::array::ensure(value);
  } catch (const py::error_already_set&) {
    a = py::array();
  }
  if (!a) throw py::type_error(std::string(what) + ": expected numbers");
  return a.dtype().kind();
}

std::string shown(py::handle value) {
  return py::repr(value).cast<std::string>();
}

}  // namespace

py::array_t<double, py::array::c_style | py::array::forcecast> toFloatArray(py::handle value,
                                                                            const char* what) {
  const char kind = dtypeKind(value, what);
  if (kind == 'c') {
    throw py::type_error(std::string(what) + ": expected real numbers, got complex " +
                         shown(value) + " (the imaginary part would be dropped)");
  }
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw py::type_error(std::string(what) + ": expected numbers, got " + shown(value));
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a) throw py::type_error(std::string(what) + ": expected numbers, got " + shown(value));
  return a;
}

IndexArray toIndexArray(py::handle value, const char* what) {
  const char kind = dtypeKind(value, what);
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    throw py::type_error(std::string(what) + ": expected integer indices, got " +
                         (kind == 'b' ? std::string("booleans ") : std::string()) + shown(value));
  }
  // Each value is checked in its own type (int64, uint64 or double) before it is narrowed.
  constexpr int64_t kLow = std::numeric_limits<int>::min();
  constexpr int64_t kHigh = std::numeric_limits<int>::max();
  IndexArray out;
  auto fail = [&](py::ssize_t k, const std::string& number, const char* fault) {
    throw py::value_error(std::string(what) + ": element " + std::to_string(k) + " (" + number +
                          ") " + fault);
  };
  auto take = [&](auto a, auto check) {
    out.shape.assign(a.shape(), a.shape() + a.ndim());
    out.values.reserve(static_cast<size_t>(a.size()));
    for (py::ssize_t k = 0; k < a.size(); ++k) {
      check(k, a.data()[k]);
      out.values.push_back(static_cast<int>(a.data()[k]));
    }
  };
  if (kind == 'i') {
    take(py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(value),
         [&](py::ssize_t k, int64_t v) {
           if (v < kLow || v > kHigh) fail(k, std::to_string(v), "is outside the int32 range");
         });
  } else if (kind == 'u') {
    take(py::array_t<uint64_t, py::array::c_style | py::array::forcecast>::ensure(value),
         [&](py::ssize_t k, uint64_t v) {
           if (v > static_cast<uint64_t>(kHigh))
             fail(k, std::to_string(v), "is outside the int32 range");
         });
  } else {
    take(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value),
         [&](py::ssize_t k, double v) {
           if (!(std::isfinite(v) && v == std::floor(v)))
             fail(k, formatNumber(v), "is not a whole number");
           if (v < static_cast<double>(kLow) || v > static_cast<double>(kHigh))
             fail(k, formatNumber(v), "is outside the int32 range");
         });
  }
  return out;
}

double finite(double value, const char* what) {
  if (!std::isfinite(value))
    throw py::value_error(std::string(what) + ": must be finite, got " + formatNumber(value));
  return value;
}

Eigen::Vector3d toVector3(py::handle value, const char* what) {
  auto a = toFloatArray(value, what);
  if (a.size() != 3)
    throw py::value_error(std::string(what) + ": expected 3 numbers, got " + shown(value));
  Eigen::Vector3d v(a.data()[0], a.data()[1], a.data()[2]);
  if (!v.allFinite())
    throw py::value_error(std::string(what) + ": must be finite, got " + shown(value));
  return v;
}

Eigen::Quaterniond toQuaternion(py::handle value, const char* what) {
  auto a = toFloatArray(value, what);
  if (a.size() != 4) throw py::value_error(std::string(what) + ": expected 4 numbers (x, y, z, w)");
  Eigen::Quaterniond q(a.data()[3], a.data()[0], a.data()[1], a.data()[2]);
  if (!q.coeffs().allFinite()) throw py::value_error(std::string(what) + ": must be finite");
  if (!(q.norm() > 1e-12)) throw py::value_error(std::string(what) + ": zero length");
  return q.normalized();
}

Eigen::VectorXd toNodeVectors(py::handle value, py::ssize_t expected, const char* what) {
  auto a = toFloatArray(value, what);
  if (a.ndim() != 2 || a.shape(1) != 3 || (expected >= 0 && a.shape(0) != expected)) {
    throw py::value_error(std::string(what) + ": expected an array of shape (" +
                          (expected >= 0 ? std::to_string(expected) : std::string("n")) + ", 3)");
  }
  Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(a.data(), a.size());
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    if (!std::isfinite(v[k])) {
      throw py::value_error(std::string(what) + ": row " + std::to_string(k / 3) +
                            " is not finite (" + formatNumber(v[k]) + ")");
    }
  }
  return v;
}

Frame toFrame(py::handle value, const char* what) {
  if (py::isinstance<Frame>(value)) return value.cast<Frame>();
  auto a = toFloatArray(value, what);
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    throw py::value_error(std::string(what) + ": expected a torsion.Frame or a 4x4 matrix");
  }
  Eigen::Matrix4d m = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(a.data());
  if (!m.allFinite()) throw py::value_error(std::string(what) + ": the 4x4 matrix is not finite");
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
