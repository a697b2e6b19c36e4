#include "torsion/analysis/exact_predicates.h"

#include <cmath>
#include <limits>
#include <vector>

namespace torsion {

namespace {

// Half the distance from 1 to the next double: the unit round-off Shewchuk calls epsilon.
constexpr double kEpsilon = std::numeric_limits<double>::epsilon() / 2;

/// A floating-point expansion: components of increasing magnitude that do not overlap, their
/// exact sum the value. Zero components are dropped, so an empty expansion is 0.
using Expansion = std::vector<double>;

/// a + b = sum + error exactly (Knuth's TwoSum).
void twoSum(double a, double b, double& sum, double& error) {
  sum = a + b;
  const double b_virtual = sum - a;
  const double a_virtual = sum - b_virtual;
  error = (a - a_virtual) + (b - b_virtual);
}

/// a * b = product + error exactly (the fused multiply-add rounds only once).
void twoProduct(double a, double b, double& product, double& error) {
  product = a * b;
  error = std::fma(a, b, -product);
}

/// a - b exactly, as an expansion of at most two components.
Expansion difference(double a, double b) {
  double sum = 0, error = 0;
  twoSum(a, -b, sum, error);
  Expansion e;
  if (error != 0) e.push_back(error);
  if (sum != 0) e.push_back(sum);
  return e;
}

/// e + b (Shewchuk's GROW-EXPANSION with zero elimination).
Expansion grow(const Expansion& e, double b) {
  Expansion h;
  h.reserve(e.size() + 1);
  double q = b;
  for (double component : e) {
    double sum = 0, error = 0;
    twoSum(q, component, sum, error);
    if (error != 0) h.push_back(error);
    q = sum;
  }
  if (q != 0) h.push_back(q);
  return h;
}

/// e + f, one component of f at a time: quadratic, but the expansions here are short.
Expansion add(const Expansion& e, const Expansion& f) {
  Expansion h = e;
  for (double component : f)
    h = grow(h, component);
  return h;
}

/// e * b (Shewchuk's SCALE-EXPANSION with zero elimination).
Expansion scale(const Expansion& e, double b) {
  Expansion h;
  if (e.empty() || b == 0) return h;
  h.reserve(2 * e.size());
  double q = 0, error = 0;
  twoProduct(e[0], b, q, error);
  if (error != 0) h.push_back(error);
  for (size_t i = 1; i < e.size(); ++i) {
    double product = 0, product_error = 0, sum = 0;
    twoProduct(e[i], b, product, product_error);
    twoSum(q, product_error, sum, error);
    if (error != 0) h.push_back(error);
    twoSum(product, sum, q, error);
    if (error != 0) h.push_back(error);
  }
  if (q != 0) h.push_back(q);
  return h;
}

Expansion multiply(const Expansion& e, const Expansion& f) {
  Expansion h;
  for (double component : f)
    h = add(h, scale(e, component));
  return h;
}

Expansion negate(Expansion e) {
  for (double& component : e)
    component = -component;
  return e;
}

/// The largest component carries the sign of a non-overlapping expansion.
int sign(const Expansion& e) {
  if (e.empty()) return 0;
  return e.back() > 0 ? 1 : -1;
}

int sign(double value) {
  return (value > 0) - (value < 0);
}

/// ad x bd - ay x by... : the 2x2 determinant u0 v1 - u1 v0 of exact expansions.
Expansion determinant2(const Expansion& u0, const Expansion& u1, const Expansion& v0,
                       const Expansion& v1) {
  return add(multiply(u0, v1), negate(multiply(u1, v0)));
}

int orient3dExact(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d) {
  Expansion ad[3], bd[3], cd[3];
  for (int k = 0; k < 3; ++k) {
    ad[k] = difference(a(k), d(k));
    bd[k] = difference(b(k), d(k));
    cd[k] = difference(c(k), d(k));
  }
  // Cofactor expansion along ad: ad . (bd x cd).
  const Expansion x = multiply(ad[0], determinant2(bd[1], bd[2], cd[1], cd[2]));
  const Expansion y = multiply(ad[1], determinant2(bd[2], bd[0], cd[2], cd[0]));
  const Expansion z = multiply(ad[2], determinant2(bd[0], bd[1], cd[0], cd[1]));
  return sign(add(add(x, y), z));
}

int orient2dExact(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return sign(determinant2(difference(a(0), c(0)), difference(a(1), c(1)), difference(b(0), c(0)),
                           difference(b(1), c(1))));
}

}  // namespace

int orient3dSign(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d) {
  const Eigen::Vector3d ad = a - d, bd = b - d, cd = c - d;
  const double bdxcdy = bd(0) * cd(1), cdxbdy = cd(0) * bd(1);
  const double cdxady = cd(0) * ad(1), adxcdy = ad(0) * cd(1);
  const double adxbdy = ad(0) * bd(1), bdxady = bd(0) * ad(1);
  const double det =
      ad(2) * (bdxcdy - cdxbdy) + bd(2) * (cdxady - adxcdy) + cd(2) * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(ad(2)) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bd(2)) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cd(2));
  // Shewchuk's o3derrboundA.
  const double bound = (7.0 + 56.0 * kEpsilon) * kEpsilon * permanent;
  if (det > bound || -det > bound) return sign(det);
  return orient3dExact(a, b, c, d);
}

int orient2dSign(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const double left = (a(0) - c(0)) * (b(1) - c(1));
  const double right = (a(1) - c(1)) * (b(0) - c(0));
  const double det = left - right;
  // Shewchuk's ccwerrboundA.
  const double bound = (3.0 + 16.0 * kEpsilon) * kEpsilon * (std::abs(left) + std::abs(right));
  if (det > bound || -det > bound) return sign(det);
  return orient2dExact(a, b, c);
}

}  // namespace torsion
