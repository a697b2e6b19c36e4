#include "torsion/bullet/checkpoint_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <deque>
#include <mutex>

#include "torsion/checkpoint_stream.h"
#include "torsion/fnv1a.h"
#include "torsion/format_number.h"

namespace torsion {
namespace {

constexpr char kMagic[8] = {'T', 'R', 'S', 'N', 'C', 'K', 'P', 'T'};
// 2: the pair multipliers of contact between FEM bodies.
// 3: the node contacts' impulses (the contact-space friction solve's warm start).
// 4: the node contacts' normals (the plane a contact keeps while its node stays over it).
// 5: the payload's hash is the standard FNV-1a (torsion/fnv1a.h); 4 used an offset basis one
//    digit short of it.
// 6: the convex solve's face features.
// 7: no augmented-Lagrangian memory: self-contact settings without its penalty and iteration
//    cap, no face contact multipliers (the face rows' features carry the convex solve's).
// 8: contact memory as the bytes of the solvers' own save() (checkpoint_stream.h), with the
//    contact friction; pair multipliers likewise.
constexpr std::uint32_t kVersion = 8;
constexpr size_t kHeaderSize = sizeof(kMagic) + 4 + 8 + 8;

// The bytes of a mesh's rest positions and elements: a body restored onto another mesh would
// index the wrong nodes.
std::uint64_t meshHash(const FemModel& model) {
  std::string bytes;
  for (const Eigen::Vector3d& x : model.mesh().restPositions())
    bytes.append(reinterpret_cast<const char*>(x.data()), 3 * sizeof(double));
  for (int node : model.elementNodes())
    bytes.append(reinterpret_cast<const char*>(&node), sizeof(int));
  return fnv1a(bytes);
}

// A static string for LinearSolveReport::breakdown_reason (reports hold them by pointer).
const char* internReason(const std::string& reason) {
  static std::mutex mutex;
  static std::deque<std::string> reasons;
  const std::lock_guard<std::mutex> lock(mutex);
  for (const std::string& r : reasons) {
    if (r == reason) return r.c_str();
  }
  return reasons.emplace_back(reason).c_str();
}

// How a node group moves, which is code, not data: a group of the world with the same index and
// name (node sets and scripted ends, made when the world is built), a hand's pursuit, or nothing
// (a released group holds no node).
enum class GroupMotion { kWorldGroup, kHand, kNone };

void writeFrame(CheckpointWriter& w, const Frame& f) {
  w.vec3(f.origin);
  for (double c : {f.rotation.x(), f.rotation.y(), f.rotation.z(), f.rotation.w()})
    w.f64(c);
}

// A frame as Frame holds one: a finite origin and a unit quaternion (saved from a unit one, so
// its norm is 1 to rounding).
Frame readFrame(CheckpointReader& r) {
  Frame f;
  f.origin = r.vec3();
  const double x = r.f64(), y = r.f64(), z = r.f64(), w = r.f64();
  f.rotation = Eigen::Quaterniond(w, x, y, z);
  if (r.ok() && !(f.origin.allFinite() && std::abs(f.rotation.norm() - 1) <= 1e-9))
    r.refuse("a frame with a non-finite origin or a rotation that is not a unit quaternion");
  return f;
}

void writeMaterial(CheckpointWriter& w, const Material& m) {
  for (double v :
       {m.youngs_modulus, m.poisson_ratio, m.density, m.mass_damping, m.stiffness_damping})
    w.f64(v);
  w.u8(static_cast<int>(m.volumetric_strain));
}

Material readMaterial(CheckpointReader& r) {
  Material m;
  m.youngs_modulus = r.f64();
  m.poisson_ratio = r.f64();
  m.density = r.f64();
  m.mass_damping = r.f64();
  m.stiffness_damping = r.f64();
  m.volumetric_strain = r.enumeration(VolumetricStrain::kNodalAverage);
  return m;
}

bool sameMaterial(const Material& a, const Material& b) {
  return a.youngs_modulus == b.youngs_modulus && a.poisson_ratio == b.poisson_ratio &&
         a.density == b.density && a.mass_damping == b.mass_damping &&
         a.stiffness_damping == b.stiffness_damping && a.volumetric_strain == b.volumetric_strain;
}

void writeReport(CheckpointWriter& w, const StepReport& s) {
  w.i32(s.solve.iterations);
  w.f64(s.solve.relative_residual);
  w.u8(s.solve.converged);
  w.u8(s.solve.breakdown);
  w.u8(s.solve.breakdown_reason != nullptr);
  w.str(s.solve.breakdown_reason != nullptr ? s.solve.breakdown_reason : "");
  w.f64(s.elastic_energy);
  w.f64(s.kinetic_energy);
  w.f64(s.max_speed);
  w.u8(static_cast<int>(s.health));
  w.str(s.message);
}

StepReport readReport(CheckpointReader& r) {
  StepReport s;
  s.solve.iterations = r.i32();
  s.solve.relative_residual = r.f64();
  s.solve.converged = r.u8() != 0;
  s.solve.breakdown = r.u8() != 0;
  const bool has_reason = r.u8() != 0;
  const std::string reason = r.str();
  if (has_reason && r.ok()) s.solve.breakdown_reason = internReason(reason);
  s.elastic_energy = r.f64();
  s.kinetic_energy = r.f64();
  s.max_speed = r.f64();
  s.health = r.enumeration(StepHealth::kBlowUp);
  s.message = r.str();
  return s;
}

void writeHand(CheckpointWriter& w, const Hand& hand, const HandCheckpoint& c) {
  w.str(hand.name());
  w.str(hand.body().name());
  writeFrame(w, c.values.goal);
  writeFrame(w, c.values.patch);
  for (double v : {c.values.time, c.values.max_speed, c.values.reach, c.speed_limit})
    w.f64(v);
  const HandSelection& s = c.selection;
  w.u8(static_cast<int>(s.status));
  w.str(s.message);
  w.i32(s.cut_triangle_count);
  w.i32(s.hit_triangle);
  w.f64(s.hit_distance);
  w.vec3(s.hit_point);
  w.ints(s.triangles);
  w.ints(s.nodes);
  w.i32(c.group);
}

HandCheckpoint readHand(CheckpointReader& r) {
  HandCheckpoint c;
  c.values.goal = readFrame(r);
  c.values.patch = readFrame(r);
  c.values.time = r.f64();
  c.values.max_speed = r.f64();
  c.values.reach = r.f64();
  c.speed_limit = r.f64();
  HandSelection& s = c.selection;
  s.status = r.enumeration(HandSelectionStatus::kRayMissed);
  s.message = r.str();
  s.cut_triangle_count = r.i32();
  s.hit_triangle = r.i32();
  s.hit_distance = r.f64();
  s.hit_point = r.vec3();
  s.triangles = r.ints();
  s.nodes = r.ints();
  c.group = r.i32();
  c.pursuit = std::make_shared<HandPursuit>(c.values);
  return c;
}

void writeBody(CheckpointWriter& w, const FemBody& body, const FemBodyCheckpoint& c,
               const std::vector<Hand*>& hands,
               const std::vector<HandCheckpoint>& hand_checkpoints) {
  const FemModel& model = *c.model;
  w.str(body.name());
  w.u32(static_cast<size_t>(model.nodeCount()));
  w.u32(static_cast<size_t>(model.elementCount()));
  w.u8(static_cast<int>(model.elementKind()));
  w.raw(meshHash(model));
  writeMaterial(w, model.material());

  w.vector(c.state.positions);
  w.vector(c.state.velocities);
  w.u32(c.state.element_rotations.size());
  for (const Eigen::Quaterniond& q : c.state.element_rotations) {
    for (double v : {q.x(), q.y(), q.z(), q.w()})
      w.f64(v);
  }
  w.vector(c.external_forces);
  w.vector(c.stepper.previous_velocities);
  w.vector(c.stepper.velocity_next);
  w.vector(c.stepper.elastic_forces);
  w.vector(c.stepper.internal_forces);
  w.f64(c.stepper.last_dt);

  w.u32(c.groups.size());
  for (size_t g = 0; g < c.groups.size(); ++g) {
    const CarriedNodes& group = c.groups[g];
    w.str(group.name());
    w.ints(group.nodes());
    w.u32(group.localCoordinates().size());
    for (const Eigen::Vector3d& p : group.localCoordinates())
      w.vec3(p);
    GroupMotion motion = group.nodes().empty() ? GroupMotion::kNone : GroupMotion::kWorldGroup;
    size_t owner = 0;
    for (size_t h = 0; h < hands.size(); ++h) {
      if (&hands[h]->body() == &body && hand_checkpoints[h].group == static_cast<int>(g)) {
        motion = GroupMotion::kHand;
        owner = h;
      }
    }
    w.u8(static_cast<int>(motion));
    w.u32(owner);
  }

  w.str(c.contacts);
  w.u8(c.self_contact);
  const SelfContactSettings& s = c.self_contact_settings;
  for (double v : {s.friction, s.gap_tolerance, s.margin, s.max_depth})
    w.f64(v);
  writeReport(w, c.last_report);
}

// "1 hand", "2 hands", "none".
std::string counted(size_t n, const std::string& one, const std::string& many = "") {
  if (n == 0) return "none";
  if (n == 1) return "1 " + one;
  return std::to_string(n) + " " + (many.empty() ? one + "s" : many);
}

// ": 'a', 'b'" (nothing for an empty list): the parts a message names.
std::string listed(const std::vector<std::string>& parts) {
  std::string out;
  for (const std::string& part : parts)
    out += (out.empty() ? ": " : ", ") + part;
  return out;
}

std::string anotherWorld(const std::string& why) {
  return "the checkpoint was saved from another world: " + why;
}

// The node groups of `body`'s section into `c` (c.model set): their motions are code, not data,
// taken from the group of the world at the same index or the hand that holds it.
Status readGroups(CheckpointReader& r, FemBody& body, const std::vector<Hand*>& hands,
                  const std::vector<HandCheckpoint>& hand_checkpoints, FemBodyCheckpoint& c) {
  const int node_count = c.model->nodeCount();
  const size_t group_count = r.count(4);
  for (size_t g = 0; g < group_count && r.ok(); ++g) {
    std::string name = r.str();
    std::vector<int> group_nodes = r.ints();
    std::vector<Eigen::Vector3d> local(r.count(24));
    for (Eigen::Vector3d& p : local)
      p = r.vec3();
    const auto motion = r.enumeration(GroupMotion::kNone);
    const size_t owner = r.u32();
    if (!r.ok()) break;
    for (int node : group_nodes) {
      if (node < 0 || node >= node_count || local.size() != group_nodes.size())
        return Error{"the checkpoint is corrupted: node group '" + name + "' is out of range"};
    }
    FrameMotion follow = [](double) { return Frame{}; };
    if (motion == GroupMotion::kWorldGroup) {
      if (g >= body.groups().size() || body.groups()[g]->name() != name) {
        return Error{anotherWorld("body '" + body.name() + "' has no node group '" + name +
                                  "' at index " + std::to_string(g))};
      }
      follow = body.groups()[g]->motion();
    } else if (motion == GroupMotion::kHand) {
      if (owner >= hands.size() || &hands[owner]->body() != &body)
        return Error{anotherWorld("node group '" + name + "' belongs to no hand of this world")};
      follow = followPursuit(hand_checkpoints[owner].pursuit);
    }
    c.groups.emplace_back(std::move(name), std::move(group_nodes), std::move(local),
                          std::move(follow));
  }
  return r.status();
}

// Reads one body's checkpoint onto `body` of the world being restored (its current checkpoint
// `now` gives what the format does not store: the constants of its material and self-contact
// that no live edit changes).
// The format's body section, read field by field in the order writeBody writes it.
Result<FemBodyCheckpoint> readBody(CheckpointReader& r, FemBody& body,
                                   const std::vector<Hand*>& hands,
                                   const std::vector<HandCheckpoint>& hand_checkpoints) {
  FemBodyCheckpoint now = body.checkpoint();
  const FemModel& model = *now.model;
  const size_t nodes = r.u32(), elements = r.u32();
  const auto kind = r.enumeration(ElementKind::kTet10);
  const auto hash = r.raw<std::uint64_t>();
  Material material = readMaterial(r);
  // The format does not store the volume barrier's constants (live edits do not change them):
  // they stay the body's own.
  material.barrier_threshold = model.material().barrier_threshold;
  material.barrier_stiffness = model.material().barrier_stiffness;
  // Nor the constitutive law (no live edit changes it).
  material.law = model.material().law;
  material.mooney_rivlin_c2_fraction = model.material().mooney_rivlin_c2_fraction;
  if (!r.ok()) return r.error();
  if (nodes != static_cast<size_t>(model.nodeCount()) ||
      elements != static_cast<size_t>(model.elementCount()) || kind != model.elementKind() ||
      hash != meshHash(model)) {
    return Error{anotherWorld("body '" + body.name() + "' has another mesh (" +
                              std::to_string(nodes) + " nodes, " + std::to_string(elements) +
                              " elements in the checkpoint; " + std::to_string(model.nodeCount()) +
                              ", " + std::to_string(model.elementCount()) + " here)")};
  }
  FemBodyCheckpoint c;
  if (sameMaterial(material, model.material())) {
    c.model = now.model;
  } else {
    Result<std::shared_ptr<const FemModel>> edited = model.withMaterial(material);
    if (!edited) return Error{"the checkpoint is corrupted: " + edited.error().message};
    c.model = std::move(edited).value();
  }

  const Eigen::Index dofs = 3 * model.nodeCount();
  c.state.positions = r.vector();
  c.state.velocities = r.vector();
  c.state.element_rotations.resize(r.count(32));
  for (Eigen::Quaterniond& q : c.state.element_rotations) {
    const double x = r.f64(), y = r.f64(), z = r.f64(), w = r.f64();
    q = Eigen::Quaterniond(w, x, y, z);
  }
  c.external_forces = r.vector();
  c.stepper.previous_velocities = r.vector();
  c.stepper.velocity_next = r.vector();
  c.stepper.elastic_forces = r.vector();
  c.stepper.internal_forces = r.vector();
  c.stepper.last_dt = r.f64();
  // Sizes the solver indexes by: wrong ones would read out of bounds. The stepper's memory is
  // empty before a body's first step.
  auto dofsOrEmpty = [dofs](const Eigen::VectorXd& v) { return v.size() == dofs || v.size() == 0; };
  if (!r.ok() || c.state.positions.size() != dofs || c.state.velocities.size() != dofs ||
      c.external_forces.size() != dofs ||
      c.state.element_rotations.size() != now.state.element_rotations.size() ||
      !dofsOrEmpty(c.stepper.previous_velocities) || !dofsOrEmpty(c.stepper.velocity_next) ||
      !dofsOrEmpty(c.stepper.elastic_forces) || !dofsOrEmpty(c.stepper.internal_forces)) {
    return r.error();
  }

  if (Status groups = readGroups(r, body, hands, hand_checkpoints, c); !groups)
    return groups.error();

  c.contacts = r.str();
  c.self_contact = r.u8() != 0;
  SelfContactSettings& s = c.self_contact_settings;
  // What the format does not store (thickness_factor, search_skin: they
  // do not change between saving and restoring a run) stays the body's own.
  s = now.self_contact_settings;
  s.friction = r.f64();
  s.gap_tolerance = r.f64();
  s.margin = r.f64();
  s.max_depth = r.f64();
  c.last_report = readReport(r);
  if (!r.ok()) return r.error();
  if (Status contacts = body.checkRestore(c); !contacts) return contacts.error();
  return c;
}

// The payload after a checked header, or why there is none.
Result<std::string_view> payloadOf(std::string_view bytes) {
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
    return Error{"not a torsion checkpoint (its first bytes are not \"TRSNCKPT\")"};
  CheckpointReader header(bytes.substr(sizeof(kMagic)));
  const size_t version = header.u32();
  const auto length = header.raw<std::uint64_t>();
  const auto hash = header.raw<std::uint64_t>();
  if (!header.ok()) return Error{"the checkpoint is truncated: its header is incomplete"};
  if (version != kVersion) {
    return Error{"the checkpoint has format version " + std::to_string(version) +
                 "; this build reads version " + std::to_string(kVersion)};
  }
  if (length != bytes.size() - kHeaderSize) {
    return Error{"the checkpoint is truncated or padded: its header says " +
                 std::to_string(length) + " bytes follow, " +
                 std::to_string(bytes.size() - kHeaderSize) + " do"};
  }
  const std::string_view payload = bytes.substr(kHeaderSize);
  if (fnv1a(payload) != hash) return Error{"the checkpoint is corrupted: its hash does not match"};
  return payload;
}

}  // namespace

// The checkpoint names the world's rigid objects by index already (FemBodyCheckpoint::contacts):
// `world` is not read.
std::string writeCheckpoint(FemWorld& /*world*/, const WorldCheckpoint& checkpoint,
                            const std::vector<Hand*>& hands,
                            const std::vector<HandCheckpoint>& hand_checkpoints,
                            std::string_view extra) {
  CheckpointWriter w;
  const FemCheckpoint& fem = checkpoint.fem;
  w.f64(fem.time);
  w.i64(fem.steps);
  w.f64(fem.last_dt);
  w.u8(fem.status.ok);
  w.i64(fem.status.failed_step);
  w.str(fem.status.message);

  w.u32(hands.size());
  for (size_t h = 0; h < hands.size(); ++h)
    writeHand(w, *hands[h], hand_checkpoints[h]);

  w.u32(fem.bodies.size());
  for (const auto& [body, saved] : fem.bodies)
    writeBody(w, *body, saved, hands, hand_checkpoints);

  w.u32(fem.fem_pairs.size());
  for (const FemPairCheckpoint& pair : fem.fem_pairs) {
    w.str(pair.a->name());
    w.str(pair.b->name());
    w.str(pair.multipliers);
  }

  w.u32(checkpoint.rigid.size());
  for (const WorldCheckpoint::RigidState& r : checkpoint.rigid) {
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col)
        w.f64(static_cast<double>(r.pose.getBasis()[row][col]));
    }
    for (const btVector3* v : {&r.pose.getOrigin(), &r.linear_velocity, &r.angular_velocity}) {
      for (int k = 0; k < 3; ++k)
        w.f64(static_cast<double>((*v)[k]));
    }
  }
  w.str(extra);

  CheckpointWriter out;
  out.bytes().append(kMagic, sizeof(kMagic));
  out.raw(kVersion);
  out.raw(static_cast<std::uint64_t>(w.bytes().size()));
  out.raw(fnv1a(w.bytes()));
  out.bytes() += w.bytes();
  return std::move(out.bytes());
}

Result<double> checkpointTime(std::string_view bytes) {
  Result<std::string_view> payload = payloadOf(bytes);
  if (!payload) return payload.error();
  CheckpointReader r(payload.value());
  const double time = r.f64();
  if (!r.ok()) return Error{"the checkpoint is truncated: it holds no clock"};
  return time;
}

namespace {

// The clock as a run leaves it: a finite time and last step, counts that are not negative, and a
// failure (if any) at most one step past the clock (a substep that failed in collision detection
// is not counted).
void checkClock(const FemCheckpoint& fem, CheckpointReader& r) {
  if (!r.ok()) return;
  if (!(std::isfinite(fem.time) && fem.time >= 0 && std::isfinite(fem.last_dt) &&
        fem.last_dt >= 0 && fem.steps >= 0))
    r.refuse("the clock (time " + formatNumber(fem.time) + " s, " + std::to_string(fem.steps) +
             " steps, last step " + formatNumber(fem.last_dt) + " s)");
  else if (fem.status.failed_step < 0 || fem.status.failed_step > fem.steps + 1 ||
           fem.status.ok != (fem.status.failed_step == 0))
    r.refuse("the health (failed step " + std::to_string(fem.status.failed_step) + " of " +
             std::to_string(fem.steps) + ")");
}

// A rigid body's pose as Bullet keeps one: finite, its basis a rotation (to float Bullet's
// rounding when saved from a float world).
void checkRigidPose(const btMatrix3x3& basis, const btVector3 (&v)[3], CheckpointReader& r) {
  if (!r.ok()) return;
  bool finite = true;
  for (int row = 0; row < 3; ++row) {
    for (int k = 0; k < 3; ++k) {
      finite = finite && std::isfinite(static_cast<double>(basis[row][k])) &&
               std::isfinite(static_cast<double>(v[row][k]));
    }
  }
  const btMatrix3x3 product = basis * basis.transpose();
  double off_identity = 0;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col)
      off_identity = std::max(off_identity, std::abs(static_cast<double>(product[row][col]) -
                                                     (row == col ? 1.0 : 0.0)));
  }
  if (!finite || !(off_identity <= 1e-5) || !(basis.determinant() > 0))
    r.refuse("a rigid body's pose or velocity (not finite, or a basis that is not a rotation)");
}

// Refuses the bytes while the hands of the checkpoint are not those of this world, naming both.
Status checkHandCount(CheckpointReader& r, size_t hand_count, const std::vector<Hand*>& hands) {
  if (hand_count == hands.size()) return Ok{};
  std::vector<std::string> here;
  here.reserve(hands.size());
  for (const Hand* hand : hands)
    here.push_back("'" + hand->name() + "' on body '" + hand->body().name() + "'");
  // A hand's record starts with its name and body's: the first can be read (the others lie
  // behind its data).
  std::string first;
  if (hand_count > 0) {
    CheckpointReader peek = r;
    const std::string name = peek.str(), body = peek.str();
    if (peek.ok()) first = " (the first '" + name + "' on body '" + body + "')";
  }
  return Error{anotherWorld("it has " +
                            (hand_count == 0 ? "no hand" : counted(hand_count, "hand")) + first +
                            ", this world " + counted(hands.size(), "hand") + listed(here))};
}

Status readHands(CheckpointReader& r, const std::vector<Hand*>& hands, StoredCheckpoint& stored) {
  r.section("the hands");
  const size_t hand_count = r.count(8);
  if (!r.ok()) return r.error();
  if (Status same = checkHandCount(r, hand_count, hands); !same) return same;
  for (size_t h = 0; h < hand_count; ++h) {
    r.section("hand " + std::to_string(h));
    const std::string name = r.str(), body = r.str();
    if (!r.ok()) return r.error();
    if (name != hands[h]->name() || body != hands[h]->body().name()) {
      std::string difference = "its hand " + std::to_string(h) + " is '";
      difference += name;
      difference += "' on body '";
      difference += body;
      difference += "', here '";
      difference += hands[h]->name();
      difference += "' on body '";
      difference += hands[h]->body().name();
      difference += "'";
      return Error{anotherWorld(difference)};
    }
    r.section("hand '" + name + "'");
    stored.hands.push_back(readHand(r));
    const HandSelection& s = stored.hands.back().selection;
    const TetMesh& mesh = hands[h]->body().model().mesh();
    const bool in_range =
        std::all_of(s.nodes.begin(), s.nodes.end(),
                    [&](int n) { return n >= 0 && n < mesh.nodeCount(); }) &&
        std::all_of(s.triangles.begin(), s.triangles.end(), [&](int t) {
          return t >= 0 && static_cast<size_t>(t) < mesh.surfaceTriangles().size();
        });
    if (!in_range) r.fail();
    if (!r.ok()) return r.error();
  }
  return Ok{};
}

// After the bodies: refuses a world with bodies the checkpoint lacks, naming them.
Status checkEveryBodyRead(CheckpointReader& r, size_t body_count, const FemWorld& world,
                          const FemCheckpoint& fem) {
  if (body_count == world.bodies().size()) return Ok{};
  std::vector<std::string> unsaved, saved;
  for (const auto& body : world.bodies()) {
    const bool in_checkpoint =
        std::any_of(fem.bodies.begin(), fem.bodies.end(),
                    [&body](const auto& entry) { return entry.first == body.get(); });
    (in_checkpoint ? saved : unsaved).push_back("'" + body->name() + "'");
  }
  if (unsaved.empty()) {  // a body saved twice
    r.fail();
    return r.error();
  }
  if (body_count == 0)
    return Error{anotherWorld("it has no FEM body, this world " + listed(unsaved).substr(2))};
  return Error{anotherWorld("it has " + counted(body_count, "FEM body", "FEM bodies") +
                            listed(saved) + "; this world also has " + listed(unsaved).substr(2))};
}

Status readBodies(CheckpointReader& r, FemWorld& world, const std::vector<Hand*>& hands,
                  StoredCheckpoint& stored) {
  FemCheckpoint& fem = stored.world.fem;
  r.section("the FEM bodies");
  const size_t body_count = r.count(8);
  if (!r.ok()) return r.error();
  std::vector<std::string> names_here;
  names_here.reserve(world.bodies().size());
  for (const auto& body : world.bodies())
    names_here.push_back("'" + body->name() + "'");
  // Matched by name, each read onto its body here (a record cannot be skipped unread): a saved
  // body missing here is named when it comes, bodies here that were not saved at the end.
  for (size_t b = 0; b < body_count; ++b) {
    r.section("FEM body " + std::to_string(b));
    const std::string name = r.str();
    if (!r.ok()) return r.error();
    FemBody* body = world.body(name);
    if (body == nullptr) {
      return Error{anotherWorld("its body '" + name + "' is not in this world (" +
                                counted(world.bodies().size(), "FEM body", "FEM bodies") +
                                listed(names_here) + ")")};
    }
    r.section("body '" + name + "'");
    Result<FemBodyCheckpoint> saved = readBody(r, *body, hands, stored.hands);
    if (!saved) return saved.error();
    fem.bodies.emplace_back(body, std::move(saved).value());
  }
  if (Status all = checkEveryBodyRead(r, body_count, world, fem); !all) return all;
  // A hand's group indexes its body's groups (its wrench reads it).
  for (size_t h = 0; h < hands.size(); ++h) {
    const int group = stored.hands[h].group;
    for (const auto& [body, saved] : fem.bodies) {
      if (body == &hands[h]->body() &&
          (group < -1 || group >= static_cast<int>(saved.groups.size()))) {
        r.section("hand '" + hands[h]->name() + "'");
        r.fail();
      }
    }
  }
  return r.status();
}

Status readPairs(CheckpointReader& r, FemWorld& world, FemCheckpoint& fem) {
  r.section("the FEM pairs");
  const size_t pair_count = r.count(16);
  if (!r.ok()) return r.error();
  for (size_t p = 0; p < pair_count; ++p) {
    r.section("FEM pair " + std::to_string(p));
    FemPairCheckpoint pair;
    const std::string a = r.str(), b = r.str();
    if (!r.ok()) return r.error();
    pair.a = world.body(a);
    pair.b = world.body(b);
    if (pair.a == nullptr || pair.b == nullptr)
      return Error{anotherWorld("this world has no body '" + (pair.a == nullptr ? a : b) + "'")};
    pair.multipliers = r.str();
    if (!r.ok()) return r.error();
    fem.fem_pairs.push_back(std::move(pair));
  }
  return FemContactIslands::checkRestore(fem.fem_pairs);
}

Status readRigidBodies(CheckpointReader& r, const FemWorld& world, WorldCheckpoint& saved) {
  r.section("the rigid bodies");
  const size_t rigid_count = r.count(18 * 8);
  if (!r.ok()) return r.error();
  if (rigid_count != world.rigidBodies().size()) {
    return Error{anotherWorld("it has " + std::to_string(rigid_count) +
                              " rigid bodies, this world " +
                              std::to_string(world.rigidBodies().size()))};
  }
  saved.rigid.resize(rigid_count);
  for (WorldCheckpoint::RigidState& rigid : saved.rigid) {
    btMatrix3x3 basis;
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col)
        basis[row][col] = static_cast<btScalar>(r.f64());
    }
    btVector3 v[3];
    for (btVector3& vector : v) {
      for (int k = 0; k < 3; ++k)
        vector[k] = static_cast<btScalar>(r.f64());
    }
    checkRigidPose(basis, v, r);
    rigid.pose = btTransform(basis, v[0]);
    rigid.linear_velocity = v[1];
    rigid.angular_velocity = v[2];
  }
  return r.status();
}

}  // namespace

// The format's sections in their order, each refused naming the value it holds.
Result<StoredCheckpoint> readCheckpoint(std::string_view bytes, FemWorld& world,
                                        const std::vector<Hand*>& hands) {
  Result<std::string_view> payload = payloadOf(bytes);
  if (!payload) return payload.error();
  CheckpointReader r(payload.value());
  StoredCheckpoint stored;
  FemCheckpoint& fem = stored.world.fem;
  r.section("the clock");
  fem.time = r.f64();
  fem.steps = r.i64();
  fem.last_dt = r.f64();
  fem.status.ok = r.u8() != 0;
  fem.status.failed_step = r.i64();
  fem.status.message = r.str();
  checkClock(fem, r);
  if (!r.ok()) return r.error();
  if (Status read = readHands(r, hands, stored); !read) return read.error();
  if (Status read = readBodies(r, world, hands, stored); !read) return read.error();
  if (Status read = readPairs(r, world, fem); !read) return read.error();
  if (Status read = readRigidBodies(r, world, stored.world); !read) return read.error();
  r.section("the caller's extra bytes");
  stored.extra = r.str();
  if (r.ok() && !r.atEnd()) r.fail();
  if (!r.ok()) return r.error();
  return stored;
}

}  // namespace torsion
