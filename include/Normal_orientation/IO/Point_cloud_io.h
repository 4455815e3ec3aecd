// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Point_cloud_io.h
/// \brief Reading and writing point clouds with optional normals in the `.xyz`, `.pwn`
/// and `.ply` formats: `read_point_cloud()` and `write_point_cloud()`, which choose the
/// format by the extension, and the readers and writers of each format.
///
/// The functions only use the C++17 standard library and POSIX. Whole files are read
/// with a single `fread`, text is parsed with `std::from_chars` and written with
/// `std::to_chars` (or an exact, faster equivalent for a fixed number of digits), so that
/// clouds of millions of points are read and written in a fraction of a second. Large
/// `.xyz`/`.pwn` files are parsed and formatted by several `std::thread`s (see
/// `Read_options` and `Write_options`); the result is the same as with one thread, byte
/// for byte and error message for error message.
///
/// Reading a `.xyz`/`.pwn` file records how many significant digits its numbers have
/// (`Point_cloud::point_digits`, `Point_cloud::normal_digits`), so that the cloud can be
/// written back with no more digits than it was read with and still lose nothing
/// (`Write_options::PRECISION_AS_READ`).
///
/// Reading keeps, for a PLY input, every vertex property other than `x y z nx ny nz`
/// (for instance colours), so that they can be written back unchanged to a PLY output.
/// Elements of a PLY file other than `vertex` (for instance `face`) are skipped: their
/// data is not kept and is not written back.
///
/// Writing is atomic: the data are written to a temporary file in the directory of the
/// target, which is then renamed over the target. On failure the temporary file is
/// removed and an existing target is left untouched.
///
/// The parts, one idea a header: `Point_cloud.h` (the cloud and the options),
/// `Xyz_io.h` and `Ply_io.h` (the two formats), `File_format.h` (the format of a file
/// name), `Io_error.h` (the errors), and below them `Number_text.h`, `Text_lines.h`,
/// `Text_threads.h`, `Xyz_lines.h`, `Ply_types.h`, `Ply_header.h`, `Ply_data.h`,
/// `Byte_order.h`, `Input_file.h` and `Atomic_output_file.h`.

#ifndef NORMAL_ORIENTATION_IO_POINT_CLOUD_IO_H
#define NORMAL_ORIENTATION_IO_POINT_CLOUD_IO_H

#include <Normal_orientation/IO/File_format.h>
#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Ply_io.h>
#include <Normal_orientation/IO/Ply_types.h>
#include <Normal_orientation/IO/Point_cloud.h>
#include <Normal_orientation/IO/Xyz_io.h>

#include <string>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

/// \brief Reads a point cloud from `filename`, choosing the format from the extension
/// (case-insensitive): `.xyz` and `.pwn` with `read_xyz()`, `.ply` with `read_ply()`
/// (which ignores `options`).
/// \throws Io_error on an unknown extension or on any reading error.
inline Point_cloud read_point_cloud(const std::string& filename, const Read_options& options = Read_options())
{
  if(internal::file_format(filename) == internal::File_format::XYZ) return read_xyz(filename, options);
  return read_ply(filename);
}

/// \brief Writes `cloud` to `filename`, choosing the format from the extension
/// (case-insensitive): `.xyz` and `.pwn` with `write_xyz()`, `.ply` with `write_ply()`.
///
/// The file is written atomically: to `<filename>.tmp.<pid>.<n>` in the same directory,
/// then renamed over `filename`. On failure the temporary file is removed, no partial
/// output is left and an existing `filename` is unchanged.
/// \throws Io_error on an unknown extension or on any writing error.
inline void write_point_cloud(const std::string& filename, const Point_cloud& cloud,
                              Write_options options = {})
{
  if(internal::file_format(filename) == internal::File_format::XYZ) return write_xyz(filename, cloud, options);
  write_ply(filename, cloud, options);
}

/// @}

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_POINT_CLOUD_IO_H
