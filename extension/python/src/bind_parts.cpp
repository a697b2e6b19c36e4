// torsion.Body, NodeSet, Hand and RigidBody: handles onto the parts of a world.
#include <pybind11/stl.h>

#include "frame_data.h"
#include "handles.h"
#include "py_convert.h"
#include "py_numbering.h"
#include "py_rigid.h"
#include "torsion/fem/corotated_element.h"
#include "torsion/format_number.h"
#include "torsion/haptics/patch_stiffness.h"

namespace torsion::python {

namespace {

// Per tet: the corotated small strain R^T F sym - I (the renderer's and tetVonMises' measure).
std::vector<Eigen::Matrix3d> tetStrains(const FemBody& body) {
  const FemModel& model = body.model();
  const TetMesh& mesh = model.mesh();
  const FemState& state = body.state();
  std::vector<Eigen::Matrix3d> strains(static_cast<size_t>(mesh.tetCount()));
  for (int t = 0; t < mesh.tetCount(); ++t) {
    const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
    std::array<Eigen::Vector3d, 4> x;
    for (size_t a = 0; a < 4; ++a)
      x[a] = state.position(tet[a]);
    const Eigen::Matrix3d F =
        deformationGradient(x, model.tetRestData()[static_cast<size_t>(t)].rest_shape_inverse);
    const size_t element = static_cast<size_t>(model.elementOfTet(t));
    const Eigen::Matrix3d R = element < state.element_rotations.size()
                                  ? state.element_rotations[element].toRotationMatrix()
                                  : Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d RtF = R.transpose() * F;
    strains[static_cast<size_t>(t)] = 0.5 * (RtF + RtF.transpose()) - Eigen::Matrix3d::Identity();
  }
  return strains;
}

py::array_t<double> rigidPose(const btRigidBody& body, bool rotation) {
  const btTransform& t = body.getCenterOfMassTransform();
  if (rotation) {
    const btQuaternion q = t.getRotation();
    const double xyzw[4] = {static_cast<double>(q.x()), static_cast<double>(q.y()),
                            static_cast<double>(q.z()), static_cast<double>(q.w())};
    return vectorArray(xyzw, 4);
  }
  const double p[3] = {static_cast<double>(t.getOrigin().x()),
                       static_cast<double>(t.getOrigin().y()),
                       static_cast<double>(t.getOrigin().z())};
  return vectorArray(p, 3);
}

std::string who(const RigidHandle& r, const char* call) {
  return std::string(call) + " '" + r.name + "'";
}

// A pose given as position and quaternion, each checked with the call and body in its message.
Frame rigidFrame(const RigidHandle& r, const char* call, py::handle position,
                 py::handle quaternion) {
  Frame frame;
  frame.origin = toVector3(position, (who(r, call) + ": position").c_str());
  frame.rotation = toQuaternion(quaternion, (who(r, call) + ": quaternion").c_str());
  return frame;
}

py::array_t<double> btArray(const btVector3& v) {
  const double p[3] = {static_cast<double>(v.x()), static_cast<double>(v.y()),
                       static_cast<double>(v.z())};
  return vectorArray(p, 3);
}

}  // namespace

void bindParts(py::module_& m) {
  using B = BodyHandle;
  py::class_<BodyHandle>(m, "Body", "An FEM body of a world (alive as long as the world).")
      .def_property_readonly("name", [](const B& b) { return b.body->name(); })
      .def_property_readonly("node_count", [](const B& b) { return b.body->model().nodeCount(); })
      .def_property_readonly("element_count",
                             [](const B& b) { return b.body->model().elementCount(); })
      .def_property_readonly("element",
                             [](const B& b) {
                               return b.body->model().elementKind() == ElementKind::kTet10 ? "tet10"
                                                                                           : "tet4";
                             })
      .def_property_readonly(
          "positions",
          [](const B& b) {
            return readOnlyView(b.body->inputPositions().data(), b.body->model().nodeCount(), 3,
                                b.owner);
          },
          "(n, 3) float64, m. A read-only view of the solver's storage: it changes as the world "
          "steps (copy it to keep a moment).")
      .def_property_readonly(
          "velocities",
          [](const B& b) {
            return readOnlyView(b.body->inputVelocities().data(), b.body->model().nodeCount(), 3,
                                b.owner);
          },
          "(n, 3) float64, m/s. A read-only view that changes as the world steps.")
      .def_property_readonly(
          "rest_positions",
          [](const B& b) {
            const auto& rest = b.body->inputMesh().restPositions();
            return readOnlyView(rest.front().data(), static_cast<py::ssize_t>(rest.size()), 3,
                                b.owner);
          },
          "(n, 3) float64, m. A read-only view (the rest shape never changes).")
      .def_property_readonly(
          "masses",
          [](const B& b) {
            const auto& masses = b.body->model().nodeMasses();
            const Eigen::VectorXd input = b.body->inputNumbering().nodesToInput(
                Eigen::Map<const Eigen::VectorXd>(masses.data(),
                                                  static_cast<Eigen::Index>(masses.size())),
                1);
            return copyArray(input.data(), input.size(), 1).attr("reshape")(-1);
          },
          "(n,) float64, kg: lumped node masses (a copy).")
      .def_property_readonly(
          "tets", [](const B& b) { return inputElementArray(*b.body); },
          "(m, 4) or (m, 10) int32: the elements' nodes (tet10: 4 corners then 6 mid-edge "
          "nodes). Read-only.")
      .def_property_readonly(
          "surface_triangles",
          [](const B& b) {
            const auto& tris = b.body->inputMesh().surfaceTriangles();
            return readOnlyView(tris.front().data(), static_cast<py::ssize_t>(tris.size()), 3,
                                b.owner);
          },
          "(k, 3) int32, counter-clockwise seen from outside. A read-only view.")
      .def_property_readonly(
          "renumbered", [](const B& b) { return !b.body->inputNumbering().identity(); },
          "Whether the body numbers its nodes inside otherwise than its mesh, for speed "
          "(add_body's node_order): every array and node list here is in the mesh's numbers "
          "either way.")
      .def_property_readonly("material", [](const B& b) { return b.body->model().material(); })
      .def(
          "set_material",
          [](const B& b, const Material& material) {
            WorldGuard guard(*b.world, WorldGuard::kWrite);
            if (Status s = b.body->setMaterial(material); !s)
              throw py::value_error(s.error().message);
            for (Hand* hand : b.world->hands()) {
              if (&hand->body() == b.body) hand->updateSpeedLimit();
            }
          },
          py::arg("material"), "Live edit: the body goes on from its current state.")
      .def_property_readonly(
          "external_forces",
          [](const B& b) {
            const Eigen::VectorXd f =
                b.body->inputNumbering().nodesToInput(b.body->externalForces());
            return copyArray(f.data(), b.body->model().nodeCount(), 3);
          },
          "(n, 3) float64, N: forces besides gravity (a copy).")
      .def(
          "set_external_forces",
          [](const B& b, py::object forces) {
            const Eigen::VectorXd f = b.body->inputNumbering().nodesToBody(
                toNodeVectors(forces, b.body->model().nodeCount(), "forces"));
            WorldGuard guard(*b.world, WorldGuard::kWrite);
            if (Status s = b.body->setExternalForces(f); !s)
              throw py::value_error(s.error().message);
          },
          py::arg("forces"), "(n, 3) N per node, applied every step until changed.")
      .def(
          "set_velocity",
          [](const B& b, py::object velocity) {
            WorldGuard guard(*b.world, WorldGuard::kWrite);
            if (Status s = b.body->setVelocity(toVector3(velocity, "velocity")); !s)
              throw py::value_error(s.error().message);
          },
          py::arg("velocity"), "Every node's velocity, m/s.")
      .def(
          "anchor",
          [](const B& b, py::object nodes, const RigidHandle& rigid) {
            IndexArray a = toIndexArray(nodes, "nodes");
            if (a.shape.size() != 1) throw py::value_error("nodes: expected a 1-D int array");
            if (rigid.world != b.world)
              throw py::value_error("rigid_body: '" + rigid.name + "' is another world's");
            WorldGuard guard(*b.world, WorldGuard::kWrite);
            std::vector<int> body_nodes = bodyNodes(
                *b.body, std::move(a.values), "body '" + b.body->name() + "': anchor: ", true);
            Result<int> anchor = b.body->anchorNodes(std::move(body_nodes), &rigid.live());
            if (!anchor) throw py::value_error(anchor.error().message);
            return anchor.value();
          },
          py::arg("nodes"), py::arg("rigid_body"),
          "Ties the nodes to the rigid body at their current offsets from it (PyBullet's "
          "createSoftBodyAnchor): they move with it and the body pulls on it, both ways, in the "
          "contact solve. Returns the anchor's id for remove_anchor. ValueError, nothing changed: "
          "no nodes, a node out of range, anchored already or listed twice.")
      .def(
          "remove_anchor",
          [](const B& b, int anchor) {
            WorldGuard guard(*b.world, WorldGuard::kWrite);
            if (Status s = b.body->removeAnchor(anchor); !s)
              throw py::value_error(s.error().message);
          },
          py::arg("anchor"), "Frees an anchor's nodes from the next step on.")
      .def(
          "enable_self_contact",
          [](const B& b, double friction, double gap_tolerance, double thickness_factor,
             double margin) {
            SelfContactSettings settings;
            settings.friction = friction;
            settings.gap_tolerance = gap_tolerance;
            settings.thickness_factor = thickness_factor;
            settings.margin = margin;
            WorldGuard guard(*b.world, WorldGuard::kWrite);
            if (Status s = b.body->enableSelfContact(settings); !s)
              throw py::value_error(s.error().message);
          },
          py::kw_only(), py::arg("friction") = SelfContactSettings{}.friction,
          py::arg("gap_tolerance") = SelfContactSettings{}.gap_tolerance,
          py::arg("thickness_factor") = SelfContactSettings{}.thickness_factor,
          py::arg("margin") = SelfContactSettings{}.margin,
          "Contact of the body's surface with itself from the next step on (docs/contact.md, "
          "\"Self-contact\"): friction (Coulomb), gap_tolerance (m; 0: 1e-3 of the mean surface "
          "edge), thickness_factor (the gap aimed at, in gap tolerances), margin (the candidate "
          "search's reach, in mean surface edges). ValueError, nothing changed, on a bad value.")
      .def(
          "disable_self_contact",
          [](const B& b) {
            WorldGuard guard(*b.world, WorldGuard::kWrite);
            b.body->disableSelfContact();
          },
          "No self-contact from the next step on.")
      .def_property_readonly(
          "self_contact", [](const B& b) { return b.body->selfContact() != nullptr; },
          "Whether the body's surface touches itself (enable_self_contact).")
      .def(
          "von_mises_stress",
          [](const B& b) {
            WorldGuard guard(*b.world);
            std::vector<double> s =
                b.body->inputNumbering().tetsToInput(render::tetVonMises(*b.body));
            return vectorArray(s.data(), static_cast<py::ssize_t>(s.size()));
          },
          "Per tet of the simulation mesh (tet10: 8 sub-tets per element), Pa: von Mises stress "
          "of the corotated linear strain.")
      .def(
          "von_mises_strain",
          [](const B& b) {
            WorldGuard guard(*b.world);
            std::vector<Eigen::Matrix3d> eps = tetStrains(*b.body);
            std::vector<double> out;
            out.reserve(eps.size());
            for (const Eigen::Matrix3d& e : eps) {
              const Eigen::Matrix3d dev = e - e.trace() / 3 * Eigen::Matrix3d::Identity();
              out.push_back(std::sqrt(2.0 / 3.0 * dev.squaredNorm()));
            }
            out = b.body->inputNumbering().tetsToInput(out);
            return vectorArray(out.data(), static_cast<py::ssize_t>(out.size()));
          },
          "Per tet, dimensionless: equivalent strain sqrt(2/3 dev(eps):dev(eps)).")
      .def_property_readonly(
          "kinetic_energy", [](const B& b) { return b.body->lastReport().kinetic_energy; },
          "J, at the end of the last step")
      .def_property_readonly(
          "solver_iterations", [](const B& b) { return b.body->lastReport().solve.iterations; },
          "CG iterations of the last step")
      .def_property_readonly(
          "newton_iterations", [](const B& b) { return b.body->lastReport().newton.iterations; },
          "Newton iterations (linear solves) of the last step: 0 for corotated bodies, whose step "
          "is one linear solve")
      .def("__repr__", [](const B& b) {
        return "<torsion.Body '" + b.body->name() +
               "': " + std::to_string(b.body->model().nodeCount()) + " nodes>";
      });

  using N = NodeSetHandle;
  py::class_<NodeSetHandle>(m, "NodeSet", "Nodes of a body held in place (or carried by a script).")
      .def_property_readonly("name", [](const N& s) { return s.set().name; })
      .def_property_readonly("body",
                             [](const N& s) {
                               return BodyHandle{s.owner, s.world, s.set().body};
                             })
      .def_property_readonly(
          "nodes",
          [](const N& s) {
            const FemBody& body = *s.set().body;
            return inputNodeArray(body, body.groups()[static_cast<size_t>(s.set().group)]->nodes());
          },
          "(k,) int32, ascending (a copy)")
      .def_property_readonly(
          "wrench",
          [](const N& s) {
            WorldGuard guard(*s.world);
            const scene::NodeSetHandle& set = s.set();
            return wrenchArray(set.body->groupWrench(set.group, set.wrench_about));
          },
          "(6,) [fx, fy, fz, tx, ty, tz]: N and N m the body exerted on the set in the last step, "
          "torque about the set's wrench_about point.")
      .def(
          "release",
          [](const N& s) {
            WorldGuard guard(*s.world, WorldGuard::kWrite);
            s.set().body->releaseGroup(s.set().group);
          },
          "Frees the nodes from the next step on (the wrench then reads zero).")
      .def(
          "move_to",
          [](const N& s, py::object frame) {
            const Frame f = toFrame(frame, ("move_to: node set '" + s.set().name + "'").c_str());
            WorldGuard guard(*s.world, WorldGuard::kWrite);
            if (Status moved = s.world->moveNodeSet(s.index, f); !moved)
              throw py::value_error(moved.error().message);
          },
          py::arg("frame"),
          "Drives the set as MuJoCo drives a mocap body: its frame (which starts at its "
          "wrench_about point with the world's axes) reaches `frame` (a Frame or a 4x4 matrix) at "
          "the end of the next step and stays there until the next call; the nodes are carried "
          "rigidly with it. ValueError, nothing changed: a released set, a set its scene file "
          "moves, a position beyond 1e6 m.")
      .def_property_readonly(
          "frame",
          [](const N& s) {
            WorldGuard guard(*s.world);
            return s.world->nodeSetFrame(s.index);
          },
          "Where the set's frame is at the end of the next step: where it started (its "
          "wrench_about point, the world's axes) while held, the last move_to, or its scene "
          "file's motion.")
      .def_property_readonly(
          "scripted", [](const N& s) { return s.world->nodeSetScripted(s.index); },
          "True for a set its scene file moves (a motion): move_to refuses it");

  using H = HandHandle;
  py::class_<HandHandle>(m, "Hand", "A hand plane acting on one body (docs/hand-plane.md).")
      .def_property_readonly("name", [](const H& h) { return h.hand->name(); })
      .def_property_readonly("body",
                             [](const H& h) {
                               return BodyHandle{h.owner, h.world, &h.hand->body()};
                             })
      .def_property_readonly("grabbed", [](const H& h) { return h.hand->grabbed(); })
      .def_property_readonly(
          "scripted", [](const H& h) { return h.world->handSpec(*h.hand) != nullptr; },
          "True for a scene's hand (its script or device moves it at each step)")
      .def(
          "grab",
          [](const H& h, py::object frame) {
            const Frame f = toFrame(frame, "grab");
            WorldGuard guard(*h.world, WorldGuard::kWrite);
            Result<int> n = h.hand->grab(f, h.world->world().time());
            if (!n) throw py::value_error("hand '" + h.hand->name() + "': " + n.error().message);
            return n.value();
          },
          py::arg("frame"),
          "Grabs the patch the frame's plane (normal k) cuts where the ray from its origin along i "
          "hits; returns the number of grabbed nodes. ValueError when it misses.")
      .def(
          "move_to",
          [](const H& h, py::object frame) {
            const Frame f = toFrame(frame, "move_to");
            WorldGuard guard(*h.world, WorldGuard::kWrite);
            if (Status moved = h.hand->moveTo(f); !moved)
              throw py::value_error(moved.error().message);
          },
          py::arg("frame"), "The goal frame the grabbed patch pursues from the next step on.")
      .def("release",
           [](const H& h) {
             WorldGuard guard(*h.world, WorldGuard::kWrite);
             h.hand->release();
           })
      .def_property_readonly("goal", [](const H& h) { return h.hand->goal(); })
      .def_property_readonly(
          "frame", [](const H& h) { return h.hand->frame(); },
          "The frame carrying the grabbed nodes in the last step.")
      .def_property_readonly(
          "wrench",
          [](const H& h) {
            WorldGuard guard(*h.world);
            return wrenchArray(h.hand->wrench());
          },
          "(6,) [fx, fy, fz, tx, ty, tz]: N and N m the body exerted on the grabbed patch in the "
          "last step, torque about the patch frame's origin; zeros when not grabbing.")
      .def_property_readonly(
          "grabbed_nodes",
          [](const H& h) { return inputNodeArray(h.hand->body(), h.hand->grabbedNodes()); })
      .def_property_readonly(
          "speed_limit", [](const H& h) { return h.hand->speedLimit(); },
          "m/s, grabbed nodes' speed bound (inf when off)")
      .def(
          "stiffness",
          [](const H& h, double tolerance) {
            if (!(tolerance > 0 && tolerance < 1))
              throw py::value_error("stiffness: tolerance must be in (0, 1), got " +
                                    formatNumber(tolerance));
            if (!h.hand->grabbed())
              throw py::value_error("hand '" + h.hand->name() + "': not grabbing");
            WorldGuard guard(*h.world, WorldGuard::kWrite);
            haptics::PatchStiffness k;
            const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> K =
                k.compute(h.hand->body(), h.hand->group(), h.hand->frame().origin, tolerance);
            return copyArray(K.data(), 6, 6);
          },
          py::arg("tolerance") = 1e-6,
          "(6, 6) K_h: dW/dpose of the patch about its origin over the next step (N/m, N, N m/rad; "
          "rows/columns [translation, rotation]). Six CG solves.");

  using R = RigidHandle;
  py::class_<RigidHandle>(m, "RigidBody",
                          "A Bullet rigid body of the world. Once World.remove_rigid_body took "
                          "it out, everything but its name raises ValueError.")
      .def_property_readonly("name", [](const R& r) { return r.name; })
      .def_property_readonly(
          "position", [](const R& r) { return rigidPose(r.live(), false); },
          "(3,) centre of mass, m")
      .def_property_readonly(
          "quaternion", [](const R& r) { return rigidPose(r.live(), true); },
          "(4,) orientation (x, y, z, w)")
      .def_property_readonly(
          "linear_velocity", [](const R& r) { return btArray(r.live().getLinearVelocity()); },
          "(3,) m/s")
      .def_property_readonly(
          "angular_velocity", [](const R& r) { return btArray(r.live().getAngularVelocity()); },
          "(3,) rad/s")
      .def_property_readonly(
          "mass",
          [](const R& r) {
            const double inverse = static_cast<double>(r.live().getInvMass());
            return inverse > 0 ? 1 / inverse : 0.0;
          },
          "kg (0: static or kinematic)")
      .def_property_readonly(
          "kind", [](const R& r) { return rigidKindName(rigidKind(*r.world, r.live())); },
          "\"dynamic\" (mass > 0), \"static\" (mass 0) or \"kinematic\" (following its scene "
          "file's script, or the targets of set_kinematic_target)")
      .def(
          "set_pose",
          [](const R& r, py::object position, py::object quaternion) {
            const Frame pose = rigidFrame(r, "set_pose", position, quaternion);
            WorldGuard guard(*r.world, WorldGuard::kWrite);
            if (Status s = setRigidPose(*r.world, r.name, r.live(), pose); !s)
              throw py::value_error(s.error().message);
          },
          py::arg("position"), py::arg("quaternion") = py::make_tuple(0.0, 0.0, 0.0, 1.0),
          "Moves the body now: its centre of mass to position (3,) m, its orientation to "
          "quaternion (4,) (x, y, z, w; normalised), velocities kept. A kinematic body stays "
          "there. Not for a body its scene file scripts.")
      .def(
          "set_velocity",
          [](const R& r, py::object linear, py::object angular) {
            if (linear.is_none() && angular.is_none())
              throw py::value_error(who(r, "set_velocity") + ": give linear, angular or both");
            std::optional<Eigen::Vector3d> v, w;
            if (!linear.is_none())
              v = toVector3(linear, (who(r, "set_velocity") + ": linear").c_str());
            if (!angular.is_none())
              w = toVector3(angular, (who(r, "set_velocity") + ": angular").c_str());
            WorldGuard guard(*r.world, WorldGuard::kWrite);
            if (Status s = setRigidVelocity(*r.world, r.name, r.live(), v, w); !s)
              throw py::value_error(s.error().message);
          },
          py::arg("linear") = py::none(), py::arg("angular") = py::none(),
          "Sets the velocity of a dynamic body now: linear (3,) m/s, angular (3,) rad/s about "
          "world axes; one left out is kept. Speeds up to 1e6 m/s, spins up to 1e6 rad/s.")
      .def(
          "apply_force",
          [](const R& r, py::object force, py::object point) {
            const Eigen::Vector3d f = toVector3(force, (who(r, "apply_force") + ": force").c_str());
            std::optional<Eigen::Vector3d> at;
            if (!point.is_none())
              at = toVector3(point, (who(r, "apply_force") + ": point").c_str());
            WorldGuard guard(*r.world, WorldGuard::kWrite);
            if (Status s = applyRigidLoad(*r.world, "apply_force", r.name, r.live(), f, at,
                                          Eigen::Vector3d::Zero());
                !s) {
              throw py::value_error(s.error().message);
            }
          },
          py::arg("force"), py::arg("point") = py::none(),
          "Adds force (3,) N to a dynamic body for the next step only, acting at point (3,) m in "
          "world coordinates (default: the centre of mass; elsewhere it adds its torque about "
          "it). Calls before one step add up.")
      .def(
          "apply_torque",
          [](const R& r, py::object torque) {
            const Eigen::Vector3d t =
                toVector3(torque, (who(r, "apply_torque") + ": torque").c_str());
            WorldGuard guard(*r.world, WorldGuard::kWrite);
            if (Status s = applyRigidLoad(*r.world, "apply_torque", r.name, r.live(),
                                          Eigen::Vector3d::Zero(), std::nullopt, t);
                !s) {
              throw py::value_error(s.error().message);
            }
          },
          py::arg("torque"),
          "Adds torque (3,) N m about world axes to a dynamic body for the next step only.")
      .def_property_readonly(
          "applied_force",
          [](const R& r) {
            WorldGuard guard(*r.world);
            const Wrench load = r.world->queuedLoad(r.live());
            return vectorArray(load.force.data(), 3);
          },
          "(3,) N: the force queued for the next step (apply_force), a copy")
      .def_property_readonly(
          "applied_torque",
          [](const R& r) {
            WorldGuard guard(*r.world);
            const Wrench load = r.world->queuedLoad(r.live());
            return vectorArray(load.torque.data(), 3);
          },
          "(3,) N m about the centre of mass: the torque queued for the next step (apply_torque, "
          "and apply_force away from the centre of mass), a copy")
      .def(
          "set_kinematic_target",
          [](const R& r, py::object position, py::object quaternion) {
            const Frame target = rigidFrame(r, "set_kinematic_target", position, quaternion);
            WorldGuard guard(*r.world, WorldGuard::kWrite);
            if (Status s = setKinematicTarget(*r.world, r.name, r.live(), target); !s)
              throw py::value_error(s.error().message);
          },
          py::arg("position"), py::arg("quaternion") = py::make_tuple(0.0, 0.0, 0.0, 1.0),
          "The pose (position (3,) m, quaternion (4,) x, y, z, w) a body of mass 0 reaches at "
          "the end of the next step, moving at the velocity that takes it there in dt (what "
          "contacts feel); it stays there until the next target. A static body becomes "
          "kinematic at its first target.");
}

}  // namespace torsion::python
