#pragma once
// Exact orientation signs of points given as doubles (Shewchuk 1997, "Adaptive precision
// floating-point arithmetic and fast robust geometric predicates", Discrete Comput. Geom.
// 18:305-363): the determinant is first evaluated in double and trusted when it is farther
// from zero than its rounding error bound (the paper's errboundA); otherwise it is recomputed
// exactly as a floating-point expansion (a sum of non-overlapping doubles: TwoSum, TwoProduct by
// fused multiply-add, scale and grow). The sign is then exact for any finite input whose products
// neither overflow nor underflow (coordinates between about 1e-90 and 1e90 in magnitude, or 0).

#include <Eigen/Core>

namespace torsion {

/// Sign of det[a - d; b - d; c - d]: +1 when d lies below the plane through a, b, c (the side
/// opposite to (b - a) x (c - a)), -1 above it, 0 exactly on it. Equivalently +1 when the tet
/// (a, b, c, d) is negatively oriented in the convention of tet_mesh.h.
int orient3dSign(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d);

/// Sign of det[a - c; b - c] in the plane: +1 when a, b, c turn counter-clockwise, -1 clockwise,
/// 0 collinear.
int orient2dSign(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

}  // namespace torsion
