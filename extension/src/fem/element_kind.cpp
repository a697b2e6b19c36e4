#include "torsion/fem/element_kind.h"

namespace torsion {

const char* toString(ElementKind kind) {
  return kind == ElementKind::kTet10 ? "tet10" : "tet4";
}

std::optional<ElementKind> parseElementKind(const std::string& name) {
  if (name == "tet4") return ElementKind::kTet4;
  if (name == "tet10") return ElementKind::kTet10;
  return std::nullopt;
}

}  // namespace torsion
