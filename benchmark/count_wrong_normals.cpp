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
#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/streaming/Point_record.h>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>

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

/// Kernel of the mesh and of the queries.
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
/// Point type.
using Point_3 = Kernel::Point_3;
/// Vector type.
using Vector_3 = Kernel::Vector_3;
/// Triangle type.
using Triangle_3 = Kernel::Triangle_3;
/// Iterator over the mesh triangles: the primitive id of the AABB tree.
using Triangle_iterator = std::vector<Triangle_3>::const_iterator;
/// Primitive of the AABB tree.
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangle_iterator>;
/// AABB tree over the mesh triangles.
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

/// Points read and processed at a time (56 MB of records).
constexpr std::size_t chunk_size = std::size_t(1) << 20;

/// Thrown on a bad command line (exit status 2).
struct Usage_error : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// The mesh: non-degenerate triangles (fan-triangulated faces) and their outward unit normals.
struct Reference_mesh
{
  /// Triangles with positive area, vertices in the order of the file.
  std::vector<Triangle_3> triangles;
  /// Unit normal of each triangle (right-hand rule: outward for an outward-oriented mesh).
  std::vector<Vector_3> normals;
  /// Bounding-box diagonal of the mesh vertices.
  double bbox_diagonal = 0.0;
};

/**
 * \brief Reads `path` as a polygon soup, fan-triangulates its faces and drops the triangles
 * of zero area.
 * \throws std::runtime_error if the file cannot be read or has no usable triangle.
 */
Reference_mesh read_mesh(const std::string& path)
{
  std::vector<Point_3> points;
  std::vector<std::vector<std::size_t>> polygons;
  std::error_code ec;
  if(!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error("cannot read mesh '" + path + "': no such file");
  if(!CGAL::IO::read_polygon_soup(path, points, polygons) || points.empty())
    throw std::runtime_error("cannot read mesh '" + path + "'");
  Reference_mesh mesh;
  const CGAL::Bbox_3 box = CGAL::bbox_3(points.begin(), points.end());
  mesh.bbox_diagonal = std::sqrt(CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                                 CGAL::square(box.zmax() - box.zmin()));
  for(const std::vector<std::size_t>& polygon : polygons)
  {
    for(std::size_t i : polygon)
      if(i >= points.size())
        throw std::runtime_error("mesh '" + path + "': vertex index out of range");
    for(std::size_t j = 1; j + 1 < polygon.size(); ++j)
    {
      const Triangle_3 t(points[polygon[0]], points[polygon[j]], points[polygon[j + 1]]);
      const Vector_3 c = CGAL::cross_product(t[1] - t[0], t[2] - t[0]);
      const double twice_area = std::sqrt(c.squared_length());
      if(!(twice_area > 0.0) || !std::isfinite(twice_area))
        continue;
      mesh.triangles.push_back(t);
      mesh.normals.push_back(c / twice_area);
    }
  }
  if(mesh.triangles.empty())
    throw std::runtime_error("mesh '" + path + "' has no triangle of positive area");
  return mesh;
}

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

/**
 * \brief Returns a closest triangle of the mesh to `p` and its squared distance to `p`.
 *
 * Fast path for points on the surface: the triangles meeting the box of half-size `h` around
 * `p` (`all_intersected_primitives`, exact box-triangle test) are the candidates; if the
 * closest of them is within `h`, it is the closest triangle of the mesh (any closer triangle
 * would meet the ball of radius `h`, hence the box). Otherwise, and when no triangle meets the
 * box, `closest_point_and_primitive` answers. Both give a closest triangle; between
 * equidistant triangles (a point on an edge) the choice may differ.
 */
std::pair<Triangle_iterator, double> closest_triangle(const Tree& tree, const Point_3& p, double h,
                                              std::vector<Triangle_iterator>& candidates)
{
  candidates.clear();
  const CGAL::Bbox_3 box(p.x() - h, p.y() - h, p.z() - h, p.x() + h, p.y() + h, p.z() + h);
  tree.all_intersected_primitives(box, std::back_inserter(candidates));
  double best = std::numeric_limits<double>::infinity();
  Triangle_iterator best_triangle{};
  for(const Triangle_iterator& t : candidates)
  {
    const double d2 = CGAL::squared_distance(p, *t);
    if(d2 < best)
    {
      best = d2;
      best_triangle = t;
    }
  }
  if(!candidates.empty() && best <= h * h)
    return {best_triangle, best};
  const Tree::Point_and_primitive_id hit = tree.closest_point_and_primitive(p);
  return {hit.second, CGAL::squared_distance(p, hit.first)};
}

/// Evaluates `records[begin, end)` against the mesh; `h` is the half-size of the fast-path box
/// of closest_triangle().
Counts evaluate(const Tree& tree, const Reference_mesh& mesh, const std::vector<NO::streaming::Point_record>& records,
                std::size_t begin, std::size_t end, double h, double far_squared)
{
  Counts counts;
  const Triangle_iterator first = mesh.triangles.begin();
  std::vector<Triangle_iterator> candidates;
  for(std::size_t i = begin; i < end; ++i)
  {
    const NO::streaming::Point_record& r = records[i];
    const Point_3 p(r.position[0], r.position[1], r.position[2]);
    const std::pair<Triangle_iterator, double> hit = closest_triangle(tree, p, h, candidates);
    const Vector_3& truth = mesh.normals[static_cast<std::size_t>(hit.first - first)];
    const double dot = truth.x() * r.normal[0] + truth.y() * r.normal[1] + truth.z() * r.normal[2];
    if(!(dot > 0.0))
      ++counts.wrong;
    const double d2 = hit.second;
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
  const Reference_mesh mesh = read_mesh(o.mesh);
  Tree tree(mesh.triangles.begin(), mesh.triangles.end());
  tree.build();
  tree.accelerate_distance_queries();
  (void)tree.closest_point_and_primitive(mesh.triangles.front()[0]); // builds the search tree now
  const double tree_seconds = since(start);

  const double far_distance = o.far * mesh.bbox_diagonal;
  const double far_squared = far_distance * far_distance;
  const double h = 1e-6 * mesh.bbox_diagonal; // fast path of closest_triangle()
  const auto query_start = Clock::now();
  double read_seconds = 0.0;
  Counts total;
  std::uint64_t n = 0;
  std::vector<NO::streaming::Point_record> chunk;
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
        partial.join(evaluate(tree, mesh, chunk, range.begin(), range.end(), h, far_squared));
        return partial;
      },
      [](Counts a, const Counts& b) {
        a.join(b);
        return a;
      });
#else
    const Counts counts = evaluate(tree, mesh, chunk, 0, chunk.size(), h, far_squared);
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
