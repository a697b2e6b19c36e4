#pragma once
// A lower layer reaching up to a higher one: check_layers.cmake must refuse it
// (unit.include_layers_refuses_an_upward_include).
#include "torsion/bullet/fem_body.h"
