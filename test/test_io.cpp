// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file test_io.cpp
/// \brief Tests of Normal_orientation/IO/Point_cloud_io.h: reading and writing `.xyz`,
/// `.pwn` and `.ply` point clouds, round trips, error reporting and atomic writing (suite
/// `Point_cloud_io`). The other suites of the test program `test_io`:
/// test_io_stream.cpp (`Point_stream`), test_io_validation.cpp (`Input_validation`),
/// test_io_transcode.cpp (`Transcode`); their helpers are in Io_test_support.h.

#include "Io_test_support.h"

using namespace io_test;

// --------------------------------------------------------------------------- xyz

TEST(Point_cloud_io, XyzRoundTripWithNormals)
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

TEST(Point_cloud_io, XyzRoundTripWithoutNormals)
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

TEST(Point_cloud_io, XyzCommentsBlankLinesAndLineEndings)
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

TEST(Point_cloud_io, XyzNumberSyntax)
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

TEST(Point_cloud_io, FastFormattingMatchesToChars)
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

TEST(Point_cloud_io, PwnAndUpperCaseExtensions)
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

TEST(Point_cloud_io, EmptyFiles)
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

TEST(Point_cloud_io, SignificantDigitsOfTokens)
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

TEST(Point_cloud_io, AsReadReproducesTheValuesBitForBit)
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

TEST(Point_cloud_io, AsReadWritesLikePrintfWithTheDigitsRead)
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

TEST(Point_cloud_io, AsReadFallsBackToShortestWhenDigitsAreUnknownOrAbove15)
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

TEST(Point_cloud_io, ParallelReadingGivesTheSequentialCloud)
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

TEST(Point_cloud_io, ParallelWritingGivesTheSequentialFile)
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

TEST(Point_cloud_io, ParallelReadingReportsTheFirstErrorWithItsLine)
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

TEST(Point_cloud_io, ReadAndWriteOptionsKeepTheirAggregateForm)
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

TEST(Point_cloud_io, PlyAsciiWithColoursAndFaces)
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

TEST(Point_cloud_io, PlyBinaryLittleEndianWrittenByteByByte)
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

TEST(Point_cloud_io, PlyBinaryBigEndianDoubleWithFaceBeforeVertex)
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

TEST(Point_cloud_io, PlyEveryScalarTypeInBothEndiannesses)
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

TEST(Point_cloud_io, PlyExtraPropertiesRoundTrip)
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

TEST(Point_cloud_io, PlyInputTypesAreKeptOnOutput)
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

TEST(Point_cloud_io, XyzToPlyAndBack)
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

TEST(Point_cloud_io, MissingFileAndUnknownExtension)
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

TEST(Point_cloud_io, XyzErrors)
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

TEST(Point_cloud_io, PlyHeaderErrors)
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

TEST(Point_cloud_io, PlyDataErrors)
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

TEST(Point_cloud_io, WriteToMissingDirectoryThrowsAndLeavesNothing)
{
  Temporary_directory directory;
  const Point_cloud cloud = sample_cloud(true);
  for(const char* name : {"no/such/dir/out.xyz", "no/such/dir/out.ply"}) {
    const std::string filename = directory.file(name);
    expect_io_error([&] { write_point_cloud(filename, cloud); }, filename, "cannot create temporary file");
  }
  EXPECT_TRUE(directory.listing().empty());
}

TEST(Point_cloud_io, FailedWriteKeepsExistingFile)
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

TEST(Point_cloud_io, WritingNeverLeavesTemporaryFiles)
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

