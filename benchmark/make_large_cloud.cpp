// SPDX-License-Identifier: GPL-3.0-or-later
// make_large_cloud MESH.off N OUT.ply [--angle-noise RADIANS] [--seed S] [--ascii]
//
// Scale-benchmark generator (issue 4): samples N points area-uniformly on a closed,
// outward-oriented triangle mesh and streams them to a PLY (or .xyz/.pwn) file with
// IO::Point_stream_writer, batch by batch, never holding the cloud: the memory used does
// not depend on N. The normal of a point is the unit normal of its triangle turned by a
// small Gaussian angle, then given a random sign. The output is the same for a seed
// whatever the batch size and the number of threads: every block of `rng_block_size`
// points has its own random generator, seeded from the seed and the block number.
#include "Mesh_sampler.h" // mix_seed, uniform_01, Gaussian_generator

#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/Point_record.h>

#include <CGAL/IO/polygon_soup_io.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace {

namespace NO = Normal_orientation;
namespace NB = Normal_orientation::benchmark;

/// Points per random-generator block: part of the definition of the output for a seed.
constexpr std::uint64_t rng_block_size = 65536;
/// Blocks generated (in parallel if TBB is available) before being written: 1M points, 56 MB.
constexpr std::uint64_t blocks_per_batch = 16;

/// Thrown on a bad command line (exit status 2).
struct Usage_error : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// A 3D vector of plain doubles.
using Vec3 = std::array<double, 3>;

/// One non-degenerate triangle of the mesh with its outward unit normal and a tangent basis.
struct Sampling_triangle
{
  /// Vertices.
  std::array<Vec3, 3> vertex;
  /// Unit normal (right-hand rule on the vertex order: outward for an outward-oriented mesh).
  Vec3 normal;
  /// Unit tangent vectors: (tangent_u, tangent_v, normal) is orthonormal.
  Vec3 tangent_u, tangent_v;
};

/// Returns the cross product `a x b`.
Vec3 cross(const Vec3& a, const Vec3& b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

/// Returns the Euclidean length of `a`.
double length(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

/// The mesh as a list of triangles with cumulative areas, for area-uniform sampling.
class Triangle_sampler
{
public:
  /**
   * \brief Reads `path` as a polygon soup (faces as in the file, fan-triangulated) and keeps
   * the triangles of positive area.
   * \throws std::runtime_error if the file cannot be read or has no usable triangle.
   */
  explicit Triangle_sampler(const std::string& path)
  {
    std::vector<NB::Point_3> points;
    std::vector<std::vector<std::size_t>> polygons;
    std::error_code ec;
    if(!std::filesystem::is_regular_file(path, ec))
      throw std::runtime_error("cannot read mesh '" + path + "': no such file");
    if(!CGAL::IO::read_polygon_soup(path, points, polygons) || points.empty())
      throw std::runtime_error("cannot read mesh '" + path + "'");
    Vec3 lo, hi;
    lo.fill(std::numeric_limits<double>::max());
    hi.fill(-std::numeric_limits<double>::max());
    for(const NB::Point_3& p : points)
      for(int d = 0; d < 3; ++d)
      {
        lo[d] = (std::min)(lo[d], p[d]);
        hi[d] = (std::max)(hi[d], p[d]);
      }
    m_bbox_diagonal = length({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});

    double total = 0.0;
    for(const std::vector<std::size_t>& polygon : polygons)
    {
      for(std::size_t i : polygon)
        if(i >= points.size())
          throw std::runtime_error("mesh '" + path + "': vertex index out of range");
      for(std::size_t j = 1; j + 1 < polygon.size(); ++j)
      {
        Sampling_triangle t;
        const std::size_t corner[3] = {polygon[0], polygon[j], polygon[j + 1]};
        for(int k = 0; k < 3; ++k)
          t.vertex[k] = {points[corner[k]].x(), points[corner[k]].y(), points[corner[k]].z()};
        const Vec3 e1 = {t.vertex[1][0] - t.vertex[0][0], t.vertex[1][1] - t.vertex[0][1],
                         t.vertex[1][2] - t.vertex[0][2]};
        const Vec3 e2 = {t.vertex[2][0] - t.vertex[0][0], t.vertex[2][1] - t.vertex[0][1],
                         t.vertex[2][2] - t.vertex[0][2]};
        const Vec3 c = cross(e1, e2);
        const double twice_area = length(c);
        if(!(twice_area > 0.0) || !std::isfinite(twice_area))
          continue; // degenerate: never sampled
        t.normal = {c[0] / twice_area, c[1] / twice_area, c[2] / twice_area};
        // Any unit vector orthogonal to the normal, then the third one.
        const Vec3 axis = std::abs(t.normal[0]) < 0.9 ? Vec3{1.0, 0.0, 0.0} : Vec3{0.0, 1.0, 0.0};
        const Vec3 u = cross(t.normal, axis);
        const double lu = length(u);
        t.tangent_u = {u[0] / lu, u[1] / lu, u[2] / lu};
        t.tangent_v = cross(t.normal, t.tangent_u);
        total += 0.5 * twice_area;
        m_triangles.push_back(t);
        m_cumulative_area.push_back(total);
      }
    }
    if(m_triangles.empty())
      throw std::runtime_error("mesh '" + path + "' has no triangle of positive area");
  }

  /// Returns the number of non-degenerate triangles.
  std::size_t number_of_triangles() const { return m_triangles.size(); }
  /// Returns the bounding-box diagonal of the mesh vertices.
  double bbox_diagonal() const { return m_bbox_diagonal; }

  /**
   * \brief Fills `out` with the points `first`, ..., `first + out.size() - 1` of block `block`
   * (whose generator is seeded from `seed` and `block` only).
   *
   * Per point, in this order: a triangle by inverse CDF of the areas (one uniform draw), a
   * point in it by the square-root rule (two draws), two N(0, 1) variates g1, g2 (Box-Muller,
   * two draws) turning the normal by the tangent offset sigma (g1 u + g2 v), i.e. by an angle
   * sigma sqrt(g1^2 + g2^2), then one draw for the sign. The variates are drawn even when
   * `angle_sigma` is 0, so positions and signs do not depend on the noise level.
   */
  void sample_block(std::uint64_t seed, std::uint64_t block, std::uint64_t first, double angle_sigma,
                    NO::Point_record* out, std::size_t count) const
  {
    std::mt19937_64 rng(NB::mix_seed(NB::mix_seed(seed) + block));
    NB::Gaussian_generator gaussian(rng);
    const double total = m_cumulative_area.back();
    for(std::size_t i = 0; i < count; ++i)
    {
      const double x = NB::uniform_01(rng) * total;
      std::size_t t = static_cast<std::size_t>(
        std::upper_bound(m_cumulative_area.begin(), m_cumulative_area.end(), x) - m_cumulative_area.begin());
      t = (std::min)(t, m_triangles.size() - 1);
      const Sampling_triangle& tri = m_triangles[t];
      const double s = std::sqrt(NB::uniform_01(rng));
      const double r = NB::uniform_01(rng);
      const double a = 1.0 - s, b = s * (1.0 - r), c = s * r;
      const double g1 = angle_sigma * gaussian();
      const double g2 = angle_sigma * gaussian();
      const bool flip = (rng() >> 63) != 0;

      NO::Point_record& record = out[i];
      for(int d = 0; d < 3; ++d)
        record.position[d] = a * tri.vertex[0][d] + b * tri.vertex[1][d] + c * tri.vertex[2][d];
      const double angle = std::sqrt(g1 * g1 + g2 * g2);
      const double along = std::cos(angle);
      const double across = angle > 0.0 ? std::sin(angle) / angle : 0.0;
      for(int d = 0; d < 3; ++d)
      {
        const double n = along * tri.normal[d] + across * (g1 * tri.tangent_u[d] + g2 * tri.tangent_v[d]);
        record.normal[d] = flip ? -n : n;
      }
      record.index = first + i;
    }
  }

private:
  std::vector<Sampling_triangle> m_triangles;
  std::vector<double> m_cumulative_area;
  double m_bbox_diagonal = 0.0;
};

/// Options of the program.
struct Options
{
  std::string mesh, output;
  std::uint64_t number_of_points = 0;
  double angle_noise = 0.05;
  std::uint64_t seed = 1;
  bool ascii = false;
};

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: make_large_cloud MESH.off N OUT.ply [--angle-noise RADIANS] [--seed S] [--ascii]\n"
               "  Streams N points sampled area-uniformly on MESH (closed, outward-oriented) to OUT\n"
               "  (.ply, binary little-endian doubles unless --ascii; or .xyz/.pwn), without holding\n"
               "  the cloud. Normal: the triangle's outward unit normal turned by a Gaussian angle\n"
               "  (standard deviation RADIANS per tangent axis, default 0.05), with a random sign.\n"
               "  Same seed (default 1) => same file. Exit status: 0 ok, 1 error, 2 bad usage.\n");
}

/// Parses an unsigned decimal integer in [minimum, maximum]; returns false otherwise.
bool parse_unsigned(const char* text, std::uint64_t minimum, std::uint64_t maximum, std::uint64_t& value)
{
  char* end = nullptr;
  if(text[0] == '-' || text[0] == '\0')
    return false;
  errno = 0;
  const unsigned long long v = std::strtoull(text, &end, 10);
  if(end == text || *end != '\0' || errno == ERANGE || v < minimum || v > maximum)
    return false;
  value = v;
  return true;
}

/// Parses the command line. \throws Usage_error on a bad one.
Options parse_options(int argc, char** argv)
{
  Options o;
  std::vector<std::string> positional;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if(arg == "--angle-noise" && has_value)
    {
      char* end = nullptr;
      const char* text = argv[++i];
      o.angle_noise = std::strtod(text, &end);
      if(end == text || *end != '\0' || !(o.angle_noise >= 0.0) || !(o.angle_noise <= 10.0))
        throw Usage_error(std::string("invalid --angle-noise '") + text + "' (radians in [0, 10])");
    }
    else if(arg == "--seed" && has_value)
    {
      if(!parse_unsigned(argv[++i], 0, UINT64_MAX, o.seed))
        throw Usage_error(std::string("invalid --seed '") + argv[i] + "'");
    }
    else if(arg == "--ascii")
      o.ascii = true;
    else if(arg.size() > 1 && arg[0] == '-')
      throw Usage_error("unknown or incomplete option '" + arg + "'");
    else
      positional.push_back(arg);
  }
  if(positional.size() != 3)
    throw Usage_error("expected MESH.off N OUT.ply");
  o.mesh = positional[0];
  if(!parse_unsigned(positional[1].c_str(), 1, std::uint64_t(1) << 40, o.number_of_points))
    throw Usage_error("invalid number of points '" + positional[1] + "' (1 to 2^40)");
  o.output = positional[2];
  return o;
}

/// Generates and writes the cloud; returns the exit status.
int run(const Options& o)
{
  const auto start = std::chrono::steady_clock::now();
  const Triangle_sampler sampler(o.mesh);
  NO::IO::Point_stream_write_options write_options;
  write_options.binary = !o.ascii;
  write_options.normals = true;
  NO::IO::Point_stream_writer writer(o.output, write_options);

  const std::uint64_t n = o.number_of_points;
  const std::uint64_t number_of_blocks = (n + rng_block_size - 1) / rng_block_size;
  std::vector<NO::Point_record> batch;
  double write_seconds = 0.0;
  for(std::uint64_t first_block = 0; first_block < number_of_blocks; first_block += blocks_per_batch)
  {
    const std::uint64_t last_block = (std::min)(first_block + blocks_per_batch, number_of_blocks);
    const std::uint64_t first_point = first_block * rng_block_size;
    const std::uint64_t end_point = (std::min)(last_block * rng_block_size, n);
    batch.resize(static_cast<std::size_t>(end_point - first_point));
    auto generate = [&](std::uint64_t block) {
      const std::uint64_t begin = block * rng_block_size;
      const std::uint64_t end = (std::min)(begin + rng_block_size, n);
      sampler.sample_block(o.seed, block, begin, o.angle_noise, batch.data() + (begin - first_point),
                           static_cast<std::size_t>(end - begin));
    };
#ifdef CGAL_LINKED_WITH_TBB
    tbb::parallel_for(tbb::blocked_range<std::uint64_t>(first_block, last_block, 1),
                      [&](const tbb::blocked_range<std::uint64_t>& range) {
                        for(std::uint64_t block = range.begin(); block != range.end(); ++block)
                          generate(block);
                      });
#else
    for(std::uint64_t block = first_block; block != last_block; ++block)
      generate(block);
#endif
    const auto write_start = std::chrono::steady_clock::now();
    writer.write(batch);
    write_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - write_start).count();
  }
  const auto commit_start = std::chrono::steady_clock::now();
  writer.commit();
  const auto end = std::chrono::steady_clock::now();
  write_seconds += std::chrono::duration<double>(end - commit_start).count();
  const double seconds = std::chrono::duration<double>(end - start).count();

  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(o.output, ec);
  std::printf("make_large_cloud: %llu points on %s (%zu triangles, bbox diagonal %.6g), angle noise %g rad, "
              "seed %llu\n",
              static_cast<unsigned long long>(n), o.mesh.c_str(), sampler.number_of_triangles(),
              sampler.bbox_diagonal(), o.angle_noise, static_cast<unsigned long long>(o.seed));
  std::printf("  %.2f s (%.2f s writing), %.3g points/s; wrote %s, %llu bytes (%.1f MB)\n", seconds,
              write_seconds, seconds > 0.0 ? static_cast<double>(n) / seconds : 0.0, o.output.c_str(),
              ec ? 0ull : static_cast<unsigned long long>(size), ec ? 0.0 : static_cast<double>(size) / 1e6);
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
    std::fprintf(stderr, "make_large_cloud: %s\n", e.what());
    print_usage(stderr);
    return 2;
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "make_large_cloud: error: %s\n", e.what());
    return 1;
  }
}
