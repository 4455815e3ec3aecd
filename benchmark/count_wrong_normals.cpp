// SPDX-License-Identifier: GPL-3.0-or-later
// count_wrong_normals MESH.off CLOUD.ply [--json] [--far F]
//
// Scale-benchmark evaluator (issue 4): streams an oriented cloud with
// IO::Point_stream_reader (any order, any size: memory does not depend on the number of
// points) and counts its wrong normals against a closed, outward-oriented mesh. The truth of
// a point is the outward unit normal of the mesh triangle closest to it (CGAL::AABB_tree);
// its normal is wrong if their dot product is <= 0 (zero normals included). It also counts
// the points farther than F x (bounding-box diagonal of the mesh) from the mesh (default
// F = 0.001), which should be none for a cloud sampled on the mesh by make_large_cloud.
#include "Reference_mesh.h"

#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/Point_record.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iterator>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace {

namespace NO = Normal_orientation;

using Normal_orientation::benchmark::Point_3;
using Normal_orientation::benchmark::Reference_normals;
using Normal_orientation::benchmark::Vector_3;
/// Scratch space of the closest-triangle queries.
using Candidates = std::vector<Normal_orientation::benchmark::Mesh_triangle_iterator>;

/// Points read and processed at a time (56 MB of records).
constexpr std::size_t chunk_size = std::size_t(1) << 20;

/// Thrown on a bad command line (exit status 2).
struct Usage_error : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// Counts over a range of points (summed over the chunks and threads).
struct Counts
{
  /// Points whose normal has a dot product <= 0 with the outward normal of the closest triangle.
  std::uint64_t wrong = 0;
  /// Points farther than the `far` threshold from the mesh.
  std::uint64_t far = 0;
  /// Largest squared distance of a point to the mesh.
  double max_squared_distance = 0.0;

  /// Adds the counts of `other`.
  void join(const Counts& other)
  {
    wrong += other.wrong;
    far += other.far;
    max_squared_distance = (std::max)(max_squared_distance, other.max_squared_distance);
  }
};

/// Evaluates `records[begin, end)` against the mesh.
Counts evaluate(const Reference_normals& reference, const std::vector<NO::Point_record>& records,
                std::size_t begin, std::size_t end, double far_squared)
{
  Counts counts;
  Candidates candidates;
  for(std::size_t i = begin; i < end; ++i)
  {
    const NO::Point_record& r = records[i];
    const Point_3 p(r.position[0], r.position[1], r.position[2]);
    const std::pair<Vector_3, double> truth = reference.truth(p, candidates);
    if(Reference_normals::is_wrong(truth.first, r.normal))
      ++counts.wrong;
    const double d2 = truth.second;
    if(d2 > far_squared)
      ++counts.far;
    counts.max_squared_distance = (std::max)(counts.max_squared_distance, d2);
  }
  return counts;
}

/// Options of the program.
struct Options
{
  std::string mesh, cloud;
  bool json = false;
  double far = 0.001;
};

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: count_wrong_normals MESH.off CLOUD.ply [--json] [--far F]\n"
               "  Streams CLOUD (.ply, .xyz or .pwn, with normals) and counts the points whose normal has\n"
               "  a dot product <= 0 with the outward normal of the closest triangle of MESH (closed,\n"
               "  outward-oriented), and the points farther than F x bbox diagonal (default 0.001) from\n"
               "  MESH. Prints 'points N wrong W (P%%)'; with --json, a JSON line on stdout instead (the\n"
               "  text goes to stderr). Exit status: 0 ok, 1 error, 2 bad usage.\n");
}

/// Parses the command line. \throws Usage_error on a bad one.
Options parse_options(int argc, char** argv)
{
  Options o;
  std::vector<std::string> positional;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if(arg == "--json")
      o.json = true;
    else if(arg == "--far" && i + 1 < argc)
    {
      char* end = nullptr;
      const char* text = argv[++i];
      o.far = std::strtod(text, &end);
      if(end == text || *end != '\0' || !(o.far >= 0.0) || !std::isfinite(o.far))
        throw Usage_error(std::string("invalid --far '") + text + "'");
    }
    else if(arg.size() > 1 && arg[0] == '-')
      throw Usage_error("unknown or incomplete option '" + arg + "'");
    else
      positional.push_back(arg);
  }
  if(positional.size() != 2)
    throw Usage_error("expected MESH.off CLOUD.ply");
  o.mesh = positional[0];
  o.cloud = positional[1];
  return o;
}

/// Writes `text` as a JSON string body (quotes and backslashes escaped, control characters dropped).
std::string json_escape(const std::string& text)
{
  std::string out;
  for(char c : text)
  {
    if(c == '"' || c == '\\')
      out += '\\';
    if(static_cast<unsigned char>(c) >= 0x20)
      out += c;
  }
  return out;
}

/// Evaluates the cloud; returns the exit status.
int run(const Options& o)
{
  using Clock = std::chrono::steady_clock;
  const auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  const auto start = Clock::now();

  // Open the cloud first: a bad cloud is reported without building the tree.
  NO::IO::Point_stream_reader reader(o.cloud);
  if(!reader.has_normals())
    throw std::runtime_error("cloud '" + o.cloud + "' has no normals");
  const Reference_normals reference(o.mesh); // builds the tree
  const NO::benchmark::Reference_mesh& mesh = reference.mesh();
  const double tree_seconds = since(start);

  const double far_distance = o.far * mesh.bbox_diagonal;
  const double far_squared = far_distance * far_distance;
  const auto query_start = Clock::now();
  double read_seconds = 0.0;
  Counts total;
  std::uint64_t n = 0;
  std::vector<NO::Point_record> chunk;
  chunk.reserve(chunk_size);
  for(;;)
  {
    chunk.clear();
    const auto read_start = Clock::now();
    const std::size_t count = reader.read(chunk, chunk_size);
    read_seconds += since(read_start);
    if(count == 0)
      break;
    n += count;
#ifdef CGAL_LINKED_WITH_TBB
    const Counts counts = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, chunk.size(), 4096), Counts(),
      [&](const tbb::blocked_range<std::size_t>& range, Counts partial) {
        partial.join(evaluate(reference, chunk, range.begin(), range.end(), far_squared));
        return partial;
      },
      [](Counts a, const Counts& b) {
        a.join(b);
        return a;
      });
#else
    const Counts counts = evaluate(reference, chunk, 0, chunk.size(), far_squared);
#endif
    total.join(counts);
  }
  const double query_seconds = since(query_start) - read_seconds;
  const double seconds = since(start);
  if(n == 0)
    throw std::runtime_error("cloud '" + o.cloud + "' holds no point");

  const double percent = 100.0 * static_cast<double>(total.wrong) / static_cast<double>(n);
  const double max_distance = std::sqrt(total.max_squared_distance);
  std::FILE* text = o.json ? stderr : stdout;
  std::fprintf(text, "points %llu wrong %llu (%.4f%%)\n", static_cast<unsigned long long>(n),
               static_cast<unsigned long long>(total.wrong), percent);
  std::fprintf(text,
               "  %llu points farther than %g x bbox diagonal (%.6g) from the mesh, max distance %.3g "
               "(%.3g x diagonal); %zu triangles; %.2f s (tree %.2f, read %.2f, queries %.2f)\n",
               static_cast<unsigned long long>(total.far), o.far, far_distance, max_distance,
               max_distance / mesh.bbox_diagonal, mesh.triangles.size(), seconds, tree_seconds, read_seconds,
               query_seconds);
  if(o.json)
    std::printf("{\"mesh\": \"%s\", \"cloud\": \"%s\", \"points\": %llu, \"wrong\": %llu, \"wrong_percent\": %.6f, "
                "\"far\": %llu, \"far_threshold\": %.9g, \"max_distance\": %.9g, \"bbox_diagonal\": %.9g, "
                "\"triangles\": %zu, \"seconds\": {\"tree\": %.6f, \"read\": %.6f, \"queries\": %.6f, "
                "\"total\": %.6f}}\n",
                json_escape(o.mesh).c_str(), json_escape(o.cloud).c_str(), static_cast<unsigned long long>(n),
                static_cast<unsigned long long>(total.wrong), percent, static_cast<unsigned long long>(total.far),
                far_distance, max_distance, mesh.bbox_diagonal, mesh.triangles.size(), tree_seconds, read_seconds,
                query_seconds, seconds);
  return 0;
}

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  for(int i = 1; i < argc; ++i)
    if(std::string(argv[i]) == "-h" || std::string(argv[i]) == "--help")
    {
      print_usage(stdout);
      return 0;
    }
  try
  {
    return run(parse_options(argc, argv));
  }
  catch(const Usage_error& e)
  {
    std::fprintf(stderr, "count_wrong_normals: %s\n", e.what());
    print_usage(stderr);
    return 2;
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "count_wrong_normals: error: %s\n", e.what());
    return 1;
  }
}
