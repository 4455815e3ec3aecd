// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Ply_header.h
/// \brief The header of a PLY file: its elements and their properties as declared,
/// parsed and checked with line-numbered messages, and the role of each property of the
/// `vertex` element (`x y z`, `nx ny nz`, or another property).

#ifndef NORMAL_ORIENTATION_IO_PLY_HEADER_H
#define NORMAL_ORIENTATION_IO_PLY_HEADER_H

#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Ply_types.h>
#include <Normal_orientation/IO/Text_lines.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace IO {
namespace internal {

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
/// `nx ny nz`, `6 + k` for the `k`-th other property.
/// \throws Io_error if `vertex` has a list property, lacks one of `x y z`, or has some
/// but not all of `nx ny nz`.
inline std::vector<std::size_t> assign_vertex_roles(const std::string& filename, const Ply_header_element& vertex)
{
  static const char* const role_names[6] = {"x", "y", "z", "nx", "ny", "nz"};
  std::vector<std::size_t> roles;
  std::array<bool, 6> present{};
  std::size_t others = 0;
  for(const Ply_header_property& property : vertex.properties) {
    if(property.is_list)
      fail(filename, "bad PLY header at line " + std::to_string(property.line) +
                       ": list property '" + property.name + "' in element 'vertex' is not supported");
    std::size_t role = 6 + others;
    for(std::size_t r = 0; r < 6; ++r)
      if(property.name == role_names[r]) role = r;
    if(role < 6) present[role] = true;
    else ++others;
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

/// \brief Returns `true` if the vertex properties of roles `roles` include a normal.
inline bool has_normal_role(const std::vector<std::size_t>& roles)
{
  return std::find(roles.begin(), roles.end(), std::size_t(3)) != roles.end();
}

} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_PLY_HEADER_H
