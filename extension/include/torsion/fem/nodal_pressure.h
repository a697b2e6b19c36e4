#pragma once
// The average nodal pressure tet4 (Bonet & Burton 1998, "A simple average nodal pressure
// tetrahedral element for incompressible and nearly incompressible dynamic explicit
// applications", Commun. Numer. Meth. Engng 14), corotated: Material::volumetric_strain =
// VolumetricStrain::kNodalAverage.
//
// The linear strain of tet e in its unrotated frame, eps_e = sym(R_e^T F_e) - I, splits into its
// deviatoric part and its trace t_e = tr(R_e^T F_e) - 3 (the volumetric strain). The deviatoric
// energy stays per tet; the volumetric one is measured per node, on the volume-weighted average
// of the traces of the node's tets:
//   V_n = sum_{e ∋ n} V_e / 4,   theta_n = sum_{e ∋ n} (V_e / 4) t_e / V_n,   p_n = kappa theta_n,
//   E = sum_e V_e mu |dev eps_e|^2 + sum_n V_n (kappa / 2) theta_n^2,
// kappa = lambda + 2 mu / 3 the bulk modulus. Its gradient (R held fixed; with R = polar(F) the
// rotation's own variation adds nothing, as for the plain tet, because the stress below commutes
// with R^T F) is the plain corotated force with the stress
//   sigma_e = 2 mu dev eps_e + pbar_e I,   pbar_e = (p_a + p_b + p_c + p_d) / 4 over e's nodes,
//   f_a = -V_e R_e sigma_e g_a   (g_a = grad N_a).
// The deviatoric part is corotated_element.h with lambda replaced by -2 mu / 3. The stiffness at
// fixed rotations is the exact Hessian of E, symmetric positive semi-definite:
//   K = K_dev + sum_n kappa V_n b_n b_n^T,   b_n = d theta_n / dx: (b_n)_a = sum_{e ∋ n, a}
//   (V_e / 4) R_e g_a / V_n,
// whose product K_vol y takes the same three passes as the force: per tet the trace increment
// dt_e = sum_a (R_e g_a) . y_a, per node dtheta_n, per tet dpbar_e, then f_a = -V_e dpbar_e R_e
// g_a. K_vol couples nodes two tets apart, so it is applied in that factored form (CG) and only
// assembled where a matrix is needed (CHOLMOD, diagonal blocks for the preconditioner).
//
// Why it cures locking: a mesh of N nodes has about 5 N tets; per-tet volume constraints (the
// plain tet4 as nu -> 0.5) outnumber the 3 N displacement unknowns, the nodal ones (N) do not. A
// rigid motion gives eps_e = 0 for every tet (R_e = Q), so theta_n = 0 and no force: corotational
// invariance carries over unchanged.
//
// The kernels take index ranges [begin, end) so the solver can split them over threads; each
// writes its own outputs only and sums in a fixed order (nodes over their tets ascending), so the
// results do not depend on the split.

#include <Eigen/Core>
#include <vector>

#include "torsion/fem/fem_model.h"

namespace torsion {

/// theta_n = sum_{e ∋ n} (V_e / 4) tet_values[e] / V_n for nodes n in [begin, end) of a tet4
/// model (the volume-weighted average over the node's tets), into node_values[n].
void averageOverNodeTets(const FemModel& model, const std::vector<double>& tet_values, int begin,
                         int end, std::vector<double>& node_values);

/// scale * (mean of node_values over tet e's four nodes) for tets e in [begin, end), into
/// tet_values[e].
void averageOverTetNodes(const FemModel& model, const std::vector<double>& node_values,
                         double scale, int begin, int end, std::vector<double>& tet_values);

/// Adds the pressure forces f_a = -V_e pbar_e R_e g_a of tets e in [begin, end) to
/// element_forces[4 e + a], given the tet pressures pbar_e (Pa) and rotations R_e.
void addPressureForces(const FemModel& model, const std::vector<double>& tet_pressure,
                       const std::vector<Eigen::Matrix3d>& rotations, int begin, int end,
                       std::vector<Eigen::Vector3d>& element_forces);

/// The volumetric energy sum_n V_n (kappa / 2) theta_n^2 over all nodes, J (in node order).
double nodalVolumetricEnergy(const FemModel& model, const std::vector<double>& node_strain);

}  // namespace torsion
