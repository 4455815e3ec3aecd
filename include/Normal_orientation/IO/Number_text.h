// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Number_text.h
/// \brief Numbers as text, exactly: parsing a decimal number as the nearest `double`,
/// printing a `double` with a number of significant digits (`%g` style, with a fast
/// exact path) or with the shortest text that reads back to it, and counting the
/// significant digits of a number as written.

#ifndef NORMAL_ORIENTATION_IO_NUMBER_TEXT_H
#define NORMAL_ORIENTATION_IO_NUMBER_TEXT_H

#include <algorithm>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <system_error>

namespace Normal_orientation {
namespace IO {
namespace internal {

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

} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_NUMBER_TEXT_H
