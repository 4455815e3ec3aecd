// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_SYMMETRIC_EIGEN_3_H
#define NORMAL_ORIENTATION_INTERNAL_SYMMETRIC_EIGEN_3_H

/// \file Symmetric_eigen_3.h
/// The eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations.
///
/// Hand-written rather than taken from Eigen: Eigen is optional for the library, and
/// the streaming driver, whose sweep axis this computes, must build without it.  The
/// result then depends on nothing but this code: the sweep order, and so the output of
/// the streaming driver, does not change with the version or configuration of another
/// library.

#include <cmath>

namespace Normal_orientation {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// Eigen-decomposition of a symmetric 3x3 matrix `m` by cyclic Jacobi
/// rotations: `values[k]` is the eigenvalue of the unit eigenvector stored in
/// column `k` of `vectors` (vectors[row][k]).  Deterministic; orthogonal output.
inline void symmetric_eigen_3(const double (&m)[3][3], double (&values)[3], double (&vectors)[3][3])
{
  double a[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      a[i][j] = 0.5 * (m[i][j] + m[j][i]);
      vectors[i][j] = (i == j) ? 1. : 0.;
    }
  static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int sweep = 0; sweep < 64; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diagonal = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (!(off > 1e-34 * diagonal)) // also stops on zero or non-finite matrices
      break;
    for (const auto& pq : pairs) {
      const int p = pq[0], q = pq[1];
      if (a[p][q] == 0.)
        continue;
      // rotation J (J_pp = J_qq = c, J_pq = s, J_qp = -s) with (J^T A J)_pq = 0:
      // t = tan(phi) is the smaller root of t^2 + 2 theta t - 1 = 0
      const double theta = (a[q][q] - a[p][p]) / (2. * a[p][q]);
      double t;
      if (std::abs(theta) > 1e150)
        t = 0.5 / theta;
      else
        t = (theta >= 0. ? 1. : -1.) / (std::abs(theta) + std::sqrt(theta * theta + 1.));
      const double c = 1. / std::sqrt(t * t + 1.);
      const double s = t * c;
      double j[3][3] = {{1., 0., 0.}, {0., 1., 0.}, {0., 0., 1.}};
      j[p][p] = c;
      j[q][q] = c;
      j[p][q] = s;
      j[q][p] = -s;
      double aj[3][3], jtaj[3][3], vj[3][3];
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) {
          aj[r][k] = a[r][0] * j[0][k] + a[r][1] * j[1][k] + a[r][2] * j[2][k];
          vj[r][k] = vectors[r][0] * j[0][k] + vectors[r][1] * j[1][k] + vectors[r][2] * j[2][k];
        }
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
          jtaj[r][k] = j[0][r] * aj[0][k] + j[1][r] * aj[1][k] + j[2][r] * aj[2][k];
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) {
          a[r][k] = (r == k) ? jtaj[r][k] : 0.5 * (jtaj[r][k] + jtaj[k][r]);
          vectors[r][k] = vj[r][k];
        }
      a[p][q] = a[q][p] = 0.;
    }
  }
  for (int k = 0; k < 3; ++k)
    values[k] = a[k][k];
}

} // namespace internal
/// \endcond
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_SYMMETRIC_EIGEN_3_H
