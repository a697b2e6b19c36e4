#pragma once
// A FEM slab in a SAP island for the preconditioner tests and bench_sap_precond: its bottom nodes
// on the ground z = 0 (one row each) and, on its top, a rigid box resting on four top nodes (four
// rows of two terms: the node, side A, and the box's corner, side B). One step from rest under
// gravity (dt = 1 ms unless set): b = M v0 + dt M g (no strain yet). gtest-free.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "torsion/contact/solve/fem_island_body.h"
#include "torsion/contact/solve/sap_problem.h"
#include "torsion/fem/fem_model.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/node_constraints.h"
#include "torsion/solve/parallel.h"
#include "torsion/solve/system_operator.h"

namespace torsion::sap::test {

struct SlabSpec {
  Eigen::Vector3d size = Eigen::Vector3d(0.4, 0.1, 0.1);  // m, from the origin
  int nx = 8, ny = 2, nz = 2;                             // cells
  double youngs_modulus = 1e8;                            // Pa
  bool ground = true;                                     // bottom nodes on z = 0
  bool box = true;                                        // rigid box on the top
  double box_mass = 2;                                    // kg
  double mu = 0.5;
  double dt = 1e-3;               // s
  int max_ground_rows = 1 << 30;  // the first this many bottom nodes only
};

class SlabScene {
 public:
  explicit SlabScene(const SlabSpec& spec) : spec_(spec), parallel_(1) {
    auto mesh = std::make_shared<const TetMesh>(
        makeBoxTetMesh(Eigen::Vector3d::Zero(), spec.size, spec.nx, spec.ny, spec.nz).value());
    Material material;
    material.youngs_modulus = spec.youngs_modulus;
    material.density = 1000;
    material.stiffness_damping = 0.01;
    model_ = FemModel::create(mesh, material).value();
    system_ = std::make_unique<SystemOperator>(model_, parallel_);
    const double dt = spec.dt;
    system_->setCoefficients(1.0, dt * dt + dt * material.stiffness_damping);
    constraints_ = std::make_unique<NodeConstraints>(model_->nodeCount());
    const int n = model_->nodeCount();
    b_.setZero(3 * n);
    for (int i = 0; i < n; ++i)
      b_(3 * i + 2) = -dt * 9.81 * model_->nodeMasses()[static_cast<size_t>(i)];
    makeRows();
  }

  double dt() const { return spec_.dt; }
  int nodeCount() const { return model_->nodeCount(); }
  int tetCount() const { return model_->mesh().tetCount(); }
  const SystemOperator& system() const { return *system_; }
  NodeConstraints& constraints() { return *constraints_; }
  const Eigen::VectorXd& momentum() const { return b_; }
  const std::vector<ContactRow>& rows() const { return rows_; }

  /// The box's rigid body (twist about its centre, 6 dofs), at rest under gravity.
  RigidBody boxBody() const {
    const double m = spec_.box_mass;
    Eigen::VectorXd b = Eigen::VectorXd::Zero(6);
    b(2) = -spec_.dt * 9.81 * m;
    return RigidBody(m, m / 6 * box_half_ * box_half_ * 4 * Eigen::Matrix3d::Identity(), b);
  }

  /// The island: the slab (body 0) and, with a box, the box (body 1).
  SapProblem problem(const FemIslandBody& slab, const RigidBody& box) const {
    std::vector<const IslandBody*> bodies{&slab};
    if (spec_.box) bodies.push_back(&box);
    return SapProblem::create(bodies, rows_, spec_.dt).value();
  }

 private:
  void makeRows() {
    const Eigen::Matrix3d frame = contactFrame(Eigen::Vector3d::UnitZ());
    const std::vector<Eigen::Vector3d>& rest = model_->mesh().restPositions();
    auto row_with = [&](ContactTerm term) {
      ContactRow row;
      row.frame = frame;
      row.terms.push_back(std::move(term));
      row.mu = spec_.mu;
      row.stiffness = 1e6;
      row.dissipation_time = 2e-3;
      return row;
    };
    int ground_rows = 0;
    for (int i = 0; i < nodeCount() && spec_.ground; ++i) {
      if (rest[static_cast<size_t>(i)].z() > 1e-9 || ground_rows >= spec_.max_ground_rows) continue;
      rows_.push_back(row_with(nodeTerm(0, i, 1.0, frame)));
      ++ground_rows;
    }
    if (!spec_.box) return;
    // The box (a cube of half the slab's smaller side) centred over the top face's middle; a row
    // at each top node nearest one of its bottom corners.
    box_half_ = 0.25 * std::min(spec_.size.x(), spec_.size.y());
    const Eigen::Vector3d centre(0.5 * spec_.size.x(), 0.5 * spec_.size.y(),
                                 spec_.size.z() + box_half_);
    for (int sx : {-1, 1})
      for (int sy : {-1, 1}) {
        const Eigen::Vector3d corner =
            centre + Eigen::Vector3d(sx * box_half_, sy * box_half_, -box_half_);
        int nearest = 0;
        for (int i = 1; i < nodeCount(); ++i)
          if ((rest[static_cast<size_t>(i)] - corner).norm() <
              (rest[static_cast<size_t>(nearest)] - corner).norm())
            nearest = i;
        ContactRow row = row_with(nodeTerm(0, nearest, -1.0, frame));
        row.terms.push_back(rigidPointTerm(1, corner - centre, 1.0, frame));
        rows_.push_back(row);
      }
  }

  SlabSpec spec_;
  Parallel parallel_;
  std::shared_ptr<const FemModel> model_;
  std::unique_ptr<SystemOperator> system_;
  std::unique_ptr<NodeConstraints> constraints_;
  Eigen::VectorXd b_;
  std::vector<ContactRow> rows_;
  double box_half_ = 0;
};

}  // namespace torsion::sap::test
