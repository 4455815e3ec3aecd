// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Point_stream_writer.h
/// \brief `Point_stream_writer`: sequential (streaming) writing of `Point_record`s to a
/// `.xyz`, `.pwn` or `.ply` file as they come, with a fixed amount of memory; the file
/// appears, atomically, only when `commit()` is called. The output of the out-of-core
/// orientation.

#ifndef NORMAL_ORIENTATION_IO_POINT_STREAM_WRITER_H
#define NORMAL_ORIENTATION_IO_POINT_STREAM_WRITER_H

#include <Normal_orientation/IO/Atomic_output_file.h>
#include <Normal_orientation/IO/File_format.h>
#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Ply_data.h>
#include <Normal_orientation/IO/Ply_types.h>
#include <Normal_orientation/IO/Point_cloud.h>
#include <Normal_orientation/Point_record.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

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
/// buffer of 1 MiB.
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
    ply_ = internal::file_format(filename) == internal::File_format::PLY;
    if(!ply_ && options_.segments) internal::fail(filename, "segments can only be written to a .ply file");
    out_.reset(new internal::Atomic_output_file(filename));
    if(!ply_) return;
    std::string header = internal::ply_header_start(options_.binary);
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
    if(ply_ && options_.binary) { // one room for the whole row: this is the hot path of large outputs
      const std::size_t size = values * sizeof(double) + (options_.segments ? 4 : 0);
      char* const target = out_->room(size);
      const bool swap = !host_is_little_endian();
      for(std::size_t c = 0; c < values; ++c)
        store_scalar(target + c * sizeof(double), c < 3 ? record.position[c] : record.normal[c - 3],
                     Ply_scalar_type::FLOAT64, swap);
      if(options_.segments)
        store_scalar(target + values * sizeof(double), static_cast<double>(segment), Ply_scalar_type::INT32, swap);
      out_->advance(size);
    } else { // text: PLY ASCII and .xyz/.pwn write the same
      for(std::size_t c = 0; c < values; ++c) {
        if(c != 0) out_->put(' ');
        put_ply_value(*out_, c < 3 ? record.position[c] : record.normal[c - 3], Ply_scalar_type::FLOAT64, false);
      }
      if(options_.segments) {
        out_->put(' ');
        put_ply_value(*out_, static_cast<double>(segment), Ply_scalar_type::INT32, false);
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

#endif // NORMAL_ORIENTATION_IO_POINT_STREAM_WRITER_H
