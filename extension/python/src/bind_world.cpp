// torsion.World: scenes from files or built in code, stepping without the GIL, checkpoints,
// pictures and VTK output.
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>

#include "body_vtk.h"
#include "camera.h"
#include "frame_data.h"
#include "handles.h"
#include "offscreen.h"
#include "py_contacts.h"
#include "py_convert.h"
#include "py_frame.h"
#include "py_numbering.h"
#include "scene_builder.h"
#include "scene_haptics.h"
#include "torsion/format_number.h"
#include "torsion/mesh/mesh_io.h"
#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/mesh/vtk_format.h"

namespace torsion::python {

namespace {

PyWorld& self(py::handle world) {
  return world.cast<PyWorld&>();
}

ElementKind toElement(const std::string& name) {
  if (name == "tet4") return ElementKind::kTet4;
  if (name == "tet10") return ElementKind::kTet10;
  throw py::value_error("element '" + name + "': expected 'tet4' or 'tet10'");
}

FemBody& findBody(PyWorld& world, py::handle body) {
  if (py::isinstance<BodyHandle>(body)) return *body.cast<BodyHandle&>().body;
  const std::string name = body.cast<std::string>();
  FemBody* found = world.world().body(name);
  if (!found) throw py::key_error("no body named '" + name + "'");
  return *found;
}

// A mesh from numpy nodes (n, 3) and tets (m, 4), validated like a mesh file.
TetMesh meshFromArrays(py::handle nodes, py::handle tets) {
  auto x = toFloatArray(nodes, "nodes");
  const IndexArray t = toIndexArray(tets, "tets");
  if (x.ndim() != 2 || x.shape(1) != 3)
    throw py::value_error("nodes: expected an array of shape (n, 3)");
  if (t.shape.size() != 2 || t.shape[1] != 4)
    throw py::value_error("tets: expected an int array of shape (m, 4) (linear tets)");
  RawTetMesh raw;
  raw.element_file = "<tets array>";
  for (py::ssize_t i = 0; i < x.shape(0); ++i) {
    const Eigen::Vector3d p(x.at(i, 0), x.at(i, 1), x.at(i, 2));
    if (!p.allFinite()) throw py::value_error("nodes: row " + std::to_string(i) + " is not finite");
    raw.positions.push_back(p);
  }
  for (py::ssize_t e = 0; e < t.shape[0]; ++e) {
    const int* row = t.values.data() + 4 * e;
    Tet tet{row[0], row[1], row[2], row[3]};
    for (int v : tet) {
      if (v < 0 || v >= static_cast<int>(raw.positions.size())) {
        raise(FailureKind::kMesh, "<tets array>: row " + std::to_string(e) + ": node " +
                                      std::to_string(v) + " is out of range [0, " +
                                      std::to_string(raw.positions.size()) + ")");
      }
    }
    raw.tets.push_back(tet);
    raw.origins.push_back({static_cast<int>(e) + 1, static_cast<long>(e)});
  }
  Result<LoadedMesh> built = buildTetMesh(std::move(raw));
  if (!built) raise(FailureKind::kMesh, built.error().message);
  return std::move(built).value().mesh;
}

std::vector<int> selectedNodes(const FemBody& body, py::object plane, py::object box,
                               py::object sphere, py::object indices, double tolerance) {
  const TetMesh& mesh = body.model().mesh();
  const int given = !plane.is_none() + !box.is_none() + !sphere.is_none() + !indices.is_none();
  if (given != 1)
    throw py::value_error("add_node_set: give exactly one of plane, box, sphere or indices");
  if (!indices.is_none()) {
    IndexArray a = toIndexArray(indices, "indices");
    if (a.shape.size() != 1) throw py::value_error("indices: expected a 1-D int array");
    for (int& node : a.values) {  // the mesh's numbers; one out of range is refused as given
      if (node >= 0 && node < mesh.nodeCount()) node = body.inputNumbering().bodyNode(node);
    }
    return std::move(a.values);
  }
  scene::NodeSelection selection;
  if (!plane.is_none()) {
    auto p = plane.cast<py::sequence>();
    selection.kind = scene::NodeSelection::Kind::kPlane;
    selection.point = toVector3(p[0], "plane point");
    const Eigen::Vector3d normal = toVector3(p[1], "plane normal");
    if (!(normal.norm() > 1e-12))
      throw py::value_error("plane normal: must not be zero, got " +
                            py::repr(p[1]).cast<std::string>());
    selection.normal = normal.normalized();
    if (!(tolerance >= 0 && std::isfinite(tolerance)))
      throw py::value_error("tolerance: must be finite and >= 0 m, got " + formatNumber(tolerance));
    selection.tolerance = tolerance;
  } else if (!box.is_none()) {
    auto b = box.cast<py::sequence>();
    selection.kind = scene::NodeSelection::Kind::kBox;
    selection.min = toVector3(b[0], "box min");
    selection.max = toVector3(b[1], "box max");
  } else {
    auto s = sphere.cast<py::sequence>();
    selection.kind = scene::NodeSelection::Kind::kSphere;
    selection.point = toVector3(s[0], "sphere centre");
    selection.radius = s[1].cast<double>();
    if (!(selection.radius > 0 && std::isfinite(selection.radius)))
      throw py::value_error("sphere radius: must be finite and > 0 m, got " +
                            formatNumber(selection.radius));
  }
  return scene::selectNodes(mesh, selection);
}

scene::RigidBodySpec::Shape toShape(const std::string& name) {
  using S = scene::RigidBodySpec::Shape;
  if (name == "box") return S::kBox;
  if (name == "sphere") return S::kSphere;
  if (name == "capsule") return S::kCapsule;
  throw py::value_error("shape '" + name + "': expected 'box', 'sphere' or 'capsule'");
}

// A World's pickled form: what rebuilds it from its scene and puts it where it was,
// (scene, threads, gravity, dt, state bytes). Only a world its scene
// describes pickles: one Python added parts to, drives devices in, or set kinematic targets in
// is refused with what stands in the way.
py::tuple worldDescription(PyWorld& w) {
  const std::string cannot = "cannot pickle this torsion.World: ";
  if (w.sceneSource().empty()) {
    throw py::type_error(cannot +
                         "it was built in code; send the function (and arguments) that builds "
                         "it, and a State (save_state) to put it where it was");
  }
  if (w.partsAdded())
    throw py::type_error(cannot +
                         "Python added bodies, node sets, hands or rigid bodies to its "
                         "scene; send the function that builds it, and a State");
  if (w.devicesOverridden())
    throw py::type_error(cannot + "it drives devices (devices= or haptics= of from_scene)");
  if (w.hasKinematicTargets())
    throw py::type_error(cannot +
                         "a rigid body has a kinematic target, which a state does not hold");
  if (w.rigidRemoved()) throw py::type_error(cannot + "Python removed rigid bodies of its scene");
  if (w.nodeSetsDriven())
    throw py::type_error(cannot + "a node set is driven by move_to, which a state does not hold");
  if (w.femContactChanged())
    throw py::type_error(cannot +
                         "Python changed its contact between FEM bodies (enable_fem_contact, "
                         "disable_fem_contact)");
  Result<PyWorldState> state = w.saveState();
  if (!state) throw py::type_error(cannot + state.error().message);
  // A demo scene's name travels as it is (each machine finds it in its own data folder); a path
  // as an absolute one, so that the unpickling process's working folder does not matter.
  std::string scene = w.sceneSource();
  if (scene.find('/') != std::string::npos || std::filesystem::exists(scene))
    scene = std::filesystem::absolute(w.scene().spec.file).lexically_normal().string();
  const WorldSettings& settings = w.world().settings();
  const Eigen::Vector3d& g = settings.gravity;
  return py::make_tuple(scene, w.sceneThreads(), py::make_tuple(g.x(), g.y(), g.z()),
                        settings.solver.time_step, py::bytes(w.serialize(state.value())));
}

std::unique_ptr<PyWorld> worldFromDescription(const py::tuple& t) {
  if (t.size() != 5) throw py::value_error("torsion.World: bad pickle (5 fields expected)");
  FailureKind kind;
  Result<std::unique_ptr<PyWorld>> built =
      PyWorld::fromScene(t[0].cast<std::string>(), t[1].cast<int>(), {}, &kind);
  if (!built) raise(kind, built.error().message);
  PyWorld& w = *built.value();
  if (Status s = w.setGravity(toVector3(t[2], "gravity")); !s)
    throw py::value_error(s.error().message);
  if (Status s = w.setTimeStep(t[3].cast<double>()); !s) throw py::value_error(s.error().message);
  PyWorldState state;
  state.in_memory = false;
  state.bytes = t[4].cast<std::string>();
  if (Status s = w.restoreState(state); !s) throw py::value_error(s.error().message);
  return std::move(built).value();
}

// World.record_series and the rest of the ParaView series (PyWorld::recordSeries).
void bindSeries(py::class_<PyWorld>& world) {
  world
      .def(
          "record_series",
          [](PyWorld& w, py::object directory, int every) {
            py::object path = py::module_::import("os").attr("fspath")(directory);
            if (!py::isinstance<py::str>(path))
              throw py::type_error("record_series: directory must be a str or a path, not bytes");
            const std::string dir = path.cast<std::string>();
            FailureKind kind;
            Status started = Ok{};
            {
              WorldGuard guard(w);
              py::gil_scoped_release release;
              started = w.recordSeries(dir, every, &kind);
            }
            if (!started) raise(kind, started.error().message);
          },
          py::arg("directory"), py::arg("every") = 1,
          "Starts the ParaView time series of `torsion run --vtk-every`: directory/series.pvd "
          "and one .vtu per body and rigid body per written step in directory/series/ (emptied "
          "of .vtu files first). The state now is the first entry; step() then writes every "
          "every-th step after it, inside the step loop. ValueError, changing nothing: every < "
          "1, a series already recorded, a directory that cannot be created. OSError (naming the "
          "file) when a file cannot be written, here or in step(); the series then ends.")
      .def(
          "stop_series",
          [](PyWorld& w) {
            Status stopped = Ok{};
            {
              WorldGuard guard(w);
              py::gil_scoped_release release;
              stopped = w.stopSeries();
            }
            if (!stopped) raise(FailureKind::kOutput, stopped.error().message);
          },
          "Writes the state now unless it was the last written and ends the series (nothing "
          "without one). OSError naming the file when it cannot be written; the series ends.")
      .def_property_readonly(
          "recording_series", [](PyWorld& w) { return w.recordingSeries(); },
          "Whether record_series started a series that has not ended")
      .def_property_readonly(
          "series_steps_written", [](PyWorld& w) { return w.seriesStepsWritten(); },
          "Steps written by the series recorded now, else by the last one (0 without any)");
}

}  // namespace

void bindWorld(py::module_& m) {
  py::class_<ContactList>(m, "Contacts",
                          "The contacts of a world's last step (World.contacts()): row k of each "
                          "array is one contact between body_a[k] and body_b[k].")
      .def("__len__", &ContactList::size)
      // Pickled as its lists (a worker's result travels back to the program that gathers it).
      .def(py::pickle(
          [](const ContactList& c) {
            return py::make_tuple(c.body_a, c.body_b, c.points, c.normals, c.impulses);
          },
          [](const py::tuple& t) {
            if (t.size() != 5) throw py::value_error("torsion.Contacts: bad pickle");
            ContactList c;
            c.body_a = t[0].cast<std::vector<std::string>>();
            c.body_b = t[1].cast<std::vector<std::string>>();
            c.points = t[2].cast<std::vector<double>>();
            c.normals = t[3].cast<std::vector<double>>();
            c.impulses = t[4].cast<std::vector<double>>();
            const size_t n = c.body_a.size();
            if (c.body_b.size() != n || c.points.size() != 3 * n || c.normals.size() != 3 * n ||
                c.impulses.size() != 3 * n)
              throw py::value_error("torsion.Contacts: bad pickle (sizes differ)");
            return c;
          }))
      .def_readonly("body_a", &ContactList::body_a,
                    "list of names: the FEM body in FEM-rigid contact, else Bullet's first body")
      .def_readonly("body_b", &ContactList::body_b,
                    "list of names: the rigid body (\"ground\" for the ground plane)")
      .def_property_readonly(
          "points",
          [](const ContactList& c) {
            return copyArray(c.points.data(), static_cast<py::ssize_t>(c.size()), 3);
          },
          "(k, 3) m: the contact point on A at the end of the step (an FEM node, a point of an "
          "FEM face, Bullet's point on A)")
      .def_property_readonly(
          "normals",
          [](const ContactList& c) {
            return copyArray(c.normals.data(), static_cast<py::ssize_t>(c.size()), 3);
          },
          "(k, 3): unit, from B towards A (PyBullet's contactNormalOnB)")
      .def_property_readonly(
          "impulses",
          [](const ContactList& c) {
            return copyArray(c.impulses.data(), static_cast<py::ssize_t>(c.size()), 3);
          },
          "(k, 3) N s: the impulse B gave A over the step, friction included; / dt: the mean force")
      .def_property_readonly(
          "normal_impulses",
          [](const ContactList& c) {
            py::array_t<double> out(static_cast<py::ssize_t>(c.size()));
            for (size_t k = 0; k < c.size(); ++k) {
              double dot = 0;
              for (size_t a = 0; a < 3; ++a)
                dot += c.impulses[3 * k + a] * c.normals[3 * k + a];
              out.mutable_at(static_cast<py::ssize_t>(k)) = dot;
            }
            return out;
          },
          "(k,) N s: impulses . normals, >= 0 where the bodies push each other apart")
      .def("__repr__", [](const ContactList& c) {
        return "<torsion.Contacts: " + std::to_string(c.size()) + " contacts>";
      });

  py::class_<PyWorld>(m, "World", "Bullet world with FEM soft bodies, hands and rigid bodies.")
      .def(py::init([](py::object gravity, double dt, double tolerance, int max_iterations,
                       const std::string& linear_solver, int threads, double max_speed,
                       double newton_tolerance, int newton_max_iterations) {
             WorldSettings settings;
             settings.gravity = toVector3(gravity, "gravity");
             settings.solver.time_step = dt;
             settings.solver.tolerance = tolerance;
             settings.solver.max_iterations = max_iterations;
             settings.solver.threads = threads;
             settings.solver.max_speed = max_speed;
             settings.solver.newton_tolerance = newton_tolerance;
             settings.solver.newton_max_iterations = newton_max_iterations;
             if (linear_solver == "cholmod") {
               settings.solver.linear_solver = LinearSolverKind::kCholmod;
             } else if (linear_solver != "cg") {
               throw py::value_error("linear_solver '" + linear_solver +
                                     "': expected 'cg' or 'cholmod'");
             }
             if (Status valid = settings.validate(); !valid)
               throw py::value_error(valid.error().message);
             return std::make_unique<PyWorld>(settings);
           }),
           py::arg("gravity") = py::make_tuple(0.0, 0.0, -9.81), py::arg("dt") = 0.01,
           py::arg("tolerance") = 1e-4, py::arg("max_iterations") = 300,
           py::arg("linear_solver") = "cg", py::arg("threads") = 0, py::arg("max_speed") = 1e3,
           py::arg("newton_tolerance") = SolverSettings{}.newton_tolerance,
           py::arg("newton_max_iterations") = SolverSettings{}.newton_max_iterations,
           "An empty world. gravity: m/s^2; dt: s; tolerance: CG relative residual; threads: "
           "solver worker threads (0: all cores); max_speed: m/s, a faster node fails the step; "
           "newton_tolerance, newton_max_iterations: the Newton solve of hyperelastic bodies' "
           "steps (docs/materials.md).")
      .def_static(
          "from_scene",
          [](const std::string& scene, int threads, py::object devices, const std::string& haptics,
             bool allow_remote_devices) {
            scene::DeviceOverrides overrides;
            overrides.haptics = haptics;
            overrides.allow_remote_devices = allow_remote_devices;
            if (py::isinstance<py::dict>(devices)) {
              for (auto item : devices.cast<py::dict>()) {
                overrides.devices.push_back(item.first.cast<std::string>() + "=" +
                                            item.second.cast<std::string>());
              }
            } else if (!devices.is_none()) {
              overrides.devices = devices.cast<std::vector<std::string>>();
            }
            FailureKind kind;
            Result<std::unique_ptr<PyWorld>> world =
                PyWorld::fromScene(scene, threads, overrides, &kind);
            if (!world) raise(kind, world.error().message);
            return std::move(world).value();
          },
          py::arg("scene"), py::arg("threads") = -1, py::kw_only(), py::arg("devices") = py::none(),
          py::arg("haptics") = "", py::arg("allow_remote_devices") = false,
          "A scene file, or a demo scene's name (resolved like `torsion run NAME`: "
          "$TORSION_SCENE_PATH, then demos/scenes of torsion.data_path()). threads < 0: the "
          "scene's. "
          "devices: {hand: 'TYPE[:ARG]'} or ['HAND=TYPE[:ARG]'], as `torsion run --device` "
          "(scripted:FILE, replay:CSV, network:[HOST:]PORT, spacemouse); haptics: 'lockstep' or "
          "'threaded' (--haptics); allow_remote_devices: --allow-remote-device.")
      .def(py::pickle(
          [](PyWorld& w) {
            WorldGuard guard(w);
            return worldDescription(w);
          },
          &worldFromDescription))
      .def(
          "step",
          [](PyWorld& w, int n) {
            if (n < 0) throw py::value_error("step: n must be >= 0");
            FailureKind kind;
            Result<Ok> stepped = Ok{};
            // Signals (Ctrl-C) are handled by Python with the GIL in the main thread: it is taken
            // back between steps every kSignalCheck to ask, and a pending KeyboardInterrupt stops
            // the run at that step boundary and is raised once the step returns.
            constexpr auto kSignalCheck = std::chrono::milliseconds(20);
            bool signalled = false;
            auto last_check = std::chrono::steady_clock::now();
            auto interrupted = [&] {
              const auto now = std::chrono::steady_clock::now();
              if (now - last_check < kSignalCheck) return false;
              last_check = now;
              py::gil_scoped_acquire acquire;
              signalled = PyErr_CheckSignals() != 0;
              return signalled;
            };
            {
              WorldGuard guard(w);
              py::gil_scoped_release release;
              stepped = w.step(n, &kind, interrupted);
            }
            if (signalled) throw py::error_already_set();
            if (!stepped) raise(kind, stepped.error().message);
          },
          py::arg("n") = 1,
          "n steps of dt, without the GIL. UnstableError (body and step in the message) when a "
          "step fails: the bodies keep their last good state and the world goes no further. "
          "Ctrl-C (KeyboardInterrupt, or any exception a signal handler raises) stops it at a step "
          "boundary: the world is as after the steps done.")
      .def_property_readonly(
          "time", [](PyWorld& w) { return w.world().time(); }, "s")
      .def_property_readonly("step_count", [](PyWorld& w) { return w.world().stepCount(); })
      .def_property(
          "dt", [](PyWorld& w) { return w.world().settings().solver.time_step; },
          [](PyWorld& w, double dt) {
            WorldGuard guard(w, WorldGuard::kWrite);
            if (Status s = w.setTimeStep(dt); !s) throw py::value_error(s.error().message);
          },
          "s: the time step of the next steps, settable between steps (within [1e-6, 1] s; not "
          "with device hands); the clock goes on from where it is.")
      .def_property(
          "gravity", [](PyWorld& w) { return vectorArray(w.world().settings().gravity.data(), 3); },
          [](PyWorld& w, py::object gravity) {
            const Eigen::Vector3d g = toVector3(gravity, "gravity");
            WorldGuard guard(w, WorldGuard::kWrite);
            if (Status s = w.setGravity(g); !s) throw py::value_error(s.error().message);
          },
          "(3,) m/s^2, a copy: the gravity of the next steps on FEM and dynamic rigid bodies, "
          "settable between steps (magnitude at most 1e6 m/s^2).")
      .def_property_readonly(
          "scene_steps", [](PyWorld& w) { return w.scene().spec.steps; },
          "The scene file's step count (what `torsion run` takes)")
      .def_property_readonly("bodies",
                             [](py::object owner) {
                               std::vector<BodyHandle> out;
                               for (const auto& b : self(owner).world().bodies())
                                 out.push_back({owner, &self(owner), b.get()});
                               return out;
                             })
      .def(
          "body",
          [](py::object owner, const std::string& name) {
            return BodyHandle{owner, &self(owner), &findBody(self(owner), py::str(name))};
          },
          py::arg("name"))
      .def_property_readonly("node_sets",
                             [](py::object owner) {
                               std::vector<NodeSetHandle> out;
                               for (size_t i = 0; i < self(owner).scene().node_sets.size(); ++i)
                                 out.push_back({owner, &self(owner), i});
                               return out;
                             })
      .def(
          "node_set",
          [](py::object owner, const std::string& name) {
            const auto& sets = self(owner).scene().node_sets;
            for (size_t i = 0; i < sets.size(); ++i) {
              if (sets[i].name == name) return NodeSetHandle{owner, &self(owner), i};
            }
            throw py::key_error("no node set named '" + name + "'");
          },
          py::arg("name"))
      .def_property_readonly("hands",
                             [](py::object owner) {
                               std::vector<HandHandle> out;
                               for (Hand* h : self(owner).hands())
                                 out.push_back({owner, &self(owner), h});
                               return out;
                             })
      .def(
          "hand",
          [](py::object owner, const std::string& name) {
            for (Hand* h : self(owner).hands()) {
              if (h->name() == name) return HandHandle{owner, &self(owner), h};
            }
            throw py::key_error("no hand named '" + name + "'");
          },
          py::arg("name"))
      .def(
          "device_wrench",
          [](py::object owner, const std::string& name) {
            const scene::BuiltScene& built = self(owner).scene();
            std::optional<Wrench> w;
            if (built.haptics) w = built.haptics->deviceWrench(name);
            if (!w) throw py::key_error("no hand or tool named '" + name + "' has a device");
            return wrenchArray(*w);
          },
          py::arg("name"),
          "The wrench the device of hand or tool `name` renders after the last step: a 6-vector "
          "(force N, torque N m) in the world frame, before the device mapping's scales and the "
          "haptic loop's local model. A tool's is its contacts' push (its weight compensated "
          "unless feel_weight).")
      .def_property_readonly(
          "rigid_bodies",
          [](py::object owner) {
            std::vector<RigidHandle> out;
            for (const scene::SceneRigidBody& r : self(owner).scene().rigid_bodies)
              out.emplace_back(owner, self(owner), r.name, r.body);
            return out;
          })
      .def(
          "rigid_body",
          [](py::object owner, const std::string& name) {
            for (const scene::SceneRigidBody& r : self(owner).scene().rigid_bodies) {
              if (r.name == name) return RigidHandle(owner, self(owner), r.name, r.body);
            }
            throw py::key_error("no rigid body named '" + name + "'");
          },
          py::arg("name"))
      .def(
          "remove_rigid_body",
          [](py::object owner, py::object body) {
            PyWorld& w = self(owner);
            btRigidBody* rigid = nullptr;
            if (py::isinstance<RigidHandle>(body)) {
              const RigidHandle& r = body.cast<const RigidHandle&>();
              if (r.world != &w)
                throw py::value_error("remove_rigid_body: '" + r.name + "' is another world's");
              rigid = &r.live();
            } else {
              const std::string name = body.cast<std::string>();
              for (const scene::SceneRigidBody& r : w.scene().rigid_bodies) {
                if (r.name == name) rigid = r.body;
              }
              if (rigid == nullptr) throw py::key_error("no rigid body named '" + name + "'");
            }
            WorldGuard guard(w, WorldGuard::kWrite);
            if (Status s = w.removeRigidBody(*rigid); !s) throw py::value_error(s.error().message);
          },
          py::arg("body"),
          "Takes a rigid body (a RigidBody or its name) out of the world for good, from the next "
          "step on: FEM bodies it pressed on are free, its handles raise ValueError, contacts() "
          "is empty until the next step and states saved before no longer restore. ValueError, "
          "nothing changed: an FEM body anchors nodes to it (remove_anchor first), a handle of a "
          "body removed already; KeyError: no rigid body of that name.")
      .def(
          "enable_fem_contact",
          [](PyWorld& w, double friction, double gap_tolerance, double thickness_factor,
             double margin) {
            BodyContactSettings settings;
            settings.friction = friction;
            settings.gap_tolerance = gap_tolerance;
            settings.thickness_factor = thickness_factor;
            settings.margin = margin;
            WorldGuard guard(w, WorldGuard::kWrite);
            if (Status s = w.setFemContact(settings, true); !s)
              throw py::value_error(s.error().message);
          },
          py::kw_only(), py::arg("friction") = BodyContactSettings{}.friction,
          py::arg("gap_tolerance") = BodyContactSettings{}.gap_tolerance,
          py::arg("thickness_factor") = BodyContactSettings{}.thickness_factor,
          py::arg("margin") = BodyContactSettings{}.margin,
          "Contact between FEM bodies from the next step on, with these settings (a scene's "
          "\"fem_contact\"; on by default): friction (Coulomb), gap_tolerance (m; 0: 1e-3 of the "
          "smaller mean surface edge), thickness_factor (the gap aimed at, in gap tolerances), "
          "margin (the candidate search's reach, in mean surface edges). ValueError, nothing "
          "changed, on a bad value.")
      .def(
          "disable_fem_contact",
          [](PyWorld& w, bool refuse_touching) {
            WorldGuard guard(w, WorldGuard::kWrite);
            (void)w.setFemContact(std::nullopt, refuse_touching);
          },
          py::kw_only(), py::arg("refuse_touching") = false,
          "No contact between FEM bodies from the next step on: they pass through each other, or, "
          "with refuse_touching=True, a step in which two touch fails (UnstableError naming "
          "them), as a scene's \"fem_contact\": {\"enabled\": false} does.")
      .def_property_readonly(
          "fem_contact", [](PyWorld& w) { return w.world().femSolver().femContact() != nullptr; },
          "Whether FEM bodies touch each other (enable_fem_contact, disable_fem_contact)")
      .def(
          "contacts",
          [](PyWorld& w) {
            WorldGuard guard(w);
            return lastStepContacts(w);
          },
          "The contacts of the last step (PyBullet's getContactPoints): FEM bodies against rigid "
          "bodies and rigid bodies against each other, not FEM against FEM. Empty before the "
          "first step and after restore_state until the next step. A copy.")
      .def(
          "save_state",
          [](PyWorld& w) {
            WorldGuard guard(w);
            Result<PyWorldState> state = w.saveState();
            if (!state) throw py::value_error(state.error().message);
            state.value().bytes = w.serialize(state.value());  // what pickle takes
            return std::move(state).value();
          },
          "The world now (FEM bodies, solver warm starts, hands, node sets, rigid bodies).")
      .def(
          "restore_state",
          [](PyWorld& w, const PyWorldState& state) {
            WorldGuard guard(w);
            if (Status s = w.restoreState(state); !s) throw py::value_error(s.error().message);
          },
          py::arg("state"), "Back to `state`; the steps after it repeat bit for bit.")
      .def(
          "add_body",
          [](py::object owner, const std::string& name, py::object mesh, py::object nodes,
             py::object tets, const Material& material, py::object frame,
             const std::string& element, const std::string& node_order) {
            PyWorld& w = self(owner);
            TetMesh built;
            if (!mesh.is_none()) {
              if (!nodes.is_none() || !tets.is_none())
                throw py::value_error("add_body: give mesh or nodes and tets, not both");
              Result<LoadedMesh> loaded = readMesh(py::str(mesh).cast<std::string>());
              if (!loaded) raise(FailureKind::kMesh, loaded.error().message);
              built = std::move(loaded).value().mesh;
            } else {
              if (nodes.is_none() || tets.is_none())
                throw py::value_error("add_body: give mesh, or nodes and tets");
              built = meshFromArrays(nodes, tets);
            }
            const Frame pose = frame.is_none() ? Frame{} : toFrame(frame, "add_body frame");
            if (node_order != "cache_friendly" && node_order != "file") {
              throw py::value_error("add_body: node_order '" + node_order +
                                    "' is not a node order (cache_friendly or file)");
            }
            const NodeNumbering numbering =
                node_order == "file" ? NodeNumbering::kAsGiven : NodeNumbering::kCacheFriendly;
            WorldGuard guard(w, WorldGuard::kWrite);
            Result<FemBody*> body =
                w.addBody(name, built, material, pose, toElement(element), numbering);
            if (!body) throw py::value_error(body.error().message);
            return BodyHandle{owner, &w, body.value()};
          },
          py::arg("name"), py::arg("mesh") = py::none(), py::kw_only(),
          py::arg("nodes") = py::none(), py::arg("tets") = py::none(),
          py::arg("material") = Material{}, py::arg("frame") = py::none(),
          py::arg("element") = "tet4", py::arg("node_order") = "cache_friendly",
          "A body from a mesh file (.node/.ele, .msh, .vtk; MeshError names file and line) or "
          "from nodes (n, 3) m and tets (m, 4), placed at `frame`. Node and tet numbers are "
          "the mesh's everywhere; node_order 'cache_friendly' renumbers the nodes inside when "
          "that pays (faster steps), 'file' keeps the mesh's order inside too.")
      .def(
          "add_node_set",
          [](py::object owner, const std::string& name, py::object body, py::object plane,
             py::object box, py::object sphere, py::object indices, double tolerance,
             py::object wrench_about) {
            PyWorld& w = self(owner);
            FemBody& b = findBody(w, body);
            std::vector<int> nodes = selectedNodes(b, plane, box, sphere, indices, tolerance);
            WorldGuard guard(w, WorldGuard::kWrite);
            Result<int> index =
                w.addNodeSet(name, b, std::move(nodes), toVector3(wrench_about, "wrench_about"));
            if (!index) throw py::value_error(index.error().message);
            return NodeSetHandle{owner, &w, static_cast<size_t>(index.value())};
          },
          py::arg("name"), py::arg("body"), py::kw_only(), py::arg("plane") = py::none(),
          py::arg("box") = py::none(), py::arg("sphere") = py::none(),
          py::arg("indices") = py::none(), py::arg("tolerance") = 1e-6,
          py::arg("wrench_about") = py::make_tuple(0.0, 0.0, 0.0),
          "Holds the nodes of `body` (a Body or its name) in place, chosen by rest position: "
          "plane=(point, normal) within tolerance (m), box=(min, max), sphere=(centre, radius), "
          "or indices.")
      .def(
          "add_hand",
          [](py::object owner, const std::string& name, py::object body, double max_drag_strain) {
            PyWorld& w = self(owner);
            HandSettings settings;
            settings.max_drag_strain = max_drag_strain;
            if (Status valid = settings.validate(); !valid)
              throw py::value_error(valid.error().message);
            WorldGuard guard(w, WorldGuard::kWrite);
            Result<Hand*> hand = w.addHand(findBody(w, body), name, settings);
            if (!hand) throw py::value_error(hand.error().message);
            return HandHandle{owner, &w, hand.value()};
          },
          py::arg("name"), py::arg("body"), py::arg("max_drag_strain") = 0.2,
          "A hand on `body`, not grabbing yet: call grab(frame), then move_to(frame) each step.")
      .def(
          "add_rigid_body",
          [](py::object owner, const std::string& name, const std::string& shape,
             py::object half_extents, double radius, double half_height, double mass,
             py::object frame, double friction, py::object linear_velocity) {
            PyWorld& w = self(owner);
            scene::RigidBodySpec spec;
            spec.name = name;
            spec.shape = toShape(shape);
            spec.half_extents = toVector3(half_extents, "half_extents");
            spec.radius = radius;
            spec.half_height = half_height;
            spec.mass = mass;
            spec.pose = frame.is_none() ? Frame{} : toFrame(frame, "add_rigid_body frame");
            spec.friction = friction;
            spec.linear_velocity = toVector3(linear_velocity, "linear_velocity");
            WorldGuard guard(w, WorldGuard::kWrite);
            Result<btRigidBody*> body = w.addRigidBody(spec, false);
            if (!body) throw py::value_error(body.error().message);
            return RigidHandle(owner, w, name, body.value());
          },
          py::arg("name"), py::arg("shape") = "box", py::kw_only(),
          py::arg("half_extents") = py::make_tuple(0.5, 0.5, 0.5), py::arg("radius") = 0.5,
          py::arg("half_height") = 0.5, py::arg("mass") = 1.0, py::arg("frame") = py::none(),
          py::arg("friction") = 0.5, py::arg("linear_velocity") = py::make_tuple(0.0, 0.0, 0.0),
          "A Bullet rigid body: box (half_extents, m), sphere (radius) or capsule along z "
          "(radius, half_height), each length in (0, 1e6] m; mass in kg: 0 for static, else in "
          "[1e-9, 1e12]. A unique name of letters, digits and \" -_.+()\".")
      .def(
          "add_ground",
          [](PyWorld& w, double height, double friction) {
            scene::RigidBodySpec spec;
            spec.name = "ground";
            spec.shape = scene::RigidBodySpec::Shape::kPlane;
            spec.plane_normal = Eigen::Vector3d::UnitZ();
            spec.plane_offset = height;
            spec.mass = 0;
            spec.friction = friction;
            WorldGuard guard(w, WorldGuard::kWrite);
            if (Result<btRigidBody*> ground = w.addRigidBody(spec, true); !ground)
              throw py::value_error(ground.error().message);
          },
          py::arg("height") = 0.0, py::arg("friction") = 0.5,
          "A static ground plane z = height (m, finite, within 1e6 of 0).")
      .def(
          "render",
          [](PyWorld& w, int width, int height, py::object camera, bool hud) {
            if (width <= 0 || height <= 0) throw py::value_error("render: width and height > 0");
            WorldGuard guard(w);
            render::FrameData frame = captureWorldFrame(w);
            Result<std::unique_ptr<render::OffscreenRenderer>> renderer =
                render::OffscreenRenderer::create(width, height);
            if (!renderer) throw std::runtime_error("render: " + renderer.error().message);
            render::RenderOptions options;
            options.hud = hud;
            options.legend = hud;
            render::Camera cam = renderer.value()->fitCamera(frame, options);
            if (!camera.is_none()) {
              py::dict c = camera.cast<py::dict>();
              for (auto item : c) {
                const std::string key = item.first.cast<std::string>();
                if (key == "target")
                  cam.target = toVector3(item.second, "camera target");
                else if (key == "up")
                  cam.up = toVector3(item.second, "camera up").normalized();
                else if (key == "distance")
                  cam.distance = finite(item.second.cast<double>(), "camera distance");
                else if (key == "yaw")
                  cam.yaw = finite(item.second.cast<double>(), "camera yaw");
                else if (key == "pitch")
                  cam.pitch = finite(item.second.cast<double>(), "camera pitch");
                else if (key == "fov_y")
                  cam.fov_y = finite(item.second.cast<double>(), "camera fov_y");
                else
                  throw py::value_error("camera: unknown key '" + key + "'");
              }
              if (!(cam.distance > 0))
                throw py::value_error("camera distance: must be > 0 m, got " +
                                      formatNumber(cam.distance));
              if (!(cam.fov_y > 0 && cam.fov_y < M_PI))
                throw py::value_error("camera fov_y: must be in (0, pi) rad, got " +
                                      formatNumber(cam.fov_y));
              if (!(cam.up.norm() > 0)) throw py::value_error("camera up: must not be zero");
            }
            const render::Image image = renderer.value()->render(frame, cam, options);
            return copyArray(image.rgb.data(), image.height, image.width * 3)
                .attr("reshape")(image.height, image.width, 3);
          },
          py::arg("width") = 640, py::arg("height") = 480, py::arg("camera") = py::none(),
          py::arg("hud") = false,
          "An (height, width, 3) uint8 picture (OSMesa, headless), stress-coloured. camera: a "
          "dict overriding the fitted camera's target, up, distance (m), yaw, pitch, fov_y (rad).")
      .def(
          "write_vtk",
          [](PyWorld& w, const std::string& path, py::object body) {
            WorldGuard guard(w);
            if (w.world().bodies().empty())
              throw py::value_error("write_vtk: the world has no body");
            FemBody& b = body.is_none() ? *w.world().bodies().front() : findBody(w, body);
            if (Status s = writeTextFile(path, scene::bodyVtkText(b, b.state().positions)); !s)
              throw std::runtime_error(s.error().message);
          },
          py::arg("path"), py::arg("body") = py::none(),
          "The body's current mesh with its displacement (legacy VTK, %.17g: reads back bit for "
          "bit), as `torsion run` writes <body>.vtk. Default: the first body.");
  py::class_<PyWorld> world = py::reinterpret_borrow<py::class_<PyWorld>>(m.attr("World"));
  bindSeries(world);
}

}  // namespace torsion::python
