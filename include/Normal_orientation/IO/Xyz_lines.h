// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Xyz_lines.h
/// \brief A line of a `.xyz`/`.pwn` text: its values parsed, a data line checked
/// (3 or 6 values, as many as the first data line, finite), and the message of each
/// error; the rules that the reader of whole files and the streaming reader share.

#ifndef NORMAL_ORIENTATION_IO_XYZ_LINES_H
#define NORMAL_ORIENTATION_IO_XYZ_LINES_H

#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Number_text.h>
#include <Normal_orientation/IO/Point_cloud.h>
#include <Normal_orientation/IO/Text_lines.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstddef>
#include <string>
#include <system_error>

namespace Normal_orientation {
namespace IO {
namespace internal {

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

/// \brief Checks the data line of `n` values (3 or 6 expected; not 0) stored in
/// `values` against `columns`, the number of values of the first data line: 0 if this
/// is the first one, and then set to `n` unless `n` is neither 3 nor 6. Returns the first
/// error of the line (`COLUMN_COUNT`, `COLUMN_MISMATCH`, `NON_FINITE_COORDINATE`,
/// `NON_FINITE_NORMAL`, in that order), or `Xyz_error::NONE`.
inline Xyz_error check_xyz_data_line(const std::array<double, 6>& values, std::size_t n, std::size_t& columns)
{
  if(n != 3 && n != 6) return Xyz_error::COLUMN_COUNT;
  if(columns == 0) columns = n;
  else if(n != columns) return Xyz_error::COLUMN_MISMATCH;
  if(!all_finite(values.data())) return Xyz_error::NON_FINITE_COORDINATE;
  if(n == 6 && !all_finite(values.data() + 3)) return Xyz_error::NON_FINITE_NORMAL;
  return Xyz_error::NONE;
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


} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_XYZ_LINES_H
