// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark-local fast reading and writing of `.xyz` files (x y z nx ny nz per line),
// based on std::from_chars / std::to_chars. Not part of the library's public API.
#ifndef NORMAL_ORIENTATION_BENCHMARK_XYZ_IO_H
#define NORMAL_ORIENTATION_BENCHMARK_XYZ_IO_H

#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <system_error>
#include <vector>

namespace Normal_orientation {
namespace benchmark {

/// One line of an `.xyz` file with normals: `{x, y, z, nx, ny, nz}`.
using Xyz_row = std::array<double, 6>;

/**
 * \brief Buffered writer of `.xyz` lines, formatting numbers with `std::to_chars`.
 *
 * Each number is written in `std::chars_format::general` with `precision` significant
 * digits (9 by default, enough for float-like precision and readable by any `.xyz` reader,
 * including `CGAL::IO::read_XYZ`). Lines are `x y z nx ny nz\n`.
 */
class Xyz_writer
{
public:
  /// Opens `path` for writing (truncates). Check `is_open()` afterwards.
  explicit Xyz_writer(const std::string& path, int precision = 9)
    : m_file(std::fopen(path.c_str(), "wb")), m_precision(precision)
  {
    m_buffer.reserve(s_capacity + 256);
  }

  /// Flushes and closes the file.
  ~Xyz_writer() { close(); }

  Xyz_writer(const Xyz_writer&) = delete;
  Xyz_writer& operator=(const Xyz_writer&) = delete;

  /// Returns `true` if the file could be opened and no write error occurred so far.
  bool is_open() const { return m_file != nullptr && !m_failed; }

  /// Appends one line `x y z nx ny nz`.
  void write_row(double x, double y, double z, double nx, double ny, double nz)
  {
    const double values[6] = {x, y, z, nx, ny, nz};
    char line[6 * 32];
    char* cursor = line;
    char* const end = line + sizeof(line);
    for(int i = 0; i < 6; ++i)
    {
      if(i != 0)
        *cursor++ = ' ';
      // -0 is written as 0 so that files do not depend on the sign of zero.
      const double v = (values[i] == 0.0) ? 0.0 : values[i];
      const std::to_chars_result r = std::to_chars(cursor, end, v, std::chars_format::general, m_precision);
      cursor = r.ptr;
    }
    *cursor++ = '\n';
    m_buffer.append(line, static_cast<std::size_t>(cursor - line));
    if(m_buffer.size() >= s_capacity)
      flush();
  }

  /// Writes the buffered lines to the file.
  void flush()
  {
    if(m_file == nullptr || m_buffer.empty())
      return;
    if(std::fwrite(m_buffer.data(), 1, m_buffer.size(), m_file) != m_buffer.size())
      m_failed = true;
    m_buffer.clear();
  }

  /// Flushes and closes the file; returns `true` if every write succeeded.
  bool close()
  {
    if(m_file == nullptr)
      return !m_failed;
    flush();
    if(std::fclose(m_file) != 0)
      m_failed = true;
    m_file = nullptr;
    return !m_failed;
  }

private:
  static constexpr std::size_t s_capacity = std::size_t(1) << 20;
  std::FILE* m_file;
  int m_precision;
  bool m_failed = false;
  std::string m_buffer;
};

/// \cond SKIP_IN_MANUAL
namespace internal {

/// Skips blanks (space, tab, carriage return) starting at `p`, not going past `end`.
inline const char* skip_blanks(const char* p, const char* end)
{
  while(p != end && (*p == ' ' || *p == '\t' || *p == '\r'))
    ++p;
  return p;
}

} // namespace internal
/// \endcond

/**
 * \brief Reads an `.xyz` file with normals into `rows`, in file order.
 *
 * Empty lines and lines starting with `#` are skipped; like `CGAL::IO::read_XYZ`, a first
 * line holding a single number (a point count) is skipped too. Every other line must start
 * with six numbers; further columns are ignored.
 *
 * \return `true` on success; on failure `error` explains why (file, line number).
 */
inline bool read_xyz_rows(const std::string& path, std::vector<Xyz_row>& rows, std::string& error)
{
  rows.clear();
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if(file == nullptr)
  {
    error = "cannot open '" + path + "'";
    return false;
  }
  std::string content;
  char chunk[1 << 16];
  std::size_t got = 0;
  while((got = std::fread(chunk, 1, sizeof(chunk), file)) > 0)
    content.append(chunk, got);
  const bool read_error = std::ferror(file) != 0;
  std::fclose(file);
  if(read_error)
  {
    error = "read error on '" + path + "'";
    return false;
  }

  const char* p = content.data();
  const char* const end = p + content.size();
  std::size_t line_number = 0;
  while(p != end)
  {
    const char* line_end = p;
    while(line_end != end && *line_end != '\n')
      ++line_end;
    ++line_number;

    const char* q = internal::skip_blanks(p, line_end);
    if(q != line_end && *q != '#')
    {
      Xyz_row row{};
      int count = 0;
      while(count < 6)
      {
        q = internal::skip_blanks(q, line_end);
        if(q != line_end && *q == '+')
          ++q;
        const std::from_chars_result r = std::from_chars(q, line_end, row[count]);
        if(r.ec != std::errc() || r.ptr == q)
          break;
        q = r.ptr;
        ++count;
      }
      if(count == 6)
        rows.push_back(row);
      else if(!(count == 1 && line_number == 1 && internal::skip_blanks(q, line_end) == line_end))
      {
        error = "'" + path + "' line " + std::to_string(line_number) + ": expected 6 numbers (x y z nx ny nz), got "
              + std::to_string(count);
        return false;
      }
    }
    p = (line_end == end) ? end : line_end + 1;
  }
  return true;
}

/// Returns the bounding-box diagonal of the points of `rows`.
inline double bbox_diagonal(const std::vector<Xyz_row>& rows)
{
  if(rows.empty())
    return 0.0;
  double lo[3] = {rows[0][0], rows[0][1], rows[0][2]};
  double hi[3] = {lo[0], lo[1], lo[2]};
  for(const Xyz_row& r : rows)
    for(int c = 0; c < 3; ++c)
    {
      lo[c] = std::fmin(lo[c], r[c]);
      hi[c] = std::fmax(hi[c], r[c]);
    }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/**
 * Checks that `oriented` has the points of `truth` in the same order, each within
 * `1e-5 x` the truth's bounding-box diagonal (both files may be written with 9 digits).
 * Returns an empty string on success, else the reason.
 */
inline std::string check_same_points(const std::vector<Xyz_row>& oriented, const std::vector<Xyz_row>& truth)
{
  if(oriented.size() != truth.size())
    return "the oriented cloud has " + std::to_string(oriented.size()) + " points, the truth " +
           std::to_string(truth.size()) + ": not the same cloud";
  const double tolerance = 1e-5 * bbox_diagonal(truth);
  for(std::size_t i = 0; i < truth.size(); ++i)
  {
    const double dx = oriented[i][0] - truth[i][0];
    const double dy = oriented[i][1] - truth[i][1];
    const double dz = oriented[i][2] - truth[i][2];
    const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
    if(!(d <= tolerance))
    {
      char message[256];
      std::snprintf(message, sizeof message,
                    "point %zu (counted from 0) is %.3g away from the truth's (tolerance %.3g): "
                    "the files do not hold the same points in the same order",
                    i, d, tolerance);
      return message;
    }
  }
  return std::string();
}

/**
 * \brief Reads an oriented cloud and its truth (`.xyz` files, as `read_xyz_rows()`) and checks
 * that the truth has points and that both hold them in the same order (`check_same_points()`).
 *
 * \return `true` on success; on failure `error` explains why.
 */
inline bool read_oriented_and_truth(const std::string& oriented_path, const std::string& truth_path,
                                    std::vector<Xyz_row>& oriented, std::vector<Xyz_row>& truth, std::string& error)
{
  if(!read_xyz_rows(oriented_path, oriented, error) || !read_xyz_rows(truth_path, truth, error))
    return false;
  if(truth.empty())
  {
    error = "'" + truth_path + "' holds no point";
    return false;
  }
  error = check_same_points(oriented, truth);
  if(!error.empty())
  {
    error = "'" + oriented_path + "' against '" + truth_path + "': " + error;
    return false;
  }
  return true;
}

/// The command line of a program that reads an oriented cloud and its truth:
/// the two files, and whether `--json` was given.
struct Oriented_and_truth_command
{
  std::string oriented, truth;
  bool json = false;
};

/**
 * \brief Parses the command line of a program that reads an oriented cloud and its truth, then
 * reads both files (`read_oriented_and_truth()`).
 *
 * `-h` or `--help` prints `usage` to stdout and exits with 0. `--json` sets `json`. Every other
 * argument starting with '-' goes to `option(argument, i)`, which returns `true` when it took it
 * (and may step `i` over its value; a bad value is for it to report, exiting with 2). An option
 * it does not take, or a count of files other than two, prints the usage to stderr and exits
 * with 2; a file that cannot be read or does not match prints `program: reason` and exits with 1.
 */
template <typename Option>
Oriented_and_truth_command read_oriented_and_truth_command(int argc, char** argv, const char* program,
                                                           void (*usage)(std::FILE*), Option option,
                                                           std::vector<Xyz_row>& oriented, std::vector<Xyz_row>& truth)
{
  Oriented_and_truth_command c;
  std::vector<std::string> files;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if(arg == "-h" || arg == "--help")
    {
      usage(stdout);
      std::exit(0);
    }
    if(arg == "--json")
      c.json = true;
    else if(!arg.empty() && arg[0] == '-' && arg != "-")
    {
      if(!option(arg, i))
      {
        std::fprintf(stderr, "%s: unknown option '%s'\n", program, arg.c_str());
        usage(stderr);
        std::exit(2);
      }
    }
    else
      files.push_back(arg);
  }
  if(files.size() != 2)
  {
    usage(stderr);
    std::exit(2);
  }
  c.oriented = files[0];
  c.truth = files[1];
  std::string error;
  if(!read_oriented_and_truth(c.oriented, c.truth, oriented, truth, error))
  {
    std::fprintf(stderr, "%s: %s\n", program, error.c_str());
    std::exit(1);
  }
  return c;
}

} // namespace benchmark
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_BENCHMARK_XYZ_IO_H
