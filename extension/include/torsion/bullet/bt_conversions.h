#pragma once
// The Bullet/Eigen conversions moved to torsion/bt_conversions.h, below every folder that uses
// them (contact/ and bullet/ alike). This forwarding header keeps code written against the old
// path compiling; include torsion/bt_conversions.h in new code.

#include "torsion/bt_conversions.h"
