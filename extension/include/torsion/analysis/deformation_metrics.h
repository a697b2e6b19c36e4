#pragma once
// How badly a body's tets are deformed: the measure the report's over-deformation complaint is
// about (tets with both grabbed and free nodes stretched or turned inside out by a fast hand).
//
// Per tet, F = Ds Bm and its singular values s1 >= s2 >= s3 (signed: s3 < 0 for an inverted tet,
// the same sign convention as polar_rotation.h). The element strain is the largest principal
// stretch deviation max_i |s_i - 1|: 0 at rest and under any rigid motion, 1 for a tet squashed
// flat or doubled in length. It is a strain of the corotated model, so it is what the linear
// stress-strain law inside each tet sees.

#include <Eigen/Core>

#include "torsion/fem/fem_model.h"

namespace torsion {

struct DeformationMetrics {
  double max_strain = 0;  ///< largest max_i |s_i - 1| over all tets
  int max_strain_tet = -1;
  int inverted_tets = 0;  ///< tets with det F <= 0
};

/// Metrics of the configuration `positions` (3n) of `model`'s body.
DeformationMetrics measureDeformation(const FemModel& model, const Eigen::VectorXd& positions);

/// Tets of `model`'s mesh with det F <= 0 (or non-finite) at `positions` (3n): the count of
/// measureDeformation() without its singular values, cheap enough to run after every step. For
/// tet10 these are the linear sub-tets of FemModel::mesh().
int countInvertedTets(const FemModel& model, const Eigen::VectorXd& positions);

/// countInvertedTets() for a check after every step (scene_anomalies.h): the same count, bit for
/// bit the same judgement per tet, at about half the cost. det F = det(Ds) det(Bm) with det(Bm) >
/// 0, so the sign of the triple product det(Ds) decides, wherever it is far enough from zero that
/// the rounding of either computation cannot flip it (a bound from the edges and from the worst
/// rest shape, computed once here); a tet closer to flat, or any non-finite value, is judged by
/// the full det F as countInvertedTets() does.
class InvertedTetCounter {
 public:
  /// The rounding bound of `model`'s rest shapes (one pass over its tets).
  explicit InvertedTetCounter(const FemModel& model);
  /// Inverted tets of `model` (the one given to the constructor, or one with the same mesh) at
  /// `positions` (3n).
  int count(const FemModel& model, const Eigen::VectorXd& positions) const;

 private:
  double threshold_;  ///< |det Ds| > threshold_ * (row sums of |Ds| multiplied) decides alone
};

/// max_i |s_i - 1| of one deformation gradient (signed singular values).
double elementStrain(const Eigen::Matrix3d& deformation_gradient);

}  // namespace torsion
