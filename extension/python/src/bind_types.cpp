// torsion.Frame, torsion.Material and torsion.State: plain values.
#include <pybind11/stl.h>

#include <array>
#include <optional>
#include <string>

#include "handles.h"
#include "py_convert.h"
#include "torsion/bullet/checkpoint_io.h"
#include "torsion/fem/material.h"

namespace torsion::python {
namespace {

// A state of bytes alone; their header, length and hash are checked now, the rest when restored.
PyWorldState stateFromBytes(const py::bytes& data) {
  PyWorldState state;
  state.in_memory = false;
  state.bytes = data;
  Result<double> time = checkpointTime(state.bytes);
  if (!time) throw py::value_error("torsion.State: " + time.error().message);
  state.time = time.value();
  return state;
}

}  // namespace

namespace {

py::array_t<double> quaternionArray(const Eigen::Quaterniond& q) {
  const double xyzw[4] = {q.x(), q.y(), q.z(), q.w()};
  return vectorArray(xyzw, 4);
}

// ((x, y, z), (qx, qy, qz, qw)): a Frame's pickled form.
py::tuple frameTuple(const Frame& f) {
  const Eigen::Quaterniond& q = f.rotation;
  return py::make_tuple(py::make_tuple(f.origin.x(), f.origin.y(), f.origin.z()),
                        py::make_tuple(q.x(), q.y(), q.z(), q.w()));
}

Material makeMaterial(double E, double nu, double rho, double mass_damping,
                      double stiffness_damping, const std::string& volumetric_strain,
                      double barrier_threshold, double barrier_stiffness, const std::string& law,
                      double mooney_rivlin_c2_fraction) {
  Material mat;
  mat.youngs_modulus = E;
  mat.poisson_ratio = nu;
  mat.density = rho;
  mat.mass_damping = mass_damping;
  mat.stiffness_damping = stiffness_damping;
  std::optional<VolumetricStrain> kind = parseVolumetricStrain(volumetric_strain);
  if (!kind) {
    throw py::value_error("material: volumetric_strain '" + volumetric_strain +
                          "': expected 'element' or 'nodal_average'");
  }
  mat.volumetric_strain = *kind;
  mat.barrier_threshold = barrier_threshold;
  mat.barrier_stiffness = barrier_stiffness;
  std::optional<MaterialLaw> law_kind = parseMaterialLaw(law);
  if (!law_kind) {
    throw py::value_error("material: law '" + law +
                          "': expected 'corotated', 'stable_neo_hookean' or 'mooney_rivlin'");
  }
  mat.law = *law_kind;
  mat.mooney_rivlin_c2_fraction = mooney_rivlin_c2_fraction;
  if (Status valid = mat.validate(); !valid) throw py::value_error(valid.error().message);
  return mat;
}

// The constructor's arguments, in its order: a Material's pickled form and what == compares.
py::tuple materialTuple(const Material& mat) {
  return py::make_tuple(mat.youngs_modulus, mat.poisson_ratio, mat.density, mat.mass_damping,
                        mat.stiffness_damping, toString(mat.volumetric_strain),
                        mat.barrier_threshold, mat.barrier_stiffness, toString(mat.law),
                        mat.mooney_rivlin_c2_fraction);
}

}  // namespace

void bindTypes(py::module_& m) {
  py::class_<Frame>(m, "Frame",
                    "A rigid frame: origin (m) and rotation as a unit quaternion (x, y, z, w). "
                    "Maps local p to world R p + origin.")
      .def(py::init([](py::object position, py::object quaternion) {
             Frame f;
             f.origin = toVector3(position, "position");
             f.rotation = toQuaternion(quaternion, "quaternion");
             return f;
           }),
           py::arg("position") = py::make_tuple(0.0, 0.0, 0.0),
           py::arg("quaternion") = py::make_tuple(0.0, 0.0, 0.0, 1.0))
      .def_static(
          "from_matrix", [](py::object matrix) { return toFrame(matrix, "Frame.from_matrix"); },
          py::arg("matrix"), "From a 4x4 homogeneous matrix (m).")
      .def_static(
          "from_axis_angle",
          [](py::object position, py::object axis, double angle) {
            Frame f;
            f.origin = toVector3(position, "position");
            const Eigen::Vector3d direction = toVector3(axis, "axis");
            if (!(direction.norm() > 1e-12)) throw py::value_error("axis: must not be zero");
            f.rotation = Eigen::AngleAxisd(finite(angle, "angle"), direction.normalized());
            return f;
          },
          py::arg("position"), py::arg("axis"), py::arg("angle"),
          "Origin (m) and a rotation of `angle` rad about `axis`.")
      .def_property_readonly(
          "position", [](const Frame& f) { return vectorArray(f.origin.data(), 3); }, "m, (3,)")
      .def_property_readonly(
          "quaternion", [](const Frame& f) { return quaternionArray(f.rotation); },
          "(x, y, z, w), unit")
      .def(
          "matrix",
          [](const Frame& f) {
            Eigen::Matrix<double, 4, 4, Eigen::RowMajor> h = Eigen::Matrix4d::Identity();
            h.topLeftCorner<3, 3>() = f.rotation.toRotationMatrix();
            h.topRightCorner<3, 1>() = f.origin;
            return copyArray(h.data(), 4, 4);
          },
          "The 4x4 homogeneous matrix.")
      .def(
          "__eq__",
          [](const Frame& a, const Frame& b) {
            return a.origin == b.origin && a.rotation.coeffs() == b.rotation.coeffs();
          },
          py::is_operator())
      .def("__hash__", [](const Frame& f) { return py::hash(frameTuple(f)); })
      // Pickled as its position and quaternion, exactly (a float per double, no rounding).
      .def(py::pickle([](const Frame& f) { return frameTuple(f); },
                      [](const py::tuple& t) {
                        if (t.size() != 2) throw py::value_error("torsion.Frame: bad pickle");
                        Frame f;
                        f.origin = toVector3(t[0], "position");
                        const auto q = t[1].cast<std::array<double, 4>>();
                        // As saved: a unit quaternion is not normalised again (that could round).
                        f.rotation = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
                        return f;
                      }))
      .def("__repr__", [](const Frame& f) {
        return "Frame(position=(" + std::to_string(f.origin.x()) + ", " +
               std::to_string(f.origin.y()) + ", " + std::to_string(f.origin.z()) +
               "), quaternion=(" + std::to_string(f.rotation.x()) + ", " +
               std::to_string(f.rotation.y()) + ", " + std::to_string(f.rotation.z()) + ", " +
               std::to_string(f.rotation.w()) + "))";
      });

  py::class_<Material>(m, "Material", "Linear elastic material, SI units.")
      .def(py::init(&makeMaterial), py::arg("E") = 1e5, py::arg("nu") = 0.3,
           py::arg("rho") = 1000.0, py::arg("mass_damping") = 0.0,
           py::arg("stiffness_damping") = 0.01, py::arg("volumetric_strain") = "element",
           py::arg("barrier_threshold") = Material{}.barrier_threshold,
           py::arg("barrier_stiffness") = Material{}.barrier_stiffness,
           py::arg("law") = "corotated",
           py::arg("mooney_rivlin_c2_fraction") = Material{}.mooney_rivlin_c2_fraction,
           "E: Young's modulus, Pa; nu: Poisson's ratio in [0, 0.5); rho: density, kg/m^3; "
           "mass_damping: 1/s; stiffness_damping: s; barrier_threshold: the volume ratio J below "
           "which the volume barrier against inverted tets acts, in [0, 1), 0 turns it off; "
           "barrier_stiffness: its pressure at J = 0 in bulk moduli; law: 'corotated', "
           "'stable_neo_hookean' or 'mooney_rivlin' (hyperelastic, on tet4 or tet10; "
           "docs/materials.md); mooney_rivlin_c2_fraction: C2 / (C1 + C2) in [0, 1].")
      .def_readonly("E", &Material::youngs_modulus, "Young's modulus, Pa")
      .def_readonly("nu", &Material::poisson_ratio, "Poisson's ratio")
      .def_readonly("rho", &Material::density, "density, kg/m^3")
      .def_readonly("mass_damping", &Material::mass_damping, "1/s")
      .def_readonly("stiffness_damping", &Material::stiffness_damping, "s")
      .def_property_readonly("volumetric_strain",
                             [](const Material& mat) { return toString(mat.volumetric_strain); })
      .def_readonly("barrier_threshold", &Material::barrier_threshold,
                    "volume ratio J below which the volume barrier acts (0: off)")
      .def_readonly("barrier_stiffness", &Material::barrier_stiffness,
                    "the barrier's pressure at J = 0, in bulk moduli")
      .def_property_readonly("law", [](const Material& mat) { return toString(mat.law); })
      .def_readonly("mooney_rivlin_c2_fraction", &Material::mooney_rivlin_c2_fraction,
                    "C2 / (C1 + C2) of the Mooney-Rivlin law")
      .def_property_readonly("shear_modulus", &Material::mu, "G, Pa")
      .def(
          "__eq__",
          [](const Material& a, const Material& b) {
            return materialTuple(a).equal(materialTuple(b));
          },
          py::is_operator())
      .def("__hash__", [](const Material& mat) { return py::hash(materialTuple(mat)); })
      // Pickled as the constructor's arguments in order, which it checks again when unpickled.
      .def(py::pickle([](const Material& mat) { return materialTuple(mat); },
                      [](const py::tuple& t) {
                        if (t.size() != 10) throw py::value_error("torsion.Material: bad pickle");
                        return makeMaterial(t[0].cast<double>(), t[1].cast<double>(),
                                            t[2].cast<double>(), t[3].cast<double>(),
                                            t[4].cast<double>(), t[5].cast<std::string>(),
                                            t[6].cast<double>(), t[7].cast<double>(),
                                            t[8].cast<std::string>(), t[9].cast<double>());
                      }))
      .def("__repr__", [](const Material& mat) {
        return "Material(E=" + std::to_string(mat.youngs_modulus) +
               ", nu=" + std::to_string(mat.poisson_ratio) +
               ", rho=" + std::to_string(mat.density) + ")";
      });

  py::class_<PyWorldState>(m, "State",
                           "A world at a moment (World.save_state). restore_state continues bit "
                           "for bit as the world did after save_state, also after pickling.")
      .def_property_readonly("time", [](const PyWorldState& s) { return s.time; })
      .def(
          "to_bytes", [](const PyWorldState& s) { return py::bytes(s.bytes); },
          "The versioned checkpoint bytes pickle stores.")
      .def_static("from_bytes", &stateFromBytes, py::arg("data"),
                  "A state of checkpoint bytes (to_bytes); errors on bytes that are not one.")
      .def(py::pickle([](const PyWorldState& s) { return py::bytes(s.bytes); },
                      [](const py::bytes& data) { return stateFromBytes(data); }));
}

}  // namespace torsion::python
