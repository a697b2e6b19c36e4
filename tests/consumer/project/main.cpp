// Links the installed Torsion package: reads a mesh, uses a device type, and checks that Bullet
// arrives in the precision the package announced (TORSION_BULLET_PRECISION) through the exported
// target, headers and library alike.
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <LinearMath/btScalar.h>

#include <cmath>
#include <cstdio>

#include "torsion/device/wrench_safety.h"
#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/mesh/tetgen_format.h"

static_assert(sizeof(btScalar) == EXPECTED_BT_SCALAR_BYTES,
              "Torsion::extension must forward the Bullet precision the package announces");

int main() {
  const char* node = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
  const char* ele = "1 4 0\n0 0 1 2 3\n";
  torsion::Result<torsion::RawTetMesh> raw = torsion::parseTetGen(node, "t.node", ele, "t.ele");
  if (!raw) return std::printf("%s\n", raw.error().message.c_str()), 1;
  torsion::Result<torsion::LoadedMesh> mesh = torsion::buildTetMesh(std::move(raw).value());
  if (!mesh || mesh.value().mesh.surfaceTriangleCount() != 4) return std::printf("bad mesh\n"), 1;
  torsion::device::DeviceLimits limits;
  limits.max_force = 1;
  const torsion::device::Wrench w = torsion::device::saturate({{3, 4, 0}, {}}, limits);
  if (std::abs(w.force.x - 0.6) > 1e-12) return std::printf("bad saturation\n"), 1;
  // The box is built by the linked Bullet library and read back by the inline header: a library
  // of the other precision would garble it.
  const btBoxShape box(btVector3(btScalar(0.5), btScalar(0.25), btScalar(0.125)));
  const btVector3 h = box.getHalfExtentsWithMargin();
  if (h.x() != btScalar(0.5) || h.y() != btScalar(0.25) || h.z() != btScalar(0.125))
    return std::printf("the linked Bullet library is not %s precision\n", PACKAGE_PRECISION), 1;
  std::printf("consumer OK: %d tets, btScalar is %zu bytes (%s Bullet)\n",
              mesh.value().mesh.tetCount(), sizeof(btScalar), PACKAGE_PRECISION);
  return 0;
}
