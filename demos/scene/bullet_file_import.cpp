#include "bullet_file_import.h"

#include <BulletWorldImporter/btBulletWorldImporter.h>

#include <filesystem>
#include <system_error>

namespace torsion::scene {

Result<std::shared_ptr<BulletFileImport>> BulletFileImport::load(const std::string& path,
                                                                 FemWorld& world) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    return Error{path + ": " + (error ? error.message() : "no such file")};
  }
  std::shared_ptr<BulletFileImport> import(new BulletFileImport());
  btSoftRigidDynamicsWorld& bullet = world.bulletWorld();
  const btVector3 gravity = bullet.getGravity();
  import->importer_ = std::make_unique<btBulletWorldImporter>(&bullet);
  import->importer_->setVerboseMode(0);
  if (!import->importer_->loadFile(path.c_str())) {
    return Error{path +
                 ": not a file Bullet's serializer wrote (.bullet), or of another "
                 "pointer size or precision Bullet cannot convert"};
  }
  bullet.setGravity(gravity);  // the scene's gravity, not the file's
  const std::string stem = std::filesystem::path(path).stem().string();
  for (int k = 0; k < import->importer_->getNumRigidBodies(); ++k) {
    btRigidBody* body = btRigidBody::upcast(import->importer_->getRigidBodyByIndex(k));
    if (body == nullptr) continue;
    body->setGravity(gravity);
    SceneRigidBody scene_body;
    const char* name = import->importer_->getNameForPointer(body);
    scene_body.name = name != nullptr && name[0] != '\0' ? name : stem + "_" + std::to_string(k);
    scene_body.body = body;
    scene_body.kinematic = body->isKinematicObject();
    world.trackRigidBody(body);
    import->bodies_.push_back(std::move(scene_body));
  }
  if (import->bodies_.empty()) return Error{path + ": holds no rigid body"};
  return import;
}

BulletFileImport::~BulletFileImport() {
  if (importer_) importer_->deleteAllData();  // removes the bodies from the world, then frees
}

}  // namespace torsion::scene
