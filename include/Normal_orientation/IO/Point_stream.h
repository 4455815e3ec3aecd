// SPDX-License-Identifier: GPL-3.0-or-later
/// \file Point_stream.h
/// \brief Sequential (streaming) reading and writing of point clouds in the `.xyz`,
/// `.pwn` and `.ply` formats, chunk by chunk, with a fixed amount of memory whatever
/// the size of the file: the input and output of the out-of-core orientation.
///
/// `Point_stream_reader` reads the same files as `read_point_cloud()` and gives, point
/// by point and bit for bit, the same coordinates and normals, as
/// `Point_record`s numbered 0, 1, ... in file order. It reports the same
/// errors with the same messages (bytes after the last element of a binary PLY file
/// included, with their byte offset). Errors are found as the data are read, so an error in
/// the middle of the file is reported by the `read()` call that reaches it (header
/// errors, and in binary PLY files most size mismatches, by the constructor).
///
/// `Point_stream_writer` writes records to a `.xyz`/`.pwn` or `.ply` file as they come
/// and makes the file appear, atomically, only when `commit()` is called.

#ifndef NORMAL_ORIENTATION_IO_POINT_STREAM_H
#define NORMAL_ORIENTATION_IO_POINT_STREAM_H

#include <Normal_orientation/IO/Point_cloud_io.h>
#include <Normal_orientation/Point_record.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <sys/types.h>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

namespace internal {

/// \brief Sequential reading of a seekable file through a buffer of fixed capacity.
///
/// `data()` and `available()` give the bytes read but not consumed yet; `fill()` reads
/// more (moving the unconsumed bytes to the front of the buffer, which invalidates the
/// pointers obtained before).
class Buffered_input
{
public:
  /// Result of `next_line()`.
  enum class Line_status
  {
    LINE,     ///< a line was found
    END,      ///< end of file, no more lines
    TOO_LONG  ///< the line does not fit in the buffer; nothing was consumed
  };

  /// Opens `filename` for reading, with a buffer of `capacity` bytes.
  Buffered_input(const std::string& filename, std::size_t capacity)
    : filename_(filename), capacity_(capacity), buffer_(new char[capacity])
  {
    std::error_code error;
    if(std::filesystem::is_directory(filename, error)) fail(filename, "cannot read file: it is a directory");
    file_ = std::fopen(filename.c_str(), "rb");
    if(file_ == nullptr) {
      const int error_number = errno;
      fail(filename, "cannot open file for reading: " + error_text(error_number));
    }
    if(::fseeko(file_, 0, SEEK_END) != 0) seek_failed();
    const off_t size = ::ftello(file_);
    if(size < 0) seek_failed();
    file_size_ = static_cast<std::uint64_t>(size);
    seek(0);
  }

  Buffered_input(const Buffered_input&) = delete;
  Buffered_input& operator=(const Buffered_input&) = delete;

  ~Buffered_input()
  {
    if(file_ != nullptr) std::fclose(file_);
  }

  /// Size of the buffer in bytes.
  std::size_t capacity() const { return capacity_; }
  /// Size of the file in bytes when it was opened.
  std::uint64_t file_size() const { return file_size_; }
  /// Byte offset in the file of `data()`.
  std::uint64_t position() const { return buffer_offset_ + static_cast<std::uint64_t>(begin_ - buffer_.get()); }
  /// The bytes read and not consumed yet.
  const char* data() const { return begin_; }
  /// Number of bytes at `data()`.
  std::size_t available() const { return static_cast<std::size_t>(end_ - begin_); }
  /// Consumes `size <= available()` bytes.
  void consume(std::size_t size) { begin_ += size; }

  /// Enlarges the buffer to at least `capacity` bytes, keeping its content.
  void reserve(std::size_t capacity)
  {
    if(capacity <= capacity_) return;
    std::unique_ptr<char[]> larger(new char[capacity]);
    const std::size_t size = available();
    std::memcpy(larger.get(), begin_, size);
    buffer_offset_ = position();
    buffer_ = std::move(larger);
    capacity_ = capacity;
    begin_ = buffer_.get();
    end_ = begin_ + size;
  }

  /// Restarts reading at byte `offset` of the file.
  void seek(std::uint64_t offset)
  {
    if(::fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) seek_failed();
    buffer_offset_ = offset;
    begin_ = end_ = buffer_.get();
    at_end_ = false;
  }

  /// Reads until at least `wanted` (at most `capacity()`) bytes are available or the
  /// file ends; returns `available()`.
  std::size_t fill(std::size_t wanted)
  {
    if(available() >= wanted || at_end_) return available();
    const std::size_t size = available();
    buffer_offset_ = position();
    std::memmove(buffer_.get(), begin_, size);
    begin_ = buffer_.get();
    end_ = begin_ + size;
    const std::size_t room = capacity_ - size;
    const std::size_t got = std::fread(end_, 1, room, file_);
    end_ += got;
    if(got < room) {
      if(std::ferror(file_)) {
        const int error_number = errno;
        fail(filename_, "cannot read file: " + error_text(error_number));
      }
      at_end_ = true;
    }
    return available();
  }

  /// Skips `size` bytes; returns `false`, at the end of the file, if it has fewer.
  bool skip(std::uint64_t size)
  {
    if(size <= available()) {
      consume(static_cast<std::size_t>(size));
      return true;
    }
    const std::uint64_t target = position() + size;
    if(target > file_size_) {
      seek(file_size_);
      return false;
    }
    seek(target);
    return true;
  }

  /// Sets `[begin, eol)` to the next line (without its `'\n'`) and consumes it.
  Line_status next_line(const char*& begin, const char*& eol)
  {
    std::size_t scanned = 0; // bytes at data() known to hold no '\n'
    for(;;) {
      const void* newline = std::memchr(begin_ + scanned, '\n', available() - scanned);
      if(newline != nullptr) {
        begin = begin_;
        eol = static_cast<const char*>(newline);
        begin_ += (eol - begin_) + 1;
        return Line_status::LINE;
      }
      scanned = available();
      if(at_end_) {
        if(scanned == 0) return Line_status::END;
        begin = begin_;
        eol = end_;
        begin_ = end_;
        return Line_status::LINE;
      }
      if(scanned == capacity_) return Line_status::TOO_LONG;
      fill(scanned + 1);
    }
  }

  /// Consumes the rest of the current line, its `'\n'` included, whatever its length.
  void skip_line()
  {
    for(;;) {
      const void* newline = std::memchr(begin_, '\n', available());
      if(newline != nullptr) {
        begin_ += (static_cast<const char*>(newline) - begin_) + 1;
        return;
      }
      begin_ = end_;
      if(fill(1) == 0) return;
    }
  }

  /// Appends the next line, its `'\n'` included, to `text`, but no more than
  /// `max_size - text.size()` bytes; returns `false` at the end of the file.
  bool append_line(std::string& text, std::size_t max_size)
  {
    if(fill(1) == 0) return false;
    while(text.size() < max_size) {
      const std::size_t size = std::min(available(), max_size - text.size());
      const void* newline = std::memchr(begin_, '\n', size);
      const std::size_t taken = newline != nullptr ? static_cast<std::size_t>(static_cast<const char*>(newline) - begin_) + 1
                                                   : size;
      text.append(begin_, taken);
      begin_ += taken;
      if(newline != nullptr || fill(1) == 0) break;
    }
    return true;
  }

private:
  [[noreturn]] void seek_failed()
  {
    const int error_number = errno;
    fail(filename_, "cannot seek in file (streaming needs a regular file): " + error_text(error_number));
  }

  std::string filename_;
  std::FILE* file_ = nullptr;
  std::uint64_t file_size_ = 0;
  std::size_t capacity_;
  std::unique_ptr<char[]> buffer_;
  std::uint64_t buffer_offset_ = 0; // byte offset in the file of buffer_[0]
  char* begin_ = nullptr;           // unconsumed data: [begin_, end_)
  char* end_ = nullptr;
  bool at_end_ = false; // the file has no more bytes after end_
};

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

} // namespace internal

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
/// which may be of any length; a PLY header is read up to
/// `internal::max_streamed_ply_header_size` bytes (1 MiB); the file must be seekable
/// (a regular file, not a pipe).
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
    const std::string extension = internal::lower_case_extension(filename);
    if(extension == ".xyz" || extension == ".pwn") format_ = Format::XYZ;
    else if(extension == ".ply") format_ = Format::PLY;
    else
      internal::fail(filename, "unknown point cloud file extension '" + extension +
                                 "' (expected .xyz, .pwn or .ply)");
    input_.reset(new internal::Buffered_input(filename, std::max(buffer_size, minimum_buffer_size)));
    if(format_ == Format::XYZ) open_xyz();
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

  /// \brief Layout of a PLY file as read from its header (elements, vertex properties and
  /// their roles, row size and property offsets of binary data, byte offsets of the end
  /// of the header and of the first vertex row); no value for a `.xyz`/`.pwn` file. For
  /// code that reads or copies the bytes of the file itself, such as
  /// `transcode_with_flips()`.
  std::optional<internal::Ply_stream_layout> ply_layout() const
  {
    if(format_ != Format::PLY) return std::nullopt;
    internal::Ply_stream_layout layout;
    layout.format = ply_format_;
    layout.elements = elements_;
    layout.vertex_element = vertex_element_;
    layout.roles = roles_;
    std::size_t offset = 0;
    for(const internal::Ply_header_property& property : elements_[vertex_element_].properties) {
      layout.offsets.push_back(offset);
      offset += ply_scalar_type_size(property.type);
    }
    layout.row_size = row_size_;
    layout.header_size = header_size_;
    layout.vertex_data_offset = data_offset_;
    return layout;
  }

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
      if(format_ == Format::XYZ) count = read_xyz_records(chunk, maximum);
      else if(binary_) count = read_binary_records(chunk, maximum);
      else count = read_ascii_records(chunk, maximum);
      if(format_ == Format::PLY && next_index_ == expected_count_ && !finished_) finish_ply();
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
  enum class Format { XYZ, PLY };

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
        if(n != 3 && n != 6) error = Xyz_error::COLUMN_COUNT;
        else if(columns_ == 0) {
          columns_ = n;
          first_data_line_ = line_;
        } else if(n != columns_) {
          error = Xyz_error::COLUMN_MISMATCH;
        }
      }
      if(error == Xyz_error::NONE && !(std::isfinite(values[0]) && std::isfinite(values[1]) && std::isfinite(values[2])))
        error = Xyz_error::NON_FINITE_COORDINATE;
      if(error == Xyz_error::NONE && n == 6 &&
         !(std::isfinite(values[3]) && std::isfinite(values[4]) && std::isfinite(values[5])))
        error = Xyz_error::NON_FINITE_NORMAL;
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
    Point_cloud roles_of; // receives the property types, unused here
    const std::vector<std::size_t> roles = assign_vertex_roles(filename_, vertex, roles_of);
    has_normals_ = std::find(roles.begin(), roles.end(), std::size_t(3)) != roles.end();
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
      std::uint64_t size = 0;
      for(const Ply_header_property& property : elements_[e].properties) {
        if(property.is_list) return; // checked when skipped
        size += ply_scalar_type_size(property.type);
      }
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
    const internal::Ply_header_element& last = elements_.back();
    internal::fail(filename_, std::to_string(size - end) + " bytes of unexpected data at byte offset " +
                                std::to_string(end) + ", after the last " +
                                (last.name == "vertex" ? std::string("vertex") : "row of element '" + last.name + "'") +
                                " of the PLY data");
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
    bool has_list = false;
    std::uint64_t row_size = 0;
    for(const Ply_header_property& property : element.properties) {
      has_list = has_list || property.is_list;
      if(!property.is_list) row_size += ply_scalar_type_size(property.type);
    }
    if(!has_list) {
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
          fail(filename_, "negative list length in element '" + element.name + "' at row " + std::to_string(row) +
                            at_byte_offset(input_->position()));
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
        if(!(std::isfinite(record.position[0]) && std::isfinite(record.position[1]) && std::isfinite(record.position[2]) &&
             (normal == nullptr || (std::isfinite(normal[0]) && std::isfinite(normal[1]) && std::isfinite(normal[2])))))
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
  Format format_ = Format::XYZ;
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

/// \brief Options of `Point_stream_writer`.
struct Point_stream_write_options
{
  /// PLY only: write `binary_little_endian` if `true`, `ascii` otherwise.
  bool binary = true;
  /// Write the normals (`nx ny nz`) of the records; only `x y z` otherwise.
  bool normals = true;
  /// PLY only: add the vertex property `int segment`, after the others, whose values are
  /// given to `Point_stream_writer::write(const Point_record&, std::uint32_t)`
  /// (`streaming_orient_files()` writes there the segment of each point). A `.xyz`/`.pwn`
  /// file cannot hold it: the writer's constructor throws `Io_error` then.
  bool segments = false;
};

/// \brief Sequential writer of `Point_record`s to a point cloud file.
///
/// The format is chosen from the extension (case-insensitive): `.xyz` and `.pwn` write
/// one line `x y z nx ny nz` (or `x y z`) per record, each value with the shortest text
/// that reads back to the same `double`; `.ply` writes a single `vertex` element with
/// properties `double x y z` and `double nx ny nz`, in `binary_little_endian` (48 bytes
/// per point) or `ascii` (shortest exact text). Normals are written as `double`, not
/// `float`, so that every value read back by `read_point_cloud()` or
/// `Point_stream_reader` is bit for bit the value written. The `index` of the records
/// is not written: records are written in the order given. With
/// `Point_stream_write_options::segments`, a PLY file has one more vertex property,
/// `int segment`, and each record is written with its segment.
///
/// The data go to a temporary file `<filename>.tmp.<pid>.<n>` in the directory of
/// `filename`, renamed over `filename` by `commit()` (for PLY, after the vertex count,
/// written in the header as a fixed-width field, has been set). A writer destroyed
/// without `commit()`, for instance after an exception, removes its temporary file: no
/// output file appears and an existing `filename` is unchanged. Memory use is a fixed
/// buffer of `internal::Atomic_output_file::capacity` bytes.
class Point_stream_writer
{
public:
  /// \brief Creates the temporary file and, for PLY, writes the header.
  /// \throws Io_error on an unknown extension, if the temporary file cannot be created,
  /// or if `options.segments` is set for a `.xyz`/`.pwn` file.
  explicit Point_stream_writer(const std::string& filename,
                               const Point_stream_write_options& options = Point_stream_write_options())
    : filename_(filename), options_(options)
  {
    const std::string extension = internal::lower_case_extension(filename);
    if(extension == ".ply") ply_ = true;
    else if(extension != ".xyz" && extension != ".pwn")
      internal::fail(filename, "unknown point cloud file extension '" + extension +
                                 "' (expected .xyz, .pwn or .ply)");
    if(!ply_ && options_.segments) internal::fail(filename, "segments can only be written to a .ply file");
    out_.reset(new internal::Atomic_output_file(filename));
    if(!ply_) return;
    std::string header = "ply\nformat ";
    header += options_.binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
    header += "comment generated by Normal_orientation\nelement vertex ";
    count_offset_ = header.size();
    header += std::string(count_width, ' ') + "\n";
    header += "property double x\nproperty double y\nproperty double z\n";
    if(options_.normals) header += "property double nx\nproperty double ny\nproperty double nz\n";
    if(options_.segments) header += "property int segment\n";
    header += "end_header\n";
    out_->put(header);
  }

  Point_stream_writer(const Point_stream_writer&) = delete;
  Point_stream_writer& operator=(const Point_stream_writer&) = delete;
  /// \brief Moves the writer and its temporary file (the moved-from writer may only be
  /// destroyed or assigned to). Assigning to a writer that was not committed removes
  /// its temporary file.
  Point_stream_writer(Point_stream_writer&&) = default;
  /// \brief See the move constructor.
  Point_stream_writer& operator=(Point_stream_writer&&) = default;

  /// \brief Name of the file written.
  const std::string& filename() const { return filename_; }
  /// \brief Returns `true` if the normals are written.
  bool has_normals() const { return options_.normals; }
  /// \brief Returns `true` if a segment is written with each record
  /// (`Point_stream_write_options::segments`).
  bool has_segments() const { return options_.segments; }
  /// \brief Number of records written so far.
  std::uint64_t count() const { return count_; }

  /// \brief Writes `record` (its position and, if `has_normals()`, its normal).
  /// \throws Io_error if a value is not finite (nothing of the record is written then),
  /// on a writing error, after `commit()`, or if `has_segments()` (a segment is needed).
  void write(const Point_record& record)
  {
    if(options_.segments) internal::fail(filename_, "cannot write a point without its segment");
    write_values(record, 0);
  }

  /// \brief Writes `record` as `write(const Point_record&)` does, followed by
  /// `segment` (the `int segment` property).
  /// \throws Io_error as `write(const Point_record&)`, if `has_segments()` is
  /// `false`, or if `segment` exceeds the range of `int` (2^31 - 1); nothing of the
  /// record is written then.
  void write(const Point_record& record, std::uint32_t segment)
  {
    if(!options_.segments) internal::fail(filename_, "cannot write a segment: segments are not enabled");
    if(segment > 2147483647u)
      internal::fail(filename_, "segment " + std::to_string(segment) + " exceeds the range of a PLY int");
    write_values(record, segment);
  }

  /// \brief Writes the records of `records`, in order.
  /// \throws Io_error as `write(const Point_record&)`; the records before
  /// the faulty one are written.
  void write(const std::vector<Point_record>& records)
  {
    for(const Point_record& record : records) write(record);
  }

  /// \brief Completes the file (PLY: sets the vertex count in the header) and renames
  /// it to `filename()`.
  /// \throws Io_error on a writing or renaming error (the temporary file is then removed
  /// by the destructor) or if already committed.
  void commit()
  {
    if(committed_) internal::fail(filename_, "cannot commit: the file was already committed");
    if(ply_) {
      std::string count = std::to_string(count_);
      count.resize(count_width, ' ');
      out_->overwrite(count_offset_, count);
    }
    out_->commit();
    committed_ = true;
  }

private:
  /// Width of the vertex count in the PLY header: the digits of any 64-bit count,
  /// padded with blanks.
  static constexpr std::size_t count_width = 20;

  /// Writes `record` and, if `has_segments()`, `segment` (at most 2^31 - 1).
  void write_values(const Point_record& record, std::uint32_t segment)
  {
    using namespace internal;
    if(committed_) fail(filename_, "cannot write: the file was already committed");
    check_finite_values(filename_, record.position, options_.normals ? record.normal : nullptr,
                        "vertex", count_);
    const std::size_t values = options_.normals ? 6 : 3;
    if(ply_ && options_.binary) {
      char* target = out_->room(values * sizeof(double));
      const bool swap = !host_is_little_endian();
      for(std::size_t c = 0; c < values; ++c)
        store_scalar(target + c * sizeof(double), c < 3 ? record.position[c] : record.normal[c - 3],
                     Ply_scalar_type::FLOAT64, swap);
      out_->advance(values * sizeof(double));
      if(options_.segments) {
        store_scalar(out_->room(4), static_cast<double>(segment), Ply_scalar_type::INT32, swap);
        out_->advance(4);
      }
    } else {
      for(std::size_t c = 0; c < values; ++c) {
        if(c != 0) out_->put(' ');
        out_->put_shortest(c < 3 ? record.position[c] : record.normal[c - 3]);
      }
      if(options_.segments) {
        out_->put(' ');
        out_->put_shortest(static_cast<long long>(segment));
      }
      out_->put('\n');
    }
    ++count_;
  }

  std::string filename_;
  Point_stream_write_options options_;
  bool ply_ = false;
  std::unique_ptr<internal::Atomic_output_file> out_;
  std::uint64_t count_ = 0;
  std::uint64_t count_offset_ = 0; // PLY: byte offset of the vertex count
  bool committed_ = false;
};

/// @}

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_POINT_STREAM_H
