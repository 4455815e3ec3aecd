// SPDX-License-Identifier: GPL-3.0-or-later
/// \file fuzz_stream_reader.cpp
/// \brief libFuzzer target of the streaming reader `IO::Point_stream_reader` (PLY and
/// `.xyz`), and of `IO::Point_stream_writer`.
///
/// The input is written to a file (`input.ply` if it starts with `ply`, `input.xyz`
/// otherwise) in a private directory (in `TMPDIR`, else `/dev/shm`), then streamed
/// twice: with a buffer larger than the input (64 KiB), in chunks of 4096 records, then
/// again from `rewind()`; and with a buffer of 16 to 79 bytes (this target is built with
/// a minimum buffer size of 1 byte) in chunks of 1 to 5 records, so that the refills of
/// the buffer fall everywhere in the data. Each reading is compared with the in-core reader
/// (`IO::read_point_cloud()`) of the same file, as the streaming reader documents:
/// - the same records, bit for bit (zero normals when the file has none), numbered
///   0, 1, ..., or
/// - the same error message; the exceptions are the errors of the streaming reader
///   only (bytes after the binary PLY data; a line longer than the small buffer) and,
///   for binary PLY files, an error about the size of the data found by the streaming
///   reader before the error the in-core reader finds.
/// After an error, `read()` must throw the same error again. Records read are written
/// by a `Point_stream_writer` (`.xyz`, binary or ASCII PLY, by turns) and must read
/// back unchanged.

#include "Fuzz_common.h"

#include <Normal_orientation/IO/Point_cloud_io.h>
#include <Normal_orientation/IO/Point_stream.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#ifndef NORMAL_ORIENTATION_MINIMUM_STREAM_BUFFER_SIZE
#error "build this target with -DNORMAL_ORIENTATION_MINIMUM_STREAM_BUFFER_SIZE=1 (see fuzz/CMakeLists.txt)"
#endif

namespace {

namespace IO = fuzz::IO;
using Normal_orientation::Point_record;

/// \brief Result of streaming a file.
struct Streamed
{
  std::vector<Point_record> records;
  std::string error;           // empty: no error
  bool has_normals = false;    // as the reader says
  std::uint64_t expected = 0;  // expected_count()
};

/// \brief Reads all of `reader` in chunks of `chunk_size` into `records`.
void read_all(IO::Point_stream_reader& reader, std::size_t chunk_size, std::vector<Point_record>& records)
{
  std::vector<Point_record> chunk;
  for(;;) {
    chunk.clear();
    const std::size_t got = reader.read(chunk, chunk_size);
    FUZZ_CHECK(got == chunk.size() && got <= chunk_size, "read() returned " + std::to_string(got) + " for " +
                                                           std::to_string(chunk.size()) + " records");
    if(got == 0) break;
    records.insert(records.end(), chunk.begin(), chunk.end());
  }
  FUZZ_CHECK(reader.read(chunk, chunk_size) == 0 && chunk.empty(), "read() after the end returned records");
  FUZZ_CHECK(reader.records_read() == records.size(), "records_read() is not the number of records read");
}

/// \brief Checks that `a` and `b` are the same records, bit for bit.
void check_same_records(const std::vector<Point_record>& a, const std::vector<Point_record>& b,
                        const std::string& what)
{
  FUZZ_CHECK(a.size() == b.size(), what + ": " + std::to_string(a.size()) + " against " + std::to_string(b.size()) +
                                     " records");
  for(std::size_t i = 0; i < a.size(); ++i)
    FUZZ_CHECK(std::memcmp(&a[i], &b[i], sizeof(Point_record)) == 0, what + ": record " + std::to_string(i) + " differs");
}

/// \brief Streams `filename` with a buffer of `buffer_size` bytes, in chunks of
/// `chunk_size` records; if it reads without error and `rewind`, reads it again from
/// `rewind()` and checks that the records are the same.
Streamed stream(const std::string& filename, std::size_t buffer_size, std::size_t chunk_size, bool rewind)
{
  Streamed result;
  std::unique_ptr<IO::Point_stream_reader> reader;
  try {
    reader.reset(new IO::Point_stream_reader(filename, buffer_size));
    result.has_normals = reader->has_normals();
    result.expected = reader->expected_count();
    read_all(*reader, chunk_size, result.records);
  } catch(const IO::Io_error& error) {
    result.error = error.what();
    FUZZ_CHECK(!result.error.empty(), "empty error message");
    if(reader) { // the same error again, until rewind()
      std::vector<Point_record> chunk;
      std::string again;
      try {
        reader->read(chunk, chunk_size);
      } catch(const IO::Io_error& error) {
        again = error.what();
      }
      FUZZ_CHECK(again == result.error, "read() after '" + result.error + "' gave '" + again + "'");
    }
    return result;
  }
  if(rewind) {
    reader->rewind();
    std::vector<Point_record> again;
    const std::string error = fuzz::io_error_of([&] { read_all(*reader, 1000, again); });
    FUZZ_CHECK(error.empty(), "error after rewind(): " + error);
    check_same_records(result.records, again, "read after rewind()");
  }
  return result;
}

/// \brief Writes `records` with a `Point_stream_writer` to `filename` and checks that
/// they read back unchanged (with zero normals when they are not written).
void check_writer(const std::vector<Point_record>& records, bool normals, const std::string& filename, bool binary)
{
  IO::Point_stream_write_options options;
  options.binary = binary;
  options.normals = normals;
  const std::string write_error = fuzz::io_error_of([&] {
    IO::Point_stream_writer writer(filename, options);
    writer.write(records);
    FUZZ_CHECK(writer.count() == records.size(), "count() is not the number of records written");
    writer.commit();
  });
  FUZZ_CHECK(write_error.empty(), "records read cannot be written: " + write_error);
  Streamed back = stream(filename, std::size_t(1) << 16, 4096, false);
  FUZZ_CHECK(back.error.empty(), "a file written cannot be read: " + back.error);
  std::vector<Point_record> expected = records;
  if(!normals)
    for(Point_record& record : expected) record.normal[0] = record.normal[1] = record.normal[2] = 0.0;
  check_same_records(expected, back.records, "written by Point_stream_writer (" + filename + ")");
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const bool ply = size >= 3 && std::memcmp(data, "ply", 3) == 0;
  const std::string& directory = fuzz::directory();
  const std::string filename = directory + (ply ? "/input.ply" : "/input.xyz");
  fuzz::write_file(filename, data, size);
  const char* const begin = reinterpret_cast<const char*>(data);
  const std::size_t lines = fuzz::line_count(begin, size);

  // The in-core reader, on the same file.
  IO::Read_options one_thread;
  one_thread.number_of_threads = 1;
  IO::Point_cloud cloud;
  const std::string core_error = fuzz::io_error_of([&] { cloud = IO::read_point_cloud(filename, one_thread); });
  bool binary = false;
  bool declares_normals = false;
  if(ply) {
    try {
      const IO::internal::Ply_header header = IO::internal::parse_ply_header(filename, begin, begin + size);
      binary = header.format != IO::internal::Ply_format::ASCII;
      for(const IO::internal::Ply_header_property& property : header.elements[header.vertex_element].properties)
        declares_normals = declares_normals || property.name == "nx";
    } catch(const IO::Io_error&) {
    }
  }

  auto compare = [&](const Streamed& streamed, const std::string& what, bool small_buffer) {
    if(!streamed.error.empty()) fuzz::check_error_message(streamed.error, filename, size, lines);
    if(streamed.error.find(" is longer than the reading buffer (") != std::string::npos) {
      FUZZ_CHECK(small_buffer, what + ": " + streamed.error);
      return;
    }
    if(core_error.empty()) {
      if(!streamed.error.empty()) {
        FUZZ_CHECK(false, what + ": error '" + streamed.error + "' where read_point_cloud() reads the file");
        return;
      }
      FUZZ_CHECK(streamed.records.size() == cloud.size(), what + ": " + std::to_string(streamed.records.size()) +
                                                            " records for " + std::to_string(cloud.size()) + " points");
      FUZZ_CHECK(streamed.has_normals == (ply ? declares_normals : cloud.has_normals()),
                 what + ": has_normals() is wrong");
      FUZZ_CHECK(streamed.expected == (ply ? cloud.size() : 0), what + ": expected_count() is wrong");
      for(std::size_t i = 0; i < cloud.size(); ++i) {
        const Point_record& record = streamed.records[i];
        FUZZ_CHECK(record.index == i, what + ": record " + std::to_string(i) + " has index " +
                                        std::to_string(record.index));
        for(std::size_t c = 0; c < 3; ++c) {
          FUZZ_CHECK(fuzz::bits(record.position[c]) == fuzz::bits(cloud.points[i][c]),
                     what + ": coordinate of record " + std::to_string(i) + ": " + fuzz::text(record.position[c]) +
                       " instead of " + fuzz::text(cloud.points[i][c]));
          const double normal = cloud.has_normals() ? cloud.normals[i][c] : 0.0;
          FUZZ_CHECK(fuzz::bits(record.normal[c]) == fuzz::bits(normal),
                     what + ": normal of record " + std::to_string(i) + ": " + fuzz::text(record.normal[c]) +
                       " instead of " + fuzz::text(normal));
        }
      }
      return;
    }
    FUZZ_CHECK(!streamed.error.empty(), what + ": read without error where read_point_cloud() fails with '" +
                                          core_error + "'");
    if(streamed.error == core_error) return;
    const bool size_error = streamed.error.find(": truncated file: ") != std::string::npos ||
                            streamed.error.find(" bytes of unexpected data at byte offset ") != std::string::npos;
    FUZZ_CHECK(binary && size_error, what + ": error '" + streamed.error + "' where read_point_cloud() fails with '" +
                                       core_error + "'");
  };

  // 64 KiB: more than any input, as the default 1 MiB, at less cost for the sanitizers
  const Streamed large = stream(filename, std::size_t(1) << 16, 4096, true);
  compare(large, "default buffer", false);
  const Streamed small = stream(filename, 16 + size % 64, 1 + size % 5, false);
  compare(small, "buffer of " + std::to_string(16 + size % 64) + " bytes", true);

  if(large.error.empty()) {
    switch(size % 3) {
    case 0: check_writer(large.records, large.has_normals, directory + "/written.xyz", true); break;
    case 1: check_writer(large.records, large.has_normals, directory + "/written.ply", true); break;
    default: check_writer(large.records, large.has_normals, directory + "/written.ply", false); break;
    }
  }
  return 0;
}
