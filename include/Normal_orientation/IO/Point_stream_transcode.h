// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Point_stream_transcode.h
/// \brief Copying a point cloud file in its own order and format with some normals
/// negated and some points left out, streaming, with a fixed amount of memory:
/// `transcode_with_flips()` (the sets of point indices it takes are `Bit_set`s).
///
/// This is how an out-of-core run can give back the input as it was, colours and other
/// vertex properties included, with only the signs of normals changed: the orientation
/// decides, point by point (by the index of the point in the file), which normals to
/// negate and which points to keep, and the input file is then copied with these changes
/// and nothing else.

#ifndef NORMAL_ORIENTATION_IO_POINT_STREAM_TRANSCODE_H
#define NORMAL_ORIENTATION_IO_POINT_STREAM_TRANSCODE_H

#include <Normal_orientation/IO/Atomic_output_file.h>
#include <Normal_orientation/IO/Bit_set.h>
#include <Normal_orientation/IO/File_format.h>
#include <Normal_orientation/IO/Input_file.h>
#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Ply_header.h>
#include <Normal_orientation/IO/Ply_types.h>
#include <Normal_orientation/IO/Point_stream_reader.h>
#include <Normal_orientation/IO/Text_lines.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/Point_record.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

/// \brief Options of `transcode_with_flips()`.
struct Transcode_options
{
  /// Size in bytes of each of the two reading buffers (see `transcode_with_flips()`);
  /// as for `Point_stream_reader`, a data line of a text file must fit in it.
  std::size_t buffer_size = Point_stream_reader::default_buffer_size;
  /// Called after each chunk of points with the bytes of the input read so far and the
  /// size of the input; returning `false` stops the copy with `Interrupted` (no output
  /// is written then). Empty: no progress.
  std::function<bool(std::uint64_t bytes_read, std::uint64_t file_size)> callback;
};

/// \brief What `transcode_with_flips()` did.
struct Transcode_report
{
  /// Points in the input.
  std::uint64_t number_of_points = 0;
  /// Points written (the points kept).
  std::uint64_t number_of_written_points = 0;
  /// Points left out (`number_of_points - number_of_written_points`).
  std::uint64_t number_of_dropped_points = 0;
  /// Points written whose normal was negated.
  std::uint64_t number_of_flipped = 0;
  /// Integer normal components to negate that held the most negative value of their type
  /// (e.g. -128 for `char`), whose negation the type cannot hold: the largest value of
  /// the type (127) was written instead.
  std::uint64_t number_of_saturated_values = 0;
  /// PLY: the elements other than `vertex` (e.g. `face`), left out of the output.
  std::vector<std::string> dropped_elements;
  /// Size of the output file in bytes.
  std::uint64_t bytes_written = 0;
};

namespace internal {

/// \brief A normal component of the vertex rows of a PLY file: its type, its byte
/// offset in a binary row, its position among the values of an ASCII row.
struct Transcoded_normal
{
  Ply_scalar_type type = Ply_scalar_type::FLOAT64; ///< the type declared
  std::size_t offset = 0;                          ///< binary: byte offset in the row
  std::size_t token = 0;                           ///< text: index of the value on the line
};

/// \brief Negates in place the binary value of type `type` at `value`, stored
/// big-endian if `big_endian`, little-endian otherwise: for `float` and `double` the sign
/// bit is toggled (exact, zeros included), a signed integer is negated, its most negative
/// value giving its largest one (returns `true` then). `type` must not be unsigned.
inline bool negate_binary_value(char* value, Ply_scalar_type type, bool big_endian)
{
  const bool swap = big_endian == host_is_little_endian();
  auto negate = [](auto x, bool& saturated) {
    using T = decltype(x);
    if(x == std::numeric_limits<T>::min()) {
      saturated = true;
      return std::numeric_limits<T>::max();
    }
    return static_cast<T>(-x);
  };
  bool saturated = false;
  switch(type) {
  case Ply_scalar_type::FLOAT32:
  case Ply_scalar_type::FLOAT64:
    value[big_endian ? 0 : ply_scalar_type_size(type) - 1] ^= static_cast<char>(0x80);
    break;
  case Ply_scalar_type::INT8: {
    signed char x = 0;
    std::memcpy(&x, value, 1);
    x = negate(x, saturated);
    std::memcpy(value, &x, 1);
    break;
  }
  case Ply_scalar_type::INT16:
    store_bits<std::int16_t, std::uint16_t>(value, negate(load_bits<std::int16_t, std::uint16_t>(value, swap), saturated),
                                            swap);
    break;
  case Ply_scalar_type::INT32:
    store_bits<std::int32_t, std::uint32_t>(value, negate(load_bits<std::int32_t, std::uint32_t>(value, swap), saturated),
                                            swap);
    break;
  default: throw std::logic_error("negate_binary_value: unsigned type");
  }
  return saturated;
}

/// \brief The PLY header `header` (the bytes of the file's header, its `end_header` line
/// included) for the copy made by `transcode_with_flips()`: the lines of the header as
/// they are, except the `element` lines of the elements other than `vertex` and their
/// `property` lines, which are left out (their names are appended to `dropped`), and,
/// if `count_changed`, the count of the `element vertex` line, replaced by `count` (the
/// rest of that line, blanks included, as it is).
inline std::string transcoded_ply_header(const std::string& header, bool count_changed, std::uint64_t count,
                                         std::vector<std::string>& dropped)
{
  std::string result;
  result.reserve(header.size() + 24);
  bool in_vertex = false; // the lines follow 'element vertex'
  std::size_t p = 0;
  while(p < header.size()) {
    const std::size_t newline = header.find('\n', p);
    const std::size_t end = newline == std::string::npos ? header.size() : newline + 1;
    const char* const line = header.data() + p;
    const std::vector<std::string_view> tokens =
      split_blanks(line, header.data() + (newline == std::string::npos ? header.size() : newline));
    bool keep = true;
    if(!tokens.empty() && tokens[0] == "element" && tokens.size() == 3) {
      in_vertex = tokens[1] == "vertex";
      if(!in_vertex) {
        dropped.emplace_back(tokens[1]);
        keep = false;
      } else if(count_changed) {
        const std::string_view old_count = tokens[2];
        result.append(line, old_count.data());
        result += std::to_string(count);
        result.append(old_count.data() + old_count.size(), header.data() + end);
        keep = false;
      }
    } else if(!tokens.empty() && tokens[0] == "property") {
      keep = in_vertex;
    }
    if(keep) result.append(header, p, end - p);
    p = end;
  }
  return result;
}

/// \brief The copy of `transcode_with_flips()`: a `Point_stream_reader` reads and checks
/// the points, chunk by chunk, and a second reading of the file, following it, copies
/// their bytes to the output with the changes.
class Flip_transcoder
{
public:
  /// Opens `input` (header checked), checks the sets against it and the output's
  /// extension; nothing is created yet.
  Flip_transcoder(const std::string& input, const std::string& output, const Bit_set& flip, const Bit_set* keep,
                  const Transcode_options& options)
    : input_(input), output_(output), flip_(flip), keep_(keep), options_(options),
      reader_(input, options.buffer_size), layout_(ply_layout(reader_))
  {
    if((file_format(output) == File_format::PLY) != ply())
      fail(output, std::string("cannot copy '") + input + "' to another format: the output must be a " +
                     (ply() ? ".ply" : ".xyz or .pwn") + " file, as the input");
    if(ply()) check_set_sizes(layout_->elements[layout_->vertex_element].count);
    flips_ = flip_.any() && (keep_ == nullptr || intersects(flip_, *keep_));
    if(flips_ && !reader_.has_normals())
      throw std::invalid_argument(input + ": cannot flip normals: the file has none");
    if(!ply()) return;

    const Ply_header_element& vertex = layout_->elements[layout_->vertex_element];
    for(std::size_t j = 0; j < layout_->roles.size(); ++j) {
      const std::size_t role = layout_->roles[j];
      if(role < 3 || role > 5) continue;
      const Ply_header_property& property = vertex.properties[j];
      normals_[role - 3] = Transcoded_normal{property.type, layout_->offsets[j], j};
      if(flips_ && !is_floating(property.type) && integer_range(property.type).first == 0)
        fail(input, std::string("cannot flip normals of unsigned type '") + ply_scalar_type_name(property.type) +
                      "' (property '" + property.name + "'): their negations do not fit the type");
    }
  }

  /// Writes the output (to a temporary file renamed at the end).
  Transcode_report run()
  {
    internal::Buffered_input raw(input_, std::max(reader_.buffer_capacity(), ply() ? layout_->row_size : 0));
    raw_ = &raw;
    if(raw.file_size() != reader_.file_size())
      changed("its size went from " + std::to_string(reader_.file_size()) + " to " + std::to_string(raw.file_size()) +
              " bytes");
    Atomic_output_file out(output_);
    out_ = &out;
    if(ply()) {
      const std::uint64_t n = layout_->elements[layout_->vertex_element].count;
      const std::uint64_t kept = keep_ == nullptr ? n : keep_->count();
      std::string header;
      while(header.size() < layout_->header_size) {
        if(raw.fill(1) == 0) changed("its header ends early");
        const std::size_t taken =
          static_cast<std::size_t>(std::min<std::uint64_t>(raw.available(), layout_->header_size - header.size()));
        header.append(raw.data(), taken);
        raw.consume(taken);
      }
      out.put(transcoded_ply_header(header, kept != n, kept, report_.dropped_elements));
      raw.seek(layout_->vertex_data_offset);
    }
    const bool binary = ply() && layout_->format != Ply_format::ASCII;
    std::vector<Point_record> chunk;
    chunk.reserve(chunk_size);
    for(;;) {
      chunk.clear();
      if(reader_.read(chunk, chunk_size) == 0) break;
      if(binary) copy_binary_rows(chunk);
      else copy_text_rows(chunk);
      progress(raw.position());
    }
    report_.number_of_points = reader_.records_read();
    // What follows the points: the end of a text file (comments, blank lines) and, when
    // `vertex` is the last element, of an ASCII PLY file are copied as they are.
    if(!binary && (!ply() || layout_->vertex_element + 1 == layout_->elements.size()))
      while(raw.fill(1) != 0) {
        out.put(std::string_view(raw.data(), raw.available()));
        raw.consume(raw.available());
      }
    if(!ply()) check_set_sizes(report_.number_of_points);
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(input_, error);
    if(error) changed("it cannot be read any more: " + error.message());
    if(size != reader_.file_size())
      changed("its size went from " + std::to_string(reader_.file_size()) + " to " + std::to_string(size) + " bytes");
    progress(reader_.file_size());
    out.commit();
    report_.number_of_dropped_points = report_.number_of_points - report_.number_of_written_points;
    report_.bytes_written = static_cast<std::uint64_t>(std::filesystem::file_size(output_, error));
    return report_;
  }

private:
  /// Points read and copied at a time.
  static constexpr std::size_t chunk_size = 16384;

  bool ply() const { return layout_.has_value(); }
  bool kept(std::uint64_t i) const { return keep_ == nullptr || keep_->test(i); }
  bool flipped(std::uint64_t i) const { return flips_ && flip_.test(i); }

  static bool intersects(const Bit_set& a, const Bit_set& b)
  {
    const std::size_t words = std::min(a.words().size(), b.words().size());
    for(std::size_t w = 0; w < words; ++w)
      if((a.words()[w] & b.words()[w]) != 0) return true;
    return false;
  }

  void check_set_sizes(std::uint64_t n) const
  {
    auto check = [&](const Bit_set& set, const char* name) {
      if(set.size() != n)
        throw std::invalid_argument(input_ + ": the " + name + " set has " + std::to_string(set.size()) +
                                    " bits for " + std::to_string(n) + " points");
    };
    if(!flip_.empty()) check(flip_, "flip");
    if(keep_ != nullptr) check(*keep_, "keep");
  }

  [[noreturn]] void changed(const std::string& what) const
  {
    fail(input_, "the file changed while it was copied (" + what + ")");
  }

  void progress(std::uint64_t bytes) const
  {
    if(options_.callback && !options_.callback(bytes, reader_.file_size())) throw Interrupted();
  }

  void put(const char* begin, const char* end) { out_->put(std::string_view(begin, static_cast<std::size_t>(end - begin))); }

  /// Copies the binary rows of the points of `chunk`, which the reader has just read.
  void copy_binary_rows(const std::vector<Point_record>& chunk)
  {
    const std::size_t row_size = layout_->row_size;
    const bool big_endian = layout_->format == Ply_format::BINARY_BIG_ENDIAN;
    bool floating_normals = true;
    std::array<std::size_t, 3> sign_bytes{}; // floating normals: the byte of each sign bit in a row
    for(std::size_t c = 0; c < 3; ++c) {
      floating_normals = floating_normals && is_floating(normals_[c].type);
      sign_bytes[c] = normals_[c].offset + (big_endian ? 0 : ply_scalar_type_size(normals_[c].type) - 1);
    }
    std::uint64_t index = chunk.front().index;
    std::size_t left = chunk.size();
    while(left > 0) {
      if(raw_->fill(row_size) < row_size) changed("the vertex data end early");
      const std::size_t rows = std::min(raw_->available() / row_size, left);
      const char* p = raw_->data();
      const char* run = p; // rows copied as they are: [run, p)
      for(std::size_t r = 0; r < rows; ++r, ++index, p += row_size) {
        if(!kept(index)) {
          put(run, p);
          run = p + row_size;
          continue;
        }
        ++report_.number_of_written_points;
        if(!flipped(index)) continue;
        put(run, p);
        run = p + row_size;
        ++report_.number_of_flipped;
        char* target = nullptr;
        if(row_size <= Atomic_output_file::capacity) {
          target = out_->room(row_size);
        } else {
          scratch_.resize(row_size);
          target = scratch_.data();
        }
        std::memcpy(target, p, row_size);
        if(floating_normals) { // the sign bits, in their bytes
          for(std::size_t c = 0; c < 3; ++c) target[sign_bytes[c]] ^= static_cast<char>(0x80);
        } else {
          for(const Transcoded_normal& normal : normals_)
            if(negate_binary_value(target + normal.offset, normal.type, big_endian)) ++report_.number_of_saturated_values;
        }
        if(target == scratch_.data()) put(scratch_.data(), scratch_.data() + row_size);
        else out_->advance(row_size);
      }
      put(run, p);
      raw_->consume(rows * row_size);
      left -= rows;
    }
  }

  /// Copies the lines of the points of `chunk`, which the reader has just read, and the
  /// comment and blank lines before each.
  void copy_text_rows(const std::vector<Point_record>& chunk)
  {
    for(const Point_record& record : chunk) {
      for(;;) {
        const char* first = nullptr;
        const char* eol = nullptr;
        const Buffered_input::Line_status status = raw_->next_line(first, eol);
        if(status == Buffered_input::Line_status::END) changed("its data end early");
        if(status == Buffered_input::Line_status::TOO_LONG) {
          copy_long_comment();
          continue;
        }
        const char* q = first;
        while(q != eol && is_blank(*q)) ++q;
        const char* const next = raw_->data(); // the line ends there, its '\n' included
        if(q == eol || (!ply() && *q == '#')) { // not a point
          put(first, next);
          continue;
        }
        if(!kept(record.index)) break;
        ++report_.number_of_written_points;
        if(!flipped(record.index)) {
          put(first, next);
          break;
        }
        ++report_.number_of_flipped;
        put_flipped_line(first, eol, next, record);
        break;
      }
    }
  }

  /// Copies a comment line of a `.xyz`/`.pwn` file longer than the buffer, which starts
  /// at the unconsumed data of the buffer.
  void copy_long_comment()
  {
    const char* q = raw_->data();
    const char* const end = q + raw_->available();
    while(q != end && is_blank(*q)) ++q;
    if(ply() || q == end || *q != '#') changed("a line is longer than the buffer");
    for(;;) {
      const char* const data = raw_->data();
      const void* newline = std::memchr(data, '\n', raw_->available());
      const std::size_t size = newline != nullptr ? static_cast<std::size_t>(static_cast<const char*>(newline) - data) + 1
                                                  : raw_->available();
      put(data, data + size);
      raw_->consume(size);
      if(newline != nullptr || raw_->fill(1) == 0) return;
    }
  }

  /// Writes the line `[first, eol)` of the point `record`, ended by `[eol, next)`, with
  /// its normal negated.
  void put_flipped_line(const char* first, const char* eol, const char* next, const Point_record& record)
  {
    const char* copied = first; // [first, copied) is written
    const char* q = first;
    for(std::size_t token = 0; q != eol; ++token) {
      while(q != eol && is_blank(*q)) ++q;
      if(q == eol) break;
      const char* token_end = q;
      while(token_end != eol && !is_blank(*token_end)) ++token_end;
      for(std::size_t c = 0; c < 3; ++c) {
        const bool is_normal = ply() ? normals_[c].token == token : token == 3 + c;
        if(!is_normal) continue;
        put(copied, q);
        put_negated_token(q, token_end, ply() ? normals_[c].type : Ply_scalar_type::FLOAT64, record.normal[c]);
        copied = token_end;
      }
      q = token_end;
    }
    put(copied, next);
  }

  /// Writes the negation of the number `[begin, end)` of type `type`, whose value is
  /// `value`: the text without its sign if it has a `-`, with a `-` otherwise (a `+` is
  /// dropped), so that it reads back as exactly `-value`; an integer 0 is written as it
  /// is, and the most negative value of an integer type as the largest one.
  void put_negated_token(const char* begin, const char* end, Ply_scalar_type type, double value)
  {
    if(!is_floating(type)) {
      if(value == 0.0) return put(begin, end);
      const std::pair<double, double> range = integer_range(type);
      if(value == range.first) {
        ++report_.number_of_saturated_values;
        char text[32];
        const std::to_chars_result result = std::to_chars(text, text + sizeof(text), static_cast<long long>(range.second));
        return put(text, result.ptr);
      }
    }
    if(*begin == '+') ++begin; // "+x" is x, "+-x" is -x (ASCII PLY)
    if(*begin == '-') return put(begin + 1, end);
    out_->put('-');
    put(begin, end);
  }

  std::string input_;
  std::string output_;
  const Bit_set& flip_;
  const Bit_set* keep_;
  Transcode_options options_;
  Point_stream_reader reader_;
  std::optional<Ply_stream_layout> layout_;
  bool flips_ = false;                         // some point kept has its flip bit set
  std::array<Transcoded_normal, 3> normals_{}; // PLY: nx ny nz
  Buffered_input* raw_ = nullptr;              // the copy's reading of the input (during run())
  Atomic_output_file* out_ = nullptr;          // the output (during run())
  std::vector<char> scratch_;                  // a flipped row larger than the output's buffer
  Transcode_report report_;
};

} // namespace internal

/// \brief Copies the point cloud file `input` to `output` in its own order and format,
/// with the normal of every point whose bit is set in `flip` negated and every point
/// whose bit is clear in `*keep` left out, and everything else as it is.
///
/// Points are numbered 0, 1, ... in file order, as `Point_stream_reader` numbers them
/// (`Point_record::index`). `flip` has one bit per point of the file, or none
/// at all (no normal is negated); `keep` is null (every point is kept) or has one bit per
/// point. The file is read with the rules and the error messages of
/// `Point_stream_reader` (the formats of `read_point_cloud()`), and `output` must have
/// the format of `input` (`.ply`, or `.xyz`/`.pwn`).
///
/// What is written:
/// - **Binary PLY** (either byte order, which is kept): each vertex row kept is copied
///   byte for byte, every property included (colours, intensities...), except that the
///   normal of a flipped point is negated in its own type: the sign bit of a `float` or
///   `double` is toggled (exact, `0` becoming `-0`), a signed integer is negated, except
///   its most negative value (e.g. -128 for `char`), whose negation the type cannot
///   hold: the largest value of the type (127) is written instead and counted in
///   `Transcode_report::number_of_saturated_values`.
/// - **ASCII PLY** and **`.xyz`/`.pwn`**: each line is copied as it is (blanks, line
///   ends and the text of every number included), except that the normal values of a
///   flipped point lose their leading `-`, or get one (`0.25` <-> `-0.25`; a leading `+`
///   is dropped), so that they read back as exactly the negated values, whatever their
///   number of digits; an integer `0` is left as it is and the most negative value of an
///   integer type is written as the largest one, as in binary files. The line of a point
///   left out is removed, its end of line included. Blank lines and, in `.xyz`/`.pwn`
///   files, comment lines (`#`) are kept where they are; what follows the last point of
///   a `.xyz`/`.pwn` file, or of an ASCII PLY file whose last element is `vertex`, is
///   copied as it is.
/// - **The PLY header** is copied as it is (comments, `obj_info`, type spellings,
///   blanks), with two exceptions. As `write_point_cloud()` does, the elements other than
///   `vertex` (e.g. `face`) are left out, their declarations and their data, whether
///   points are left out or not (`Transcode_report::dropped_elements`). When points are
///   left out, the count of the `element vertex` line is replaced by the number of points
///   written (in decimal; the rest of the line as it is). So the copy with no bit of
///   `flip` set and every point kept, of a PLY file with a `vertex` element only, or of a
///   `.xyz`/`.pwn` file, is the input byte for byte.
///
/// Memory is fixed whatever the size of the file: two reading buffers of
/// `Transcode_options::buffer_size` bytes (one for `Point_stream_reader`, which checks
/// the points, one for the copy, which follows it), 16,384 points read at a time
/// (900 kB) and the output's buffer (1 MiB). The input is read once by each; the second
/// reading follows the first closely, so it is mostly served by the system's cache.
/// The output is written to `<output>.tmp.<pid>.<n>`, registered for
/// `remove_temporary_files()`, and renamed to `output` when complete; on any error or
/// interruption it is removed, and an existing `output` is left unchanged. `output` may
/// be `input` itself: the input is replaced only when the copy is complete.
///
/// \param input the file copied (`.xyz`, `.pwn` or `.ply`)
/// \param output the file written, in the format of `input`
/// \param flip the points whose normal is negated, by index: empty, or one bit per point
/// \param keep the points written, by index, one bit per point; null: every point
/// \param options the size of the buffers and a progress callback
/// \return the numbers of points read, written and flipped, the values saturated, the
///   elements left out and the size of the output
/// \throws Io_error (one line naming the file) if `input` cannot be read or is invalid
///   (the errors of `Point_stream_reader`), if `output` has an unknown extension or
///   another format than `input`, if a normal to negate has an unsigned integer type
///   (before anything is written), if `input` changes size while it is copied, or if
///   `output` cannot be written.
/// \throws std::invalid_argument if a set has a size other than the number of points
///   (`flip` may be empty), or if a point kept is to be flipped in a file without
///   normals. For a `.xyz`/`.pwn` file the number of points is known at its end only:
///   the error comes then, and no output is left either.
/// \throws Interrupted if `Transcode_options::callback` returns `false`.
inline Transcode_report transcode_with_flips(const std::string& input, const std::string& output, const Bit_set& flip,
                                             const Bit_set* keep = nullptr,
                                             const Transcode_options& options = Transcode_options())
{
  internal::Flip_transcoder transcoder(input, output, flip, keep, options);
  return transcoder.run();
}

/// @}

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_POINT_STREAM_TRANSCODE_H
