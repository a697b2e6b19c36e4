#include "torsion/mesh/gmsh_format.h"

#include <gtest/gtest.h>

#include "error_matchers.h"
