// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Point_stream_reader.h
/// \brief `Point_stream_reader`: sequential (streaming) reading of a `.xyz`, `.pwn` or
/// `.ply` point cloud, chunk by chunk, with a fixed amount of memory whatever the size
/// of the file: the input of the out-of-core orientation.
///
/// The reader reads the same files as `read_point_cloud()` and gives, point by point and
/// bit for bit, the same coordinates and normals, as `Point_record`s numbered 0, 1, ...
/// in file order. It reports the same errors with the same messages (bytes after the last
/// element of a binary PLY file included, with their byte offset). Errors are found as
/// the data are read, so an error in the middle of the file is reported by the `read()`
/// call that reaches it (header errors, and in binary PLY files most size mismatches, by
/// the constructor).

#ifndef NORMAL_ORIENTATION_IO_POINT_STREAM_READER_H
#define NORMAL_ORIENTATION_IO_POINT_STREAM_READER_H

#include <Normal_orientation/IO/File_format.h>
#include <Normal_orientation/IO/Input_file.h>
#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Ply_data.h>
#include <Normal_orientation/IO/Ply_header.h>
#include <Normal_orientation/IO/Ply_types.h>
#include <Normal_orientation/IO/Point_cloud.h>
#include <Normal_orientation/IO/Text_lines.h>
#include <Normal_orientation/IO/Xyz_lines.h>
#include <Normal_orientation/Point_record.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace IO {

class Point_stream_reader;

namespace internal {

/// \brief Largest PLY header read by `Point_stream_reader`, in bytes.
constexpr std::size_t max_streamed_ply_header_size = std::size_t(1) << 20;

/// \brief Layout of a PLY file as `Point_stream_reader` found it in the header, for the
/// code that works on the bytes of the file itself (`transcode_with_flips()`).
struct Ply_stream_layout
{
  /// Encoding of the data.
  Ply_format format = Ply_format::ASCII;
  /// The elements declared by the header, in file order.
  std::vector<Ply_header_element> elements;
  /// Index of the element `vertex` in `elements`.
  std::size_t vertex_element = 0;
  /// Role of each property of `vertex`, as `assign_vertex_roles()` gives them: `0..2` for
  /// `x y z`, `3..5` for `nx ny nz`, 6 and above for the other properties.
  std::vector<std::size_t> roles;
  /// Binary data: byte offset of each property of `vertex` in a row.
  std::vector<std::size_t> offsets;
  /// Binary data: bytes per vertex row.
  std::size_t row_size = 0;
  /// Bytes of the header, its `end_header` line included: the data start there.
  std::uint64_t header_size = 0;
  /// Byte offset of the first vertex row (after the data of the elements before `vertex`).
  std::uint64_t vertex_data_offset = 0;
};

/// \brief Layout of the PLY file read by `reader` as found in its header; no value for
/// a `.xyz`/`.pwn` file. For code that reads or copies the bytes of the file itself,
/// such as `transcode_with_flips()`.
inline std::optional<Ply_stream_layout> ply_layout(const Point_stream_reader& reader);

} // namespace internal

/// \addtogroup PkgNormalOrientationIO
/// @{


/// \brief Sequential reader of a point cloud file, chunk by chunk, with a buffer of
/// fixed size: the file is never loaded as a whole.
///
/// Reads the files that `read_point_cloud()` reads, choosing the format from the
/// extension (case-insensitive): `.xyz` and `.pwn` (lines `x y z` or `x y z nx ny nz`,
/// with the rules of `read_xyz()`), `.ply` (`ascii`, `binary_little_endian` or
/// `binary_big_endian`; vertex properties `x y z` and optionally `nx ny nz`, of any
/// scalar type, the other vertex properties and the other elements, before or after
/// `vertex`, being skipped). The records read are those `read_point_cloud()` gives,
/// bit for bit, numbered 0, 1, ... in file order; the normal is zero when the file has
/// no normals.
///
/// Errors are reported as `Io_error` with the messages of `read_point_cloud()` (file
/// name, then line number for text data, vertex or row number for binary data), by the
/// constructor for the header, by `read()` for the data. As there, a binary PLY file
/// with bytes after its last element is rejected (with the byte offset). The elements
/// following `vertex` are checked when the last vertex is read. After an error, `read()`
/// throws the same error again until `rewind()`.
///
/// Limits that `read_point_cloud()` does not have: a line of a text file must fit in
/// the buffer (`buffer_capacity()`), except a comment line of a `.xyz`/`.pwn` file,
/// which may be of any length; a PLY header is read up to 1 MiB; the file must be
/// seekable (a regular file, not a pipe).
class Point_stream_reader
{
public:
  /// Default buffer size in bytes (1 MiB).
  static constexpr std::size_t default_buffer_size = std::size_t(1) << 20;
  /// Smallest buffer size in bytes; smaller requests are raised to it. 4096 unless the
  /// macro `NORMAL_ORIENTATION_MINIMUM_STREAM_BUFFER_SIZE` is defined (the fuzz targets
  /// set it to 1, so that small inputs exercise the refills of the buffer).
  static constexpr std::size_t minimum_buffer_size =
#ifdef NORMAL_ORIENTATION_MINIMUM_STREAM_BUFFER_SIZE
    std::size_t(NORMAL_ORIENTATION_MINIMUM_STREAM_BUFFER_SIZE);
#else
    4096;
#endif
  static_assert(minimum_buffer_size >= 1, "the reading buffer needs at least one byte");

  /// \brief Opens `filename` and reads its header (for a `.xyz`/`.pwn` file, up to its
  /// first data line, to know whether it has normals), with a reading buffer of
  /// `buffer_size` bytes (at least `minimum_buffer_size`, and at least one binary PLY
  /// vertex row).
  /// \throws Io_error if the file cannot be read, if its extension is unknown, if its
  /// PLY header is invalid, if the data declared do not fit the size of a binary PLY
  /// file (when the elements before and after `vertex` have fixed-size rows), or if the
  /// first data line of a `.xyz`/`.pwn` file is invalid.
  explicit Point_stream_reader(const std::string& filename, std::size_t buffer_size = default_buffer_size)
    : filename_(filename)
  {
    format_ = internal::file_format(filename);
    input_.reset(new internal::Buffered_input(filename, std::max(buffer_size, minimum_buffer_size)));
    if(format_ == internal::File_format::XYZ) open_xyz();
    else open_ply();
    rewind();
  }

  Point_stream_reader(const Point_stream_reader&) = delete;
  Point_stream_reader& operator=(const Point_stream_reader&) = delete;
  /// \brief Moves the reader (the moved-from reader may only be destroyed or assigned to).
  Point_stream_reader(Point_stream_reader&&) = default;
  /// \brief Moves the reader (the moved-from reader may only be destroyed or assigned to).
  Point_stream_reader& operator=(Point_stream_reader&&) = default;

  /// \brief Name of the file read.
  const std::string& filename() const { return filename_; }

  /// \brief Returns `true` if the file has normals (PLY: `nx ny nz` properties;
  /// `.xyz`/`.pwn`: six values on the first data line).
  bool has_normals() const { return has_normals_; }

  /// \brief Number of points declared by a PLY header; 0 for a `.xyz`/`.pwn` file
  /// (unknown).
  std::uint64_t expected_count() const { return expected_count_; }

  /// \brief Number of records read since the opening or the last `rewind()`.
  std::uint64_t records_read() const { return next_index_; }

  /// \brief Size of the reading buffer in bytes: the memory used for the data, which
  /// does not depend on the size of the file.
  std::size_t buffer_capacity() const { return input_->capacity(); }

  /// \brief Size of the file in bytes when it was opened.
  std::uint64_t file_size() const { return input_->file_size(); }

  /// \brief Reads up to `maximum` records and appends them to `chunk`; returns their
  /// number, which is 0 only at the end of the data (or if `maximum` is 0). Records
  /// have their index in the file (0, 1, ...) as `index`.
  /// \throws Io_error on any error in the data (records read before the error in this
  /// call may have been appended); `read()` then throws the same error until `rewind()`.
  std::size_t read(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    if(!error_.empty()) throw Io_error(error_);
    try {
      std::size_t count = 0;
      if(format_ == internal::File_format::XYZ) count = read_xyz_records(chunk, maximum);
      else if(binary_) count = read_binary_records(chunk, maximum);
      else count = read_ascii_records(chunk, maximum);
      if(format_ == internal::File_format::PLY && next_index_ == expected_count_ && !finished_) finish_ply();
      return count;
    } catch(const Io_error& error) {
      error_ = error.what();
      throw;
    }
  }

  /// \brief Restarts reading from the first point (and clears a reading error).
  void rewind()
  {
    input_->seek(data_offset_);
    line_ = data_line_;
    next_index_ = 0;
    finished_ = false;
    error_.clear();
  }

private:
  /// \cond SKIP_IN_MANUAL
  friend std::optional<internal::Ply_stream_layout> internal::ply_layout(const Point_stream_reader&);
  /// \endcond

  /// The layout of a PLY file (see `internal::ply_layout()`).
  std::optional<internal::Ply_stream_layout> ply_layout() const
  {
    if(format_ != internal::File_format::PLY) return std::nullopt;
    internal::Ply_stream_layout layout;
    layout.format = ply_format_;
    layout.elements = elements_;
    layout.vertex_element = vertex_element_;
    layout.roles = roles_;
    layout.offsets = internal::property_offsets(elements_[vertex_element_]);
    layout.row_size = row_size_;
    layout.header_size = header_size_;
    layout.vertex_data_offset = data_offset_;
    return layout;
  }

  /// A `x y z nx ny nz` vertex property of a binary PLY file.
  struct Binary_field
  {
    std::size_t offset;   // in the row
    Ply_scalar_type type;
    std::size_t role;     // 0..5: x y z nx ny nz
  };

  // ------------------------------------------------------------------------ xyz

  void open_xyz()
  {
    // Find the first data line, which decides the number of columns.
    data_offset_ = 0;
    data_line_ = 0;
    rewind();
    std::array<double, 6> values{};
    while(columns_ == 0 && next_xyz_line(values) != 0) {
    }
    has_normals_ = columns_ == 6;
  }

  /// Parses the next line (whose number is then `line_`) into `values` and returns its
  /// number of values: 3 or 6 for a data line (checked against the first one and for
  /// finiteness), 0 at the end of the file; skips blank and comment lines.
  std::size_t next_xyz_line(std::array<double, 6>& values)
  {
    using namespace internal;
    for(;;) {
      const char* first = nullptr;
      const char* eol = nullptr;
      const Buffered_input::Line_status status = input_->next_line(first, eol);
      if(status == Buffered_input::Line_status::END) return 0;
      ++line_;
      if(status == Buffered_input::Line_status::TOO_LONG) {
        const char* q = input_->data();
        const char* const end = q + input_->available();
        while(q != end && is_blank(*q)) ++q;
        if(q == end || *q != '#')
          fail(filename_, "line " + std::to_string(line_) + " is longer than the reading buffer (" +
                            std::to_string(input_->capacity()) + " bytes)");
        input_->skip_line(); // a long comment
        continue;
      }
      std::size_t n = 0;
      int digits[2] = {0, 0};
      std::string token;
      Xyz_error error = parse_xyz_values(first, eol, values, n, digits, token);
      if(error == Xyz_error::NONE) {
        if(n == 0) continue; // blank or comment line
        const bool first_data = columns_ == 0;
        error = check_xyz_data_line(values, n, columns_);
        if(first_data && columns_ != 0) first_data_line_ = line_;
      }
      if(error != Xyz_error::NONE)
        fail(filename_, xyz_error_message(error, line_, n, token, first_data_line_, columns_));
      return n;
    }
  }

  std::size_t read_xyz_records(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    std::size_t count = 0;
    std::array<double, 6> values{};
    while(count < maximum && !finished_) {
      const std::size_t n = next_xyz_line(values);
      if(n == 0) {
        finished_ = true;
        break;
      }
      Point_record record{};
      for(std::size_t c = 0; c < 3; ++c) record.position[c] = values[c];
      if(n == 6)
        for(std::size_t c = 0; c < 3; ++c) record.normal[c] = values[3 + c];
      record.index = next_index_++;
      chunk.push_back(record);
      ++count;
    }
    return count;
  }

  // ------------------------------------------------------------------------ PLY

  void open_ply()
  {
    using namespace internal;
    // The header, line by line, up to the 'end_header' line (or a bounded size).
    std::string text;
    for(std::size_t lines = 1; text.size() < max_streamed_ply_header_size; ++lines) {
      const std::size_t start = text.size();
      if(!input_->append_line(text, max_streamed_ply_header_size)) break;
      const std::size_t end = text.back() == '\n' ? text.size() - 1 : text.size();
      const std::vector<std::string_view> tokens = split_blanks(text.data() + start, text.data() + end);
      if(lines == 1 && (tokens.size() != 1 || tokens[0] != "ply")) break; // not a PLY file: reported below
      if(!tokens.empty() && tokens[0] == "end_header") break;
    }
    const Ply_header header = parse_ply_header(filename_, text.data(), text.data() + text.size());
    elements_ = header.elements;
    vertex_element_ = header.vertex_element;
    ply_format_ = header.format;
    header_size_ = static_cast<std::uint64_t>(header.data_begin - text.data());
    binary_ = header.format != Ply_format::ASCII;
    swap_ = (header.format == Ply_format::BINARY_LITTLE_ENDIAN) != host_is_little_endian();
    const Ply_header_element& vertex = elements_[vertex_element_];
    const std::vector<std::size_t> roles = assign_vertex_roles(filename_, vertex);
    has_normals_ = has_normal_role(roles);
    expected_count_ = vertex.count;

    std::size_t offset = 0;
    for(std::size_t j = 0; j < roles.size(); ++j) {
      if(roles[j] < 6) fields_.push_back(Binary_field{offset, vertex.properties[j].type, roles[j]});
      offset += ply_scalar_type_size(vertex.properties[j].type);
    }
    row_size_ = offset;
    row_values_.resize(roles.size());
    roles_ = roles;

    // Skip the elements before 'vertex'.
    input_->seek(static_cast<std::uint64_t>(header.data_begin - text.data()));
    line_ = header.line_count;
    for(std::size_t e = 0; e < vertex_element_; ++e) skip_element(elements_[e]);
    data_offset_ = input_->position();
    data_line_ = line_;
    if(!binary_) return;

    input_->reserve(row_size_);
    // Check the size of the vertex data and, if the rows of the following elements have
    // a fixed size, of the whole data.
    const std::uint64_t file_size = input_->file_size();
    const std::uint64_t remaining = file_size - data_offset_;
    if(remaining / row_size_ < vertex.count)
      fail(filename_, truncated_message(vertex, static_cast<std::size_t>(remaining / row_size_),
                                        data_offset_ + remaining / row_size_ * row_size_, file_size));
    std::uint64_t end = data_offset_ + static_cast<std::uint64_t>(vertex.count) * row_size_;
    for(std::size_t e = vertex_element_ + 1; e < elements_.size(); ++e) {
      const std::optional<std::size_t> row_size = fixed_row_size(elements_[e]);
      if(!row_size) return; // checked when skipped
      const std::uint64_t size = *row_size;
      if(size == 0) continue;
      const std::uint64_t left = file_size - end;
      if(left / size < elements_[e].count)
        fail(filename_, truncated_message(elements_[e], static_cast<std::size_t>(left / size), end + left / size * size,
                                          file_size));
      end += size * elements_[e].count;
    }
    check_no_trailing_data(end);
  }

  /// Throws if the file has bytes after byte `end`, the end of the binary PLY data.
  void check_no_trailing_data(std::uint64_t end) const
  {
    const std::uint64_t size = input_->file_size();
    if(size <= end) return;
    internal::fail(filename_, internal::trailing_data_message(elements_.back(), size - end, end));
  }

  /// Skips the data of `element`, which is not the vertex element.
  void skip_element(const internal::Ply_header_element& element)
  {
    using namespace internal;
    if(!binary_) {
      const char* first = nullptr;
      const char* eol = nullptr;
      for(std::size_t row = 0; row < element.count; ++row)
        if(!next_nonblank_line(first, eol)) fail(filename_, truncated_message(element, row));
      return;
    }
    if(const std::optional<std::size_t> fixed_size = fixed_row_size(element)) {
      const std::uint64_t row_size = *fixed_size;
      if(row_size == 0) return;
      const std::uint64_t file_size = input_->file_size();
      const std::uint64_t left = file_size - input_->position();
      if(left / row_size < element.count)
        fail(filename_, truncated_message(element, static_cast<std::size_t>(left / row_size),
                                          input_->position() + left / row_size * row_size, file_size));
      input_->skip(row_size * element.count);
      return;
    }
    const std::uint64_t file_size = input_->file_size();
    for(std::size_t row = 0; row < element.count; ++row) {
      const std::uint64_t row_begin = input_->position();
      for(const Ply_header_property& property : element.properties) {
        if(!property.is_list) {
          if(!input_->skip(ply_scalar_type_size(property.type)))
            fail(filename_, truncated_message(element, row, row_begin, file_size));
          continue;
        }
        const std::size_t count_size = ply_scalar_type_size(property.count_type);
        if(input_->fill(count_size) < count_size) fail(filename_, truncated_message(element, row, row_begin, file_size));
        const double count = load_scalar(input_->data(), property.count_type, swap_);
        if(count < 0)
          fail(filename_, negative_list_message(element, row, input_->position()));
        input_->consume(count_size);
        if(!input_->skip(static_cast<std::uint64_t>(count) * ply_scalar_type_size(property.type)))
          fail(filename_, truncated_message(element, row, row_begin, file_size));
      }
    }
  }

  /// After the last vertex: skips the following elements and checks the end of the file.
  void finish_ply()
  {
    for(std::size_t e = vertex_element_ + 1; e < elements_.size(); ++e) skip_element(elements_[e]);
    if(binary_) check_no_trailing_data(input_->position());
    finished_ = true;
  }

  /// Sets `[first, eol)` to the next line that is not blank (whose number is then
  /// `line_`), as `internal::Line_reader` does; `false` at the end of the file.
  bool next_nonblank_line(const char*& first, const char*& eol)
  {
    using namespace internal;
    for(;;) {
      const Buffered_input::Line_status status = input_->next_line(first, eol);
      if(status == Buffered_input::Line_status::END) return false;
      ++line_;
      if(status == Buffered_input::Line_status::TOO_LONG)
        fail(filename_, "line " + std::to_string(line_) + " is longer than the reading buffer (" +
                          std::to_string(input_->capacity()) + " bytes)");
      while(first != eol && is_blank(*first)) ++first;
      if(first != eol) return true;
    }
  }

  std::size_t read_ascii_records(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    using namespace internal;
    const Ply_header_element& vertex = elements_[vertex_element_];
    std::size_t count = 0;
    for(; count < maximum && next_index_ < expected_count_; ++count) {
      const char* first = nullptr;
      const char* eol = nullptr;
      if(!next_nonblank_line(first, eol)) fail(filename_, truncated_message(vertex, static_cast<std::size_t>(next_index_)));
      parse_ascii_row(filename_, vertex, first, eol, line_, row_values_.data());
      Point_record record{};
      for(std::size_t j = 0; j < roles_.size(); ++j) {
        const std::size_t role = roles_[j];
        if(role < 3) record.position[role] = row_values_[j];
        else if(role < 6) record.normal[role - 3] = row_values_[j];
      }
      check_finite_values(filename_, record.position, has_normals_ ? record.normal : nullptr, "line", line_);
      record.index = next_index_++;
      chunk.push_back(record);
    }
    return count;
  }

  std::size_t read_binary_records(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    using namespace internal;
    std::size_t count = 0;
    while(count < maximum && next_index_ < expected_count_) {
      if(input_->fill(row_size_) < row_size_)
        fail(filename_, truncated_message(elements_[vertex_element_], static_cast<std::size_t>(next_index_),
                                          input_->position(), input_->file_size()));
      const std::size_t rows = static_cast<std::size_t>(std::min<std::uint64_t>(
        {input_->available() / row_size_, maximum - count, expected_count_ - next_index_}));
      const char* p = input_->data();
      for(std::size_t r = 0; r < rows; ++r, p += row_size_) {
        Point_record record{};
        for(const Binary_field& field : fields_) {
          const double value = load_scalar(p + field.offset, field.type, swap_);
          if(field.role < 3) record.position[field.role] = value;
          else record.normal[field.role - 3] = value;
        }
        const double* const normal = has_normals_ ? record.normal : nullptr;
        if(!all_finite(record.position) || (normal != nullptr && !all_finite(normal)))
          check_finite_values(filename_, record.position, normal, "vertex", next_index_,
                              at_byte_offset(input_->position()).c_str());
        record.index = next_index_++;
        chunk.push_back(record);
        input_->consume(row_size_);
      }
      count += rows;
    }
    return count;
  }

  std::string filename_;
  internal::File_format format_ = internal::File_format::XYZ;
  std::unique_ptr<internal::Buffered_input> input_;
  bool has_normals_ = false;
  std::uint64_t expected_count_ = 0;
  std::uint64_t data_offset_ = 0; // byte offset of the first point
  std::uint64_t data_line_ = 0;   // number of the line before the first point
  std::uint64_t line_ = 0;        // number of the last line read (text data)
  std::uint64_t next_index_ = 0;  // index of the next record
  bool finished_ = false;         // the end of the data was reached and checked
  std::string error_;             // message of the last reading error, if any
  // xyz
  std::size_t columns_ = 0;         // values of the first data line, 0 if none
  std::size_t first_data_line_ = 0; // its line number
  // PLY
  std::vector<internal::Ply_header_element> elements_;
  std::size_t vertex_element_ = 0;
  internal::Ply_format ply_format_ = internal::Ply_format::ASCII;
  std::uint64_t header_size_ = 0; // bytes of the header
  bool binary_ = false;
  bool swap_ = false;
  std::vector<std::size_t> roles_;      // role of each vertex property (see assign_vertex_roles)
  std::vector<Binary_field> fields_;    // binary: x y z nx ny nz in the row
  std::size_t row_size_ = 0;            // binary: bytes per vertex
  std::vector<double> row_values_;      // ASCII: values of one vertex row
};

/// @}

namespace internal {

inline std::optional<Ply_stream_layout> ply_layout(const Point_stream_reader& reader)
{
  return reader.ply_layout();
}

} // namespace internal

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_POINT_STREAM_READER_H
