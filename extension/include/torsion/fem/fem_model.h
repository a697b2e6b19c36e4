#pragma once
// The immutable FEM description of one body: the mesh, its element kind, its material, and
// per-element rest data precomputed once (Mueller & Gross 2004, "Interactive Virtual Materials").
// Shared read-only by every thread; per-step state lives in FemState.
//
// Two meshes, one role each:
//  - mesh(): every simulation node, with the surface and incidence every surface-based module
//    uses. For tet4 it is the input mesh and its tets are the elements; for tet10 it is the
//    refined mesh of quadratic_tet_mesh.h (8 linear sub-tets per element, over all P2 nodes).
//  - the elements: elementNodes(), nodesPerElement() nodes each; the solver's connectivity.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "torsion/fem/element_kind.h"
#include "torsion/fem/material.h"
#include "torsion/fem/quadratic_element.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

/// Rest data of one linear tet.
struct TetRestData {
  Eigen::Matrix3d rest_shape_inverse;  ///< Bm = Dm^-1, Dm = [X1-X0, X2-X0, X3-X0]; 1/m
  double volume = 0;                   ///< rest volume V, m^3
};

/// The rest data of a tet with rest corners X0..X3 (volume positive when X1-X0, X2-X0, X3-X0 are
/// right-handed, as TetMesh orders them).
TetRestData tetRestData(const std::array<Eigen::Vector3d, 4>& corners);

class FemModel {
 public:
  /// Precomputes rest data of `mesh` (a linear mesh) discretised with `element`; fails if the
  /// material is invalid or asks for nodal-average volumetric strain on tet10.
  static Result<std::shared_ptr<const FemModel>> create(std::shared_ptr<const TetMesh> mesh,
                                                        const Material& material,
                                                        ElementKind element = ElementKind::kTet4);
  /// The same meshes, elements and rest data with another material (live edits); the masses
  /// follow the density. Fails as create() does.
  Result<std::shared_ptr<const FemModel>> withMaterial(const Material& material) const;

  /// All simulation nodes, their surface and incidence (see above).
  const TetMesh& mesh() const { return *mesh_; }
  /// The linear mesh the model was created from (mesh() itself for tet4).
  const std::shared_ptr<const TetMesh>& linearMeshPtr() const { return linear_mesh_; }
  const Material& material() const { return material_; }
  int nodeCount() const { return mesh_->nodeCount(); }

  ElementKind elementKind() const { return element_kind_; }
  int nodesPerElement() const { return torsion::nodesPerElement(element_kind_); }
  int elementCount() const { return static_cast<int>(element_nodes_.size()) / nodesPerElement(); }
  /// Element e's nodes are elementNodes()[N e .. N e + N), N = nodesPerElement(); for tet4 the
  /// tets of mesh(), for tet10 the Tet10 order of quadratic_tet_mesh.h.
  const std::vector<int>& elementNodes() const { return element_nodes_; }
  /// The element that tet t of mesh() belongs to (t itself for tet4).
  int elementOfTet(int t) const { return element_kind_ == ElementKind::kTet10 ? t / 8 : t; }

  /// Linear rest data of every tet of mesh(): the elements for tet4; the sub-tets for tet10
  /// (strain display and deformation metrics).
  const std::vector<TetRestData>& tetRestData() const { return rest_; }
  /// P2 rest data per element (tet10; empty for tet4).
  const std::vector<QuadraticRestData>& quadraticRestData() const { return quadratic_rest_; }
  /// True when the tet4 volumetric strain is averaged over nodes (fem/nodal_pressure.h).
  bool nodalPressure() const {
    return material_.volumetric_strain == VolumetricStrain::kNodalAverage;
  }
  /// V_n = sum of V / 4 over the node's tets (tet4; empty for tet10), m^3.
  const std::vector<double>& nodeVolumes() const { return node_volume_; }
  /// Lumped node masses, kg: rho V / 4 per corner for tet4; HRZ for tet10 (quadratic_element.h).
  const std::vector<double>& nodeMasses() const { return node_mass_; }
  double totalMass() const { return total_mass_; }
  /// The rest volume, m^3.
  double totalVolume() const { return total_volume_; }

 private:
  FemModel() = default;
  void computeMasses();

  std::shared_ptr<const TetMesh> mesh_;
  std::shared_ptr<const TetMesh> linear_mesh_;
  ElementKind element_kind_ = ElementKind::kTet4;
  Material material_;
  std::vector<int> element_nodes_;
  std::vector<TetRestData> rest_;
  std::vector<QuadraticRestData> quadratic_rest_;
  std::vector<double> node_volume_;
  std::vector<double> node_mass_;
  double total_mass_ = 0;
  double total_volume_ = 0;
};

}  // namespace torsion
