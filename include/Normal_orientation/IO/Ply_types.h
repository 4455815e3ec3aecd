// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Ply_types.h
/// \brief The scalar types of the PLY format: their names and sizes, the values each
/// holds, and one value read or written in binary or as ASCII text.

#ifndef NORMAL_ORIENTATION_IO_PLY_TYPES_H
#define NORMAL_ORIENTATION_IO_PLY_TYPES_H

#include <Normal_orientation/IO/Byte_order.h>
#include <Normal_orientation/IO/Number_text.h>

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

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

/// @}

namespace internal {

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

} // namespace internal

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_PLY_TYPES_H
