#include "torsion/solve/system_operator.h"

#include "torsion/fem/corotated_element.h"

namespace torsion {

namespace {
constexpr int kTetGrain = 512;
constexpr int kNodeGrain = 512;
}  // namespace

SystemOperator::SystemOperator(std::shared_ptr<const FemModel> model, const Parallel& parallel)
    : model_(std::move(model)), parallel_(parallel) {
  const TetMesh& mesh = model_->mesh();
  rotations_.assign(static_cast<size_t>(mesh.tetCount()), Eigen::Matrix3d::Identity());
  tet_scratch_.resize(static_cast<size_t>(mesh.tetCount()));
  const CompressedRows& node_tets = mesh.nodeTets();
  node_offsets_ = node_tets.offsets;
  node_entries_.resize(node_tets.items.size());
  for (int n = 0; n < mesh.nodeCount(); ++n) {
    for (int k = node_tets.rowBegin(n); k < node_tets.rowEnd(n); ++k) {
      const int t = node_tets.items[static_cast<size_t>(k)];
      const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
      int local = 0;
      while (tet[static_cast<size_t>(local)] != n)
        ++local;
      node_entries_[static_cast<size_t>(k)] = 4 * t + local;
    }
  }
}

void SystemOperator::setCoefficients(double mass_coefficient, double stiffness_coefficient) {
  mass_coefficient_ = mass_coefficient;
  stiffness_coefficient_ = stiffness_coefficient;
}

void SystemOperator::apply(const Eigen::VectorXd& y, Eigen::VectorXd& out, double mass_scale,
                           double stiffness_scale) const {
  const TetMesh& mesh = model_->mesh();
  const double mu = model_->material().mu();
  const double lambda = model_->material().lambda();
  parallel_.forRange(mesh.tetCount(), kTetGrain, [&](int begin, int end) {
    for (int t = begin; t < end; ++t) {
      const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
      std::array<Eigen::Vector3d, 4> dx;
      for (size_t a = 0; a < 4; ++a)
        dx[a] = y.segment<3>(3 * tet[a]);
      tet_scratch_[static_cast<size_t>(t)] =
          corotatedForceDifferential(dx, rotations_[static_cast<size_t>(t)],
                                     model_->tetRestData()[static_cast<size_t>(t)], mu, lambda);
    }
  });
  out.resize(y.size());
  gather(tet_scratch_, -stiffness_scale, out);
  if (mass_scale != 0.0) {
    const std::vector<double>& mass = model_->nodeMasses();
    for (int n = 0; n < mesh.nodeCount(); ++n) {
      out.segment<3>(3 * n) += mass_scale * mass[static_cast<size_t>(n)] * y.segment<3>(3 * n);
    }
  }
}

void SystemOperator::gather(const std::vector<std::array<Eigen::Vector3d, 4>>& tet_values,
                            double scale, Eigen::VectorXd& out) const {
  const int node_count = model_->nodeCount();
  out.resize(3 * node_count);
  parallel_.forRange(node_count, kNodeGrain, [&](int begin, int end) {
    for (int n = begin; n < end; ++n) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int k = node_offsets_[static_cast<size_t>(n)];
           k < node_offsets_[static_cast<size_t>(n) + 1]; ++k) {
        const int entry = node_entries_[static_cast<size_t>(k)];
        sum += tet_values[static_cast<size_t>(entry / 4)][static_cast<size_t>(entry % 4)];
      }
      out.segment<3>(3 * n) = scale * sum;
    }
  });
}

void SystemOperator::multiply(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  apply(y, out, mass_coefficient_, stiffness_coefficient_);
}

void SystemOperator::multiplyStiffness(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  apply(y, out, 0.0, 1.0);
}

void SystemOperator::diagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const {
  // K_aa of one tet is R V (mu |g|^2 I + (mu + lambda) g g^T) R^T with g = grad N_a, which is
  // V (mu |g|^2 I + (mu + lambda) (R g)(R g)^T): built per node straight from the tet's rotation,
  // with no per-tet buffer (see corotatedDiagonalBlocks for the same formula per tet).
  const TetMesh& mesh = model_->mesh();
  const double mu = model_->material().mu();
  const double mu_plus_lambda = mu + model_->material().lambda();
  const std::vector<double>& mass = model_->nodeMasses();
  blocks.resize(static_cast<size_t>(mesh.nodeCount()));
  parallel_.forRange(mesh.nodeCount(), kNodeGrain, [&](int begin, int end) {
    for (int n = begin; n < end; ++n) {
      Eigen::Matrix3d k = Eigen::Matrix3d::Zero();
      for (int e = node_offsets_[static_cast<size_t>(n)];
           e < node_offsets_[static_cast<size_t>(n) + 1]; ++e) {
        const int entry = node_entries_[static_cast<size_t>(e)];
        const int t = entry / 4, a = entry % 4;
        const TetRestData& rest = model_->tetRestData()[static_cast<size_t>(t)];
        const Eigen::Matrix3d& B = rest.rest_shape_inverse;
        const Eigen::Vector3d g =
            a == 0 ? Eigen::Vector3d(-(B.row(0) + B.row(1) + B.row(2)).transpose())
                   : Eigen::Vector3d(B.row(a - 1).transpose());
        const Eigen::Vector3d rg = rotations_[static_cast<size_t>(t)] * g;
        k.diagonal().array() += rest.volume * mu * g.squaredNorm();
        k.noalias() += (rest.volume * mu_plus_lambda) * rg * rg.transpose();
      }
      blocks[static_cast<size_t>(n)] =
          mass_coefficient_ * mass[static_cast<size_t>(n)] * Eigen::Matrix3d::Identity() +
          stiffness_coefficient_ * k;
    }
  });
}

}  // namespace torsion
