#pragma once
// What Python holds for the parts of a world: the World object itself (so a body outlives no
// world) and a stable way to find the part again. Bodies, hands and rigid bodies live as long as
// their world and never move; node sets are found by index (their list grows).

#include <pybind11/pybind11.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <utility>

#include "py_world.h"

namespace torsion::python {

namespace py = pybind11;

/// Held while C++ touches a world from Python: a step running in another thread (without the
/// GIL) makes the call fail instead of racing it.
class WorldGuard {
 public:
  enum Access { kRead, kWrite };
  explicit WorldGuard(PyWorld& world, Access access = kRead)
      : lock_(world.busy(), std::try_to_lock) {
    if (!lock_.owns_lock())
      throw std::runtime_error(
          "the world is stepping in another thread; wait for step() to return");
    if (access == kWrite) world.touched();
  }

 private:
  std::unique_lock<std::mutex> lock_;
};

struct BodyHandle {
  py::object owner;  ///< the torsion.World
  PyWorld* world = nullptr;
  FemBody* body = nullptr;
};

struct NodeSetHandle {
  py::object owner;
  PyWorld* world = nullptr;
  size_t index = 0;  ///< into BuiltScene::node_sets
  const scene::NodeSetHandle& set() const { return world->scene().node_sets[index]; }
};

struct HandHandle {
  py::object owner;
  PyWorld* world = nullptr;
  Hand* hand = nullptr;
};

struct RigidHandle {
  py::object owner;
  PyWorld* world = nullptr;
  std::string name;
  btRigidBody* body = nullptr;
  std::uint64_t serial = 0;  ///< PyWorld::rigidSerial of the body when the handle was made

  RigidHandle(py::object owner_, PyWorld& world_, std::string name_, btRigidBody* body_)
      : owner(std::move(owner_)),
        world(&world_),
        name(std::move(name_)),
        body(body_),
        serial(world_.rigidSerial(body_)) {}
  /// The body, while it is in the world: ValueError once remove_rigid_body took it out (its
  /// address may be another body's by then, so it is never touched).
  btRigidBody& live() const {
    if (serial == 0 || world->rigidSerial(body) != serial)
      throw py::value_error("rigid body '" + name + "' was removed from its world");
    return *body;
  }
};

void bindTypes(py::module_& m);
void bindParts(py::module_& m);
void bindWorld(py::module_& m);
void bindViewer(py::module_& m);

}  // namespace torsion::python
