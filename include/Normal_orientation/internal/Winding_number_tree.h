// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_WINDING_NUMBER_TREE_H
#define NORMAL_ORIENTATION_INTERNAL_WINDING_NUMBER_TREE_H

/// \file Winding_number_tree.h
/// The kd-tree and the Barnes-Hut sums behind `Normal_orientation::Winding_number_field`,
/// on plain doubles.

#include <CGAL/tags.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/parallel_invoke.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// One sample of the field: position, a_i s_i n_i (area times signed unit
/// normal), area a_i, its squared smoothing width over the smoothing factor
/// (a_i, or the square of a smaller cap), and its index in the input.
struct Winding_sample
{
  double p[3];
  double an[3];
  double area;
  double width2;
  std::uint32_t index;
};

/// One node of the tree: the Taylor moments of its samples about their
/// area-weighted centre c.
struct Winding_node
{
  double center[3];   // area-weighted centre c (the plain centroid when all areas are 0)
  double radius;      // max |p_i - c| over the node's samples
  double mean_area;   // sum a_i width2_i / sum a_i: the node's squared smoothing width is f^2 * mean_area
  double dipole[3];   // N = sum a_i s_i n_i
  double second[9];   // M[l][k] = sum a_i (p_i - c)_l (s_i n_i)_k, row-major
  double third[18];   // Q[kl][j] = sum a_i (p_i - c)_k (p_i - c)_l (s_i n_i)_j, kl in 00 01 02 11 12 22
};

/// The charges of one node for `Winding_tree::charge_field()`: their sum
/// and their first moment about the node's centre.
struct Charge_node
{
  double charge = 0.0;
  double moment[3] = {0.0, 0.0, 0.0};
};

/// the index in `Winding_node::third` of the symmetric pair (k, l)
inline int winding_pair(int k, int l)
{
  static const int pair[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  return pair[k][l];
}

/// The mollified Green's function G(r) = (|r|^2 + eps^2)^(-1/2) and the
/// sums of its derivatives that give w and grad w, with the 1/(4 pi) left
/// out.  A sample contributes a (r . n) / d^3 to w and a H(r) n to grad w,
/// with r = p - q, d^2 = |r|^2 + eps^2 and H the Hessian of G.
struct Winding_kernel
{
  /// adds one sample (r = p - q, an = a s n, e2 = eps^2) to w (and g)
  template <bool Gradient>
  static void add_sample(const double r[3], const double an[3], double e2, double& w, double* g)
  {
    const double d2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + e2;
    if (!(d2 > 0.0))
      return; // the query is on an unsmoothed sample: its own term is 0
    const double inv_d = 1.0 / std::sqrt(d2);
    const double inv_d3 = inv_d * inv_d * inv_d;
    const double rn = r[0] * an[0] + r[1] * an[1] + r[2] * an[2];
    w += rn * inv_d3;
    if (Gradient) {
      const double c = 3.0 * rn * inv_d3 / d2;
      for (int j = 0; j < 3; ++j)
        g[j] += c * r[j] - an[j] * inv_d3;
    }
  }

  /// adds the expansion of a whole node about its centre (R = c - q), to
  /// second order in p_i - c
  template <bool Gradient>
  static void add_node(const Winding_node& node, const double R[3], double e2, double& w, double* g)
  {
    const double d2 = R[0] * R[0] + R[1] * R[1] + R[2] * R[2] + e2;
    if (!(d2 > 0.0))
      return;
    const double inv_d2 = 1.0 / d2;
    const double inv_d = std::sqrt(inv_d2);
    const double inv_d3 = inv_d * inv_d2;
    const double inv_d5 = inv_d3 * inv_d2;
    const double inv_d7 = inv_d5 * inv_d2;
    const double* N = node.dipole;
    const double* M = node.second;
    const double* Q = node.third;
    const double NR = N[0] * R[0] + N[1] * R[1] + N[2] * R[2];
    const double trace = M[0] + M[4] + M[8];
    double MR[3], MtR[3], u[3], v[3], P[3], QR[6];
    for (int j = 0; j < 3; ++j) {
      MR[j] = M[3 * j] * R[0] + M[3 * j + 1] * R[1] + M[3 * j + 2] * R[2];
      MtR[j] = M[j] * R[0] + M[3 + j] * R[1] + M[6 + j] * R[2];
      // u_j = sum a (p - c)_j ((p - c) . n), v_j = sum a |p - c|^2 n_j
      u[j] = Q[3 * winding_pair(j, 0)] + Q[3 * winding_pair(j, 1) + 1] + Q[3 * winding_pair(j, 2) + 2];
      v[j] = Q[j] + Q[9 + j] + Q[15 + j];
    }
    // P_j = sum a (R . (p - c))^2 n_j
    const double rr[6] = {R[0] * R[0], 2.0 * R[0] * R[1], 2.0 * R[0] * R[2],
                          R[1] * R[1], 2.0 * R[1] * R[2], R[2] * R[2]};
    for (int j = 0; j < 3; ++j) {
      P[j] = 0.0;
      for (int s = 0; s < 6; ++s)
        P[j] += rr[s] * Q[3 * s + j];
    }
    const double RMR = R[0] * MR[0] + R[1] * MR[1] + R[2] * MR[2];
    const double Ru = R[0] * u[0] + R[1] * u[1] + R[2] * u[2];
    const double Rv = R[0] * v[0] + R[1] * v[1] + R[2] * v[2];
    const double C = R[0] * P[0] + R[1] * P[1] + R[2] * P[2];
    // w = (N.R + tr M) / d^3 - 3 R.M.R / d^5 - 3/2 (2 R.u + R.v) / d^5 + 15/2 C / d^7
    w += (NR + trace) * inv_d3 - (3.0 * RMR + 1.5 * (2.0 * Ru + Rv)) * inv_d5 + 7.5 * C * inv_d7;
    if (Gradient) {
      // H(R) N + T(R) : M + 1/2 F(R) : Q, with T and F the third and fourth derivatives of G
      for (int s = 0; s < 6; ++s)
        QR[s] = Q[3 * s] * R[0] + Q[3 * s + 1] * R[1] + Q[3 * s + 2] * R[2];
      const double inv_d9 = inv_d7 * inv_d2;
      const double a = 3.0 * (NR + trace) * inv_d5 - 15.0 * RMR * inv_d7 - 7.5 * (2.0 * Ru + Rv) * inv_d7
                       + 52.5 * C * inv_d9;
      for (int j = 0; j < 3; ++j) {
        // Z_j = sum a (p - c)_j (R . (p - c)) (R . n)
        const double Z = R[0] * QR[winding_pair(j, 0)] + R[1] * QR[winding_pair(j, 1)] + R[2] * QR[winding_pair(j, 2)];
        g[j] += a * R[j] - N[j] * inv_d3 + 3.0 * (MR[j] + MtR[j]) * inv_d5
                + 1.5 * (v[j] + 2.0 * u[j]) * inv_d5 - 7.5 * (P[j] + 2.0 * Z) * inv_d7;
      }
    }
  }
};

/// A kd-tree over the samples with median splits (by count) along the
/// longest side of each node's bounding box, cut to the same depth
/// everywhere, so that its shape depends only on the number of samples: a
/// complete binary tree in heap layout (children of node i are 2i+1 and
/// 2i+2), whose node (level d, rank j) holds the samples
/// [floor(j n / 2^d), floor((j+1) n / 2^d)).  Leaves hold at most
/// `leaf_size` samples.  The build is deterministic for any thread count.
class Winding_tree
{
public:
  /// Builds over `samples` (given in input order; reordered here).
  template <typename ConcurrencyTag>
  void build(std::vector<Winding_sample> samples, unsigned int leaf_size)
  {
    samples_ = std::move(samples);
    const std::size_t n = samples_.size();
    depth_ = 0;
    leaf_size = std::max(1u, leaf_size);
    while ((n + (std::size_t(1) << depth_) - 1) >> depth_ > leaf_size)
      ++depth_;
    nodes_.assign(n == 0 ? 0 : (std::size_t(2) << depth_) - 1, Winding_node());
    charges_.clear();
    position_charge_.clear();
    if (n > 0)
      build_node<ConcurrencyTag>(0, 0, 0);
    position_.assign(n, 0);
    for (std::size_t t = 0; t < n; ++t)
      position_[samples_[t].index] = std::uint32_t(t);
  }

  std::size_t size() const { return samples_.size(); }
  const std::vector<Winding_sample>& samples() const { return samples_; }
  /// the tree position of the sample of input index i
  std::size_t position(std::size_t i) const { return position_[i]; }

  /// Negates a s n of the samples of the given input indices and updates
  /// the moments of the nodes above them (the geometry is unchanged).
  template <typename IndexIterator>
  void negate(IndexIterator begin, IndexIterator end)
  {
    if (nodes_.empty())
      return;
    const std::size_t first_leaf = (std::size_t(1) << depth_) - 1;
    std::vector<unsigned char> dirty(nodes_.size(), 0);
    for (; begin != end; ++begin) {
      Winding_sample& s = samples_[position_[std::size_t(*begin)]];
      for (double& c : s.an)
        c = -c;
      dirty[first_leaf + leaf_of(position_[std::size_t(*begin)])] = 1;
    }
    for (std::size_t i = nodes_.size(); i-- > 0;) {
      if (i < first_leaf)
        dirty[i] = dirty[2 * i + 1] | dirty[2 * i + 2];
      if (!dirty[i])
        continue;
      if (i >= first_leaf) {
        const std::size_t j = i - first_leaf;
        leaf_moments(nodes_[i], range_begin(depth_, j), range_begin(depth_, j + 1));
      } else {
        inner_moments(i);
      }
    }
  }

  /// w(q) (and grad w(q)) by the treecode, without the factor 1/(4 pi); f2
  /// is the squared smoothing factor, beta2 the squared opening ratio.
  template <bool Gradient>
  void evaluate(const double q[3], double beta2, double f2, double& w, double* g) const
  {
    w = 0.0;
    if (Gradient)
      g[0] = g[1] = g[2] = 0.0;
    traverse(
      q, beta2,
      [&](std::size_t i, const double R[3], double) {
        Winding_kernel::add_node<Gradient>(nodes_[i], R, f2 * nodes_[i].mean_area, w, g);
      },
      [&](std::size_t b, std::size_t e) { add_samples<Gradient>(q, f2, b, e, w, g); });
  }

  /// w(q) (and grad w(q)) by the direct sum over all samples, without the
  /// factor 1/(4 pi).
  template <bool Gradient>
  void evaluate_direct(const double q[3], double f2, double& w, double* g) const
  {
    w = 0.0;
    if (Gradient)
      g[0] = g[1] = g[2] = 0.0;
    add_samples<Gradient>(q, f2, 0, samples_.size(), w, g);
  }

  /// w(q) over the samples at distance at least `exclusion` from q only,
  /// without the factor 1/(4 pi): by the treecode (nodes wholly outside
  /// that sphere are expanded when they pass the opening test, nodes wholly
  /// inside are skipped, the others are opened), or by the direct sum.
  template <bool Direct>
  double evaluate_far(const double q[3], double beta2, double f2, double exclusion) const
  {
    double w = 0.0;
    const double x2 = exclusion * exclusion;
    if (Direct) {
      add_samples<false>(q, f2, 0, samples_.size(), w, nullptr, x2);
      return w;
    }
    traverse(
      q, beta2,
      [&](std::size_t i, const double R[3], double) {
        Winding_kernel::add_node<false>(nodes_[i], R, f2 * nodes_[i].mean_area, w, nullptr);
      },
      [&](std::size_t b, std::size_t e) { add_samples<false>(q, f2, b, e, w, nullptr, x2); }, exclusion);
    return w;
  }

  /// Sets the charges q_t of the samples, given by input index, for
  /// `charge_field()`: every node keeps their sum and their first moment
  /// sum q_t (p_t - c) about its centre.
  void set_charges(const std::vector<double>& charge_by_index)
  {
    charges_.assign(nodes_.size(), Charge_node());
    position_charge_.assign(samples_.size(), 0.0);
    for (std::size_t t = 0; t < samples_.size(); ++t)
      position_charge_[t] = charge_by_index[samples_[t].index];
    if (nodes_.empty())
      return;
    const std::size_t first_leaf = (std::size_t(1) << depth_) - 1;
    for (std::size_t i = nodes_.size(); i-- > 0;) {
      Charge_node& c = charges_[i];
      const Winding_node& node = nodes_[i];
      if (i >= first_leaf) {
        const std::size_t j = i - first_leaf;
        for (std::size_t t = range_begin(depth_, j); t < range_begin(depth_, j + 1); ++t) {
          const double q = position_charge_[t];
          c.charge += q;
          for (int k = 0; k < 3; ++k)
            c.moment[k] += q * (samples_[t].p[k] - node.center[k]);
        }
      } else {
        for (std::size_t h = 2 * i + 1; h <= 2 * i + 2; ++h) {
          const Charge_node& child = charges_[h];
          c.charge += child.charge;
          for (int k = 0; k < 3; ++k)
            c.moment[k] += child.moment[k] + child.charge * (nodes_[h].center[k] - node.center[k]);
        }
      }
    }
  }

  /// F(x) = sum_t q_t (x - p_t) / (|x - p_t|^2 + e2)^(3/2) by the treecode
  /// (nodes to first order, opened as in `evaluate()`), with the charges of
  /// `set_charges()`: the derivative of sum_t q_t w(p_t) with respect to the
  /// moment a s n of a sample at x with smoothing e2, times 4 pi.
  void charge_field(const double x[3], double beta2, double e2, double F[3]) const
  {
    F[0] = F[1] = F[2] = 0.0;
    if (charges_.size() != nodes_.size())
      return;
    traverse(
      x, beta2,
      [&](std::size_t i, const double R[3], double dist2) {
        // F = -Q R / d^3 - D / d^3 + 3 (D . R) R / d^5, with R = c - x
        const Charge_node& c = charges_[i];
        const double d2 = dist2 + e2;
        const double inv_d3 = 1.0 / (d2 * std::sqrt(d2));
        const double DR = c.moment[0] * R[0] + c.moment[1] * R[1] + c.moment[2] * R[2];
        for (int k = 0; k < 3; ++k)
          F[k] += (-c.charge * R[k] - c.moment[k] + 3.0 * DR * R[k] / d2) * inv_d3;
      },
      [&](std::size_t b, std::size_t e) {
        for (std::size_t t = b; t < e; ++t) {
          const Winding_sample& s = samples_[t];
          const double r[3] = {x[0] - s.p[0], x[1] - s.p[1], x[2] - s.p[2]};
          const double d2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + e2;
          if (!(d2 > 0.0))
            continue;
          const double f = position_charge_[t] / (d2 * std::sqrt(d2));
          for (int k = 0; k < 3; ++k)
            F[k] += f * r[k];
        }
      });
  }

private:
  /// The Barnes-Hut walk from the root, nearer child first: a node whose
  /// centre is farther from q than beta times its radius goes to
  /// `far(i, R, |R|^2)` with R = c - q; a leaf that is not goes to
  /// `leaf(b, e)`, its samples [b, e) in tree order.  With an `exclusion`
  /// radius > 0, a node wholly inside that sphere about q is skipped, and
  /// one that straddles it is opened.
  template <typename Far, typename Leaf>
  void traverse(const double q[3], double beta2, const Far& far, const Leaf& leaf, double exclusion = 0.0) const
  {
    if (nodes_.empty())
      return;
    const std::size_t first_leaf = (std::size_t(1) << depth_) - 1;
    std::size_t stack[128];
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const std::size_t i = stack[--top];
      const Winding_node& node = nodes_[i];
      const double R[3] = {node.center[0] - q[0], node.center[1] - q[1], node.center[2] - q[2]};
      const double dist2 = R[0] * R[0] + R[1] * R[1] + R[2] * R[2];
      bool straddles = false;
      if (exclusion > 0.0) {
        const double dist = std::sqrt(dist2);
        if (dist + node.radius < exclusion)
          continue;
        straddles = dist - node.radius < exclusion;
      }
      if (!straddles && dist2 > beta2 * node.radius * node.radius) {
        far(i, R, dist2);
      } else if (i >= first_leaf) {
        const std::size_t j = i - first_leaf;
        leaf(range_begin(depth_, j), range_begin(depth_, j + 1));
      } else { // the far child first, so that the near one is summed first
        stack[top++] = 2 * i + 2;
        stack[top++] = 2 * i + 1;
      }
    }
  }

  std::size_t range_begin(unsigned int d, std::size_t j) const
  {
    return std::size_t(std::uint64_t(j) * std::uint64_t(samples_.size()) >> d);
  }

  /// the rank of the leaf that holds tree position t
  std::size_t leaf_of(std::size_t t) const
  {
    // the leaf j with range_begin(j) <= t < range_begin(j + 1)
    std::size_t j = std::size_t((std::uint64_t(t) << depth_) / std::uint64_t(samples_.size()));
    while (j + 1 < (std::size_t(1) << depth_) && range_begin(depth_, j + 1) <= t)
      ++j;
    while (j > 0 && range_begin(depth_, j) > t)
      --j;
    return j;
  }

  template <bool Gradient>
  /// adds the samples [b, e) but those nearer to q than sqrt(x2)
  void add_samples(const double q[3], double f2, std::size_t b, std::size_t e, double& w, double* g,
                   double x2 = 0.0) const
  {
    for (std::size_t t = b; t < e; ++t) {
      const Winding_sample& s = samples_[t];
      const double r[3] = {s.p[0] - q[0], s.p[1] - q[1], s.p[2] - q[2]};
      if (x2 > 0.0 && r[0] * r[0] + r[1] * r[1] + r[2] * r[2] < x2)
        continue;
      Winding_kernel::add_sample<Gradient>(r, s.an, f2 * s.width2, w, g);
    }
  }

  template <typename ConcurrencyTag>
  void build_node(std::size_t i, unsigned int d, std::size_t j)
  {
    const std::size_t b = range_begin(d, j), e = range_begin(d, j + 1);
    Winding_node& node = nodes_[i];
    if (d == depth_) {
      leaf_geometry(node, b, e);
      leaf_moments(node, b, e);
      return;
    }
    split(b, range_begin(d + 1, 2 * j + 1), e);
    auto left = [&] { build_node<ConcurrencyTag>(2 * i + 1, d + 1, 2 * j); };
    auto right = [&] { build_node<ConcurrencyTag>(2 * i + 2, d + 1, 2 * j + 1); };
#ifdef CGAL_LINKED_WITH_TBB
    if (std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value && e - b > (std::size_t(1) << 15)) {
      tbb::parallel_invoke(left, right);
    } else
#endif
    {
      left();
      right();
    }
    leaf_geometry(node, b, e); // (from the samples, as for a leaf)
    inner_moments(i);
  }

  /// puts the samples of [b, e) with the smallest coordinates along the
  /// longest side of their bounding box in [b, m), ties broken by index
  void split(std::size_t b, std::size_t m, std::size_t e)
  {
    double lo[3] = {samples_[b].p[0], samples_[b].p[1], samples_[b].p[2]};
    double hi[3] = {lo[0], lo[1], lo[2]};
    for (std::size_t t = b; t < e; ++t)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], samples_[t].p[k]);
        hi[k] = std::max(hi[k], samples_[t].p[k]);
      }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (hi[k] - lo[k] > hi[axis] - lo[axis])
        axis = k;
    std::nth_element(samples_.begin() + std::ptrdiff_t(b), samples_.begin() + std::ptrdiff_t(m),
                     samples_.begin() + std::ptrdiff_t(e), [axis](const Winding_sample& x, const Winding_sample& y) {
                       return x.p[axis] < y.p[axis] || (x.p[axis] == y.p[axis] && x.index < y.index);
                     });
  }

  void set_radius(Winding_node& node, std::size_t b, std::size_t e) const
  {
    double r2 = 0.0;
    for (std::size_t t = b; t < e; ++t) {
      double s = 0.0;
      for (int k = 0; k < 3; ++k)
        s += (samples_[t].p[k] - node.center[k]) * (samples_[t].p[k] - node.center[k]);
      r2 = std::max(r2, s);
    }
    node.radius = std::sqrt(r2);
  }

  /// the centre, mean area and radius of the samples [b, e)
  void leaf_geometry(Winding_node& node, std::size_t b, std::size_t e) const
  {
    double sum_a = 0.0, sum_a2 = 0.0, c[3] = {0.0, 0.0, 0.0}, plain[3] = {0.0, 0.0, 0.0};
    for (std::size_t t = b; t < e; ++t) {
      const Winding_sample& s = samples_[t];
      sum_a += s.area;
      sum_a2 += s.area * s.width2;
      for (int k = 0; k < 3; ++k) {
        c[k] += s.area * s.p[k];
        plain[k] += s.p[k];
      }
    }
    for (int k = 0; k < 3; ++k) // (an empty node, possible with tiny leaves, sits at 0)
      node.center[k] = sum_a > 0.0 ? c[k] / sum_a : (e > b ? plain[k] / double(e - b) : 0.0);
    node.mean_area = sum_a > 0.0 ? sum_a2 / sum_a : 0.0;
    set_radius(node, b, e);
  }

  void leaf_moments(Winding_node& node, std::size_t b, std::size_t e) const
  {
    double N[3] = {0.0, 0.0, 0.0}, M[9] = {}, Q[18] = {};
    for (std::size_t t = b; t < e; ++t) {
      const Winding_sample& s = samples_[t];
      const double dl[3] = {s.p[0] - node.center[0], s.p[1] - node.center[1], s.p[2] - node.center[2]};
      for (int l = 0; l < 3; ++l) {
        N[l] += s.an[l];
        for (int k = 0; k < 3; ++k)
          M[3 * l + k] += dl[l] * s.an[k];
        for (int k = l; k < 3; ++k)
          for (int j = 0; j < 3; ++j)
            Q[3 * winding_pair(l, k) + j] += dl[l] * dl[k] * s.an[j];
      }
    }
    std::copy(N, N + 3, node.dipole);
    std::copy(M, M + 9, node.second);
    std::copy(Q, Q + 18, node.third);
  }

  /// N and M of node i from its children's (moments shifted to i's centre)
  void inner_moments(std::size_t i)
  {
    Winding_node& node = nodes_[i];
    double N[3] = {0.0, 0.0, 0.0}, M[9] = {}, Q[18] = {};
    for (std::size_t c = 2 * i + 1; c <= 2 * i + 2; ++c) {
      // p - c_node = (p - c_child) + t
      const Winding_node& child = nodes_[c];
      const double t[3] = {child.center[0] - node.center[0], child.center[1] - node.center[1],
                           child.center[2] - node.center[2]};
      for (int l = 0; l < 3; ++l) {
        N[l] += child.dipole[l];
        for (int k = 0; k < 3; ++k)
          M[3 * l + k] += child.second[3 * l + k] + t[l] * child.dipole[k];
        for (int k = l; k < 3; ++k)
          for (int j = 0; j < 3; ++j)
            Q[3 * winding_pair(l, k) + j] += child.third[3 * winding_pair(l, k) + j] + t[l] * child.second[3 * k + j]
                                             + t[k] * child.second[3 * l + j] + t[l] * t[k] * child.dipole[j];
      }
    }
    std::copy(N, N + 3, node.dipole);
    std::copy(M, M + 9, node.second);
    std::copy(Q, Q + 18, node.third);
  }

  std::vector<Winding_sample> samples_; // in tree order
  std::vector<std::uint32_t> position_;  // input index -> tree position
  std::vector<Winding_node> nodes_;      // heap layout
  std::vector<Charge_node> charges_;     // heap layout, from set_charges()
  std::vector<double> position_charge_;  // by tree position, from set_charges()
  unsigned int depth_ = 0;
};

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_WINDING_NUMBER_TREE_H
