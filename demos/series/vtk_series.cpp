#include "vtk_series.h"

#include <LinearMath/btQuaternion.h>

#include <cstdio>
#include <filesystem>

#include "frame_data.h"
#include "rigid_geometry.h"
#include "rigid_surface.h"
#include "torsion/analysis/deformation_metrics.h"
#include "torsion/device/file_io.h"
#include "torsion/fem/corotated_element.h"

namespace torsion::series {

namespace {

namespace fs = std::filesystem;

// VTK_QUADRATIC_TETRA's mid-edge order (01, 12, 02, 03, 13, 23) from Torsion's (01, 02, 03, 12,
// 13, 23; quadratic_tet_mesh.h).
constexpr int kVtkFromTorsionTet10[10] = {0, 1, 2, 3, 4, 7, 5, 6, 8, 9};

std::vector<double> wrenchValues(const Wrench& w) {
  return {w.force.x(), w.force.y(), w.force.z(), w.torque.x(), w.torque.y(), w.torque.z()};
}

std::string bodyFile(const FemBody& body, const scene::BuiltScene& scene, int step) {
  const FemModel& model = body.model();
  const TetMesh& mesh = model.mesh();
  const FemState& state = body.state();
  // Points, cells and their data in the numbering of the body's mesh file (input_numbering.h).
  const InputNumbering& numbering = body.inputNumbering();
  VtuBuilder vtu;
  const int n = mesh.nodeCount();
  std::vector<double> points(static_cast<size_t>(3 * n)), displacement(points.size()),
      velocity(points.size());
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x = state.position(i);
    const Eigen::Vector3d u = x - mesh.restPositions()[static_cast<size_t>(i)];
    const Eigen::Vector3d v = state.velocities.segment<3>(3 * i);
    const int at = 3 * numbering.inputNode(i);
    for (int c = 0; c < 3; ++c) {
      points[static_cast<size_t>(at + c)] = x[c];
      displacement[static_cast<size_t>(at + c)] = u[c];
      velocity[static_cast<size_t>(at + c)] = v[c];
    }
  }
  vtu.setPoints(std::move(points));
  vtu.addPointData("displacement", 3, std::move(displacement));
  vtu.addPointData("velocity", 3, std::move(velocity));
  // Each hand on this body: its grabbed nodes (1, else 0), to colour or threshold in ParaView.
  for (const scene::SceneHand& h : scene.hands) {
    if (h.spec.body != body.name()) continue;
    std::vector<double> grabbed(static_cast<size_t>(n), 0.0);
    for (int node : h.hand->grabbedNodes())
      grabbed[static_cast<size_t>(numbering.inputNode(node))] = 1.0;
    vtu.addPointData("grabbed_" + h.spec.name, 1, std::move(grabbed));
  }

  // Per tet of mesh(), then per element (a tet4 element is its tet).
  const std::vector<double> tet_stress = render::tetVonMises(body);
  const int elements = model.elementCount();
  std::vector<double> stress(static_cast<size_t>(elements), 0.0), volume(stress.size(), 0.0),
      strain(stress.size(), 0.0);
  std::vector<std::uint8_t> inverted(stress.size(), 0);
  for (int t = 0; t < mesh.tetCount(); ++t) {
    const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
    std::array<Eigen::Vector3d, 4> x;
    for (size_t a = 0; a < 4; ++a)
      x[a] = state.position(tet[a]);
    const TetRestData& rest = model.tetRestData()[static_cast<size_t>(t)];
    const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
    const size_t e = static_cast<size_t>(model.elementOfTet(t));
    stress[e] += rest.volume * tet_stress[static_cast<size_t>(t)];
    volume[e] += rest.volume;
    strain[e] = std::max(strain[e], elementStrain(F));
    if (!(F.determinant() > 0)) inverted[e] = 1;
  }
  for (size_t e = 0; e < stress.size(); ++e)
    stress[e] = volume[e] > 0 ? stress[e] / volume[e] : 0.0;
  const int per = model.nodesPerElement();
  const int tets_per_element = mesh.tetCount() / elements;
  const std::vector<int>& nodes = model.elementNodes();
  std::vector<std::int64_t> cell(static_cast<size_t>(per));
  std::vector<double> cell_stress(stress.size()), cell_strain(stress.size());
  std::vector<std::uint8_t> cell_inverted(stress.size());
  for (int c = 0; c < elements; ++c) {
    const int e = numbering.bodyElement(c, tets_per_element);
    for (int k = 0; k < per; ++k) {
      const int from = per == 10 ? kVtkFromTorsionTet10[k] : k;
      cell[static_cast<size_t>(k)] =
          numbering.inputNode(nodes[static_cast<size_t>(per * e + from)]);
    }
    vtu.addCell(per == 10 ? VtkCellType::kQuadraticTetra : VtkCellType::kTetra, cell);
    cell_stress[static_cast<size_t>(c)] = stress[static_cast<size_t>(e)];
    cell_strain[static_cast<size_t>(c)] = strain[static_cast<size_t>(e)];
    cell_inverted[static_cast<size_t>(c)] = inverted[static_cast<size_t>(e)];
  }
  vtu.addCellData("von_mises", 1, std::move(cell_stress));
  vtu.addCellData("strain", 1, std::move(cell_strain));
  vtu.addCellFlags("inverted", std::move(cell_inverted));

  vtu.addFieldData("TimeValue", {scene.world->time()});
  vtu.addFieldData("step", {static_cast<double>(step)});
  for (const scene::NodeSetHandle& s : scene.node_sets) {
    if (s.body == &body)
      vtu.addFieldData("wrench_" + s.name,
                       wrenchValues(s.body->groupWrench(s.group, s.wrench_about)));
  }
  for (const scene::SceneHand& h : scene.hands) {
    if (h.spec.body != body.name()) continue;
    vtu.addFieldData("wrench_" + h.spec.name, wrenchValues(h.hand->wrench()));
    // The frame carrying the patch (origin, then the quaternion x y z w): the hand's plane passes
    // through the origin with the frame's z axis as its normal (hand_plane.h).
    const Frame& f = h.hand->frame();
    vtu.addFieldData("hand_frame_" + h.spec.name,
                     {f.origin.x(), f.origin.y(), f.origin.z(), f.rotation.x(), f.rotation.y(),
                      f.rotation.z(), f.rotation.w()});
  }
  return vtu.text();
}

std::string rigidFile(const scene::SceneRigidBody& rigid, const scene::BuiltScene& scene,
                      int step) {
  const render::RigidDrawData data = render::rigidDrawData(*rigid.body);
  const RigidSurface surface = rigidSurface(data);
  VtuBuilder vtu;
  std::vector<double> points;
  points.reserve(3 * surface.vertices.size());
  for (const Eigen::Vector3d& v : surface.vertices)
    points.insert(points.end(), {v.x(), v.y(), v.z()});
  vtu.setPoints(std::move(points));
  for (const auto& t : surface.triangles)
    vtu.addCell(VtkCellType::kTriangle, {t[0], t[1], t[2]});
  const btTransform& pose = rigid.body->getCenterOfMassTransform();
  const btQuaternion q = pose.getRotation();
  vtu.addFieldData("TimeValue", {scene.world->time()});
  vtu.addFieldData("step", {static_cast<double>(step)});
  vtu.addFieldData("position", {static_cast<double>(pose.getOrigin().x()),
                                static_cast<double>(pose.getOrigin().y()),
                                static_cast<double>(pose.getOrigin().z())});
  vtu.addFieldData("orientation", {static_cast<double>(q.x()), static_cast<double>(q.y()),
                                   static_cast<double>(q.z()), static_cast<double>(q.w())});
  return vtu.text();
}

std::string stepName(const std::string& prefix, int step) {
  char digits[16];
  std::snprintf(digits, sizeof digits, "%06d", step);
  return prefix + "_" + digits + ".vtu";
}

}  // namespace

Result<std::unique_ptr<VtkSeries>> VtkSeries::start(const std::string& out_dir, int every,
                                                    const scene::BuiltScene& scene,
                                                    int first_step) {
  const fs::path dir = fs::path(out_dir) / "series";
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Error{dir.string() + ": cannot create: " + ec.message()};
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (entry.path().extension() == ".vtu" && entry.is_regular_file(ec))
      fs::remove(entry.path(), ec);
  }
  // And what a killed run's atomic writes left: "<body>_<step>.vtu.tmp-<pid>".
  const std::string left = device::removeStaleTemporaries(
      dir.string(), [](const std::string& name) { return fs::path(name).extension() == ".vtu"; });
  if (!left.empty()) return Error{left};
  std::unique_ptr<VtkSeries> series(new VtkSeries(out_dir, every, first_step));
  if (Status written = series->write(scene, first_step); !written) return written.error();
  series->last_written_ = first_step;
  return series;
}

Status VtkSeries::onStep(const scene::BuiltScene& scene, int step, int total) {
  if ((step - first_step_) % every_ != 0 && step != total) return Ok{};
  return writeStep(scene, step);
}

Status VtkSeries::finish(const scene::BuiltScene& scene, int step) {
  if (step == last_written_) return Ok{};
  return writeStep(scene, step);
}

Status VtkSeries::writeStep(const scene::BuiltScene& scene, int step) {
  if (Status s = write(scene, step); !s) return s;
  last_written_ = step;
  return writeIndex();
}

Status VtkSeries::writeIndex() const {
  const std::string pvd = (fs::path(out_dir_) / "series.pvd").string();
  if (std::string error = device::writeFileAtomically(pvd, pvdText(entries_)); !error.empty())
    return Error{error};
  return Ok{};
}

Status VtkSeries::write(const scene::BuiltScene& scene, int step) {
  int part = 0;
  auto put = [&](const std::string& file, const std::string& text) -> Status {
    const std::string path = (fs::path(out_dir_) / "series" / file).string();
    if (std::string error = device::writeFileAtomically(path, text); !error.empty())
      return Error{error};
    entries_.push_back({scene.world->time(), part++, "series/" + file});
    return Ok{};
  };
  for (const auto& body : scene.world->bodies()) {
    if (Status s = put(stepName(body->name(), step), bodyFile(*body, scene, step)); !s) return s;
  }
  for (const scene::SceneRigidBody& rigid : scene.rigid_bodies) {
    if (Status s = put(stepName("rigid_" + rigid.name, step), rigidFile(rigid, scene, step)); !s)
      return s;
  }
  ++steps_written_;
  return Ok{};
}

}  // namespace torsion::series
