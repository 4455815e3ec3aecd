// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file test_io_stream.cpp
/// \brief Tests of Normal_orientation/IO/Point_stream.h: streaming reading and writing,
/// chunk by chunk (suite `Point_stream`).

#include "Io_test_support.h"

using namespace io_test;

TEST(Point_stream, ReadsWhatReadPointCloudReads)
{
  Temporary_directory directory;
  std::vector<std::string> files;
  // Text with normals, comments, blank lines, CRLF line ends and tabs.
  files.push_back(directory.file("normals.xyz"));
  write_file(files.back(), large_xyz_text(3000));
  // Text without normals, without a final end of line.
  std::string plain = "# x y z\n\n";
  for(int i = 0; i < 2500; ++i)
    plain += shortest_text(std::sin(i * 0.1)) + " " + shortest_text(i * 1e-7) + "  " + shortest_text(-i / 3.0) +
             (i + 1 < 2500 ? "\n" : "");
  files.push_back(directory.file("plain.pwn"));
  write_file(files.back(), plain);
  // PLY files in every encoding.
  for(const std::string format : {"ascii", "binary_little_endian", "binary_big_endian"})
    for(bool double_points : {false, true}) {
      const bool normals = !(format == "ascii" && !double_points);
      files.push_back(directory.file(format + (double_points ? "_double" : "_float") + ".ply"));
      const bool face_before = format == "binary_big_endian" || (format == "ascii" && double_points);
      write_file(files.back(), streaming_ply(format, double_points, normals, 2000, face_before));
    }

  for(const std::string& file : files) {
    const Point_cloud cloud = read_point_cloud(file);
    ASSERT_GE(cloud.size(), 2000u) << file;
    const bool ply = file.size() > 4 && file.substr(file.size() - 4) == ".ply";
    for(std::size_t buffer_size : {Point_stream_reader::default_buffer_size, std::size_t(0)}) {
      Point_stream_reader reader(file, buffer_size);
      EXPECT_EQ(reader.filename(), file);
      EXPECT_EQ(reader.has_normals(), cloud.has_normals()) << file;
      EXPECT_EQ(reader.expected_count(), ply ? cloud.size() : 0u) << file;
      EXPECT_EQ(reader.buffer_capacity(), buffer_size == 0 ? Point_stream_reader::minimum_buffer_size
                                                           : Point_stream_reader::default_buffer_size);
      const std::string what = file + " with a buffer of " + std::to_string(reader.buffer_capacity());
      for(std::size_t chunk_size : {std::size_t(1), std::size_t(7), std::size_t(1000)}) {
        expect_records_of_cloud(read_stream(reader, chunk_size), cloud, what + ", chunks of " + std::to_string(chunk_size));
        reader.rewind();
      }
      // read() appends; rewinding in the middle restarts from the first point.
      std::vector<Point_record> chunk(1);
      EXPECT_EQ(reader.read(chunk, 5), 5u);
      EXPECT_EQ(chunk.size(), 6u);
      EXPECT_EQ(chunk[1].index, 0u);
      EXPECT_EQ(reader.read(chunk, 0), 0u);
      reader.rewind();
      EXPECT_EQ(reader.records_read(), 0u);
      expect_records_of_cloud(read_stream(reader, 1000), cloud, what + ", after a rewind");
    }
  }
}

TEST(Point_stream, ReadingErrorsNameTheFileAndThePlace)
{
  Temporary_directory directory;
  struct Case
  {
    std::string name;
    std::string content;
    std::string expected;
  };
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 3\n" + xyz + "property uchar red\nend_header\n";
  Bytes binary;
  binary.data = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n" + xyz +
                "property float nx\nproperty float ny\nproperty float nz\nend_header\n";
  binary << 1.f << 2.f << 3.f << 0.f << 0.f << 1.f;
  binary << 4.f << 5.f << 6.f << 0.f << 0.f << 0.f;
  const std::string two_vertices = binary.data;
  Bytes nan_normal{two_vertices, false};
  nan_normal << 7.f << 8.f << 9.f << std::numeric_limits<float>::quiet_NaN() << 0.f << 0.f;
  Bytes inf_point{two_vertices, false};
  inf_point << 7.f << std::numeric_limits<float>::infinity() << 9.f << 0.f << 0.f << 1.f;
  Bytes face_first;
  face_first.data = "ply\nformat binary_big_endian 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
                    "element vertex 2\n" + xyz + "end_header\n";
  face_first.big_endian = true;
  face_first << std::uint8_t(3) << std::int32_t(0) << std::int32_t(1) << std::int32_t(1) << 1.f << 2.f << 3.f;
  Bytes face_last;
  face_last.data = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n" + xyz +
                   "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  face_last << 1.f << 2.f << 3.f << 4.f << 5.f << 6.f << std::uint8_t(3) << std::int32_t(0) << std::int32_t(1)
            << std::int32_t(1);

  const std::vector<Case> cases = {
    // .xyz
    {"four.xyz", "1 2 3\n1 2 3 4\n", "wrong column count at line 2: 4 values"},
    {"seven.xyz", "1 2 3 4 5 6 7\n", "wrong column count at line 1: 7 values"},
    {"two.xyz", "# x y z\n1 2\n", "wrong column count at line 2: 2 values"},
    {"mixed.xyz", "1 2 3\n\n1 2 3 0 0 1\n", "wrong column count at line 3: 6 values, but line 1 has 3"},
    {"token.xyz", "1 2 3\n1 2 abc\n", "non-numeric token 'abc' at line 2"},
    {"sign.xyz", "1 2 ++3\n", "non-numeric token '++3' at line 1"},
    {"nan.xyz", "1 2 3\n4 5 6\nnan 0 0\n", "non-finite coordinate at line 3"},
    {"normal.xyz", "1 2 3 0 0 1\n1 2 3 0 inf 1\n", "non-finite normal at line 2"},
    {"huge.xyz", "1 2 1e999\n", "out of range at line 1"},
    {"late.xyz", large_xyz_text(3000) + "1 2 3 4 5 x\n", "non-numeric token 'x' at line 3001"},
    // PLY header
    {"magic.ply", "plyx\nformat ascii 1.0\n", "not a PLY file"},
    {"keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 0\nend_header\n",
     "bad PLY header at line 3: unknown keyword 'elemnt'"},
    {"int64.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty int64 x\nend_header\n",
     "bad PLY header at line 4: unknown type 'int64'"},
    {"no_end.ply", "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz, "no 'end_header' line"},
    {"no_z.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
     "element 'vertex' has no property 'z'"},
    {"list.ply", "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz + "property list uchar int n\nend_header\n",
     "list property 'n' in element 'vertex' is not supported"},
    // ASCII PLY data
    {"truncated_ascii.ply", ascii + "1 2 3 4\n5 6 7 8\n", "truncated file: 3 vertices declared, data end at vertex 2"},
    {"short_line.ply", ascii + "1 2 3 4\n5 6 7\n8 9 1 2\n", "short line: 3 values instead of 4 at line 10"},
    {"long_line.ply", ascii + "1 2 3 4\n5 6 7 8 9\n8 9 1 2\n", "too many values: expected 4 at line 10"},
    {"token.ply", ascii + "1 2 3 4\n5 six 7 8\n8 9 1 2\n", "non-numeric token 'six' at line 10"},
    {"nan.ply", ascii + "1 2 3 4\n\n5 6 7 8\n8 NaN 1 2\n", "non-finite coordinate at line 12"},
    {"colour.ply", ascii + "1 2 3 4\n5 6 7 256\n8 9 1 2\n",
     "value '256' out of range for property 'red' of type uchar at line 10"},
    {"truncated_face.ply",
     "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz +
       "element face 2\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n3 0 0 0\n",
     "truncated file: element 'face' declares 2 rows, data end at row 1"},
    // binary PLY data
    {"truncated_binary.ply", two_vertices + std::string(12, '\0'),
     "truncated file: 3 vertices declared, data end at vertex 2"},
    {"truncated_after_face.ply", face_first.data, "truncated file: 2 vertices declared, data end at vertex 1"},
    {"truncated_face_list.ply", face_last.data, "truncated file: element 'face' declares 2 rows, data end at row 1"},
    {"nan_normal.ply", nan_normal.data, "non-finite normal at vertex 2"},
    {"inf_binary.ply", inf_point.data, "non-finite coordinate at vertex 2"},
    // files
    {"cloud.txt", "1 2 3\n", "unknown point cloud file extension '.txt'"},
  };
  for(const Case& c : cases) {
    const std::string filename = directory.file(c.name);
    write_file(filename, c.content);
    for(std::size_t buffer_size : {Point_stream_reader::default_buffer_size, std::size_t(0)}) {
      const std::string message = stream_error(filename, buffer_size);
      EXPECT_NE(message.find(filename), std::string::npos) << message;
      EXPECT_NE(message.find(c.expected), std::string::npos) << message;
      // The same error as read_point_cloud(), word for word.
      EXPECT_EQ(message, error_message([&] { read_point_cloud(filename); }));
    }
  }
  const std::string missing = directory.file("missing.ply");
  EXPECT_NE(stream_error(missing).find(missing + ": cannot open file for reading"), std::string::npos);
  EXPECT_EQ(stream_error(missing), error_message([&] { read_point_cloud(missing); }));
  fs::create_directory(directory.file("dir.xyz"));
  EXPECT_EQ(stream_error(directory.file("dir.xyz")), error_message([&] { read_point_cloud(directory.file("dir.xyz")); }));

  // Bytes after the binary data: an error of both readers (with the byte offset), found
  // by the streaming reader's constructor or, after a list element, at the end of the data.
  Bytes three{two_vertices, false};
  three << 7.f << 8.f << 9.f << 0.f << 0.f << 1.f;
  write_file(directory.file("garbage.ply"), three.data + "abc");
  EXPECT_EQ(error_message([&] { read_point_cloud(directory.file("garbage.ply")); }),
            stream_error(directory.file("garbage.ply")));
  EXPECT_EQ(stream_error(directory.file("garbage.ply")),
            directory.file("garbage.ply") + ": 3 bytes of unexpected data at byte offset " +
              std::to_string(three.data.size()) + ", after the last vertex of the PLY data");
  Bytes face_garbage{face_last.data, false};
  face_garbage << std::uint8_t(0) << std::uint8_t(7);
  write_file(directory.file("face_garbage.ply"), face_garbage.data);
  EXPECT_EQ(error_message([&] { read_point_cloud(directory.file("face_garbage.ply")); }),
            stream_error(directory.file("face_garbage.ply")));
  EXPECT_EQ(stream_error(directory.file("face_garbage.ply")),
            directory.file("face_garbage.ply") + ": 1 bytes of unexpected data at byte offset " +
              std::to_string(face_garbage.data.size() - 1) + ", after the last row of element 'face' of the PLY data");

  // A line must fit in the buffer, except a comment line.
  const std::string long_comment = directory.file("long_comment.xyz");
  write_file(long_comment, "# " + std::string(10000, 'c') + "\n1 2 3\n\n1 2 x\n");
  EXPECT_EQ(stream_error(long_comment, 0), long_comment + ": non-numeric token 'x' at line 4");
  const std::string long_line = directory.file("long_line.xyz");
  write_file(long_line, "1 2 3\n1 2 3" + std::string(10000, ' ') + "\n");
  EXPECT_EQ(stream_error(long_line, 0), long_line + ": line 2 is longer than the reading buffer (4096 bytes)");
  EXPECT_EQ(stream_error(long_line), "no error");

  // An error is thrown again until rewind().
  Point_stream_reader reader(directory.file("nan.xyz"));
  std::vector<Point_record> chunk;
  const std::string expected = directory.file("nan.xyz") + ": non-finite coordinate at line 3";
  EXPECT_EQ(error_message([&] { reader.read(chunk, 10); }), expected);
  EXPECT_EQ(error_message([&] { reader.read(chunk, 10); }), expected);
  reader.rewind();
  chunk.clear();
  EXPECT_EQ(reader.read(chunk, 2), 2u);
  EXPECT_EQ(chunk[1].position[0], 4.0);
}

TEST(Point_stream, WriterRoundTrip)
{
  Temporary_directory directory;
  const std::vector<Point_record> records = awkward_records();
  std::vector<std::string> names;
  for(bool normals : {true, false})
    for(const std::string name : {"text.xyz", "text.pwn", "binary.ply", "ascii.ply"}) {
      const std::string filename = directory.file((normals ? "n_" : "p_") + name);
      names.push_back((normals ? "n_" : "p_") + name);
      Point_stream_write_options options;
      options.binary = name != "ascii.ply";
      options.normals = normals;
      {
        Point_stream_writer writer(filename, options);
        EXPECT_EQ(writer.filename(), filename);
        EXPECT_EQ(writer.has_normals(), normals);
        writer.write(records[0]);
        writer.write(std::vector<Point_record>(records.begin() + 1, records.end()));
        EXPECT_EQ(writer.count(), records.size());
        EXPECT_TRUE(directory.has_temporary_file());
        writer.commit();
        EXPECT_EQ(error_message([&] { writer.write(records[0]); }),
                  filename + ": cannot write: the file was already committed");
      }
      const Point_cloud cloud = read_point_cloud(filename);
      ASSERT_EQ(cloud.size(), records.size()) << filename;
      EXPECT_EQ(cloud.has_normals(), normals);
      std::size_t differences = 0;
      for(std::size_t i = 0; i < records.size(); ++i)
        for(std::size_t c = 0; c < 3; ++c) {
          differences += bits(cloud.points[i][c]) != bits(records[i].position[c]);
          if(normals) differences += bits(cloud.normals[i][c]) != bits(records[i].normal[c]);
        }
      EXPECT_EQ(differences, 0u) << filename;
      if(name == "binary.ply") {
        EXPECT_NE(file_content(filename).find("format binary_little_endian 1.0"), std::string::npos);
        EXPECT_EQ(cloud.point_types[0], Ply_scalar_type::FLOAT64);
        if(normals) {
          EXPECT_EQ(cloud.normal_types[0], Ply_scalar_type::FLOAT64);
        }
      }
      if(name == "ascii.ply") {
        EXPECT_NE(file_content(filename).find("format ascii 1.0"), std::string::npos);
      }
      // The streaming reader reads it back too, numbering the records 0, 1, ...
      Point_stream_reader reader(filename);
      expect_records_of_cloud(read_stream(reader, 5), cloud, filename);
    }
  // No records: a valid empty file.
  for(const std::string name : {"empty.ply", "empty.xyz"}) {
    Point_stream_writer writer(directory.file(name));
    writer.commit();
    EXPECT_EQ(read_point_cloud(directory.file(name)).size(), 0u);
    names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  EXPECT_EQ(directory.listing(), names);
}

TEST(Point_stream, UncommittedOrFailedWriterLeavesNoFile)
{
  Temporary_directory directory;
  const std::vector<Point_record> records = awkward_records();
  for(const std::string name : {"a.ply", "b.xyz"}) {
    Point_stream_writer writer(directory.file(name));
    writer.write(records);
    EXPECT_TRUE(directory.has_temporary_file());
  }
  EXPECT_TRUE(directory.listing().empty());

  // A non-finite value is refused, naming the vertex; an existing file is kept.
  write_file(directory.file("c.ply"), "previous content");
  {
    Point_stream_writer writer(directory.file("c.ply"));
    std::vector<Point_record> bad = records;
    bad[3].normal[1] = std::numeric_limits<double>::infinity();
    expect_io_error([&] { writer.write(bad); }, directory.file("c.ply"), "non-finite normal at vertex 3");
    EXPECT_EQ(writer.count(), 3u);
  }
  {
    Point_stream_write_options no_normals;
    no_normals.normals = false;
    Point_stream_writer writer(directory.file("c.ply"), no_normals);
    std::vector<Point_record> bad = records;
    bad[3].normal[1] = std::numeric_limits<double>::infinity(); // not written: fine
    bad[5].position[2] = std::numeric_limits<double>::quiet_NaN();
    expect_io_error([&] { writer.write(bad); }, directory.file("c.ply"), "non-finite coordinate at vertex 5");
  }
  EXPECT_EQ(file_content(directory.file("c.ply")), "previous content");
  EXPECT_EQ(directory.listing(), std::vector<std::string>{"c.ply"});

  expect_io_error([&] { Point_stream_writer writer(directory.file("d.off")); }, directory.file("d.off"),
                  "unknown point cloud file extension '.off'");
  expect_io_error([&] { Point_stream_writer writer(directory.file("no/dir/d.xyz")); },
                  directory.file("no/dir/d.xyz"), "cannot create temporary file");
  // A failed rename (the target is a directory) leaves no temporary file.
  fs::create_directory(directory.file("e.ply"));
  {
    Point_stream_writer writer(directory.file("e.ply"));
    writer.write(records);
    expect_io_error([&] { writer.commit(); }, directory.file("e.ply"), "cannot rename");
  }
  EXPECT_EQ(directory.listing(), (std::vector<std::string>{"c.ply", "e.ply"}));
}

TEST(Point_stream, ReaderMemoryDoesNotGrowWithTheFile)
{
  Temporary_directory directory;
  const std::size_t n = 200000;
  for(const std::string name : {"big.ply", "big.xyz"}) {
    const std::string filename = directory.file(name);
    {
      Point_stream_writer writer(filename);
      std::vector<Point_record> chunk;
      for(std::size_t i = 0; i < n; ++i) {
        const double d = static_cast<double>(i);
        chunk.push_back(Point_record{{d * 0.5, -d, d * 0.25}, {0.0, 1.0, -0.5}, i});
        if(chunk.size() == 4096 || i + 1 == n) {
          writer.write(chunk);
          chunk.clear();
        }
      }
      writer.commit();
    }
    const std::uintmax_t file_size = fs::file_size(filename);
    for(std::size_t buffer_size : {Point_stream_reader::default_buffer_size, std::size_t(0)}) {
      Point_stream_reader reader(filename, buffer_size);
      const std::size_t capacity = reader.buffer_capacity();
      EXPECT_LT(capacity * 4, file_size) << filename;
      std::vector<Point_record> chunk;
      std::size_t count = 0;
      std::size_t wrong = 0;
      while(reader.read(chunk, 4096) != 0) {
        for(const Point_record& record : chunk) {
          const double d = static_cast<double>(count);
          wrong += !(record.index == count && record.position[0] == d * 0.5 && record.position[1] == -d &&
                     record.position[2] == d * 0.25 && record.normal[2] == -0.5);
          ++count;
        }
        chunk.clear();
        EXPECT_EQ(reader.buffer_capacity(), capacity);
      }
      EXPECT_EQ(count, n) << filename;
      EXPECT_EQ(wrong, 0u) << filename;
    }
  }
}

