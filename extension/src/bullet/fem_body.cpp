#include "torsion/bullet/fem_body.h"

#include <algorithm>
#include <cassert>

#include "torsion/bt_conversions.h"
namespace torsion {

FemBody::FemBody(std::string name, std::shared_ptr<const FemModel> model,
                 const SolverSettings& settings, const Parallel& parallel,
                 btSoftBodyWorldInfo& world_info, const btCollisionObjectArray& world_objects,
                 InputNumbering input_numbering)
    : name_(std::move(name)),
      model_(std::move(model)),
      state_(FemState::atRest(*model_)),
      parallel_(parallel),
      stepper_(model_, settings, parallel),
      constraints_(model_->nodeCount()),
      external_forces_(Eigen::VectorXd::Zero(3 * model_->nodeCount())),
      world_objects_(world_objects),
      input_numbering_(std::move(input_numbering)) {
  const int n = model_->nodeCount();
  std::vector<btVector3> x(static_cast<size_t>(n));
  std::vector<btScalar> m(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    x[static_cast<size_t>(i)] = toBt(state_.position(i));
    m[static_cast<size_t>(i)] = toBtScalar(model_->nodeMasses()[static_cast<size_t>(i)]);
  }
  // Nodes and surface faces only: our solver never uses Bullet's links, and soft-rigid contact
  // (SDF_RS) is node-based. No VF_SS/SDF_RD flags: without links their tree build would hang.
  // For tet10 bodies the nodes are all P2 nodes and the faces the split surface triangles.
  soft_body_ = std::make_unique<btSoftBody>(&world_info, n, x.data(), m.data());
  for (const Triangle& tri : model_->mesh().surfaceTriangles()) {
    soft_body_->appendFace(tri[0], tri[1], tri[2]);
  }
  soft_body_->m_cfg.collisions = btSoftBody::fCollision::SDF_RS;
  const Eigen::Vector3d extent = model_->mesh().boundsMax() - model_->mesh().boundsMin();
  soft_body_->getCollisionShape()->setMargin(toBtScalar(1e-3 * extent.norm()));
  soft_body_->setActivationState(DISABLE_DEACTIVATION);
  soft_body_->updateNodeTree(false, false);
  soft_body_->updateBounds();
  soft_body_->updateNormals();
  contacts_ = std::make_unique<RigidContactSolver>(model_, soft_body_.get());
  writeBack();  // the input-numbered copy of the state
}

FemBody::~FemBody() = default;

int FemBody::carryNodes(std::string group_name, std::vector<int> nodes, FrameMotion motion,
                        double now) {
  groups_.push_back(std::make_unique<CarriedNodes>(std::move(group_name), std::move(nodes),
                                                   std::move(motion), state_, now));
  return static_cast<int>(groups_.size()) - 1;
}

void FemBody::releaseGroup(int group) {
  auto& g = groups_[static_cast<size_t>(group)];
  g = std::make_unique<CarriedNodes>(
      g->name(), std::vector<int>{}, [](double) { return Frame{}; }, state_, 0.0);
}

void FemBody::setGroupMotion(int group, FrameMotion motion) {
  CarriedNodes& g = *groups_[static_cast<size_t>(group)];
  if (!g.nodes().empty()) g.setMotion(std::move(motion));
}

Wrench FemBody::groupWrench(int group, const Eigen::Vector3d& point) {
  const CarriedNodes& carried = *groups_[static_cast<size_t>(group)];
  return carried.wrenchOn(stepper_.internalForcesAt(carried.nodes()), state_, point);
}

Result<int> FemBody::anchorNodes(std::vector<int> nodes, btCollisionObject* object) {
  const std::string where = "body '" + name_ + "': anchor: ";
  if (object == nullptr) return Error{where + "no object to anchor to"};
  if (nodes.empty()) return Error{where + "no nodes"};
  std::vector<char> listed(static_cast<size_t>(model_->nodeCount()), 0);
  for (int node : nodes) {
    if (node < 0 || node >= model_->nodeCount()) {
      return Error{where + "node " + std::to_string(node) + " out of range [0, " +
                   std::to_string(model_->nodeCount()) + ")"};
    }
    if (listed[static_cast<size_t>(node)]++)
      return Error{where + "node " + std::to_string(node) + " listed twice"};
    if (contacts_->anchors().anchored(node))
      return Error{where + "node " + std::to_string(node) + " is anchored already"};
  }
  return contacts_->addAnchor(object, std::move(nodes), state_);
}

Status FemBody::removeAnchor(int anchor) {
  const auto& anchors = contacts_->anchors().anchors();
  if (anchor < 0 || anchor >= static_cast<int>(anchors.size()) ||
      anchors[static_cast<size_t>(anchor)].object == nullptr) {
    return Error{"body '" + name_ + "': no anchor " + std::to_string(anchor)};
  }
  contacts_->removeAnchor(anchor);
  return Ok{};
}

std::vector<int> FemBody::anchorsOn(const btCollisionObject* object) const {
  std::vector<int> ids;
  const auto& anchors = contacts_->anchors().anchors();
  for (size_t k = 0; k < anchors.size(); ++k) {
    if (object != nullptr && anchors[k].object == object) ids.push_back(static_cast<int>(k));
  }
  return ids;
}

void FemBody::forgetObject(const btCollisionObject* object) {
  // What the next step takes over from the last names objects by pointer: a deleted object's
  // address could come back as another's. Going through the warm starts, as a checkpoint restore
  // does, rebuilds the solver's memory without it.
  CarriedContacts carried = contacts_->carriedContacts();
  bool named = false;
  for (const RigidPartner& partner : contacts_->partners())
    named = named || partner.object == object;
  const auto is_object = [object](const auto& entry) { return entry.object == object; };
  const size_t node_count = carried.nodes.size(), feature_count = carried.features.size();
  carried.nodes.erase(std::remove_if(carried.nodes.begin(), carried.nodes.end(), is_object),
                      carried.nodes.end());
  carried.features.erase(
      std::remove_if(carried.features.begin(), carried.features.end(), is_object),
      carried.features.end());
  named = named || carried.nodes.size() != node_count || carried.features.size() != feature_count;
  if (named) contacts_->restoreCarriedContacts(carried);
  soft_body_->m_rcontacts.resizeNoInitialize(0);
}

Status FemBody::setVelocity(const Eigen::Vector3d& velocity) {
  if (!velocity.allFinite()) return Error{"body '" + name_ + "': the velocity is not finite"};
  for (int i = 0; i < model_->nodeCount(); ++i)
    state_.velocities.segment<3>(3 * i) = velocity;
  writeBack();
  return Ok{};
}

Status FemBody::setRigidVelocity(const Eigen::Vector3d& linear, const Eigen::Vector3d& angular) {
  if (!(linear.allFinite() && angular.allFinite()))
    return Error{"body '" + name_ + "': the rigid velocity is not finite"};
  const std::vector<double>& masses = model_->nodeMasses();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int i = 0; i < model_->nodeCount(); ++i)
    centre += masses[static_cast<size_t>(i)] * state_.positions.segment<3>(3 * i);
  centre /= model_->totalMass();
  for (int i = 0; i < model_->nodeCount(); ++i)
    state_.velocities.segment<3>(3 * i) =
        linear + angular.cross(Eigen::Vector3d(state_.positions.segment<3>(3 * i)) - centre);
  writeBack();
  return Ok{};
}

Status FemBody::setExternalForces(const Eigen::VectorXd& forces) {
  if (forces.size() != external_forces_.size()) {
    return Error{"body '" + name_ + "': external forces have " + std::to_string(forces.size()) +
                 " components, the body has " + std::to_string(model_->nodeCount()) +
                 " nodes (3 each)"};
  }
  for (int i = 0; i < model_->nodeCount(); ++i) {
    if (!forces.segment<3>(3 * i).allFinite())
      return Error{"body '" + name_ + "': external force on node " + std::to_string(i) +
                   " is not finite"};
  }
  external_forces_ = forces;
  return Ok{};
}

Status FemBody::setNodeForce(int node, const Eigen::Vector3d& force) {
  if (node < 0 || node >= model_->nodeCount()) {
    return Error{"body '" + name_ + "': node " + std::to_string(node) + " out of range [0, " +
                 std::to_string(model_->nodeCount()) + ")"};
  }
  if (!force.allFinite())
    return Error{"body '" + name_ + "': external force on node " + std::to_string(node) +
                 " is not finite"};
  external_forces_.segment<3>(3 * node) = force;
  return Ok{};
}

Status FemBody::setMaterial(const Material& material) {
  Result<std::shared_ptr<const FemModel>> model = model_->withMaterial(material);
  if (!model) return Error{"body '" + name_ + "': " + model.error().message};
  model_ = std::move(model).value();
  stepper_.replaceModel(model_);
  contacts_->replaceModel(model_);  // gravity follows the new masses at the next step
  if (self_contact_) self_contact_->replaceModel(model_);
  for (int i = 0; i < model_->nodeCount(); ++i)
    soft_body_->m_nodes[i].m_im = toBtScalar(1 / model_->nodeMasses()[static_cast<size_t>(i)]);
  return Ok{};
}

void FemBody::predict(double dt, bool for_contact) {
  btSoftBody& sb = *soft_body_;
  sb.m_sst.sdt = toBtScalar(dt);
  sb.m_sst.isdt = toBtScalar(1 / dt);
  sb.m_sst.velmrg = toBtScalar(3 * dt);
  sb.m_sst.radmrg = sb.getCollisionShape()->getMargin();
  sb.m_sst.updmrg = sb.m_sst.radmrg / 4;
  for (int i = 0; i < model_->nodeCount(); ++i) {
    btSoftBody::Node& node = sb.m_nodes[i];
    node.m_q = toBt(state_.position(i));
    node.m_v = toBt(state_.velocity(i));
    node.m_x = toBt(state_.position(i) + dt * state_.velocity(i));
  }
  if (for_contact) sb.updateNodeTree(true, true);  // a refit: a function of m_x, m_v, dt only
  sb.updateBounds();
  sb.m_rcontacts.resizeNoInitialize(0);
  sb.m_scontacts.resizeNoInitialize(0);
  contacts_->beginStep(dt);
}

sap::FemIslandBody& FemBody::islandBody() {
  const PreparedSystem p = stepper_.prepared();
  if (island_body_ == nullptr) {
    island_body_ = std::make_unique<sap::FemIslandBody>(*p.op, *p.constraints, *p.b);
  } else {
    island_body_->beginStep(*p.b);
  }
  return *island_body_;
}

bool FemBody::prepare(const StepContext& ctx, bool touches_fem_bodies) {
  const double dt = ctx.dt;
  constraints_.reset(model_->nodeCount());
  for (const auto& group : groups_)
    group->prescribe(ctx.endTime(), dt, state_, constraints_);
  step_forces_ = external_forces_;
  for (int i = 0; i < model_->nodeCount(); ++i)
    step_forces_.segment<3>(3 * i) += model_->nodeMasses()[static_cast<size_t>(i)] * ctx.gravity;
  // Contacts with rigid bodies: unilateral constraints in the same projected solve.
  rigid_contact_ = contacts_->detect(state_, constraints_, dt, ctx.joints);
  // Self-contact: rows of the body's island; it looks again along the solved motion, candidates
  // or not.
  const bool self = self_contact_ != nullptr;
  if (self) self_contact_->detect(state_, constraints_, dt);
  last_report_ = stepper_.prepare(state_, constraints_, step_forces_, dt);
  if (isFatal(last_report_.health)) return false;
  if (model_->material().hyperelastic() && (rigid_contact_ || self || touches_fem_bodies)) {
    // The Newton solve finds the free motion; the island solves the contacts about it.
    const LinearSolveReport free = stepper_.linearizeAboutFreeMotion();
    if (free.breakdown || !stepper_.prepared().v->allFinite()) {
      last_report_.solve = free;
      last_report_.health = StepHealth::kSolverFailed;
      last_report_.message =
          std::string("the Newton solve of the free motion broke down") +
          (free.breakdown_reason ? std::string(": ") + free.breakdown_reason : std::string());
      return false;
    }
  }
  return true;
}

const StepReport& FemBody::finish(const Eigen::Ref<const Eigen::VectorXd>& velocities,
                                  const LinearSolveReport& solve) {
  last_report_.solve = solve;
  stepper_.finish(state_, velocities, last_report_);
  if (self_contact_ && !self_contact_->stats().converged && !isFatal(last_report_.health)) {
    // Reported per step, never accepted silently (a warning: the step is usable).
    const SelfContactStats& s = self_contact_->stats();
    if (last_report_.health == StepHealth::kOk)
      last_report_.health = StepHealth::kContactNotConverged;
    last_report_.message += (last_report_.message.empty() ? "" : "; ") +
                            std::string("self-contact did not converge in ") +
                            std::to_string(s.iterations) + " Newton iterations (end penetration " +
                            std::to_string(s.max_end_penetration) + " m, tolerance " +
                            std::to_string(self_contact_->gapTolerance()) + " m)";
  }
  if (!isFatal(last_report_.health)) contacts_->finish();
  if (!isFatal(last_report_.health)) writeBack();
  return last_report_;
}

void FemBody::noteContactNotConverged(const std::string& what) {
  if (last_report_.health == StepHealth::kOk)
    last_report_.health = StepHealth::kContactNotConverged;
  last_report_.message += (last_report_.message.empty() ? "" : "; ") + what;
}

Status FemBody::enableSelfContact(const SelfContactSettings& settings) {
  if (Status valid = settings.validate(); !valid)
    return Error{"body '" + name_ + "': " + valid.error().message};
  self_contact_ = std::make_unique<SelfContactSolver>(model_, settings, parallel_);
  return Ok{};
}

void FemBody::disableSelfContact() {
  self_contact_.reset();
}

FemBodyCheckpoint FemBody::checkpoint() {
  FemBodyCheckpoint c;
  c.model = model_;
  c.state = state_;
  c.external_forces = external_forces_;
  c.stepper = stepper_.memory();
  c.groups.reserve(groups_.size());
  for (const auto& group : groups_)
    c.groups.push_back(*group);
  CheckpointWriter contacts;
  contacts_->save(contacts);
  if (self_contact_) {
    c.self_contact = true;
    c.self_contact_settings = self_contact_->settings();
    self_contact_->set().save(contacts);
  }
  c.contacts = std::move(contacts.bytes());
  c.last_report = last_report_;
  return c;
}

Status FemBody::readContacts(const FemBodyCheckpoint& c, RigidContactSolver& rigid,
                             SurfaceContactSet* self) const {
  CheckpointReader in(c.contacts, &world_objects_);
  in.section("body '" + name_ + "': its rigid contacts");
  if (Status read = rigid.restore(in); !read) return read;
  if (c.self_contact) {
    in.section("body '" + name_ + "': its self-contact multipliers");
    if (Status read = self->restore(in); !read) return read;
  }
  if (!in.atEnd()) in.refuse("contact bytes that no part of the body reads");
  return in.status();
}

Status FemBody::checkRestore(const FemBodyCheckpoint& c) const {
  RigidContactSolver rigid(c.model, nullptr);
  SurfaceContactSet self;
  return readContacts(c, rigid, &self);
}

void FemBody::restore(const FemBodyCheckpoint& c) {
  if (c.model != model_) {
    model_ = c.model;
    stepper_.replaceModel(model_);
    contacts_->replaceModel(model_);
    for (int i = 0; i < model_->nodeCount(); ++i)
      soft_body_->m_nodes[i].m_im = toBtScalar(1 / model_->nodeMasses()[static_cast<size_t>(i)]);
  }
  state_ = c.state;
  external_forces_ = c.external_forces;
  stepper_.restore(c.stepper);
  groups_.clear();
  for (const CarriedNodes& group : c.groups)
    groups_.push_back(std::make_unique<CarriedNodes>(group));
  self_contact_.reset();
  if (c.self_contact)
    self_contact_ = std::make_unique<SelfContactSolver>(model_, c.self_contact_settings, parallel_);
  // Bytes that would not pass checkRestore (edited by hand) leave the part that does not read as
  // it was (a new self-contact cold); nothing reads past their end.
  const Status read = readContacts(c, *contacts_, self_contact_ ? &self_contact_->set() : nullptr);
  assert(read.ok());
  (void)read;
  last_report_ = c.last_report;
  writeBack();
}

void FemBody::refreshSurface() {
  // Normals every step: a program of the user's may draw the body from Bullet's nodes.
  soft_body_->updateNormals();
  soft_body_->updateBounds();
}

void FemBody::writeBack() {
  btSoftBody& sb = *soft_body_;
  for (int i = 0; i < model_->nodeCount(); ++i) {
    sb.m_nodes[i].m_x = toBt(state_.position(i));
    sb.m_nodes[i].m_v = toBt(state_.velocity(i));
  }
  if (input_numbering_.identity()) return;
  input_positions_.resize(state_.positions.size());  // no reallocation: the addresses stay
  input_velocities_.resize(state_.velocities.size());
  for (int i = 0; i < model_->nodeCount(); ++i) {
    const int to = 3 * input_numbering_.inputNode(i);
    input_positions_.segment<3>(to) = state_.positions.segment<3>(3 * i);
    input_velocities_.segment<3>(to) = state_.velocities.segment<3>(3 * i);
  }
}

}  // namespace torsion
