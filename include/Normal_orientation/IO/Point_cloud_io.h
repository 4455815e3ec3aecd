// SPDX-License-Identifier: GPL-3.0-or-later
/// \file Point_cloud_io.h
/// \brief Reading and writing point clouds with optional normals in the `.xyz`, `.pwn`
/// and `.ply` formats, for the command-line program.
///
/// The functions only use the C++17 standard library (plus `getpid()` to name temporary
/// files). Whole files are read with a single `fread`, text is parsed with
/// `std::from_chars` and written with `std::to_chars` (or an exact, faster equivalent for
/// a fixed number of digits), so that clouds of millions of points are read and written
/// in a fraction of a second. Large `.xyz`/`.pwn` files are parsed and formatted by
/// several `std::thread`s (see `Read_options` and `Write_options`); the result is the
/// same as with one thread, byte for byte and error message for error message.
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

#ifndef NORMAL_ORIENTATION_IO_POINT_CLOUD_IO_H
#define NORMAL_ORIENTATION_IO_POINT_CLOUD_IO_H

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include <unistd.h>

#include <Normal_orientation/internal/Temporary_files.h>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

/// \brief Exception thrown by every reading and writing function of this header.
///
/// The message is a single line that starts with the name of the file concerned and,
/// where it applies, names the line number (1-based) or the vertex index (0-based) and
/// the byte offset (binary PLY data). Bytes of the input quoted in a message (a bad
/// token, an unknown keyword) are written `\xNN` unless they are printable ASCII
/// characters.
class Io_error : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

/// \brief Scalar types of the PLY format.
///
/// Each enumerator accepts two spellings in a PLY header: the classic one (`char`,
/// `uchar`, `short`, `ushort`, `int`, `uint`, `float`, `double`) and the sized one
/// (`int8`, `uint8`, `int16`, `uint16`, `int32`, `uint32`, `float32`, `float64`).
enum class Ply_scalar_type
{
  INT8,    ///< `char` or `int8`
  UINT8,   ///< `uchar` or `uint8`
  INT16,   ///< `short` or `int16`
  UINT16,  ///< `ushort` or `uint16`
  INT32,   ///< `int` or `int32`
  UINT32,  ///< `uint` or `uint32`
  FLOAT32, ///< `float` or `float32`
  FLOAT64  ///< `double` or `float64`
};

/// \brief Classic PLY name of `type` (`char`, `uchar`, ..., `float`, `double`), the
/// spelling used when writing a PLY header.
inline const char* ply_scalar_type_name(Ply_scalar_type type)
{
  switch(type) {
  case Ply_scalar_type::INT8: return "char";
  case Ply_scalar_type::UINT8: return "uchar";
  case Ply_scalar_type::INT16: return "short";
  case Ply_scalar_type::UINT16: return "ushort";
  case Ply_scalar_type::INT32: return "int";
  case Ply_scalar_type::UINT32: return "uint";
  case Ply_scalar_type::FLOAT32: return "float";
  case Ply_scalar_type::FLOAT64: return "double";
  }
  return "?";
}

/// \brief Size in bytes of one value of `type` in a binary PLY file.
inline std::size_t ply_scalar_type_size(Ply_scalar_type type)
{
  switch(type) {
  case Ply_scalar_type::INT8:
  case Ply_scalar_type::UINT8: return 1;
  case Ply_scalar_type::INT16:
  case Ply_scalar_type::UINT16: return 2;
  case Ply_scalar_type::INT32:
  case Ply_scalar_type::UINT32:
  case Ply_scalar_type::FLOAT32: return 4;
  case Ply_scalar_type::FLOAT64: return 8;
  }
  return 0;
}

/// \brief Type named `name` in a PLY header (either spelling, case-sensitive), or no
/// value if `name` is not a PLY scalar type.
inline std::optional<Ply_scalar_type> ply_scalar_type_from_name(std::string_view name)
{
  if(name == "char" || name == "int8") return Ply_scalar_type::INT8;
  if(name == "uchar" || name == "uint8") return Ply_scalar_type::UINT8;
  if(name == "short" || name == "int16") return Ply_scalar_type::INT16;
  if(name == "ushort" || name == "uint16") return Ply_scalar_type::UINT16;
  if(name == "int" || name == "int32") return Ply_scalar_type::INT32;
  if(name == "uint" || name == "uint32") return Ply_scalar_type::UINT32;
  if(name == "float" || name == "float32") return Ply_scalar_type::FLOAT32;
  if(name == "double" || name == "float64") return Ply_scalar_type::FLOAT64;
  return std::nullopt;
}

/// \brief A scalar vertex property of a PLY file: its name and its type.
struct Ply_property
{
  std::string name;                              ///< property name, e.g. `red`
  Ply_scalar_type type = Ply_scalar_type::FLOAT64; ///< property type, e.g. `UINT8`
};

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

/// \brief Options of `read_point_cloud()`.
struct Read_options
{
  /// `.xyz`/`.pwn` only: number of threads parsing the text. 0 chooses automatically:
  /// one thread for a file of at most 4 MB, otherwise `std::thread::hardware_concurrency()`
  /// threads, at most 8. A positive value is used whatever the file size, at most 8.
  /// The file is split at line boundaries into one chunk per thread; the cloud read, and
  /// the message of the first error in file order, do not depend on the number of threads.
  unsigned int number_of_threads = 0;
};

/// \brief Options of `write_point_cloud()`.
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

namespace internal {

/// \brief Throws `Io_error` with the message `<filename>: <what>`.
[[noreturn]] inline void fail(const std::string& filename, const std::string& what)
{
  throw Io_error(filename + ": " + what);
}

/// \brief Text of `errno` value `error`.
inline std::string error_text(int error) { return std::strerror(error); }

/// \brief Extension of `filename` (with its dot), lower-cased.
inline std::string lower_case_extension(const std::string& filename)
{
  std::string extension = std::filesystem::path(filename).extension().string();
  for(char& c : extension)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

/// \brief Blanks separating values on a line (the newline excluded).
inline bool is_blank(char c)
{
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/// \brief Returns `true` if `c` is a control character (a byte below 32, or 127).
inline bool is_control(char c)
{
  const unsigned char byte = static_cast<unsigned char>(c);
  return byte < 0x20 || byte == 0x7F;
}

/// \brief Appends `c` to `text`, written `\xNN` unless it is a printable ASCII
/// character.
inline void append_printable(std::string& text, char c)
{
  const unsigned char byte = static_cast<unsigned char>(c);
  if(!is_control(c) && byte < 0x80) {
    text += c;
    return;
  }
  static const char digits[] = "0123456789abcdef";
  text += "\\x";
  text += digits[byte >> 4];
  text += digits[byte & 0xF];
}

/// \brief `[begin, end)` quoted for an error message, with its bytes other than
/// printable ASCII characters (control characters, bytes above 126) written `\xNN`, so
/// that the message stays one printable line whatever the input, and shortened to about
/// 40 characters (`...` then ends it).
inline std::string quote(const char* begin, const char* end)
{
  const std::size_t max_length = 40;
  std::string text = "'";
  for(; begin != end && text.size() <= max_length; ++begin) append_printable(text, *begin);
  if(begin != end) text += "...";
  return text + "'";
}

/// \brief `token` quoted, shortened and made printable for an error message.
inline std::string quote(std::string_view token) { return quote(token.data(), token.data() + token.size()); }

/// \brief The whole content of a file.
struct File_content
{
  std::unique_ptr<char[]> data;
  std::size_t size = 0;
  const char* begin() const { return data.get(); }
  const char* end() const { return data.get() + size; }
};

/// \brief Reads the whole file `filename` (a single `fread` for a regular file).
inline File_content read_file_content(const std::string& filename)
{
  std::error_code error;
  if(std::filesystem::is_directory(filename, error))
    fail(filename, "cannot read file: it is a directory");
  std::FILE* file = std::fopen(filename.c_str(), "rb");
  if(file == nullptr) {
    const int error_number = errno;
    fail(filename, "cannot open file for reading: " + error_text(error_number));
  }
  struct Closer {
    std::FILE* file;
    ~Closer() { std::fclose(file); }
  } closer{file};

  const std::uintmax_t size_hint = std::filesystem::file_size(filename, error);
  if(!error && size_hint >= std::numeric_limits<std::size_t>::max() / 2)
    fail(filename, "file too large");
  // One more byte than expected, so that a regular file is read by a single fread.
  std::size_t capacity = error ? std::size_t(1) << 16 : static_cast<std::size_t>(size_hint) + 1;
  File_content content;
  content.data.reset(new char[capacity]);
  for(;;) {
    const std::size_t wanted = capacity - content.size;
    const std::size_t got = std::fread(content.data.get() + content.size, 1, wanted, file);
    content.size += got;
    if(got < wanted) {
      if(std::ferror(file)) {
        const int error_number = errno;
        fail(filename, "cannot read file: " + error_text(error_number));
      }
      break; // end of file
    }
    // The file grew or its size was unknown: enlarge the buffer.
    if(capacity >= std::numeric_limits<std::size_t>::max() / 4)
      fail(filename, "file too large");
    std::unique_ptr<char[]> larger(new char[capacity * 2]);
    std::memcpy(larger.get(), content.data.get(), content.size);
    content.data = std::move(larger);
    capacity *= 2;
  }
  return content;
}

/// \brief Result of parsing one number.
enum class Parse_status { OK, INVALID, OUT_OF_RANGE };

/// \brief Parses the whole of `[begin, end)` as a `double` (an optional leading `+` is
/// accepted; `nan` and `inf` are accepted and must be rejected by the caller).
inline Parse_status parse_real(const char* begin, const char* end, double& value)
{
  if(begin != end && *begin == '+') {
    ++begin;
    if(begin == end || *begin == '+' || *begin == '-') return Parse_status::INVALID;
  }
  const std::from_chars_result result = std::from_chars(begin, end, value);
  if(result.ec == std::errc::invalid_argument || result.ptr != end) return Parse_status::INVALID;
  if(result.ec == std::errc::result_out_of_range) return Parse_status::OUT_OF_RANGE;
  return Parse_status::OK;
}

/// \brief Exact powers of ten `1e0 ... 1e22` (all exactly representable as `double`).
inline double exact_power_of_ten(int exponent)
{
  static const double powers[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  return powers[exponent];
}

/// \brief Returns `true` if `double` arithmetic is evaluated in `double` precision, which
/// `format_general_fast()` relies on (it is not with x87 extended precision).
inline constexpr bool has_exact_double_arithmetic()
{
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD == 0
  return true;
#else
  return false;
#endif
}

/// \brief Fast formatting of `value` with `precision` (1 to 12) significant digits,
/// producing the same text as `std::to_chars(..., std::chars_format::general, precision)`
/// (that is `printf("%.*g")`). `value * 10^k` is computed with one rounding using an
/// exact power of ten, so its error is far below the distance to a rounding tie unless
/// the value is very close to one; such values, and values out of `[1e-10, 1e21)`, make
/// it return `nullptr` and the caller uses `std::to_chars`. Otherwise returns the end of
/// the text written at `out` (at most 32 characters).
inline char* format_general_fast(char* out, double value, int precision)
{
  if(!has_exact_double_arithmetic() || precision < 1 || precision > 12) return nullptr;
  std::uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof(bits));
  const bool negative = (bits >> 63) != 0;
  const int biased_exponent = static_cast<int>((bits >> 52) & 0x7FF);
  if(biased_exponent == 0 && (bits << 1) == 0) { // zero, printed as "0" or "-0"
    if(negative) *out++ = '-';
    *out++ = '0';
    return out;
  }
  if(biased_exponent == 0 || biased_exponent == 0x7FF) return nullptr; // subnormal, inf, nan
  const double magnitude = std::fabs(value);
  // 2^(e2) <= magnitude < 2^(e2 + 1), so floor(e2 * log10(2)) <= floor(log10(magnitude)),
  // with floor(e2 * log10(2)) == floor(e2 * 315653 / 2^20) for |e2| <= 1650.
  const int e2 = biased_exponent - 1023;
  const long scaled_e2 = static_cast<long>(e2) * 315653L;
  int decimal_exponent = static_cast<int>(scaled_e2 >= 0 ? scaled_e2 / 1048576L : -((-scaled_e2 + 1048575L) / 1048576L));
  static const std::uint64_t integer_powers[13] = {1ull,         10ull,         100ull,         1000ull,
                                                   10000ull,     100000ull,     1000000ull,     10000000ull,
                                                   100000000ull, 1000000000ull, 10000000000ull, 100000000000ull,
                                                   1000000000000ull};
  auto scale = [magnitude](int k) {
    return k >= 0 ? magnitude * exact_power_of_ten(k) : magnitude / exact_power_of_ten(-k);
  };
  int k = precision - 1 - decimal_exponent;
  if(k < -22 || k > 22) return nullptr;
  double scaled = scale(k);
  if(scaled >= static_cast<double>(integer_powers[precision])) {
    ++decimal_exponent;
    --k;
    if(k < -22 || k > 22) return nullptr;
    scaled = scale(k);
  }
  std::uint64_t digits = static_cast<std::uint64_t>(scaled);
  const double fraction = scaled - static_cast<double>(digits); // exact
  if(std::fabs(fraction - 0.5) < 1e-3) return nullptr;          // near a tie: let to_chars decide
  if(fraction > 0.5) ++digits;
  if(digits == integer_powers[precision]) { // 9.9999 rounded up to 10.000
    digits /= 10;
    ++decimal_exponent;
  }
  if(digits < integer_powers[precision - 1] || digits >= integer_powers[precision]) return nullptr;

  // The `precision` digits, two at a time, then without trailing zeros.
  static const char pairs[] = "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
                              "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
                              "8081828384858687888990919293949596979899";
  char text[12];
  int position = precision;
  for(; position >= 2; position -= 2) {
    const std::size_t pair = static_cast<std::size_t>(digits % 100) * 2;
    digits /= 100;
    text[position - 2] = pairs[pair];
    text[position - 1] = pairs[pair + 1];
  }
  if(position == 1) text[0] = static_cast<char>('0' + digits);
  int length = precision;
  while(length > 1 && text[length - 1] == '0') --length;

  if(negative) *out++ = '-';
  if(decimal_exponent < -4 || decimal_exponent >= precision) { // d.ddde+XX
    *out++ = text[0];
    if(length > 1) {
      *out++ = '.';
      for(int i = 1; i < length; ++i) *out++ = text[i];
    }
    *out++ = 'e';
    int shown = decimal_exponent;
    *out++ = shown < 0 ? '-' : '+';
    if(shown < 0) shown = -shown;
    if(shown >= 100) *out++ = static_cast<char>('0' + shown / 100);
    *out++ = static_cast<char>('0' + (shown / 10) % 10);
    *out++ = static_cast<char>('0' + shown % 10);
  } else if(decimal_exponent >= 0) { // ddd.ddd
    const int integer_digits = decimal_exponent + 1;
    for(int i = 0; i < integer_digits; ++i) *out++ = i < length ? text[i] : '0';
    if(length > integer_digits) {
      *out++ = '.';
      for(int i = integer_digits; i < length; ++i) *out++ = text[i];
    }
  } else { // 0.000ddd
    *out++ = '0';
    *out++ = '.';
    for(int i = 0; i < -decimal_exponent - 1; ++i) *out++ = '0';
    for(int i = 0; i < length; ++i) *out++ = text[i];
  }
  return out;
}

/// \brief Room needed by `format_real()` (at most 24 characters are written).
constexpr std::size_t max_real_length = 32;

/// \brief Writes `value` at `out` with `precision` significant digits (`%g` style, at
/// most 17 are used), or with the shortest text that reads back to the same `double`
/// if `precision <= 0`; `out` must have room for `max_real_length` characters. Returns
/// the end of the text.
inline char* format_real(char* out, double value, int precision)
{
  if(precision <= 0) return std::to_chars(out, out + max_real_length, value).ptr;
  if(char* end = format_general_fast(out, value, precision)) return end;
  return std::to_chars(out, out + max_real_length, value, std::chars_format::general, std::min(precision, 17)).ptr;
}

/// \brief Number of significant digits of the decimal number `[begin, end)`, as
/// written: the digits of the mantissa from the first non-zero one on, trailing zeros
/// included (`0.012345` has 5, `-1.2300e5` has 5, `0012` has 2); 1 if they are all
/// zeros (`-0`, `0.000`). The sign, the decimal point and the exponent are not counted.
inline int significant_digits(const char* begin, const char* end)
{
  const char* p = begin;
  if(p != end && (*p == '-' || *p == '+')) ++p;
  while(p != end && (*p == '0' || *p == '.')) ++p; // leading zeros
  int digits = 0;
  for(; p != end; ++p) {
    if(static_cast<unsigned char>(*p - '0') > 9) {
      if(*p == '.') continue;
      break; // exponent
    }
    ++digits;
  }
  return digits == 0 ? 1 : digits;
}

/// \brief Number of `'\n'` in `[begin, end)` (as `std::count`, eight bytes at a time).
inline std::size_t count_newlines(const char* begin, const char* end)
{
  constexpr std::uint64_t ones = 0x0101010101010101ull;
  constexpr std::uint64_t low7 = 0x7F7F7F7F7F7F7F7Full;
  std::size_t count = 0;
  while(static_cast<std::size_t>(end - begin) >= 8) {
    // Up to 255 words at a time: one counter byte per byte position.
    const std::size_t words = std::min<std::size_t>(static_cast<std::size_t>(end - begin) / 8, 255);
    std::uint64_t counters = 0;
    for(std::size_t w = 0; w < words; ++w, begin += 8) {
      std::uint64_t word = 0;
      std::memcpy(&word, begin, 8);
      const std::uint64_t x = word ^ (ones * '\n');               // zero bytes where '\n'
      const std::uint64_t nonzero = ((x & low7) + low7) | x;      // high bit set iff byte != 0
      counters += (~nonzero >> 7) & ones;
    }
    // Sum of the eight counter bytes (at most 8 * 255), through four 16-bit sums.
    constexpr std::uint64_t low_bytes = 0x00FF00FF00FF00FFull;
    const std::uint64_t pairs = (counters & low_bytes) + ((counters >> 8) & low_bytes);
    count += static_cast<std::size_t>((pairs * 0x0001000100010001ull) >> 48);
  }
  return count + static_cast<std::size_t>(std::count(begin, end, '\n'));
}

/// \brief Smallest and largest values of the integer PLY type `type`.
inline std::pair<double, double> integer_range(Ply_scalar_type type)
{
  switch(type) {
  case Ply_scalar_type::INT8: return {-128.0, 127.0};
  case Ply_scalar_type::UINT8: return {0.0, 255.0};
  case Ply_scalar_type::INT16: return {-32768.0, 32767.0};
  case Ply_scalar_type::UINT16: return {0.0, 65535.0};
  case Ply_scalar_type::INT32: return {-2147483648.0, 2147483647.0};
  case Ply_scalar_type::UINT32: return {0.0, 4294967295.0};
  default: return {0.0, 0.0};
  }
}

/// \brief Returns `true` if `type` is `FLOAT32` or `FLOAT64`.
inline bool is_floating(Ply_scalar_type type)
{
  return type == Ply_scalar_type::FLOAT32 || type == Ply_scalar_type::FLOAT64;
}

/// \brief Type in which `write_ply()` writes normals of type `type`: `type` itself if
/// it is a floating type, otherwise the smallest floating type that holds every value of
/// `type` exactly (`FLOAT32` for 8- and 16-bit integers, `FLOAT64` for 32-bit ones).
inline Ply_scalar_type written_normal_type(Ply_scalar_type type)
{
  if(is_floating(type)) return type;
  return ply_scalar_type_size(type) <= 2 ? Ply_scalar_type::FLOAT32 : Ply_scalar_type::FLOAT64;
}

/// \brief Returns `true` if `value` can be stored exactly as `type` (any value fits
/// `FLOAT64`; `FLOAT32` rounds finite values but must not overflow).
inline bool is_representable(double value, Ply_scalar_type type)
{
  if(type == Ply_scalar_type::FLOAT64) return true;
  if(type == Ply_scalar_type::FLOAT32)
    return !std::isfinite(value) || std::fabs(value) <= double(std::numeric_limits<float>::max());
  const std::pair<double, double> range = integer_range(type);
  return value >= range.first && value <= range.second && value == std::trunc(value);
}

/// \brief Parses one value of an ASCII PLY file as `type`. A `FLOAT32` value is the
/// `float` nearest to the decimal number, as a binary file would store it (so that the
/// shortest text of any `float`, e.g. `3.4028235e+38` for the largest one, reads back
/// exactly); a value too small for a `float` becomes 0 (or the nearest subnormal). An
/// integer value may be written as a real (`255.0`); `-0` is read as 0.
inline Parse_status parse_ply_ascii_value(const char* begin, const char* end,
                                          Ply_scalar_type type, double& value)
{
  const char* const unsigned_first = (begin != end && *begin == '+') ? begin + 1 : begin;
  if(!is_floating(type)) {
    long long integer = 0;
    const std::from_chars_result result = std::from_chars(unsigned_first, end, integer);
    if(result.ec == std::errc() && result.ptr == end) {
      value = static_cast<double>(integer);
    } else {
      // Accept integral values written as reals, e.g. `255.0`.
      const Parse_status status = parse_real(begin, end, value);
      if(status != Parse_status::OK) return status;
      if(!std::isfinite(value)) return Parse_status::OUT_OF_RANGE;
      if(value == 0.0) value = 0.0; // -0.0: an integer has no negative zero
    }
    return is_representable(value, type) ? Parse_status::OK : Parse_status::OUT_OF_RANGE;
  }
  const Parse_status status = parse_real(begin, end, value);
  if(status != Parse_status::OK) return status;
  if(type == Ply_scalar_type::FLOAT32 && std::isfinite(value)) {
    // Rounding the decimal number to a double, then to a float, could miss the nearest
    // float (and refuses the decimal numbers between FLT_MAX and the half-way point to
    // the next power of two): read the float directly. The syntax was checked above.
    float single = 0.0f;
    const std::from_chars_result result = std::from_chars(unsigned_first, end, single);
    if(result.ec == std::errc() && result.ptr == end) {
      value = static_cast<double>(single);
    } else {
      if(std::fabs(value) > double(std::numeric_limits<float>::max())) return Parse_status::OUT_OF_RANGE;
      value = static_cast<double>(static_cast<float>(value)); // underflow: 0 or a subnormal
    }
  }
  return Parse_status::OK;
}

/// \brief Returns `true` if this machine stores integers little-endian.
inline bool host_is_little_endian()
{
  const std::uint16_t one = 1;
  unsigned char first_byte = 0;
  std::memcpy(&first_byte, &one, 1);
  return first_byte == 1;
}

/// \brief Byte-swapped `value`.
inline std::uint16_t byte_swap(std::uint16_t value)
{
  return static_cast<std::uint16_t>((value >> 8) | (value << 8));
}
/// \brief Byte-swapped `value`.
inline std::uint32_t byte_swap(std::uint32_t value)
{
  return ((value & 0x000000FFu) << 24) | ((value & 0x0000FF00u) << 8) |
         ((value & 0x00FF0000u) >> 8) | ((value & 0xFF000000u) >> 24);
}
/// \brief Byte-swapped `value`.
inline std::uint64_t byte_swap(std::uint64_t value)
{
  return (std::uint64_t(byte_swap(std::uint32_t(value))) << 32) |
         std::uint64_t(byte_swap(std::uint32_t(value >> 32)));
}

/// \brief Reads a value of type `Stored` (via its bit pattern `Bits`) at `source`.
template <class Stored, class Bits>
inline Stored load_bits(const char* source, bool swap)
{
  Bits bits;
  std::memcpy(&bits, source, sizeof(Bits));
  if(swap) bits = byte_swap(bits);
  Stored value;
  std::memcpy(&value, &bits, sizeof(Stored));
  return value;
}

/// \brief Reads a binary value of `type` at `source`, byte-swapping it if `swap`.
inline double load_scalar(const char* source, Ply_scalar_type type, bool swap)
{
  switch(type) {
  case Ply_scalar_type::INT8: return static_cast<signed char>(*source);
  case Ply_scalar_type::UINT8: return static_cast<unsigned char>(*source);
  case Ply_scalar_type::INT16: return load_bits<std::int16_t, std::uint16_t>(source, swap);
  case Ply_scalar_type::UINT16: return load_bits<std::uint16_t, std::uint16_t>(source, swap);
  case Ply_scalar_type::INT32: return load_bits<std::int32_t, std::uint32_t>(source, swap);
  case Ply_scalar_type::UINT32: return load_bits<std::uint32_t, std::uint32_t>(source, swap);
  case Ply_scalar_type::FLOAT32: return load_bits<float, std::uint32_t>(source, swap);
  case Ply_scalar_type::FLOAT64: return load_bits<double, std::uint64_t>(source, swap);
  }
  return 0.0;
}

/// \brief Writes `value` (of type `Stored`, via its bit pattern `Bits`) at `target`.
template <class Stored, class Bits>
inline void store_bits(char* target, Stored value, bool swap)
{
  Bits bits;
  std::memcpy(&bits, &value, sizeof(Bits));
  if(swap) bits = byte_swap(bits);
  std::memcpy(target, &bits, sizeof(Bits));
}

/// \brief Writes `value`, which must be representable as `type`, at `target` in binary,
/// byte-swapping it if `swap`.
inline void store_scalar(char* target, double value, Ply_scalar_type type, bool swap)
{
  switch(type) {
  case Ply_scalar_type::INT8: *target = static_cast<char>(static_cast<signed char>(value)); return;
  case Ply_scalar_type::UINT8: *target = static_cast<char>(static_cast<unsigned char>(value)); return;
  case Ply_scalar_type::INT16: store_bits<std::int16_t, std::uint16_t>(target, static_cast<std::int16_t>(value), swap); return;
  case Ply_scalar_type::UINT16: store_bits<std::uint16_t, std::uint16_t>(target, static_cast<std::uint16_t>(value), swap); return;
  case Ply_scalar_type::INT32: store_bits<std::int32_t, std::uint32_t>(target, static_cast<std::int32_t>(value), swap); return;
  case Ply_scalar_type::UINT32: store_bits<std::uint32_t, std::uint32_t>(target, static_cast<std::uint32_t>(value), swap); return;
  case Ply_scalar_type::FLOAT32: store_bits<float, std::uint32_t>(target, static_cast<float>(value), swap); return;
  case Ply_scalar_type::FLOAT64: store_bits<double, std::uint64_t>(target, value, swap); return;
  }
}

/// \brief Returns the end of the line starting at `begin` (the `'\n'` or `end`).
inline const char* end_of_line(const char* begin, const char* end)
{
  const void* newline = std::memchr(begin, '\n', static_cast<std::size_t>(end - begin));
  return newline != nullptr ? static_cast<const char*>(newline) : end;
}

/// \brief Blank-separated tokens of `[begin, end)`.
inline std::vector<std::string_view> split_blanks(const char* begin, const char* end)
{
  std::vector<std::string_view> tokens;
  for(;;) {
    while(begin != end && is_blank(*begin)) ++begin;
    if(begin == end) return tokens;
    const char* token_end = begin;
    while(token_end != end && !is_blank(*token_end)) ++token_end;
    tokens.emplace_back(begin, static_cast<std::size_t>(token_end - begin));
    begin = token_end;
  }
}

// ------------------------------------------------------------------------- PLY header

/// \brief Data encodings of a PLY file.
enum class Ply_format { ASCII, BINARY_LITTLE_ENDIAN, BINARY_BIG_ENDIAN };

/// \brief A property of a PLY element as declared in the header.
struct Ply_header_property
{
  std::string name;
  Ply_scalar_type type = Ply_scalar_type::FLOAT64; // item type for a list
  bool is_list = false;
  Ply_scalar_type count_type = Ply_scalar_type::UINT8; // lists only
  std::size_t line = 0;                                // header line
};

/// \brief An element of a PLY file as declared in the header.
struct Ply_header_element
{
  std::string name;
  std::size_t count = 0;
  std::vector<Ply_header_property> properties;
  std::size_t line = 0; // header line
};

/// \brief The header of a PLY file.
struct Ply_header
{
  Ply_format format = Ply_format::ASCII;
  std::vector<Ply_header_element> elements;
  std::size_t vertex_element = 0; // index in `elements`
  const char* data_begin = nullptr;
  std::size_t line_count = 0; // number of header lines
};

/// \brief Parses the header of the PLY file `filename` whose content is `[begin, end)`.
inline Ply_header parse_ply_header(const std::string& filename, const char* begin, const char* end)
{
  auto bad = [&filename](std::size_t line, const std::string& what) {
    fail(filename, "bad PLY header at line " + std::to_string(line) + ": " + what);
  };
  // Names are quoted in messages and written back to PLY headers: no control characters.
  auto check_name = [&bad](std::size_t line, std::string_view name) {
    if(std::any_of(name.begin(), name.end(), is_control)) bad(line, "control character in the name " + quote(name));
  };
  if(begin == end) fail(filename, "not a PLY file: the file is empty");
  Ply_header header;
  bool has_format = false;
  bool has_end = false;
  bool has_vertex = false;
  std::size_t line = 0;
  const char* p = begin;
  while(p < end) {
    ++line;
    const char* eol = end_of_line(p, end);
    const std::vector<std::string_view> tokens = split_blanks(p, eol);
    p = (eol < end) ? eol + 1 : end;

    if(line == 1) {
      if(tokens.size() != 1 || tokens[0] != "ply")
        fail(filename, "not a PLY file: the first line is not 'ply'");
      continue;
    }
    if(tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if(keyword == "comment" || keyword == "obj_info") continue;
    if(keyword == "end_header") {
      if(tokens.size() != 1) bad(line, "unexpected text after 'end_header'");
      has_end = true;
      break;
    }
    if(keyword == "format") {
      if(has_format) bad(line, "second 'format' line");
      if(tokens.size() != 3) bad(line, "expected 'format <encoding> 1.0'");
      if(tokens[1] == "ascii") header.format = Ply_format::ASCII;
      else if(tokens[1] == "binary_little_endian") header.format = Ply_format::BINARY_LITTLE_ENDIAN;
      else if(tokens[1] == "binary_big_endian") header.format = Ply_format::BINARY_BIG_ENDIAN;
      else bad(line, "unknown format " + quote(tokens[1]));
      if(tokens[2] != "1.0") bad(line, "unsupported PLY version " + quote(tokens[2]));
      has_format = true;
    } else if(keyword == "element") {
      if(tokens.size() != 3) bad(line, "expected 'element <name> <count>'");
      Ply_header_element element;
      check_name(line, tokens[1]);
      element.name = std::string(tokens[1]);
      element.line = line;
      unsigned long long count = 0;
      const char* first = tokens[2].data();
      const char* last = first + tokens[2].size();
      const std::from_chars_result result = std::from_chars(first, last, count);
      if(result.ec != std::errc() || result.ptr != last || count > std::numeric_limits<std::size_t>::max())
        bad(line, "invalid element count " + quote(tokens[2]));
      element.count = static_cast<std::size_t>(count);
      for(const Ply_header_element& other : header.elements)
        if(other.name == element.name) bad(line, "second element " + quote(element.name));
      if(element.name == "vertex") {
        has_vertex = true;
        header.vertex_element = header.elements.size();
      }
      header.elements.push_back(std::move(element));
    } else if(keyword == "property") {
      if(header.elements.empty()) bad(line, "'property' before any 'element'");
      Ply_header_property property;
      property.line = line;
      if(tokens.size() >= 2 && tokens[1] == "list") {
        if(tokens.size() != 5) bad(line, "expected 'property list <count type> <item type> <name>'");
        const std::optional<Ply_scalar_type> count_type = ply_scalar_type_from_name(tokens[2]);
        const std::optional<Ply_scalar_type> item_type = ply_scalar_type_from_name(tokens[3]);
        if(!count_type) bad(line, "unknown type " + quote(tokens[2]));
        if(!item_type) bad(line, "unknown type " + quote(tokens[3]));
        if(is_floating(*count_type)) bad(line, "the count type of a list must be an integer type");
        property.is_list = true;
        property.count_type = *count_type;
        property.type = *item_type;
        check_name(line, tokens[4]);
        property.name = std::string(tokens[4]);
      } else {
        if(tokens.size() != 3) bad(line, "expected 'property <type> <name>'");
        const std::optional<Ply_scalar_type> type = ply_scalar_type_from_name(tokens[1]);
        if(!type) bad(line, "unknown type " + quote(tokens[1]));
        property.type = *type;
        check_name(line, tokens[2]);
        property.name = std::string(tokens[2]);
      }
      Ply_header_element& element = header.elements.back();
      for(const Ply_header_property& other : element.properties)
        if(other.name == property.name)
          bad(line, "second property " + quote(property.name) + " in element " + quote(element.name));
      element.properties.push_back(std::move(property));
    } else {
      bad(line, "unknown keyword " + quote(keyword));
    }
  }
  if(!has_end) fail(filename, "bad PLY header: no 'end_header' line");
  if(!has_format) fail(filename, "bad PLY header: no 'format' line");
  if(!has_vertex) fail(filename, "bad PLY header: no 'vertex' element");
  header.data_begin = p;
  header.line_count = line;
  return header;
}

/// \brief Where the values of each vertex property go: `0..2` for `x y z`, `3..5` for
/// `nx ny nz`, `6 + k` for extra property `k`.
inline std::vector<std::size_t> assign_vertex_roles(const std::string& filename,
                                                    const Ply_header_element& vertex,
                                                    Point_cloud& cloud)
{
  static const char* const role_names[6] = {"x", "y", "z", "nx", "ny", "nz"};
  std::vector<std::size_t> roles;
  std::array<bool, 6> present{};
  for(const Ply_header_property& property : vertex.properties) {
    if(property.is_list)
      fail(filename, "bad PLY header at line " + std::to_string(property.line) +
                       ": list property '" + property.name + "' in element 'vertex' is not supported");
    std::size_t role = 6 + cloud.extra_properties.size();
    for(std::size_t r = 0; r < 6; ++r)
      if(property.name == role_names[r]) role = r;
    if(role < 6) {
      present[role] = true;
      if(role < 3) cloud.point_types[role] = property.type;
      else cloud.normal_types[role - 3] = property.type;
    } else {
      cloud.extra_properties.push_back(Ply_property{property.name, property.type});
    }
    roles.push_back(role);
  }
  for(std::size_t r = 0; r < 3; ++r)
    if(!present[r])
      fail(filename, std::string("bad PLY header: element 'vertex' has no property '") + role_names[r] + "'");
  const int normal_count = int(present[3]) + int(present[4]) + int(present[5]);
  if(normal_count != 0 && normal_count != 3)
    fail(filename, "bad PLY header: element 'vertex' must have all of 'nx ny nz' or none of them");
  return roles;
}

/// \brief Message for a PLY file whose data end before all declared rows.
inline std::string truncated_message(const Ply_header_element& element, std::size_t rows_found)
{
  if(element.name == "vertex")
    return "truncated file: " + std::to_string(element.count) + " vertices declared, data end at vertex " +
           std::to_string(rows_found);
  return "truncated file: element '" + element.name + "' declares " + std::to_string(element.count) +
         " rows, data end at row " + std::to_string(rows_found);
}

/// \brief `truncated_message()` for binary data: the incomplete row starts at byte
/// `offset` of a file of `file_size` bytes.
inline std::string truncated_message(const Ply_header_element& element, std::size_t rows_found,
                                     std::uint64_t offset, std::uint64_t file_size)
{
  return truncated_message(element, rows_found) + " (byte offset " + std::to_string(offset) + ", file size " +
         std::to_string(file_size) + ")";
}

/// \brief ` (byte offset <offset>)`, the place of an error in binary data.
inline std::string at_byte_offset(std::uint64_t offset)
{
  return " (byte offset " + std::to_string(offset) + ")";
}

/// \brief Stores a decoded vertex value according to its role.
inline void store_vertex_value(Point_cloud& cloud, std::size_t vertex, std::size_t role, double value)
{
  if(role < 3) cloud.points[vertex][role] = value;
  else if(role < 6) cloud.normals[vertex][role - 3] = value;
  else cloud.extra_values[vertex * cloud.extra_properties.size() + (role - 6)] = value;
}

/// \brief Checks that the coordinates `point[0..2]` and, unless `normal` is null, the
/// normal `normal[0..2]` are finite; the error message names the point as `<where>
/// <position><suffix>`, e.g. `line 12` or `vertex 11 (byte offset 296)`.
inline void check_finite_values(const std::string& filename, const double* point, const double* normal,
                                const char* where, std::uint64_t position, const char* suffix = "")
{
  if(!(std::isfinite(point[0]) && std::isfinite(point[1]) && std::isfinite(point[2])))
    fail(filename, std::string("non-finite coordinate at ") + where + " " + std::to_string(position) + suffix);
  if(normal != nullptr && !(std::isfinite(normal[0]) && std::isfinite(normal[1]) && std::isfinite(normal[2])))
    fail(filename, std::string("non-finite normal at ") + where + " " + std::to_string(position) + suffix);
}

/// \brief Checks that point `vertex` has finite coordinates and normal; the error
/// message names it as `<where> <position><suffix>`, e.g. `line 12` or `vertex 11
/// (byte offset 296)`.
inline void check_finite_vertex(const std::string& filename, const Point_cloud& cloud,
                                std::size_t vertex, const char* where, std::size_t position,
                                const char* suffix = "")
{
  check_finite_values(filename, cloud.points[vertex].data(),
                      cloud.has_normals() ? cloud.normals[vertex].data() : nullptr, where, position, suffix);
}

/// \brief Returns `true` if point `vertex` of `cloud` has finite coordinates and normal.
inline bool is_finite_vertex(const Point_cloud& cloud, std::size_t vertex)
{
  const std::array<double, 3>& p = cloud.points[vertex];
  if(!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) return false;
  if(!cloud.has_normals()) return true;
  const std::array<double, 3>& n = cloud.normals[vertex];
  return std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]);
}

/// \brief Skips the binary data of `element` starting at `p` in the file content
/// `[file_begin, end)`; returns the end of the data.
inline const char* skip_binary_element(const std::string& filename, const Ply_header_element& element,
                                       const char* file_begin, const char* p, const char* end, bool swap)
{
  const std::uint64_t file_size = static_cast<std::uint64_t>(end - file_begin);
  auto offset = [file_begin](const char* q) { return static_cast<std::uint64_t>(q - file_begin); };
  bool has_list = false;
  std::size_t row_size = 0;
  for(const Ply_header_property& property : element.properties) {
    has_list = has_list || property.is_list;
    if(!property.is_list) row_size += ply_scalar_type_size(property.type);
  }
  if(!has_list) {
    if(row_size == 0) return p;
    const std::size_t available = static_cast<std::size_t>(end - p) / row_size;
    if(available < element.count)
      fail(filename, truncated_message(element, available, offset(p + available * row_size), file_size));
    return p + element.count * row_size;
  }
  for(std::size_t row = 0; row < element.count; ++row) {
    const char* const row_begin = p;
    for(const Ply_header_property& property : element.properties) {
      if(!property.is_list) {
        const std::size_t size = ply_scalar_type_size(property.type);
        if(static_cast<std::size_t>(end - p) < size)
          fail(filename, truncated_message(element, row, offset(row_begin), file_size));
        p += size;
        continue;
      }
      const std::size_t count_size = ply_scalar_type_size(property.count_type);
      if(static_cast<std::size_t>(end - p) < count_size)
        fail(filename, truncated_message(element, row, offset(row_begin), file_size));
      const double count = load_scalar(p, property.count_type, swap);
      if(count < 0)
        fail(filename, "negative list length in element '" + element.name + "' at row " + std::to_string(row) +
                         at_byte_offset(offset(p)));
      p += count_size;
      const std::size_t item_size = ply_scalar_type_size(property.type);
      if(static_cast<std::size_t>(end - p) / item_size < static_cast<std::size_t>(count))
        fail(filename, truncated_message(element, row, offset(row_begin), file_size));
      p += static_cast<std::size_t>(count) * item_size;
    }
  }
  return p;
}

/// \brief Decodes the binary vertex data starting at `p` in the file content
/// `[file_begin, end)`; returns the end of the data.
inline const char* read_binary_vertices(const std::string& filename, const Ply_header_element& element,
                                        const std::vector<std::size_t>& roles, const char* file_begin,
                                        const char* p, const char* end, bool swap, Point_cloud& cloud)
{
  std::vector<std::size_t> offsets;
  std::size_t row_size = 0;
  for(const Ply_header_property& property : element.properties) {
    offsets.push_back(row_size);
    row_size += ply_scalar_type_size(property.type);
  }
  const std::size_t available = static_cast<std::size_t>(end - p) / row_size;
  if(available < element.count)
    fail(filename, truncated_message(element, available, static_cast<std::uint64_t>(p + available * row_size - file_begin),
                                     static_cast<std::uint64_t>(end - file_begin)));

  const std::size_t n = element.count;
  cloud.points.resize(n);
  if(std::find(roles.begin(), roles.end(), std::size_t(3)) != roles.end())
    cloud.normals.resize(n);
  cloud.extra_values.resize(n * cloud.extra_properties.size());
  const std::size_t property_count = roles.size();
  for(std::size_t i = 0; i < n; ++i, p += row_size) {
    for(std::size_t j = 0; j < property_count; ++j)
      store_vertex_value(cloud, i, roles[j], load_scalar(p + offsets[j], element.properties[j].type, swap));
    if(!is_finite_vertex(cloud, i))
      check_finite_vertex(filename, cloud, i, "vertex", i,
                          at_byte_offset(static_cast<std::uint64_t>(p - file_begin)).c_str());
  }
  return p;
}

/// \brief Reads the non-blank lines of the data section of an ASCII PLY file.
struct Line_reader
{
  const char* p;
  const char* end;
  std::size_t line; // number of the last line read

  /// Sets `[begin, last)` to the next line that is not blank; `false` at end of file.
  bool next(const char*& begin, const char*& last)
  {
    while(p < end) {
      ++line;
      const char* eol = end_of_line(p, end);
      begin = p;
      last = eol;
      p = (eol < end) ? eol + 1 : end;
      while(begin != last && is_blank(*begin)) ++begin;
      if(begin != last) return true;
    }
    return false;
  }
};

/// \brief Parses the row `[q, eol)`, line `line` of the file, of the ASCII PLY element
/// `element`, which must have scalar properties only, into `values` (one per property).
inline void parse_ascii_row(const std::string& filename, const Ply_header_element& element, const char* q,
                            const char* eol, std::uint64_t line, double* values)
{
  const std::size_t property_count = element.properties.size();
  auto at_line = [line] { return " at line " + std::to_string(line); };
  for(std::size_t j = 0; j < property_count; ++j) {
    while(q != eol && is_blank(*q)) ++q;
    if(q == eol)
      fail(filename, "short line: " + std::to_string(j) + " values instead of " +
                       std::to_string(property_count) + at_line());
    const char* token_end = q;
    while(token_end != eol && !is_blank(*token_end)) ++token_end;
    const Ply_header_property& property = element.properties[j];
    const Parse_status status = parse_ply_ascii_value(q, token_end, property.type, values[j]);
    if(status == Parse_status::INVALID)
      fail(filename, "non-numeric token " + quote(q, token_end) + at_line());
    if(status == Parse_status::OUT_OF_RANGE)
      fail(filename, "value " + quote(q, token_end) + " out of range for property '" + property.name +
                       "' of type " + ply_scalar_type_name(property.type) + at_line());
    q = token_end;
  }
  while(q != eol && is_blank(*q)) ++q;
  if(q != eol)
    fail(filename, "too many values: expected " + std::to_string(property_count) + at_line());
}

/// \brief Decodes the ASCII vertex data, one vertex per line.
inline void read_ascii_vertices(const std::string& filename, const Ply_header_element& element,
                                const std::vector<std::size_t>& roles, Line_reader& reader,
                                Point_cloud& cloud)
{
  const bool has_normals = std::find(roles.begin(), roles.end(), std::size_t(3)) != roles.end();
  const std::size_t property_count = roles.size();
  const std::size_t extra_count = cloud.extra_properties.size();
  // A row takes at least 2 bytes per property: do not trust the declared count blindly.
  const std::size_t max_rows = (static_cast<std::size_t>(reader.end - reader.p) + 1) / (2 * property_count);
  const std::size_t reserved = std::min(element.count, max_rows);
  cloud.points.reserve(reserved);
  if(has_normals) cloud.normals.reserve(reserved);
  cloud.extra_values.reserve(reserved * extra_count);

  std::vector<double> row(property_count);
  for(std::size_t i = 0; i < element.count; ++i) {
    const char* q = nullptr;
    const char* eol = nullptr;
    if(!reader.next(q, eol)) fail(filename, truncated_message(element, i));
    cloud.points.emplace_back();
    if(has_normals) cloud.normals.emplace_back();
    cloud.extra_values.resize(cloud.extra_values.size() + extra_count);
    parse_ascii_row(filename, element, q, eol, reader.line, row.data());
    for(std::size_t j = 0; j < property_count; ++j) store_vertex_value(cloud, i, roles[j], row[j]);
    check_finite_vertex(filename, cloud, i, "line", reader.line);
  }
}

// -------------------------------------------------------------------------- writing

/// \brief Output file written through a temporary file renamed over the target by
/// `commit()`; if `commit()` is not reached, the destructor removes the temporary file.
class Atomic_output_file
{
public:
  /// Creates `<target>.tmp.<pid>.<counter>` for writing.
  explicit Atomic_output_file(const std::string& target)
    : target_(target), buffer_(new char[capacity])
  {
    static std::atomic<unsigned long> counter{0};
    temporary_ = target + ".tmp." + std::to_string(static_cast<long>(::getpid())) + "." +
                 std::to_string(counter.fetch_add(1));
    file_ = std::fopen(temporary_.c_str(), "wb");
    if(file_ == nullptr) {
      const int error_number = errno;
      fail(target_, "cannot create temporary file '" + temporary_ + "': " + error_text(error_number));
    }
    // a signal handler calling remove_temporary_files() removes it too
    slot_ = Normal_orientation::internal::register_temporary_file(temporary_);
  }

  Atomic_output_file(const Atomic_output_file&) = delete;
  Atomic_output_file& operator=(const Atomic_output_file&) = delete;

  ~Atomic_output_file()
  {
    Normal_orientation::internal::unregister_temporary_file(slot_);
    if(committed_) return;
    if(file_ != nullptr) std::fclose(file_);
    std::remove(temporary_.c_str());
  }

  /// Name of the target file.
  const std::string& target() const { return target_; }

  /// Makes room for `size` (at most `capacity`) bytes and returns where to put them;
  /// `advance()` must then be called with the number of bytes put.
  char* room(std::size_t size)
  {
    if(used_ + size > capacity) flush_buffer();
    return buffer_.get() + used_;
  }

  /// Accounts for `size` bytes put at `room()`.
  void advance(std::size_t size) { used_ += size; }

  /// Appends one character.
  void put(char c)
  {
    *room(1) = c;
    ++used_;
  }

  /// Appends `text`.
  void put(std::string_view text)
  {
    if(text.size() > capacity) {
      flush_buffer();
      write_through(text.data(), text.size());
      return;
    }
    std::memcpy(room(text.size()), text.data(), text.size());
    used_ += text.size();
  }

  /// Appends the shortest text that reads back as `value` (a `double`, `float` or integer).
  template <class T>
  void put_shortest(T value)
  {
    char* first = room(max_number_length);
    const std::to_chars_result result = std::to_chars(first, first + max_number_length, value);
    used_ += static_cast<std::size_t>(result.ptr - first);
  }

  /// Appends `value` with `precision` significant digits (`%g` style); shortest exact
  /// text if `precision <= 0`.
  void put_real(double value, int precision)
  {
    char* first = room(max_number_length);
    used_ += static_cast<std::size_t>(format_real(first, value, precision) - first);
  }

  /// Replaces the `data.size()` bytes at byte `offset` of the data put so far (for
  /// instance a count in a header, written with a fixed width); appending resumes at
  /// the end of the data.
  void overwrite(std::uint64_t offset, std::string_view data)
  {
    flush_buffer();
    if(::fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0)
      fail(target_, "cannot seek in file: " + error_text(errno));
    write_through(data.data(), data.size());
    if(::fseeko(file_, 0, SEEK_END) != 0)
      fail(target_, "cannot seek in file: " + error_text(errno));
  }

  /// Writes the remaining data, closes the temporary file and renames it over the target.
  void commit()
  {
    flush_buffer();
    if(std::fflush(file_) != 0 || std::ferror(file_))
      fail(target_, "cannot write file: " + error_text(errno));
    std::FILE* file = file_;
    file_ = nullptr;
    if(std::fclose(file) != 0)
      fail(target_, "cannot close file: " + error_text(errno));
    if(std::rename(temporary_.c_str(), target_.c_str()) != 0) {
      const int error_number = errno;
      fail(target_, "cannot rename '" + temporary_ + "' to the target: " + error_text(error_number));
    }
    Normal_orientation::internal::unregister_temporary_file(slot_);
    slot_ = -1;
    committed_ = true;
  }

  /// Size of the write buffer.
  static constexpr std::size_t capacity = std::size_t(1) << 20;
  /// Room reserved for one number.
  static constexpr std::size_t max_number_length = 64;

private:
  void write_through(const char* data, std::size_t size)
  {
    if(size != 0 && std::fwrite(data, 1, size, file_) != size)
      fail(target_, "cannot write file: " + error_text(errno));
  }

  void flush_buffer()
  {
    write_through(buffer_.get(), used_);
    used_ = 0;
  }

  std::string target_;
  std::string temporary_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<char[]> buffer_;
  std::size_t used_ = 0;
  bool committed_ = false;
  int slot_ = -1;
};

/// \brief Checks that `cloud` is consistent and finite before writing it to `filename`.
inline void check_writable(const std::string& filename, const Point_cloud& cloud, bool check_extras)
{
  const std::size_t n = cloud.points.size();
  if(!cloud.normals.empty() && cloud.normals.size() != n)
    fail(filename, "cannot write: " + std::to_string(cloud.normals.size()) + " normals for " +
                     std::to_string(n) + " points");
  for(std::size_t i = 0; i < n; ++i) {
    const std::array<double, 3>& p = cloud.points[i];
    if(!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
      fail(filename, "cannot write non-finite coordinate at vertex " + std::to_string(i));
  }
  for(std::size_t i = 0; i < cloud.normals.size(); ++i) {
    const std::array<double, 3>& v = cloud.normals[i];
    if(!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])))
      fail(filename, "cannot write non-finite normal at vertex " + std::to_string(i));
  }
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

// ----------------------------------------------------------------- parallel text files

/// \brief Text size above which `.xyz`/`.pwn` files are parsed and formatted by several
/// threads when the number of threads is chosen automatically.
constexpr std::size_t parallel_text_size = std::size_t(4) << 20;

/// \brief Largest number of threads parsing or formatting a text file.
constexpr unsigned int max_text_threads = 8;

/// \brief Number of threads for a text of about `size` bytes: `requested` if positive,
/// otherwise 1 up to `parallel_text_size` bytes and the number of hardware threads
/// above; at most `max_text_threads` in all cases.
inline unsigned int text_thread_count(unsigned int requested, std::size_t size)
{
  if(requested > 0) return std::min(requested, max_text_threads);
  if(size <= parallel_text_size) return 1;
  const unsigned int hardware = std::thread::hardware_concurrency(); // 0 if unknown
  return std::max(1u, std::min(hardware, max_text_threads));
}

/// \brief Calls `task(i)` for every `i` in `[0, count)`, concurrently: `task(0)` in the
/// calling thread, the others in new threads (in the calling thread, after `task(0)`,
/// if no more threads can be started). Returns when all calls have returned; then
/// rethrows the exception of the call with the smallest `i` that threw, if any.
template <class Task>
inline void run_concurrently(std::size_t count, const Task& task)
{
  if(count == 0) return;
  std::vector<std::exception_ptr> errors(count);
  auto run = [&task, &errors](std::size_t i) {
    try {
      task(i);
    } catch(...) {
      errors[i] = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(count - 1); // emplace_back below does not reallocate
  std::size_t started = 1;
  try {
    for(; started < count; ++started) threads.emplace_back(run, started);
  } catch(...) {
    // No more threads: the remaining calls are made by the calling thread.
  }
  run(0);
  for(std::size_t i = started; i < count; ++i) run(i);
  for(std::thread& thread : threads) thread.join();
  for(const std::exception_ptr& error : errors)
    if(error) std::rethrow_exception(error);
}

/// \brief Splits `[begin, end)` into `parts` consecutive chunks of about the same size,
/// each made of whole lines (a chunk ends just after a `'\n'`, or at `end`; some chunks
/// may be empty). Returns the `parts + 1` chunk bounds.
inline std::vector<const char*> split_at_lines(const char* begin, const char* end, unsigned int parts)
{
  std::vector<const char*> bounds(1, begin);
  const std::size_t step = static_cast<std::size_t>(end - begin) / std::max(parts, 1u);
  for(unsigned int i = 1; i < parts; ++i) {
    const char* target = std::max(begin + step * i, bounds.back());
    const char* eol = end_of_line(target, end);
    bounds.push_back(eol < end ? eol + 1 : end);
  }
  bounds.push_back(end);
  return bounds;
}

/// \brief Errors found while parsing a `.xyz`/`.pwn` text.
enum class Xyz_error
{
  NONE,
  NON_NUMERIC,
  OUT_OF_RANGE,
  COLUMN_COUNT,    // neither 3 nor 6 values
  COLUMN_MISMATCH, // not as many values as the first data line
  NON_FINITE_COORDINATE,
  NON_FINITE_NORMAL
};

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

/// \brief Parses the values of the line `[q, eol)` (without its `'\n'`) of a
/// `.xyz`/`.pwn` text, as `read_xyz()` specifies: stores the first six values in
/// `values` and sets `n` to the number of values of the line (which may exceed 6; 0 for
/// a blank or comment line), and raises `digits[0]` (coordinates) and `digits[1]`
/// (normals) to the significant digits of the values (see `Point_cloud::point_digits`).
/// Returns `Xyz_error::NONE`, or `NON_NUMERIC` or `OUT_OF_RANGE` with the offending
/// token, quoted, in `error_token`. Non-finite values are not rejected here.
inline Xyz_error parse_xyz_values(const char* q, const char* const eol, std::array<double, 6>& values,
                                  std::size_t& n, int (&digits)[2], std::string& error_token)
{
  n = 0;
  for(;;) {
    while(q != eol && is_blank(*q)) ++q;
    if(q == eol || (n == 0 && *q == '#')) return Xyz_error::NONE;
    if(n < 6) {
      // Parse in place: the number must be followed by a blank or the end of the line.
      const char* first = (*q == '+' && q + 1 != eol && q[1] != '-' && q[1] != '+') ? q + 1 : q;
      const std::from_chars_result result = std::from_chars(first, eol, values[n]);
      if(result.ec == std::errc() && (result.ptr == eol || is_blank(*result.ptr))) {
        // Count the digits only if the token may have more than `maximum`: it has at
        // most as many as characters, its sign and a leading `0.` excluded.
        int& maximum = digits[n < 3 ? 0 : 1];
        const char* const unsigned_first = first + (*first == '-');
        std::ptrdiff_t bound = result.ptr - unsigned_first;
        if(bound >= 2 && unsigned_first[0] == '0' && unsigned_first[1] == '.') bound -= 2;
        if(bound > maximum || maximum == 0) maximum = std::max(maximum, significant_digits(first, result.ptr));
        q = result.ptr;
        ++n;
        continue;
      }
      const char* token_end = q;
      while(token_end != eol && !is_blank(*token_end)) ++token_end;
      error_token = quote(q, token_end);
      const bool out_of_range = result.ec == std::errc::result_out_of_range && result.ptr == token_end;
      return out_of_range ? Xyz_error::OUT_OF_RANGE : Xyz_error::NON_NUMERIC;
    }
    while(q != eol && !is_blank(*q)) ++q;
    ++n;
  }
}

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
    if(n != 3 && n != 6) {
      chunk.error_values = n;
      return failed(Xyz_error::COLUMN_COUNT);
    }
    if(columns == 0) {
      columns = n;
      chunk.columns = n;
      chunk.first_data_line = line;
      if(columns == 6) chunk.normals.reserve(chunk.points.capacity());
    } else if(n != columns) {
      chunk.error_values = n;
      return failed(Xyz_error::COLUMN_MISMATCH);
    }
    if(!(std::isfinite(values[0]) && std::isfinite(values[1]) && std::isfinite(values[2])))
      return failed(Xyz_error::NON_FINITE_COORDINATE);
    chunk.points.push_back({{values[0], values[1], values[2]}});
    if(n == 6) {
      if(!(std::isfinite(values[3]) && std::isfinite(values[4]) && std::isfinite(values[5])))
        return failed(Xyz_error::NON_FINITE_NORMAL);
      chunk.normals.push_back({{values[3], values[4], values[5]}});
    }
  }
  chunk.lines = line;
  chunk.point_digits = digits[0];
  chunk.normal_digits = digits[1];
}

/// \brief Message (without the file name) of the error `error` (not `NONE`) of a
/// `.xyz`/`.pwn` text at line `line`: `values` is the number of values of the line
/// (`COLUMN_COUNT`, `COLUMN_MISMATCH`), `token` the quoted token (`NON_NUMERIC`,
/// `OUT_OF_RANGE`), `first_data_line` and `columns` the line number and number of values
/// of the first data line of the file (`COLUMN_MISMATCH`).
inline std::string xyz_error_message(Xyz_error error, std::size_t line, std::size_t values,
                                     const std::string& token, std::size_t first_data_line,
                                     std::size_t columns)
{
  const std::string at_line = " at line " + std::to_string(line);
  switch(error) {
  case Xyz_error::NONE: break;
  case Xyz_error::NON_NUMERIC: return "non-numeric token " + token + at_line;
  case Xyz_error::OUT_OF_RANGE: return "number " + token + " out of range" + at_line;
  case Xyz_error::COLUMN_COUNT:
    return "wrong column count" + at_line + ": " + std::to_string(values) +
           " values, expected 3 (x y z) or 6 (x y z nx ny nz)";
  case Xyz_error::COLUMN_MISMATCH:
    return "wrong column count" + at_line + ": " + std::to_string(values) + " values, but line " +
           std::to_string(first_data_line) + " has " + std::to_string(columns);
  case Xyz_error::NON_FINITE_COORDINATE: return "non-finite coordinate" + at_line;
  case Xyz_error::NON_FINITE_NORMAL: return "non-finite normal" + at_line;
  }
  return "error" + at_line;
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

/// \brief The cloud of the PLY data `[begin, end)`, as `read_ply()` reads it from the
/// file `filename` (named in the error messages only).
inline Point_cloud parse_ply_data(const std::string& filename, const char* begin, const char* end)
{
  const Ply_header header = parse_ply_header(filename, begin, end);
  Point_cloud cloud;
  const std::vector<std::size_t> roles =
    assign_vertex_roles(filename, header.elements[header.vertex_element], cloud);

  if(header.format == Ply_format::ASCII) {
    Line_reader reader{header.data_begin, end, header.line_count};
    for(std::size_t e = 0; e < header.elements.size(); ++e) {
      const Ply_header_element& element = header.elements[e];
      if(e == header.vertex_element) {
        read_ascii_vertices(filename, element, roles, reader, cloud);
        continue;
      }
      const char* first = nullptr;
      const char* last = nullptr;
      for(std::size_t row = 0; row < element.count; ++row)
        if(!reader.next(first, last)) fail(filename, truncated_message(element, row));
    }
    return cloud;
  }

  const bool file_is_little_endian = header.format == Ply_format::BINARY_LITTLE_ENDIAN;
  const bool swap = file_is_little_endian != host_is_little_endian();
  const char* p = header.data_begin;
  for(std::size_t e = 0; e < header.elements.size(); ++e) {
    const Ply_header_element& element = header.elements[e];
    if(e == header.vertex_element)
      p = read_binary_vertices(filename, element, roles, begin, p, end, swap, cloud);
    else
      p = skip_binary_element(filename, element, begin, p, end, swap);
  }
  if(p < end) { // most often a wrong element count: refused rather than guessed at
    const Ply_header_element& last = header.elements.back();
    fail(filename, std::to_string(end - p) + " bytes of unexpected data at byte offset " + std::to_string(p - begin) +
                     ", after the last " +
                     (last.name == "vertex" ? std::string("vertex") : "row of element '" + last.name + "'") +
                     " of the PLY data");
  }
  return cloud;
}

} // namespace internal

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

/// \brief Reads a PLY point cloud from `filename`, whatever its extension.
///
/// Accepts the `ascii`, `binary_little_endian` and `binary_big_endian` encodings (version
/// 1.0). The `vertex` element must have scalar properties `x y z` and may have `nx ny nz`
/// (all three or none), of any scalar type. Its other scalar properties are stored in
/// `extra_properties`/`extra_values`, and the types of `x y z nx ny nz` in `point_types`
/// and `normal_types`. Other elements (e.g. `face`, with list properties), before or
/// after `vertex`, are skipped and their data are not kept. In an ASCII file each
/// element row must be on its own line; rows of other elements are not validated.
/// Coordinates and normals must be finite (a NaN or an infinity is an error); other
/// properties may hold any value of their type. An ASCII `float` value is read as the
/// nearest `float`; an integer value may be written as a real (`255.0`).
/// \throws Io_error on any error (unreadable or empty file, bad header, truncated data,
/// non-numeric token, value out of the range of its type, non-finite coordinate or
/// normal), naming the file and the line (ASCII) or the vertex or row index and the
/// byte offset (binary).
inline Point_cloud read_ply(const std::string& filename)
{
  const internal::File_content content = internal::read_file_content(filename);
  return internal::parse_ply_data(filename, content.begin(), content.end());
}

/// \brief Reads a point cloud from `filename`, choosing the format from the extension
/// (case-insensitive): `.xyz` and `.pwn` with `read_xyz()`, `.ply` with `read_ply()`
/// (which ignores `options`).
/// \throws Io_error on an unknown extension or on any reading error.
inline Point_cloud read_point_cloud(const std::string& filename, const Read_options& options = Read_options())
{
  const std::string extension = internal::lower_case_extension(filename);
  if(extension == ".xyz" || extension == ".pwn") return read_xyz(filename, options);
  if(extension == ".ply") return read_ply(filename);
  internal::fail(filename, "unknown point cloud file extension '" + extension +
                             "' (expected .xyz, .pwn or .ply)");
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

/// \brief Writes `cloud` to `filename` as PLY, whatever its extension:
/// `binary_little_endian` if `options.binary`, `ascii` otherwise.
///
/// The single `vertex` element has the properties `x y z` with types `point_types`,
/// then `nx ny nz` (if the cloud has normals) with types `normal_types` (`float` for
/// 8- and 16-bit integer types, `double` for 32-bit ones: see `Point_cloud::normal_types`),
/// then every extra property with its name and type, in order.
/// Types are written with their classic names (`uchar`, `float`...). ASCII values are
/// written with the shortest text that reads back exactly, so that extra values
/// round-trip exactly in both encodings. The file is written atomically.
/// \throws Io_error if `cloud` is inconsistent, if a value cannot be stored in its
/// type (e.g. `1.5` as `uchar`), or on any writing error; no file is left behind then
/// and an existing `filename` is unchanged.
inline void write_ply(const std::string& filename, const Point_cloud& cloud,
                      const Write_options& options = Write_options())
{
  using namespace internal;
  check_writable(filename, cloud, true);
  static const char* const names[6] = {"x", "y", "z", "nx", "ny", "nz"};
  const std::size_t n = cloud.points.size();
  const std::size_t extra_count = cloud.extra_properties.size();

  struct Column
  {
    std::size_t role; // as in assign_vertex_roles()
    Ply_scalar_type type;
    const std::string* name;
  };
  std::vector<Column> columns;
  std::vector<std::string> fixed_names(names, names + 6);
  for(std::size_t r = 0; r < 3; ++r) columns.push_back({r, cloud.point_types[r], &fixed_names[r]});
  if(cloud.has_normals())
    for(std::size_t r = 0; r < 3; ++r) {
      const Ply_scalar_type type = written_normal_type(cloud.normal_types[r]);
      columns.push_back({3 + r, type, &fixed_names[3 + r]});
    }
  for(std::size_t k = 0; k < extra_count; ++k)
    columns.push_back({6 + k, cloud.extra_properties[k].type, &cloud.extra_properties[k].name});

  std::string header = "ply\nformat ";
  header += options.binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  header += "comment generated by Normal_orientation\n";
  header += "element vertex " + std::to_string(n) + "\n";
  for(const Column& column : columns)
    header += std::string("property ") + ply_scalar_type_name(column.type) + " " + *column.name + "\n";
  header += "end_header\n";

  Atomic_output_file out(filename);
  out.put(header);
  const bool swap = !host_is_little_endian();
  for(std::size_t i = 0; i < n; ++i) {
    for(std::size_t c = 0; c < columns.size(); ++c) {
      const Column& column = columns[c];
      const double value = column.role < 3   ? cloud.points[i][column.role]
                           : column.role < 6 ? cloud.normals[i][column.role - 3]
                                             : cloud.extra_values[i * extra_count + (column.role - 6)];
      if(!is_representable(value, column.type)) {
        char text[64];
        const std::to_chars_result result = std::to_chars(text, text + sizeof(text), value);
        fail(filename, "cannot write value " + std::string(text, result.ptr) + " of property '" +
                         *column.name + "' at vertex " + std::to_string(i) + " as " +
                         ply_scalar_type_name(column.type));
      }
      if(options.binary) {
        const std::size_t size = ply_scalar_type_size(column.type);
        store_scalar(out.room(size), value, column.type, swap);
        out.advance(size);
        continue;
      }
      if(c != 0) out.put(' ');
      switch(column.type) {
      case Ply_scalar_type::FLOAT32: out.put_shortest(static_cast<float>(value)); break;
      case Ply_scalar_type::FLOAT64: out.put_shortest(value); break;
      default: out.put_shortest(static_cast<long long>(value)); break;
      }
    }
    if(!options.binary) out.put('\n');
  }
  out.commit();
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
  const std::string extension = internal::lower_case_extension(filename);
  if(extension == ".xyz" || extension == ".pwn") return write_xyz(filename, cloud, options);
  if(extension == ".ply") return write_ply(filename, cloud, options);
  internal::fail(filename, "unknown point cloud file extension '" + extension +
                             "' (expected .xyz, .pwn or .ply)");
}

/// @}

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_POINT_CLOUD_IO_H
