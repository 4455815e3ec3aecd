// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_UNIT_VECTOR_H
#define NORMAL_ORIENTATION_INTERNAL_UNIT_VECTOR_H

/// \file Unit_vector.h
/// The one rule by which both drivers and the flip criteria make normals
/// unit length, and the orthonormal basis of the plane normal to a unit
/// vector that the winding-number areas and the two-layer fit share.

#include <array>
#include <cmath>

namespace Normal_orientation {
namespace internal {

/// (x, y, z) times 1 / sqrt(x^2 + y^2 + z^2); the zero vector when that
/// squared length is 0 or not finite (a zero normal stays zero and weighs
/// nothing).
inline std::array<double, 3> unit_vector(double x, double y, double z)
{
  const double l2 = x * x + y * y + z * z;
  if (!(l2 > 0.0) || !std::isfinite(l2))
    return {0.0, 0.0, 0.0};
  const double inv = 1.0 / std::sqrt(l2);
  return {x * inv, y * inv, z * inv};
}

/// Writes to u and v an orthonormal basis of the plane normal to the unit
/// vector n, with (u, v, n) right-handed: u is e_x x n normalised when
/// |n_x| < 0.6, else e_y x n normalised; v = n x u.  Deterministic.
inline void tangent_basis(const double n[3], double u[3], double v[3])
{
  if (std::abs(n[0]) < 0.6) {
    u[0] = 0.0; u[1] = n[2]; u[2] = -n[1]; // e_x x n
  } else {
    u[0] = -n[2]; u[1] = 0.0; u[2] = n[0]; // e_y x n
  }
  const double ul = 1.0 / std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int d = 0; d < 3; ++d)
    u[d] *= ul;
  v[0] = n[1] * u[2] - n[2] * u[1];
  v[1] = n[2] * u[0] - n[0] * u[2];
  v[2] = n[0] * u[1] - n[1] * u[0];
}

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_UNIT_VECTOR_H
