// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// score_normals ORIENTED.xyz TRUTH.gt.xyz [--json]
//
// Scores an oriented cloud against the truth written by make_cloud: both files hold the same
// points in the same order (x y z nx ny nz). A normal is wrong when its dot product with the
// true normal is <= 0. The score is given over all normals and over the "clear" normals, whose
// line is within 60 degrees of the true normal's line (|cos| >= 0.5): only there does the sign
// of a normal mean something. Zero and non-finite normals are wrong, in both counts.
#include "Normal_score.h"
#include "Xyz_io.h"

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

using Normal_orientation::benchmark::Normal_score;
using Normal_orientation::benchmark::Xyz_row;
using Normal_orientation::benchmark::percent;

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: score_normals ORIENTED.xyz TRUTH.gt.xyz [--json]\n"
               "  Both files: x y z nx ny nz per line, the same points in the same order (the\n"
               "  truth as make_cloud writes it). Prints the points, the wrong normals (dot with\n"
               "  the true normal <= 0) over all normals, and over the clear normals, whose line\n"
               "  is within 60 degrees of the true normal (|cos| >= 0.5). Zero and non-finite\n"
               "  normals are wrong and count as clear. --json: one JSON line on stdout.\n"
               "  Exit status: 0 scored, 1 unreadable or mismatched files, 2 bad usage.\n");
}

/// Scores `oriented` against `truth` (same size, checked before).
Normal_score score(const std::vector<Xyz_row>& oriented, const std::vector<Xyz_row>& truth)
{
  Normal_score s;
  for(std::size_t i = 0; i < truth.size(); ++i)
    s.add(&oriented[i][3], &truth[i][3]);
  return s;
}

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  const auto start = std::chrono::steady_clock::now();
  std::vector<Xyz_row> oriented, truth;
  const bool json = Normal_orientation::benchmark::read_oriented_and_truth_command(
                      argc, argv, "score_normals", print_usage, [](const std::string&, int&) { return false; },
                      oriented, truth)
                      .json;
  const Normal_score s = score(oriented, truth);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  if(json)
    std::printf("{\"points\":%zu,\"wrong\":%zu,\"wrong_percent\":%.4f,\"clear\":%zu,\"clear_wrong\":%zu,"
                "\"clear_wrong_percent\":%.4f,\"invalid\":%zu,\"seconds\":%.3f}\n",
                s.points, s.wrong, percent(s.wrong, s.points), s.clear, s.clear_wrong,
                percent(s.clear_wrong, s.clear), s.invalid, seconds);
  else
    std::printf("points %zu wrong %zu (%.2f%%) clear %zu (%.2f%%) clear_wrong %zu (%.2f%%) invalid %zu\n", s.points,
                s.wrong, percent(s.wrong, s.points), s.clear, percent(s.clear, s.points), s.clear_wrong,
                percent(s.clear_wrong, s.clear), s.invalid);
  return EXIT_SUCCESS;
}
