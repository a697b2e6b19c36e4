#pragma once
// A scene's "bullet_file": rigid bodies (shapes, masses, poses, velocities, friction) and their
// constraints from a file Bullet wrote with its serializer (btDiscreteDynamicsWorld::serialize),
// loaded by Bullet's own btBulletWorldImporter into the scene's world, beside its FEM bodies.

#include <memory>
#include <string>
#include <vector>

#include "rigid_body_builder.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/result.h"

class btBulletWorldImporter;

namespace torsion::scene {

class BulletFileImport {
 public:
  /// Loads `path` into `world`. The scene's gravity stays the world's (a .bullet file carries
  /// its own, which the importer would impose). The bodies are named after their names in the
  /// file, else "<file stem>_<index>". Errors: the file is missing, not a .bullet file, or holds
  /// no rigid body.
  static Result<std::shared_ptr<BulletFileImport>> load(const std::string& path, FemWorld& world);
  ~BulletFileImport();
  BulletFileImport(const BulletFileImport&) = delete;
  BulletFileImport& operator=(const BulletFileImport&) = delete;

  /// The imported rigid bodies (static ones too), in file order, named.
  std::vector<SceneRigidBody>& bodies() { return bodies_; }

 private:
  BulletFileImport() = default;
  std::unique_ptr<btBulletWorldImporter> importer_;
  std::vector<SceneRigidBody> bodies_;
};

}  // namespace torsion::scene
