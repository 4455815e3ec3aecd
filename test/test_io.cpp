// SPDX-License-Identifier: GPL-3.0-or-later
/// \file test_io.cpp
/// \brief Tests of Normal_orientation/IO/Point_cloud_io.h: reading and writing `.xyz`,
/// `.pwn` and `.ply` point clouds, error reporting and atomic writing; and of
/// Normal_orientation/IO/Point_stream.h: streaming reading and writing; and of
/// Normal_orientation/IO/Point_stream_transcode.h: copies with flipped normals (at the end).

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

namespace {

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
void write_file(const std::string& filename, const std::string& content)
{
  std::ofstream out(filename, std::ios::binary);
  out.write(content.data(), static_cast<std::streamsize>(content.size()));
  ASSERT_TRUE(out.good()) << filename;
}

/// \brief Content of `filename`.
std::string file_content(const std::string& filename)
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
void expect_io_error(const std::function<void()>& action, const std::string& filename,
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
void expect_read_error(const Temporary_directory& directory, const std::string& name,
                       const std::string& content, const std::string& expected)
{
  const std::string filename = directory.file(name);
  write_file(filename, content);
  expect_io_error([&] { read_point_cloud(filename); }, filename, expected);
}

/// \brief A small cloud with awkward values.
Point_cloud sample_cloud(bool with_normals)
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
void add_extra_properties(Point_cloud& cloud)
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

void expect_same_points(const Point_cloud& a, const Point_cloud& b)
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
std::uint64_t bits(double value)
{
  std::uint64_t result = 0;
  std::memcpy(&result, &value, sizeof(result));
  return result;
}

/// \brief Checks that `a` and `b` have the same points and normals, bit for bit (so
/// that `0.0` and `-0.0` differ), and the same recorded digits.
void expect_identical_clouds(const Point_cloud& a, const Point_cloud& b)
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
std::string random_decimal(std::mt19937_64& random, int digits, int max_exponent = 30)
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
std::string large_xyz_text(std::size_t lines)
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
std::string error_message(const std::function<void()>& action)
{
  try {
    action();
  } catch(const Io_error& error) {
    return error.what();
  }
  return "no error";
}

/// \brief Reads `filename` with `threads` threads.
Point_cloud read_with_threads(const std::string& filename, unsigned int threads)
{
  Read_options options;
  options.number_of_threads = threads;
  return read_point_cloud(filename, options);
}

void expect_same_extras(const Point_cloud& a, const Point_cloud& b)
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

} // namespace

// --------------------------------------------------------------------------- xyz

TEST(Point_cloud_io, xyz_round_trip_with_normals)
{
  Temporary_directory directory;
  const Point_cloud cloud = sample_cloud(true);
  Write_options exact;
  exact.precision = 0;
  write_point_cloud(directory.file("a.xyz"), cloud, exact);
  const Point_cloud read = read_point_cloud(directory.file("a.xyz"));
  EXPECT_TRUE(read.has_normals());
  EXPECT_EQ(read.size(), cloud.size());
  expect_same_points(cloud, read);

  // Default precision: 9 significant digits.
  write_point_cloud(directory.file("b.xyz"), cloud);
  const Point_cloud rounded = read_point_cloud(directory.file("b.xyz"));
  ASSERT_EQ(rounded.size(), cloud.size());
  for(std::size_t i = 0; i < cloud.size(); ++i)
    for(std::size_t c = 0; c < 3; ++c) {
      EXPECT_NEAR(rounded.points[i][c], cloud.points[i][c], 1e-8 * std::fabs(cloud.points[i][c]));
      EXPECT_NEAR(rounded.normals[i][c], cloud.normals[i][c], 1e-8 * std::fabs(cloud.normals[i][c]));
    }
  EXPECT_EQ(file_content(directory.file("b.xyz")).substr(0, 2), "0 ");
  EXPECT_FALSE(directory.has_temporary_file());
}

TEST(Point_cloud_io, xyz_round_trip_without_normals)
{
  Temporary_directory directory;
  const Point_cloud cloud = sample_cloud(false);
  Write_options exact;
  exact.precision = -1;
  write_point_cloud(directory.file("a.xyz"), cloud, exact);
  const Point_cloud read = read_point_cloud(directory.file("a.xyz"));
  EXPECT_FALSE(read.has_normals());
  expect_same_points(cloud, read);
  // Three values per line.
  const std::string text = file_content(directory.file("a.xyz"));
  const std::string first_line = text.substr(0, text.find('\n'));
  EXPECT_EQ(std::count(first_line.begin(), first_line.end(), ' '), 2) << first_line;
}

TEST(Point_cloud_io, xyz_comments_blank_lines_and_line_endings)
{
  Temporary_directory directory;
  const std::string filename = directory.file("c.xyz");
  write_file(filename, "# a comment\n\n   # indented comment\r\n1 2 3 0 0 1\r\n"
                       "\t-1.5\t+2e3   .25  0 0 0 \n   \n1e-3 -0 7 0.5 -0.5 0");
  const Point_cloud cloud = read_point_cloud(filename);
  ASSERT_EQ(cloud.size(), 3u);
  ASSERT_TRUE(cloud.has_normals());
  EXPECT_EQ(cloud.points[0], (std::array<double, 3>{{1, 2, 3}}));
  EXPECT_EQ(cloud.normals[0], (std::array<double, 3>{{0, 0, 1}}));
  EXPECT_EQ(cloud.points[1], (std::array<double, 3>{{-1.5, 2000, 0.25}}));
  EXPECT_EQ(cloud.normals[1], (std::array<double, 3>{{0, 0, 0}})); // zero normals are allowed
  EXPECT_EQ(cloud.points[2], (std::array<double, 3>{{1e-3, 0, 7}}));
  EXPECT_TRUE(std::signbit(cloud.points[2][1]));
  EXPECT_EQ(cloud.normals[2], (std::array<double, 3>{{0.5, -0.5, 0}}));
}

TEST(Point_cloud_io, xyz_number_syntax)
{
  Temporary_directory directory;
  write_file(directory.file("n.xyz"), "1. .5 +.25\n1e+05 -0.0e0 7E-3\n0012 1e0 -1.5e-310\n");
  const Point_cloud cloud = read_point_cloud(directory.file("n.xyz"));
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.points[0], (std::array<double, 3>{{1.0, 0.5, 0.25}}));
  EXPECT_EQ(cloud.points[1], (std::array<double, 3>{{1e5, 0.0, 7e-3}}));
  EXPECT_EQ(cloud.points[2], (std::array<double, 3>{{12.0, 1.0, -1.5e-310}}));
  expect_read_error(directory, "e.xyz", "1 2 1e\n", "non-numeric token '1e' at line 1");
  expect_read_error(directory, "hex.xyz", "1 2 0x10\n", "non-numeric token '0x10' at line 1");
  expect_read_error(directory, "plus_minus.xyz", "1 2 +-3\n", "non-numeric token '+-3' at line 1");
  expect_read_error(directory, "dot.xyz", "1 2 .\n", "non-numeric token '.' at line 1");
}

TEST(Point_cloud_io, fast_formatting_matches_to_chars)
{
  using Normal_orientation::IO::internal::format_general_fast;
  std::uint64_t state = 12345;
  auto next = [&state] { // xorshift64*
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return state * 2685821657736338717ull;
  };
  std::size_t fast = 0;
  auto check = [&fast](double value, int precision) {
    char expected[64];
    char actual[64];
    const std::to_chars_result result =
      std::to_chars(expected, expected + 64, value, std::chars_format::general, precision);
    if(char* end = format_general_fast(actual, value, precision)) {
      ++fast;
      ASSERT_EQ(std::string(expected, result.ptr), std::string(actual, end))
        << "precision " << precision << " value " << std::string(expected, result.ptr);
    }
  };
  for(int i = 0; i < 300000; ++i) {
    const double mantissa = static_cast<double>(next() >> 11) / 9007199254740992.0 * 2.0 - 1.0;
    const int exponent = static_cast<int>(next() % 61) - 30;
    check(mantissa * std::pow(10.0, exponent), 1 + static_cast<int>(next() % 12));
  }
  // Powers of ten, short decimals and ties, and their neighbours.
  for(int precision = 1; precision <= 12; ++precision)
    for(int exponent = -12; exponent <= 22; exponent += 3)
      for(int m = 1; m < 200; ++m)
        for(double value : {m * std::pow(10.0, exponent), (m + 0.5) * std::pow(10.0, exponent)}) {
          check(value, precision);
          check(-value, precision);
          check(std::nextafter(value, 0.0), precision);
          check(std::nextafter(value, 1e300), precision);
        }
  for(double value : {0.0, -0.0, 1e-300, 1e300, 5e-324, std::numeric_limits<double>::max()})
    for(int precision = 1; precision <= 12; ++precision) check(value, precision);
  EXPECT_GT(fast, 300000u); // most values take the fast path
}

TEST(Point_cloud_io, pwn_and_upper_case_extensions)
{
  Temporary_directory directory;
  write_file(directory.file("a.PWN"), "1 2 3 0 1 0\n4 5 6 1 0 0\n");
  const Point_cloud cloud = read_point_cloud(directory.file("a.PWN"));
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.normals[1], (std::array<double, 3>{{1, 0, 0}}));
  write_point_cloud(directory.file("b.Xyz"), cloud);
  write_point_cloud(directory.file("c.pwn"), cloud);
  write_point_cloud(directory.file("d.PLY"), cloud);
  expect_same_points(cloud, read_point_cloud(directory.file("b.Xyz")));
  expect_same_points(cloud, read_point_cloud(directory.file("c.pwn")));
  expect_same_points(cloud, read_point_cloud(directory.file("d.PLY")));
}

TEST(Point_cloud_io, empty_files)
{
  Temporary_directory directory;
  write_file(directory.file("e.xyz"), "# nothing\n\n");
  EXPECT_EQ(read_point_cloud(directory.file("e.xyz")).size(), 0u);
  write_file(directory.file("e.ply"), "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                                      "property float y\nproperty float z\nend_header\n");
  EXPECT_EQ(read_point_cloud(directory.file("e.ply")).size(), 0u);
  const Point_cloud empty;
  write_point_cloud(directory.file("f.ply"), empty);
  write_point_cloud(directory.file("f.xyz"), empty);
  EXPECT_EQ(read_point_cloud(directory.file("f.ply")).size(), 0u);
  EXPECT_EQ(read_point_cloud(directory.file("f.xyz")).size(), 0u);
  EXPECT_EQ(file_content(directory.file("f.xyz")), "");
}

// --------------------------------------------------------------------------- precision as read

TEST(Point_cloud_io, significant_digits_of_tokens)
{
  using Normal_orientation::IO::internal::significant_digits;
  const std::vector<std::pair<std::string, int>> cases = {
    {"0.012345", 5}, {"1.2300e5", 5}, {"-0", 1},         {"0", 1},        {"0.000", 1},
    {"+12.5", 3},    {"0012", 2},     {"100", 3},        {"-1.5E-07", 2}, {".5", 1},
    {"1.", 1},       {"-.0", 1},      {"0e5", 1},        {"5e-324", 1},   {"1.000000", 7},
    {"0.1000", 4},   {"-0.00606638857", 9}, {"123456789012345678", 18}, {"9.99e+300", 3},
    {"12.34e-5", 4}, {"000.000120", 3}, {"7E0", 1}};
  for(const std::pair<std::string, int>& c : cases)
    EXPECT_EQ(significant_digits(c.first.data(), c.first.data() + c.first.size()), c.second) << c.first;

  // Reading records the largest counts, separately for coordinates and normals.
  Temporary_directory directory;
  write_file(directory.file("a.xyz"), "# 1.23456789012 comments do not count\n"
                                      "1.5 -0.25 3 0.5 0.25 -0.125\n"
                                      "\n"
                                      "0.012345 1 2 1 0 -0\n"
                                      "1e5 -2.50E+3 7 0.1 0.20 0.3\n");
  const Point_cloud cloud = read_point_cloud(directory.file("a.xyz"));
  EXPECT_EQ(cloud.point_digits, 5);
  EXPECT_EQ(cloud.normal_digits, 3);
  write_file(directory.file("b.xyz"), "0.5 1 2\n3 4 5.0000000000000001\n");
  const Point_cloud no_normals = read_point_cloud(directory.file("b.xyz"));
  EXPECT_EQ(no_normals.point_digits, 17);
  EXPECT_EQ(no_normals.normal_digits, 0);
  // Digits increasing along the file, in various forms: every token is counted.
  const std::vector<std::string> forms = {"0.", "-0.", "-0.0", "+0.00", "", "-", "1.", "-1.", "2e3 ", "0.0e"};
  for(const std::string& form : forms) {
    std::string text;
    std::string digits;
    for(int count = 1; count <= 15; ++count) {
      digits += static_cast<char>('1' + count % 9);
      const std::string token = form == "2e3 "   ? digits + "e3"
                                : form == "0.0e" ? "0.0" + digits + "e-7"
                                                 : form + digits;
      text += (count % 3 == 1 ? "" : " ") + token + (count % 3 == 0 ? "\n" : "");
      write_file(directory.file("d.xyz"), text + (count % 3 == 0 ? "" : count % 3 == 1 ? " 0 0\n" : " 0\n"));
      const int expected = form == "1." || form == "-1." ? count + 1 : count;
      EXPECT_EQ(read_point_cloud(directory.file("d.xyz")).point_digits, expected) << text;
    }
  }
  write_file(directory.file("c.xyz"), "# nothing\n");
  EXPECT_EQ(read_point_cloud(directory.file("c.xyz")).point_digits, 0);
  // Unknown for PLY and in-memory clouds.
  write_point_cloud(directory.file("d.ply"), cloud);
  const Point_cloud from_ply = read_point_cloud(directory.file("d.ply"));
  EXPECT_EQ(from_ply.point_digits, 0);
  EXPECT_EQ(from_ply.normal_digits, 0);
  EXPECT_EQ(Point_cloud().point_digits, 0);
}

TEST(Point_cloud_io, as_read_reproduces_the_values_bit_for_bit)
{
  Temporary_directory directory;
  std::mt19937_64 random(7);
  for(int point_digits = 1; point_digits <= 15; ++point_digits) {
    const int normal_digits = 16 - point_digits; // points and normals differ
    std::string text;
    for(int line = 0; line < 400; ++line) {
      for(int c = 0; c < 3; ++c) text += random_decimal(random, 1 + static_cast<int>(random() % point_digits)) + " ";
      for(int c = 0; c < 3; ++c)
        text += random_decimal(random, 1 + static_cast<int>(random() % normal_digits), 3) + " ";
      text += "\n";
    }
    // Extreme magnitudes (subnormal, largest, smallest normal) with the digits allowed.
    auto extremes = [](int digits) -> std::string {
      if(digits >= 14) return "4.9406564584125e-324 -1.7976931348623e308 2.2250738585072e-308";
      if(digits >= 2) return "-2.5e-324 1.7e308 -2.2e-308";
      return "5e-324 -1e308 2e-308";
    };
    text += extremes(point_digits) + " " + extremes(normal_digits) + "\n";
    // The largest counts are reached.
    text += "-0 0.000 1" + std::string(static_cast<std::size_t>(point_digits - 1), '0') + " " +
            (normal_digits >= 2 ? "-1.5e-310 " : "-1e-310 ") + random_decimal(random, normal_digits, 300) + " -0\n";
    const std::string input = directory.file("in.xyz");
    write_file(input, text);
    Point_cloud cloud = read_point_cloud(input);
    ASSERT_EQ(cloud.point_digits, point_digits);
    ASSERT_EQ(cloud.normal_digits, normal_digits);
    // Flip some normals: their signs change, not their digit counts.
    for(std::size_t i = 0; i < cloud.size(); i += 3)
      for(double& v : cloud.normals[i]) v = -v;

    Write_options as_read;
    as_read.precision = Write_options::PRECISION_AS_READ;
    const std::string output = directory.file("out.xyz");
    write_point_cloud(output, cloud, as_read);
    const Point_cloud back = read_point_cloud(output);
    ASSERT_EQ(back.size(), cloud.size());
    std::size_t differences = 0;
    for(std::size_t i = 0; i < cloud.size(); ++i)
      for(std::size_t c = 0; c < 3; ++c) {
        differences += bits(back.points[i][c]) != bits(cloud.points[i][c]);
        differences += bits(back.normals[i][c]) != bits(cloud.normals[i][c]);
      }
    EXPECT_EQ(differences, 0u) << point_digits << " digits";
    // No more digits than read.
    EXPECT_LE(back.point_digits, point_digits);
    EXPECT_LE(back.normal_digits, normal_digits);
    // Any negative precision means "as read".
    Write_options minus_two;
    minus_two.precision = -2;
    write_point_cloud(directory.file("out2.xyz"), cloud, minus_two);
    EXPECT_EQ(file_content(directory.file("out2.xyz")), file_content(output));
  }
}

TEST(Point_cloud_io, as_read_writes_like_printf_with_the_digits_read)
{
  Temporary_directory directory;
  write_file(directory.file("in.xyz"), "0.149716222 -0.487264655 0.213049765 0.00606638857 0.998976844 -0.0448158807\n"
                                       "1.50 2 3 0.5 -0.25 1e3\n");
  Point_cloud cloud = read_point_cloud(directory.file("in.xyz"));
  ASSERT_EQ(cloud.point_digits, 9);
  ASSERT_EQ(cloud.normal_digits, 9);
  cloud.normals[1] = {{-0.5, 0.25, -1000.0}};
  Write_options as_read;
  as_read.precision = Write_options::PRECISION_AS_READ;
  write_point_cloud(directory.file("out.xyz"), cloud, as_read);
  EXPECT_EQ(file_content(directory.file("out.xyz")),
            "0.149716222 -0.487264655 0.213049765 0.00606638857 0.998976844 -0.0448158807\n"
            "1.5 2 3 -0.5 0.25 -1000\n");
  // Different precisions for points and normals.
  cloud.point_digits = 2;
  cloud.normal_digits = 4;
  write_point_cloud(directory.file("out.xyz"), cloud, as_read);
  EXPECT_EQ(file_content(directory.file("out.xyz")), "0.15 -0.49 0.21 0.006066 0.999 -0.04482\n"
                                                       "1.5 2 3 -0.5 0.25 -1000\n");
  // A positive precision or PRECISION_SHORTEST ignores the digits read.
  write_point_cloud(directory.file("out.xyz"), cloud, Write_options{true, 3});
  EXPECT_EQ(file_content(directory.file("out.xyz")).substr(0, 16), "0.15 -0.487 0.21");
}

TEST(Point_cloud_io, as_read_falls_back_to_shortest_when_digits_are_unknown_or_above_15)
{
  Temporary_directory directory;
  Write_options as_read;
  as_read.precision = Write_options::PRECISION_AS_READ;
  Write_options shortest;
  shortest.precision = Write_options::PRECISION_SHORTEST;
  // 16 and 17 digits: a %.16g round trip is not always exact, the shortest text is.
  write_file(directory.file("in.xyz"), "0.1000000000000001 9007199254740993 0.3 "
                                       "0.30000000000000004 -1 2.2250738585072014e-308\n"
                                       "1.7976931348623157e308 4.9406564584124654e-324 1 0 0 1\n");
  Point_cloud cloud = read_point_cloud(directory.file("in.xyz"));
  EXPECT_EQ(cloud.point_digits, 17);
  EXPECT_EQ(cloud.normal_digits, 17);
  for(int point_digits : {16, 17, 25, 0}) {
    cloud.point_digits = point_digits;
    cloud.normal_digits = point_digits == 0 ? 0 : 16;
    write_point_cloud(directory.file("as_read.xyz"), cloud, as_read);
    write_point_cloud(directory.file("shortest.xyz"), cloud, shortest);
    EXPECT_EQ(file_content(directory.file("as_read.xyz")), file_content(directory.file("shortest.xyz")))
      << point_digits;
    Point_cloud back = read_point_cloud(directory.file("as_read.xyz"));
    back.point_digits = cloud.point_digits;
    back.normal_digits = cloud.normal_digits;
    expect_identical_clouds(cloud, back);
  }
  // A cloud built in memory (digits unknown) is written exactly.
  const Point_cloud memory = sample_cloud(true);
  write_point_cloud(directory.file("as_read.xyz"), memory, as_read);
  write_point_cloud(directory.file("shortest.xyz"), memory, shortest);
  EXPECT_EQ(file_content(directory.file("as_read.xyz")), file_content(directory.file("shortest.xyz")));
  // Only the normals known: the points are written shortest.
  cloud.point_digits = 0;
  cloud.normal_digits = 1;
  write_point_cloud(directory.file("as_read.xyz"), cloud, as_read);
  const std::string text = file_content(directory.file("as_read.xyz"));
  EXPECT_EQ(text.substr(text.find('\n') + 1), "1.7976931348623157e+308 5e-324 1 0 0 1\n");
}

// --------------------------------------------------------------------------- parallel text

TEST(Point_cloud_io, parallel_reading_gives_the_sequential_cloud)
{
  Temporary_directory directory;
  const std::string filename = directory.file("large.xyz");
  const std::size_t lines = 100000;
  write_file(filename, large_xyz_text(lines));
  ASSERT_GT(fs::file_size(filename), std::uintmax_t(5) << 20); // more than the 4 MB threshold
  const Point_cloud sequential = read_with_threads(filename, 1);
  EXPECT_EQ(sequential.size(), lines - lines / 997 - lines / 1009 + lines / (997 * 1009));
  EXPECT_EQ(sequential.point_digits, 9);
  EXPECT_EQ(sequential.normal_digits, 9);
  for(unsigned int threads : {2u, 3u, 5u, 8u, 0u, 100u}) {
    SCOPED_TRACE(threads);
    expect_identical_clouds(sequential, read_with_threads(filename, threads));
  }
  expect_identical_clouds(sequential, read_point_cloud(filename)); // default options

  // Small files split at every possible place: more threads than lines, empty chunks,
  // comments, blank lines and a missing final newline.
  const std::string small = "# head\n1 2 3 4 5 6\n\n  7 8 9.125 0 0 1\r\n# c\n-1 -2 -3 0.5 0.5 0.5\n\t\n4 5 6 7 8 9";
  for(std::size_t length = 0; length <= small.size(); ++length) {
    write_file(directory.file("small.xyz"), small.substr(0, length));
    std::string expected_message;
    Point_cloud expected;
    try {
      expected = read_with_threads(directory.file("small.xyz"), 1);
    } catch(const Io_error& error) {
      expected_message = error.what();
    }
    for(unsigned int threads = 2; threads <= 8; ++threads) {
      SCOPED_TRACE("length " + std::to_string(length) + ", threads " + std::to_string(threads));
      if(expected_message.empty())
        expect_identical_clouds(expected, read_with_threads(directory.file("small.xyz"), threads));
      else
        EXPECT_EQ(error_message([&] { read_with_threads(directory.file("small.xyz"), threads); }), expected_message);
    }
  }
}

TEST(Point_cloud_io, parallel_writing_gives_the_sequential_file)
{
  Temporary_directory directory;
  write_file(directory.file("large.xyz"), large_xyz_text(100000));
  Point_cloud cloud = read_point_cloud(directory.file("large.xyz"));
  for(std::size_t i = 0; i < cloud.size(); i += 5)
    for(double& v : cloud.normals[i]) v = -v;
  Point_cloud no_normals = cloud;
  no_normals.normals.clear();
  for(const Point_cloud* written : {&cloud, &no_normals})
    for(int precision : {Write_options::PRECISION_AS_READ, Write_options::PRECISION_SHORTEST, 4}) {
      SCOPED_TRACE("precision " + std::to_string(precision));
      Write_options options;
      options.precision = precision;
      options.number_of_threads = 1;
      write_point_cloud(directory.file("sequential.xyz"), *written, options);
      const std::string expected = file_content(directory.file("sequential.xyz"));
      EXPECT_GT(expected.size(), std::size_t(1) << 20);
      for(unsigned int threads : {2u, 3u, 8u}) {
        options.number_of_threads = threads;
        write_point_cloud(directory.file("parallel.xyz"), *written, options);
        EXPECT_TRUE(file_content(directory.file("parallel.xyz")) == expected) << threads << " threads";
      }
      if(precision == Write_options::PRECISION_AS_READ) {
        Point_cloud back = read_point_cloud(directory.file("parallel.xyz"));
        back.point_digits = written->point_digits;
        back.normal_digits = written->normal_digits;
        expect_identical_clouds(*written, back);
      }
    }
  EXPECT_FALSE(directory.has_temporary_file());

  // Small clouds with many threads (fewer blocks than threads).
  const Point_cloud small = sample_cloud(true);
  Write_options options;
  options.number_of_threads = 1;
  write_point_cloud(directory.file("s1.xyz"), small, options);
  options.number_of_threads = 8;
  write_point_cloud(directory.file("s8.xyz"), small, options);
  EXPECT_EQ(file_content(directory.file("s1.xyz")), file_content(directory.file("s8.xyz")));
  write_point_cloud(directory.file("empty.xyz"), Point_cloud(), options);
  EXPECT_EQ(file_content(directory.file("empty.xyz")), "");
}

TEST(Point_cloud_io, parallel_reading_reports_the_first_error_with_its_line)
{
  Temporary_directory directory;
  const std::size_t lines = 100000;
  const std::string text = large_xyz_text(lines);
  std::vector<std::size_t> line_starts(1, 0);
  for(std::size_t i = 0; i < text.size(); ++i)
    if(text[i] == '\n') line_starts.push_back(i + 1);
  ASSERT_EQ(line_starts.size(), lines + 1);
  // `text` with line `line` (1-based, a data line) replaced by `replacement`.
  auto with_line = [&](const std::string& base, std::size_t line, const std::string& replacement) {
    const std::size_t begin = line_starts[line - 1];
    const std::size_t end = base.find('\n', begin);
    return base.substr(0, begin) + replacement + base.substr(end);
  };
  const std::string broken_late = with_line(text, 80000, "1 2 3 0 0 nan");
  struct Case
  {
    std::string name;
    std::string content;
    std::string expected;
  };
  const std::vector<Case> cases = {
    {"token", with_line(text, 70001, "1 2 3 0 zero 1"), "non-numeric token 'zero' at line 70001"},
    {"range", with_line(text, 66000, "1 2 3 0 1e999 1"), "number '1e999' out of range at line 66000"},
    {"count", with_line(text, 88888, "1 2 3 0"), "wrong column count at line 88888: 4 values, expected 3"},
    {"mismatch", with_line(text, 50001, "1 2 3"), "wrong column count at line 50001: 3 values, but line 1 has 6"},
    {"coordinate", with_line(text, 89999, "inf 2 3 0 0 1"), "non-finite coordinate at line 89999"},
    {"normal", broken_late, "non-finite normal at line 80000"},
    {"last", with_line(text, 100000, "1 2 3 0 0"), "wrong column count at line 100000: 5 values"},
    // Two errors: the first one in the file wins, whatever the chunks.
    {"two", with_line(broken_late, 46000, "x 2 3 0 0 1"), "non-numeric token 'x' at line 46000"},
    {"two_late", with_line(broken_late, 85000, "x"), "non-finite normal at line 80000"},
    // From line 60000 on, three columns: the mismatch is at line 60000 whatever the
    // chunk holding it, even with another error after it in the same chunk.
    {"columns", [&] {
       std::string three = text.substr(0, line_starts[59999]);
       for(std::size_t line = 60000; line <= lines; ++line) three += line == 70000 ? "1 2 z\n" : "1 2 3\n";
       return three;
     }(),
     "wrong column count at line 60000: 3 values, but line 1 has 6"},
  };
  for(const Case& c : cases) {
    const std::string filename = directory.file(c.name + ".xyz");
    write_file(filename, c.content);
    for(unsigned int threads : {1u, 2u, 7u, 0u}) {
      SCOPED_TRACE(c.name + ", threads " + std::to_string(threads));
      expect_io_error([&] { read_with_threads(filename, threads); }, filename, c.expected);
    }
  }

  // In a small file, every error position and every split give the sequential message.
  const std::vector<std::string> good = {"1 2 3 0 0 1", "# comment", "", "4 5 6 1 0 0", "7 8 9 0 1 0",
                                         "\t", "1.5 2.5 3.5 0 0 1", "9 9 9 1 1 1"};
  const std::vector<std::string> bad = {"1 2 x 0 0 1", "1 2 3", "1 2 3 4", "nan 0 0 0 0 1", "0 0 0 0 0 inf",
                                        "1e400 0 0 0 0 0", "1 2 3 4 5 6 7"};
  for(std::size_t position = 0; position < good.size(); ++position)
    for(const std::string& error : bad) {
      std::string content;
      for(std::size_t line = 0; line < good.size(); ++line)
        content += (line == position ? error : good[line]) + "\n";
      if(position + 2 < good.size()) content += error + " trailing\n"; // a second error
      const std::string filename = directory.file("small.xyz");
      write_file(filename, content);
      const std::string expected = error_message([&] { read_with_threads(filename, 1); });
      EXPECT_NE(expected.find("at line"), std::string::npos) << expected;
      for(unsigned int threads = 2; threads <= 8; ++threads)
        EXPECT_EQ(error_message([&] { read_with_threads(filename, threads); }), expected)
          << "error '" << error << "' at line " << position + 1 << ", threads " << threads;
    }
}

TEST(Point_cloud_io, read_and_write_options_keep_their_aggregate_form)
{
  const Write_options legacy{false, 12};
  EXPECT_FALSE(legacy.binary);
  EXPECT_EQ(legacy.precision, 12);
  EXPECT_EQ(legacy.number_of_threads, 0u);
  EXPECT_EQ(Write_options().precision, 9);
  const Read_options automatic{};
  EXPECT_EQ(automatic.number_of_threads, 0u);
  EXPECT_EQ(Write_options::PRECISION_AS_READ, -1);
  EXPECT_EQ(Write_options::PRECISION_SHORTEST, 0);
}

// --------------------------------------------------------------------------- ply reading

TEST(Point_cloud_io, ply_ascii_with_colours_and_faces)
{
  Temporary_directory directory;
  const std::string filename = directory.file("a.ply");
  write_file(filename, "ply\r\n"
                       "format ascii 1.0\r\n"
                       "comment made by hand\r\n"
                       "obj_info nothing\r\n"
                       "element vertex 3\r\n"
                       "property float x\r\n"
                       "property float y\r\n"
                       "property float z\r\n"
                       "property uchar red\r\n"
                       "property uchar green\r\n"
                       "property uchar blue\r\n"
                       "property float nx\r\n"
                       "property float ny\r\n"
                       "property float nz\r\n"
                       "element face 2\r\n"
                       "property list uchar int vertex_indices\r\n"
                       "end_header\r\n"
                       "0 0 0 255 0 0 0 0 1\r\n"
                       "1.5 0 0 0 255 0 0 1 0\r\n"
                       "0.1 1 -2 0 0 255 1 0 0\r\n"
                       "3 0 1 2\r\n"
                       "3 2 1 0\r\n");
  const Point_cloud cloud = read_point_cloud(filename);
  ASSERT_EQ(cloud.size(), 3u);
  ASSERT_TRUE(cloud.has_normals());
  EXPECT_EQ(cloud.points[1], (std::array<double, 3>{{1.5, 0, 0}}));
  EXPECT_EQ(cloud.points[2][0], static_cast<double>(0.1f)); // float property: rounded to float
  EXPECT_EQ(cloud.points[2][2], -2.0);
  EXPECT_EQ(cloud.normals[0], (std::array<double, 3>{{0, 0, 1}}));
  EXPECT_EQ(cloud.normals[2], (std::array<double, 3>{{1, 0, 0}}));
  ASSERT_EQ(cloud.extra_properties.size(), 3u);
  EXPECT_EQ(cloud.extra_properties[0].name, "red");
  EXPECT_EQ(cloud.extra_properties[1].name, "green");
  EXPECT_EQ(cloud.extra_properties[2].name, "blue");
  EXPECT_EQ(cloud.extra_properties[2].type, Ply_scalar_type::UINT8);
  EXPECT_EQ(cloud.extra_values, (std::vector<double>{255, 0, 0, 0, 255, 0, 0, 0, 255}));
  EXPECT_EQ(cloud.point_types[0], Ply_scalar_type::FLOAT32);
  EXPECT_EQ(cloud.normal_types[2], Ply_scalar_type::FLOAT32);
}

TEST(Point_cloud_io, ply_binary_little_endian_written_byte_by_byte)
{
  Temporary_directory directory;
  const std::string filename = directory.file("hand.ply");
  std::string content = "ply\n"
                        "format binary_little_endian 1.0\n"
                        "element vertex 2\n"
                        "property float x\n"
                        "property float y\n"
                        "property float z\n"
                        "property uchar red\n"
                        "property uchar green\n"
                        "property uchar blue\n"
                        "element face 1\n"
                        "property list uchar int vertex_indices\n"
                        "end_header\n";
  const unsigned char data[] = {
    // vertex 0: x = 1.0f, y = -2.0f, z = 0.5f, colour (255, 128, 0)
    0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0xc0, 0x00, 0x00, 0x00, 0x3f, 0xff, 0x80, 0x00,
    // vertex 1: x = 0.0f, y = 3.0f, z = -0.25f, colour (1, 2, 3)
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40, 0x40, 0x00, 0x00, 0x80, 0xbe, 0x01, 0x02, 0x03,
    // face 0: 3 indices 0 1 1 (int, little endian)
    0x03, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00};
  content.append(reinterpret_cast<const char*>(data), sizeof(data));
  write_file(filename, content);

  const Point_cloud cloud = read_point_cloud(filename);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_FALSE(cloud.has_normals());
  EXPECT_EQ(cloud.points[0], (std::array<double, 3>{{1.0, -2.0, 0.5}}));
  EXPECT_EQ(cloud.points[1], (std::array<double, 3>{{0.0, 3.0, -0.25}}));
  ASSERT_EQ(cloud.extra_properties.size(), 3u);
  EXPECT_EQ(cloud.extra_values, (std::vector<double>{255, 128, 0, 1, 2, 3}));

  // The same file cut in the middle of the face is truncated.
  write_file(directory.file("cut.ply"), content.substr(0, content.size() - 2));
  expect_io_error([&] { read_point_cloud(directory.file("cut.ply")); }, directory.file("cut.ply"),
                  "truncated file: element 'face' declares 1 rows, data end at row 0");
}

TEST(Point_cloud_io, ply_binary_big_endian_double_with_face_before_vertex)
{
  Temporary_directory directory;
  const std::string filename = directory.file("be.ply");
  Bytes bytes;
  bytes.big_endian = true;
  bytes.data = "ply\nformat binary_big_endian 1.0\ncomment faces first\n"
               "element face 2\nproperty list ushort uint vertex_indices\nproperty uchar flags\n"
               "element vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
               "property double nx\nproperty double ny\nproperty double nz\nproperty uint8 red\n"
               "property uint8 green\nproperty uint8 blue\n"
               "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  // faces: a triangle and a quad
  bytes << std::uint16_t(3) << std::uint32_t(0) << std::uint32_t(1) << std::uint32_t(0) << std::uint8_t(7);
  bytes << std::uint16_t(4) << std::uint32_t(1) << std::uint32_t(0) << std::uint32_t(1) << std::uint32_t(0)
        << std::uint8_t(9);
  // vertices
  bytes << 0.1 << -1e300 << 3.0 << 0.0 << 0.0 << -1.0 << std::uint8_t(10) << std::uint8_t(20) << std::uint8_t(30);
  bytes << 1.0 / 3 << 2.0 << -0.0 << 0.6 << 0.8 << 0.0 << std::uint8_t(0) << std::uint8_t(1) << std::uint8_t(255);
  // edge
  bytes << std::int32_t(0) << std::int32_t(1);
  write_file(filename, bytes.data);

  const Point_cloud cloud = read_point_cloud(filename);
  ASSERT_EQ(cloud.size(), 2u);
  ASSERT_TRUE(cloud.has_normals());
  EXPECT_EQ(cloud.points[0], (std::array<double, 3>{{0.1, -1e300, 3.0}}));
  EXPECT_EQ(cloud.points[1], (std::array<double, 3>{{1.0 / 3, 2.0, 0.0}}));
  EXPECT_EQ(cloud.normals[0], (std::array<double, 3>{{0, 0, -1}}));
  EXPECT_EQ(cloud.normals[1], (std::array<double, 3>{{0.6, 0.8, 0}}));
  EXPECT_EQ(cloud.extra_values, (std::vector<double>{10, 20, 30, 0, 1, 255}));
  EXPECT_EQ(cloud.point_types[1], Ply_scalar_type::FLOAT64);
  EXPECT_EQ(cloud.normal_types[1], Ply_scalar_type::FLOAT64);

  // Missing the last byte of the edge element: truncated.
  write_file(directory.file("cut.ply"), bytes.data.substr(0, bytes.data.size() - 1));
  expect_io_error([&] { read_point_cloud(directory.file("cut.ply")); }, directory.file("cut.ply"),
                  "truncated file");
}

TEST(Point_cloud_io, ply_every_scalar_type_in_both_endiannesses)
{
  Temporary_directory directory;
  for(bool big_endian : {false, true}) {
    Bytes bytes;
    bytes.big_endian = big_endian;
    bytes.data = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                 " 1.0\nelement vertex 2\n"
                 "property int16 x\nproperty int32 y\nproperty int8 z\n"
                 "property float32 nx\nproperty float64 ny\nproperty float nz\n"
                 "property char a\nproperty uchar b\nproperty short c\nproperty ushort d\n"
                 "property int e\nproperty uint f\nproperty float g\nproperty double h\nend_header\n";
    bytes << std::int16_t(-300) << std::int32_t(-70000) << std::int8_t(-5) << 0.5f << 0.25 << -1.0f;
    bytes << std::int8_t(-128) << std::uint8_t(255) << std::int16_t(-32768) << std::uint16_t(65535)
          << std::int32_t(-2147483647 - 1) << std::uint32_t(4294967295u) << 1.1f << 1.1;
    bytes << std::int16_t(32767) << std::int32_t(2147483647) << std::int8_t(127) << 0.f << 0.0 << 0.f;
    bytes << std::int8_t(127) << std::uint8_t(0) << std::int16_t(32767) << std::uint16_t(0)
          << std::int32_t(2147483647) << std::uint32_t(0) << -0.f << 1e-310;
    const std::string filename = directory.file(big_endian ? "be.ply" : "le.ply");
    write_file(filename, bytes.data);
    const Point_cloud cloud = read_point_cloud(filename);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.points[0], (std::array<double, 3>{{-300, -70000, -5}}));
    EXPECT_EQ(cloud.normals[0], (std::array<double, 3>{{0.5, 0.25, -1}}));
    EXPECT_EQ(cloud.points[1], (std::array<double, 3>{{32767, 2147483647, 127}}));
    EXPECT_EQ(cloud.point_types[0], Ply_scalar_type::INT16);
    EXPECT_EQ(cloud.point_types[1], Ply_scalar_type::INT32);
    EXPECT_EQ(cloud.point_types[2], Ply_scalar_type::INT8);
    EXPECT_EQ(cloud.normal_types[1], Ply_scalar_type::FLOAT64);
    ASSERT_EQ(cloud.extra_properties.size(), 8u);
    const std::vector<Ply_scalar_type> types = {Ply_scalar_type::INT8,   Ply_scalar_type::UINT8,
                                                Ply_scalar_type::INT16,  Ply_scalar_type::UINT16,
                                                Ply_scalar_type::INT32,  Ply_scalar_type::UINT32,
                                                Ply_scalar_type::FLOAT32, Ply_scalar_type::FLOAT64};
    for(std::size_t k = 0; k < types.size(); ++k) EXPECT_EQ(cloud.extra_properties[k].type, types[k]);
    const std::vector<double> expected = {-128, 255, -32768, 65535, -2147483648.0, 4294967295.0,
                                          static_cast<double>(1.1f), 1.1,
                                          127, 0, 32767, 0, 2147483647, 0, -0.0, 1e-310};
    EXPECT_EQ(cloud.extra_values, expected);
    EXPECT_TRUE(std::signbit(cloud.extra_values[14]));

    // Integer coordinates and float64 normals are written back with their types.
    write_point_cloud(directory.file("out.ply"), cloud);
    const Point_cloud again = read_point_cloud(directory.file("out.ply"));
    expect_same_points(cloud, again);
    expect_same_extras(cloud, again);
    EXPECT_EQ(again.point_types, cloud.point_types);
    EXPECT_EQ(again.normal_types, cloud.normal_types);
  }
}

// --------------------------------------------------------------------------- ply writing

TEST(Point_cloud_io, ply_extra_properties_round_trip)
{
  Temporary_directory directory;
  Point_cloud cloud = sample_cloud(true);
  add_extra_properties(cloud);
  for(bool binary : {true, false}) {
    Write_options options;
    options.binary = binary;
    const std::string first = directory.file(binary ? "first_binary.ply" : "first_ascii.ply");
    const std::string second = directory.file(binary ? "second_binary.ply" : "second_ascii.ply");
    write_point_cloud(first, cloud, options);
    const Point_cloud read = read_point_cloud(first);
    // Coordinates are doubles; normals are floats by default.
    EXPECT_EQ(read.point_types[0], Ply_scalar_type::FLOAT64);
    EXPECT_EQ(read.normal_types[0], Ply_scalar_type::FLOAT32);
    ASSERT_EQ(read.size(), cloud.size());
    for(std::size_t i = 0; i < cloud.size(); ++i) {
      EXPECT_EQ(read.points[i], cloud.points[i]);
      for(std::size_t c = 0; c < 3; ++c)
        EXPECT_EQ(read.normals[i][c], static_cast<double>(static_cast<float>(cloud.normals[i][c])));
    }
    expect_same_extras(cloud, read);
    // PLY -> Point_cloud -> PLY is stable, byte for byte.
    write_point_cloud(second, read, options);
    EXPECT_EQ(file_content(first), file_content(second));
    expect_same_extras(read, read_point_cloud(second));
  }
  // The header lists x y z, nx ny nz, then the extra properties in order.
  const std::string text = file_content(directory.file("first_ascii.ply"));
  const std::string header = text.substr(0, text.find("end_header"));
  EXPECT_NE(header.find("format ascii 1.0\ncomment generated by Normal_orientation\nelement vertex 51\n"
                        "property double x\nproperty double y\nproperty double z\n"
                        "property float nx\nproperty float ny\nproperty float nz\n"
                        "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                        "property int label\nproperty float quality\nproperty double density\n"
                        "property char flag\nproperty uint id\nproperty short s\nproperty ushort u\n"),
            std::string::npos)
    << header;
  EXPECT_NE(file_content(directory.file("first_binary.ply")).find("format binary_little_endian 1.0\n"),
            std::string::npos);
  EXPECT_FALSE(directory.has_temporary_file());
}

TEST(Point_cloud_io, ply_input_types_are_kept_on_output)
{
  Temporary_directory directory;
  write_file(directory.file("in.ply"), "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                       "property float y\nproperty float z\nproperty double nx\n"
                                       "property double ny\nproperty double nz\nproperty uchar alpha\n"
                                       "end_header\n0.1 0.2 0.3 0.6 0 0.8 7\n1 2 3 0 1 0 8\n");
  Point_cloud cloud = read_point_cloud(directory.file("in.ply"));
  cloud.normals[1] = {{0, -1, 0}}; // as the orientation would do
  write_point_cloud(directory.file("out.ply"), cloud);
  const std::string text = file_content(directory.file("out.ply"));
  EXPECT_NE(text.find("property float x\nproperty float y\nproperty float z\nproperty double nx\n"
                      "property double ny\nproperty double nz\nproperty uchar alpha\nend_header\n"),
            std::string::npos);
  // 2 vertices of 3 floats, 3 doubles, 1 uchar.
  EXPECT_EQ(text.size() - (text.find("end_header\n") + 11), 2u * (12 + 24 + 1));
  const Point_cloud read = read_point_cloud(directory.file("out.ply"));
  expect_same_points(cloud, read);
  expect_same_extras(cloud, read);

  // Integer-typed normals are written as float.
  Point_cloud integer_normals = cloud;
  integer_normals.normal_types = {{Ply_scalar_type::INT8, Ply_scalar_type::INT8, Ply_scalar_type::INT8}};
  integer_normals.normals[0] = {{0.6, 0, 0.8}};
  write_point_cloud(directory.file("floats.ply"), integer_normals);
  EXPECT_EQ(read_point_cloud(directory.file("floats.ply")).normal_types[0], Ply_scalar_type::FLOAT32);
}

TEST(Point_cloud_io, xyz_to_ply_and_back)
{
  Temporary_directory directory;
  Write_options exact;
  exact.precision = 0;
  const Point_cloud cloud = sample_cloud(true);
  write_point_cloud(directory.file("a.xyz"), cloud, exact);
  const Point_cloud from_xyz = read_point_cloud(directory.file("a.xyz"));
  write_point_cloud(directory.file("a.ply"), from_xyz);
  const Point_cloud from_ply = read_point_cloud(directory.file("a.ply"));
  ASSERT_EQ(from_ply.size(), cloud.size());
  for(std::size_t i = 0; i < cloud.size(); ++i) EXPECT_EQ(from_ply.points[i], cloud.points[i]);
  // Extra properties are dropped when writing .xyz.
  Point_cloud with_extras = cloud;
  add_extra_properties(with_extras);
  write_point_cloud(directory.file("b.xyz"), with_extras, exact);
  const Point_cloud b = read_point_cloud(directory.file("b.xyz"));
  EXPECT_TRUE(b.extra_properties.empty());
  expect_same_points(cloud, b);
}

// --------------------------------------------------------------------------- errors

TEST(Point_cloud_io, missing_file_and_unknown_extension)
{
  Temporary_directory directory;
  const std::string missing = directory.file("missing.xyz");
  expect_io_error([&] { read_point_cloud(missing); }, missing, "cannot open file for reading");
  const std::string missing_ply = directory.file("missing.ply");
  expect_io_error([&] { read_point_cloud(missing_ply); }, missing_ply, "No such file");
  const std::string text = directory.file("cloud.txt");
  write_file(text, "1 2 3\n");
  expect_io_error([&] { read_point_cloud(text); }, text, "unknown point cloud file extension '.txt'");
  const std::string no_extension = directory.file("cloud");
  write_file(no_extension, "1 2 3\n");
  expect_io_error([&] { read_point_cloud(no_extension); }, no_extension, "unknown point cloud file extension");
  expect_io_error([&] { write_point_cloud(directory.file("out.off"), sample_cloud(false)); },
                  directory.file("out.off"), "unknown point cloud file extension '.off'");
  fs::create_directory(directory.file("dir.xyz"));
  expect_io_error([&] { read_point_cloud(directory.file("dir.xyz")); }, directory.file("dir.xyz"),
                  "directory");
  EXPECT_EQ(directory.listing(), (std::vector<std::string>{"cloud", "cloud.txt", "dir.xyz"}));
}

TEST(Point_cloud_io, xyz_errors)
{
  Temporary_directory directory;
  expect_read_error(directory, "four.xyz", "1 2 3\n1 2 3 4\n", "wrong column count at line 2: 4 values");
  expect_read_error(directory, "two.xyz", "# x y z\n1 2\n", "wrong column count at line 2: 2 values");
  expect_read_error(directory, "seven.xyz", "1 2 3 4 5 6 7\n", "wrong column count at line 1: 7 values");
  expect_read_error(directory, "mixed.xyz", "1 2 3\n\n1 2 3 0 0 1\n",
                    "wrong column count at line 3: 6 values, but line 1 has 3");
  expect_read_error(directory, "short.xyz", "1 2 3 0 0 1\n1 2 3 0 0", "wrong column count at line 2: 5 values");
  expect_read_error(directory, "token.xyz", "1 2 3\n1 2 abc\n", "non-numeric token 'abc' at line 2");
  expect_read_error(directory, "comma.xyz", "1,2,3\n", "non-numeric token '1,2,3' at line 1");
  expect_read_error(directory, "sign.xyz", "1 2 ++3\n", "non-numeric token '++3' at line 1");
  expect_read_error(directory, "trailing.xyz", "1 2 3 # comment\n", "non-numeric token '#' at line 1");
  expect_read_error(directory, "nan.xyz", "1 2 3\n4 5 6\nnan 0 0\n", "non-finite coordinate at line 3");
  expect_read_error(directory, "inf.xyz", "1 2 -inf\n", "non-finite coordinate at line 1");
  expect_read_error(directory, "huge.xyz", "1 2 1e999\n", "out of range at line 1");
  expect_read_error(directory, "normal.xyz", "1 2 3 0 0 1\n1 2 3 0 inf 1\n", "non-finite normal at line 2");
}

TEST(Point_cloud_io, ply_header_errors)
{
  Temporary_directory directory;
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  expect_read_error(directory, "magic.ply", "plyx\nformat ascii 1.0\n", "not a PLY file");
  expect_read_error(directory, "format.ply", "ply\nformat text 1.0\nend_header\n", "bad PLY header at line 2");
  expect_read_error(directory, "version.ply", "ply\nformat ascii 2.0\nend_header\n", "unsupported PLY version");
  expect_read_error(directory, "no_format.ply", "ply\nelement vertex 0\n" + xyz + "end_header\n",
                    "no 'format' line");
  expect_read_error(directory, "no_end.ply", "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz,
                    "no 'end_header' line");
  expect_read_error(directory, "keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 0\nend_header\n",
                    "bad PLY header at line 3: unknown keyword 'elemnt'");
  expect_read_error(directory, "type.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty real x\nend_header\n",
                    "bad PLY header at line 4: unknown type 'real'");
  expect_read_error(directory, "count.ply", "ply\nformat ascii 1.0\nelement vertex -1\n" + xyz + "end_header\n",
                    "bad PLY header at line 3: invalid element count '-1'");
  expect_read_error(directory, "orphan.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
                    "'property' before any 'element'");
  expect_read_error(directory, "no_vertex.ply", "ply\nformat ascii 1.0\nelement face 0\nend_header\n",
                    "no 'vertex' element");
  expect_read_error(directory, "no_z.ply",
                    "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
                    "element 'vertex' has no property 'z'");
  expect_read_error(directory, "partial_normal.ply",
                    "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz + "property float nx\nend_header\n",
                    "all of 'nx ny nz' or none");
  expect_read_error(directory, "duplicate.ply",
                    "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz + "property float x\nend_header\n",
                    "bad PLY header at line 7: second property 'x'");
  expect_read_error(directory, "list.ply",
                    "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz +
                      "property list uchar int neighbours\nend_header\n",
                    "list property 'neighbours' in element 'vertex' is not supported");
  expect_read_error(directory, "float_count.ply",
                    "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz +
                      "element face 0\nproperty list float int vertex_indices\nend_header\n",
                    "count type of a list must be an integer type");
}

TEST(Point_cloud_io, ply_data_errors)
{
  Temporary_directory directory;
  const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                            "property float z\nproperty uchar red\nend_header\n";
  expect_read_error(directory, "truncated_ascii.ply", ascii + "1 2 3 4\n5 6 7 8\n",
                    "truncated file: 3 vertices declared, data end at vertex 2");
  expect_read_error(directory, "short_line.ply", ascii + "1 2 3 4\n5 6 7\n8 9 1 2\n",
                    "short line: 3 values instead of 4 at line 10");
  expect_read_error(directory, "long_line.ply", ascii + "1 2 3 4\n5 6 7 8 9\n8 9 1 2\n",
                    "too many values: expected 4 at line 10");
  expect_read_error(directory, "token.ply", ascii + "1 2 3 4\n5 six 7 8\n8 9 1 2\n",
                    "non-numeric token 'six' at line 10");
  expect_read_error(directory, "nan.ply", ascii + "1 2 3 4\n5 6 7 8\n8 NaN 1 2\n",
                    "non-finite coordinate at line 11");
  expect_read_error(directory, "colour.ply", ascii + "1 2 3 4\n5 6 7 256\n8 9 1 2\n",
                    "value '256' out of range for property 'red' of type uchar at line 10");
  expect_read_error(directory, "fraction.ply", ascii + "1 2 3 4\n5 6 7 2.5\n8 9 1 2\n", "out of range");
  expect_read_error(directory, "truncated_face.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                    "1 2 3\n3 0 0 0\n",
                    "truncated file: element 'face' declares 2 rows, data end at row 1");

  // Binary: 3 vertices declared, 2.5 present.
  Bytes bytes;
  bytes.data = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
               "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n";
  bytes << 1.f << 2.f << 3.f << 0.f << 0.f << 1.f;
  bytes << 4.f << 5.f << 6.f << 0.f << 0.f << 0.f; // zero normal: allowed
  const std::string good = bytes.data;
  bytes << 7.f << 8.f << 9.f;
  expect_read_error(directory, "truncated_binary.ply", bytes.data,
                    "truncated file: 3 vertices declared, data end at vertex 2");
  bytes << std::numeric_limits<float>::quiet_NaN() << 0.f << 0.f;
  const std::string nan_normal = bytes.data;
  expect_read_error(directory, "nan_normal.ply", nan_normal, "non-finite normal at vertex 2");
  Bytes infinite;
  infinite.data = good;
  infinite << 7.f << std::numeric_limits<float>::infinity() << 9.f << 0.f << 0.f << 1.f;
  expect_read_error(directory, "inf_binary.ply", infinite.data, "non-finite coordinate at vertex 2");
  Bytes fine;
  fine.data = good;
  fine << 7.f << 8.f << 9.f << 0.f << 0.f << 1.f;
  write_file(directory.file("fine.ply"), fine.data);
  EXPECT_EQ(read_point_cloud(directory.file("fine.ply")).size(), 3u);
}

// --------------------------------------------------------------------------- atomic writing

TEST(Point_cloud_io, write_to_missing_directory_throws_and_leaves_nothing)
{
  Temporary_directory directory;
  const Point_cloud cloud = sample_cloud(true);
  for(const char* name : {"no/such/dir/out.xyz", "no/such/dir/out.ply"}) {
    const std::string filename = directory.file(name);
    expect_io_error([&] { write_point_cloud(filename, cloud); }, filename, "cannot create temporary file");
  }
  EXPECT_TRUE(directory.listing().empty());
}

TEST(Point_cloud_io, failed_write_keeps_existing_file)
{
  Temporary_directory directory;
  const std::string filename = directory.file("out.ply");
  write_file(filename, "previous content");

  // A value that does not fit its type is detected in the middle of the data.
  Point_cloud cloud = sample_cloud(false);
  add_extra_properties(cloud);
  cloud.extra_values[40 * cloud.extra_properties.size()] = 256; // red of vertex 40
  for(bool binary : {true, false}) {
    Write_options options;
    options.binary = binary;
    expect_io_error([&] { write_point_cloud(filename, cloud, options); }, filename,
                    "cannot write value 256 of property 'red' at vertex 40 as uchar");
  }
  // Inconsistent clouds.
  Point_cloud bad_normals = sample_cloud(true);
  bad_normals.normals.pop_back();
  expect_io_error([&] { write_point_cloud(filename, bad_normals); }, filename, "normals for");
  Point_cloud bad_extras = sample_cloud(false);
  add_extra_properties(bad_extras);
  bad_extras.extra_values.pop_back();
  expect_io_error([&] { write_point_cloud(filename, bad_extras); }, filename, "extra values for");
  Point_cloud reserved_name = sample_cloud(false);
  reserved_name.extra_properties.push_back({"nx", Ply_scalar_type::FLOAT32});
  reserved_name.extra_values.assign(reserved_name.size(), 0.0);
  expect_io_error([&] { write_point_cloud(filename, reserved_name); }, filename, "extra property named 'nx'");
  Point_cloud not_finite = sample_cloud(true);
  not_finite.points[3][1] = std::numeric_limits<double>::quiet_NaN();
  expect_io_error([&] { write_point_cloud(directory.file("out.xyz"), not_finite); }, directory.file("out.xyz"),
                  "non-finite coordinate at vertex 3");

  EXPECT_EQ(file_content(filename), "previous content");
  EXPECT_EQ(directory.listing(), std::vector<std::string>{"out.ply"});

  // A target that is a directory cannot be replaced.
  fs::create_directory(directory.file("dir.ply"));
  expect_io_error([&] { write_point_cloud(directory.file("dir.ply"), sample_cloud(false)); },
                  directory.file("dir.ply"), "cannot rename");
  EXPECT_EQ(directory.listing(), (std::vector<std::string>{"dir.ply", "out.ply"}));
}

TEST(Point_cloud_io, writing_never_leaves_temporary_files)
{
  Temporary_directory directory;
  Point_cloud cloud = sample_cloud(true);
  add_extra_properties(cloud);
  Write_options ascii;
  ascii.binary = false;
  write_point_cloud(directory.file("a.xyz"), cloud);
  write_point_cloud(directory.file("a.xyz"), cloud); // overwrite
  write_point_cloud(directory.file("b.ply"), cloud);
  write_point_cloud(directory.file("b.ply"), cloud, ascii);
  write_point_cloud(directory.file("c.pwn"), cloud);
  EXPECT_EQ(directory.listing(), (std::vector<std::string>{"a.xyz", "b.ply", "c.pwn"}));
  EXPECT_NE(file_content(directory.file("b.ply")).find("format ascii 1.0"), std::string::npos);
  EXPECT_FALSE(directory.has_temporary_file());
}

// --------------------------------------------------------------------------- streaming

namespace {

using Normal_orientation::IO::Point_stream_reader;
using Normal_orientation::IO::Point_stream_write_options;
using Normal_orientation::IO::Point_stream_writer;
using Normal_orientation::Point_record;

/// \brief All the records of `reader`, read `chunk_size` at a time.
std::vector<Point_record> read_stream(Point_stream_reader& reader, std::size_t chunk_size)
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
void expect_records_of_cloud(const std::vector<Point_record>& records, const Point_cloud& cloud,
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
std::string streaming_ply(const std::string& format, bool double_points, bool normals, std::size_t n,
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
std::string stream_error(const std::string& filename,
                         std::size_t buffer_size = Point_stream_reader::default_buffer_size)
{
  return error_message([&] {
    Point_stream_reader reader(filename, buffer_size);
    std::vector<Point_record> chunk;
    while(reader.read(chunk, 3) != 0) chunk.clear();
  });
}

/// \brief Records with awkward values, whose indices are not 0, 1, ...
std::vector<Point_record> awkward_records()
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

} // namespace

TEST(Point_stream, reads_what_read_point_cloud_reads)
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

TEST(Point_stream, reading_errors_name_the_file_and_the_place)
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

TEST(Point_stream, writer_round_trip)
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

TEST(Point_stream, uncommitted_or_failed_writer_leaves_no_file)
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

TEST(Point_stream, reader_memory_does_not_grow_with_the_file)
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

TEST(Input_validation, empty_files)
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

TEST(Input_validation, vertex_count_larger_than_the_file)
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

TEST(Input_validation, binary_errors_name_the_byte_offset)
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

TEST(Input_validation, garbage_after_the_header)
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

TEST(Input_validation, control_characters_in_messages_are_escaped)
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

TEST(Input_validation, ascii_ply_float_values_are_the_nearest_floats)
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

TEST(Input_validation, ascii_ply_integer_minus_zero_is_zero)
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

TEST(Input_validation, integer_normals_are_written_exactly)
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

TEST(Input_validation, unreadable_input_and_unwritable_output)
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

namespace {

/// \brief Checks the values of `a` and `b`, extra values included, bit for bit.
void expect_same_bits(const Point_cloud& a, const Point_cloud& b, const std::string& what)
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

} // namespace

// Each input that made a fuzz target (fuzz/) fail is kept in test/data/regressions/
// (see the README there) and read here, in core and streamed: a clean error (one
// printable line naming the file), or a cloud that satisfies the reader's contract and
// comes back unchanged from the files the writers write.
TEST(Input_validation, fuzzer_regressions)
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

// --------------------------------------------------------------------------- transcoding

namespace {

using Normal_orientation::IO::Bit_set;
using Normal_orientation::IO::Transcode_options;
using Normal_orientation::IO::Transcode_report;
using Normal_orientation::IO::transcode_with_flips;

/// \brief A PLY file for the transcoding tests: `n` vertices with properties
/// `x y z red green blue nx ny nz intensity` (`uchar` colours, `float32` intensity) of
/// the given types, in `format`; with `other_elements`, an element `camera` before
/// `vertex` and an element `face` (with lists) after it. ASCII values are written in
/// various forms (shortest, with a `+`, with a trailing zero), with tabs, blank lines and
/// CRLF line ends here and there. Integer normals take the most negative value of their
/// type at every 50th vertex and 0 at the next one.
struct Transcode_ply
{
  std::string format = "binary_little_endian";
  std::string point_type = "float";
  std::array<std::string, 3> normal_types{{"double", "double", "double"}};
  bool other_elements = false;

  std::string make(std::size_t n) const
  {
    const bool ascii = format == "ascii";
    std::string header = "ply\nformat " + format + " 1.0\ncomment transcoding test\n";
    if(other_elements) header += "element camera 2\nproperty float fov\nproperty uchar id\n";
    header += "obj_info scanner 7\nelement vertex " + std::to_string(n) + "\n";
    for(const char* name : {"x", "y", "z"}) header += "property " + point_type + " " + name + "\n";
    header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    for(std::size_t c = 0; c < 3; ++c) header += "property " + normal_types[c] + " " + "n" + "xyz"[c] + "\n";
    header += "property float32 intensity\n";
    if(other_elements) header += "element face " + std::to_string(n / 2) + "\nproperty list uchar int vertex_indices\n";
    header += "comment end of the header\nend_header\n";
    Bytes bytes;
    bytes.big_endian = format == "binary_big_endian";
    bytes.data = header;
    std::size_t value_count = 0;
    auto separator = [&](std::size_t i) {
      if(ascii && value_count++ != 0) bytes.data += (i % 9 == 4) ? "\t " : " ";
    };
    auto put = [&](const std::string& type, double v, std::size_t i) {
      separator(i);
      if(ascii) {
        std::string text = type == "float" || type == "float32" ? shortest_text(static_cast<float>(v))
                           : type == "double"                    ? shortest_text(v)
                                                                 : std::to_string(static_cast<long long>(v));
        if(i % 3 == 1 && v >= 0) text = "+" + text;
        if(i % 5 == 2 && text.find('.') != std::string::npos && text.find('e') == std::string::npos) text += "0";
        bytes.data += text;
        return;
      }
      if(type == "float" || type == "float32") bytes << static_cast<float>(v);
      else if(type == "double") bytes << v;
      else if(type == "uchar") bytes << static_cast<std::uint8_t>(v);
      else if(type == "char") bytes << static_cast<std::int8_t>(v);
      else if(type == "short") bytes << static_cast<std::int16_t>(v);
      else if(type == "ushort") bytes << static_cast<std::uint16_t>(v);
      else if(type == "int") bytes << static_cast<std::int32_t>(v);
      else ADD_FAILURE() << "type " << type;
    };
    auto end_row = [&](std::size_t i) {
      value_count = 0;
      if(ascii) bytes.data += (i % 7 == 3) ? "\r\n" : (i % 100 == 50) ? "\n \n" : "\n";
    };
    if(other_elements)
      for(std::size_t i = 0; i < 2; ++i) {
        put("float", 0.5 + static_cast<double>(i), i);
        put("uchar", static_cast<double>(i), i);
        end_row(i);
      }
    for(std::size_t i = 0; i < n; ++i) {
      const double t = static_cast<double>(i);
      for(std::size_t c = 0; c < 3; ++c) put(point_type, std::sin(t * 0.37 + static_cast<double>(c)) * 100.0 + t * 1e-3, i);
      for(std::size_t c = 0; c < 3; ++c) put("uchar", static_cast<double>((i * 7 + c * 91) % 256), i);
      for(std::size_t c = 0; c < 3; ++c) {
        const std::string& type = normal_types[c];
        double v = std::cos(t * 0.11 + static_cast<double>(c) * 2.0);
        if(type == "ushort") {
          v = std::round((v + 1.0) * 30000.0);
        } else if(type == "char" || type == "short" || type == "int") {
          const double scale = type == "char" ? 127 : type == "short" ? 32767 : 2147483647.0;
          v = std::round(v * scale);
          if(i % 50 == 7) v = -scale - 1;
          if(i % 50 == 8) v = 0;
        } else if(i % 50 == 8) {
          v = 0.0;
        }
        put(type, v, i);
      }
      put("float32", t / 7.0, i);
      end_row(i);
    }
    if(other_elements)
      for(std::size_t f = 0; f < n / 2; ++f) {
        if(ascii) {
          bytes.data += "3 " + std::to_string(f) + " " + std::to_string(f + 1) + " " + std::to_string((f + 2) % n) + "\n";
        } else {
          bytes << static_cast<std::uint8_t>(3) << static_cast<std::int32_t>(f) << static_cast<std::int32_t>(f + 1)
                << static_cast<std::int32_t>((f + 2) % n);
        }
      }
    return bytes.data;
  }
};

/// \brief `n` bits, each set with probability `p`.
Bit_set random_bits(std::size_t n, double p, unsigned seed)
{
  std::mt19937_64 random(seed);
  std::bernoulli_distribution draw(p);
  Bit_set set(n);
  for(std::size_t i = 0; i < n; ++i)
    if(draw(random)) set.set(i);
  return set;
}

/// \brief The cloud that transcoding the file of `cloud` with `flip` and `keep` must
/// give: the points kept, in order, with every property, and the normals of the points
/// of `flip` negated (an integer 0 stays 0, the most negative integer becomes the largest).
Point_cloud expected_transcoding(const Point_cloud& cloud, const Bit_set& flip, const Bit_set* keep)
{
  Point_cloud expected = cloud;
  expected.points.clear();
  expected.normals.clear();
  expected.extra_values.clear();
  const std::size_t extras = cloud.extra_properties.size();
  for(std::size_t i = 0; i < cloud.size(); ++i) {
    if(keep != nullptr && !keep->test(i)) continue;
    expected.points.push_back(cloud.points[i]);
    expected.extra_values.insert(expected.extra_values.end(), cloud.extra_values.begin() + std::ptrdiff_t(i * extras),
                                 cloud.extra_values.begin() + std::ptrdiff_t((i + 1) * extras));
    if(!cloud.has_normals()) continue;
    std::array<double, 3> normal = cloud.normals[i];
    if(flip.test(i))
      for(std::size_t c = 0; c < 3; ++c) {
        const Ply_scalar_type type = cloud.normal_types[c];
        if(type == Ply_scalar_type::FLOAT32 || type == Ply_scalar_type::FLOAT64) {
          normal[c] = -normal[c];
          continue;
        }
        const auto range = Normal_orientation::IO::internal::integer_range(type);
        normal[c] = normal[c] == 0.0 ? 0.0 : normal[c] == range.first ? range.second : -normal[c];
      }
    expected.normals.push_back(normal);
  }
  return expected;
}

/// \brief Transcodes `input` to `output` with `flip` and `keep` and checks, reading both
/// in core, that the output is the expected transcoding, bit for bit, property types and
/// digits included, and that the report counts what was done.
Transcode_report expect_transcoding(const std::string& input, const std::string& output, const Bit_set& flip,
                                    const Bit_set* keep, std::size_t buffer_size = Point_stream_reader::default_buffer_size)
{
  Transcode_options options;
  options.buffer_size = buffer_size;
  const Transcode_report report = transcode_with_flips(input, output, flip, keep, options);
  const Point_cloud cloud = read_point_cloud(input);
  const Point_cloud expected = expected_transcoding(cloud, flip, keep);
  const Point_cloud written = read_point_cloud(output);
  const std::string what = input + " with a buffer of " + std::to_string(buffer_size);
  expect_same_bits(expected, written, what);
  expect_same_extras(expected, written);
  EXPECT_EQ(written.point_types, cloud.point_types) << what;
  EXPECT_EQ(written.normal_types, cloud.normal_types) << what;
  if(keep == nullptr) { // the digits of the values written: those of the input
    EXPECT_EQ(written.point_digits, cloud.point_digits) << what;
    EXPECT_EQ(written.normal_digits, cloud.normal_digits) << what;
  }
  EXPECT_EQ(report.number_of_points, cloud.size()) << what;
  EXPECT_EQ(report.number_of_written_points, expected.size()) << what;
  EXPECT_EQ(report.number_of_dropped_points, cloud.size() - expected.size()) << what;
  std::uint64_t flipped = 0;
  for(std::size_t i = 0; i < cloud.size(); ++i) flipped += flip.test(i) && (keep == nullptr || keep->test(i));
  EXPECT_EQ(report.number_of_flipped, cloud.has_normals() ? flipped : 0u) << what;
  EXPECT_EQ(report.bytes_written, fs::file_size(output)) << what;
  return report;
}

/// \brief Checks that `action` throws `Exception` with a message containing `expected`.
template <class Exception>
void expect_exception(const std::function<void()>& action, const std::string& expected)
{
  try {
    action();
    ADD_FAILURE() << "no exception thrown, expected '" << expected << "'";
  } catch(const Exception& error) {
    EXPECT_NE(std::string(error.what()).find(expected), std::string::npos) << error.what();
  } catch(const std::exception& error) {
    ADD_FAILURE() << "unexpected exception: " << error.what();
  }
}

} // namespace

TEST(Transcode, bit_set)
{
  Bit_set set;
  EXPECT_TRUE(set.empty());
  EXPECT_FALSE(set.any());
  EXPECT_TRUE(set.all());
  EXPECT_FALSE(set.test(0));
  set.resize(70);
  EXPECT_EQ(set.size(), 70u);
  EXPECT_EQ(set.count(), 0u);
  set.set(0);
  set.set(63);
  set.set(64);
  set.set(69);
  EXPECT_TRUE(set.test(63) && set.test(64) && set.test(69) && !set.test(1) && !set.test(70));
  EXPECT_EQ(set.count(), 4u);
  set.reset(63);
  EXPECT_FALSE(set.test(63));
  EXPECT_THROW(set.set(70), std::out_of_range);
  // Growing with set bits, across words; shrinking clears the bits beyond the size.
  set.resize(200, true);
  EXPECT_EQ(set.count(), 3u + 130u);
  EXPECT_TRUE(set.test(70) && set.test(199) && !set.test(200) && !set.test(65));
  set.resize(100);
  EXPECT_EQ(set.count(), 3u + 30u);
  EXPECT_EQ(set.words().size(), 2u);
  EXPECT_EQ(set.words()[1] >> 36, 0u); // bits 100..127 are clear
  set.resize(128);
  EXPECT_EQ(set.count(), 33u);
  EXPECT_FALSE(set.test(100));
  set.assign_all(true);
  EXPECT_TRUE(set.all());
  EXPECT_EQ(set.count(), 128u);
  EXPECT_EQ(Bit_set(5, true), Bit_set(5, true));
  EXPECT_NE(Bit_set(5, true), Bit_set(6, true));
  EXPECT_NE(Bit_set(5, true), Bit_set(5, false));
  const Bit_set ones(1000, true);
  EXPECT_EQ(ones.count(), 1000u);
  EXPECT_EQ(random_bits(1000, 0.5, 1).count(), random_bits(1000, 0.5, 1).count());
}

TEST(Transcode, the_reader_gives_the_ply_layout)
{
  Temporary_directory directory;
  write_file(directory.file("cloud.xyz"), "1 2 3\n");
  EXPECT_FALSE(Normal_orientation::IO::internal::ply_layout(Point_stream_reader(directory.file("cloud.xyz"))).has_value());
  Transcode_ply spec;
  spec.format = "binary_big_endian";
  spec.other_elements = true;
  spec.normal_types = {{"double", "short", "float"}};
  const std::string content = spec.make(10);
  write_file(directory.file("cloud.ply"), content);
  Point_stream_reader reader(directory.file("cloud.ply"));
  EXPECT_EQ(reader.file_size(), content.size());
  const auto layout = Normal_orientation::IO::internal::ply_layout(reader);
  ASSERT_TRUE(layout.has_value());
  EXPECT_EQ(layout->format, Normal_orientation::IO::internal::Ply_format::BINARY_BIG_ENDIAN);
  ASSERT_EQ(layout->elements.size(), 3u);
  EXPECT_EQ(layout->vertex_element, 1u);
  EXPECT_EQ(layout->roles, std::vector<std::size_t>({0, 1, 2, 6, 7, 8, 3, 4, 5, 9}));
  EXPECT_EQ(layout->offsets, std::vector<std::size_t>({0, 4, 8, 12, 13, 14, 15, 23, 25, 29}));
  EXPECT_EQ(layout->row_size, 33u);
  EXPECT_EQ(layout->header_size, content.find("end_header\n") + 11);
  EXPECT_EQ(layout->vertex_data_offset, layout->header_size + 2 * 5); // two cameras of 5 bytes
}

TEST(Transcode, binary_ply_round_trips_with_extra_properties)
{
  Temporary_directory directory;
  std::vector<Transcode_ply> specs;
  for(const std::string format : {"binary_little_endian", "binary_big_endian"}) {
    Transcode_ply spec;
    spec.format = format;
    specs.push_back(spec); // float points, double normals
    spec.point_type = "double";
    spec.normal_types = {{"float", "float", "float"}};
    specs.push_back(spec);
    spec.normal_types = {{"char", "short", "int"}};
    specs.push_back(spec);
    spec.other_elements = true;
    spec.normal_types = {{"float", "double", "float"}};
    specs.push_back(spec);
  }
  const std::size_t n = 3001;
  int file = 0;
  for(const Transcode_ply& spec : specs) {
    const std::string input = directory.file("in" + std::to_string(file++) + ".ply");
    write_file(input, spec.make(n));
    SCOPED_TRACE(input + ": " + spec.format + ", normals " + spec.normal_types[0] + " " + spec.normal_types[1] + " " +
                 spec.normal_types[2]);
    const std::string output = directory.file("out.ply");
    for(std::size_t buffer_size : {Point_stream_reader::default_buffer_size, std::size_t(0)}) {
      const Bit_set flip = random_bits(n, 0.5, 7);
      const Bit_set keep = random_bits(n, 0.8, 8);
      expect_transcoding(input, output, flip, &keep, buffer_size);
      expect_transcoding(input, output, flip, nullptr, buffer_size);
      const Transcode_report report = expect_transcoding(input, output, Bit_set(n, true), nullptr, buffer_size);
      const bool integers = spec.normal_types[0] == "char";
      EXPECT_EQ(report.number_of_saturated_values, integers ? 3u * ((n + 42) / 50) : 0u);
      EXPECT_EQ(report.dropped_elements,
                spec.other_elements ? std::vector<std::string>({"camera", "face"}) : std::vector<std::string>());
      // The header: the input's, with the count of the points kept.
      const std::string header = file_content(output).substr(0, file_content(output).find("end_header\n"));
      EXPECT_NE(header.find("comment transcoding test\nobj_info scanner 7\nelement vertex " + std::to_string(n) + "\n"),
                std::string::npos);
      EXPECT_NE(header.find("property float32 intensity\ncomment end of the header\n"), std::string::npos) << header;
      expect_transcoding(input, output, Bit_set(), &keep, buffer_size);
      EXPECT_NE(file_content(output).find("element vertex " + std::to_string(keep.count()) + "\n"), std::string::npos);
    }
    // Nothing kept: a valid file of no point.
    const Bit_set none(n);
    expect_transcoding(input, output, Bit_set(), &none);
    EXPECT_NE(file_content(output).find("element vertex 0\n"), std::string::npos);
  }
  EXPECT_FALSE(directory.has_temporary_file());
}

TEST(Transcode, binary_normals_are_negated_in_their_own_type)
{
  Temporary_directory directory;
  // Every value of every normal type, flipped: floats by their sign bit (zeros, the
  // smallest subnormal, the largest values), integers exactly, their most negative
  // value saturated to the largest one.
  for(bool big_endian : {false, true}) {
    Bytes bytes;
    bytes.big_endian = big_endian;
    bytes.data = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                 " 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                 "property double nx\nproperty float ny\nproperty short nz\nproperty char c\nend_header\n";
    const double doubles[] = {0.0, -0.0, 5e-324, -std::numeric_limits<double>::max(), 0.1, -1.0};
    const float floats[] = {-0.0f, 0.0f, std::numeric_limits<float>::max(), 1e-45f, -0.25f, 1.0f};
    const std::int16_t shorts[] = {-32768, 32767, 0, -1, 1, -32767};
    for(int i = 0; i < 6; ++i)
      bytes << float(i) << 0.f << 0.f << doubles[i] << floats[i] << shorts[i] << std::int8_t(-128);
    const std::string input = directory.file(big_endian ? "be.ply" : "le.ply");
    write_file(input, bytes.data);
    const Transcode_report report =
      transcode_with_flips(input, directory.file("out.ply"), Bit_set(6, true), nullptr, Transcode_options());
    EXPECT_EQ(report.number_of_saturated_values, 1u);
    const Point_cloud back = read_point_cloud(directory.file("out.ply"));
    ASSERT_EQ(back.size(), 6u);
    const std::int16_t negated_shorts[] = {32767, -32767, 0, 1, -1, 32767};
    for(int i = 0; i < 6; ++i) {
      EXPECT_EQ(bits(back.normals[i][0]), bits(-doubles[i])) << i;
      EXPECT_EQ(bits(back.normals[i][1]), bits(static_cast<double>(-floats[i]))) << i;
      EXPECT_EQ(back.normals[i][2], negated_shorts[i]) << i;
      EXPECT_EQ(back.extra_values[i], -128.0) << i; // not a normal: kept
    }
  }
}

TEST(Transcode, ascii_ply_keeps_the_text_of_every_other_value)
{
  Temporary_directory directory;
  std::vector<Transcode_ply> specs;
  Transcode_ply spec;
  spec.format = "ascii";
  specs.push_back(spec);
  spec.point_type = "double";
  spec.normal_types = {{"float", "float", "double"}};
  spec.other_elements = true;
  specs.push_back(spec);
  spec.normal_types = {{"char", "short", "int"}};
  specs.push_back(spec);
  const std::size_t n = 2003;
  int file = 0;
  for(const Transcode_ply& s : specs) {
    const std::string input = directory.file("in" + std::to_string(file++) + ".ply");
    write_file(input, s.make(n));
    SCOPED_TRACE(input);
    const std::string output = directory.file("out.ply");
    for(std::size_t buffer_size : {Point_stream_reader::default_buffer_size, std::size_t(0)}) {
      const Bit_set flip = random_bits(n, 0.5, 11);
      const Bit_set keep = random_bits(n, 0.7, 12);
      expect_transcoding(input, output, flip, &keep, buffer_size);
      const Transcode_report report = expect_transcoding(input, output, Bit_set(n, true), nullptr, buffer_size);
      EXPECT_EQ(report.number_of_saturated_values, s.normal_types[0] == "char" ? 3u * ((n + 42) / 50) : 0u);
    }
    // Line by line: only the signs of the normal values changed, their digits did not.
    const Bit_set flip = random_bits(n, 0.5, 13);
    transcode_with_flips(input, output, flip);
    const std::string in_text = file_content(input);
    const std::string out_text = file_content(output);
    std::size_t p = in_text.find("end_header\n");
    std::size_t q = out_text.find("end_header\n");
    for(std::size_t line = 0; line < (s.other_elements ? 2u : 0u); ++line) p = in_text.find('\n', p) + 1; // camera
    std::size_t row = 0;
    for(p = in_text.find('\n', p) + 1, q = out_text.find('\n', q) + 1; row < n;) {
      const std::size_t p_end = in_text.find('\n', p) + 1;
      const std::size_t q_end = out_text.find('\n', q) + 1;
      std::string a = in_text.substr(p, p_end - p);
      const std::string b = out_text.substr(q, q_end - q);
      p = p_end;
      q = q_end;
      if(a.find_first_not_of(" \t\r\n") == std::string::npos) {
        EXPECT_EQ(a, b);
        continue;
      }
      if(flip.test(row) && s.normal_types[0] != "char") {
        // the 7th, 8th and 9th values lose or gain a '-' (and lose a '+')
        std::vector<std::size_t> starts;
        for(std::size_t k = 0; k < a.size(); ++k)
          if(a[k] != ' ' && a[k] != '\t' && (k == 0 || a[k - 1] == ' ' || a[k - 1] == '\t')) starts.push_back(k);
        ASSERT_EQ(starts.size(), 10u) << a;
        for(std::size_t t = 9; t-- > 6;) {
          std::size_t k = starts[t];
          if(a[k] == '+') a.erase(k, 1);
          if(a[k] == '-') a.erase(k, 1);
          else a.insert(k, "-");
        }
      }
      if(!flip.test(row) || s.normal_types[0] != "char") {
        EXPECT_EQ(a, b) << "row " << row;
      }
      ++row;
    }
    if(!s.other_elements) {
      EXPECT_EQ(out_text.substr(q), in_text.substr(p)); // the end, as it is
    } else {
      EXPECT_EQ(q, out_text.size()); // the faces are left out
    }
  }
  // Integer normals: "+-5" is -5 for the reader, "0" stays "0", "-128" becomes "127".
  const std::string input = directory.file("integers.ply");
  write_file(input, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "property char nx\nproperty int ny\nproperty short nz\nend_header\n"
                    "1 2 3 +-5 0 -32768\n4 5 6 -128 +7 -0\n7 8 9 5.0 -2147483648 +0\n\n");
  const Transcode_report report = transcode_with_flips(input, directory.file("integers_out.ply"), Bit_set(3, true));
  EXPECT_EQ(report.number_of_saturated_values, 3u);
  EXPECT_EQ(file_content(directory.file("integers_out.ply")),
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "property char nx\nproperty int ny\nproperty short nz\nend_header\n"
            "1 2 3 5 0 32767\n4 5 6 127 -7 -0\n7 8 9 -5.0 2147483647 +0\n\n");
}

TEST(Transcode, xyz_keeps_comments_blank_lines_and_digits)
{
  Temporary_directory directory;
  // Six columns: comments, blank lines, CRLF line ends, tabs, every number form.
  const std::string input = directory.file("normals.xyz");
  const std::string long_comment = "#" + std::string(10000, 'c') + "\n"; // longer than the smallest buffer
  std::string text = "# a scan\n\n" + long_comment + large_xyz_text(5000) + "+1 +2 +3 +0.5 -0 0\n# the end\n\n";
  text += long_comment;
  write_file(input, text);
  const std::size_t n = read_point_cloud(input).size();
  ASSERT_GT(n, 4900u);
  for(const std::string out_name : {"out.xyz", "out.pwn"})
    for(std::size_t buffer_size : {Point_stream_reader::default_buffer_size, std::size_t(0)}) {
      const Bit_set flip = random_bits(n, 0.5, 21);
      const Bit_set keep = random_bits(n, 0.9, 22);
      expect_transcoding(input, directory.file(out_name), flip, &keep, buffer_size);
      expect_transcoding(input, directory.file(out_name), Bit_set(n, true), nullptr, buffer_size);
    }
  // The last point flipped: '+' dropped, "-0" -> "0", "0" -> "-0"; comments kept.
  Bit_set last(n);
  last.set(n - 1);
  transcode_with_flips(input, directory.file("last.xyz"), last);
  std::string expected = text;
  const std::string old_line = "+1 +2 +3 +0.5 -0 0\n";
  expected.replace(expected.find(old_line), old_line.size(), "+1 +2 +3 -0.5 0 -0\n");
  EXPECT_EQ(file_content(directory.file("last.xyz")), expected);
  // Dropping it removes its line only.
  Bit_set all_but_last(n, true);
  all_but_last.reset(n - 1);
  transcode_with_flips(input, directory.file("dropped.xyz"), Bit_set(), &all_but_last);
  expected = text;
  expected.erase(expected.find(old_line), old_line.size());
  EXPECT_EQ(file_content(directory.file("dropped.xyz")), expected);

  // Three columns, no final end of line: points can be left out, not flipped.
  const std::string plain = directory.file("plain.xyz");
  std::string plain_text = "# x y z\n";
  for(int i = 0; i < 3000; ++i)
    plain_text += shortest_text(std::sin(i * 0.1)) + "\t" + shortest_text(i * 1e-7) + " " + shortest_text(-i / 3.0) +
                  (i + 1 < 3000 ? "\n" : "");
  write_file(plain, plain_text);
  const Bit_set keep = random_bits(3000, 0.5, 23);
  for(std::size_t buffer_size : {Point_stream_reader::default_buffer_size, std::size_t(0)})
    expect_transcoding(plain, directory.file("plain_out.xyz"), Bit_set(3000), &keep, buffer_size);
  expect_exception<std::invalid_argument>(
    [&] { transcode_with_flips(plain, directory.file("plain_out.xyz"), Bit_set(3000, true)); },
    "cannot flip normals: the file has none");
  EXPECT_FALSE(directory.has_temporary_file());
}

TEST(Transcode, copies_byte_for_byte_when_nothing_changes)
{
  Temporary_directory directory;
  std::vector<std::pair<std::string, std::string>> files; // name, content
  for(const std::string format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    Transcode_ply spec;
    spec.format = format;
    spec.normal_types = {{"float", "int", "double"}};
    files.emplace_back(format + ".ply", spec.make(1500));
  }
  files.emplace_back("normals.xyz", large_xyz_text(2000) + "\n# end\n");
  files.emplace_back("plain.pwn", "1 2 3\n4 5 6");
  // A count padded with blanks, as Point_stream_writer writes it.
  {
    Point_stream_writer writer(directory.file("padded.ply"));
    for(const Point_record& record : awkward_records()) writer.write(record);
    writer.commit();
    files.emplace_back("padded.ply", file_content(directory.file("padded.ply")));
  }
  for(const auto& [name, content] : files) {
    SCOPED_TRACE(name);
    const std::string input = directory.file(name);
    write_file(input, content);
    const std::size_t n = read_point_cloud(input).size();
    const std::string output = directory.file("copy" + fs::path(name).extension().string());
    transcode_with_flips(input, output, Bit_set());
    EXPECT_TRUE(file_content(output) == content);
    const Bit_set all(n, true);
    const Transcode_report report = transcode_with_flips(input, output, Bit_set(n), &all);
    EXPECT_TRUE(file_content(output) == content);
    EXPECT_EQ(report.number_of_written_points, n);
    EXPECT_EQ(report.number_of_flipped, 0u);
  }
  // Dropping a point of the padded file rewrites its count, keeping the padding.
  const std::size_t n = awkward_records().size();
  Bit_set keep(n, true);
  keep.reset(3);
  transcode_with_flips(directory.file("padded.ply"), directory.file("fewer.ply"), Bit_set(), &keep);
  std::string padded = file_content(directory.file("padded.ply"));
  const std::string count_line = "element vertex " + std::to_string(n) + std::string(20 - std::to_string(n).size(), ' ');
  ASSERT_NE(padded.find(count_line), std::string::npos);
  EXPECT_EQ(file_content(directory.file("fewer.ply")).substr(0, padded.find("end_header")),
            padded.substr(0, padded.find("end_header"))
              .replace(padded.find(count_line), ("element vertex " + std::to_string(n)).size(),
                       "element vertex " + std::to_string(n - 1)));
  // Other elements are left out, their declarations with them; the rest is the input.
  Transcode_ply with_faces;
  with_faces.other_elements = true;
  Transcode_ply without_faces;
  for(const std::string format : {"ascii", "binary_big_endian"}) {
    with_faces.format = without_faces.format = format;
    write_file(directory.file("faces.ply"), with_faces.make(1000));
    const Transcode_report report = transcode_with_flips(directory.file("faces.ply"), directory.file("no_faces.ply"), Bit_set());
    EXPECT_TRUE(file_content(directory.file("no_faces.ply")) == without_faces.make(1000)) << format;
    EXPECT_EQ(report.dropped_elements, std::vector<std::string>({"camera", "face"}));
  }
}

TEST(Transcode, gives_the_in_core_program_output_byte_for_byte)
{
  // The in-core program reads the file, negates normals and writes it with
  // PRECISION_AS_READ (binary PLY unless --ascii). On files that this writer wrote (PLY:
  // its header, property order and little-endian byte order; xyz: its number forms),
  // the transcoder gives the same bytes for the same flips.
  Temporary_directory directory;
  Point_cloud cloud = sample_cloud(true);
  add_extra_properties(cloud);
  const std::size_t n = cloud.size();
  const Bit_set flip = random_bits(n, 0.5, 31);
  struct Case
  {
    std::string name;
    bool binary;
    int precision;
  };
  for(const Case& c : {Case{"binary.ply", true, 9}, Case{"ascii.ply", false, 9}, Case{"shortest.xyz", true, 0},
                       Case{"six_digits.xyz", true, 6}}) {
    SCOPED_TRACE(c.name);
    Write_options options;
    options.binary = c.binary;
    options.precision = c.precision;
    const std::string input = directory.file(c.name);
    write_point_cloud(input, cloud, options);
    // in core
    Point_cloud in_core = read_point_cloud(input);
    for(std::size_t i = 0; i < n; ++i)
      if(flip.test(i))
        for(double& v : in_core.normals[i]) v = -v;
    options.precision = Write_options::PRECISION_AS_READ;
    const std::string in_core_file = directory.file("in_core_" + c.name);
    write_point_cloud(in_core_file, in_core, options);
    // transcoded
    const std::string transcoded = directory.file("transcoded_" + c.name);
    transcode_with_flips(input, transcoded, flip);
    EXPECT_TRUE(file_content(transcoded) == file_content(in_core_file));
  }
}

TEST(Transcode, reading_errors_are_those_of_the_reader)
{
  // Every bad input of the command-line tests: the reader's error, word for word, and
  // no output. The files without any point are copied as they are.
  const fs::path bad_inputs = fs::path(__FILE__).parent_path() / "bad_inputs";
  ASSERT_TRUE(fs::is_directory(bad_inputs)) << bad_inputs;
  Temporary_directory directory;
  std::size_t errors = 0;
  for(const auto& entry : fs::directory_iterator(bad_inputs)) {
    const std::string input = entry.path().string();
    if(entry.path().extension() == ".md") continue;
    SCOPED_TRACE(input);
    const std::string expected = stream_error(input);
    const std::string output = directory.file("out" + entry.path().extension().string());
    const std::string message = error_message([&] { transcode_with_flips(input, output, Bit_set()); });
    EXPECT_EQ(message, expected);
    if(expected != "no error") {
      ++errors;
      EXPECT_FALSE(fs::exists(output));
    } else {
      EXPECT_EQ(read_point_cloud(input).size(), 0u);
      EXPECT_TRUE(file_content(output) == file_content(input));
      fs::remove(output);
    }
    EXPECT_EQ(directory.count(), 0u);
  }
  EXPECT_GE(errors, 40u);
  // Errors in the data, found while copying (ASCII and binary, after many points).
  Transcode_ply spec;
  for(const std::string format : {"ascii", "binary_little_endian"}) {
    spec.format = format;
    std::string content = spec.make(40000);
    const std::string input = directory.file("nan.ply");
    if(format == "ascii") {
      const std::size_t p = content.rfind("\n", content.rfind("\n", content.size() - 2) - 1) + 1; // the row before last
      content.replace(p, content.find(' ', p) - p, "nan");
    } else {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      std::memcpy(&content[content.size() - 2 * (3 * 4 + 3 + 3 * 8 + 4) + 12 + 3], &nan, 8); // nx of the row before last
    }
    write_file(input, content);
    const std::string expected = stream_error(input);
    EXPECT_NE(expected.find(format == "ascii" ? "non-finite coordinate at line" : "non-finite normal at vertex 39998"),
              std::string::npos)
      << expected;
    EXPECT_EQ(error_message([&] { transcode_with_flips(input, directory.file("out.ply"), Bit_set(40000, true)); }),
              expected);
    EXPECT_FALSE(fs::exists(directory.file("out.ply")));
    EXPECT_FALSE(directory.has_temporary_file());
  }
}

TEST(Transcode, refuses_what_it_cannot_do_before_writing)
{
  Temporary_directory directory;
  Transcode_ply spec;
  spec.normal_types = {{"float", "ushort", "float"}};
  const std::string input = directory.file("unsigned.ply");
  write_file(input, spec.make(100));
  const std::string output = directory.file("out.ply");
  // Unsigned normals cannot be negated: an error, unless no point kept is flipped.
  expect_io_error([&] { transcode_with_flips(input, output, Bit_set(100, true)); }, input,
                  "cannot flip normals of unsigned type 'ushort' (property 'ny')");
  Bit_set flip(100);
  flip.set(5);
  Bit_set keep(100, true);
  keep.reset(5);
  transcode_with_flips(input, output, flip, &keep);
  EXPECT_EQ(read_point_cloud(output).size(), 99u);
  fs::remove(output);
  // Sets of the wrong size.
  expect_exception<std::invalid_argument>([&] { transcode_with_flips(input, output, Bit_set(99)); },
                                          "the flip set has 99 bits for 100 points");
  const Bit_set long_keep(101, true);
  expect_exception<std::invalid_argument>([&] { transcode_with_flips(input, output, Bit_set(), &long_keep); },
                                          "the keep set has 101 bits for 100 points");
  // .xyz: the number of points is known at the end; no output either.
  const std::string xyz = directory.file("cloud.xyz");
  write_file(xyz, "1 2 3 0 0 1\n4 5 6 0 1 0\n");
  expect_exception<std::invalid_argument>([&] { transcode_with_flips(xyz, directory.file("out.xyz"), Bit_set(3)); },
                                          "the flip set has 3 bits for 2 points");
  // Formats and extensions.
  expect_io_error([&] { transcode_with_flips(xyz, directory.file("out.ply"), Bit_set()); }, directory.file("out.ply"),
                  "the output must be a .xyz or .pwn file, as the input");
  expect_io_error([&] { transcode_with_flips(input, directory.file("out.xyz"), Bit_set()); }, directory.file("out.xyz"),
                  "the output must be a .ply file, as the input");
  expect_io_error([&] { transcode_with_flips(input, directory.file("out.txt"), Bit_set()); }, directory.file("out.txt"),
                  "unknown point cloud file extension '.txt'");
  EXPECT_EQ(directory.listing(), std::vector<std::string>({"cloud.xyz", "unsigned.ply"}));
}

TEST(Transcode, unwritable_output_leaves_nothing)
{
  Temporary_directory directory;
  const std::string input = directory.file("cloud.ply");
  Transcode_ply spec;
  write_file(input, spec.make(500));
  write_file(directory.file("file"), "x");
  for(const std::string& output : {directory.file("file/out.ply"), directory.file("missing/out.ply")})
    expect_io_error([&] { transcode_with_flips(input, output, Bit_set(500, true)); }, output,
                    "cannot create temporary file");
  // A failure after the start keeps an existing output as it was.
  write_file(directory.file("out.ply"), "old");
  Transcode_options options;
  options.callback = [](std::uint64_t, std::uint64_t) { return false; };
  EXPECT_THROW(transcode_with_flips(input, directory.file("out.ply"), Bit_set(500, true), nullptr, options),
               Normal_orientation::Interrupted);
  EXPECT_EQ(file_content(directory.file("out.ply")), "old");
  EXPECT_EQ(directory.listing(), std::vector<std::string>({"cloud.ply", "file", "out.ply"}));
}

TEST(Transcode, output_is_a_registered_temporary_file_until_complete)
{
  Temporary_directory directory;
  const std::string input = directory.file("cloud.ply");
  Transcode_ply spec;
  write_file(input, spec.make(50000));
  // A signal handler calling remove_temporary_files() in the middle removes the output
  // being written: the copy then fails and leaves nothing.
  std::size_t removed = 0;
  std::vector<std::string> during;
  std::uint64_t last_bytes = 0;
  Transcode_options options;
  options.callback = [&](std::uint64_t bytes, std::uint64_t size) {
    EXPECT_GE(bytes, last_bytes);
    EXPECT_LE(bytes, size);
    last_bytes = bytes;
    if(during.empty()) {
      during = directory.listing();
      removed = Normal_orientation::remove_temporary_files();
    }
    return true;
  };
  expect_io_error([&] { transcode_with_flips(input, directory.file("out.ply"), Bit_set(50000, true), nullptr, options); },
                  directory.file("out.ply"), "cannot rename");
  EXPECT_EQ(removed, 1u);
  ASSERT_EQ(during.size(), 2u);
  EXPECT_EQ(during[1].rfind("out.ply.tmp.", 0), 0u) << during[1];
  EXPECT_EQ(directory.listing(), std::vector<std::string>({"cloud.ply"}));
  // Without it: progress up to the size of the file, then the output.
  last_bytes = 0;
  options.callback = [&](std::uint64_t bytes, std::uint64_t) {
    last_bytes = bytes;
    return true;
  };
  transcode_with_flips(input, directory.file("out.ply"), Bit_set(50000, true), nullptr, options);
  EXPECT_EQ(last_bytes, fs::file_size(input));
}

TEST(Transcode, input_changing_under_it_is_an_error)
{
  Temporary_directory directory;
  Transcode_ply spec;
  const std::string ply = directory.file("cloud.ply");
  const std::string xyz = directory.file("cloud.xyz");
  for(const std::string& input : {ply, xyz}) {
    for(const std::string change : {"append", "truncate"}) {
      SCOPED_TRACE(input + ": " + change);
      if(input == ply) write_file(ply, spec.make(50000));
      else write_file(xyz, large_xyz_text(50000));
      const std::uint64_t size = fs::file_size(input);
      Transcode_options options;
      bool changed = false;
      options.callback = [&](std::uint64_t, std::uint64_t) {
        if(!changed) {
          changed = true;
          if(change == "append") {
            std::ofstream out(input, std::ios::binary | std::ios::app);
            out << "1 2 3 0 0 1\n";
          } else {
            fs::resize_file(input, size / 2);
          }
        }
        return true;
      };
      const std::string output = directory.file("out" + fs::path(input).extension().string());
      const std::string message =
        error_message([&] { transcode_with_flips(input, output, Bit_set(), nullptr, options); });
      EXPECT_EQ(message.rfind(input + ": ", 0), 0u) << message;
      if(change == "append") {
        EXPECT_NE(message.find("the file changed while it was copied"), std::string::npos) << message;
      }
      EXPECT_FALSE(fs::exists(output));
      EXPECT_FALSE(directory.has_temporary_file());
    }
  }
}

TEST(Transcode, in_place)
{
  Temporary_directory directory;
  const std::string input = directory.file("cloud.ply");
  Transcode_ply spec;
  spec.format = "binary_big_endian";
  write_file(input, spec.make(20000));
  const Point_cloud before = read_point_cloud(input);
  const Bit_set flip = random_bits(20000, 0.3, 41);
  transcode_with_flips(input, input, flip);
  expect_same_bits(expected_transcoding(before, flip, nullptr), read_point_cloud(input), "in place");
  EXPECT_EQ(directory.listing(), std::vector<std::string>({"cloud.ply"}));
}
