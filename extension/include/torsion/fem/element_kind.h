#pragma once
// The finite element a body is discretised with, chosen per body (scene key "element").

#include <optional>
#include <string>

namespace torsion {

enum class ElementKind {
  kTet4,   ///< linear tetrahedron: 4 corner nodes, constant strain
  kTet10,  ///< quadratic tetrahedron: 4 corners + 6 mid-edge nodes, linear strain
};

/// "tet4" or "tet10".
const char* toString(ElementKind kind);
/// The inverse of toString; nullopt for anything else.
std::optional<ElementKind> parseElementKind(const std::string& name);
/// 4 or 10.
inline int nodesPerElement(ElementKind kind) {
  return kind == ElementKind::kTet10 ? 10 : 4;
}

}  // namespace torsion
