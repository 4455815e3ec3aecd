// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Io_test_support.h
/// \brief What the tests of Normal_orientation/IO share (test_io*.cpp): temporary
/// directories and files, binary PLY data, sample clouds, comparisons bit for bit,
/// error messages, and the streaming reader and writer driven chunk by chunk.

#ifndef NORMAL_ORIENTATION_TEST_IO_TEST_SUPPORT_H
#define NORMAL_ORIENTATION_TEST_IO_TEST_SUPPORT_H

#include <Normal_orientation/IO/Point_cloud_io.h>
#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/IO/Point_stream_transcode.h>

#include "Test_directory.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

namespace io_test {

namespace fs = std::filesystem;
using Normal_orientation::IO::Io_error;
using Normal_orientation::IO::Ply_property;
using Normal_orientation::IO::Ply_scalar_type;
using Normal_orientation::IO::Point_cloud;
using Normal_orientation::IO::Read_options;
using Normal_orientation::IO::Write_options;
using Normal_orientation::IO::read_point_cloud;
using Normal_orientation::IO::write_point_cloud;

/// \brief A fresh temporary directory for the running test (see Test_directory.h).
class Temporary_directory : public Normal_orientation::test::Test_directory
{
public:
  Temporary_directory() : Test_directory("normal_orientation_test_io_") {}
  /// Returns `true` if a temporary file (`*.tmp.*`) is in the directory.
  bool has_temporary_file() const
  {
    for(const std::string& name : listing())
      if(name.find(".tmp.") != std::string::npos) return true;
    return false;
  }
};

/// \brief Writes `content` to `filename` as is.
inline void write_file(const std::string& filename, const std::string& content)
{
  std::ofstream out(filename, std::ios::binary);
  out.write(content.data(), static_cast<std::streamsize>(content.size()));
  ASSERT_TRUE(out.good()) << filename;
}

/// \brief Content of `filename`.
inline std::string file_content(const std::string& filename)
{
  std::ifstream in(filename, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// \brief Builds binary PLY data.
struct Bytes
{
  std::string data;
  bool big_endian = false;

  template <class T>
  Bytes& operator<<(T value)
  {
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    const std::uint16_t one = 1;
    unsigned char first = 0;
    std::memcpy(&first, &one, 1);
    const bool host_little = first == 1;
    if(host_little == big_endian) std::reverse(raw, raw + sizeof(T));
    data.append(reinterpret_cast<const char*>(raw), sizeof(T));
    return *this;
  }
};

/// \brief Checks that `action` throws an Io_error whose message contains `filename`
/// and `expected`.
inline void expect_io_error(const std::function<void()>& action, const std::string& filename,
                            const std::string& expected)
{
  try {
    action();
    ADD_FAILURE() << "no Io_error thrown, expected '" << expected << "' for " << filename;
  } catch(const Io_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(filename), std::string::npos) << message;
    EXPECT_NE(message.find(expected), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  } catch(const std::exception& error) {
    ADD_FAILURE() << "unexpected exception: " << error.what();
  }
}

/// \brief Checks that reading `filename` with content `content` throws an Io_error
/// naming the file and containing `expected`.
inline void expect_read_error(const Temporary_directory& directory, const std::string& name,
                              const std::string& content, const std::string& expected)
{
  const std::string filename = directory.file(name);
  write_file(filename, content);
  expect_io_error([&] { read_point_cloud(filename); }, filename, expected);
}

/// \brief A small cloud with awkward values.
inline Point_cloud sample_cloud(bool with_normals)
{
  Point_cloud cloud;
  for(int i = 0; i < 50; ++i) {
    const double t = i * 0.731;
    cloud.points.push_back({{std::sin(t) * 1e3, std::cos(t) / 3.0, -t * 1e-7 + 0.1}});
    if(with_normals) cloud.normals.push_back({{std::sin(t), -std::cos(t), i == 7 ? 0.0 : 1.0 / (i + 1)}});
  }
  cloud.points.push_back({{0.0, -0.0, 1e-300}});
  if(with_normals) cloud.normals.push_back({{0.0, 0.0, 0.0}});
  return cloud;
}

/// \brief Adds uchar colours and other extra properties to `cloud`.
inline void add_extra_properties(Point_cloud& cloud)
{
  cloud.extra_properties = {{"red", Ply_scalar_type::UINT8},      {"green", Ply_scalar_type::UINT8},
                            {"blue", Ply_scalar_type::UINT8},     {"label", Ply_scalar_type::INT32},
                            {"quality", Ply_scalar_type::FLOAT32}, {"density", Ply_scalar_type::FLOAT64},
                            {"flag", Ply_scalar_type::INT8},      {"id", Ply_scalar_type::UINT32},
                            {"s", Ply_scalar_type::INT16},        {"u", Ply_scalar_type::UINT16}};
  for(std::size_t i = 0; i < cloud.size(); ++i) {
    const double d = static_cast<double>(i);
    const std::vector<double> row = {std::fmod(d * 37, 256), 255, 0, -d * 1000,
                                     static_cast<double>(static_cast<float>(d / 7)), d / 3 + 1e-12,
                                     -128 + std::fmod(d, 256), 4294967295.0 - d, -32768 + d, 65535 - d};
    cloud.extra_values.insert(cloud.extra_values.end(), row.begin(), row.end());
  }
}

inline void expect_same_points(const Point_cloud& a, const Point_cloud& b)
{
  ASSERT_EQ(a.points.size(), b.points.size());
  ASSERT_EQ(a.normals.size(), b.normals.size());
  for(std::size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i], b.points[i]) << "point " << i;
    if(a.has_normals()) {
      EXPECT_EQ(a.normals[i], b.normals[i]) << "normal " << i;
    }
  }
}

/// \brief Bit pattern of `value`.
inline std::uint64_t bits(double value)
{
  std::uint64_t result = 0;
  std::memcpy(&result, &value, sizeof(result));
  return result;
}

/// \brief Checks that `a` and `b` have the same points and normals, bit for bit (so
/// that `0.0` and `-0.0` differ), and the same recorded digits.
inline void expect_identical_clouds(const Point_cloud& a, const Point_cloud& b)
{
  ASSERT_EQ(a.points.size(), b.points.size());
  ASSERT_EQ(a.normals.size(), b.normals.size());
  EXPECT_EQ(a.point_digits, b.point_digits);
  EXPECT_EQ(a.normal_digits, b.normal_digits);
  std::size_t differences = 0;
  for(std::size_t i = 0; i < a.points.size(); ++i)
    for(std::size_t c = 0; c < 3; ++c) {
      if(bits(a.points[i][c]) != bits(b.points[i][c]) && ++differences < 10)
        ADD_FAILURE() << "point " << i << "[" << c << "]: " << a.points[i][c] << " vs " << b.points[i][c];
      if(a.has_normals() && bits(a.normals[i][c]) != bits(b.normals[i][c]) && ++differences < 10)
        ADD_FAILURE() << "normal " << i << "[" << c << "]: " << a.normals[i][c] << " vs " << b.normals[i][c];
    }
  EXPECT_EQ(differences, 0u);
}

/// \brief Text of a random decimal number with exactly `digits` significant digits as
/// written (the first one non-zero, the others possibly zeros), in a random form:
/// scientific, fixed with leading zeros, or integer, with a random sign; its decimal
/// exponent lies in `[-max_exponent, max_exponent]`.
inline std::string random_decimal(std::mt19937_64& random, int digits, int max_exponent = 30)
{
  std::string mantissa(1, static_cast<char>('1' + random() % 9));
  for(int i = 1; i < digits; ++i)
    mantissa += static_cast<char>('0' + (random() % 4 == 0 ? 0 : random() % 10)); // zeros are frequent
  std::string text = random() % 2 == 0 ? "-" : "";
  const int exponent = static_cast<int>(random() % (2 * max_exponent + 1)) - max_exponent; // of the first digit
  switch(random() % 3) {
  case 0: // d.ddde-12
    text += mantissa.substr(0, 1);
    if(digits > 1) text += "." + mantissa.substr(1);
    text += (random() % 2 == 0 ? "e" : "E") + std::to_string(exponent);
    break;
  case 1: // 0.000ddd or ddd.ddd, if the exponent allows it
    if(exponent < 0 && exponent >= -6) {
      text += "0." + std::string(static_cast<std::size_t>(-exponent - 1), '0') + mantissa;
    } else if(exponent >= 0 && exponent < digits - 1) {
      text += mantissa.substr(0, static_cast<std::size_t>(exponent) + 1) + "." +
              mantissa.substr(static_cast<std::size_t>(exponent) + 1);
    } else {
      text += mantissa + "e" + std::to_string(exponent - (digits - 1));
    }
    break;
  default: // dddd (integer mantissa) and an exponent
    const int integer_exponent = exponent - (digits - 1);
    text += mantissa + (random() % 2 == 0 || integer_exponent < 0 ? "e" : "e+") + std::to_string(integer_exponent);
    break;
  }
  return text;
}

/// \brief A large `.xyz` text (about `lines * 75` bytes) with normals, comments, blank
/// lines, CRLF line ends, tabs and various number forms.
inline std::string large_xyz_text(std::size_t lines)
{
  std::mt19937_64 random(42);
  std::string text;
  text.reserve(lines * 80);
  for(std::size_t line = 1; line <= lines; ++line) {
    if(line % 997 == 0) {
      text += "# comment line " + std::to_string(line) + "\n";
      continue;
    }
    if(line % 1009 == 0) {
      text += " \t \n";
      continue;
    }
    for(int c = 0; c < 6; ++c) {
      if(c != 0) text += (line % 7 == 0) ? "\t" : " ";
      text += random_decimal(random, 1 + static_cast<int>(random() % 9), 3);
    }
    text += (line % 11 == 0) ? "\r\n" : "\n";
  }
  return text;
}

/// \brief Message of the `Io_error` thrown by `action`, or `"no error"`.
inline std::string error_message(const std::function<void()>& action)
{
  try {
    action();
  } catch(const Io_error& error) {
    return error.what();
  }
  return "no error";
}

/// \brief Reads `filename` with `threads` threads.
inline Point_cloud read_with_threads(const std::string& filename, unsigned int threads)
{
  Read_options options;
  options.number_of_threads = threads;
  return read_point_cloud(filename, options);
}

inline void expect_same_extras(const Point_cloud& a, const Point_cloud& b)
{
  ASSERT_EQ(a.extra_properties.size(), b.extra_properties.size());
  for(std::size_t k = 0; k < a.extra_properties.size(); ++k) {
    EXPECT_EQ(a.extra_properties[k].name, b.extra_properties[k].name);
    EXPECT_EQ(a.extra_properties[k].type, b.extra_properties[k].type) << a.extra_properties[k].name;
  }
  ASSERT_EQ(a.extra_values.size(), b.extra_values.size());
  for(std::size_t j = 0; j < a.extra_values.size(); ++j)
    EXPECT_EQ(a.extra_values[j], b.extra_values[j]) << "extra value " << j;
}

// ------------------------------------------------------------------ streaming

using Normal_orientation::IO::Point_stream_reader;
using Normal_orientation::IO::Point_stream_write_options;
using Normal_orientation::IO::Point_stream_writer;
using Normal_orientation::Point_record;

/// \brief All the records of `reader`, read `chunk_size` at a time.
inline std::vector<Point_record> read_stream(Point_stream_reader& reader, std::size_t chunk_size)
{
  std::vector<Point_record> records;
  std::vector<Point_record> chunk;
  for(;;) {
    chunk.clear();
    const std::size_t got = reader.read(chunk, chunk_size);
    EXPECT_LE(got, chunk_size);
    EXPECT_EQ(got, chunk.size());
    if(got == 0) break;
    records.insert(records.end(), chunk.begin(), chunk.end());
  }
  EXPECT_EQ(reader.read(chunk, chunk_size), 0u); // stays at the end
  EXPECT_EQ(reader.records_read(), records.size());
  return records;
}

/// \brief Checks that `records` are the points of `cloud`, bit for bit (zero normals
/// if it has none), numbered 0, 1, ...
inline void expect_records_of_cloud(const std::vector<Point_record>& records, const Point_cloud& cloud,
                                    const std::string& what)
{
  ASSERT_EQ(records.size(), cloud.size()) << what;
  std::size_t differences = 0;
  for(std::size_t i = 0; i < records.size() && differences < 10; ++i) {
    const Point_record& record = records[i];
    bool same = record.index == i;
    for(std::size_t c = 0; c < 3; ++c) {
      same = same && bits(record.position[c]) == bits(cloud.points[i][c]);
      same = same && bits(record.normal[c]) == bits(cloud.has_normals() ? cloud.normals[i][c] : 0.0);
    }
    if(!same) {
      ++differences;
      ADD_FAILURE() << what << ": record " << i << " (index " << record.index << ") differs";
    }
  }
}

/// \brief Shortest text of `value` that reads back exactly.
template <class T>
std::string shortest_text(T value)
{
  char text[64];
  const std::to_chars_result result = std::to_chars(text, text + sizeof(text), value);
  return std::string(text, result.ptr);
}

/// \brief A PLY file of `n` vertices with `x y z` (`double` or `float`), a colour and,
/// if `normals`, `nx ny nz` (`float` if the points are `double` and vice versa), then a
/// `face` element with lists; also a face element before the vertices if `face_before`.
/// `format` is `ascii`, `binary_little_endian` or `binary_big_endian`. The ASCII data
/// have a few blank lines.
inline std::string streaming_ply(const std::string& format, bool double_points, bool normals, std::size_t n,
                                 bool face_before)
{
  const bool ascii = format == "ascii";
  const std::size_t faces = n / 3;
  const std::string point_type = double_points ? "double" : "float";
  const std::string normal_type = double_points ? "float" : "double";
  std::string face_element = "element face " + std::to_string(faces) +
                             "\nproperty list uchar int vertex_indices\nproperty float quality\n";
  std::string header = "ply\nformat " + format + " 1.0\ncomment streaming test\n";
  if(face_before) header += "element before " + std::to_string(faces) +
                            "\nproperty list uchar int vertex_indices\nproperty float quality\n";
  header += "element vertex " + std::to_string(n) + "\n";
  for(const char* name : {"x", "y", "z"}) header += "property " + point_type + " " + name + "\n";
  header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if(normals)
    for(const char* name : {"nx", "ny", "nz"}) header += "property " + normal_type + " " + name + "\n";
  header += face_element + "end_header\n";

  Bytes bytes;
  bytes.big_endian = format == "binary_big_endian";
  bytes.data = header;
  auto value = [](std::size_t i, std::size_t c) {
    return std::sin(static_cast<double>(i) * 0.37 + static_cast<double>(c)) * 100.0 + static_cast<double>(i) * 1e-3;
  };
  auto put_real = [&](double v, bool as_double) {
    if(ascii) {
      bytes.data += (as_double ? shortest_text(v) : shortest_text(static_cast<float>(v))) + " ";
    } else if(as_double) {
      bytes << v;
    } else {
      bytes << static_cast<float>(v);
    }
  };
  auto put_faces = [&] {
    for(std::size_t f = 0; f < faces; ++f) {
      const std::size_t corners = 3 + f % 2;
      if(ascii) {
        bytes.data += std::to_string(corners);
        for(std::size_t k = 0; k < corners; ++k) bytes.data += " " + std::to_string((f + k) % n);
        bytes.data += " 0.5\n";
      } else {
        bytes << static_cast<std::uint8_t>(corners);
        for(std::size_t k = 0; k < corners; ++k) bytes << static_cast<std::int32_t>((f + k) % n);
        bytes << 0.5f;
      }
    }
  };
  if(face_before) put_faces();
  for(std::size_t i = 0; i < n; ++i) {
    for(std::size_t c = 0; c < 3; ++c) put_real(value(i, c), double_points);
    for(std::size_t c = 0; c < 3; ++c) {
      if(ascii) bytes.data += std::to_string((i * 7 + c) % 256) + " ";
      else bytes << static_cast<std::uint8_t>((i * 7 + c) % 256);
    }
    if(normals)
      for(std::size_t c = 0; c < 3; ++c) put_real(value(i, c + 3) / 100.0, !double_points);
    if(ascii) bytes.data += (i % 500 == 0) ? "\n\n" : "\n";
  }
  put_faces();
  return bytes.data;
}

/// \brief Message of the `Io_error` thrown when streaming the whole of `filename`
/// (construction and reading), or `"no error"`.
inline std::string stream_error(const std::string& filename,
                                std::size_t buffer_size = Point_stream_reader::default_buffer_size)
{
  return error_message([&] {
    Point_stream_reader reader(filename, buffer_size);
    std::vector<Point_record> chunk;
    while(reader.read(chunk, 3) != 0) chunk.clear();
  });
}

/// \brief Records with awkward values, whose indices are not 0, 1, ...
inline std::vector<Point_record> awkward_records()
{
  const Point_cloud cloud = sample_cloud(true);
  std::vector<Point_record> records;
  for(std::size_t i = 0; i < cloud.size(); ++i) {
    Point_record record{};
    for(std::size_t c = 0; c < 3; ++c) {
      record.position[c] = cloud.points[i][c];
      record.normal[c] = cloud.normals[i][c];
    }
    record.index = 1000 - i;
    records.push_back(record);
  }
  const double values[] = {-0.0, 5e-324, std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
                           0.1, 1.0 / 3, 123456789.123456789, -2.5e-200};
  for(std::size_t i = 0; i < std::size(values); ++i) {
    Point_record record{};
    for(std::size_t c = 0; c < 3; ++c) {
      record.position[c] = values[(i + c) % std::size(values)];
      record.normal[c] = values[(i + c + 3) % std::size(values)];
    }
    record.index = 7;
    records.push_back(record);
  }
  return records;
}

/// \brief Checks the values of `a` and `b`, extra values included, bit for bit.
inline void expect_same_bits(const Point_cloud& a, const Point_cloud& b, const std::string& what)
{
  ASSERT_EQ(a.size(), b.size()) << what;
  ASSERT_EQ(a.normals.size(), b.normals.size()) << what;
  ASSERT_EQ(a.extra_values.size(), b.extra_values.size()) << what;
  for(std::size_t i = 0; i < a.size(); ++i)
    for(std::size_t c = 0; c < 3; ++c) {
      EXPECT_EQ(bits(a.points[i][c]), bits(b.points[i][c])) << what << ": point " << i;
      if(a.has_normals()) {
        EXPECT_EQ(bits(a.normals[i][c]), bits(b.normals[i][c])) << what << ": normal " << i;
      }
    }
  for(std::size_t j = 0; j < a.extra_values.size(); ++j)
    EXPECT_TRUE(bits(a.extra_values[j]) == bits(b.extra_values[j]) ||
                (std::isnan(a.extra_values[j]) && std::isnan(b.extra_values[j])))
      << what << ": extra value " << j;
}

} // namespace io_test

#endif // NORMAL_ORIENTATION_TEST_IO_TEST_SUPPORT_H
