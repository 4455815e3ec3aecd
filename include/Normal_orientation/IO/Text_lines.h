// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Text_lines.h
/// \brief Lines and blank-separated tokens of a text in memory: what a blank is, where a
/// line ends, the tokens of a line, the number of lines, the non-blank lines in turn.

#ifndef NORMAL_ORIENTATION_IO_TEXT_LINES_H
#define NORMAL_ORIENTATION_IO_TEXT_LINES_H

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

namespace Normal_orientation {
namespace IO {
namespace internal {

/// \brief Blanks separating values on a line (the newline excluded).
inline bool is_blank(char c)
{
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
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

/// \brief Reads the non-blank lines of a text in memory (the data section of an ASCII
/// PLY file), counting lines.
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

} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_TEXT_LINES_H
