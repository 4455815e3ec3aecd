// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file test_io_transcode.cpp
/// \brief Tests of Normal_orientation/IO/Point_stream_transcode.h: copies of a file with
/// flipped normals and dropped points (suite `Transcode`).

#include "Io_test_support.h"

using namespace io_test;
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

TEST(Transcode, BitSet)
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

TEST(Transcode, TheReaderGivesThePlyLayout)
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

TEST(Transcode, BinaryPlyRoundTripsWithExtraProperties)
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

TEST(Transcode, BinaryNormalsAreNegatedInTheirOwnType)
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

TEST(Transcode, AsciiPlyKeepsTheTextOfEveryOtherValue)
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

TEST(Transcode, XyzKeepsCommentsBlankLinesAndDigits)
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

TEST(Transcode, CopiesByteForByteWhenNothingChanges)
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

TEST(Transcode, GivesTheInCoreProgramOutputByteForByte)
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

TEST(Transcode, ReadingErrorsAreThoseOfTheReader)
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

TEST(Transcode, RefusesWhatItCannotDoBeforeWriting)
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

TEST(Transcode, UnwritableOutputLeavesNothing)
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

TEST(Transcode, OutputIsARegisteredTemporaryFileUntilComplete)
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

TEST(Transcode, InputChangingUnderItIsAnError)
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

TEST(Transcode, InPlace)
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

