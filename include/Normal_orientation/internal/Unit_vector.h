// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_UNIT_VECTOR_H
#define NORMAL_ORIENTATION_INTERNAL_UNIT_VECTOR_H

/// \file Unit_vector.h
/// The one rule by which both drivers and the flip criteria make normals
/// unit length.

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

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_UNIT_VECTOR_H
