#pragma once
// The OpenGL 1.x (compatibility profile) entry points the renderer uses, loaded at run time from
// whichever context is current: OSMesa's for headless pictures, GLX's (through GLFW) for the
// window. Nothing links libGL or libOSMesa directly, so one `torsion` binary can hold both paths
// without their identically named gl* symbols colliding.

#include <GL/gl.h>

#include <string>

namespace torsion::render {

// Each entry: the name without its "gl" prefix. The member's type is taken from <GL/gl.h>'s
// declaration (decltype is unevaluated: no link-time reference to the symbol).
// One entry per line; the formatter would staircase the macro list.
// clang-format off
#define TORSION_GL_FUNCTIONS(X) \
  X(Viewport) \
  X(ClearColor) \
  X(Clear) \
  X(Enable) \
  X(Disable) \
  X(BlendFunc) \
  X(DepthMask) \
  X(DepthFunc) \
  X(MatrixMode) \
  X(LoadIdentity) \
  X(LoadMatrixd) \
  X(PushMatrix) \
  X(PopMatrix) \
  X(Ortho) \
  X(Lightfv) \
  X(LightModelfv) \
  X(LightModeli) \
  X(Materialfv) \
  X(Materialf) \
  X(ColorMaterial) \
  X(ShadeModel) \
  X(Begin) \
  X(End) \
  X(Vertex3d) \
  X(Vertex2d) \
  X(Normal3d) \
  X(Color4d) \
  X(LineWidth) \
  X(PointSize) \
  X(PolygonOffset) \
  X(EnableClientState) \
  X(DisableClientState) \
  X(VertexPointer) \
  X(NormalPointer) \
  X(ColorPointer) \
  X(DrawElements) \
  X(ReadPixels) \
  X(PixelStorei) \
  X(Finish) \
  X(GetError) \
  X(Hint) \
  X(GetString) \
  X(PolygonMode)
// clang-format on

struct GlApi {
// NOLINTNEXTLINE(bugprone-macro-parentheses): `name` is pasted into identifiers, not an expression
#define TORSION_GL_MEMBER(name) decltype(&::gl##name) name = nullptr;
  TORSION_GL_FUNCTIONS(TORSION_GL_MEMBER)
#undef TORSION_GL_MEMBER
};

using GlProcLoader = void* (*)(const char* name);

/// Fills `gl` from `load` (called with "glViewport", ...). Returns an empty string, or the names
/// of the entry points the context does not provide.
std::string loadGlApi(GlApi& gl, GlProcLoader load);

}  // namespace torsion::render
