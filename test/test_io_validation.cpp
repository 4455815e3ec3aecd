// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file test_io_validation.cpp
/// \brief Tests of the validation of bad input by every reader, in memory and streaming,
/// with the same messages, and regressions found by the fuzz targets (suite
/// `Input_validation`).

#include "Io_test_support.h"

using namespace io_test;
// --------------------------------------------------------------------------- input validation

namespace {

/// \brief Checks that `message` is one line without control characters.
void expect_printable_line(const std::string& message)
{
  for(const char c : message) {
    const unsigned char byte = static_cast<unsigned char>(c);
    EXPECT_FALSE(byte < 0x20 || byte == 0x7F) << "control character " << int(byte) << " in: " << message;
  }
}

/// \brief Checks that reading `filename` in core and streaming it (with the default and
/// with the smallest buffer) fail with the message `<filename>: <expected>`, word for word.
void expect_same_error_everywhere(const std::string& filename, const std::string& expected)
{
  EXPECT_EQ(error_message([&] { read_point_cloud(filename); }), filename + ": " + expected);
  EXPECT_EQ(stream_error(filename), filename + ": " + expected);
  EXPECT_EQ(stream_error(filename, 0), filename + ": " + expected);
  expect_printable_line(expected);
}

/// \brief The header of a binary little-endian PLY file of `n` vertices `float x y z`.
std::string binary_xyz_header(const std::string& n, const std::string& more = std::string())
{
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + n +
         "\nproperty float x\nproperty float y\nproperty float z\n" + more + "end_header\n";
}

} // namespace

TEST(Input_validation, EmptyFiles)
{
  Temporary_directory directory;
  // An empty text file is a valid cloud of no point (the program refuses it later).
  write_file(directory.file("empty.xyz"), "");
  EXPECT_EQ(read_point_cloud(directory.file("empty.xyz")).size(), 0u);
  Point_stream_reader reader(directory.file("empty.xyz"));
  EXPECT_TRUE(read_stream(reader, 10).empty());
  EXPECT_FALSE(reader.has_normals());
  // An empty PLY file is not a PLY file.
  write_file(directory.file("empty.ply"), "");
  expect_same_error_everywhere(directory.file("empty.ply"), "not a PLY file: the file is empty");
  write_file(directory.file("magic_only.ply"), "ply\n");
  expect_same_error_everywhere(directory.file("magic_only.ply"), "bad PLY header: no 'end_header' line");
}

TEST(Input_validation, VertexCountLargerThanTheFile)
{
  Temporary_directory directory;
  // Counts far beyond the size of the file fail without allocating for them.
  Bytes one_vertex;
  one_vertex.data = binary_xyz_header("1000000000000");
  const std::size_t data_begin = one_vertex.data.size();
  one_vertex << 1.f << 2.f << 3.f << 4.f;
  write_file(directory.file("binary.ply"), one_vertex.data);
  expect_same_error_everywhere(directory.file("binary.ply"),
                               "truncated file: 1000000000000 vertices declared, data end at vertex 1 (byte offset " +
                                 std::to_string(data_begin + 12) + ", file size " +
                                 std::to_string(one_vertex.data.size()) + ")");
  Bytes largest;
  largest.data = binary_xyz_header("18446744073709551615");
  largest << 1.f << 2.f << 3.f;
  write_file(directory.file("largest.ply"), largest.data);
  expect_same_error_everywhere(directory.file("largest.ply"),
                               "truncated file: 18446744073709551615 vertices declared, data end at vertex 1 "
                               "(byte offset " + std::to_string(largest.data.size()) + ", file size " +
                                 std::to_string(largest.data.size()) + ")");
  write_file(directory.file("overflow.ply"), binary_xyz_header("18446744073709551616"));
  expect_same_error_everywhere(directory.file("overflow.ply"),
                               "bad PLY header at line 3: invalid element count '18446744073709551616'");
  write_file(directory.file("ascii.ply"), "ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\n"
                                          "property float y\nproperty float z\nend_header\n1 2 3\n\n4 5 6\n");
  expect_same_error_everywhere(directory.file("ascii.ply"),
                               "truncated file: 1000000000000 vertices declared, data end at vertex 2");
  // A fixed-size element after the vertices.
  Bytes faces;
  faces.data = binary_xyz_header("1", "element face 1000000\nproperty int a\nproperty int b\n");
  faces << 1.f << 2.f << 3.f << std::int32_t(1) << std::int32_t(2) << std::int32_t(3);
  write_file(directory.file("faces.ply"), faces.data);
  const std::size_t faces_begin = faces.data.size() - 12;
  EXPECT_EQ(error_message([&] { read_point_cloud(directory.file("faces.ply")); }),
            directory.file("faces.ply") + ": truncated file: element 'face' declares 1000000 rows, data end at row 1 "
                                          "(byte offset " + std::to_string(faces_begin + 8) + ", file size " +
              std::to_string(faces.data.size()) + ")");
  EXPECT_EQ(stream_error(directory.file("faces.ply")), error_message([&] { read_point_cloud(directory.file("faces.ply")); }));
}

TEST(Input_validation, BinaryErrorsNameTheByteOffset)
{
  Temporary_directory directory;
  const std::string header = binary_xyz_header("3", "property float nx\nproperty float ny\nproperty float nz\n");
  const std::size_t h = header.size();
  Bytes two;
  two.data = header;
  two << 1.f << 2.f << 3.f << 0.f << 0.f << 1.f << 4.f << 5.f << 6.f << 0.f << 1.f << 0.f;
  // Two vertices and a half.
  Bytes truncated{two.data, false};
  truncated << 7.f << 8.f << 9.f;
  write_file(directory.file("truncated.ply"), truncated.data);
  expect_same_error_everywhere(directory.file("truncated.ply"),
                               "truncated file: 3 vertices declared, data end at vertex 2 (byte offset " +
                                 std::to_string(h + 48) + ", file size " + std::to_string(h + 60) + ")");
  // A NaN normal at vertex 2, an infinite coordinate at vertex 1.
  Bytes nan_normal{two.data, false};
  nan_normal << 7.f << 8.f << 9.f << 0.f << std::numeric_limits<float>::quiet_NaN() << 0.f;
  write_file(directory.file("nan.ply"), nan_normal.data);
  expect_same_error_everywhere(directory.file("nan.ply"),
                               "non-finite normal at vertex 2 (byte offset " + std::to_string(h + 48) + ")");
  Bytes infinite;
  infinite.data = header;
  infinite << 1.f << 2.f << 3.f << 0.f << 0.f << 1.f << 4.f << -std::numeric_limits<float>::infinity() << 6.f << 0.f
           << 1.f << 0.f << 7.f << 8.f << 9.f << 0.f << 0.f << 1.f;
  write_file(directory.file("inf.ply"), infinite.data);
  expect_same_error_everywhere(directory.file("inf.ply"),
                               "non-finite coordinate at vertex 1 (byte offset " + std::to_string(h + 24) + ")");
  // Lists: a truncated row and a negative length, in an element before the vertices.
  const std::string lists = "ply\nformat binary_big_endian 1.0\nelement face 2\nproperty list char int corners\n"
                            "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  Bytes short_list;
  short_list.big_endian = true;
  short_list.data = lists;
  short_list << std::int8_t(2) << std::int32_t(0) << std::int32_t(1) << std::int8_t(3) << std::int32_t(0);
  write_file(directory.file("short_list.ply"), short_list.data);
  expect_same_error_everywhere(directory.file("short_list.ply"),
                               "truncated file: element 'face' declares 2 rows, data end at row 1 (byte offset " +
                                 std::to_string(lists.size() + 9) + ", file size " +
                                 std::to_string(short_list.data.size()) + ")");
  Bytes negative;
  negative.big_endian = true;
  negative.data = lists;
  negative << std::int8_t(1) << std::int32_t(0) << std::int8_t(-1) << 1.f << 2.f << 3.f;
  write_file(directory.file("negative.ply"), negative.data);
  expect_same_error_everywhere(directory.file("negative.ply"), "negative list length in element 'face' at row 1 "
                                                               "(byte offset " + std::to_string(lists.size() + 5) + ")");
}

TEST(Input_validation, GarbageAfterTheHeader)
{
  Temporary_directory directory;
  const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                            "property float z\nend_header\n";
  // Binary data under an ASCII header.
  Bytes binary;
  binary.data = ascii;
  binary << 1.f << 2.f << 3.f << 4.f << 5.f << 6.f;
  write_file(directory.file("binary_data.ply"), binary.data);
  const std::string message = error_message([&] { read_point_cloud(directory.file("binary_data.ply")); });
  EXPECT_NE(message.find(": non-numeric token '\\x00\\x00\\x80?\\x00\\x00\\x00@"), std::string::npos) << message;
  EXPECT_NE(message.find("' at line 8"), std::string::npos) << message;
  EXPECT_EQ(stream_error(directory.file("binary_data.ply")), message);
  expect_printable_line(message);
  // Text on the 'end_header' line, text in place of numbers.
  write_file(directory.file("end_header.ply"), "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                                               "property float y\nproperty float z\nend_header garbage\n");
  expect_same_error_everywhere(directory.file("end_header.ply"),
                               "bad PLY header at line 7: unexpected text after 'end_header'");
  write_file(directory.file("text.ply"), ascii + "1 2 3\nGarbage!\n");
  expect_same_error_everywhere(directory.file("text.ply"), "non-numeric token 'Garbage!' at line 9");
  write_file(directory.file("too_many.ply"), ascii + "1 2 3 4\n5 6 7\n");
  expect_same_error_everywhere(directory.file("too_many.ply"), "too many values: expected 3 at line 8");
  // Bytes after the binary data: read in core (a documented difference), refused when
  // streamed (Point_stream, reading_errors_name_the_file_and_the_place).
}

TEST(Input_validation, ControlCharactersInMessagesAreEscaped)
{
  Temporary_directory directory;
  write_file(directory.file("token.xyz"), "1 2 3\n1 2 \x01\x1b[2J\n");
  expect_same_error_everywhere(directory.file("token.xyz"), "non-numeric token '\\x01\\x1b[2J' at line 2");
  write_file(directory.file("keyword.ply"), std::string("ply\nformat ascii 1.0\nele\x07ment vertex 0\nend_header\n"));
  expect_same_error_everywhere(directory.file("keyword.ply"), "bad PLY header at line 3: unknown keyword 'ele\\x07ment'");
  write_file(directory.file("element.ply"), std::string("ply\nformat ascii 1.0\nelement ver\x7ftex 0\nend_header\n"));
  expect_same_error_everywhere(directory.file("element.ply"),
                               "bad PLY header at line 3: control character in the name 'ver\\x7ftex'");
  write_file(directory.file("property.ply"),
             std::string("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                         "property float z\nproperty uchar re") +
               '\0' + "d\nend_header\n");
  expect_same_error_everywhere(directory.file("property.ply"),
                               "bad PLY header at line 7: control character in the name 're\\x00d'");
  write_file(directory.file("value.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                          "property float z\nproperty uchar red\nend_header\n1 2 3 \x02\x03\n");
  expect_same_error_everywhere(directory.file("value.ply"), "non-numeric token '\\x02\\x03' at line 9");
  // A long token is shortened.
  write_file(directory.file("long.xyz"), "1 2 " + std::string(100, 'x') + "\n");
  expect_same_error_everywhere(directory.file("long.xyz"),
                               "non-numeric token '" + std::string(40, 'x') + "...' at line 1");
}

TEST(Input_validation, AsciiPlyFloatValuesAreTheNearestFloats)
{
  Temporary_directory directory;
  const float largest = std::numeric_limits<float>::max();
  // The shortest text of the largest float (3.4028235e+38) is above FLT_MAX as a
  // double, and was refused as out of range: a written file could not be read back.
  write_file(directory.file("floats.ply"), "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                           "property float y\nproperty float z\nproperty float s\nend_header\n"
                                           "3.4028235e+38 -3.4028235e38 1e-50 nan\n"
                                           "0.1 1.4e-45 -0 -inf\n");
  const Point_cloud cloud = read_point_cloud(directory.file("floats.ply"));
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[0][0], double(largest));
  EXPECT_EQ(cloud.points[0][1], -double(largest));
  EXPECT_EQ(bits(cloud.points[0][2]), bits(0.0)); // below the smallest subnormal: 0
  EXPECT_TRUE(std::isnan(cloud.extra_values[0]));
  EXPECT_EQ(cloud.points[1][0], double(0.1f));
  EXPECT_EQ(cloud.points[1][1], double(std::numeric_limits<float>::denorm_min()));
  EXPECT_EQ(bits(cloud.points[1][2]), bits(-0.0));
  EXPECT_EQ(cloud.extra_values[1], -std::numeric_limits<double>::infinity());
  expect_read_error(directory, "too_large.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                    "end_header\n1 2 3.5e38\n",
                    "value '3.5e38' out of range for property 'z' of type float at line 8");
  // A cloud holding the largest float is written as ASCII and reads back.
  Point_cloud extreme;
  extreme.points = {{{double(largest), -double(largest), double(std::numeric_limits<float>::denorm_min())}}};
  extreme.point_types = {{Ply_scalar_type::FLOAT32, Ply_scalar_type::FLOAT32, Ply_scalar_type::FLOAT32}};
  Write_options ascii;
  ascii.binary = false;
  write_point_cloud(directory.file("extreme.ply"), extreme, ascii);
  const Point_cloud back = read_point_cloud(directory.file("extreme.ply"));
  ASSERT_EQ(back.size(), 1u);
  for(std::size_t c = 0; c < 3; ++c) EXPECT_EQ(bits(back.points[0][c]), bits(extreme.points[0][c])) << c;
  Point_stream_reader reader(directory.file("extreme.ply"));
  expect_records_of_cloud(read_stream(reader, 4), back, "extreme.ply");
}

TEST(Input_validation, AsciiPlyIntegerMinusZeroIsZero)
{
  Temporary_directory directory;
  // `-0.0` for an integer property was kept as -0.0, which no binary integer holds: the
  // value changed in a PLY round trip.
  write_file(directory.file("zero.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty short x\n"
                                         "property float y\nproperty float z\nproperty uchar red\nend_header\n"
                                         "-0.0 -0.0 1 -0.0\n");
  const Point_cloud cloud = read_point_cloud(directory.file("zero.ply"));
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_EQ(bits(cloud.points[0][0]), bits(0.0));  // short
  EXPECT_EQ(bits(cloud.points[0][1]), bits(-0.0)); // float: -0 exists
  EXPECT_EQ(bits(cloud.extra_values[0]), bits(0.0));
  for(bool binary : {true, false}) {
    Write_options options;
    options.binary = binary;
    write_point_cloud(directory.file("again.ply"), cloud, options);
    expect_identical_clouds(cloud, read_point_cloud(directory.file("again.ply")));
  }
}

TEST(Input_validation, IntegerNormalsAreWrittenExactly)
{
  Temporary_directory directory;
  // 32-bit integer normals were written as float, which rounded large values.
  Bytes bytes;
  bytes.data = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
               "property float z\nproperty int nx\nproperty short ny\nproperty uint nz\nend_header\n";
  bytes << 1.f << 2.f << 3.f << std::int32_t(1050995571) << std::int16_t(-32768) << std::uint32_t(4294967295u);
  write_file(directory.file("int_normals.ply"), bytes.data);
  const Point_cloud cloud = read_point_cloud(directory.file("int_normals.ply"));
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_EQ(cloud.normals[0][0], 1050995571.0);
  for(bool binary : {true, false}) {
    Write_options options;
    options.binary = binary;
    write_point_cloud(directory.file("again.ply"), cloud, options);
    const Point_cloud back = read_point_cloud(directory.file("again.ply"));
    expect_identical_clouds(cloud, back);
    EXPECT_EQ(back.normal_types[0], Ply_scalar_type::FLOAT64); // int
    EXPECT_EQ(back.normal_types[1], Ply_scalar_type::FLOAT32); // short
    EXPECT_EQ(back.normal_types[2], Ply_scalar_type::FLOAT64); // uint
  }
}

TEST(Input_validation, UnreadableInputAndUnwritableOutput)
{
  Temporary_directory directory;
  // A path through a regular file can be neither read nor written, even by root.
  write_file(directory.file("file"), "1 2 3\n");
  for(const char* name : {"file/cloud.xyz", "file/cloud.ply"}) {
    const std::string filename = directory.file(name);
    expect_io_error([&] { read_point_cloud(filename); }, filename, "cannot open file for reading: Not a directory");
    EXPECT_EQ(stream_error(filename), error_message([&] { read_point_cloud(filename); }));
    expect_io_error([&] { write_point_cloud(filename, sample_cloud(true)); }, filename,
                    "cannot create temporary file");
    expect_io_error([&] { Point_stream_writer writer(filename); }, filename, "cannot create temporary file");
  }
  // Permissions (root reads and writes anyway).
  if(::geteuid() != 0) {
    const std::string locked = directory.file("locked.xyz");
    write_file(locked, "1 2 3\n");
    fs::permissions(locked, fs::perms::none);
    expect_io_error([&] { read_point_cloud(locked); }, locked, "cannot open file for reading: Permission denied");
    EXPECT_EQ(stream_error(locked), error_message([&] { read_point_cloud(locked); }));
    fs::permissions(locked, fs::perms::owner_all);
    fs::create_directory(directory.file("read_only"));
    fs::permissions(directory.file("read_only"), fs::perms::owner_read | fs::perms::owner_exec);
    const std::string target = directory.file("read_only/out.ply");
    expect_io_error([&] { write_point_cloud(target, sample_cloud(true)); }, target, "Permission denied");
    fs::permissions(directory.file("read_only"), fs::perms::owner_all);
    EXPECT_TRUE(fs::is_empty(directory.file("read_only")));
  }
  EXPECT_FALSE(directory.has_temporary_file());
}

// --------------------------------------------------------------------------- fuzzing regressions

// Each input that made a fuzz target (fuzz/) fail is kept in test/data/regressions/
// (see the README there) and read here, in core and streamed: a clean error (one
// printable line naming the file), or a cloud that satisfies the reader's contract and
// comes back unchanged from the files the writers write.
TEST(Input_validation, FuzzerRegressions)
{
  struct Case
  {
    std::string name;
    std::string expected; // a part of the error message, or empty: read without error
    std::size_t points;   // without error
  };
  const std::vector<Case> cases = {
    // error messages quoted the input's control characters as they were
    {"ply_control_character_in_token.ply",
     "non-numeric token '-0.0999999999999\\x06\\x00\\x00\\x00\\x00\\x00...' at line 11", 0},
    {"xyz_control_character_in_token.xyz", "non-numeric token '1e999\\x0f-\\x01\\x00@`\\x00\\x00' at line 1", 0},
    {"xyz_control_character_in_token_2.xyz", "non-numeric token '\\xe0\\x8b\\x02\\x00\\xd0`\\x00\\x00yz' at line 1",
     0},
    // the largest float, read from a binary file, was written as ASCII text that the
    // reader refused (3.4028235e+38 > FLT_MAX as a double)
    {"ply_binary_float_max_ascii_round_trip.ply", "", 1},
    // -0.0 for an integer property stayed -0.0 and became 0 in a round trip
    {"ply_ascii_integer_negative_zero.ply", "", 1},
    // 32-bit integer normals were written as float, rounding large values
    {"ply_int32_normals_round_trip.ply", "", 5},
  };
#ifdef NORMAL_ORIENTATION_TEST_DATA_DIR
  const fs::path regressions = fs::path(NORMAL_ORIENTATION_TEST_DATA_DIR) / "regressions";
#else
  const fs::path regressions = fs::path(__FILE__).parent_path() / "data" / "regressions"; // test/data/regressions
#endif
  ASSERT_TRUE(fs::is_directory(regressions)) << regressions;
  std::vector<std::string> listed;
  for(const Case& c : cases) listed.push_back(c.name);
  std::sort(listed.begin(), listed.end());
  std::vector<std::string> present;
  for(const auto& entry : fs::directory_iterator(regressions)) {
    const std::string name = entry.path().filename().string();
    if(name != "README.md" && entry.path().extension() != ".license") present.push_back(name);
  }
  std::sort(present.begin(), present.end());
  EXPECT_EQ(present, listed) << "every file of " << regressions << " has a case here, and vice versa";

  Temporary_directory directory;
  for(const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string filename = (regressions / c.name).string();
    Point_cloud cloud;
    const std::string message = error_message([&] { cloud = read_point_cloud(filename); });
    // Streamed: the same error, or the same points.
    for(std::size_t buffer_size : {Point_stream_reader::default_buffer_size, std::size_t(0)})
      EXPECT_EQ(stream_error(filename, buffer_size), message);
    if(!c.expected.empty()) {
      EXPECT_EQ(message.rfind(filename + ": ", 0), 0u) << message;
      EXPECT_NE(message.find(c.expected), std::string::npos) << message;
      expect_printable_line(message.substr(filename.size()));
      continue;
    }
    ASSERT_EQ(message, "no error");
    ASSERT_EQ(cloud.size(), c.points);
    Point_stream_reader reader(filename);
    expect_records_of_cloud(read_stream(reader, 3), cloud, c.name);
    for(std::size_t i = 0; i < cloud.size(); ++i)
      for(std::size_t k = 0; k < cloud.extra_properties.size(); ++k)
        if(cloud.extra_properties[k].type != Ply_scalar_type::FLOAT32 &&
           cloud.extra_properties[k].type != Ply_scalar_type::FLOAT64) {
          EXPECT_NE(bits(cloud.extra_values[i * cloud.extra_properties.size() + k]), bits(-0.0));
        }
    // Written and read back: the same values, bit for bit.
    for(const std::string written : {"back.ply", "back_ascii.ply", "back.xyz"}) {
      Write_options options;
      options.binary = written != "back_ascii.ply";
      options.precision = Write_options::PRECISION_SHORTEST;
      Point_cloud expected = cloud;
      if(written == "back.xyz") {
        expected.extra_properties.clear();
        expected.extra_values.clear();
      }
      write_point_cloud(directory.file(written), expected, options);
      expect_same_bits(expected, read_point_cloud(directory.file(written)), written);
    }
  }
}

