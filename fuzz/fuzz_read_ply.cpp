// SPDX-License-Identifier: GPL-3.0-or-later
/// \file fuzz_read_ply.cpp
/// \brief libFuzzer target of the in-core PLY reader (`IO::read_ply()`, which parses
/// the content of the file with `IO::internal::parse_ply_data()`, called here on the
/// input bytes).
///
/// An `Io_error` is a normal outcome; its message must name the file, be one printable
/// line and name only lines and byte offsets of the input. A cloud read must satisfy
/// the reader's contract (`check_cloud()`: finite coordinates and normals, values of
/// their declared types, counts that agree), have the vertex count and the properties
/// of the header, and come back unchanged, bit for bit, from a binary and an ASCII PLY
/// file written by `IO::write_ply()` and (coordinates and normals) from a `.xyz` file
/// written by `IO::write_xyz()` with the shortest exact text.

#include "Fuzz_common.h"

#include <Normal_orientation/IO/Point_cloud_io.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace {

/// \brief Checks that `back`, read from a file written from `cloud`, is `cloud`, with
/// the types the writer documents (integer normal types become `float` or `double`).
void check_ply_round_trip(const fuzz::IO::Point_cloud& cloud, const fuzz::IO::Point_cloud& back,
                          const std::string& what)
{
  using fuzz::IO::Ply_scalar_type;
  fuzz::check_same_cloud(cloud, back, what);
  for(std::size_t c = 0; c < 3; ++c) {
    FUZZ_CHECK(back.point_types[c] == cloud.point_types[c], what + ": a coordinate type changed");
    if(!cloud.has_normals()) continue;
    // floating types are kept; integer ones become the smallest floating type that
    // holds all their values
    Ply_scalar_type written = cloud.normal_types[c];
    if(!fuzz::IO::internal::is_floating(written))
      written = fuzz::IO::ply_scalar_type_size(written) <= 2 ? Ply_scalar_type::FLOAT32 : Ply_scalar_type::FLOAT64;
    FUZZ_CHECK(back.normal_types[c] == written, what + ": a normal type changed");
  }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  namespace IO = fuzz::IO;
  const std::string filename = "input.ply";
  const char* const begin = reinterpret_cast<const char*>(data);
  const char* const end = begin + size;

  IO::Point_cloud cloud;
  const std::string error = fuzz::io_error_of([&] { cloud = IO::internal::parse_ply_data(filename, begin, end); });
  if(!error.empty()) {
    fuzz::check_error_message(error, filename, size, fuzz::line_count(begin, size));
    return 0;
  }
  fuzz::check_cloud(cloud, true);

  // The cloud is what the header declares.
  IO::internal::Ply_header header;
  const std::string header_error =
    fuzz::io_error_of([&] { header = IO::internal::parse_ply_header(filename, begin, end); });
  FUZZ_CHECK(header_error.empty(), "the file was read but its header fails: " + header_error);
  const IO::internal::Ply_header_element& vertex = header.elements[header.vertex_element];
  FUZZ_CHECK(vertex.count == cloud.size(),
             std::to_string(vertex.count) + " vertices declared, " + std::to_string(cloud.size()) + " read");
  static const char* const names[6] = {"x", "y", "z", "nx", "ny", "nz"};
  bool declares_normals = false;
  std::size_t extra = 0;
  for(const IO::internal::Ply_header_property& property : vertex.properties) {
    std::size_t role = 6;
    for(std::size_t r = 0; r < 6; ++r)
      if(property.name == names[r]) role = r;
    if(role < 3) {
      FUZZ_CHECK(cloud.point_types[role] == property.type, "wrong type of " + property.name);
    } else if(role < 6) {
      declares_normals = true;
      FUZZ_CHECK(cloud.normal_types[role - 3] == property.type, "wrong type of " + property.name);
    } else {
      FUZZ_CHECK(extra < cloud.extra_properties.size() && cloud.extra_properties[extra].name == property.name &&
                   cloud.extra_properties[extra].type == property.type,
                 "extra property " + property.name + " missing or changed");
      ++extra;
    }
  }
  FUZZ_CHECK(extra == cloud.extra_properties.size(), "more extra properties than the header declares");
  FUZZ_CHECK(cloud.normals.size() == (declares_normals ? cloud.size() : 0), "wrong number of normals");

  // What is read can be written, and reads back unchanged.
  const std::string& directory = fuzz::directory();
  for(bool binary : {true, false}) {
    const std::string written = directory + (binary ? "/binary.ply" : "/ascii.ply");
    IO::Write_options options;
    options.binary = binary;
    const std::string write_error = fuzz::io_error_of([&] { IO::write_ply(written, cloud, options); });
    FUZZ_CHECK(write_error.empty(), "a cloud read cannot be written: " + write_error);
    IO::Point_cloud back;
    const std::string read_error = fuzz::io_error_of([&] { back = IO::read_ply(written); });
    FUZZ_CHECK(read_error.empty(), "a PLY file written cannot be read: " + read_error);
    check_ply_round_trip(cloud, back, binary ? "binary PLY round trip" : "ASCII PLY round trip");
  }
  IO::Point_cloud points_only = cloud;
  points_only.extra_properties.clear();
  points_only.extra_values.clear();
  IO::Write_options shortest;
  shortest.precision = IO::Write_options::PRECISION_SHORTEST;
  const std::string written = directory + "/text.xyz";
  const std::string write_error = fuzz::io_error_of([&] { IO::write_xyz(written, points_only, shortest); });
  FUZZ_CHECK(write_error.empty(), "a cloud read cannot be written as text: " + write_error);
  IO::Point_cloud back;
  const std::string read_error = fuzz::io_error_of([&] { back = IO::read_xyz(written); });
  FUZZ_CHECK(read_error.empty(), "a text file written cannot be read: " + read_error);
  if(cloud.size() == 0) points_only.normals.clear(); // a text file of no line has no normals
  fuzz::check_same_cloud(points_only, back, "PLY to .xyz round trip");
  return 0;
}
