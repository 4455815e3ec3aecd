// SPDX-License-Identifier: GPL-3.0-or-later
/// \file render_cloud.cpp
/// \brief render_cloud CLOUD OUT.png [--view AZ,EL] [--up AXIS] [--width W] [--height H]
/// [--color shading|wrong|segments] [--reference MESH.off] [--property NAME] [--splat F]
/// [--bits B] [--quiet]
///
/// A small headless renderer of oriented point clouds, for the pictures of the README: reads a
/// cloud with normals (.ply, .xyz or .pwn, with `IO::read_point_cloud()`) and writes a PNG
/// image (libpng). The view is orthographic, from the direction given by an azimuth and an
/// elevation around the up axis, fitted to the bounding box of the projected points. Each
/// point is a screen-space disk (a splat) whose radius follows the point spacing (the mean
/// distance to the 6th nearest neighbour, over a sample) and the image scale. A first pass
/// finds the depth of the front surface at each pixel (z-buffer); a second one gives the
/// pixel to the splat, among those within one spacing of that depth, whose centre is
/// closest (a mosaic of cells of the point spacing, the farther surfaces hidden). The image
/// is computed at twice the resolution, then averaged down (2 x 2 supersampling).
///
/// The shading is one-sided on purpose, so that a flipped patch shows: a normal facing the
/// viewer is shaded light grey (Lambert, light from the upper left), a normal facing away is
/// dark blue. Colour modes:
///  - `shading` (default): as above;
///  - `wrong`: with `--reference MESH.off` (closed, outward-oriented), the wrong normals in
///    red, the others shaded grey; a normal is wrong when its dot product with the outward
///    normal of the closest mesh triangle is <= 0 (`Reference_mesh.h`, as
///    `count_wrong_normals`), and the wrong count is printed;
///  - `segments`: colour from an integer vertex property of a PLY cloud (default `segment`,
///    as written by `orient_normals --stream --write-segments`), hashed to distinct colours,
///    darker where the normal faces away.
///
/// The output is deterministic (the same bytes for the same input and options, whatever the
/// number of threads). It is written to a temporary file in the directory of OUT and renamed
/// when complete: on any error no OUT appears (an existing OUT is left unchanged), the
/// program prints one line on stderr and exits with 1 (2 on a bad command line).
#include "Reference_mesh.h"

#include <Normal_orientation/IO/Point_cloud_io.h>

#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#endif

#include <png.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace {

namespace NO = Normal_orientation;
namespace NB = Normal_orientation::benchmark;

/// Thrown on a bad command line (exit status 2).
struct Usage_error : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// A vector of three doubles.
using Vec3 = std::array<double, 3>;

/// Dot product.
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// `a` scaled to unit length; zero if `a` is zero or not finite.
Vec3 normalized(const Vec3& a)
{
  const double length = std::sqrt(dot(a, a));
  if(!(length > 0.0) || !std::isfinite(length))
    return {0.0, 0.0, 0.0};
  return {a[0] / length, a[1] / length, a[2] / length};
}

/// What the points are coloured by.
enum class Color_mode
{
  SHADING,  ///< one-sided shading from the normal
  WRONG,    ///< wrong normals (against a reference mesh) in red
  SEGMENTS  ///< an integer vertex property, hashed to colours
};

/// Options of the program.
struct Options
{
  std::string cloud, output;
  double azimuth = 30.0, elevation = 15.0; // degrees
  int up_axis = 1;                          // 0, 1, 2: x, y, z
  bool up_negative = false;                 // -x, -y, -z
  int width = 800, height = 800;
  Color_mode mode = Color_mode::SHADING;
  std::string reference;                    // --color wrong
  std::string property = "segment";         // --color segments
  bool property_given = false;
  double splat = 1.0;
  int bits = 8; // significant bits per colour channel
  bool quiet = false;
};

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: render_cloud CLOUD OUT.png [--view AZ,EL] [--up AXIS] [--width W] [--height H]\n"
               "                    [--color shading|wrong|segments] [--reference MESH.off]\n"
               "                    [--property NAME] [--splat F] [--bits B] [--quiet]\n"
               "  Renders CLOUD (.ply, .xyz or .pwn, with normals) to a PNG image: orthographic view\n"
               "  from azimuth AZ and elevation EL degrees (default 30,15; 0,0 looks along -Z when\n"
               "  the up axis is y), fitted to the cloud, point splats with a z-buffer, 2x2\n"
               "  supersampling. One-sided shading: normals facing the viewer light grey, facing\n"
               "  away dark blue.\n"
               "  --up AXIS      up axis of the view: x, y (default), z, -x, -y or -z\n"
               "  --width W, --height H   image size in pixels (default 800 x 800, 16..4096)\n"
               "  --color shading   the shading above (default)\n"
               "  --color wrong     with --reference MESH.off (closed, outward-oriented): wrong\n"
               "                    normals (dot with the outward normal of the closest triangle\n"
               "                    <= 0) in red, the others shaded grey; prints the wrong count\n"
               "  --color segments  colour by the integer vertex property NAME of a PLY cloud\n"
               "                    (--property, default 'segment': orient_normals --stream\n"
               "                    --write-segments), hashed to distinct colours\n"
               "  --splat F      splat radius: F x the mean distance to the 6th neighbour (default 1)\n"
               "  --bits B       keep B significant bits per colour channel (1..8, default 8): a\n"
               "                 smaller PNG file (6 is hard to tell from 8)\n"
               "  --quiet        print nothing but errors\n"
               "  OUT is written to a temporary file and renamed when complete. Exit status: 0 ok,\n"
               "  1 error (one line on stderr, no OUT), 2 bad usage.\n");
}

/// Parses a double in [low, high]; throws Usage_error naming `option` otherwise.
double parse_double(const std::string& option, const std::string& text, double low, double high)
{
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if(text.empty() || end != text.c_str() + text.size() || errno != 0 || !(value >= low && value <= high))
    throw Usage_error("invalid " + option + " '" + text + "' (expected a number in [" + std::to_string(low) + ", " +
                      std::to_string(high) + "])");
  return value;
}

/// Parses an integer in [low, high]; throws Usage_error naming `option` otherwise.
int parse_int(const std::string& option, const std::string& text, int low, int high)
{
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text.c_str(), &end, 10);
  if(text.empty() || end != text.c_str() + text.size() || errno != 0 || value < low || value > high)
    throw Usage_error("invalid " + option + " '" + text + "' (expected an integer in [" + std::to_string(low) + ", " +
                      std::to_string(high) + "])");
  return static_cast<int>(value);
}

/// Parses the command line. \throws Usage_error on a bad one.
Options parse_options(int argc, char** argv)
{
  Options o;
  std::vector<std::string> positional;
  bool reference_given = false;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if(i + 1 >= argc)
        throw Usage_error("option " + arg + " needs a value");
      return argv[++i];
    };
    if(arg == "--view")
    {
      const std::string v = value();
      const std::size_t comma = v.find(',');
      if(comma == std::string::npos)
        throw Usage_error("invalid --view '" + v + "' (expected AZIMUTH,ELEVATION in degrees)");
      o.azimuth = parse_double("--view azimuth", v.substr(0, comma), -3600.0, 3600.0);
      o.elevation = parse_double("--view elevation", v.substr(comma + 1), -90.0, 90.0);
    }
    else if(arg == "--up")
    {
      std::string v = value();
      o.up_negative = !v.empty() && v[0] == '-';
      if(o.up_negative)
        v = v.substr(1);
      if(v != "x" && v != "y" && v != "z")
        throw Usage_error("invalid --up '" + std::string(argv[i]) + "' (x, y, z, -x, -y or -z)");
      o.up_axis = v[0] - 'x';
    }
    else if(arg == "--width")
      o.width = parse_int(arg, value(), 16, 4096);
    else if(arg == "--height")
      o.height = parse_int(arg, value(), 16, 4096);
    else if(arg == "--color")
    {
      const std::string v = value();
      if(v == "shading")
        o.mode = Color_mode::SHADING;
      else if(v == "wrong")
        o.mode = Color_mode::WRONG;
      else if(v == "segments")
        o.mode = Color_mode::SEGMENTS;
      else
        throw Usage_error("unknown --color '" + v + "' (shading, wrong, segments)");
    }
    else if(arg == "--reference")
    {
      o.reference = value();
      reference_given = true;
    }
    else if(arg == "--property")
    {
      o.property = value();
      o.property_given = true;
    }
    else if(arg == "--splat")
      o.splat = parse_double(arg, value(), 0.05, 20.0);
    else if(arg == "--bits")
      o.bits = parse_int(arg, value(), 1, 8);
    else if(arg == "--quiet" || arg == "-q")
      o.quiet = true;
    else if(arg.size() > 1 && arg[0] == '-')
      throw Usage_error("unknown option '" + arg + "'");
    else
      positional.push_back(arg);
  }
  if(positional.size() != 2)
    throw Usage_error("expected CLOUD and OUT.png");
  o.cloud = positional[0];
  o.output = positional[1];
  if(o.mode == Color_mode::WRONG && (!reference_given || o.reference.empty()))
    throw Usage_error("--color wrong needs --reference MESH.off");
  if(o.mode != Color_mode::WRONG && reference_given)
    throw Usage_error("--reference is only used with --color wrong");
  if(o.mode != Color_mode::SEGMENTS && o.property_given)
    throw Usage_error("--property is only used with --color segments");
  return o;
}

/// The orthographic camera: an orthonormal frame and the map from the plane to the pixels.
struct Camera
{
  Vec3 right{}, up{}, toward{}; // toward: from the scene to the viewer
  double centre_x = 0.0, centre_y = 0.0, scale = 1.0;
  int width = 0, height = 0; // pixels of the (supersampled) image

  /// Pixel coordinates (x to the right, y down) of `p`.
  std::pair<double, double> project(const Vec3& p) const
  {
    return {0.5 * width + (dot(p, right) - centre_x) * scale, 0.5 * height - (dot(p, up) - centre_y) * scale};
  }
};

/// The camera of the options, fitted to `points` in an image of `width` x `height` pixels
/// with a margin of 4 % on each side.
Camera make_camera(const Options& o, const std::vector<Vec3>& points, int width, int height)
{
  // the reference frame: right0 x up0 = front0 (right-handed), the view from front0 at 0,0
  static const int right_axis[3] = {1, 0, 0};
  static const int front_axis[3] = {2, 2, 1};
  static const double front_sign[3] = {-1.0, 1.0, -1.0};
  Vec3 right0{0, 0, 0}, up0{0, 0, 0}, front0{0, 0, 0};
  const double s = o.up_negative ? -1.0 : 1.0;
  right0[right_axis[o.up_axis]] = 1.0;
  up0[o.up_axis] = s;
  front0[front_axis[o.up_axis]] = s * front_sign[o.up_axis];
  const double a = o.azimuth * M_PI / 180.0, e = o.elevation * M_PI / 180.0;
  Camera c;
  for(int k = 0; k < 3; ++k)
  {
    c.toward[k] = std::cos(e) * (std::sin(a) * right0[k] + std::cos(a) * front0[k]) + std::sin(e) * up0[k];
    c.right[k] = std::cos(a) * right0[k] - std::sin(a) * front0[k];
  }
  c.toward = normalized(c.toward);
  c.right = normalized(c.right);
  c.up = normalized({c.toward[1] * c.right[2] - c.toward[2] * c.right[1],
                     c.toward[2] * c.right[0] - c.toward[0] * c.right[2],
                     c.toward[0] * c.right[1] - c.toward[1] * c.right[0]});
  double x_min = HUGE_VAL, x_max = -HUGE_VAL, y_min = HUGE_VAL, y_max = -HUGE_VAL;
  for(const Vec3& p : points)
  {
    const double x = dot(p, c.right), y = dot(p, c.up);
    x_min = (std::min)(x_min, x);
    x_max = (std::max)(x_max, x);
    y_min = (std::min)(y_min, y);
    y_max = (std::max)(y_max, y);
  }
  c.width = width;
  c.height = height;
  c.centre_x = 0.5 * (x_min + x_max);
  c.centre_y = 0.5 * (y_min + y_max);
  const double usable = 0.92;
  const double sx = x_max > x_min ? usable * width / (x_max - x_min) : HUGE_VAL;
  const double sy = y_max > y_min ? usable * height / (y_max - y_min) : HUGE_VAL;
  c.scale = (std::min)(sx, sy);
  if(!std::isfinite(c.scale) || !(c.scale > 0.0))
    c.scale = 1.0; // a single point, or all on the line of sight
  return c;
}

/// Mean distance from (up to 20,000 evenly spread) points to their 6th nearest neighbour:
/// the point spacing that sizes the splats. 0 when the cloud has fewer than 7 points.
double point_spacing(const std::vector<Vec3>& points)
{
  using Traits = CGAL::Search_traits_3<NB::Kernel>;
  using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
  constexpr unsigned int k = 6;
  if(points.size() <= k)
    return 0.0;
  std::vector<NB::Point_3> cgal_points;
  cgal_points.reserve(points.size());
  for(const Vec3& p : points)
    cgal_points.emplace_back(p[0], p[1], p[2]);
  const Search::Tree tree(cgal_points.begin(), cgal_points.end());
  const std::size_t step = (std::max)(std::size_t(1), points.size() / 20000);
  double sum = 0.0;
  std::size_t count = 0;
  for(std::size_t i = 0; i < cgal_points.size(); i += step)
  {
    const Search search(tree, cgal_points[i], k + 1); // the point itself and its k neighbours
    double farthest = 0.0;
    for(const auto& neighbor : search)
      farthest = (std::max)(farthest, neighbor.second);
    sum += std::sqrt(farthest);
    ++count;
  }
  return sum / static_cast<double>(count);
}

/// An RGB colour, components in [0, 1].
using Color = std::array<double, 3>;

/// `c` times `f`.
Color scaled(const Color& c, double f) { return {c[0] * f, c[1] * f, c[2] * f}; }

/// A well-mixed 64-bit hash of `x` (SplitMix64 finaliser).
std::uint64_t mix_bits(std::uint64_t x)
{
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// A distinct colour for the integer `id` (hashed hue, saturation and value).
Color segment_color(std::int64_t id)
{
  const std::uint64_t h = mix_bits(static_cast<std::uint64_t>(id));
  const double hue = static_cast<double>(h & 0xFFFFu) / 65536.0 * 6.0;
  const double saturation = 0.45 + 0.45 * static_cast<double>((h >> 16) & 0xFFu) / 255.0;
  const double value = 0.70 + 0.30 * static_cast<double>((h >> 24) & 0xFFu) / 255.0;
  const int sector = static_cast<int>(hue) % 6;
  const double f = hue - std::floor(hue);
  const double p = value * (1.0 - saturation), q = value * (1.0 - saturation * f),
               t = value * (1.0 - saturation * (1.0 - f));
  switch(sector)
  {
  case 0: return {value, t, p};
  case 1: return {q, value, p};
  case 2: return {p, value, t};
  case 3: return {p, q, value};
  case 4: return {t, p, value};
  default: return {value, p, q};
  }
}

/// Light grey of the front faces.
constexpr Color front_color{0.86, 0.86, 0.88};
/// Dark blue of the back faces.
constexpr Color back_color{0.16, 0.26, 0.66};
/// Red of the wrong normals.
constexpr Color wrong_color{0.90, 0.10, 0.08};

/// The colour of a point of unit normal `n` (zero if unknown), seen from `toward`, lit from
/// `light`; `wrong`: the point is wrong (mode WRONG), `base`: its segment colour (mode
/// SEGMENTS).
Color shade(Color_mode mode, const Vec3& n, const Vec3& toward, const Vec3& light, bool wrong, const Color& base)
{
  const bool front = dot(n, toward) > 0.0;
  const double lit = (std::max)(0.0, dot(n, light));    // front lighting
  const double back_lit = (std::max)(0.0, -dot(n, light)); // the back side, lit as if turned
  switch(mode)
  {
  case Color_mode::WRONG:
    if(wrong)
      return scaled(wrong_color, 0.55 + 0.45 * std::fabs(dot(n, light)));
    return front ? scaled(front_color, 0.22 + 0.78 * lit) : scaled(front_color, 0.12 + 0.25 * back_lit);
  case Color_mode::SEGMENTS:
    return front ? scaled(base, 0.35 + 0.65 * lit) : scaled(base, 0.12 + 0.18 * back_lit);
  case Color_mode::SHADING:
  default:
    if(front)
      return scaled(front_color, 0.22 + 0.78 * lit);
    // from the ambient grey of a grazing normal (at a silhouette) to the full back colour
    // of a normal turned 20 degrees or more away from the viewer
    const double t = (std::min)(1.0, -dot(n, toward) / 0.34);
    const Color grey = scaled(front_color, 0.22), blue = scaled(back_color, 0.35 + 0.55 * back_lit);
    return {(1.0 - t) * grey[0] + t * blue[0], (1.0 - t) * grey[1] + t * blue[1], (1.0 - t) * grey[2] + t * blue[2]};
  }
}

/// Writes the 8-bit RGB `pixels` (`width` x `height`, rows top to bottom) to the PNG file
/// `path` through a temporary file renamed when complete. \throws std::runtime_error.
void write_png(const std::string& path, const std::vector<unsigned char>& pixels, int width, int height)
{
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::error_code ec;
  if(fs::is_directory(target, ec))
    throw std::runtime_error("cannot write '" + path + "': it is a directory");
  const std::string temporary = path + ".tmp." + std::to_string(static_cast<long long>(::getpid()));
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  if(file == nullptr)
    throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = PNG_FORMAT_RGB;
  const bool written = png_image_write_to_stdio(&image, file, 0, pixels.data(), 0, nullptr) != 0;
  const std::string message = written ? std::string() : std::string(image.message);
  png_image_free(&image);
  const bool flushed = std::fflush(file) == 0 && !std::ferror(file);
  const int close_error = std::fclose(file) == 0 ? 0 : errno;
  if(!written || !flushed || close_error != 0)
  {
    fs::remove(temporary, ec);
    throw std::runtime_error("cannot write '" + path + "': " +
                             (!written ? message : std::string(std::strerror(close_error != 0 ? close_error : EIO))));
  }
  fs::rename(temporary, target, ec);
  if(ec)
  {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw std::runtime_error("cannot write '" + path + "': " + ec.message());
  }
}

/// Per point, the colour of its segment (`o.property`, an integer vertex
/// property of `cloud`); sets `number_of_segments` to the distinct values.
std::vector<Color> segment_colors_of(const NO::IO::Point_cloud& cloud, const Options& o,
                                     std::size_t& number_of_segments)
{
  const std::size_t n = cloud.size();
  std::vector<Color> segment_colors;
  const std::vector<NO::IO::Ply_property>& properties = cloud.extra_properties;
  std::size_t column = properties.size();
  std::string names;
  for(std::size_t k = 0; k < properties.size(); ++k)
  {
    if(properties[k].name == o.property)
      column = k;
    names += (names.empty() ? "" : ", ") + properties[k].name;
  }
  if(column == properties.size())
    throw std::runtime_error("'" + o.cloud + "' has no vertex property '" + o.property + "' (" +
                             (names.empty() ? std::string("no extra property") : "extra properties: " + names) + ")");
  segment_colors.resize(n);
  std::vector<std::int64_t> ids(n);
  for(std::size_t i = 0; i < n; ++i)
  {
    const double v = cloud.extra_values[i * properties.size() + column];
    if(!(std::fabs(v) < 9.0e15) || v != std::trunc(v))
      throw std::runtime_error("'" + o.cloud + "': vertex " + std::to_string(i) + ": property '" + o.property +
                               "' is not an integer");
    ids[i] = static_cast<std::int64_t>(v);
    segment_colors[i] = segment_color(ids[i]);
  }
  std::sort(ids.begin(), ids.end());
  number_of_segments = static_cast<std::size_t>(std::unique(ids.begin(), ids.end()) - ids.begin());
  return segment_colors;
}

/// Per point of `cloud`, 1 where its normal is wrong against the reference
/// mesh `o.reference`.
std::vector<char> wrong_normals_of(const NO::IO::Point_cloud& cloud, const Options& o)
{
  const std::size_t n = cloud.size();
  std::vector<char> wrong;
  const NB::Reference_normals reference(o.reference);
  wrong.assign(n, 0);
  auto evaluate = [&](std::size_t begin, std::size_t end) {
    std::vector<NB::Mesh_triangle_iterator> candidates;
    for(std::size_t i = begin; i < end; ++i)
    {
      const std::array<double, 3>& p = cloud.points[i];
      const std::pair<NB::Vector_3, double> truth = reference.truth(NB::Point_3(p[0], p[1], p[2]), candidates);
      wrong[i] = NB::Reference_normals::is_wrong(truth.first, cloud.normals[i].data()) ? 1 : 0;
    }
  };
#ifdef CGAL_LINKED_WITH_TBB
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 2048),
                    [&](const tbb::blocked_range<std::size_t>& r) { evaluate(r.begin(), r.end()); });
#else
  evaluate(0, n);
#endif
  return wrong;
}

/// Renders the cloud; returns the exit status.
int run(const Options& o)
{
  // Read and check everything before any work.
  const NO::IO::Point_cloud cloud = NO::IO::read_point_cloud(o.cloud);
  if(cloud.size() == 0)
    throw std::runtime_error("'" + o.cloud + "' holds no point");
  if(!cloud.has_normals())
    throw std::runtime_error("'" + o.cloud + "' has no normals");
  const std::size_t n = cloud.size();
  std::vector<Color> segment_colors; // per point, mode SEGMENTS
  std::size_t number_of_segments = 0;
  if(o.mode == Color_mode::SEGMENTS)
    segment_colors = segment_colors_of(cloud, o, number_of_segments);

  // Wrong normals against the reference mesh.
  std::vector<char> wrong;
  std::size_t number_of_wrong = 0;
  if(o.mode == Color_mode::WRONG)
  {
    wrong = wrong_normals_of(cloud, o);
    number_of_wrong = static_cast<std::size_t>(std::count(wrong.begin(), wrong.end(), char(1)));
  }

  // The camera, the splat radius and the z-buffer, at twice the resolution.
  constexpr int supersampling = 2;
  const int width = o.width * supersampling, height = o.height * supersampling;
  const std::vector<Vec3>& points = cloud.points;
  const Camera camera = make_camera(o, points, width, height);
  const double spacing = point_spacing(points);
  const double radius = (std::min)(64.0, (std::max)(0.75 * supersampling, o.splat * spacing * camera.scale));
  const double radius_squared = radius * radius;
  // Visibility splatting, in two passes over the points. 1: the depth of the front surface
  // at each pixel (the nearest splat). 2: among the splats covering a pixel whose depth is
  // within `tolerance` of that front depth (the front layer: its noise and its spacing), the
  // one whose centre is closest on screen gives the pixel its point (first point on ties).
  // The front layer is thus drawn as a mosaic of cells of the point spacing, whatever the
  // splat radius, and the farther surfaces are hidden.
  const double tolerance = spacing > 0.0 ? spacing : radius / camera.scale;
  const std::size_t number_of_pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<double> depth(number_of_pixels, -HUGE_VAL);
  std::vector<double> closest(number_of_pixels, HUGE_VAL);
  std::vector<std::int64_t> owner(number_of_pixels, -1);
  for(int pass = 0; pass < 2; ++pass)
    for(std::size_t i = 0; i < n; ++i)
    {
      const std::pair<double, double> xy = camera.project(points[i]);
      const double z = dot(points[i], camera.toward);
      if(!std::isfinite(xy.first) || !std::isfinite(xy.second) || !std::isfinite(z))
        continue;
      const int x_first = (std::max)(0, static_cast<int>(std::floor(xy.first - radius))),
                x_last = (std::min)(width - 1, static_cast<int>(std::floor(xy.first + radius)));
      const int y_first = (std::max)(0, static_cast<int>(std::floor(xy.second - radius))),
                y_last = (std::min)(height - 1, static_cast<int>(std::floor(xy.second + radius)));
      for(int y = y_first; y <= y_last; ++y)
      {
        const double dy = y + 0.5 - xy.second;
        for(int x = x_first; x <= x_last; ++x)
        {
          const double dx = x + 0.5 - xy.first;
          const double d2 = dx * dx + dy * dy;
          if(d2 > radius_squared)
            continue;
          const std::size_t pixel = static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + x;
          if(pass == 0)
            depth[pixel] = (std::max)(depth[pixel], z);
          else if(z >= depth[pixel] - tolerance && d2 < closest[pixel])
          {
            closest[pixel] = d2;
            owner[pixel] = static_cast<std::int64_t>(i);
          }
        }
      }
    }

  // Shade and average down (white background).
  const Vec3 light = normalized({-0.35 * camera.right[0] + 0.55 * camera.up[0] + camera.toward[0],
                                 -0.35 * camera.right[1] + 0.55 * camera.up[1] + camera.toward[1],
                                 -0.35 * camera.right[2] + 0.55 * camera.up[2] + camera.toward[2]});
  std::vector<Color> point_color(n);
  std::vector<char> point_shaded(n, 0);
  std::vector<unsigned char> pixels(static_cast<std::size_t>(o.width) * static_cast<std::size_t>(o.height) * 3);
  for(int y = 0; y < o.height; ++y)
    for(int x = 0; x < o.width; ++x)
    {
      Color sum{0.0, 0.0, 0.0};
      for(int sy = 0; sy < supersampling; ++sy)
        for(int sx = 0; sx < supersampling; ++sx)
        {
          const std::size_t pixel = static_cast<std::size_t>(y * supersampling + sy) * static_cast<std::size_t>(width) +
                                    static_cast<std::size_t>(x * supersampling + sx);
          const std::int64_t i = owner[pixel];
          Color c{1.0, 1.0, 1.0};
          if(i >= 0)
          {
            const std::size_t p = static_cast<std::size_t>(i);
            if(!point_shaded[p])
            {
              point_color[p] = shade(o.mode, normalized(cloud.normals[p]), camera.toward, light,
                                     !wrong.empty() && wrong[p] != 0,
                                     segment_colors.empty() ? Color{0, 0, 0} : segment_colors[p]);
              point_shaded[p] = 1;
            }
            c = point_color[p];
          }
          for(int k = 0; k < 3; ++k)
            sum[k] += c[k];
        }
      const double levels = static_cast<double>((1 << o.bits) - 1);
      for(int k = 0; k < 3; ++k)
      {
        const double v = (std::min)(1.0, (std::max)(0.0, sum[k] / (supersampling * supersampling)));
        pixels[(static_cast<std::size_t>(y) * static_cast<std::size_t>(o.width) + static_cast<std::size_t>(x)) * 3 +
               static_cast<std::size_t>(k)] =
          static_cast<unsigned char>(std::lround(255.0 * std::round(levels * v) / levels));
      }
    }
  write_png(o.output, pixels, o.width, o.height);

  if(!o.quiet)
  {
    std::printf("render_cloud: %zu points, %dx%d, view %g,%g, splat radius %.2f px", n, o.width, o.height, o.azimuth,
                o.elevation, radius / supersampling);
    if(o.mode == Color_mode::WRONG)
      std::printf(", wrong %zu (%.2f%%)", number_of_wrong, 100.0 * static_cast<double>(number_of_wrong) / double(n));
    if(o.mode == Color_mode::SEGMENTS)
      std::printf(", %zu distinct '%s' values", number_of_segments, o.property.c_str());
    std::printf(" -> %s\n", o.output.c_str());
  }
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
    std::fprintf(stderr, "render_cloud: %s (see --help)\n", e.what());
    return 2;
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "render_cloud: error: %s\n", e.what());
    return 1;
  }
}
