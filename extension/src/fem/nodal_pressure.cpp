#include "torsion/fem/nodal_pressure.h"

namespace torsion {

void averageOverNodeTets(const FemModel& model, const std::vector<double>& tet_values, int begin,
                         int end, std::vector<double>& node_values) {
  const CompressedRows& node_tets = model.mesh().nodeTets();
  const std::vector<TetRestData>& rest = model.tetRestData();
  const std::vector<double>& node_volume = model.nodeVolumes();
  for (int n = begin; n < end; ++n) {
    double sum = 0;
    for (int k = node_tets.rowBegin(n); k < node_tets.rowEnd(n); ++k) {
      const size_t t = static_cast<size_t>(node_tets.items[static_cast<size_t>(k)]);
      sum += rest[t].volume * tet_values[t];
    }
    const double volume = node_volume[static_cast<size_t>(n)];
    node_values[static_cast<size_t>(n)] = volume > 0 ? 0.25 * sum / volume : 0.0;
  }
}

void averageOverTetNodes(const FemModel& model, const std::vector<double>& node_values,
                         double scale, int begin, int end, std::vector<double>& tet_values) {
  const std::vector<int>& nodes = model.elementNodes();
  for (int t = begin; t < end; ++t) {
    const size_t i = 4 * static_cast<size_t>(t);
    tet_values[static_cast<size_t>(t)] = 0.25 * scale *
                                         (node_values[static_cast<size_t>(nodes[i])] +
                                          node_values[static_cast<size_t>(nodes[i + 1])] +
                                          node_values[static_cast<size_t>(nodes[i + 2])] +
                                          node_values[static_cast<size_t>(nodes[i + 3])]);
  }
}

void addPressureForces(const FemModel& model, const std::vector<double>& tet_pressure,
                       const std::vector<Eigen::Matrix3d>& rotations, int begin, int end,
                       std::vector<Eigen::Vector3d>& element_forces) {
  for (int t = begin; t < end; ++t) {
    const size_t i = static_cast<size_t>(t);
    const TetRestData& rest = model.tetRestData()[i];
    // Columns of -V p R Bm^T are the forces on nodes 1..3 (g_1..3 are Bm's rows); node 0 takes
    // minus their sum.
    const Eigen::Matrix3d H =
        (-rest.volume * tet_pressure[i]) * rotations[i] * rest.rest_shape_inverse.transpose();
    element_forces[4 * i] -= H.col(0) + H.col(1) + H.col(2);
    for (size_t a = 1; a < 4; ++a)
      element_forces[4 * i + a] += H.col(static_cast<Eigen::Index>(a - 1));
  }
}

double nodalVolumetricEnergy(const FemModel& model, const std::vector<double>& node_strain) {
  const double half_kappa = 0.5 * model.material().bulkModulus();
  double energy = 0;
  for (size_t n = 0; n < node_strain.size(); ++n)
    energy += half_kappa * model.nodeVolumes()[n] * node_strain[n] * node_strain[n];
  return energy;
}

}  // namespace torsion
