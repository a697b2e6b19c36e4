#pragma once
// Measuring torsion of a body along the z axis (docs/design.md section 5): the rotation angle of
// thin slices and the twist rate, for validation against St-Venant (T = G J theta').

#include <Eigen/Core>
#include <array>
#include <vector>

namespace torsion {

struct SliceRotation {
  double z = 0;      ///< slice centre (rest coordinates), m
  double angle = 0;  ///< least-squares rotation about the axis, rad (unwrapped along z)
  int nodes = 0;     ///< nodes in the slice
};

/// Least-squares (Procrustes) rotation about the z axis through (axis_x, axis_y) of the nodes
/// whose rest z lies within half_thickness of each requested z:
///   theta = atan2(sum(X y - Y x), sum(X x + Y y)),  (X, Y) rest, (x, y) current, both about the
/// axis. Angles are unwrapped from one slice to the next (in the order given), so a 2 pi twist
/// reads 2 pi. A slice with no nodes reports nodes = 0 and angle NaN.
std::vector<SliceRotation> twistProfile(const std::vector<Eigen::Vector3d>& rest,
                                        const Eigen::VectorXd& current,  // 3n
                                        const std::vector<double>& slice_z, double half_thickness,
                                        double axis_x = 0, double axis_y = 0);

/// Least-squares slope d(angle)/dz over the slices with z in [z_min, z_max] (rad/m).
double twistRate(const std::vector<SliceRotation>& profile, double z_min, double z_max);

/// Largest deviation of the angles in [z_min, z_max] from their least-squares line, relative to
/// the angle change across that range (0 for a perfectly linear profile).
double twistNonlinearity(const std::vector<SliceRotation>& profile, double z_min, double z_max);

/// Polar moment of the body's cross-section about the z axis through (axis_x, axis_y), averaged
/// over its length: (1 / length) * integral of ((x - ax)^2 + (y - ay)^2) dV, exact for the meshed
/// (polygonal) section. For a prismatic body this is the section's J; St-Venant's J = pi r^4 / 2
/// is the smooth circle's, a few % more than a 20-gon's.
double polarMomentOfSection(const std::vector<Eigen::Vector3d>& rest,
                            const std::vector<std::array<int, 4>>& tets, double length,
                            double axis_x = 0, double axis_y = 0);

}  // namespace torsion
