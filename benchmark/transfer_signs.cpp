// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// transfer_signs IN.xyz MESH.ply OUT.xyz
//
// Gives every normal of IN the sign of a reconstructed surface: OUT holds the points of IN in
// the same order, each with its input normal, negated where its dot product with the normal of
// the closest triangle of MESH (right-hand rule) is negative. Used by benchmark/ipsr/ipsr_orient.sh
// to turn the mesh that iPSR writes into an orientation of the input cloud; only signs change.
#include "Reference_mesh.h"
#include "Xyz_io.h"

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

namespace {

namespace NO = Normal_orientation;

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: transfer_signs IN.xyz MESH.ply OUT.xyz\n"
               "  Writes OUT: the points and normals of IN (x y z nx ny nz), in the same order,\n"
               "  each normal negated where it disagrees with the normal of the closest triangle\n"
               "  of MESH (any polygon soup CGAL reads: .ply, .off, .obj). Prints to stderr the\n"
               "  flipped count and the largest distance of a point to MESH.\n"
               "  Exit status: 0 written, 1 unreadable input or mesh or unwritable output, 2 usage.\n");
}

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  if(argc == 2 && (std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help"))
  {
    print_usage(stdout);
    return EXIT_SUCCESS;
  }
  if(argc != 4)
  {
    print_usage(stderr);
    return 2;
  }
  const std::string input = argv[1], mesh_path = argv[2], output = argv[3];

  std::vector<NO::benchmark::Xyz_row> rows;
  std::string error;
  if(!NO::benchmark::read_xyz_rows(input, rows, error))
  {
    std::fprintf(stderr, "transfer_signs: %s\n", error.c_str());
    return EXIT_FAILURE;
  }
  try
  {
    const NO::benchmark::Reference_normals surface(mesh_path);
    std::vector<NO::benchmark::Mesh_triangle_iterator> candidates;
    std::size_t flipped = 0;
    double max_squared_distance = 0.0;
    for(NO::benchmark::Xyz_row& r : rows)
    {
      const std::pair<NO::benchmark::Vector_3, double> hit =
        surface.truth(NO::benchmark::Point_3(r[0], r[1], r[2]), candidates);
      max_squared_distance = std::fmax(max_squared_distance, hit.second);
      const double dot = hit.first.x() * r[3] + hit.first.y() * r[4] + hit.first.z() * r[5];
      if(dot < 0.0)
      {
        r[3] = -r[3];
        r[4] = -r[4];
        r[5] = -r[5];
        ++flipped;
      }
    }
    // Written to a temporary name, renamed when complete: OUT is either whole or absent.
    const std::string temporary = output + ".tmp";
    {
      NO::benchmark::Xyz_writer writer(temporary);
      const bool opened = writer.is_open();
      for(const NO::benchmark::Xyz_row& r : rows)
        writer.write_row(r[0], r[1], r[2], r[3], r[4], r[5]);
      if(!writer.close() || !opened || std::rename(temporary.c_str(), output.c_str()) != 0)
      {
        std::remove(temporary.c_str());
        std::fprintf(stderr, "transfer_signs: cannot write '%s'\n", output.c_str());
        return EXIT_FAILURE;
      }
    }
    std::fprintf(stderr, "transfer_signs: %zu points, %zu flipped, largest distance to the mesh %.3g (%.3g of its diagonal)\n",
                 rows.size(), flipped, std::sqrt(max_squared_distance),
                 std::sqrt(max_squared_distance) / surface.mesh().bbox_diagonal);
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "transfer_signs: %s\n", e.what());
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
