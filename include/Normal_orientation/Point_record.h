// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_POINT_RECORD_H
#define NORMAL_ORIENTATION_POINT_RECORD_H

/// \file Point_record.h
/// One point with its normal and its position in the input: the unit of
/// data of the streaming readers and writers, the external sort, the sweep
/// and the temporary record files.

#include <cstdint>
#include <type_traits>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationStreaming
/// One point of a streamed cloud: its coordinates and normal exactly as
/// read (doubles, so that nothing is lost for any input type), and its
/// index in the input (0, 1, ...), which makes every order deterministic
/// (ties are broken by index) and lets outputs be traced back to the input.
/// A trivially copyable 56-byte struct, written to temporary files as is.
struct Point_record
{
  /// x, y, z
  double position[3];
  /// nx, ny, nz (any length; zero when the input has no normal)
  double normal[3];
  /// the index of the point in the input
  std::uint64_t index;
};

static_assert(std::is_trivially_copyable<Point_record>::value, "Point_record is written to files as bytes");
static_assert(sizeof(Point_record) == 56, "Point_record has no padding");

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_POINT_RECORD_H
