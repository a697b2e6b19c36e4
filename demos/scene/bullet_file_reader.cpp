#include "bullet_file_reader.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btStridingMeshInterface.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <BulletWorldImporter/btBulletWorldImporter.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

namespace torsion::scene {

namespace {

using nlohmann::json;

// Thrown while one body is described; the message names the body.
struct BodyFault {
  std::string message;
};

json vec(const btVector3& v) {
  return json::array(
      {static_cast<double>(v.x()), static_cast<double>(v.y()), static_cast<double>(v.z())});
}

// Every number in `value` finite (the scene parser would read JSON's null for NaN as a wrong
// type, which says less).
void checkFinite(const json& value, const std::string& where) {
  if (value.is_number_float() && !std::isfinite(value.get<double>()))
    throw BodyFault{where + " is not finite (NaN or infinity)"};
  if (value.is_structured()) {
    for (auto it = value.begin(); it != value.end(); ++it)
      checkFinite(*it, value.is_object() ? where + "." + it.key() : where);
  }
}

// The pose of a body: its basis must be a rotation. A file whose header's precision flag or
// pointer size does not match its data is read by Bullet as zeros or garbage, not refused.
json pose(const btTransform& t) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      r(i, j) = static_cast<double>(t.getBasis()[i][j]);
  }
  if (!r.allFinite() ||
      !((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-4) ||
      !(r.determinant() > 0)) {
    throw BodyFault{
        "its orientation is not a rotation (the file's data do not match its header: precision "
        "or pointer size)"};
  }
  // The scene's form of a rotation (readPose): an axis and an angle, none for the identity.
  const Eigen::AngleAxisd rotation{Eigen::Quaterniond(r).normalized()};
  json out{{"position", vec(t.getOrigin())}};
  if (rotation.angle() > 0) {
    const Eigen::Vector3d& a = rotation.axis();
    out["axis_angle"] = {{"axis", json::array({a.x(), a.y(), a.z()})}, {"angle", rotation.angle()}};
  }
  return out;
}

json scaledPoints(const btVector3* points, int count, const btVector3& scale) {
  json out = json::array();
  for (int i = 0; i < count; ++i)
    out.push_back(vec(points[i] * scale));
  return out;
}

// A BVH triangle mesh: its vertices (scaled) and triangles, over all its parts.
json triangleMesh(const btBvhTriangleMeshShape& shape) {
  const btStridingMeshInterface& mesh = *shape.getMeshInterface();
  const btVector3 scale = mesh.getScaling() * shape.getLocalScaling();
  json vertices = json::array(), triangles = json::array();
  for (int part = 0; part < mesh.getNumSubParts(); ++part) {
    const unsigned char* vertex_base = nullptr;
    const unsigned char* index_base = nullptr;
    int vertex_count = 0, vertex_stride = 0, index_stride = 0, face_count = 0;
    PHY_ScalarType vertex_type = PHY_FLOAT, index_type = PHY_INTEGER;
    mesh.getLockedReadOnlyVertexIndexBase(&vertex_base, vertex_count, vertex_type, vertex_stride,
                                          &index_base, index_stride, face_count, index_type, part);
    const auto offset = static_cast<long long>(vertices.size());
    for (int v = 0; v < vertex_count; ++v) {
      const unsigned char* p = vertex_base + static_cast<std::ptrdiff_t>(v) * vertex_stride;
      btVector3 x;
      if (vertex_type == PHY_DOUBLE) {
        const auto* d = reinterpret_cast<const double*>(p);
        x.setValue(btScalar(d[0]), btScalar(d[1]), btScalar(d[2]));
      } else {
        const auto* f = reinterpret_cast<const float*>(p);
        x.setValue(btScalar(f[0]), btScalar(f[1]), btScalar(f[2]));
      }
      vertices.push_back(vec(x * scale));
    }
    for (int t = 0; t < face_count; ++t) {
      const unsigned char* p = index_base + static_cast<std::ptrdiff_t>(t) * index_stride;
      json triangle = json::array();
      for (int k = 0; k < 3; ++k) {
        long long index = 0;
        if (index_type == PHY_SHORT)
          index = reinterpret_cast<const unsigned short*>(p)[k];
        else if (index_type == PHY_UCHAR)
          index = p[k];
        else
          index = reinterpret_cast<const unsigned int*>(p)[k];
        triangle.push_back(offset + index);
      }
      triangles.push_back(std::move(triangle));
    }
    mesh.unLockReadOnlyVertexBase(part);
  }
  return json{{"vertices", std::move(vertices)}, {"triangles", std::move(triangles)}};
}

json shapeOf(const btCollisionShape& shape) {
  switch (shape.getShapeType()) {
    case BOX_SHAPE_PROXYTYPE:
      return json{{"box",
                   {{"half_extents",
                     vec(static_cast<const btBoxShape&>(shape).getHalfExtentsWithMargin())}}}};
    case SPHERE_SHAPE_PROXYTYPE:
      return json{{"sphere",
                   {{"radius",
                     static_cast<double>(static_cast<const btSphereShape&>(shape).getRadius())}}}};
    case CAPSULE_SHAPE_PROXYTYPE: {
      const auto& capsule = static_cast<const btCapsuleShape&>(shape);
      const int axis = capsule.getUpAxis();
      return json{{"capsule",
                   {{"radius", static_cast<double>(capsule.getRadius())},
                    {"half_height", static_cast<double>(capsule.getHalfHeight())},
                    {"axis", std::string(1, static_cast<char>(
                                                'x' + (axis >= 0 && axis < 3 ? axis : 2)))}}}};
    }
    case CONVEX_HULL_SHAPE_PROXYTYPE: {
      const auto& hull = static_cast<const btConvexHullShape&>(shape);
      return json{{"convex_hull",
                   {{"points", scaledPoints(hull.getUnscaledPoints(), hull.getNumPoints(),
                                            hull.getLocalScaling())},
                    {"margin", static_cast<double>(hull.getMargin())}}}};
    }
    case STATIC_PLANE_PROXYTYPE: {
      const auto& plane = static_cast<const btStaticPlaneShape&>(shape);
      if (!(plane.getLocalScaling() - btVector3(1, 1, 1)).fuzzyZero())
        throw BodyFault{"its plane is scaled, which a scene's plane cannot be"};
      return json{{"plane",
                   {{"normal", vec(plane.getPlaneNormal())},
                    {"offset", static_cast<double>(plane.getPlaneConstant())}}}};
    }
    case TRIANGLE_MESH_SHAPE_PROXYTYPE:
      return json{
          {"triangle_mesh", triangleMesh(static_cast<const btBvhTriangleMeshShape&>(shape))}};
    default:
      throw BodyFault{std::string("its shape is a ") + shape.getName() +
                      ", which is not imported (box, sphere, capsule, convex hull, static plane "
                      "and BVH triangle mesh are)"};
  }
}

json describe(const btRigidBody& body, const std::string& name) {
  const btCollisionShape* shape = body.getCollisionShape();
  if (shape == nullptr) throw BodyFault{"it has no collision shape"};
  json out{{"name", name}, {"shape", shapeOf(*shape)}, {"pose", pose(body.getWorldTransform())}};
  // A kinematic body without the scene's motions would stay where it is: static.
  const bool dynamic = !body.isStaticOrKinematicObject() && body.getInvMass() > 0;
  out["mass"] = dynamic ? 1.0 / static_cast<double>(body.getInvMass()) : 0.0;
  if (dynamic) {
    out["linear_velocity"] = vec(body.getLinearVelocity());
    out["angular_velocity"] = vec(body.getAngularVelocity());
  }
  out["friction"] = static_cast<double>(body.getFriction());
  out["restitution"] = static_cast<double>(body.getRestitution());
  checkFinite(out, "its description");
  return out;
}

}  // namespace

Result<std::string> bulletFileBodiesJson(const std::string& path) {
  btBulletWorldImporter importer(nullptr);  // into no world: only the objects are wanted
  importer.setVerboseMode(0);
  if (!importer.loadFile(path.c_str())) {
    return Error{
        "not a file Bullet's serializer wrote (.bullet), or of another pointer size or precision "
        "Bullet cannot convert"};
  }
  if (importer.getNumConstraints() > 0) {
    return Error{"holds " + std::to_string(importer.getNumConstraints()) +
                 " constraint(s) between its bodies, which a scene does not import (rigid bodies "
                 "only; a program of your own can load them with btBulletWorldImporter, "
                 "examples/bullet_import.cpp)"};
  }
  const std::string stem = std::filesystem::path(path).stem().string();
  json bodies = json::array();
  for (int k = 0; k < importer.getNumRigidBodies(); ++k) {
    const btRigidBody* body = btRigidBody::upcast(importer.getRigidBodyByIndex(k));
    if (body == nullptr) continue;
    const char* name = importer.getNameForPointer(body);
    const std::string named =
        name != nullptr && name[0] != '\0' ? std::string(name) : stem + "_" + std::to_string(k);
    try {
      bodies.push_back(describe(*body, named));
    } catch (const BodyFault& fault) {
      return Error{"rigid body " + std::to_string(k) + " (" +
                   json(named).dump(-1, ' ', true, json::error_handler_t::replace) +
                   "): " + fault.message};
    }
  }
  if (bodies.empty()) return Error{"holds no rigid body"};
  // Names may be any bytes: replaced where they are not UTF-8, then refused by the scene parser's
  // name check with the rest of its rules.
  return json{{"rigid_bodies", std::move(bodies)}}.dump(-1, ' ', false,
                                                        json::error_handler_t::replace);
}

}  // namespace torsion::scene
