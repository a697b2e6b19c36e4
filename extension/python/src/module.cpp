// The compiled half of the torsion package (torsion/_torsion): the Python half (torsion/
// __init__.py, errors.py) re-exports it and defines the exceptions it raises.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "data_directory.h"
#include "handles.h"

#ifndef TORSION_VERSION
#error "TORSION_VERSION must be defined by the build (the CMake project's version)"
#endif

PYBIND11_MODULE(_torsion, m) {
  m.doc() = "Corotational FEM soft bodies in Bullet: the compiled core of the torsion package.";
  m.attr("__version__") = TORSION_VERSION;
  m.attr("bullet_precision") = sizeof(btScalar) == 8 ? "double" : "float";
  m.def("_data_directory", &torsion::scene::dataDirectory,
        "The data folder (demos/scenes, assets) found from this module's file, or None; "
        "torsion.data_path() wraps it.");
  torsion::python::bindTypes(m);
  torsion::python::bindParts(m);
  torsion::python::bindWorld(m);
  torsion::python::bindViewer(m);
}
