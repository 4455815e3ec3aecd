// SPDX-License-Identifier: GPL-3.0-or-later
/// \file Fuzz_common.h
/// \brief Helpers shared by the libFuzzer targets of the point cloud readers: checks
/// that abort with a message, the checks of an error message and of a cloud, and a
/// private temporary directory (in `TMPDIR`, else `/dev/shm`, else `/tmp`).

#ifndef NORMAL_ORIENTATION_FUZZ_FUZZ_COMMON_H
#define NORMAL_ORIENTATION_FUZZ_FUZZ_COMMON_H

#include <Normal_orientation/IO/Point_cloud_io.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

namespace fuzz {

namespace IO = Normal_orientation::IO;

/// \brief Reports a broken invariant and aborts, which libFuzzer records as a crash.
[[noreturn]] inline void fail(const char* file, int line, const char* condition, const std::string& detail)
{
  std::fprintf(stderr, "\n*** invariant broken at %s:%d: %s\n*** %s\n", file, line, condition, detail.c_str());
  std::fflush(stderr);
  std::abort();
}

} // namespace fuzz

/// Aborts with `detail` (a `std::string` expression) when `condition` is false.
#define FUZZ_CHECK(condition, detail)                                                                       \
  do {                                                                                                      \
    if(!(condition)) ::fuzz::fail(__FILE__, __LINE__, #condition, (detail));                                \
  } while(false)

namespace fuzz {

/// \brief A private directory for the files of this process, removed at exit (a
/// crashing run may leave it behind: the fuzzing script removes its `TMPDIR`).
inline const std::string& directory()
{
  static std::string path;
  if(!path.empty()) return path;
  std::string base = "/tmp";
  const char* tmpdir = std::getenv("TMPDIR");
  if(tmpdir != nullptr && *tmpdir != '\0') base = tmpdir;
  else if(::access("/dev/shm", W_OK) == 0) base = "/dev/shm";
  std::string pattern = base + "/normal_orientation_fuzz_XXXXXX";
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  if(::mkdtemp(name.data()) == nullptr) {
    std::perror(("cannot create a directory in " + base).c_str());
    std::abort();
  }
  path = name.data();
  std::atexit([] {
    std::error_code error;
    std::filesystem::remove_all(path, error);
  });
  return path;
}

/// \brief Writes `[data, data + size)` to `filename`, aborting on failure.
inline void write_file(const std::string& filename, const std::uint8_t* data, std::size_t size)
{
  std::FILE* file = std::fopen(filename.c_str(), "wb");
  if(file == nullptr || (size != 0 && std::fwrite(data, 1, size, file) != size) || std::fclose(file) != 0) {
    std::perror(("cannot write " + filename).c_str());
    std::abort();
  }
}

/// \brief Message of the `Io_error` thrown by `action`, or an empty string if it threw
/// nothing. Any other exception escapes, and libFuzzer reports it.
inline std::string io_error_of(const std::function<void()>& action)
{
  try {
    action();
  } catch(const IO::Io_error& error) {
    std::string message = error.what();
    FUZZ_CHECK(!message.empty(), "empty error message");
    return message;
  }
  return std::string();
}

/// \brief Number of lines of `[data, data + size)` (a last line without `'\n'` counts).
inline std::size_t line_count(const char* data, std::size_t size)
{
  const std::size_t newlines = static_cast<std::size_t>(std::count(data, data + size, '\n'));
  return newlines + (size != 0 && data[size - 1] != '\n' ? 1 : 0);
}

/// \brief Checks an error message of a reader of `filename`, whose content has `size`
/// bytes in `lines` lines: one line that starts with `<filename>: `, then printable
/// text; every `line N` it names is a line of the file and every `byte offset N` is
/// within it.
inline void check_error_message(const std::string& message, const std::string& filename, std::size_t size,
                                std::size_t lines)
{
  const std::string prefix = filename + ": ";
  FUZZ_CHECK(message.compare(0, prefix.size(), prefix) == 0, "message without the file name: " + message);
  FUZZ_CHECK(message.size() > prefix.size() + 3, "message without text: " + message);
  for(std::size_t i = prefix.size(); i < message.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(message[i]);
    FUZZ_CHECK(c >= 0x20 && c != 0x7F, "control character " + std::to_string(c) + " in the message: " + message);
  }
  auto check_numbers = [&](const std::string& word, std::size_t maximum, std::size_t minimum) {
    for(std::size_t at = message.find(word, prefix.size()); at != std::string::npos;
        at = message.find(word, at + 1)) {
      const std::size_t first = at + word.size();
      std::size_t last = first;
      while(last < message.size() && message[last] >= '0' && message[last] <= '9') ++last;
      if(last == first || last - first > 19) continue;
      const unsigned long long value = std::stoull(message.substr(first, last - first));
      FUZZ_CHECK(value >= minimum && value <= maximum,
                 word + std::to_string(value) + " outside [" + std::to_string(minimum) + ", " +
                   std::to_string(maximum) + "]: " + message);
    }
  };
  check_numbers(" line ", std::max<std::size_t>(lines, 1), 1);
  check_numbers("byte offset ", size, 0);
}

/// \brief Bit pattern of `value`.
inline std::uint64_t bits(double value)
{
  std::uint64_t result = 0;
  std::memcpy(&result, &value, sizeof(result));
  return result;
}

/// \brief Returns `true` if `a` and `b` are the same value (bit for bit, or both NaN).
inline bool same_value(double a, double b) { return bits(a) == bits(b) || (std::isnan(a) && std::isnan(b)); }

/// \brief Text of `value` for a message.
inline std::string text(double value)
{
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

/// \brief Checks the invariants of any cloud returned by a reader: normals absent or
/// one per point, coordinates and normals finite, one extra value per point and extra
/// property, integer-typed values integral and in the range of their type,
/// `float`-typed values exactly `float`s (`typed`: a PLY cloud, whose `point_types` and
/// `normal_types` are those of the file; the values of a text cloud are `double`s).
inline void check_cloud(const IO::Point_cloud& cloud, bool typed)
{
  const std::size_t n = cloud.points.size();
  FUZZ_CHECK(cloud.normals.empty() || cloud.normals.size() == n,
             std::to_string(cloud.normals.size()) + " normals for " + std::to_string(n) + " points");
  FUZZ_CHECK(cloud.extra_values.size() == n * cloud.extra_properties.size(),
             std::to_string(cloud.extra_values.size()) + " extra values");
  auto check_typed = [typed](double value, IO::Ply_scalar_type type, bool may_be_non_finite,
                             const std::string& what) {
    if(!typed) type = IO::Ply_scalar_type::FLOAT64;
    if(!std::isfinite(value)) {
      FUZZ_CHECK(may_be_non_finite, "non-finite " + what + ": " + text(value));
      FUZZ_CHECK(type == IO::Ply_scalar_type::FLOAT32 || type == IO::Ply_scalar_type::FLOAT64,
                 "non-finite " + what + " of an integer type");
      return;
    }
    if(type == IO::Ply_scalar_type::FLOAT64) return;
    if(type == IO::Ply_scalar_type::FLOAT32) {
      FUZZ_CHECK(static_cast<double>(static_cast<float>(value)) == value, what + " not a float: " + text(value));
      return;
    }
    const std::pair<double, double> range = IO::internal::integer_range(type);
    FUZZ_CHECK(value >= range.first && value <= range.second && value == std::trunc(value),
               what + " not an integer of its type: " + text(value));
    FUZZ_CHECK(bits(value) != bits(-0.0), what + " of an integer type is -0");
  };
  for(std::size_t i = 0; i < n; ++i)
    for(std::size_t c = 0; c < 3; ++c) {
      check_typed(cloud.points[i][c], cloud.point_types[c], false, "coordinate of point " + std::to_string(i));
      if(cloud.has_normals())
        check_typed(cloud.normals[i][c], cloud.normal_types[c], false, "normal of point " + std::to_string(i));
    }
  const std::size_t extras = cloud.extra_properties.size();
  for(std::size_t k = 0; k < extras; ++k) {
    const std::string& name = cloud.extra_properties[k].name;
    FUZZ_CHECK(!name.empty(), "empty extra property name");
    for(const char* reserved : {"x", "y", "z", "nx", "ny", "nz"})
      FUZZ_CHECK(name != reserved, "extra property named " + name);
    for(std::size_t i = 0; i < n; ++i)
      check_typed(cloud.extra_values[i * extras + k], cloud.extra_properties[k].type, true,
                  "extra value '" + name + "' of point " + std::to_string(i));
  }
}

/// \brief Checks that `b` holds the points, normals and extra values of `a`, bit for bit
/// (NaN extra values: NaN), and the same extra properties; `what` names the comparison.
inline void check_same_cloud(const IO::Point_cloud& a, const IO::Point_cloud& b, const std::string& what)
{
  FUZZ_CHECK(a.points.size() == b.points.size(),
             what + ": " + std::to_string(a.points.size()) + " against " + std::to_string(b.points.size()) + " points");
  FUZZ_CHECK(a.normals.size() == b.normals.size(), what + ": not the same number of normals");
  for(std::size_t i = 0; i < a.points.size(); ++i)
    for(std::size_t c = 0; c < 3; ++c) {
      FUZZ_CHECK(bits(a.points[i][c]) == bits(b.points[i][c]),
                 what + ": point " + std::to_string(i) + ": " + text(a.points[i][c]) + " became " +
                   text(b.points[i][c]));
      if(a.has_normals())
        FUZZ_CHECK(bits(a.normals[i][c]) == bits(b.normals[i][c]),
                   what + ": normal " + std::to_string(i) + ": " + text(a.normals[i][c]) + " became " +
                     text(b.normals[i][c]));
    }
  FUZZ_CHECK(a.extra_properties.size() == b.extra_properties.size(), what + ": not the same extra properties");
  for(std::size_t k = 0; k < a.extra_properties.size(); ++k)
    FUZZ_CHECK(a.extra_properties[k].name == b.extra_properties[k].name &&
                 a.extra_properties[k].type == b.extra_properties[k].type,
               what + ": extra property " + a.extra_properties[k].name + " changed");
  FUZZ_CHECK(a.extra_values.size() == b.extra_values.size(), what + ": not the same number of extra values");
  for(std::size_t i = 0; i < a.extra_values.size(); ++i)
    FUZZ_CHECK(same_value(a.extra_values[i], b.extra_values[i]),
               what + ": extra value " + std::to_string(i) + ": " + text(a.extra_values[i]) + " became " +
                 text(b.extra_values[i]));
}

} // namespace fuzz

#endif // NORMAL_ORIENTATION_FUZZ_FUZZ_COMMON_H
