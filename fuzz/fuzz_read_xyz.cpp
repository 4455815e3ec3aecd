// SPDX-License-Identifier: GPL-3.0-or-later
/// \file fuzz_read_xyz.cpp
/// \brief libFuzzer target of the in-core `.xyz`/`.pwn` reader (`IO::read_xyz()`, which
/// parses the content of the file with `IO::internal::parse_xyz_text()`, called here on
/// the input bytes).
///
/// An `Io_error` is a normal outcome; its message must name the file, be one printable
/// line and name a line of the input. The input is parsed by one thread and by three
/// (the text split in three chunks at line boundaries): the cloud, or the error message,
/// must be the same. A cloud read must satisfy the reader's contract (finite values,
/// one point per data line, normals absent or one per point, significant digits
/// recorded) and come back bit for bit from the files `IO::write_xyz()` writes with
/// `PRECISION_AS_READ` (after changing some signs, as the guarantee allows) and with
/// `PRECISION_SHORTEST`.

#include "Fuzz_common.h"

#include <Normal_orientation/IO/Point_cloud_io.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace {

/// \brief Number of data lines of `[p, end)`: lines that are neither blank nor start
/// with `#` after their leading blanks (counted here independently of the reader).
std::size_t data_lines(const char* p, const char* end)
{
  std::size_t count = 0;
  bool line_start = true;
  bool counted = false;
  for(; p != end; ++p) {
    const char c = *p;
    if(c == '\n') {
      line_start = true;
      counted = false;
      continue;
    }
    if(!line_start || counted) continue;
    if(c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f') continue;
    line_start = false;
    if(c != '#') {
      ++count;
      counted = true;
    }
  }
  return count;
}

/// \brief Writes `cloud` with `precision` and checks that it reads back unchanged.
void check_text_round_trip(const fuzz::IO::Point_cloud& cloud, int precision, const std::string& what)
{
  namespace IO = fuzz::IO;
  const std::string written = fuzz::directory() + "/round_trip.xyz";
  IO::Write_options options;
  options.precision = precision;
  const std::string write_error = fuzz::io_error_of([&] { IO::write_xyz(written, cloud, options); });
  FUZZ_CHECK(write_error.empty(), what + ": a cloud read cannot be written: " + write_error);
  IO::Point_cloud back;
  const std::string read_error = fuzz::io_error_of([&] { back = IO::read_xyz(written); });
  FUZZ_CHECK(read_error.empty(), what + ": the file written cannot be read: " + read_error);
  fuzz::check_same_cloud(cloud, back, what);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  namespace IO = fuzz::IO;
  const std::string filename = "input.xyz";
  const char* const begin = reinterpret_cast<const char*>(data);
  const char* const end = begin + size;

  IO::Read_options one_thread;
  one_thread.number_of_threads = 1;
  IO::Read_options three_threads;
  three_threads.number_of_threads = 3;
  IO::Point_cloud cloud;
  IO::Point_cloud parallel;
  const std::string error =
    fuzz::io_error_of([&] { cloud = IO::internal::parse_xyz_text(filename, begin, end, one_thread); });
  const std::string parallel_error =
    fuzz::io_error_of([&] { parallel = IO::internal::parse_xyz_text(filename, begin, end, three_threads); });
  FUZZ_CHECK(error == parallel_error, "1 thread: '" + error + "', 3 threads: '" + parallel_error + "'");
  if(!error.empty()) {
    fuzz::check_error_message(error, filename, size, fuzz::line_count(begin, size));
    FUZZ_CHECK(error.find(" at line ") != std::string::npos, "the error names no line: " + error);
    return 0;
  }
  fuzz::check_same_cloud(cloud, parallel, "1 thread against 3");
  FUZZ_CHECK(cloud.point_digits == parallel.point_digits && cloud.normal_digits == parallel.normal_digits,
             "the digits depend on the number of threads");
  fuzz::check_cloud(cloud, false);
  FUZZ_CHECK(cloud.extra_properties.empty(), "extra properties in a text cloud");

  const std::size_t n = cloud.size();
  FUZZ_CHECK(n == data_lines(begin, end),
             std::to_string(n) + " points for " + std::to_string(data_lines(begin, end)) + " data lines");
  FUZZ_CHECK((n == 0) == (cloud.point_digits == 0), "point_digits " + std::to_string(cloud.point_digits));
  FUZZ_CHECK(cloud.has_normals() == (cloud.normal_digits != 0), "normal_digits " + std::to_string(cloud.normal_digits));
  FUZZ_CHECK(cloud.point_digits >= 0 && cloud.normal_digits >= 0, "negative digits");

  // Written with the digits read (some signs changed, as the guarantee allows) and with
  // the shortest exact text, the cloud reads back bit for bit.
  IO::Point_cloud changed = cloud;
  for(std::size_t i = 0; i < n; ++i) {
    if(i % 3 == 0) changed.points[i][i % 2] = -changed.points[i][i % 2];
    if(cloud.has_normals() && i % 2 == 0) changed.normals[i][2] = -changed.normals[i][2];
  }
  check_text_round_trip(changed, IO::Write_options::PRECISION_AS_READ, "precision as read");
  check_text_round_trip(cloud, IO::Write_options::PRECISION_SHORTEST, "shortest precision");
  return 0;
}
