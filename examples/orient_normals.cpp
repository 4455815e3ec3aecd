// SPDX-License-Identifier: GPL-3.0-or-later
// orient_normals: the command-line program of Normal_orientation.
//
//   orient_normals [options] [IN [OUT]]
//
// Reads a point cloud (.xyz/.pwn or .ply), estimates normals when it has
// none, orients them consistently and outward, and writes the result
// (.xyz or .ply, by extension) through a temporary file and a rename, so
// an output file is either complete or absent.

#include <Normal_orientation/IO/Point_cloud_io.h>
#include <Normal_orientation/orient_normals.h>
#include <Normal_orientation/solvers/Lsa_tr_solver.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>
#include <Normal_orientation/streaming_orient_normals.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/jet_estimate_normals.h>
#include <CGAL/pca_estimate_normals.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#endif

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace NO = Normal_orientation;
namespace NP = Normal_orientation::parameters;
typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef Kernel::Vector_3 Vector;

namespace {

/// A bad command line: reported with the usage hint, exit status 2.
struct Usage_error : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// Reads the positions of a `Point_cloud` by index.
struct Cloud_point_map
{
  typedef std::size_t key_type;
  typedef Point value_type;
  typedef Point reference;
  typedef boost::readable_property_map_tag category;
  const NO::IO::Point_cloud* cloud;
  friend Point get(const Cloud_point_map& m, std::size_t i)
  {
    const auto& p = m.cloud->points[i];
    return Point(p[0], p[1], p[2]);
  }
};

/// Reads and writes the normals of a `Point_cloud` by index.
struct Cloud_normal_map
{
  typedef std::size_t key_type;
  typedef Vector value_type;
  typedef Vector reference;
  typedef boost::read_write_property_map_tag category;
  NO::IO::Point_cloud* cloud;
  friend Vector get(const Cloud_normal_map& m, std::size_t i)
  {
    const auto& n = m.cloud->normals[i];
    return Vector(n[0], n[1], n[2]);
  }
  friend void put(const Cloud_normal_map& m, std::size_t i, const Vector& v)
  {
    m.cloud->normals[i] = {v.x(), v.y(), v.z()};
  }
};

struct Options
{
  std::string input, output;
  unsigned int k = NO::default_number_of_neighbors;
  double radius = 0.0;
  std::string criterion = "hoppe";
  std::string solver = "qpbo-i";
  unsigned int orders = 3;
  std::string sign = "outward";
  bool has_viewpoint = false;
  double viewpoint[3] = {0, 0, 0};
  double prior_weight = 0.0;
  std::string normals = "jet";
  unsigned int normal_k = 18;
  int threads = 0;
  unsigned long seed = 0;
  bool json = false, quiet = false, ascii = false;
  bool stream = false;
  bool sign_given = false;
  std::string presorted;      // --stream: "", "x", "y" or "z"
  std::string components_dir; // --stream: one file per component there
  unsigned long long min_component_size = 0;
  bool min_component_size_given = false;
  bool write_segments = false; // --stream: the segment of each point in OUT (PLY)
  bool keep_order = false;     // --stream: OUT is IN in its own order and format
  unsigned long long batch_size = 0; // --stream: 0 = the library's default
  long refine_rounds = -1;            // --stream: -1 = the library's default
};

const char* usage_text =
  "usage: orient_normals [options] [IN [OUT]]\n"
  "\n"
  "Orients the normals of a point cloud consistently and outward.\n"
  "IN: .xyz/.pwn (x y z [nx ny nz] per line) or .ply (ascii or binary).\n"
  "OUT: .xyz or .ply, by extension (default: IN with '_oriented' added).\n"
  "Without IN, orients the sample cloud shipped with the library.\n"
  "Normals are estimated first when IN has none.\n"
  "\n"
  "options:\n"
  "  --k N                neighbours per point (default 12)\n"
  "  --radius R           neighbour radius (default: estimated from the data)\n"
  "  --criterion NAME     flip criterion: hoppe (default), xie, konig\n"
  "  --solver NAME        solver: qpbo-i (default: MST, then QPBO-I on the segment graph),\n"
  "                       mst (fastest), lsa-tr\n"
  "  --orders N           qpbo-i: random orders tried, the best is kept (default 3)\n"
  "  --sign NAME          component sign: outward (default), keep\n"
  "  --viewpoint X,Y,Z    make every component face this point instead\n"
  "  --prior-weight W     with --viewpoint: also a soft prior for every point to face\n"
  "                       it, of weight W * cos(angle) (edges weigh at most 1), which\n"
  "                       every solver weighs against the edges (default 0: none)\n"
  "  --normals NAME       estimator when IN has no normals: jet (default), pca\n"
  "  --normal-k N         neighbours of the normal estimator (default 18)\n"
  "  --threads N          at most N threads (default, or 0: all cores); the output\n"
  "                       does not depend on N (the same bytes)\n"
  "  --seed S             random seed of randomised solvers (default 0)\n"
  "  --stream             out of core, for clouds larger than memory: sort along the\n"
  "                       principal axis (temporary files in TMPDIR), sweep, segment,\n"
  "                       solve the segment graph; IN must have normals; OUT holds\n"
  "                       the points in sweep order (outward sign only); a one-line\n"
  "                       progress (stage, percent) on stderr when it is a terminal\n"
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

template <typename T>
T parse_number(const std::string& option, const std::string& text)
{
  std::istringstream in(text);
  T value;
  if (!(in >> value) || !in.eof())
    throw Usage_error("invalid value '" + text + "' for " + option);
  return value;
}

Options parse_options(int argc, char** argv)
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
    if (a == "--help" || a == "-h") {
      std::cout << usage_text;
      std::exit(0);
    } else if (a == "--k") {
      const long k = parse_number<long>(a, value());
      if (k < 1 || k > 1000)
        throw Usage_error("--k must be between 1 and 1000");
      o.k = unsigned(k);
    } else if (a == "--radius") {
      o.radius = parse_number<double>(a, value());
      if (!(o.radius > 0.0) || !std::isfinite(o.radius))
        throw Usage_error("--radius must be a number > 0");
    } else if (a == "--criterion") {
      o.criterion = value();
      if (o.criterion != "hoppe" && o.criterion != "xie" && o.criterion != "konig")
        throw Usage_error("unknown criterion '" + o.criterion + "' (hoppe, xie, konig)");
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
    } else if (a == "--viewpoint") {
      std::string v = value();
      for (char& c : v)
        if (c == ',')
          c = ' ';
      std::istringstream in(v);
      if (!(in >> o.viewpoint[0] >> o.viewpoint[1] >> o.viewpoint[2]) || !(in >> std::ws).eof() ||
          !std::isfinite(o.viewpoint[0] + o.viewpoint[1] + o.viewpoint[2]))
        throw Usage_error("--viewpoint needs X,Y,Z");
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
      if (r < 0 || r > 16)
        throw Usage_error("--refine must be a number of rounds between 0 and 16");
      o.refine_rounds = r;
    } else if (a.size() > 1 && a[0] == '-') {
      throw Usage_error("unknown option " + a);
    } else {
      positional.push_back(a);
    }
  }
  if (positional.size() > 2)
    throw Usage_error("too many arguments");
  if (o.prior_weight > 0.0 && !o.has_viewpoint)
    throw Usage_error("--prior-weight needs --viewpoint");
  if (o.stream && (o.has_viewpoint || (o.sign_given && o.sign != "outward")))
    throw Usage_error("--stream orients every component outward: --sign keep and --viewpoint are not supported");
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
  if (positional.empty()) {
    o.input = NORMAL_ORIENTATION_SAMPLE_CLOUD;
    o.output = "sample_oriented.ply";
  } else {
    o.input = positional[0];
    if (positional.size() == 2) {
      o.output = positional[1];
    } else {
      const std::size_t slash = o.input.find_last_of('/');
      const std::size_t dot = o.input.find_last_of('.');
      const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
      o.output = has_ext ? o.input.substr(0, dot) + "_oriented" + o.input.substr(dot)
                         : o.input + "_oriented.ply";
    }
  }
  if (o.write_segments && NO::IO::lower_case_extension(o.output) != ".ply")
    throw Usage_error("--write-segments needs a .ply OUT");
  if (o.keep_order && (NO::IO::lower_case_extension(o.input) == ".ply") !=
                        (NO::IO::lower_case_extension(o.output) == ".ply"))
    throw Usage_error("--keep-order writes OUT in the format of IN: OUT must be a .ply file for a .ply IN, "
                      "a .xyz or .pwn file for a .xyz or .pwn IN");
  return o;
}

/// A progress bar on stderr, drawn only when stderr is a terminal and the
/// run lasts long enough to need one.
class Progress_bar
{
public:
  explicit Progress_bar(bool enabled)
    : m_enabled(enabled && isatty(2)), m_start(std::chrono::steady_clock::now())
  {}
  bool operator()(double x)
  {
    if (!m_enabled)
      return true;
    const int percent = int(x * 100.0);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    if (percent == m_last || elapsed < 0.5)
      return true;
    m_last = percent;
    const int width = 40, filled = percent * width / 100;
    std::fprintf(stderr, "\r[%s%s] %3d%%", std::string(std::size_t(filled), '#').c_str(),
                 std::string(std::size_t(width - filled), ' ').c_str(), percent);
    m_drawn = true;
    return true;
  }
  void finish()
  {
    if (m_drawn)
      std::fprintf(stderr, "\r%60s\r", "");
    m_drawn = false;
  }

private:
  bool m_enabled;
  std::chrono::steady_clock::time_point m_start;
  int m_last = -1;
  bool m_drawn = false;
};

/// The one-line progress of --stream on stderr: the stage and, when its
/// size is known, a bar and a percentage, in the style of `Progress_bar`;
/// drawn only when stderr is a terminal and the run lasts long enough, and
/// erased when done (also when an error unwinds).
class Stage_progress_line
{
public:
  explicit Stage_progress_line(bool enabled)
    : m_enabled(enabled && isatty(2)), m_start(std::chrono::steady_clock::now())
  {}
  ~Stage_progress_line() { finish(); }
  Stage_progress_line(const Stage_progress_line&) = delete;
  Stage_progress_line& operator=(const Stage_progress_line&) = delete;
  bool operator()(const NO::Progress_info& p)
  {
    if (!m_enabled)
      return true;
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - m_start).count() < 0.5)
      return true;
    const int percent = p.total > 0 ? int(p.stage_fraction() * 100.0) : -1;
    const bool same = p.stage == m_stage && percent == m_percent;
    if (same && (percent >= 0 || std::chrono::duration<double>(now - m_drawn_at).count() < 0.25))
      return true;
    m_stage = p.stage;
    m_percent = percent;
    m_drawn_at = now;
    char line[96];
    if (percent >= 0) {
      const int width = 40, filled = percent * width / 100;
      std::snprintf(line, sizeof line, "%-10s [%s%s] %3d%%", NO::stage_name(p.stage),
                    std::string(std::size_t(filled), '#').c_str(), std::string(std::size_t(width - filled), ' ').c_str(),
                    percent);
    } else
      std::snprintf(line, sizeof line, "%-10s %llu points", NO::stage_name(p.stage),
                    (unsigned long long)p.done);
    std::fprintf(stderr, "\r%-60s", line);
    m_drawn = true;
    return true;
  }
  void finish()
  {
    if (m_drawn)
      std::fprintf(stderr, "\r%60s\r", "");
    m_drawn = false;
  }

private:
  bool m_enabled;
  std::chrono::steady_clock::time_point m_start, m_drawn_at;
  NO::Stage m_stage = NO::Stage::SCAN;
  int m_percent = -2;
  bool m_drawn = false;
};

std::string json_escape(const std::string& s)
{
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\')
      out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
      continue;
    }
    out += c;
  }
  return out;
}

template <typename Criterion, typename Sign, typename Range, typename Np>
NO::Orientation_result run(Range& range, const Np& np, const Criterion& criterion, const Sign& sign,
                           const Options& o)
{
  if (o.solver == "qpbo-i")
    return NO::orient_normals(
      range, np.flip_criterion(criterion).component_sign(sign).solver(NO::Qpbo_i_solver(o.orders, o.seed)));
  if (o.solver == "lsa-tr")
    return NO::orient_normals(range, np.flip_criterion(criterion).component_sign(sign).solver(NO::Lsa_tr_solver()));
  return NO::orient_normals(range, np.flip_criterion(criterion).component_sign(sign).solver(NO::Mst_solver()));
}

template <typename Range, typename Np>
NO::Orientation_result run_with_criterion(Range& range, const Np& np, const Options& o, std::vector<double>& prior)
{
  auto with_sign = [&](const auto& criterion) {
    if (o.has_viewpoint) {
      const NO::Viewpoint_component_sign towards(o.viewpoint[0], o.viewpoint[1], o.viewpoint[2]);
      if (!prior.empty())
        return run(range, np.orientation_prior_map(CGAL::make_property_map(prior)), criterion, towards, o);
      return run(range, np, criterion, towards, o);
    }
    if (o.sign == "keep")
      return run(range, np, criterion, NO::Keep_component_sign(), o);
    return run(range, np, criterion, NO::Outward_component_sign(), o);
  };
  if (o.criterion == "xie")
    return with_sign(NO::Xie_criterion());
  if (o.criterion == "konig")
    return with_sign(NO::Konig_criterion());
  return with_sign(NO::Hoppe_criterion());
}

/// --stream: the out-of-core pipeline, file to file.
int run_stream(const Options& o, std::chrono::steady_clock::time_point t0)
{
  const NO::Presorted_axis axis = o.presorted == "x"   ? NO::Presorted_axis::X
                                  : o.presorted == "y" ? NO::Presorted_axis::Y
                                  : o.presorted == "z" ? NO::Presorted_axis::Z
                                                       : NO::Presorted_axis::NONE;
  NO::Component_files_options component_files;
  component_files.directory = o.components_dir; // in OUT's format
  const unsigned int refine_rounds =
    o.refine_rounds >= 0 ? unsigned(o.refine_rounds) : NO::streaming::Refinement_options().rounds;
  Stage_progress_line progress(!o.quiet);
  const auto np = NP::number_of_neighbors(o.k)
                    .neighbor_radius(o.radius)
                    .presorted_axis(axis)
                    .minimum_component_size(std::uint64_t(o.min_component_size))
                    .batch_size(o.batch_size != 0 ? std::size_t(o.batch_size) : std::size_t(1) << 18)
                    .refinement_rounds(refine_rounds)
                    .component_files(component_files)
                    .number_of_threads(o.threads)
                    .callback([&progress](const NO::Progress_info& p) { return progress(p); });
  NO::IO::Point_stream_write_options wo;
  wo.binary = !o.ascii;
  wo.segments = o.write_segments;
  NO::Streaming_result r;
  auto run = [&](const auto& criterion, const auto& solver) {
    if (o.keep_order)
      return NO::streaming_orient_files_in_input_order(o.input, o.output,
                                                       np.flip_criterion(criterion).solver(solver));
    return NO::streaming_orient_files(o.input, o.output, np.flip_criterion(criterion).solver(solver), wo);
  };
  auto with_solver = [&](const auto& criterion) {
    if (o.solver == "mst")
      return run(criterion, NO::Mst_solver());
    if (o.solver == "lsa-tr")
      return run(criterion, NO::Lsa_tr_solver());
    return run(criterion, NO::Qpbo_i_solver(o.orders, o.seed));
  };
  if (o.criterion == "xie")
    r = with_solver(NO::Xie_criterion());
  else if (o.criterion == "konig")
    r = with_solver(NO::Konig_criterion());
  else
    r = with_solver(NO::Hoppe_criterion());
  progress.finish();
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.quiet) {
    std::fprintf(stderr,
                 "oriented %llu points out of core%s: %llu edges (k = %u, r = %.6g), %zu segments, %zu component%s, "
                 "peak window %zu points, %llu normals flipped, %.3f s\n",
                 (unsigned long long)r.number_of_points, r.presorted ? " (presorted input)" : "",
                 (unsigned long long)r.number_of_edges, o.k, r.neighbor_radius, r.number_of_segments,
                 r.number_of_components, r.number_of_components == 1 ? "" : "s", r.peak_window,
                 (unsigned long long)r.number_of_flipped, total);
    if (r.number_of_dropped_components > 0)
      std::fprintf(stderr, "dropped %zu component%s of fewer than %llu points (%llu points)\n",
                   r.number_of_dropped_components, r.number_of_dropped_components == 1 ? "" : "s",
                   o.min_component_size, (unsigned long long)r.number_of_dropped_points);
    std::error_code ec;
    const std::string where = std::filesystem::absolute(o.output, ec).string();
    std::fprintf(stderr, "wrote %s\n", ec ? o.output.c_str() : where.c_str());
    if (!o.components_dir.empty()) {
      const std::string dir = std::filesystem::absolute(o.components_dir, ec).string();
      std::fprintf(stderr, "wrote %zu component file%s in %s\n", r.component_files.size(),
                   r.component_files.size() == 1 ? "" : "s", ec ? o.components_dir.c_str() : dir.c_str());
    }
  }
  if (o.json)
    std::printf("{\"input\": \"%s\", \"output\": \"%s\", \"mode\": \"stream\", \"points\": %llu, \"edges\": %llu, "
                "\"segments\": %zu, \"segment_edges\": %zu, \"components\": %zu, \"dropped_components\": %zu, "
                "\"dropped_points\": %llu, \"min_component_size\": %llu, \"component_files\": %zu, "
                "\"components_dir\": %s, \"presorted\": %s, \"keep_order\": %s, \"peak_window\": %zu, \"k\": %u, "
                "\"radius\": %.9g, \"radius_estimated\": %s, \"criterion\": \"%s\", \"solver\": \"%s\", "
                "\"threads\": %d, \"segment_energy_before\": %.9g, \"segment_energy_after\": %.9g, "
                "\"refinement_rounds\": %u, \"refinement_rounds_accepted\": %u, \"refinement_moves\": %llu, "
                "\"energy_before_refinement\": %.9g, \"energy_after_refinement\": %.9g, \"edge_span\": %llu, "
                "\"flipped\": %llu, "
                "\"seconds\": {\"frame\": %.6f, \"radius\": %.6f, \"sort\": %.6f, \"sweep\": %.6f, \"solve\": %.6f, "
                "\"refine\": %.6f, \"sign\": %.6f, \"output\": %.6f, \"components\": %.6f, \"total\": %.6f}}\n",
                json_escape(o.input).c_str(), json_escape(o.output).c_str(), (unsigned long long)r.number_of_points,
                (unsigned long long)r.number_of_edges, r.number_of_segments, r.number_of_segment_edges,
                r.number_of_components, r.number_of_dropped_components,
                (unsigned long long)r.number_of_dropped_points, o.min_component_size, r.component_files.size(),
                o.components_dir.empty() ? "null" : ("\"" + json_escape(o.components_dir) + "\"").c_str(),
                o.presorted.empty() ? "null" : ("\"" + o.presorted + "\"").c_str(), o.keep_order ? "true" : "false", r.peak_window, o.k,
                r.neighbor_radius, r.radius_estimated ? "true" : "false",
                o.criterion.c_str(), o.solver.c_str(), o.threads, r.segment_energy_before, r.segment_energy_after,
                refine_rounds, r.refinement_rounds_accepted, (unsigned long long)r.refinement_moves,
                r.energy_before_refinement, r.energy_after_refinement, (unsigned long long)r.edge_span,
                (unsigned long long)r.number_of_flipped, r.seconds.frame, r.seconds.radius, r.seconds.sort,
                r.seconds.sweep, r.seconds.solve, r.seconds.refine, r.seconds.sign, r.seconds.output,
                r.seconds.components, total);
  return 0;
}

int main_impl(int argc, char** argv)
{
  const auto t0 = std::chrono::steady_clock::now();
  const Options o = parse_options(argc, argv);
#ifdef CGAL_LINKED_WITH_TBB
  // --threads N: at most N threads in every parallel stage of the process,
  // normal estimation included (the library's own stages also run in an
  // arena of N threads, see number_of_threads)
  std::unique_ptr<tbb::global_control> thread_limit;
  if (o.threads > 0)
    thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                         std::size_t(o.threads));
#endif
  if (o.stream)
    return run_stream(o, t0);
  auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };

  // --threads bounds every stage: reading, orienting and writing.
  NO::IO::Read_options ro;
  ro.number_of_threads = unsigned(o.threads); // 0: automatic
  NO::IO::Point_cloud cloud = NO::IO::read_point_cloud(o.input, ro);
  const double read_seconds = since(t0);
  if (cloud.size() == 0)
    throw std::runtime_error(o.input + ": the file holds no point");

  // The program's own structure, seen through index-based property maps.
  std::vector<std::size_t> range(cloud.size());
  std::iota(range.begin(), range.end(), std::size_t(0));
  const Cloud_point_map point_map{&cloud};
  const Cloud_normal_map normal_map{&cloud};

  // Normal estimation, when the file has none.
  double estimate_seconds = 0.0;
  bool estimated = false;
  if (!cloud.has_normals()) {
    const auto t = std::chrono::steady_clock::now();
    if (cloud.size() < 4)
      throw std::runtime_error(o.input + ": too few points to estimate normals");
    cloud.normals.assign(cloud.size(), {0.0, 0.0, 0.0});
    const unsigned nk = unsigned(std::min<std::size_t>(o.normal_k, cloud.size() - 1));
    auto np = CGAL::parameters::point_map(point_map).normal_map(normal_map);
    if (o.normals == "pca")
      CGAL::pca_estimate_normals<CGAL::Parallel_if_available_tag>(range, nk, np);
    else
      CGAL::jet_estimate_normals<CGAL::Parallel_if_available_tag>(range, nk, np);
    estimate_seconds = since(t);
    estimated = true;
  }

  Progress_bar bar(!o.quiet);
  std::function<bool(double)> callback = [&bar](double x) { return bar(x); };
  auto np = NO::parameters::point_map(point_map)
              .normal_map(normal_map)
              .number_of_neighbors(o.k)
              .neighbor_radius(o.radius)
              .number_of_threads(o.threads)
              .random_seed(o.seed)
              .callback(callback);
  // The viewpoint prior: a_i = W cos(angle between n_i and p_i -> viewpoint).
  std::vector<double> prior;
  if (o.prior_weight > 0.0) {
    prior.resize(cloud.size(), 0.0);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      double to[3], dot = 0.0, lt = 0.0, ln = 0.0;
      for (int d = 0; d < 3; ++d) {
        to[d] = o.viewpoint[d] - cloud.points[i][d];
        dot += to[d] * cloud.normals[i][d];
        lt += to[d] * to[d];
        ln += cloud.normals[i][d] * cloud.normals[i][d];
      }
      if (lt > 0.0 && ln > 0.0)
        prior[i] = o.prior_weight * dot / std::sqrt(lt * ln);
    }
  }
  const NO::Orientation_result r = run_with_criterion(range, np, o, prior);
  bar.finish();

  const auto tw = std::chrono::steady_clock::now();
  NO::IO::Write_options wo;
  wo.binary = !o.ascii;
  wo.number_of_threads = ro.number_of_threads;
  // The digits the input text had (or the shortest exact text): values read
  // back from the output equal, bit for bit, those read from the input.
  wo.precision = NO::IO::Write_options::PRECISION_AS_READ;
  NO::IO::write_point_cloud(o.output, cloud, wo);
  const double write_seconds = since(tw);
  const double total_seconds = since(t0);

  if (!o.quiet) {
    std::fprintf(stderr,
                 "oriented %zu points%s: %zu edges (k = %u, r = %.6g), %zu component%s, energy %.6g -> %.6g, "
                 "%zu normals flipped, %.3f s\n",
                 r.number_of_points, estimated ? " (normals estimated)" : "", r.number_of_edges,
                 r.number_of_neighbors, r.neighbor_radius, r.number_of_components,
                 r.number_of_components == 1 ? "" : "s", r.energy_before, r.energy_after, r.number_of_flipped,
                 total_seconds);
    std::error_code ec;
    const std::string where = std::filesystem::absolute(o.output, ec).string();
    std::fprintf(stderr, "wrote %s\n", ec ? o.output.c_str() : where.c_str());
  }
  if (o.json) {
    std::printf("{\"input\": \"%s\", \"output\": \"%s\", \"points\": %zu, \"edges\": %zu, \"components\": %zu, "
                "\"k\": %u, \"radius\": %.9g, \"radius_estimated\": %s, \"criterion\": \"%s\", \"solver\": \"%s\", "
                "\"component_sign\": \"%s\", \"seed\": %lu, \"threads\": %d, \"normals_estimated\": %s, "
                "\"energy_before\": %.9g, \"energy_after\": %.9g, \"frustrated_edges\": %zu, \"segments\": %zu, "
                "\"unary_terms\": %zu, \"flipped\": %zu, "
                "\"zero_normals\": %zu, \"seconds\": {\"read\": %.6f, \"estimate_normals\": %.6f, "
                "\"neighbors\": %.6f, \"graph\": %.6f, \"solve\": %.6f, \"sign\": %.6f, \"orient_total\": %.6f, "
                "\"write\": %.6f, \"total\": %.6f}}\n",
                json_escape(o.input).c_str(), json_escape(o.output).c_str(), r.number_of_points, r.number_of_edges,
                r.number_of_components, r.number_of_neighbors, r.neighbor_radius,
                r.radius_estimated ? "true" : "false", r.criterion.c_str(), r.solver.c_str(),
                r.component_sign.c_str(), o.seed, o.threads, estimated ? "true" : "false", r.energy_before,
                r.energy_after, r.frustrated_edges, r.number_of_segments, r.number_of_unary_terms, r.number_of_flipped, r.number_of_zero_normals, read_seconds,
                estimate_seconds, r.seconds.neighbors, r.seconds.graph, r.seconds.solve, r.seconds.sign,
                r.seconds.total, write_seconds, total_seconds);
  }
  return 0;
}

} // namespace

/// SIGINT/SIGTERM: remove every temporary file (sort runs, record files, the
/// output being written), then die of the signal as usual.
extern "C" void on_terminating_signal(int sig)
{
  NO::remove_temporary_files();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

int main(int argc, char** argv)
{
  std::signal(SIGINT, on_terminating_signal);
  std::signal(SIGTERM, on_terminating_signal);
  try {
    return main_impl(argc, argv);
  } catch (const Usage_error& e) {
    std::fprintf(stderr, "orient_normals: %s (see --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "orient_normals: error: %s\n", e.what());
    return 1;
  }
}
