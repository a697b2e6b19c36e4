#include "torsion/fem/fem_model.h"

#include <Eigen/LU>

#include "torsion/mesh/quadratic_tet_mesh.h"

namespace torsion {

namespace {

TetRestData linearRestData(const TetMesh& mesh, const Tet& tet) {
  const auto& x = mesh.restPositions();
  std::array<Eigen::Vector3d, 4> corners;
  for (size_t a = 0; a < 4; ++a)
    corners[a] = x[static_cast<size_t>(tet[a])];
  return tetRestData(corners);  // positive volume: TetMesh guarantees orientation
}

Status checkElementSupports(const Material& material, ElementKind element) {
  Status valid = material.validate();
  if (!valid) return valid;
  if (element == ElementKind::kTet10 &&
      material.volumetric_strain == VolumetricStrain::kNodalAverage) {
    return Error{
        "material: volumetric_strain = nodal_average is a tet4 option (quadratic tets do not "
        "lock)"};
  }
  if (material.hyperelastic() && material.volumetric_strain == VolumetricStrain::kNodalAverage) {
    return Error{std::string("material: law = ") + toString(material.law) +
                 " takes volumetric_strain = element only (its volume term is per tet)"};
  }
  return Ok{};
}

}  // namespace

TetRestData tetRestData(const std::array<Eigen::Vector3d, 4>& corners) {
  Eigen::Matrix3d Dm;
  for (size_t k = 0; k < 3; ++k)
    Dm.col(static_cast<Eigen::Index>(k)) = corners[k + 1] - corners[0];
  TetRestData rest;
  rest.rest_shape_inverse = Dm.inverse();
  rest.volume = Dm.determinant() / 6.0;
  return rest;
}

Result<std::shared_ptr<const FemModel>> FemModel::create(std::shared_ptr<const TetMesh> mesh,
                                                         const Material& material,
                                                         ElementKind element) {
  Status valid = checkElementSupports(material, element);
  if (!valid) return valid.error();

  std::shared_ptr<FemModel> model(new FemModel());
  model->material_ = material;
  model->element_kind_ = element;
  model->linear_mesh_ = mesh;
  if (element == ElementKind::kTet4) {
    model->mesh_ = std::move(mesh);
    for (const Tet& tet : model->mesh_->tets())
      model->element_nodes_.insert(model->element_nodes_.end(), tet.begin(), tet.end());
  } else {
    QuadraticTetMesh quadratic = buildQuadraticTetMesh(*mesh);
    model->mesh_ = std::move(quadratic.refined);
    model->element_nodes_.reserve(10 * quadratic.elements.size());
    model->quadratic_rest_.reserve(quadratic.elements.size());
    for (const Tet10& element_nodes : quadratic.elements)
      model->element_nodes_.insert(model->element_nodes_.end(), element_nodes.begin(),
                                   element_nodes.end());
    for (const Tet& corners : mesh->tets()) {
      const TetRestData corner_rest = linearRestData(*mesh, corners);
      model->quadratic_rest_.push_back(
          torsion::quadraticRestData(corner_rest.rest_shape_inverse, corner_rest.volume));
    }
  }
  const TetMesh& m = *model->mesh_;
  model->rest_.reserve(static_cast<size_t>(m.tetCount()));
  for (const Tet& tet : m.tets())
    model->rest_.push_back(linearRestData(m, tet));
  if (element == ElementKind::kTet4) {
    model->node_volume_.assign(static_cast<size_t>(m.nodeCount()), 0.0);
    for (size_t t = 0; t < model->rest_.size(); ++t) {
      for (int n : m.tets()[t])
        model->node_volume_[static_cast<size_t>(n)] += model->rest_[t].volume / 4.0;
    }
  }
  model->computeMasses();
  return std::shared_ptr<const FemModel>(std::move(model));
}

Result<std::shared_ptr<const FemModel>> FemModel::withMaterial(const Material& material) const {
  Status valid = checkElementSupports(material, element_kind_);
  if (!valid) return valid.error();
  std::shared_ptr<FemModel> model(new FemModel(*this));
  model->material_ = material;
  model->computeMasses();
  return std::shared_ptr<const FemModel>(std::move(model));
}

void FemModel::computeMasses() {
  node_mass_.assign(static_cast<size_t>(mesh_->nodeCount()), 0.0);
  total_mass_ = 0;
  total_volume_ = 0;
  for (const TetRestData& tet : rest_)
    total_volume_ += tet.volume;
  const double density = material_.density;
  if (element_kind_ == ElementKind::kTet4) {
    for (size_t t = 0; t < rest_.size(); ++t) {
      const double quarter_mass = density * rest_[t].volume / 4.0;
      for (int n : mesh_->tets()[t])
        node_mass_[static_cast<size_t>(n)] += quarter_mass;
      total_mass_ += 4 * quarter_mass;
    }
    return;
  }
  for (size_t e = 0; e < quadratic_rest_.size(); ++e) {
    const double mass = density * quadratic_rest_[e].volume;
    for (size_t a = 0; a < 10; ++a) {
      node_mass_[static_cast<size_t>(element_nodes_[10 * e + a])] +=
          (a < 4 ? kTet10CornerMassFraction : kTet10EdgeMassFraction) * mass;
    }
    total_mass_ += mass;
  }
}

}  // namespace torsion
