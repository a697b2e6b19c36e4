#include "run_provenance.h"

#include <LinearMath/btScalar.h>

#include <cstdint>
#include <cstdio>

#include "build_info.h"
#include "torsion/fnv1a.h"

namespace torsion::scene {

void addProvenance(nlohmann::json& summary) {
  summary["schema_version"] = kSummarySchemaVersion;
  summary["torsion_version"] = torsionVersion();
  summary["git_commit"] = torsionGitCommit();
  summary["bullet_precision"] = sizeof(btScalar) == 8 ? "double" : "float";
}

std::string finalStateHash(const BuiltScene& scene,
                           const std::vector<Eigen::VectorXd>& final_positions) {
  Fnv1a fnv;
  for (size_t b = 0; b < final_positions.size(); ++b) {
    // In the numbering of the body's mesh file, as in <body>.vtk.
    const Eigen::VectorXd x =
        scene.world->bodies()[b]->inputNumbering().nodesToInput(final_positions[b]);
    fnv.add(x.data(), sizeof(double) * static_cast<size_t>(x.size()));
  }
  for (const SceneRigidBody& r : scene.rigid_bodies) {
    const btTransform& t = r.body->getCenterOfMassTransform();
    const btQuaternion q = t.getRotation();
    for (int a = 0; a < 3; ++a)
      fnv.add(static_cast<double>(t.getOrigin()[a]));
    for (const btScalar c : {q.x(), q.y(), q.z(), q.w()})
      fnv.add(static_cast<double>(c));
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv.value()));
  return hex;
}

}  // namespace torsion::scene
