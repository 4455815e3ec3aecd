// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_GLOBAL_SIGN_H
#define NORMAL_ORIENTATION_GLOBAL_SIGN_H

/// \file Global_sign.h
/// The global sign stage: the signs of patches that the winding number of
/// the whole cloud decides (`decide_patch_signs()`).

#include <Normal_orientation/Orientation_result.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/internal/Parallel.h>

#include <CGAL/Kernel_traits.h>
#include <CGAL/tags.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationGlobal
/// Whether the drivers run the global sign stage after the component signs.
enum class Global_orientation
{
  NONE,    ///< no global stage: the component sign policy has the last word
  WINDING, ///< the winding number decides the signs of patches where the cloud is closed
  /// first exterior visibility: components and sheets face the side they
  /// were seen from (`exterior_visibility()`, with an up direction); then
  /// the winding number decides where the cloud is closed, except where it
  /// would turn a component away from the side it was seen from
  VISIBILITY_AND_WINDING
};

/// \ingroup PkgNormalOrientationGlobal
/// The number of samples the drivers build the global stage's field on, for
/// a cloud of n points: n / 4 where its normals agree at its own spacing
/// (`dense`), n / 16 where they do not (noise wider than the spacing, which
/// the coarse-to-fine pass handles), at least 2^14 (or n) and at most 2^16.
/// They take every ceil(n / m)-th point of the spatially sorted cloud (in
/// core) or of the sweep order (streamed).  A subsample much coarser than the
/// cloud blurs walls thinner than its spacing; the noisy normals of a denser
/// one mislead the field.
inline std::uint64_t global_samples(std::uint64_t n, bool dense = false)
{
  const std::uint64_t share = n / (dense ? 4 : 16);
  return std::min<std::uint64_t>(
    n, std::max<std::uint64_t>(std::uint64_t(1) << 14, std::min<std::uint64_t>(share, std::uint64_t(1) << 16)));
}

/// \ingroup PkgNormalOrientationGlobal
/// The settings of `decide_patch_signs()`.
struct Global_sign_options
{
  /// a sample counts as agreeing with a closed surface when |w - 1/2| is at
  /// most this
  double agreement_tolerance = 0.25;
  /// a component is closed, and the stage's signs are kept in it, when the
  /// samples agreeing with a closed surface hold at least this fraction of
  /// its area
  double closed_fraction = 0.5;
  /// a patch is negated only when that lowers the energy by at least this
  /// much per unit of its area: smaller changes are within what noise and
  /// sampling make of w.  (The first-order decrease bounds the exact one,
  /// so only the patches whose first-order decrease, as screened with
  /// `screening_opening_ratio`, reaches it are tried.)
  double minimum_decrease = 0.3;
  /// the most rounds of patch flips
  unsigned int maximum_rounds = 8;
  /// the patches whose exact change of energy is computed per round (those
  /// with the largest first-order decrease)
  std::size_t candidates_per_round = 32;
  /// the opening ratio of the first-order decreases
  /// (`Winding_number_field::moment_derivatives()`), smaller than the
  /// field's: they only choose the candidates, whose exact changes decide
  double screening_opening_ratio = 1.2;
};

/// \ingroup PkgNormalOrientationGlobal
/// Decides the signs of patches, each a set of points whose normals the
/// solver already made consistent, from the winding number w of the whole
/// oriented cloud.
///
/// On a closed surface sampled with every normal outward, w is 1/2 at the
/// samples (their own term vanishes; the rest of the surface fills the other
/// half of the solid angle).  An inverted part moves w away from 1/2 at the
/// samples around it, on both sides, and an inverted closed object brings
/// it to -1/2.  The stage therefore minimises
///
///   E(s) = sum_j a_j (w_s(p_j) - 1/2)^2
///
/// over the signs s_P of the patches, with w_s = sum_P s_P w_P linear in
/// them.  Rounds: w at every sample (treecode); the first-order decrease of
/// E for negating each patch, all in one pass
/// (`Winding_number_field::moment_derivatives()` with the coarser
/// `screening_opening_ratio`); the exact change, from its own field, for
/// each of the `candidates_per_round` patches with the largest one; then,
/// best first, every candidate whose exact decrease reaches
/// `minimum_decrease` per unit of its area joins the patches to negate
/// while their joint change (exact: E is quadratic in the signs) stays a
/// decrease.  Rounds stop when none joins.  Then the
/// components decide: where at least `closed_fraction` of a component's
/// area has |w - 1/2| <= `agreement_tolerance`, the component is closed and
/// keeps the stage's signs; elsewhere (an open scan, a lone sheet) its
/// patches keep their input signs.
///
/// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`;
///         the result is the same for any number of threads
/// \param points the samples (a bounded subsample of a large cloud is enough)
/// \param normals their normals, oriented as the solver left them (unit or zero)
/// \param areas their areas (see `estimate_point_areas()`)
/// \param patch the patch of every sample, in [0, `number_of_patches`)
/// \param component the component of every patch (any numbering below 2^32)
/// \param fixed per patch, non-zero when its sign must not change (empty: none)
/// \param flip receives, per patch, 1 when it is to be negated
/// \param options the settings
/// \return what the stage saw and did (`Global_sign_summary`)
/// \throw std::invalid_argument when the sizes disagree or a patch index is out of range
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename Point, typename Vector>
Global_sign_summary decide_patch_signs(const std::vector<Point>& points, const std::vector<Vector>& normals,
                                       const std::vector<double>& areas, const std::vector<std::uint32_t>& patch,
                                       const std::vector<std::uint32_t>& component, const std::vector<char>& fixed,
                                       std::vector<char>& flip,
                                       const Global_sign_options& options = {});

/// \cond SKIP_IN_MANUAL
namespace internal {

/// The median of `values` (not empty): the upper one of an even count.
inline double median(std::vector<double> values)
{
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(values.size() / 2), values.end());
  return values[values.size() / 2];
}

/// Caps every area at 16 times the median: an isolated point (an outlier,
/// a tiny far component) would otherwise stand for a huge area and drown
/// the field of the surfaces.
inline void cap_areas(std::vector<double>& areas)
{
  if (areas.empty())
    return;
  const double cap = 16.0 * median(areas);
  for (double& a : areas)
    a = std::min(a, cap);
}

/// The samples of every patch, as lists of sample indices.
inline std::vector<std::vector<std::uint32_t>> patch_members(const std::vector<std::uint32_t>& patch,
                                                             std::size_t number_of_patches)
{
  std::vector<std::vector<std::uint32_t>> members(number_of_patches);
  for (std::size_t j = 0; j < patch.size(); ++j)
    members[patch[j]].push_back(std::uint32_t(j));
  return members;
}

/// E = sum_j a_j (w_j - 1/2)^2 at the samples, with the values w_j in `w`.
template <typename ConcurrencyTag, typename Field, typename Point>
double winding_energy(const Field& field, const std::vector<Point>& points, const std::vector<double>& areas,
                      std::vector<double>& w)
{
  field.template evaluate<ConcurrencyTag>(points, w);
  double e = 0.0; // (sequential: the same sum for any thread count)
  for (std::size_t j = 0; j < w.size(); ++j)
    e += areas[j] * (w[j] - 0.5) * (w[j] - 0.5);
  return e;
}

/// Per patch, the first-order decrease of E from negating it, divided by
/// its area: 4 g_P / A_P with g_P = sum_j a_j (w_j - 1/2) w_P(p_j), by the
/// moment derivatives of `field` with the opening ratio `opening_ratio`.
template <typename ConcurrencyTag, typename Field>
std::vector<double> patch_gains(Field& field, const std::vector<double>& areas, const std::vector<double>& w,
                                const std::vector<std::vector<std::uint32_t>>& members, double opening_ratio)
{
  const std::size_t n = w.size();
  std::vector<double> weight(n);
  for (std::size_t j = 0; j < n; ++j)
    weight[j] = areas[j] * (w[j] - 0.5);
  std::vector<typename Field::Vector_3> v;
  field.template moment_derivatives<ConcurrencyTag>(weight, v, opening_ratio);
  std::vector<double> gain(members.size(), 0.0);
  for (std::size_t P = 0; P < members.size(); ++P) {
    double g = 0.0, a = 0.0;
    for (std::uint32_t j : members[P]) {
      g += field.moment(j) * v[j];
      a += areas[j];
    }
    gain[P] = a > 0.0 ? 4.0 * g / a : 0.0;
  }
  return gain;
}

/// The exact change of E when the samples `members` (one patch) are
/// negated: their own field c_j at every sample, and sum_j a_j ((r_j -
/// 2 c_j)^2 - r_j^2) with r_j = w_j - 1/2; `own` receives c_j.
template <typename ConcurrencyTag, typename Kernel, typename Field, typename Point>
double negation_change(const Field& field, const std::vector<Point>& points, const std::vector<double>& areas,
                       const std::vector<double>& w, const std::vector<std::uint32_t>& members,
                       std::vector<float>& own)
{
  std::vector<typename Kernel::Point_3> p;
  std::vector<typename Kernel::Vector_3> m;
  std::vector<double> a, caps;
  for (std::uint32_t j : members) {
    p.push_back(points[j]);
    m.push_back(field.moment(j)); // a s n: its length is the area, its direction the signed normal
    a.push_back(areas[j]);
    caps.push_back(field.width_cap(j));
  }
  Winding_number_field<Kernel> patch_field;
  patch_field.set_opening_ratio(field.opening_ratio());
  patch_field.set_smoothing_factor(field.smoothing_factor());
  patch_field.template build<ConcurrencyTag>(p, m, a, caps);
  std::vector<double> c(points.size()); // (the samples are in a spatial order already: no sort)
  parallel_chunks<ConcurrencyTag>(points.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j)
      c[j] = patch_field.value(points[j]);
  }, 256);
  double d = 0.0;
  own.resize(c.size());
  for (std::size_t j = 0; j < c.size(); ++j) {
    const double r = w[j] - 0.5;
    d += areas[j] * ((r - 2.0 * c[j]) * (r - 2.0 * c[j]) - r * r);
    own[j] = float(c[j]);
  }
  return d;
}

/// Negates the samples of the patches `batch` in `field` and toggles them in `flip`.
template <typename Field>
void negate_patches(Field& field, const std::vector<std::uint32_t>& batch,
                    const std::vector<std::vector<std::uint32_t>>& members, std::vector<char>& flip)
{
  std::vector<std::uint32_t> points;
  for (std::uint32_t P : batch) {
    points.insert(points.end(), members[P].begin(), members[P].end());
    flip[P] = char(!flip[P]);
  }
  field.negate(points);
}

/// Per group id below `number_of_groups`, whether it reads closed: the
/// samples (w at them, `w`, their `areas` and group ids `group`) with
/// |w - 1/2| <= `options.agreement_tolerance` hold at least
/// `options.closed_fraction` of its area.  A group without area does not.
inline std::vector<char> groups_read_closed(const std::vector<double>& w, const std::vector<double>& areas,
                                            const std::vector<std::uint32_t>& group, std::size_t number_of_groups,
                                            const Global_sign_options& options)
{
  std::vector<double> agree(number_of_groups, 0.0), area(number_of_groups, 0.0);
  for (std::size_t j = 0; j < w.size(); ++j) {
    area[group[j]] += areas[j];
    agree[group[j]] += std::abs(w[j] - 0.5) <= options.agreement_tolerance ? areas[j] : 0.0;
  }
  std::vector<char> closed(number_of_groups, 0);
  for (std::size_t g = 0; g < number_of_groups; ++g)
    closed[g] = char(area[g] > 0.0 && agree[g] >= options.closed_fraction * area[g]);
  return closed;
}

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationGlobal
/// The search of `decide_patch_signs()` over a field that persists, so
/// that several partitions of the same samples into patches (coarse to
/// fine) can be tried one after the other on one tree: `decide()` leaves
/// the field with the signs it chose.
template <typename Kernel>
class Winding_patch_signs
{
public:
  /// the point type
  typedef typename Kernel::Point_3 Point_3;
  /// the vector type
  typedef typename Kernel::Vector_3 Vector_3;

  /// Builds the field over the samples (oriented normals and areas as for
  /// `decide_patch_signs()`, the caps of the smoothing widths as for
  /// `Winding_number_field::build()`, empty: none) and evaluates w at them.
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
  void build(const std::vector<Point_3>& points, const std::vector<Vector_3>& normals,
             const std::vector<double>& areas, const std::vector<double>& width_caps = std::vector<double>())
  {
    if (normals.size() != points.size() || areas.size() != points.size())
      throw std::invalid_argument("Winding_patch_signs: points, normals and areas differ in size");
    m_points = points;
    m_areas = areas;
    m_field.template build<ConcurrencyTag>(points, normals, areas, width_caps);
    m_energy = internal::winding_energy<ConcurrencyTag>(m_field, m_points, m_areas, m_w);
  }

  /// the number of samples
  std::size_t size() const { return m_points.size(); }
  /// w at the samples, with the signs chosen so far (evaluated by the
  /// treecode, then moved by the changes of the patches negated since)
  const std::vector<double>& values() const { return m_w; }
  /// E = sum_j a_j (w_j - 1/2)^2 with the signs chosen so far
  double energy() const { return m_energy; }

  /// Negates the samples `indices` (the labels changed outside the search,
  /// e.g. by a veto) and evaluates w at every sample again.
  /// \throw std::out_of_range if an index is not that of a sample
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
  void negate_samples(const std::vector<std::uint32_t>& indices)
  {
    m_field.negate(indices);
    m_energy = internal::winding_energy<ConcurrencyTag>(m_field, m_points, m_areas, m_w);
  }

  /// Negates the samples `members` (one patch) in the field when that
  /// changes E by less than `most_change` per unit of their area (0: only
  /// when E falls), and returns whether it did.  w moves by the patch's own
  /// field, as in `decide()`.
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
  bool negate_unless_worse(const std::vector<std::uint32_t>& members, double most_change = 0.0)
  {
    std::vector<float> own;
    const double d = internal::negation_change<ConcurrencyTag, Kernel>(m_field, m_points, m_areas, m_w, members, own);
    double area = 0.0;
    for (std::uint32_t j : members)
      area += m_areas[j];
    if (!(d < most_change * area))
      return false;
    m_field.negate(members);
    for (std::size_t j = 0; j < m_w.size(); ++j)
      m_w[j] -= 2.0 * double(own[j]);
    m_energy += d;
    return true;
  }

  /// Decides the signs of the patches of one partition (the parameters are
  /// those of `decide_patch_signs()`) and keeps them in the field.
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
  Global_sign_summary decide(const std::vector<std::uint32_t>& patch, const std::vector<std::uint32_t>& component,
                             const std::vector<char>& fixed, std::vector<char>& flip,
                             const Global_sign_options& options = {});

private:
  template <typename ConcurrencyTag>
  bool round(const std::vector<std::vector<std::uint32_t>>& members, const std::vector<char>& fixed,
             std::vector<char>& flip, const Global_sign_options& options);
  void keep_closed(const std::vector<std::uint32_t>& patch, const std::vector<std::uint32_t>& component,
                   const std::vector<std::vector<std::uint32_t>>& members, std::vector<char>& flip,
                   const Global_sign_options& options, Global_sign_summary& report);

  Winding_number_field<Kernel> m_field;
  std::vector<Point_3> m_points;
  std::vector<double> m_areas, m_w;
  double m_energy = 0.0;
};

template <typename Kernel>
template <typename ConcurrencyTag>
bool Winding_patch_signs<Kernel>::round(const std::vector<std::vector<std::uint32_t>>& members,
                                        const std::vector<char>& fixed, std::vector<char>& flip,
                                        const Global_sign_options& options)
{
  const std::size_t n = m_points.size(), np = members.size();
  const std::vector<double> gain =
    internal::patch_gains<ConcurrencyTag>(m_field, m_areas, m_w, members, options.screening_opening_ratio);
  std::vector<std::uint32_t> candidates;
  for (std::uint32_t P = 0; P < np; ++P)
    if ((fixed.empty() || !fixed[P]) && !members[P].empty() && gain[P] >= options.minimum_decrease)
      candidates.push_back(P);
  std::stable_sort(candidates.begin(), candidates.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return gain[a] > gain[b]; });
  if (candidates.size() > options.candidates_per_round)
    candidates.resize(options.candidates_per_round);
  // The exact change of E for negating each candidate alone, then a greedy
  // set of them whose joint change (from their own fields) is lowest: E is
  // quadratic in the signs, so the prediction is exact up to the treecode's
  // error.
  std::vector<std::vector<float>> own(candidates.size());
  std::vector<std::pair<double, std::size_t>> better;
  for (std::size_t t = 0; t < candidates.size(); ++t) {
    const std::uint32_t P = candidates[t];
    const double d =
      internal::negation_change<ConcurrencyTag, Kernel>(m_field, m_points, m_areas, m_w, members[P], own[t]);
    double area = 0.0;
    for (std::uint32_t j : members[P])
      area += m_areas[j];
    if (d < -options.minimum_decrease * area)
      better.emplace_back(d, t);
  }
  std::stable_sort(better.begin(), better.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::uint32_t> batch;
  std::vector<double> residual(n);
  for (std::size_t j = 0; j < n; ++j)
    residual[j] = m_w[j] - 0.5;
  for (const auto& b : better) {
    const std::uint32_t P = candidates[b.second];
    const std::vector<float>& c = own[b.second];
    double change = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      const double r = residual[j], r2 = r - 2.0 * double(c[j]);
      change += m_areas[j] * (r2 * r2 - r * r);
    }
    if (!(change < 0.0))
      continue;
    for (std::size_t j = 0; j < n; ++j)
      residual[j] -= 2.0 * double(c[j]);
    batch.push_back(P);
  }
  if (batch.empty())
    return false;
  // Negate the batch; w moves by -2 sum c_P, as predicted.  The next rounds
  // and levels start from the prediction, which is the treecode's value up
  // to the error of the candidates' own fields.
  internal::negate_patches(m_field, batch, members, flip);
  m_energy = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    m_w[j] = residual[j] + 0.5;
    m_energy += m_areas[j] * residual[j] * residual[j];
  }
  return true;
}

template <typename Kernel>
void Winding_patch_signs<Kernel>::keep_closed(const std::vector<std::uint32_t>& patch,
                                              const std::vector<std::uint32_t>& component,
                                              const std::vector<std::vector<std::uint32_t>>& members,
                                              std::vector<char>& flip, const Global_sign_options& options,
                                              Global_sign_summary& report)
{
  const std::size_t n = m_points.size(), np = component.size();
  std::vector<std::uint32_t> ids(component);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  auto slot = [&](std::uint32_t c) { return std::size_t(std::lower_bound(ids.begin(), ids.end(), c) - ids.begin()); };
  std::vector<std::uint32_t> group(n);
  std::vector<char> has_area(ids.size(), 0);
  double total_agree = 0.0, total_area = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    const double a = m_areas[j];
    group[j] = std::uint32_t(slot(component[patch[j]]));
    has_area[group[j]] = char(has_area[group[j]] || a > 0.0);
    total_area += a;
    total_agree += std::abs(m_w[j] - 0.5) <= options.agreement_tolerance ? a : 0.0;
  }
  report.closedness = total_area > 0.0 ? total_agree / total_area : 0.0;
  const std::vector<char> closed = internal::groups_read_closed(m_w, m_areas, group, ids.size(), options);
  for (std::size_t c = 0; c < ids.size(); ++c)
    if (has_area[c])
      ++(closed[c] ? report.closed_components : report.open_components);
  std::vector<std::uint32_t> undo;
  for (std::uint32_t P = 0; P < np; ++P)
    if (flip[P] && !closed[slot(component[P])])
      undo.push_back(P);
  if (!undo.empty()) { // open components keep their input signs
    internal::negate_patches(m_field, undo, members, flip);
    m_energy = internal::winding_energy<CGAL::Parallel_if_available_tag>(m_field, m_points, m_areas, m_w);
  }
  for (std::size_t P = 0; P < np; ++P)
    report.patches_flipped += flip[P] ? 1 : 0;
}

template <typename Kernel>
template <typename ConcurrencyTag>
Global_sign_summary Winding_patch_signs<Kernel>::decide(const std::vector<std::uint32_t>& patch,
                                                        const std::vector<std::uint32_t>& component,
                                                        const std::vector<char>& fixed, std::vector<char>& flip,
                                                        const Global_sign_options& options)
{
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = m_points.size(), np = component.size();
  if (patch.size() != n || (!fixed.empty() && fixed.size() != np))
    throw std::invalid_argument("decide_patch_signs: the patches or the fixed flags do not match the samples");
  for (std::uint32_t P : patch)
    if (P >= np)
      throw std::invalid_argument("decide_patch_signs: a patch index is out of range");
  Global_sign_summary report;
  report.ran = true;
  report.number_of_samples = n;
  report.number_of_patches = np;
  flip.assign(np, 0);
  const std::vector<std::vector<std::uint32_t>> members = internal::patch_members(patch, np);
  report.energy_before = m_energy;
  while (report.rounds < options.maximum_rounds && round<ConcurrencyTag>(members, fixed, flip, options))
    ++report.rounds;
  keep_closed(patch, component, members, flip, options, report);
  report.energy_after = m_energy;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

template <typename ConcurrencyTag, typename Point, typename Vector>
Global_sign_summary decide_patch_signs(const std::vector<Point>& points, const std::vector<Vector>& normals,
                                       const std::vector<double>& areas, const std::vector<std::uint32_t>& patch,
                                       const std::vector<std::uint32_t>& component, const std::vector<char>& fixed,
                                       std::vector<char>& flip,
                                       const Global_sign_options& options)
{
  typedef typename CGAL::Kernel_traits<Point>::Kernel Kernel;
  const auto t0 = std::chrono::steady_clock::now();
  Winding_patch_signs<Kernel> search;
  search.template build<ConcurrencyTag>(points, normals, areas);
  Global_sign_summary report = search.template decide<ConcurrencyTag>(patch, component, fixed, flip, options);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_GLOBAL_SIGN_H
