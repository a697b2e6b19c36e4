#include "torsion/device/passive_stiffness.h"

#include <algorithm>
#include <cmath>

namespace torsion::device {

namespace {

constexpr int kN = 6;

// Cyclic Jacobi on the symmetric part of k: a (eigenvalues on its diagonal on return) and v
// (eigenvectors in its columns). Jacobi because it is short, exact for a 6x6 in a few sweeps and
// needs no library here (this layer knows nothing of Eigen).
void symmetricEigen(const double k[36], double a[kN][kN], double v[kN][kN]) {
  for (int r = 0; r < kN; ++r) {
    for (int c = 0; c < kN; ++c) {
      a[r][c] = 0.5 * (k[kN * r + c] + k[kN * c + r]);
      v[r][c] = r == c ? 1.0 : 0.0;
    }
  }
  for (int sweep = 0; sweep < 50; ++sweep) {
    double off = 0, scale = 0;
    for (int r = 0; r < kN; ++r) {
      for (int c = 0; c < kN; ++c) {
        scale += a[r][c] * a[r][c];
        if (r != c) off += a[r][c] * a[r][c];
      }
    }
    if (!(off > 1e-30 * scale)) return;
    for (int p = 0; p < kN - 1; ++p) {
      for (int q = p + 1; q < kN; ++q) {
        if (a[p][q] == 0) continue;
        const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1);
        const double s = t * c;
        for (int j = 0; j < kN; ++j) {  // a <- a J (columns p, q)
          const double ajp = a[j][p], ajq = a[j][q];
          a[j][p] = c * ajp - s * ajq;
          a[j][q] = s * ajp + c * ajq;
        }
        for (int j = 0; j < kN; ++j) {  // a <- J^T a (rows p, q)
          const double apj = a[p][j], aqj = a[q][j];
          a[p][j] = c * apj - s * aqj;
          a[q][j] = s * apj + c * aqj;
        }
        for (int j = 0; j < kN; ++j) {
          const double vjp = v[j][p], vjq = v[j][q];
          v[j][p] = c * vjp - s * vjq;
          v[j][q] = s * vjp + c * vjq;
        }
      }
    }
  }
}

bool allFinite(const double k[36]) {
  return std::all_of(k, k + 36, [](double x) { return std::isfinite(x); });
}

}  // namespace

void passiveStiffness(const double k[36], double out[36]) {
  if (!allFinite(k)) {
    std::fill(out, out + 36, 0.0);
    return;
  }
  double a[kN][kN], v[kN][kN];
  symmetricEigen(k, a, v);
  for (int r = 0; r < kN; ++r) {
    for (int c = 0; c < kN; ++c) {
      double sum = 0;
      for (int e = 0; e < kN; ++e)
        sum += v[r][e] * std::min(a[e][e], 0.0) * v[c][e];
      out[kN * r + c] = sum;
    }
  }
  // Exactly symmetric (the sum above is, up to rounding).
  for (int r = 0; r < kN; ++r) {
    for (int c = r + 1; c < kN; ++c) {
      const double m = 0.5 * (out[kN * r + c] + out[kN * c + r]);
      out[kN * r + c] = out[kN * c + r] = m;
    }
  }
}

double largestSymmetricEigenvalue(const double k[36]) {
  if (!allFinite(k)) return std::nan("");
  double a[kN][kN], v[kN][kN];
  symmetricEigen(k, a, v);
  double largest = a[0][0];
  for (int e = 1; e < kN; ++e)
    largest = std::max(largest, a[e][e]);
  return largest;
}

}  // namespace torsion::device
