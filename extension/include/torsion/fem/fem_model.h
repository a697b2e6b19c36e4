#pragma once
// The immutable FEM description of one body: the mesh, its material, and per-tet rest data
// precomputed once (Mueller & Gross 2004, "Interactive Virtual Materials"). Shared read-only by
// every thread; per-step state lives in FemState.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "torsion/fem/material.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

/// Rest data of one tet.
struct TetRestData {
  Eigen::Matrix3d rest_shape_inverse;  ///< Bm = Dm^-1, Dm = [X1-X0, X2-X0, X3-X0]; 1/m
  double volume = 0;                   ///< rest volume V, m^3
};

class FemModel {
 public:
  /// Precomputes rest data; fails if the material is invalid.
  static Result<std::shared_ptr<const FemModel>> create(std::shared_ptr<const TetMesh> mesh,
                                                        const Material& material);

  const TetMesh& mesh() const { return *mesh_; }
  const std::shared_ptr<const TetMesh>& meshPtr() const { return mesh_; }
  const Material& material() const { return material_; }
  int nodeCount() const { return mesh_->nodeCount(); }
  int tetCount() const { return mesh_->tetCount(); }

  const std::vector<TetRestData>& tetRestData() const { return rest_; }
  /// Lumped mass m_i = sum over incident tets of rho V / 4, kg.
  const std::vector<double>& nodeMasses() const { return node_mass_; }
  double totalMass() const { return total_mass_; }

 private:
  FemModel() = default;
  std::shared_ptr<const TetMesh> mesh_;
  Material material_;
  std::vector<TetRestData> rest_;
  std::vector<double> node_mass_;
  double total_mass_ = 0;
};

}  // namespace torsion
