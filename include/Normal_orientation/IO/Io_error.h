// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Io_error.h
/// \brief `Io_error`, the exception of every reader and writer of `Normal_orientation::IO`,
/// and the rules of its messages: one line, the file name first, the bytes of the input
/// quoted printable.

#ifndef NORMAL_ORIENTATION_IO_IO_ERROR_H
#define NORMAL_ORIENTATION_IO_IO_ERROR_H

#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

/// \brief Exception thrown by every reading and writing function of `Normal_orientation::IO`.
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

/// @}

namespace internal {

/// \brief Throws `Io_error` with the message `<filename>: <what>`.
[[noreturn]] inline void fail(const std::string& filename, const std::string& what)
{
  throw Io_error(filename + ": " + what);
}

/// \brief Text of `errno` value `error`.
inline std::string error_text(int error) { return std::strerror(error); }

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

} // namespace internal

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_IO_ERROR_H
