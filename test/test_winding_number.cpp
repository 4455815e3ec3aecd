// SPDX-License-Identifier: GPL-3.0-or-later
// Tests of Winding_number_field and estimate_point_areas: the treecode against
// the direct sum, a sampled sphere, a flipped patch, thread counts, areas,
// the caps of the smoothing widths and the layer gaps that give them.

#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/internal/Layer_gap.h>

#include "Synthetic_shapes.h"

#include <gtest/gtest.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

namespace NO = Normal_orientation;
using NO::test::Kernel;
using NO::test::Point;
using NO::test::Vector;
typedef NO::Winding_number_field<Kernel> Field;

namespace {

struct Cloud
{
  std::vector<Point> points;
  std::vector<Vector> normals;
  std::vector<double> areas;
};

Cloud make_cloud(const std::vector<NO::test::Sample>& samples)
{
  Cloud c;
  for (const NO::test::Sample& s : samples) {
    c.points.push_back(s.p);
    c.normals.push_back(s.n);
  }
  c.areas = NO::estimate_point_areas(c.points, c.normals);
  return c;
}

Cloud sphere_cloud(std::size_t n, unsigned seed)
{
  std::mt19937_64 rng(seed);
  return make_cloud(NO::test::sphere(n, rng));
}

/// queries: half uniform in [-1.6, 1.6]^3, half at distance `offset` on
/// either side of random samples, and a few on samples
std::vector<Point> make_queries(const Cloud& c, std::size_t m, unsigned seed, double offset = 0.02)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.6, 1.6);
  std::uniform_int_distribution<std::size_t> pick(0, c.points.size() - 1);
  std::vector<Point> q;
  for (std::size_t t = 0; t < m; ++t) {
    if (t % 2 == 0) {
      const double x = u(rng), y = u(rng), z = u(rng);
      q.push_back(Point(x, y, z));
    } else {
      const std::size_t i = pick(rng);
      const double side = t % 4 == 1 ? 1.0 : -1.0;
      q.push_back(t % 20 == 19 ? c.points[i] : c.points[i] + side * offset * c.normals[i]);
    }
  }
  return q;
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b)
{
  double e = 0.0;
  for (std::size_t t = 0; t < a.size(); ++t)
    e = std::max(e, std::abs(a[t] - b[t]));
  return e;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b)
{
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

} // namespace

TEST(Winding_number_areas, SumToTheAreaOfASphere)
{
  const Cloud c = sphere_cloud(20000, 1);
  double sum = 0.0;
  for (double a : c.areas) {
    ASSERT_GT(a, 0.0);
    sum += a;
  }
  std::cout << "sum of areas / 4 pi = " << sum / (4.0 * M_PI) << "\n";
  EXPECT_NEAR(sum / (4.0 * M_PI), 1.0, 0.03);
}

TEST(Winding_number_areas, RegularGridDuplicatesAndSmallClouds)
{
  // a 20 x 20 grid of spacing h in the plane z = 1: interior cells are h x h squares
  const double h = 0.1;
  std::vector<Point> points;
  std::vector<Vector> normals;
  for (int a = 0; a < 20; ++a)
    for (int b = 0; b < 20; ++b) {
      points.push_back(Point(a * h, b * h, 1.0));
      normals.push_back(Vector(0, 0, b % 2 ? 2.0 : -1.0)); // any length and sign
    }
  const std::vector<double> areas = NO::estimate_point_areas<CGAL::Sequential_tag>(points, normals);
  for (int a = 0; a < 20; ++a)
    for (int b = 0; b < 20; ++b) {
      const double area = areas[std::size_t(a * 20 + b)];
      if (a > 1 && a < 18 && b > 1 && b < 18) {
        EXPECT_NEAR(area, h * h, 1e-12);
      }
      EXPECT_TRUE(std::isfinite(area) && area > 0.0 && area < 8 * h * h) << area / (h * h);
    }
  // every point twice: each of a pair gets half the cell
  std::vector<Point> twice = points;
  twice.insert(twice.end(), points.begin(), points.end());
  std::vector<Vector> twice_normals = normals;
  twice_normals.insert(twice_normals.end(), normals.begin(), normals.end());
  const std::vector<double> halves = NO::estimate_point_areas(twice, twice_normals);
  EXPECT_NEAR(halves[5 * 20 + 5], 0.5 * h * h, 1e-12);
  EXPECT_NEAR(halves[400 + 5 * 20 + 5], 0.5 * h * h, 1e-12);
  // a zero normal: the disc estimate
  normals[5 * 20 + 5] = Vector(0, 0, 0);
  const std::vector<double> disc = NO::estimate_point_areas(points, normals);
  EXPECT_NEAR(disc[5 * 20 + 5], M_PI * 5 * h * h / 17.0, 1e-12); // d_16 = sqrt(5) h
  // 0 and 1 points; bad arguments
  EXPECT_TRUE(NO::estimate_point_areas(std::vector<Point>(), std::vector<Vector>()).empty());
  EXPECT_EQ(NO::estimate_point_areas(std::vector<Point>(1, Point(0, 0, 0)), std::vector<Vector>(1, Vector(0, 0, 1)))[0],
            0.0);
  EXPECT_THROW(NO::estimate_point_areas(points, normals, 0), std::invalid_argument);
  EXPECT_THROW(NO::estimate_point_areas(points, normals, 65), std::invalid_argument);
  normals.pop_back();
  EXPECT_THROW(NO::estimate_point_areas(points, normals), std::invalid_argument);
}

TEST(Winding_number_field, TreecodeMatchesTheDirectSum)
{
  for (int shape = 0; shape < 2; ++shape) {
    std::mt19937_64 rng(7);
    const Cloud c = shape == 0 ? make_cloud(NO::test::sphere(50000, rng)) : make_cloud(NO::test::torus(50000, rng));
    Field field;
    field.build(c.points, c.normals, c.areas);
    const std::vector<Point> q = make_queries(c, 2000, 11);
    std::vector<double> exact, approx;
    std::vector<Vector> exact_g, approx_g;
    field.evaluate_direct(q, exact, exact_g);
    // beta -> the bound on |w - w_direct| and on |grad w - grad_direct| / max(1, |grad_direct|)
    const double betas[3] = {1.5, 2.0, 3.0};
    const double bounds[3] = {0.05, 0.015, 0.003};
    for (int b = 0; b < 3; ++b) {
      field.set_opening_ratio(betas[b]);
      field.evaluate(q, approx, approx_g);
      double gradient_error = 0.0;
      for (std::size_t t = 0; t < q.size(); ++t) {
        const double scale = std::max(1.0, std::sqrt(exact_g[t].squared_length()));
        gradient_error = std::max(gradient_error, std::sqrt((approx_g[t] - exact_g[t]).squared_length()) / scale);
      }
      const double error = max_abs_difference(approx, exact);
      double mean = 0.0;
      for (std::size_t t = 0; t < q.size(); ++t)
        mean += std::abs(approx[t] - exact[t]) / double(q.size());
      std::cout << (shape == 0 ? "sphere" : "torus") << " beta " << betas[b] << ": mean |w error| " << mean
                << ", max |w error| " << error
                << ", max relative gradient error " << gradient_error << "\n";
      EXPECT_LT(error, bounds[b]);
      EXPECT_LT(gradient_error, 16.0 * bounds[b]);
      // one query at a time gives the same values
      for (std::size_t t = 0; t < q.size(); t += 97)
        EXPECT_EQ(field.value(q[t]), approx[t]);
    }
  }
}

TEST(Winding_number_field, SampledSphereIsOneInsideZeroOutsideHalfOnTheSurface)
{
  const Cloud c = sphere_cloud(20000, 3);
  Field field;
  field.build(c.points, c.normals, c.areas);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double inside = 0.0, outside = 0.0, surface = 0.0;
  for (int t = 0; t < 2000; ++t) {
    const double z = g(rng), y = g(rng), x = g(rng);
    const Vector d = NO::test::unit(Vector(x, y, z));
    inside = std::max(inside, std::abs(field.value(Point(0, 0, 0) + 0.8 * std::cbrt(u(rng)) * d) - 1.0));
    outside = std::max(outside, std::abs(field.value(Point(0, 0, 0) + (1.2 + 2.0 * u(rng)) * d)));
  }
  for (std::size_t i = 0; i < c.points.size(); i += 10)
    surface = std::max(surface, std::abs(field.value(c.points[i]) - 0.5));
  std::cout << "sphere: max |w - 1| inside " << inside << ", max |w| outside " << outside
            << ", max |w - 1/2| on samples " << surface << "\n";
  EXPECT_LT(inside, 0.03);
  EXPECT_LT(outside, 0.015);
  EXPECT_LT(surface, 0.05);
  // just off the surface, on either side of a sample
  const double eps = field.smoothing_width(0);
  EXPECT_GT(field.value(c.points[0] - 3.0 * eps * c.normals[0]), 0.75);
  EXPECT_LT(field.value(c.points[0] + 3.0 * eps * c.normals[0]), 0.25);
  // grad w points inward (-n) on the surface
  EXPECT_LT(field.gradient(c.points[0]) * c.normals[0], 0.0);
  // unsmoothed: still finite on the samples, and the same far from them
  Field sharp;
  sharp.set_smoothing_factor(0.0);
  sharp.build(c.points, c.normals, c.areas);
  EXPECT_TRUE(std::isfinite(sharp.value(c.points[0])));
  EXPECT_NEAR(sharp.value(Point(0.1, 0.2, 0.3)), field.value(Point(0.1, 0.2, 0.3)), 5e-3);
}

TEST(Winding_number_field, FlippingAPatchSubtractsTwiceItsField)
{
  const Cloud c = sphere_cloud(30000, 9);
  std::vector<std::size_t> patch;
  Cloud p;
  for (std::size_t i = 0; i < c.points.size(); ++i)
    if (c.points[i].z() > 0.4 && c.points[i].x() > -0.2) {
      patch.push_back(i);
      p.points.push_back(c.points[i]);
      p.normals.push_back(c.normals[i]);
      p.areas.push_back(c.areas[i]);
    }
  Field whole, part;
  whole.build(c.points, c.normals, c.areas);
  part.build(p.points, p.normals, p.areas);
  const std::vector<Point> q = make_queries(c, 1000, 13, 0.05);
  std::vector<double> before, own, after, before_direct, own_direct, after_direct;
  whole.evaluate(q, before);
  whole.evaluate_direct(q, before_direct);
  part.evaluate(q, own);
  part.evaluate_direct(q, own_direct);
  whole.negate(patch);
  EXPECT_TRUE(whole.is_negated(patch[0]));
  EXPECT_FALSE(whole.is_negated(0) && patch[0] != 0);
  whole.evaluate(q, after);
  whole.evaluate_direct(q, after_direct);
  double direct_error = 0.0, tree_error = 0.0, largest = 0.0;
  for (std::size_t t = 0; t < q.size(); ++t) {
    direct_error = std::max(direct_error, std::abs(after_direct[t] - (before_direct[t] - 2.0 * own_direct[t])));
    tree_error = std::max(tree_error, std::abs(after[t] - (before[t] - 2.0 * own[t])));
    largest = std::max(largest, std::abs(own_direct[t]));
  }
  std::cout << "flipped patch: max |w_P| " << largest << ", direct error " << direct_error << ", treecode error "
            << tree_error << "\n";
  EXPECT_GT(largest, 0.4);
  EXPECT_LT(direct_error, 1e-12);
  EXPECT_LT(tree_error, 0.02);

  // the same, bit for bit, as a field built with those normals negated
  std::vector<Vector> flipped = c.normals;
  for (std::size_t i : patch)
    flipped[i] = -flipped[i];
  Field rebuilt;
  rebuilt.build(c.points, flipped, c.areas);
  std::vector<double> fresh;
  rebuilt.evaluate(q, fresh);
  EXPECT_TRUE(same_bits(fresh, after));
  // and negating again restores the field exactly
  whole.negate(patch);
  whole.evaluate(q, after);
  EXPECT_TRUE(same_bits(before, after));
  EXPECT_THROW(whole.negate(std::vector<std::size_t>(1, c.points.size())), std::out_of_range);
}

TEST(Winding_number_field, SameOutputForOneAndTwoThreads)
{
  const Cloud c = sphere_cloud(100000, 17);
  const std::vector<Point> q = make_queries(c, 20000, 19);
  std::vector<double> values[3];
  std::vector<Vector> gradients[3];
  std::vector<double> areas[3];
  for (int run = 0; run < 3; ++run) {
    Field field;
    if (run == 0) {
      areas[run] = NO::estimate_point_areas<CGAL::Sequential_tag>(c.points, c.normals);
      field.build<CGAL::Sequential_tag>(c.points, c.normals, areas[run]);
      field.evaluate<CGAL::Sequential_tag>(q, values[run], gradients[run]);
      continue;
    }
#ifdef CGAL_LINKED_WITH_TBB
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(run));
    areas[run] = NO::estimate_point_areas<CGAL::Parallel_tag>(c.points, c.normals);
    field.build<CGAL::Parallel_tag>(c.points, c.normals, areas[run]);
    field.evaluate<CGAL::Parallel_tag>(q, values[run], gradients[run]);
#else
    areas[run] = areas[0];
    values[run] = values[0];
    gradients[run] = gradients[0];
#endif
  }
  for (int run = 1; run < 3; ++run) {
    EXPECT_TRUE(same_bits(areas[0], areas[run]));
    EXPECT_TRUE(same_bits(values[0], values[run]));
    bool same = true;
    for (std::size_t t = 0; t < q.size(); ++t)
      for (int k = 0; k < 3; ++k)
        same = same && gradients[0][t][k] == gradients[run][t][k];
    EXPECT_TRUE(same);
  }
}

TEST(Winding_number_field, GradientMatchesFiniteDifferences)
{
  std::mt19937_64 rng(23);
  const Cloud c = make_cloud(NO::test::torus(20000, rng));
  Field field;
  field.build(c.points, c.normals, c.areas);
  const std::vector<Point> q = make_queries(c, 200, 29, 0.05);
  const double h = 1e-5;
  for (const Point& x : q) {
    const Vector g = field.direct_gradient(x);
    for (int k = 0; k < 3; ++k) {
      const Vector e(k == 0 ? h : 0.0, k == 1 ? h : 0.0, k == 2 ? h : 0.0);
      const double fd = (field.direct_value(x + e) - field.direct_value(x - e)) / (2.0 * h);
      EXPECT_NEAR(g[k], fd, 1e-4 * std::max(1.0, std::abs(fd)));
    }
  }
}

// Two unit spheres that nearly touch, and a shell whose two walls are as close:
// the far field in the gap is near 1 across the contact and near 0 inside the
// wall, whereas the field itself reads about 0.6 and 0.35 there.
TEST(Winding_number_field, FarFieldTellsAContactFromAWall)
{
  const double gap = 0.02, exclusion = 0.3;
  const std::size_t n = 20000;
  std::mt19937_64 rng(13);
  Cloud contact, wall;
  const double offsets[2] = {-(1.0 + 0.5 * gap), 1.0 + 0.5 * gap};
  for (double x : offsets)
    for (const NO::test::Sample& s : NO::test::sphere(n, rng, Point(x, 0, 0))) {
      contact.points.push_back(s.p);
      contact.normals.push_back(s.n);
      contact.areas.push_back(4.0 * M_PI / double(n));
    }
  const double radii[2] = {1.0, 1.0 + gap}; // the inner wall faces the cavity
  for (double r : radii)
    for (const NO::test::Sample& s : NO::test::sphere(n, rng, Point(0, 0, 0), r)) {
      wall.points.push_back(s.p);
      wall.normals.push_back(r < 1.0 + 0.5 * gap ? -s.n : s.n);
      wall.areas.push_back(4.0 * M_PI * r * r / double(n));
    }
  const Point contact_gap(0, 0, 0), wall_gap(1.0 + 0.5 * gap, 0, 0);
  Field fc, fw;
  fc.build(contact.points, contact.normals, contact.areas);
  fw.build(wall.points, wall.normals, wall.areas);
  const double wc = fc.far_value(contact_gap, exclusion), ww = fw.far_value(wall_gap, exclusion);
  std::cout << "far field in the gap: contact " << wc << " (w " << fc.value(contact_gap) << "), wall " << ww
            << " (w " << fw.value(wall_gap) << ")\n";
  // Across the contact each sphere gives the solid angle of its left-out cap
  // over 4 pi: (1 - cos a) / 2, where cos a = 0.0545 / 0.3 at the rim of the
  // cap (0.3 from the gap's middle), so 0.818 for the two.
  EXPECT_NEAR(wc, 0.818, 0.03);
  EXPECT_LT(ww, 0.15);
  EXPECT_NEAR(wc, fc.direct_far_value(contact_gap, exclusion), 0.015);
  EXPECT_NEAR(ww, fw.direct_far_value(wall_gap, exclusion), 0.015);
  // the signs of the points within the exclusion radius do not matter
  std::vector<std::size_t> near;
  for (std::size_t i = 0; i < wall.points.size(); ++i)
    if (std::sqrt((wall.points[i] - wall_gap).squared_length()) < exclusion)
      near.push_back(i);
  ASSERT_GT(near.size(), 100u);
  const double before = fw.value(wall_gap);
  fw.negate(near);
  EXPECT_EQ(fw.far_value(wall_gap, exclusion), ww);
  EXPECT_GT(std::abs(fw.value(wall_gap) - before), 0.3); // while the field itself changed
}

TEST(Winding_number_field, FarFieldMatchesTheDirectSum)
{
  const Cloud c = sphere_cloud(20000, 17);
  Field field;
  field.build(c.points, c.normals, c.areas);
  const std::vector<Point> q = make_queries(c, 600, 19);
  const double radii[5] = {0.0, 0.05, 0.3, 1.0, 10.0};
  std::vector<double> exclusions(q.size());
  for (std::size_t t = 0; t < q.size(); ++t)
    exclusions[t] = radii[t % 5];
  std::vector<double> values, sequential;
  field.evaluate_far(q, exclusions, values);
  field.evaluate_far<CGAL::Sequential_tag>(q, exclusions, sequential);
  EXPECT_TRUE(same_bits(values, sequential));
  double error = 0.0;
  for (std::size_t t = 0; t < q.size(); ++t) {
    EXPECT_EQ(values[t], field.far_value(q[t], exclusions[t]));
    error = std::max(error, std::abs(values[t] - field.direct_far_value(q[t], exclusions[t])));
    if (exclusions[t] == 0.0) { // nothing left out: the field itself
      EXPECT_NEAR(values[t], field.value(q[t]), 1e-12);
    }
    if (exclusions[t] == 10.0) { // everything left out
      EXPECT_EQ(values[t], 0.0);
    }
  }
  std::cout << "far field: max |error| against the direct sum " << error << "\n";
  EXPECT_LT(error, 0.015); // the bound of the full field at the default opening ratio
  EXPECT_THROW(field.far_value(q[0], -1.0), std::invalid_argument);
  EXPECT_THROW(field.direct_far_value(q[0], std::nan("")), std::invalid_argument);
  EXPECT_THROW(field.evaluate_far(q, std::vector<double>(3, 0.0), values), std::invalid_argument);
  exclusions[5] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(field.evaluate_far(q, exclusions, values), std::invalid_argument);
}

TEST(Winding_number_field, SmallAndBadInputs)
{
  Field empty;
  EXPECT_EQ(empty.size(), 0u);
  EXPECT_EQ(empty.value(Point(1, 2, 3)), 0.0);
  EXPECT_EQ(empty.gradient(Point(1, 2, 3)), Vector(0, 0, 0));
  // one point: the formula itself; a zero normal contributes nothing
  Field one;
  one.build(std::vector<Point>{Point(0, 0, 0), Point(5, 5, 5)}, std::vector<Vector>{Vector(0, 0, 2), Vector(0, 0, 0)},
            std::vector<double>{0.5, 1.0});
  const double r = 2.0, e2 = 0.5;
  EXPECT_NEAR(one.value(Point(0, 0, -r)), 0.5 * r / std::pow(r * r + e2, 1.5) / (4.0 * M_PI), 1e-15);
  EXPECT_NEAR(one.direct_value(Point(0, 0, -r)), one.value(Point(0, 0, -r)), 1e-15);
  EXPECT_EQ(one.value(Point(0, 0, 0)), 0.0);
  std::vector<Point> pts(3, Point(0, 0, 0));
  std::vector<Vector> nrm(3, Vector(0, 0, 1));
  EXPECT_THROW(empty.build(pts, nrm, std::vector<double>(2, 1.0)), std::invalid_argument);
  EXPECT_THROW(empty.build(pts, nrm, std::vector<double>{1.0, -1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(empty.build(pts, nrm, std::vector<double>(3, 1.0), 0), std::invalid_argument);
  pts[1] = Point(std::nan(""), 0, 0);
  EXPECT_THROW(empty.build(pts, nrm, std::vector<double>(3, 1.0)), std::invalid_argument);
  EXPECT_THROW(empty.set_opening_ratio(0.0), std::invalid_argument);
  EXPECT_THROW(empty.set_smoothing_factor(-1.0), std::invalid_argument);
  // coincident points (a node of radius 0) and a leaf size of 1
  Field same;
  same.build(std::vector<Point>(100, Point(1, 1, 1)), std::vector<Vector>(100, Vector(1, 0, 0)),
             std::vector<double>(100, 0.01), 1);
  EXPECT_NEAR(same.value(Point(0, 1, 1)), same.direct_value(Point(0, 1, 1)), 1e-15);
  EXPECT_TRUE(std::isfinite(same.value(Point(1, 1, 1))));
}

TEST(Winding_number_field, WidthCapsSharpenTheFieldAtAContact)
{
  // Two unit spheres, all normals outward, 0.4 spacings apart.  The energy
  // sum a (w - 1/2)^2 over the contact samples of the first sphere tells the
  // right signs from those with the second sphere's contact region P
  // negated (w moves by -2 w_P) only weakly when the field is smoothed over
  // one spacing: w_P reads well above 0 outside P's sphere.  With the widths
  // near the contact capped (at 0.35 spacings, as the global stage floors
  // its caps), the right signs cost clearly less than the negated ones.
  std::mt19937_64 rng(5);
  const double gap = 0.01; // (the spacing is about 0.025)
  std::vector<NO::test::Sample> a = NO::test::sphere(20000, rng), b = NO::test::sphere(20000, rng, Point(2.0 + gap, 0, 0));
  a.insert(a.end(), b.begin(), b.end());
  const Cloud c = make_cloud(a);
  const std::size_t n = c.points.size();
  std::vector<double> caps(n, HUGE_VAL);
  std::vector<std::size_t> contact;   // (samples of the first sphere within 0.02 of the second)
  Cloud region;                        // P: those of the second sphere within 0.02 of the first
  std::vector<double> region_caps;
  for (std::size_t i = 0; i < n; ++i) {
    const bool first = i < 20000;
    const double to_other = std::sqrt(CGAL::squared_distance(c.points[i], first ? Point(2.0 + gap, 0, 0) : Point(0, 0, 0))) - 1.0;
    if (to_other < 0.02) {
      caps[i] = 0.35 * std::sqrt(c.areas[i]);
      if (first) {
        contact.push_back(i);
      } else {
        region.points.push_back(c.points[i]);
        region.normals.push_back(c.normals[i]);
        region.areas.push_back(c.areas[i]);
        region_caps.push_back(caps[i]);
      }
    }
  }
  ASSERT_GT(contact.size(), 20u);
  ASSERT_GT(region.points.size(), 20u);
  Field smooth, sharp, smooth_p, sharp_p;
  smooth.build(c.points, c.normals, c.areas);
  sharp.build(c.points, c.normals, c.areas, caps);
  smooth_p.build(region.points, region.normals, region.areas);
  sharp_p.build(region.points, region.normals, region.areas, region_caps);
  auto energies = [&](const Field& all, const Field& p, double& right, double& negated) {
    right = negated = 0.0;
    for (std::size_t i : contact) {
      const double w = all.value(c.points[i]), wp = p.value(c.points[i]);
      right += c.areas[i] * (w - 0.5) * (w - 0.5);
      negated += c.areas[i] * (w - 2.0 * wp - 0.5) * (w - 2.0 * wp - 0.5);
    }
  };
  double smooth_right, smooth_negated, sharp_right, sharp_negated;
  energies(smooth, smooth_p, smooth_right, smooth_negated);
  energies(sharp, sharp_p, sharp_right, sharp_negated);
  std::cout << "contact samples " << contact.size() << ", region " << region.points.size()
            << ": energy right / P negated " << smooth_right << " / " << smooth_negated << " smoothed, "
            << sharp_right << " / " << sharp_negated << " with caps\n";
  EXPECT_GT(sharp_negated / sharp_right, 1.5 * (smooth_negated / smooth_right));
  EXPECT_GT(sharp_negated, 3.0 * sharp_right);
  EXPECT_LT(sharp_right, smooth_right);
  // the caps are used by the treecode as by the direct sum, and by the widths
  std::vector<Point> q;
  for (std::size_t t = 0; t < contact.size(); ++t)
    q.push_back(c.points[contact[t]] + Vector(0.5 * gap, 0.0, 0.0));
  const std::vector<Point> far = make_queries(c, 500, 3);
  q.insert(q.end(), far.begin(), far.end());
  std::vector<double> exact, approx;
  sharp.evaluate_direct(q, exact);
  sharp.evaluate(q, approx);
  EXPECT_LT(max_abs_difference(approx, exact), 0.015);
  EXPECT_DOUBLE_EQ(sharp.smoothing_width(contact[0]), 0.35 * std::sqrt(c.areas[contact[0]]));
  EXPECT_DOUBLE_EQ(sharp.width_cap(contact[0]), 0.35 * std::sqrt(c.areas[contact[0]]));
  std::size_t leftmost = 0; // (far from the contact)
  for (std::size_t i = 0; i < 20000; ++i)
    if (c.points[i].x() < c.points[leftmost].x())
      leftmost = i;
  EXPECT_EQ(sharp.width_cap(leftmost), HUGE_VAL);
  EXPECT_DOUBLE_EQ(sharp.smoothing_width(leftmost), smooth.smoothing_width(leftmost));
  EXPECT_EQ(smooth.width_cap(contact[0]), HUGE_VAL);
  // no caps (all +inf) is the field without caps, bit for bit
  Field none;
  none.build(c.points, c.normals, c.areas, std::vector<double>(n, HUGE_VAL));
  std::vector<double> plain, capped;
  smooth.evaluate(q, plain);
  none.evaluate(q, capped);
  EXPECT_EQ(plain, capped);
  // bad caps
  EXPECT_THROW(none.build(c.points, c.normals, c.areas, std::vector<double>(n - 1, 1.0)), std::invalid_argument);
  caps[7] = -1.0;
  EXPECT_THROW(none.build(c.points, c.normals, c.areas, caps), std::invalid_argument);
  caps[7] = std::nan("");
  EXPECT_THROW(none.build(c.points, c.normals, c.areas, caps), std::invalid_argument);
}

TEST(Layer_gap, AnotherLayerIsSteepAndParallel)
{
  namespace I = NO::internal;
  const double p[3] = {0, 0, 0}, up[3] = {0, 0, 1};
  const double above[3] = {0.3, 0, 0.2}, beside[3] = {0.3, 0, 0.01};
  const double down[3] = {0, 0, -2}, tilted[3] = {0.5, 0, 1}, across[3] = {1, 0, 0}, zero[3] = {0, 0, 0};
  // a parallel layer above (slope 0.55, opposite normal of any length): its distance
  EXPECT_DOUBLE_EQ(I::layer_gap_to(p, up, above, down), std::sqrt(0.13));
  // the same surface (slope 0.03), a crease (normals at right angles), a
  // bend of 27 degrees (|cos| 0.89), a zero normal, the same position: none
  EXPECT_EQ(I::layer_gap_to(p, up, beside, up), HUGE_VAL);
  EXPECT_EQ(I::layer_gap_to(p, up, above, across), HUGE_VAL);
  EXPECT_EQ(I::layer_gap_to(p, up, above, tilted), HUGE_VAL);
  EXPECT_EQ(I::layer_gap_to(p, up, above, zero), HUGE_VAL);
  EXPECT_EQ(I::layer_gap_to(p, zero, above, up), HUGE_VAL);
  EXPECT_EQ(I::layer_gap_to(p, up, p, up), HUGE_VAL);
  // 8-bit codes: 0 for none, within 1/510 of the radius, at least 1, at most 255
  EXPECT_EQ(I::layer_gap_code(HUGE_VAL, 1.0), 0);
  EXPECT_EQ(I::layer_gap_value(0, 1.0), HUGE_VAL);
  for (double g : {1e-9, 0.003, 0.1, 0.4567, 0.99, 1.0, 3.0}) {
    const std::uint8_t code = I::layer_gap_code(g, 2.0);
    EXPECT_GE(code, 1);
    EXPECT_LE(std::abs(I::layer_gap_value(code, 2.0) - std::min(g, 2.0)), 2.0 / 255.0);
  }
  // the caps: the factor times the gaps, +inf without one; none when too
  // many points have a gap (noise) or no sample has one
  // (3 samples of a cloud of 100 points: a sample of area a stands for
  // points of spacing sqrt(3 a / 100); the floor binds on the last one)
  const std::vector<std::uint8_t> codes = {0, 51, 1};
  const std::vector<double> areas = {1.0, 0.01, 1.0};
  const std::vector<double> caps = I::contact_width_caps(codes, 30, 100, 2.0, areas);
  ASSERT_EQ(caps.size(), 3u);
  EXPECT_EQ(caps[0], HUGE_VAL);
  EXPECT_DOUBLE_EQ(caps[1], I::contact_width_factor * 0.4);
  EXPECT_DOUBLE_EQ(caps[2], I::contact_width_floor * std::sqrt(0.03));
  EXPECT_TRUE(I::contact_width_caps(codes, 36, 100, 2.0, areas).empty());
  EXPECT_TRUE(I::contact_width_caps(std::vector<std::uint8_t>(3, 0), 30, 100, 2.0, areas).empty());
}
