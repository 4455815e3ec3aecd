// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Ply_io.h
/// \brief Reading and writing whole PLY point clouds in memory: `read_ply()` and
/// `write_ply()`.

#ifndef NORMAL_ORIENTATION_IO_PLY_IO_H
#define NORMAL_ORIENTATION_IO_PLY_IO_H

#include <Normal_orientation/IO/Atomic_output_file.h>
#include <Normal_orientation/IO/Input_file.h>
#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Ply_data.h>
#include <Normal_orientation/IO/Ply_header.h>
#include <Normal_orientation/IO/Ply_types.h>
#include <Normal_orientation/IO/Point_cloud.h>
#include <Normal_orientation/IO/Text_lines.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

namespace Normal_orientation {
namespace IO {
namespace internal {

/// \brief Records in `cloud` the types of `x y z` and `nx ny nz` of the PLY `vertex`
/// element, whose properties have the roles `roles` (see `assign_vertex_roles()`), and
/// its other properties, as `extra_properties`.
inline void take_vertex_types(const Ply_header_element& vertex, const std::vector<std::size_t>& roles,
                              Point_cloud& cloud)
{
  for(std::size_t j = 0; j < roles.size(); ++j) {
    const Ply_header_property& property = vertex.properties[j];
    if(roles[j] < 3) cloud.point_types[roles[j]] = property.type;
    else if(roles[j] < 6) cloud.normal_types[roles[j] - 3] = property.type;
    else cloud.extra_properties.push_back(Ply_property{property.name, property.type});
  }
}

/// \brief Stores a decoded vertex value according to its role (see `assign_vertex_roles()`).
inline void store_vertex_value(Point_cloud& cloud, std::size_t vertex, std::size_t role, double value)
{
  if(role < 3) cloud.points[vertex][role] = value;
  else if(role < 6) cloud.normals[vertex][role - 3] = value;
  else cloud.extra_values[vertex * cloud.extra_properties.size() + (role - 6)] = value;
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
  return all_finite(cloud.points[vertex].data()) && (!cloud.has_normals() || all_finite(cloud.normals[vertex].data()));
}

/// \brief Skips the binary data of `element` starting at `p` in the file content
/// `[file_begin, end)`; returns the end of the data.
inline const char* skip_binary_element(const std::string& filename, const Ply_header_element& element,
                                       const char* file_begin, const char* p, const char* end, bool swap)
{
  const std::uint64_t file_size = static_cast<std::uint64_t>(end - file_begin);
  auto offset = [file_begin](const char* q) { return static_cast<std::uint64_t>(q - file_begin); };
  if(const std::optional<std::size_t> fixed_size = fixed_row_size(element)) {
    const std::size_t row_size = *fixed_size;
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
        fail(filename, negative_list_message(element, row, offset(p)));
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
  const std::vector<std::size_t> offsets = property_offsets(element);
  const std::size_t row_size = *fixed_row_size(element);
  const std::size_t available = static_cast<std::size_t>(end - p) / row_size;
  if(available < element.count)
    fail(filename, truncated_message(element, available, static_cast<std::uint64_t>(p + available * row_size - file_begin),
                                     static_cast<std::uint64_t>(end - file_begin)));

  const std::size_t n = element.count;
  cloud.points.resize(n);
  if(has_normal_role(roles)) cloud.normals.resize(n);
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

/// \brief Decodes the ASCII vertex data, one vertex per line.
inline void read_ascii_vertices(const std::string& filename, const Ply_header_element& element,
                                const std::vector<std::size_t>& roles, Line_reader& reader,
                                Point_cloud& cloud)
{
  const bool has_normals = has_normal_role(roles);
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

/// \brief The cloud of the PLY data `[begin, end)`, as `read_ply()` reads it from the
/// file `filename` (named in the error messages only).
inline Point_cloud parse_ply_data(const std::string& filename, const char* begin, const char* end)
{
  const Ply_header header = parse_ply_header(filename, begin, end);
  Point_cloud cloud;
  const Ply_header_element& vertex = header.elements[header.vertex_element];
  const std::vector<std::size_t> roles = assign_vertex_roles(filename, vertex);
  take_vertex_types(vertex, roles, cloud);

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
    fail(filename, trailing_data_message(header.elements.back(), static_cast<std::uint64_t>(end - p),
                                         static_cast<std::uint64_t>(p - begin)));
  }
  return cloud;
}

} // namespace internal

/// \addtogroup PkgNormalOrientationIO
/// @{

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

  std::string header = ply_header_start(options.binary) + std::to_string(n) + "\n";
  for(const Column& column : columns)
    header += std::string("property ") + ply_scalar_type_name(column.type) + " " + *column.name + "\n";
  header += "end_header\n";

  Atomic_output_file out(filename);
  out.put(header);
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
      if(!options.binary && c != 0) out.put(' ');
      put_ply_value(out, value, column.type, options.binary);
    }
    if(!options.binary) out.put('\n');
  }
  out.commit();
}

/// @}

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_PLY_IO_H
