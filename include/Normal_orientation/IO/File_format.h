// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file File_format.h
/// \brief The format of a point cloud file, told by its extension: `.xyz` and `.pwn`
/// (text), `.ply`; one rule, and one message for an unknown extension, for every reader
/// and writer.

#ifndef NORMAL_ORIENTATION_IO_FILE_FORMAT_H
#define NORMAL_ORIENTATION_IO_FILE_FORMAT_H

#include <Normal_orientation/IO/Io_error.h>

#include <cctype>
#include <filesystem>
#include <string>

namespace Normal_orientation {
namespace IO {

/// \ingroup PkgNormalOrientationIO
/// \brief Extension of `filename`, with its dot, lower-cased (`"cloud.PLY"` gives
/// `".ply"`; no extension gives `""`): what the readers and writers of
/// `Normal_orientation::IO` choose the format of a file by.
inline std::string lower_case_extension(const std::string& filename)
{
  std::string extension = std::filesystem::path(filename).extension().string();
  for(char& c : extension)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

namespace internal {

/// \brief The formats of point cloud files.
enum class File_format
{
  XYZ, ///< text, `.xyz` or `.pwn`
  PLY  ///< `.ply`
};

/// \brief Format of `filename` by its extension (case-insensitive).
/// \throws Io_error `<filename>: unknown point cloud file extension '<ext>' (expected
/// .xyz, .pwn or .ply)` for any other extension.
inline File_format file_format(const std::string& filename)
{
  const std::string extension = lower_case_extension(filename);
  if(extension == ".xyz" || extension == ".pwn") return File_format::XYZ;
  if(extension == ".ply") return File_format::PLY;
  fail(filename, "unknown point cloud file extension '" + extension + "' (expected .xyz, .pwn or .ply)");
}

} // namespace internal

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_FILE_FORMAT_H
