// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Ply_data.h
/// \brief The data of a PLY file, as laid out by its header: the size and offsets of a
/// binary row, an ASCII row parsed, a vertex row written, and the messages of data that
/// do not fit the header (truncated, negative list length, bytes after the last
/// element). What the reader of whole files, the streaming reader and writers share.

#ifndef NORMAL_ORIENTATION_IO_PLY_DATA_H
#define NORMAL_ORIENTATION_IO_PLY_DATA_H

#include <Normal_orientation/IO/Atomic_output_file.h>
#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Ply_header.h>
#include <Normal_orientation/IO/Ply_types.h>
#include <Normal_orientation/IO/Text_lines.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace Normal_orientation {
namespace IO {
namespace internal {

// ------------------------------------------------------------------------- layout

/// \brief Bytes of a binary row of `element`, or no value if it has a list property
/// (its rows then have no fixed size).
inline std::optional<std::size_t> fixed_row_size(const Ply_header_element& element)
{
  std::size_t size = 0;
  for(const Ply_header_property& property : element.properties) {
    if(property.is_list) return std::nullopt;
    size += ply_scalar_type_size(property.type);
  }
  return size;
}

/// \brief Byte offset of each property in a binary row of `element`, which has no list
/// property.
inline std::vector<std::size_t> property_offsets(const Ply_header_element& element)
{
  std::vector<std::size_t> offsets;
  std::size_t offset = 0;
  for(const Ply_header_property& property : element.properties) {
    offsets.push_back(offset);
    offset += ply_scalar_type_size(property.type);
  }
  return offsets;
}

// ----------------------------------------------------------------------- messages

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

/// \brief Message for `bytes` bytes at byte `offset` after the binary data of the last
/// element, `last`.
inline std::string trailing_data_message(const Ply_header_element& last, std::uint64_t bytes, std::uint64_t offset)
{
  return std::to_string(bytes) + " bytes of unexpected data at byte offset " + std::to_string(offset) +
         ", after the last " +
         (last.name == "vertex" ? std::string("vertex") : "row of element '" + last.name + "'") +
         " of the PLY data";
}

/// \brief Message for a negative list length in row `row` of `element`, at byte `offset`.
inline std::string negative_list_message(const Ply_header_element& element, std::size_t row, std::uint64_t offset)
{
  return "negative list length in element '" + element.name + "' at row " + std::to_string(row) +
         at_byte_offset(offset);
}

// ---------------------------------------------------------------------- ASCII rows

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

// ------------------------------------------------------------------------- writing

/// \brief The start of the PLY header that the writers write, up to the vertex count:
/// `ply`, the format line (`binary_little_endian` if `binary`, `ascii` otherwise), a
/// comment, and `element vertex `.
inline std::string ply_header_start(bool binary)
{
  std::string header = "ply\nformat ";
  header += binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  header += "comment generated by Normal_orientation\nelement vertex ";
  return header;
}

/// \brief Appends `value`, which must be representable as `type`, to `out`: in binary
/// little-endian if `binary`, otherwise with the shortest text that reads back to it
/// in its type (the caller writes the blanks and line ends).
inline void put_ply_value(Atomic_output_file& out, double value, Ply_scalar_type type, bool binary)
{
  if(binary) {
    const std::size_t size = ply_scalar_type_size(type);
    store_scalar(out.room(size), value, type, !host_is_little_endian());
    out.advance(size);
    return;
  }
  switch(type) {
  case Ply_scalar_type::FLOAT32: out.put_shortest(static_cast<float>(value)); break;
  case Ply_scalar_type::FLOAT64: out.put_shortest(value); break;
  default: out.put_shortest(static_cast<long long>(value)); break;
  }
}

} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_PLY_DATA_H
