#include "torsion/fem/fem_model.h"

#include <Eigen/LU>

namespace torsion {

Result<std::shared_ptr<const FemModel>> FemModel::create(std::shared_ptr<const TetMesh> mesh,
                                                         const Material& material) {
  Status valid = material.validate();
  if (!valid) return valid.error();

  std::shared_ptr<FemModel> model(new FemModel());
  model->mesh_ = std::move(mesh);
  model->material_ = material;
  const TetMesh& m = *model->mesh_;
  const auto& x = m.restPositions();
  model->rest_.resize(static_cast<size_t>(m.tetCount()));
  model->node_mass_.assign(static_cast<size_t>(m.nodeCount()), 0.0);
  for (int t = 0; t < m.tetCount(); ++t) {
    const Tet& tet = m.tets()[static_cast<size_t>(t)];
    Eigen::Matrix3d Dm;
    for (int k = 0; k < 3; ++k) {
      Dm.col(k) =
          x[static_cast<size_t>(tet[static_cast<size_t>(k + 1)])] - x[static_cast<size_t>(tet[0])];
    }
    TetRestData& rest = model->rest_[static_cast<size_t>(t)];
    rest.rest_shape_inverse = Dm.inverse();
    rest.volume = Dm.determinant() / 6.0;  // positive: TetMesh guarantees orientation
    const double quarter_mass = material.density * rest.volume / 4.0;
    for (int n : tet)
      model->node_mass_[static_cast<size_t>(n)] += quarter_mass;
    model->total_mass_ += 4 * quarter_mass;
  }
  return std::shared_ptr<const FemModel>(std::move(model));
}

}  // namespace torsion
