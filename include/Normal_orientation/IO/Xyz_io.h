// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Xyz_io.h
/// \brief Reading and writing whole `.xyz`/`.pwn` point clouds in memory: `read_xyz()`
/// and `write_xyz()`, the text parsed and formatted by several threads for large files,
/// with the result of one thread.

#ifndef NORMAL_ORIENTATION_IO_XYZ_IO_H
#define NORMAL_ORIENTATION_IO_XYZ_IO_H

#include <Normal_orientation/IO/Atomic_output_file.h>
#include <Normal_orientation/IO/Input_file.h>
#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Number_text.h>
#include <Normal_orientation/IO/Point_cloud.h>
#include <Normal_orientation/IO/Text_lines.h>
#include <Normal_orientation/IO/Text_threads.h>
#include <Normal_orientation/IO/Xyz_lines.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cfloat>
#include <condition_variable>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace Normal_orientation {
namespace IO {
namespace internal {

/// \brief Result of parsing a chunk of whole lines of a `.xyz`/`.pwn` text on its own;
/// line numbers are relative to the chunk (the first line of the chunk is line 1).
struct Xyz_chunk
{
  std::vector<std::array<double, 3>> points;
  std::vector<std::array<double, 3>> normals;
  std::size_t lines = 0;           // lines of the chunk (unset after an error)
  std::size_t columns = 0;         // values of the first data line, 0 if none
  std::size_t first_data_line = 0; // 0 if none
  int point_digits = 0;            // as `Point_cloud::point_digits` (unset after an error)
  int normal_digits = 0;           // as `Point_cloud::normal_digits` (unset after an error)
  Xyz_error error = Xyz_error::NONE; // first error of the chunk, which stops parsing
  std::size_t error_line = 0;
  std::size_t error_values = 0; // COLUMN_COUNT, COLUMN_MISMATCH: values on the line
  std::string error_token;      // NON_NUMERIC, OUT_OF_RANGE: the token, quoted
};

/// \brief Parses the whole lines `[p, end)` of a `.xyz`/`.pwn` text into `chunk`, as
/// `read_xyz()` specifies, up to the first error, which is recorded in `chunk`.
inline void parse_xyz_chunk(const char* p, const char* const end, Xyz_chunk& chunk)
{
  chunk.points.reserve(count_newlines(p, end) + 1);
  std::size_t columns = 0;
  std::size_t line = 0;
  int digits[2] = {0, 0}; // of coordinates, of normals
  auto failed = [&chunk, &line](Xyz_error error) {
    chunk.error = error;
    chunk.error_line = line;
  };
  while(p < end) {
    ++line;
    const char* const eol = end_of_line(p, end);
    std::array<double, 6> values{};
    std::size_t n = 0;
    const char* const q = p;
    p = (eol < end) ? eol + 1 : end;
    const Xyz_error error = parse_xyz_values(q, eol, values, n, digits, chunk.error_token);
    if(error != Xyz_error::NONE) return failed(error);
    if(n == 0) continue; // blank or comment line
    const bool first = columns == 0;
    const Xyz_error line_error = check_xyz_data_line(values, n, columns);
    if(first && columns != 0) {
      chunk.columns = n;
      chunk.first_data_line = line;
      if(columns == 6) chunk.normals.reserve(chunk.points.capacity());
    }
    if(line_error != Xyz_error::NONE) {
      chunk.error_values = n;
      return failed(line_error);
    }
    chunk.points.push_back({{values[0], values[1], values[2]}});
    if(n == 6) chunk.normals.push_back({{values[3], values[4], values[5]}});
  }
  chunk.lines = line;
  chunk.point_digits = digits[0];
  chunk.normal_digits = digits[1];
}

/// \brief The cloud made of the consecutive `chunks` of the text file `filename`, or
/// the first error in file order, with line numbers counted from the start of the file.
/// The chunks are consumed.
inline Point_cloud merge_xyz_chunks(const std::string& filename, std::vector<Xyz_chunk>& chunks)
{
  std::size_t columns = 0;
  std::size_t first_data_line = 0;
  std::size_t lines_before = 0; // lines of the previous chunks
  Point_cloud cloud;
  std::size_t point_count = 0;
  for(const Xyz_chunk& chunk : chunks) {
    if(chunk.columns != 0) {
      // No error precedes the first data line of a chunk.
      if(columns == 0) {
        columns = chunk.columns;
        first_data_line = lines_before + chunk.first_data_line;
      } else if(chunk.columns != columns) {
        fail(filename, xyz_error_message(Xyz_error::COLUMN_MISMATCH, lines_before + chunk.first_data_line,
                                         chunk.columns, std::string(), first_data_line, columns));
      }
    }
    if(chunk.error != Xyz_error::NONE)
      fail(filename, xyz_error_message(chunk.error, lines_before + chunk.error_line, chunk.error_values,
                                       chunk.error_token, first_data_line, columns));
    lines_before += chunk.lines;
    point_count += chunk.points.size();
    cloud.point_digits = std::max(cloud.point_digits, chunk.point_digits);
    cloud.normal_digits = std::max(cloud.normal_digits, chunk.normal_digits);
  }
  if(chunks.size() == 1) {
    cloud.points = std::move(chunks[0].points);
    cloud.normals = std::move(chunks[0].normals);
    return cloud;
  }
  cloud.points.reserve(point_count);
  if(columns == 6) cloud.normals.reserve(point_count);
  for(Xyz_chunk& chunk : chunks) {
    cloud.points.insert(cloud.points.end(), chunk.points.begin(), chunk.points.end());
    cloud.normals.insert(cloud.normals.end(), chunk.normals.begin(), chunk.normals.end());
    chunk.points = {};
    chunk.normals = {};
  }
  return cloud;
}

/// \brief Writes the lines of points `[first, last)` of `cloud` as `write_xyz()`
/// specifies at `out`, which must have room for `(last - first) * 6 * (max_real_length
/// + 1)` characters; returns the end of the text.
inline char* format_xyz_lines(char* out, const Point_cloud& cloud, std::size_t first, std::size_t last,
                              int point_precision, int normal_precision)
{
  const bool normals = cloud.has_normals();
  for(std::size_t i = first; i < last; ++i) {
    const std::array<double, 3>& p = cloud.points[i];
    out = format_real(out, p[0], point_precision);
    *out++ = ' ';
    out = format_real(out, p[1], point_precision);
    *out++ = ' ';
    out = format_real(out, p[2], point_precision);
    if(normals) {
      const std::array<double, 3>& v = cloud.normals[i];
      *out++ = ' ';
      out = format_real(out, v[0], normal_precision);
      *out++ = ' ';
      out = format_real(out, v[1], normal_precision);
      *out++ = ' ';
      out = format_real(out, v[2], normal_precision);
    }
    *out++ = '\n';
  }
  return out;
}

/// \brief Precision used for values read with `digits` significant digits when the
/// requested precision is `requested` (see `Write_options::precision`).
inline int effective_precision(int requested, int digits)
{
  if(requested >= 0) return requested;
  return (digits >= 1 && digits <= DBL_DIG) ? digits : Write_options::PRECISION_SHORTEST;
}

/// \brief Number of points formatted at once by one thread of `write_xyz()`.
constexpr std::size_t xyz_block_points = 16384;

/// \brief The cloud of the `.xyz`/`.pwn` text `[begin, end)`, as `read_xyz()` reads
/// it from the file `filename` (named in the error messages only).
inline Point_cloud parse_xyz_text(const std::string& filename, const char* begin, const char* end,
                                  const Read_options& options)
{
  const unsigned int threads = text_thread_count(options.number_of_threads, static_cast<std::size_t>(end - begin));
  const std::vector<const char*> bounds = split_at_lines(begin, end, threads);
  std::vector<Xyz_chunk> chunks(threads);
  run_concurrently(threads,
                   [&bounds, &chunks](std::size_t i) { parse_xyz_chunk(bounds[i], bounds[i + 1], chunks[i]); });
  return merge_xyz_chunks(filename, chunks);
}

} // namespace internal

/// \addtogroup PkgNormalOrientationIO
/// @{

/// \brief Reads a text point cloud (`.xyz` or `.pwn` layout) from `filename`, whatever
/// its extension.
///
/// Each line holds `x y z` or `x y z nx ny nz`, separated by blanks; every data line
/// must have the same number of values. Blank lines and lines starting with `#` are
/// skipped. Normals may be zero but coordinates and normals must be finite. The largest
/// numbers of significant digits of the coordinates and of the normals are recorded in
/// `point_digits` and `normal_digits`. A large file is parsed by several threads (see
/// `Read_options::number_of_threads`), with the same result.
/// \throws Io_error on any error (unreadable file, non-numeric token, wrong column count,
/// non-finite value), naming the file and the line; with several errors, the first one
/// in the file.
inline Point_cloud read_xyz(const std::string& filename, const Read_options& options = Read_options())
{
  const internal::File_content content = internal::read_file_content(filename);
  return internal::parse_xyz_text(filename, content.begin(), content.end(), options);
}

/// \brief Writes `cloud` to `filename` as text, whatever its extension: one line
/// `x y z nx ny nz` per point (`x y z` without normals), with the precision given by
/// `options.precision` (see `Write_options::precision`, notably `PRECISION_AS_READ`).
/// Extra properties are not written.
///
/// A large cloud is formatted by several threads (see `Write_options::number_of_threads`),
/// each formatting blocks of points that are written in order: the file does not depend
/// on the number of threads. The file is written atomically (temporary file renamed
/// over `filename`).
/// \throws Io_error if `cloud` is inconsistent or not finite, or on any writing error;
/// no file is left behind then and an existing `filename` is unchanged.
inline void write_xyz(const std::string& filename, const Point_cloud& cloud,
                      const Write_options& options = Write_options())
{
  using namespace internal;
  check_writable(filename, cloud, false);
  Atomic_output_file out(filename);
  const int point_precision = effective_precision(options.precision, cloud.point_digits);
  const int normal_precision = effective_precision(options.precision, cloud.normal_digits);
  const std::size_t n = cloud.points.size();
  const std::size_t columns = cloud.has_normals() ? 6 : 3;
  const std::size_t blocks = (n + xyz_block_points - 1) / xyz_block_points;
  const std::size_t estimated_size = n * columns * 12; // about 12 bytes per value
  const std::size_t threads = std::min<std::size_t>(text_thread_count(options.number_of_threads, estimated_size),
                                                    std::max<std::size_t>(blocks, 1));
  const std::size_t buffer_size = std::min(n, xyz_block_points) * columns * (max_real_length + 1) + 1;

  // Each thread takes the next block, formats it in its buffer, waits for the previous
  // blocks to be written, then writes it: blocks are formatted concurrently and written
  // in order, by one thread at a time.
  std::atomic<std::size_t> next_block{0};
  std::mutex mutex;
  std::condition_variable turn_changed;
  std::size_t turn = 0;  // next block to write (guarded by `mutex`)
  bool aborted = false;  // a write failed (guarded by `mutex`)
  run_concurrently(threads, [&](std::size_t) {
    const std::unique_ptr<char[]> buffer(new char[buffer_size]);
    for(;;) {
      const std::size_t block = next_block.fetch_add(1);
      if(block >= blocks) return;
      const std::size_t first = block * xyz_block_points;
      const char* const text_end = format_xyz_lines(buffer.get(), cloud, first,
                                                    std::min(n, first + xyz_block_points),
                                                    point_precision, normal_precision);
      {
        std::unique_lock<std::mutex> lock(mutex);
        turn_changed.wait(lock, [&] { return turn == block || aborted; });
        if(aborted) return;
      }
      try {
        out.put(std::string_view(buffer.get(), static_cast<std::size_t>(text_end - buffer.get())));
      } catch(...) {
        {
          const std::lock_guard<std::mutex> lock(mutex);
          aborted = true;
        }
        turn_changed.notify_all();
        throw;
      }
      {
        const std::lock_guard<std::mutex> lock(mutex);
        ++turn;
      }
      turn_changed.notify_all();
    }
  });
  out.commit();
}

/// @}

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_XYZ_IO_H
