#include "torsion/analysis/twist_profile.h"

#include <Eigen/LU>
#include <cmath>
#include <limits>

namespace torsion {

std::vector<SliceRotation> twistProfile(const std::vector<Eigen::Vector3d>& rest,
                                        const Eigen::VectorXd& current,
                                        const std::vector<double>& slice_z, double half_thickness,
                                        double axis_x, double axis_y) {
  std::vector<SliceRotation> profile;
  profile.reserve(slice_z.size());
  double previous = 0;
  bool have_previous = false;
  for (double z : slice_z) {
    double cross = 0, dot = 0;
    int count = 0;
    for (size_t i = 0; i < rest.size(); ++i) {
      if (std::abs(rest[i].z() - z) > half_thickness) continue;
      const double X = rest[i].x() - axis_x, Y = rest[i].y() - axis_y;
      const double x = current[static_cast<Eigen::Index>(3 * i)] - axis_x;
      const double y = current[static_cast<Eigen::Index>(3 * i + 1)] - axis_y;
      cross += X * y - Y * x;
      dot += X * x + Y * y;
      ++count;
    }
    SliceRotation slice;
    slice.z = z;
    slice.nodes = count;
    if (count == 0) {
      slice.angle = std::numeric_limits<double>::quiet_NaN();
    } else {
      double angle = std::atan2(cross, dot);
      if (have_previous) angle += 2 * M_PI * std::round((previous - angle) / (2 * M_PI));
      slice.angle = angle;
      previous = angle;
      have_previous = true;
    }
    profile.push_back(slice);
  }
  return profile;
}

namespace {
struct Line {
  double slope = 0, intercept = 0;
};
Line fit(const std::vector<SliceRotation>& profile, double z_min, double z_max) {
  double n = 0, sz = 0, sa = 0, szz = 0, sza = 0;
  for (const SliceRotation& s : profile) {
    if (s.nodes == 0 || s.z < z_min || s.z > z_max) continue;
    n += 1;
    sz += s.z;
    sa += s.angle;
    szz += s.z * s.z;
    sza += s.z * s.angle;
  }
  Line line;
  const double denominator = n * szz - sz * sz;
  if (n < 2 || denominator == 0) {
    line.slope = std::numeric_limits<double>::quiet_NaN();
    return line;
  }
  line.slope = (n * sza - sz * sa) / denominator;
  line.intercept = (sa - line.slope * sz) / n;
  return line;
}
}  // namespace

double twistRate(const std::vector<SliceRotation>& profile, double z_min, double z_max) {
  return fit(profile, z_min, z_max).slope;
}

double twistNonlinearity(const std::vector<SliceRotation>& profile, double z_min, double z_max) {
  const Line line = fit(profile, z_min, z_max);
  double worst = 0;
  for (const SliceRotation& s : profile) {
    if (s.nodes == 0 || s.z < z_min || s.z > z_max) continue;
    worst = std::max(worst, std::abs(s.angle - (line.slope * s.z + line.intercept)));
  }
  const double span = std::abs(line.slope) * (z_max - z_min);
  return span > 0 ? worst / span : std::numeric_limits<double>::infinity();
}

double polarMomentOfSection(const std::vector<Eigen::Vector3d>& rest,
                            const std::vector<std::array<int, 4>>& tets, double length,
                            double axis_x, double axis_y) {
  // Exact integral of a quadratic over a tet: int x_i x_j dV = V/20 (sum_a x_ai x_aj + s_i s_j),
  // with s the sum of the four vertex coordinates.
  double total = 0;
  for (const auto& tet : tets) {
    Eigen::Vector2d p[4];
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (int a = 0; a < 4; ++a) {
      const Eigen::Vector3d& x = rest[static_cast<size_t>(tet[static_cast<size_t>(a)])];
      p[a] = Eigen::Vector2d(x.x() - axis_x, x.y() - axis_y);
      sum += p[a];
    }
    const Eigen::Vector3d& x0 = rest[static_cast<size_t>(tet[0])];
    Eigen::Matrix3d D;
    for (int k = 0; k < 3; ++k)
      D.col(k) = rest[static_cast<size_t>(tet[static_cast<size_t>(k + 1)])] - x0;
    const double volume = std::abs(D.determinant()) / 6.0;
    double squares = sum.squaredNorm();
    for (int a = 0; a < 4; ++a)
      squares += p[a].squaredNorm();
    total += volume / 20.0 * squares;
  }
  return total / length;
}

}  // namespace torsion
