#pragma once
// Small meshes written inline, shared by the unit tests.

#include <string>

namespace torsion::test {

/// A unit cube split into 5 tets (4 corner tets + 1 central), TetGen, 0-based.
inline const std::string kCubeNode = R"(# unit cube corners
8 3 0 0
0 0 0 0
1 1 0 0
2 0 1 0
3 1 1 0
4 0 0 1
5 1 0 1
6 0 1 1
7 1 1 1
)";
inline const std::string kCubeEle = R"(5 4 0
0 0 1 2 4
1 3 2 1 7
2 5 1 4 7
3 6 4 2 7
4 1 2 4 7
)";

}  // namespace torsion::test
