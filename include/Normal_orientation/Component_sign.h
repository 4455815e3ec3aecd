// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_COMPONENT_SIGN_H
#define NORMAL_ORIENTATION_COMPONENT_SIGN_H

/// \file Component_sign.h
/// Component sign policies: the energy does not change when every label of
/// a connected component flips, so after the solve a policy decides the
/// sign of each component.  A policy is an accumulator that both drivers
/// feed, point by point, in as many passes as it asks for: the in-core
/// driver from its vectors (`component_signs()`), the streaming driver from
/// its record file.  Each rule therefore exists once.

#include <Normal_orientation/Orientation_problem.h>

#include <CGAL/number_utils.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationSign
/// What a sign accumulator is told before the passes over the points.
struct Component_sign_setup
{
  /// the number of components, numbered 0 ... number_of_components - 1
  std::size_t number_of_components = 0;
  /// the number of points of each component (the points fed to every pass)
  std::vector<std::uint64_t> component_size;
  /// the neighbour radius r of the graph
  double radius = 0.0;
};

/// \ingroup PkgNormalOrientationSign
/// One point as a sign accumulator sees it, in every pass, in the same
/// order each time.
struct Component_sign_point
{
  /// its component
  std::uint32_t component = 0;
  /// its position
  std::array<double, 3> position{{0.0, 0.0, 0.0}};
  /// its current orientation: the unit input normal times `label` (zero
  /// when the input normal is zero)
  std::array<double, 3> normal{{0.0, 0.0, 0.0}};
  /// the label the solver gave it: +1 keeps the input sign, -1 flips it
  Label label = 1;
  /// true when its input normal is known to be correctly oriented
  /// (`point_is_constrained_map`)
  bool constrained = false;
};

/// \ingroup PkgNormalOrientationSign
/// Leaves every component as the solver left it.
/// \cgalModels `ComponentSignPolicy`
struct Keep_component_sign
{
  /// the accumulator: needs no pass
  class Accumulator
  {
  public:
    /// an accumulator for `setup`
    explicit Accumulator(const Component_sign_setup& setup) : m_components(setup.number_of_components) {}
    /// the passes over the points needed: none
    unsigned int number_of_passes() const { return 0; }
    /// nothing to do
    void add(unsigned int, const Component_sign_point&) {}
    /// never flips
    std::vector<char> decide() const { return std::vector<char>(m_components, 0); }

  private:
    std::size_t m_components;
  };
  /// begins the accumulation
  Accumulator begin(const Component_sign_setup& setup) const { return Accumulator(setup); }
  /// the name used in reports
  static const char* name() { return "keep"; }
};

/// \ingroup PkgNormalOrientationSign
/// The default: every component is made to face outward, as the boundary of
/// a closed object would.  For a component of at least
/// `minimum_size_for_directions` points, each of `number_of_directions`
/// directions d spread evenly on the sphere is a witness: the points whose
/// projection on d lies within `band` times the component's extent along d
/// of the extremal one are on the convex hull side facing d, where outward
/// normals point along d; the witness's vote is the mean of d . n over
/// those points, weighted by closeness to the extremal plane, a number in
/// [-1, 1].  The component flips when the sum of the votes is negative.
/// Components larger than `maximum_voters` vote with an evenly spread
/// subsample of that size, which keeps the cost at O(n + 64 *
/// maximum_voters) per component.
/// Many witnesses, each averaging many points, keep one noisy normal at the
/// topmost point (the peers' rule) from flipping a whole object.  Smaller
/// components flip when the normals point on average towards their
/// centroid.  Open surfaces (a single flat patch, say) get a vote near zero
/// and are left as they are.  A closed component nested inside another
/// (the inner wall of a hollow object) is also made to face outward of
/// itself, which is wrong for such walls: use a viewpoint or constraints.
/// \cgalModels `ComponentSignPolicy`
struct Outward_component_sign
{
  /// witnesses per component
  unsigned int number_of_directions = 64;
  /// relative depth of the band of points that vote for each direction
  double band = 0.03;
  /// components smaller than this use the centroid rule
  std::size_t minimum_size_for_directions = 128;
  /// larger components vote with an evenly spread subsample of about this
  /// many points
  std::size_t maximum_voters = 16384;

  /// the name used in reports
  static const char* name() { return "outward"; }

  /// The accumulator: two passes when a component is large enough for the
  /// witnesses (their extents, then their votes), else one.  Every sum is
  /// accumulated in the order of the points: deterministic.
  class Accumulator
  {
  public:
    /// an accumulator for `setup`, with the parameters of `rule`
    Accumulator(const Outward_component_sign& rule, const Component_sign_setup& setup)
      : m_band(rule.band), m_minimum_size(rule.minimum_size_for_directions), m_size(setup.component_size), m_stride(setup.number_of_components, 1),
        m_seen(setup.number_of_components, 0), m_sum_p(setup.number_of_components, {0.0, 0.0, 0.0}),
        m_sum_n(setup.number_of_components, {0.0, 0.0, 0.0}), m_sum_pn(setup.number_of_components, 0.0)
    {
      const std::size_t nc = setup.number_of_components;
      m_size.resize(nc, 0);
      const unsigned D = std::max(1u, rule.number_of_directions);
      m_direction.resize(D);
      const double golden = M_PI * (3.0 - std::sqrt(5.0));
      for (unsigned d = 0; d < D; ++d) { // Fibonacci sphere
        const double z = 1.0 - (2.0 * d + 1.0) / double(D);
        const double sz = std::sqrt(std::max(0.0, 1.0 - z * z));
        m_direction[d] = {sz * std::cos(golden * d), sz * std::sin(golden * d), z};
      }
      // A component of more than `maximum_voters` points votes with every
      // s-th of its points, s = ceil(size / maximum_voters): the vote needs
      // a dense sample of the extremal bands, and the drivers feed points
      // in a spatially coherent order, so the subsample is spread evenly.
      const std::uint64_t voters = std::max<std::uint64_t>(1, rule.maximum_voters);
      for (std::size_t c = 0; c < nc; ++c) {
        m_stride[c] = std::max<std::uint64_t>(1, (m_size[c] + voters - 1) / voters);
        m_any_large = m_any_large || large(c);
      }
      if (m_any_large) {
        m_hi.assign(nc * D, -HUGE_VAL);
        m_lo.assign(nc * D, HUGE_VAL);
        m_num.assign(nc * D, 0.0);
        m_den.assign(nc * D, 0.0);
      }
    }
    /// the passes over the points needed: 2 when a component is large
    /// enough for the witnesses, else 1
    unsigned int number_of_passes() const { return m_any_large ? 2 : 1; }
    /// adds point `p` in pass `pass`
    void add(unsigned int pass, const Component_sign_point& p)
    {
      const std::uint32_t c = p.component;
      if (!large(c)) { // (p - centroid) . n summed, as sum p.n - centroid . sum n
        if (pass == 0) {
          for (int d = 0; d < 3; ++d) {
            m_sum_p[c][d] += p.position[d];
            m_sum_n[c][d] += p.normal[d];
          }
          m_sum_pn[c] += p.position[0] * p.normal[0] + p.position[1] * p.normal[1] + p.position[2] * p.normal[2];
        }
        return;
      }
      if (pass != m_pass) { // a new pass: the subsample starts again
        m_pass = pass;
        std::fill(m_seen.begin(), m_seen.end(), 0);
      }
      if (m_seen[c]++ % m_stride[c] != 0)
        return;
      const std::size_t D = m_direction.size();
      for (std::size_t d = 0; d < D; ++d) {
        const std::array<double, 3>& u = m_direction[d];
        const double proj = p.position[0] * u[0] + p.position[1] * u[1] + p.position[2] * u[2];
        const std::size_t slot = std::size_t(c) * D + d;
        if (pass == 0) {
          m_hi[slot] = std::max(m_hi[slot], proj);
          m_lo[slot] = std::min(m_lo[slot], proj);
        } else {
          const double depth = m_band * (m_hi[slot] - m_lo[slot]);
          const double w = depth > 0.0 ? 1.0 - (m_hi[slot] - proj) / depth : (proj >= m_hi[slot] ? 1.0 : 0.0);
          if (w > 0.0) {
            m_num[slot] += w * (p.normal[0] * u[0] + p.normal[1] * u[1] + p.normal[2] * u[2]);
            m_den[slot] += w;
          }
        }
      }
    }
    /// for each component, whether to flip it
    std::vector<char> decide() const
    {
      const std::size_t nc = m_size.size(), D = m_direction.size();
      std::vector<char> flip(nc, 0);
      for (std::size_t c = 0; c < nc; ++c) {
        double vote = 0.0;
        if (large(c)) {
          for (std::size_t d = 0; d < D; ++d)
            if (m_den[c * D + d] > 0.0)
              vote += m_num[c * D + d] / m_den[c * D + d];
        } else if (m_size[c] > 0) {
          const double m = double(m_size[c]);
          vote = m_sum_pn[c] -
                 (m_sum_p[c][0] * m_sum_n[c][0] + m_sum_p[c][1] * m_sum_n[c][1] + m_sum_p[c][2] * m_sum_n[c][2]) / m;
        }
        flip[c] = vote < 0.0 ? 1 : 0;
      }
      return flip;
    }

  private:
    bool large(std::size_t c) const { return m_size[c] >= m_minimum_size; }

    double m_band;
    std::size_t m_minimum_size;
    std::vector<std::uint64_t> m_size, m_stride, m_seen;
    std::vector<std::array<double, 3>> m_direction, m_sum_p, m_sum_n;
    std::vector<double> m_sum_pn, m_hi, m_lo, m_num, m_den;
    bool m_any_large = false;
    unsigned int m_pass = 0;
  };
  /// begins the accumulation
  Accumulator begin(const Component_sign_setup& setup) const { return Accumulator(*this, setup); }
};

/// \ingroup PkgNormalOrientationSign
/// Every component faces a viewpoint (a scanner position, a camera): it
/// flips when its normals point, on average, away from the viewpoint.
/// \cgalModels `ComponentSignPolicy`
struct Viewpoint_component_sign
{
  /// the viewpoint
  std::array<double, 3> viewpoint{{0.0, 0.0, 0.0}};

  /// the policy for the viewpoint (x, y, z)
  Viewpoint_component_sign(double x = 0.0, double y = 0.0, double z = 0.0) : viewpoint{{x, y, z}} {}

  /// the name used in reports
  static const char* name() { return "viewpoint"; }

  /// the accumulator: one pass, the cosine between each normal and the
  /// direction to the viewpoint summed per component
  class Accumulator
  {
  public:
    /// an accumulator for `setup` and the viewpoint `v`
    Accumulator(const std::array<double, 3>& v, const Component_sign_setup& setup)
      : m_viewpoint(v), m_vote(setup.number_of_components, 0.0)
    {}
    /// one pass
    unsigned int number_of_passes() const { return 1; }
    /// adds point `p`
    void add(unsigned int, const Component_sign_point& p)
    {
      double v[3], l2 = 0.0, dn = 0.0;
      for (int d = 0; d < 3; ++d) {
        v[d] = m_viewpoint[d] - p.position[d];
        l2 += v[d] * v[d];
      }
      if (!(l2 > 0.0))
        return;
      for (int d = 0; d < 3; ++d)
        dn += v[d] * p.normal[d];
      m_vote[p.component] += dn / std::sqrt(l2);
    }
    /// for each component, whether to flip it
    std::vector<char> decide() const
    {
      std::vector<char> flip(m_vote.size(), 0);
      for (std::size_t c = 0; c < flip.size(); ++c)
        flip[c] = m_vote[c] < 0.0 ? 1 : 0;
      return flip;
    }

  private:
    std::array<double, 3> m_viewpoint;
    std::vector<double> m_vote;
  };
  /// begins the accumulation
  Accumulator begin(const Component_sign_setup& setup) const { return Accumulator(viewpoint, setup); }
};

/// \ingroup PkgNormalOrientationSign
/// User-fixed points (CGAL's `point_is_constrained_map` idea): a component
/// that holds constrained points takes the sign on which most of them agree
/// with their input orientation; components without constrained points,
/// or with a tie, are decided by `Fallback`.
/// \cgalModels `ComponentSignPolicy`
template <typename Fallback = Outward_component_sign>
struct Constrained_component_sign
{
  /// the policy for components without constrained points
  Fallback fallback;

  /// the name used in reports
  static const char* name() { return "constrained"; }

  /// the accumulator: the fallback's passes (at least one), and the labels
  /// of the constrained points summed per component
  class Accumulator
  {
  public:
    /// an accumulator for `setup`, around the fallback's
    Accumulator(const Fallback& fallback, const Component_sign_setup& setup)
      : m_fallback(fallback.begin(setup)), m_agree(setup.number_of_components, 0)
    {}
    /// the fallback's passes, at least one
    unsigned int number_of_passes() const { return std::max(1u, m_fallback.number_of_passes()); }
    /// adds point `p` in pass `pass`
    void add(unsigned int pass, const Component_sign_point& p)
    {
      if (pass < m_fallback.number_of_passes())
        m_fallback.add(pass, p);
      if (pass == 0 && p.constrained)
        m_agree[p.component] += p.label;
    }
    /// for each component, whether to flip it
    std::vector<char> decide() const
    {
      std::vector<char> flip = m_fallback.decide();
      for (std::size_t c = 0; c < flip.size(); ++c)
        if (m_agree[c] != 0)
          flip[c] = m_agree[c] < 0 ? 1 : 0;
      return flip;
    }

  private:
    typename Fallback::Accumulator m_fallback;
    std::vector<long long> m_agree;
  };
  /// begins the accumulation
  Accumulator begin(const Component_sign_setup& setup) const { return Accumulator(fallback, setup); }
};

/// \ingroup PkgNormalOrientationSign
/// The points of an in-core run, as `component_signs()` reads them.
/// `normals[i] * labels[i]` is the current orientation of point i.
template <typename Kernel>
struct Component_sign_input
{
  /// the positions
  const std::vector<typename Kernel::Point_3>& points;
  /// the input normals, normalised (zero where the input normal was zero)
  const std::vector<typename Kernel::Vector_3>& normals;
  /// the labels chosen by the solver (+1 / -1)
  const std::vector<Label>& labels;
  /// the component of every point, 0 ... number_of_components - 1
  const std::vector<std::uint32_t>& component;
  /// the number of components
  std::size_t number_of_components;
  /// the neighbour radius r of the graph
  double radius;
  /// when not null, `(*constrained)[i] != 0` marks a point whose input
  /// normal is known to be correctly oriented (`point_is_constrained_map`)
  const std::vector<char>* constrained;
};

/// \ingroup PkgNormalOrientationSign
/// Runs the sign policy `policy` over in-core points: feeds its
/// accumulator every point, in index order, in each of its passes, and
/// returns its decision (the in-core driver's sign stage; it also serves
/// any graph of the user's, as in the example `orient_mesh_graph.cpp`).
/// \tparam ComponentSignPolicy a model of `ComponentSignPolicy`
/// \param policy the policy
/// \param in the points, their normals, labels and components
/// \return for each component, whether to flip it (non-zero)
template <typename ComponentSignPolicy, typename Kernel>
std::vector<char> component_signs(const ComponentSignPolicy& policy, const Component_sign_input<Kernel>& in)
{
  const std::size_t n = in.points.size();
  Component_sign_setup setup;
  setup.number_of_components = in.number_of_components;
  setup.radius = in.radius;
  setup.component_size.assign(in.number_of_components, 0);
  for (std::size_t i = 0; i < n; ++i)
    ++setup.component_size[in.component[i]];
  auto accumulator = policy.begin(setup);
  const unsigned int passes = accumulator.number_of_passes();
  Component_sign_point p;
  for (unsigned int pass = 0; pass < passes; ++pass)
    for (std::size_t i = 0; i < n; ++i) {
      p.component = in.component[i];
      p.label = in.labels[i];
      p.constrained = in.constrained != nullptr && (*in.constrained)[i] != 0;
      for (int d = 0; d < 3; ++d) {
        p.position[d] = CGAL::to_double(in.points[i][d]);
        p.normal[d] = double(in.labels[i]) * CGAL::to_double(in.normals[i][d]);
      }
      accumulator.add(pass, p);
    }
  return accumulator.decide();
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_COMPONENT_SIGN_H
