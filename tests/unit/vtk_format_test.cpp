#include "torsion/mesh/vtk_format.h"

#include <gtest/gtest.h>

#include "error_matchers.h"
