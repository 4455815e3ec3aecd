// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Point_cloud.h
/// \brief `Point_cloud`, a point cloud in memory as the readers of
/// `Point_cloud_io.h` give it and its writers take it, the options of reading and
/// writing it, and the checks a cloud passes before it is written: finite values,
/// consistent sizes, valid property names.

#ifndef NORMAL_ORIENTATION_IO_POINT_CLOUD_H
#define NORMAL_ORIENTATION_IO_POINT_CLOUD_H

#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Ply_types.h>
#include <Normal_orientation/IO/Text_lines.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

/// \brief In-memory point cloud with optional normals and optional extra per-vertex
/// properties.
///
/// `normals` is either empty or has one entry per point. `extra_values` holds the
/// values of `extra_properties`, row-major: the value of property `k` of point `i` is
/// `extra_values[i * extra_properties.size() + k]`. A `double` represents every PLY
/// scalar exactly, so a PLY to PLY round trip keeps every extra value bit for bit.
struct Point_cloud
{
  /// Point coordinates.
  std::vector<std::array<double, 3>> points;
  /// Normal vectors, one per point; empty when the cloud has no normals.
  std::vector<std::array<double, 3>> normals;
  /// Vertex properties of a PLY input other than `x y z nx ny nz`, in file order.
  std::vector<Ply_property> extra_properties;
  /// Values of `extra_properties`, row-major: `points.size() * extra_properties.size()`.
  std::vector<double> extra_values;
  /// PLY types of `x y z`: those of the PLY input, `FLOAT64` otherwise. They are used
  /// when writing a PLY file.
  std::array<Ply_scalar_type, 3> point_types{
    {Ply_scalar_type::FLOAT64, Ply_scalar_type::FLOAT64, Ply_scalar_type::FLOAT64}};
  /// PLY types of `nx ny nz`: those of the PLY input, `FLOAT32` otherwise. They are
  /// used when writing a PLY file, except integer types, which cannot hold unit normals:
  /// they are replaced by `FLOAT32` (8- and 16-bit types, whose values a `float` holds
  /// exactly) or `FLOAT64` (32-bit types), so that the values read are written exactly.
  std::array<Ply_scalar_type, 3> normal_types{
    {Ply_scalar_type::FLOAT32, Ply_scalar_type::FLOAT32, Ply_scalar_type::FLOAT32}};
  /// Largest number of significant decimal digits of a coordinate of a `.xyz`/`.pwn`
  /// input, counted as written: leading zeros are not counted, the other digits of the
  /// mantissa are, trailing zeros included, and the exponent is not (`0.012345` has 5,
  /// `1.2300e5` has 5, `-0` and `0.000` have 1). 0 means unknown: PLY input, text input
  /// without data lines, or cloud built in memory. Used by
  /// `Write_options::PRECISION_AS_READ`; a caller that replaces coordinates by computed
  /// values must reset it to 0.
  int point_digits = 0;
  /// Same as `point_digits` for the components of the normals; 0 when unknown or when
  /// the input has no normals. A caller that replaces normals by computed values (other
  /// than by negating them) must reset it to 0.
  int normal_digits = 0;

  /// \brief Returns `true` if the cloud has normals (`normals` is not empty).
  bool has_normals() const { return !normals.empty(); }
  /// \brief Returns the number of points.
  std::size_t size() const { return points.size(); }
};

/// \brief Options of `read_point_cloud()` (and `read_xyz()`).
struct Read_options
{
  /// `.xyz`/`.pwn` only: number of threads parsing the text. 0 chooses automatically:
  /// one thread for a file of at most 4 MB, otherwise `std::thread::hardware_concurrency()`
  /// threads, at most 8. A positive value is used whatever the file size, at most 8.
  /// The file is split at line boundaries into one chunk per thread; the cloud read, and
  /// the message of the first error in file order, do not depend on the number of threads.
  unsigned int number_of_threads = 0;
};

/// \brief Options of `write_point_cloud()` (and `write_xyz()`, `write_ply()`).
struct Write_options
{
  /// Value of `precision` that writes each value with the shortest text that reads back
  /// to the exact same `double`.
  static constexpr int PRECISION_SHORTEST = 0;
  /// Value of `precision` (any negative value does the same) that writes the values
  /// with as many significant digits as the `.xyz`/`.pwn` input had, when that is
  /// known to be lossless, and with `PRECISION_SHORTEST` otherwise. See `precision`.
  static constexpr int PRECISION_AS_READ = -1;

  /// PLY only: write `binary_little_endian` if `true`, `ascii` otherwise.
  bool binary = true;
  /// `.xyz`/`.pwn` only: how many significant digits each value is written with.
  /// - A positive value: that many significant digits (`%g` style, at most 17 are used).
  /// - `PRECISION_SHORTEST` (0): the shortest text that reads back to the exact same
  ///   `double`.
  /// - `PRECISION_AS_READ` (any negative value): the coordinates with
  ///   `Point_cloud::point_digits` significant digits (`%g` style) if it lies in
  ///   `[1, 15]`, with `PRECISION_SHORTEST` otherwise (unknown, i.e. 0, or more than 15);
  ///   the normals likewise with `Point_cloud::normal_digits`.
  ///
  /// Guarantee of `PRECISION_AS_READ`: if the cloud was read from a `.xyz`/`.pwn` file
  /// and its values were not changed since, except for the signs of some values (e.g.
  /// flipped normals; which signs changed is the caller's business), then reading the
  /// file written gives, bit for bit, the `double` values that reading the input gave
  /// (with the changed signs). Reason: a decimal number with `D <= 15` (`DBL_DIG`)
  /// significant digits read as the nearest `double` and printed back with `D` digits
  /// gives the same decimal number, which reads back to the same `double`; negating a
  /// `double` and its text are both exact. Above 15 digits this does not hold for `D`
  /// digits, and the shortest exact text is used. The written text may differ from
  /// the input text (`1.50` is written `1.5`, `1e3` is written `1e+03`), not the values.
  /// An ASCII PLY file is always written with the shortest exact representation of each
  /// value in its declared type, so that it round-trips.
  int precision = 9;
  /// `.xyz`/`.pwn` only: number of threads formatting the text. 0 chooses automatically:
  /// one thread for a small cloud (less than about 4 MB of text), otherwise
  /// `std::thread::hardware_concurrency()` threads, at most 8. A positive value is used
  /// whatever the size, at most 8. The file written does not depend on it, byte for byte.
  unsigned int number_of_threads = 0;
};

/// @}

namespace internal {

/// \brief Returns `true` if the three values `v[0..2]` are finite.
inline bool all_finite(const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

/// \brief Checks that the coordinates `point[0..2]` and, unless `normal` is null, the
/// normal `normal[0..2]` are finite; the error message names the point as `<where>
/// <position><suffix>`, e.g. `line 12` or `vertex 11 (byte offset 296)`.
inline void check_finite_values(const std::string& filename, const double* point, const double* normal,
                                const char* where, std::uint64_t position, const char* suffix = "")
{
  if(!all_finite(point))
    fail(filename, std::string("non-finite coordinate at ") + where + " " + std::to_string(position) + suffix);
  if(normal != nullptr && !all_finite(normal))
    fail(filename, std::string("non-finite normal at ") + where + " " + std::to_string(position) + suffix);
}

/// \brief Checks that `cloud` is consistent and finite before writing it to `filename`.
inline void check_writable(const std::string& filename, const Point_cloud& cloud, bool check_extras)
{
  const std::size_t n = cloud.points.size();
  if(!cloud.normals.empty() && cloud.normals.size() != n)
    fail(filename, "cannot write: " + std::to_string(cloud.normals.size()) + " normals for " +
                     std::to_string(n) + " points");
  for(std::size_t i = 0; i < n; ++i)
    if(!all_finite(cloud.points[i].data()))
      fail(filename, "cannot write non-finite coordinate at vertex " + std::to_string(i));
  for(std::size_t i = 0; i < cloud.normals.size(); ++i)
    if(!all_finite(cloud.normals[i].data()))
      fail(filename, "cannot write non-finite normal at vertex " + std::to_string(i));
  if(!check_extras) return;
  if(cloud.extra_values.size() != n * cloud.extra_properties.size())
    fail(filename, "cannot write: " + std::to_string(cloud.extra_values.size()) + " extra values for " +
                     std::to_string(n) + " points and " + std::to_string(cloud.extra_properties.size()) +
                     " extra properties");
  static const char* const reserved[6] = {"x", "y", "z", "nx", "ny", "nz"};
  for(std::size_t k = 0; k < cloud.extra_properties.size(); ++k) {
    const std::string& name = cloud.extra_properties[k].name;
    const bool blank = std::any_of(name.begin(), name.end(), [](char c) {
      return is_blank(c) || c == '\n' || c == '\0';
    });
    if(name.empty() || blank)
      fail(filename, "cannot write: invalid extra property name '" + name + "'");
    for(const char* r : reserved)
      if(name == r) fail(filename, "cannot write: extra property named '" + name + "'");
    for(std::size_t l = 0; l < k; ++l)
      if(cloud.extra_properties[l].name == name)
        fail(filename, "cannot write: two extra properties named '" + name + "'");
  }
}

} // namespace internal

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_POINT_CLOUD_H
