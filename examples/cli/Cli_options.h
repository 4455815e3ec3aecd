// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// The command line of the orient_normals program: its options, the usage
// text, and their parsing and checking.

#ifndef NORMAL_ORIENTATION_EXAMPLES_CLI_CLI_OPTIONS_H
#define NORMAL_ORIENTATION_EXAMPLES_CLI_CLI_OPTIONS_H

#include <Normal_orientation/IO/File_format.h>
#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/streaming/Streaming_settings.h>

#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace Cli {

/// \brief A bad command line: reported with the usage hint, exit status 2.
struct Usage_error : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// \brief The options of the program, as given (checked by `parse_options()`).
struct Options
{
  std::string input, output; ///< IN and OUT
  unsigned int k = Normal_orientation::default_number_of_neighbors; ///< --k
  double radius = 0.0;                 ///< --radius (0: estimated)
  std::string criterion = "hoppe-konig"; ///< --criterion
  std::string solver = "qpbo-i";       ///< --solver
  unsigned int orders = 3;             ///< --orders
  std::string sign = "outward";        ///< --sign
  bool sign_given = false;             ///< --sign was given
  bool has_viewpoint = false;          ///< --viewpoint was given
  double viewpoint[3] = {0, 0, 0};     ///< --viewpoint
  double prior_weight = 0.0;           ///< --prior-weight (0: no prior)
  std::string global = "auto";         ///< --global: auto, visibility, winding or none
  std::array<double, 3> up = {{0, 0, 1}}; ///< --up
  bool layer_edges = true;             ///< --layer-edges
  std::string normals = "jet";         ///< --normals
  unsigned int normal_k = 18;          ///< --normal-k
  int threads = 0;                     ///< --threads (0: all cores)
  unsigned long seed = 0;              ///< --seed
  bool json = false;                   ///< --json
  bool quiet = false;                  ///< --quiet
  bool ascii = false;                  ///< --ascii
  bool return_memory = false;          ///< --return-memory
  bool stream = false;                 ///< --stream
  std::string presorted;               ///< --presorted: "", "x", "y" or "z"
  std::string components_dir;          ///< --components-dir: one file per component there
  unsigned long long min_component_size = 0; ///< --min-component-size
  bool min_component_size_given = false;     ///< --min-component-size was given
  bool write_segments = false;         ///< --write-segments: the segment of each point in OUT (PLY)
  bool keep_order = false;             ///< --keep-order: OUT is IN in its own order and format
  unsigned long long batch_size = 0;   ///< --batch-size (0: the library's default)
  long refine_rounds = -1;             ///< --refine (-1: the library's default)
};

/// \brief The text of `--help`.
inline const char* usage_text()
{
  return "usage: orient_normals [options] [IN [OUT]]\n"
         "\n"
         "Orients the normals of a point cloud consistently and outward.\n"
         "IN: .xyz/.pwn (x y z [nx ny nz] per line) or .ply (ascii or binary).\n"
         "OUT: .xyz or .ply, by extension (default: IN with '_oriented' added).\n"
         "Without IN, orients the sample cloud shipped with the library.\n"
         "Normals are estimated first when IN has none, or when all of them are zero;\n"
         "points with a zero normal among others are left as they are.\n"
         "\n"
         "options:\n"
         "  --k N                neighbours per point (default 12)\n"
         "  --radius R           neighbour radius (default: estimated from the data)\n"
         "  --criterion NAME     flip criterion: hoppe-konig (default: Hoppe's, and Konig's where\n"
         "                       the normals are over 60 degrees apart and it is surer), hoppe, xie, konig\n"
         "  --solver NAME        solver: qpbo-i (default: MST, then QPBO-I on the segment graph),\n"
         "                       mst (fastest), lsa-tr\n"
         "  --orders N           qpbo-i: random orders tried, the best is kept (default 3)\n"
         "  --sign NAME          component sign: outward (default), keep\n"
         "  --viewpoint X,Y,Z    make every component face this point instead\n"
         "  --prior-weight W     with --viewpoint: also a soft prior for every point to face\n"
         "                       it, of weight W * cos(angle) (edges weigh at most 1), which\n"
         "                       every solver weighs against the edges (default 0: none)\n"
         "  --global NAME        global sign stage: visibility (components and sheets face the\n"
         "                       side they were seen from, then the winding number decides\n"
         "                       where the cloud is closed), winding (the winding number\n"
         "                       only) or none; default auto: visibility with the outward\n"
         "                       sign and no viewpoint, none otherwise\n"
         "  --up X,Y,Z           the scene's up direction, for visibility: views from below\n"
         "                       weigh less, and components whose top surface faces down\n"
         "                       are negated (default 0,0,1; 0,0,0: no up direction, for an\n"
         "                       object scanned from below)\n"
         "  --layer-edges on|off negate the edges across two layers closer than the\n"
         "                       neighbour distance (thin parts, contacts) so that they get\n"
         "                       opposite signs (default on; off: the paper's graph)\n"
         "  --normals NAME       estimator when IN has no normals: jet (default), pca\n"
         "  --normal-k N         neighbours of the normal estimator (default 18)\n"
         "  --threads N          at most N threads (default, or 0: all cores); the output\n"
         "                       does not depend on N (the same bytes)\n"
         "  --return-memory      in core: give freed memory back to the system at once\n"
         "                       (the C library's default): a lower peak, slower where\n"
         "                       page faults are costly, as on many virtual machines; by\n"
         "                       default the program keeps it for reuse (glibc only)\n"
         "  --seed S             random seed of randomised solvers (default 0)\n"
         "  --stream             out of core, for clouds larger than memory: sort along the\n"
         "                       principal axis (temporary files in TMPDIR), sweep, segment,\n"
         "                       solve the segment graph; IN must have normals, not all zero;\n"
         "                       OUT holds the points in sweep order (outward sign only); a\n"
         "                       one-line progress (stage, percent) on stderr when it is a\n"
         "                       terminal\n"
         "  --presorted x|y|z    with --stream: IN is already sorted by increasing x (y, z):\n"
         "                       no principal axis, no external sort, the sweep reads IN as\n"
         "                       it is and OUT keeps its order; an unsorted IN is an error\n"
         "                       naming the first point out of order\n"
         "  --components-dir DIR with --stream: also write each connected component to\n"
         "                       DIR/component_000000.EXT, component_000001.EXT, ... (largest\n"
         "                       first, EXT and format of OUT, each written atomically;\n"
         "                       DIR is created when missing, files of the same names are\n"
         "                       replaced)\n"
         "  --min-component-size N  with --stream: drop the components of fewer than N\n"
         "                       points from OUT and the component files (counted in the\n"
         "                       report: dropped_points, dropped_components; default 0)\n"
         "  --write-segments     with --stream and a .ply OUT: add to each point its segment\n"
         "                       (vertex property 'int segment', 0 to segments - 1)\n"
         "  --keep-order         with --stream: write OUT as a copy of IN in its own order and\n"
         "                       format (OUT .ply for a .ply IN, .xyz/.pwn for .xyz/.pwn),\n"
         "                       with every other property kept and only the signs of the\n"
         "                       normals changed (one more reading of IN)\n"
         "  --batch-size N       with --stream: points whose neighbours are searched at\n"
         "                       once (one kd-tree each; default 262144): larger is\n"
         "                       faster and holds more points (the peak window grows by\n"
         "                       about 2N); the output does not depend on N\n"
         "  --refine N           with --stream: rounds of refinement after the segment graph\n"
         "                       is solved (default 3; 0: none): each segments the points\n"
         "                       again around the current labelling, with finer segments\n"
         "                       than the last, and solves the new segment graph; single\n"
         "                       points move too; the energy never rises. It keeps the\n"
         "                       edges in a temporary file (about 56 bytes a point)\n"
         "  --ascii              write PLY as ascii instead of binary\n"
         "  --json               print one JSON object with the report on stdout\n"
         "  --quiet              print nothing on stderr but errors\n"
         "  --help               print this text\n";
}

/// \cond SKIP_IN_MANUAL
namespace internal {

/// `text` read whole as a `T`, or a `Usage_error` naming `option`
template <typename T>
T parse_number(const std::string& option, const std::string& text)
{
  std::istringstream in(text);
  T value;
  if (!(in >> value) || !in.eof())
    throw Usage_error("invalid value '" + text + "' for " + option);
  return value;
}

/// `text` read whole as "X,Y,Z" of finite numbers into `xyz`, or a
/// `Usage_error` naming `option`
inline void parse_triple(const std::string& option, std::string text, double* xyz)
{
  for (char& c : text)
    if (c == ',')
      c = ' ';
  std::istringstream in(text);
  if (!(in >> xyz[0] >> xyz[1] >> xyz[2]) || !(in >> std::ws).eof() || !std::isfinite(xyz[0] + xyz[1] + xyz[2]))
    throw Usage_error(option + " needs X,Y,Z");
}

/// reads option `a` (at argv[i]) into `o`, with `value()` its value;
/// returns false when `a` is not an option (a positional argument)
template <typename Value>
bool read_option(Options& o, const std::string& a, const Value& value)
{
  if (a == "--help" || a == "-h") {
    std::cout << usage_text();
    std::exit(0);
  } else if (a == "--k") {
    const long k = parse_number<long>(a, value());
    if (k < 1 || k > long(Normal_orientation::maximum_number_of_neighbors)) // the library's limit
      throw Usage_error("--k must be between 1 and " + std::to_string(Normal_orientation::maximum_number_of_neighbors));
    o.k = unsigned(k);
  } else if (a == "--radius") {
    o.radius = parse_number<double>(a, value());
    if (!(o.radius > 0.0) || !std::isfinite(o.radius))
      throw Usage_error("--radius must be a number > 0");
  } else if (a == "--criterion") {
    o.criterion = value();
    if (o.criterion != "hoppe-konig" && o.criterion != "hoppe" && o.criterion != "xie" && o.criterion != "konig")
      throw Usage_error("unknown criterion '" + o.criterion + "' (hoppe-konig, hoppe, xie, konig)");
  } else if (a == "--solver") {
    o.solver = value();
    if (o.solver != "mst" && o.solver != "qpbo-i" && o.solver != "lsa-tr")
      throw Usage_error("unknown solver '" + o.solver + "' (mst, qpbo-i, lsa-tr)");
  } else if (a == "--orders") {
    const long n = parse_number<long>(a, value());
    if (n < 1 || n > 1000)
      throw Usage_error("--orders must be between 1 and 1000");
    o.orders = unsigned(n);
  } else if (a == "--sign") {
    o.sign = value();
    o.sign_given = true;
    if (o.sign != "outward" && o.sign != "keep")
      throw Usage_error("unknown sign policy '" + o.sign + "' (outward, keep)");
  } else if (a == "--global") {
    o.global = value();
    if (o.global != "auto" && o.global != "visibility" && o.global != "winding" && o.global != "none")
      throw Usage_error("unknown global stage '" + o.global + "' (auto, visibility, winding, none)");
  } else if (a == "--layer-edges") {
    const std::string v = value();
    if (v != "on" && v != "off")
      throw Usage_error("--layer-edges takes on or off, not '" + v + "'");
    o.layer_edges = v == "on";
  } else if (a == "--up") {
    parse_triple(a, value(), o.up.data());
  } else if (a == "--viewpoint") {
    parse_triple(a, value(), o.viewpoint);
    o.has_viewpoint = true;
  } else if (a == "--prior-weight") {
    o.prior_weight = parse_number<double>(a, value());
    if (!(o.prior_weight >= 0.0 && o.prior_weight <= 1e6))
      throw Usage_error("--prior-weight must be between 0 and 1e6");
  } else if (a == "--normals") {
    o.normals = value();
    if (o.normals != "jet" && o.normals != "pca")
      throw Usage_error("unknown normal estimator '" + o.normals + "' (jet, pca)");
  } else if (a == "--normal-k") {
    const long k = parse_number<long>(a, value());
    if (k < 3 || k > 1000)
      throw Usage_error("--normal-k must be between 3 and 1000");
    o.normal_k = unsigned(k);
  } else if (a == "--threads") {
    const long t = parse_number<long>(a, value());
    if (t < 0 || t > 1024)
      throw Usage_error("--threads must be between 1 and 1024 (0: all cores)");
    o.threads = int(t);
  } else if (a == "--seed") {
    o.seed = parse_number<unsigned long>(a, value());
  } else if (a == "--json") {
    o.json = true;
  } else if (a == "--quiet" || a == "-q") {
    o.quiet = true;
  } else if (a == "--ascii") {
    o.ascii = true;
  } else if (a == "--return-memory") {
    o.return_memory = true;
  } else if (a == "--stream") {
    o.stream = true;
  } else if (a == "--presorted") {
    o.presorted = value();
    if (o.presorted != "x" && o.presorted != "y" && o.presorted != "z")
      throw Usage_error("unknown axis '" + o.presorted + "' for --presorted (x, y, z)");
  } else if (a == "--components-dir") {
    o.components_dir = value();
    if (o.components_dir.empty())
      throw Usage_error("--components-dir needs a directory");
  } else if (a == "--min-component-size") {
    const long long m = parse_number<long long>(a, value());
    if (m < 0)
      throw Usage_error("--min-component-size must be a number of points >= 0");
    o.min_component_size = (unsigned long long)m;
    o.min_component_size_given = true;
  } else if (a == "--write-segments") {
    o.write_segments = true;
  } else if (a == "--keep-order") {
    o.keep_order = true;
  } else if (a == "--batch-size") {
    const long long b = parse_number<long long>(a, value());
    if (b < 1 || b > (1ll << 30))
      throw Usage_error("--batch-size must be a number of points between 1 and 2^30");
    o.batch_size = (unsigned long long)b;
  } else if (a == "--refine") {
    const long r = parse_number<long>(a, value());
    if (r < 0 || r > long(Normal_orientation::maximum_refinement_rounds)) // the library's limit
      throw Usage_error("--refine must be a number of rounds between 0 and " +
                        std::to_string(Normal_orientation::maximum_refinement_rounds));
    o.refine_rounds = r;
  } else if (a.size() > 1 && a[0] == '-') {
    throw Usage_error("unknown option " + a);
  } else {
    return false;
  }
  return true;
}

/// the options of --stream used without it, and the combinations refused
inline void check_combinations(const Options& o)
{
  if (o.prior_weight > 0.0 && !o.has_viewpoint)
    throw Usage_error("--prior-weight needs --viewpoint");
  if (!o.stream && !o.presorted.empty())
    throw Usage_error("--presorted needs --stream");
  if (!o.stream && !o.components_dir.empty())
    throw Usage_error("--components-dir needs --stream");
  if (!o.stream && o.batch_size != 0)
    throw Usage_error("--batch-size needs --stream");
  if (!o.stream && o.min_component_size_given)
    throw Usage_error("--min-component-size needs --stream");
  if (!o.stream && o.write_segments)
    throw Usage_error("--write-segments needs --stream");
  if (!o.stream && o.refine_rounds >= 0)
    throw Usage_error("--refine needs --stream");
  if (!o.stream && o.keep_order)
    throw Usage_error("--keep-order needs --stream");
  if (o.keep_order && o.write_segments)
    throw Usage_error("--keep-order copies IN: --write-segments is not supported with it");
  if (o.keep_order && o.ascii)
    throw Usage_error("--keep-order writes OUT in the format of IN: --ascii is not supported with it");
}

/// IN and OUT from the positional arguments: the sample cloud without IN,
/// IN with "_oriented" before its extension without OUT
inline void choose_files(Options& o, const std::vector<std::string>& positional, const std::string& sample_cloud)
{
  if (positional.empty()) {
    o.input = sample_cloud;
    o.output = "sample_oriented.ply";
    return;
  }
  o.input = positional[0];
  if (positional.size() == 2) {
    o.output = positional[1];
    return;
  }
  const std::size_t slash = o.input.find_last_of('/');
  const std::size_t dot = o.input.find_last_of('.');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  o.output = has_ext ? o.input.substr(0, dot) + "_oriented" + o.input.substr(dot) : o.input + "_oriented.ply";
}

} // namespace internal
/// \endcond

/// \brief Reads and checks the command line; `sample_cloud` is IN when none
/// is given.  `--help` prints the usage and exits.
/// \throw Usage_error for a bad command line
inline Options parse_options(int argc, char** argv, const std::string& sample_cloud)
{
  Options o;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc)
        throw Usage_error("option " + a + " needs a value");
      return argv[++i];
    };
    if (!internal::read_option(o, a, value))
      positional.push_back(a);
  }
  if (positional.size() > 2)
    throw Usage_error("too many arguments");
  internal::check_combinations(o);
  internal::choose_files(o, positional, sample_cloud);
  using Normal_orientation::IO::lower_case_extension;
  if (o.write_segments && lower_case_extension(o.output) != ".ply")
    throw Usage_error("--write-segments needs a .ply OUT");
  if (o.keep_order && (lower_case_extension(o.input) == ".ply") != (lower_case_extension(o.output) == ".ply"))
    throw Usage_error("--keep-order writes OUT in the format of IN: OUT must be a .ply file for a .ply IN, "
                      "a .xyz or .pwn file for a .xyz or .pwn IN");
  return o;
}

} // namespace Cli

#endif // NORMAL_ORIENTATION_EXAMPLES_CLI_CLI_OPTIONS_H
