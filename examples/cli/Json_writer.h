// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// A small JSON writer for the reports of the orient_normals program: one
// line, members separated by ", " and keys followed by ": ".

#ifndef NORMAL_ORIENTATION_EXAMPLES_CLI_JSON_WRITER_H
#define NORMAL_ORIENTATION_EXAMPLES_CLI_JSON_WRITER_H

#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace Cli {

/// \brief Writes one JSON value (usually an object) into a string.
///
/// Calls nest as the JSON does: `begin_object()`, then `key()` and a value
/// per member, then `end_object()`; arrays likewise, without keys.  The
/// writer places the separators.  It does not check the nesting: a caller
/// that writes a value without a key inside an object writes bad JSON.
class Json_writer
{
public:
  /// \brief Opens an object.
  Json_writer& begin_object() { return open('{'); }
  /// \brief Closes the innermost object.
  Json_writer& end_object() { return close('}'); }
  /// \brief Opens an array.
  Json_writer& begin_array() { return open('['); }
  /// \brief Closes the innermost array.
  Json_writer& end_array() { return close(']'); }

  /// \brief Writes the key of the next member of the innermost object.
  Json_writer& key(std::string_view name)
  {
    separate();
    quote(name);
    m_text += ": ";
    m_after_key = true;
    return *this;
  }

  /// \brief Writes a string, escaped (quotes, backslashes, control characters).
  Json_writer& string(std::string_view s)
  {
    separate();
    quote(s);
    return *this;
  }
  /// \brief Writes `s` as a string, or `null` when it is empty.
  Json_writer& string_or_null(std::string_view s) { return s.empty() ? null() : string(s); }
  /// \brief Writes `true` or `false`.
  Json_writer& boolean(bool b) { return raw(b ? "true" : "false"); }
  /// \brief Writes `null`.
  Json_writer& null() { return raw("null"); }

  /// \brief Writes an integer, in full.
  template <typename Integer>
  Json_writer& integer(Integer i)
  {
    static_assert(std::is_integral_v<Integer> && !std::is_same_v<Integer, bool>, "an integer");
    if constexpr (std::is_signed_v<Integer>)
      return raw(std::to_string(static_cast<long long>(i)));
    else
      return raw(std::to_string(static_cast<unsigned long long>(i)));
  }
  /// \brief Writes `x` with `digits` significant digits (`%.*g`); `null` when
  /// `x` is not finite (JSON has no infinity or NaN).
  Json_writer& number(double x, int digits = 9) { return formatted(false, digits, x); }
  /// \brief Writes `x` with `decimals` digits after the point (`%.*f`);
  /// `null` when `x` is not finite.
  Json_writer& fixed(double x, int decimals = 6) { return formatted(true, decimals, x); }

  /// \brief The JSON written so far.
  const std::string& str() const { return m_text; }

private:
  Json_writer& open(char c)
  {
    separate();
    m_text += c;
    m_first.push_back(true);
    return *this;
  }
  Json_writer& close(char c)
  {
    m_text += c;
    if (!m_first.empty())
      m_first.pop_back();
    return *this;
  }
  Json_writer& raw(std::string_view text)
  {
    separate();
    m_text += text;
    return *this;
  }
  Json_writer& formatted(bool fixed_point, int precision, double x)
  {
    if (!std::isfinite(x))
      return null();
    char buffer[512]; // %f of the largest double: 309 digits before the point
    if (fixed_point)
      std::snprintf(buffer, sizeof buffer, "%.*f", precision, x);
    else
      std::snprintf(buffer, sizeof buffer, "%.*g", precision, x);
    return raw(buffer);
  }
  /// ", " before every element of a container but the first; nothing
  /// between a key and its value
  void separate()
  {
    if (m_after_key) {
      m_after_key = false;
      return;
    }
    if (m_first.empty())
      return;
    if (!m_first.back())
      m_text += ", ";
    m_first.back() = false;
  }
  void quote(std::string_view s)
  {
    m_text += '"';
    for (const char c : s) {
      if (c == '"' || c == '\\')
        m_text += '\\';
      if (static_cast<unsigned char>(c) < 0x20) {
        char buffer[8];
        std::snprintf(buffer, sizeof buffer, "\\u%04x", unsigned(static_cast<unsigned char>(c)));
        m_text += buffer;
        continue;
      }
      m_text += c;
    }
    m_text += '"';
  }

  std::string m_text;
  std::vector<bool> m_first; // per open container: no element written yet
  bool m_after_key = false;
};

} // namespace Cli

#endif // NORMAL_ORIENTATION_EXAMPLES_CLI_JSON_WRITER_H
