#pragma once
// One body of a contact island as the SAP solve (sap_problem.h) sees it: its velocity dofs, its
// linear system A v = b without contact, A symmetric positive definite, and its prescribed dofs.
//
//   FEM body:   A = M (1 + dt alpha) + (dt^2 + dt beta) K (the step's SystemOperator), b the
//               momentum M v0 + dt (f_elastic + f_external); 3 dofs per node, 3x3 blocks;
//               prescribed components (NodeConstraints) are projected out of the unknowns
//               (fem_island_body.h).
//   rigid body: A = diag(m I, I_world), b = A twist0 + dt (f, tau); the twist [v; omega] about the
//               centre of mass, world frame; one 6x6 block.
//   link:       A = Lambda, a multibody link's effective mass at its reference point, b = A twist0
//               (multibody_partner.h); one 6x6 block.
//
// Prescribed dofs: the filter S (an orthogonal projection onto the free dofs) and the prescribed
// values. The solve keeps every prescribed component at its value and moves only free ones; a
// contact row still sees the prescribed motion (a carried node pushes what it touches).

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace torsion::sap {

class NodeCoarseSpace;

/// A square diagonal block of A, at most 6 x 6, stored inline.
using DiagonalBlock = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;

class IslandBody {
 public:
  virtual ~IslandBody() = default;
  virtual int dofs() const = 0;
  /// The size of A's diagonal blocks (3: a node; 6: a twist); divides dofs(). A contact term on
  /// this body covers exactly one block.
  virtual int blockSize() const = 0;
  /// out = A x (out sized by the body).
  virtual void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const = 0;
  /// b, the right-hand side of A v = b.
  virtual const Eigen::VectorXd& momentum() const = 0;
  /// A's diagonal block `block` (rows blockSize() block ..).
  virtual DiagonalBlock diagonalBlock(int block) const = 0;
  /// Zeroes the prescribed components of x (x = S x). Default: every dof free.
  virtual void filter(Eigen::VectorXd& /*x*/) const {}
  /// Sets the prescribed components of v to their values. Default: none.
  virtual void impose(Eigen::VectorXd& /*v*/) const {}
  /// S restricted to block `block` (blockSize() square). Default: the identity.
  virtual DiagonalBlock freeProjector(int block) const;
  /// Whether the body brings its own approximate inverse of A (applyPreconditioner). Then the
  /// island's CG preconditions this body's dofs with it alone; otherwise with block-Jacobi on
  /// A's diagonal blocks plus the contact terms on them (sap_problem.h). Default: no.
  virtual bool hasPreconditioner() const { return false; }
  /// z = S P S r, P symmetric positive definite on the free dofs, approximating A^-1 there (the
  /// step's Cholesky factor: exactly A^-1). Called only when hasPreconditioner(). Default: z = S r.
  virtual void applyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;
  /// The body's coarse space in the island's block-Jacobi CG (coarse_space.h), or nullptr
  /// (default): none.
  virtual const NodeCoarseSpace* coarseSpace() const { return nullptr; }
};

/// A body given by an assembled sparse SPD matrix (tests; spring networks), 3x3 blocks, with
/// optional prescribed dofs (each one a whole coordinate).
class MatrixBody final : public IslandBody {
 public:
  MatrixBody(const Eigen::SparseMatrix<double>& matrix, Eigen::VectorXd momentum);
  /// Prescribes dof `dof` to `value` (m/s).
  void prescribe(int dof, double value);

  int dofs() const override { return static_cast<int>(momentum_.size()); }
  int blockSize() const override { return 3; }
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const override;
  const Eigen::VectorXd& momentum() const override { return momentum_; }
  DiagonalBlock diagonalBlock(int block) const override;
  void filter(Eigen::VectorXd& x) const override;
  void impose(Eigen::VectorXd& v) const override;
  DiagonalBlock freeProjector(int block) const override;

 private:
  Eigen::SparseMatrix<double> matrix_;
  Eigen::VectorXd momentum_;
  std::vector<int> prescribed_;  // ascending dofs
  std::vector<double> values_;   // their velocities
};

/// A dynamic rigid body: mass m, world inertia about the centre of mass, twist [v; omega].
class RigidBody final : public IslandBody {
 public:
  /// momentum = diag(m I, inertia) twist0 + dt (force; torque).
  RigidBody(double mass, const Eigen::Matrix3d& inertia, Eigen::VectorXd momentum);

  int dofs() const override { return 6; }
  int blockSize() const override { return 6; }
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const override;
  const Eigen::VectorXd& momentum() const override { return momentum_; }
  DiagonalBlock diagonalBlock(int block) const override;

 private:
  double mass_;
  Eigen::Matrix3d inertia_;
  Eigen::VectorXd momentum_;
};

/// A multibody link seen through its effective mass Lambda = (J M^-1 J^T)^-1
/// (contact/multibody_partner.h): the twist [v; omega] at the link's reference point, one 6 x 6
/// SPD block.
class LinkBody final : public IslandBody {
 public:
  /// momentum = Lambda twist0.
  LinkBody(const Eigen::Matrix<double, 6, 6>& effective_mass, Eigen::VectorXd momentum);

  int dofs() const override { return 6; }
  int blockSize() const override { return 6; }
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const override;
  const Eigen::VectorXd& momentum() const override { return momentum_; }
  DiagonalBlock diagonalBlock(int block) const override;

 private:
  Eigen::Matrix<double, 6, 6> effective_mass_;
  Eigen::VectorXd momentum_;
};

}  // namespace torsion::sap
