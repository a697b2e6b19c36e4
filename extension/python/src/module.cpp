// The compiled half of the torsion package (torsion/_torsion): the Python half (torsion/
// __init__.py, errors.py) re-exports it and defines the exceptions it raises.
#include <pybind11/pybind11.h>

#include "handles.h"

#ifndef TORSION_VERSION
#error "TORSION_VERSION must be defined by the build (the CMake project's version)"
#endif

PYBIND11_MODULE(_torsion, m) {
  m.doc() = "Corotational FEM soft bodies in Bullet: the compiled core of the torsion package.";
  m.attr("__version__") = TORSION_VERSION;
  m.attr("bullet_precision") = sizeof(btScalar) == 8 ? "double" : "float";
  torsion::python::bindTypes(m);
  torsion::python::bindParts(m);
  torsion::python::bindWorld(m);
}
