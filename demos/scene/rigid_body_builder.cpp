#include "rigid_body_builder.h"

#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btTriangleMesh.h>
#include <btBulletDynamicsCommon.h>

#include "torsion/bt_conversions.h"

namespace torsion::scene {

namespace {

btTransform toTransform(const Frame& f) {
  btTransform t;
  t.setOrigin(toBt(f.origin));
  t.setRotation(toBt(f.rotation));
  return t;
}

// A BVH triangle mesh shape that owns its triangles (Bullet's shape only points to them).
class OwningTriangleMeshShape : public btBvhTriangleMeshShape {
 public:
  explicit OwningTriangleMeshShape(std::unique_ptr<btTriangleMesh> mesh)
      : btBvhTriangleMeshShape(mesh.get(), true), mesh_(std::move(mesh)) {}

 private:
  std::unique_ptr<btTriangleMesh> mesh_;
};

// Bullet reads a kinematic body's pose from its motion state once per step, before the step
// (saveKinematicState), and takes (that pose - the last) / dt as the body's velocity. So the
// state answers with the scripted pose at the end of the coming step, world.time() + dt; before
// it is armed (while the body is being set up) with the pose at t = 0.
class ScriptedMotionState : public btMotionState {
 public:
  ScriptedMotionState(RigidBodySpec spec, const FemWorld& world)
      : spec_(std::move(spec)), world_(world) {}
  void arm() { armed_ = true; }
  void getWorldTransform(btTransform& transform) const override {
    const double t = armed_ ? world_.time() + world_.settings().solver.time_step : 0.0;
    transform = toTransform(spec_.poseAt(t));
  }
  void setWorldTransform(const btTransform& /*transform*/) override {}  // Bullet never moves it

 private:
  RigidBodySpec spec_;
  const FemWorld& world_;
  bool armed_ = false;
};

}  // namespace

std::unique_ptr<btCollisionShape> makeRigidShape(const RigidBodySpec& r) {
  switch (r.shape) {
    case RigidBodySpec::Shape::kBox:
      return std::make_unique<btBoxShape>(toBt(r.half_extents));
    case RigidBodySpec::Shape::kSphere:
      return std::make_unique<btSphereShape>(toBtScalar(r.radius));
    case RigidBodySpec::Shape::kCapsule: {
      // Bullet's height is the distance between the cap centres.
      const btScalar radius = toBtScalar(r.radius), height = toBtScalar(2 * r.half_height);
      if (r.axis == 0) return std::make_unique<btCapsuleShapeX>(radius, height);
      if (r.axis == 1) return std::make_unique<btCapsuleShape>(radius, height);
      return std::make_unique<btCapsuleShapeZ>(radius, height);
    }
    case RigidBodySpec::Shape::kConvexHull: {
      auto hull = std::make_unique<btConvexHullShape>();
      for (const Eigen::Vector3d& p : r.points)
        hull->addPoint(toBt(p), false);
      hull->recalcLocalAabb();
      hull->setMargin(toBtScalar(r.margin));
      return hull;
    }
    case RigidBodySpec::Shape::kPlane:
      return std::make_unique<btStaticPlaneShape>(toBt(r.plane_normal), toBtScalar(r.plane_offset));
    case RigidBodySpec::Shape::kTriangleMesh: {
      auto mesh = std::make_unique<btTriangleMesh>();
      for (const auto& t : r.triangles) {
        mesh->addTriangle(toBt(r.points[static_cast<size_t>(t[0])]),
                          toBt(r.points[static_cast<size_t>(t[1])]),
                          toBt(r.points[static_cast<size_t>(t[2])]));
      }
      return std::make_unique<OwningTriangleMeshShape>(std::move(mesh));
    }
  }
  return nullptr;
}

SceneRigidBody addSceneRigidBody(FemWorld& world, const RigidBodySpec& spec) {
  SceneRigidBody added;
  added.name = spec.name;
  added.kinematic = spec.isKinematic();
  btRigidBody* body = world.addRigidBody(makeRigidShape(spec), spec.mass, toTransform(spec.pose));
  body->setFriction(toBtScalar(spec.friction));
  body->setRestitution(toBtScalar(spec.restitution));
  if (spec.mass > 0) {
    body->setLinearVelocity(toBt(spec.linear_velocity));
    body->setAngularVelocity(toBt(spec.angular_velocity));
  }
  if (added.kinematic) {
    // Bullet's recipe: mass 0 (CF_STATIC_OBJECT) plus CF_KINEMATIC_OBJECT, never asleep.
    body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    body->setActivationState(DISABLE_DEACTIVATION);
    auto script = std::make_unique<ScriptedMotionState>(spec, world);
    body->setMotionState(script.get());
    script->arm();
    added.script = std::move(script);
  }
  added.body = body;
  if (spec.grasper) {
    // The jaws hang below the palm's bottom face, open: their inner faces `opening` apart.
    const GrasperSpec& g = *spec.grasper;
    const double x = 0.5 * g.settings.opening + g.jaw_half_extents.x();
    const double z = -(spec.half_extents.z() + g.jaw_half_extents.z());
    for (int side : {0, 1}) {
      Frame pose = spec.pose;
      pose.origin = spec.pose.toWorld(Eigen::Vector3d(side == 0 ? -x : x, 0, z));
      auto shape = std::make_unique<btBoxShape>(toBt(g.jaw_half_extents));
      btRigidBody* jaw = world.addRigidBody(std::move(shape), g.jaw_mass, toTransform(pose));
      jaw->setFriction(toBtScalar(g.jaw_friction));
      added.jaws[static_cast<size_t>(side)] = jaw;
    }
  }
  return added;
}

}  // namespace torsion::scene
