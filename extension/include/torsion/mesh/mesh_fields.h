#pragma once
// Named per-node or per-tet data written beside a mesh (displacement, stress, ...).

#include <string>
#include <vector>

namespace torsion {

struct MeshField {
  std::string name;            ///< no spaces (VTK requirement); e.g. "von_mises_Pa"
  int components = 1;          ///< 1 (scalar) or 3 (vector)
  std::vector<double> values;  ///< count * components values, entity-major
};

struct MeshFields {
  std::vector<MeshField> node_fields;  ///< one entry per node each
  std::vector<MeshField> tet_fields;   ///< one entry per tet each
};

}  // namespace torsion
