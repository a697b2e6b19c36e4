#include "gl_api.h"

namespace torsion::render {

std::string loadGlApi(GlApi& gl, GlProcLoader load) {
  std::string missing;
#define TORSION_GL_LOAD(name)                                      \
  gl.name = reinterpret_cast<decltype(gl.name)>(load("gl" #name)); \
  if (gl.name == nullptr) missing += (missing.empty() ? "gl" : ", gl") + std::string(#name);
  TORSION_GL_FUNCTIONS(TORSION_GL_LOAD)
#undef TORSION_GL_LOAD
  return missing;
}

}  // namespace torsion::render
