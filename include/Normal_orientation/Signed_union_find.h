// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SIGNED_UNION_FIND_H
#define NORMAL_ORIENTATION_SIGNED_UNION_FIND_H

/// \file Signed_union_find.h
/// The signed union-find of the paper's supplement, section 2.

#include <cstdint>
#include <utility>
#include <limits>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationSolvers
/// A union-find (disjoint-set forest) whose nodes carry a sign bit s_i.  The
/// sign of an element is the XOR of the bits on its path to the root, root
/// included (supplement eq. 2), so flipping the sign of every element of a
/// set costs one bit flip at its root.  Union by rank and full path
/// compression (with the sign update s_i <- s_i xor ... xor s_q of the
/// supplement) keep both operations in effectively constant time.
///
/// Elements are the integers 0 ... size()-1.  Every element starts alone,
/// with sign `false` (+).  Not thread safe: `find()` and `sign()` compress
/// paths, so they modify the structure.
class Signed_union_find
{
public:
  /// the element type (32-bit: at most 2^32 - 1 elements)
  typedef std::uint32_t Index;

  /// creates `n` singleton sets with positive signs
  explicit Signed_union_find(std::size_t n = 0) { reset(n); }

  /// discards everything and creates `n` singleton sets with positive signs
  void reset(std::size_t n)
  {
    if (n >= std::size_t(std::numeric_limits<Index>::max()))
      throw std::length_error("Signed_union_find: too many elements for 32-bit indices");
    m_parent.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      m_parent[i] = Index(i);
    m_rank.assign(n, 0);
    m_sign.assign(n, 0);
  }

  /// the number of elements
  std::size_t size() const { return m_parent.size(); }

  /// returns the root (representative) of the set of `i`, compressing the path
  Index find(Index i)
  {
    Index root = i;
    unsigned char path_xor = 0; // XOR of the bits strictly below the root
    while (m_parent[root] != root) {
      path_xor ^= m_sign[root];
      root = m_parent[root];
    }
    // Relink every node of the path to the root.  A node's new bit is the
    // XOR of the old bits from itself up to (excluding) the root, which is
    // `path_xor` minus the bits of the nodes already passed.
    Index node = i;
    while (m_parent[node] != root && node != root) {
      const Index next = m_parent[node];
      const unsigned char old_bit = m_sign[node];
      m_sign[node] = path_xor;
      path_xor ^= old_bit;
      m_parent[node] = root;
      node = next;
    }
    return root;
  }

  /// returns the root of `i` and stores the sign of `i` (`true` for -) in
  /// `sign`, with one path compression
  Index find(Index i, bool& sign)
  {
    const Index root = find(i);
    sign = (root == i ? m_sign[i] : (m_sign[i] ^ m_sign[root])) != 0;
    return root;
  }

  /// flips the sign of every element of the set whose root is `root`
  /// \pre `root` is a root
  void flip_root(Index root) { m_sign[root] ^= 1; }

  /// merges the sets of the roots `a` and `b` without changing any sign;
  /// returns the new root
  /// \pre `a` and `b` are different roots
  Index unite_roots(Index a, Index b)
  {
    if (m_rank[a] < m_rank[b] || (m_rank[a] == m_rank[b] && b < a))
      std::swap(a, b);
    // a becomes the root of b: b's subtree keeps its signs iff s_b ^= s_a
    m_parent[b] = a;
    m_sign[b] ^= m_sign[a];
    if (m_rank[a] == m_rank[b])
      ++m_rank[a];
    return a;
  }

  /// returns the sign of `i` (`true` for -), compressing its path
  bool sign(Index i)
  {
    const Index root = find(i);
    return (root == i ? m_sign[i] : (m_sign[i] ^ m_sign[root])) != 0;
  }

  /// flips the sign of every element of the set of `i`
  void flip(Index i) { m_sign[find(i)] ^= 1; }

  /// `true` iff `i` and `j` are in the same set
  bool same_set(Index i, Index j) { return find(i) == find(j); }

  /// merges the sets of `i` and `j` (union by rank, the lower index wins a
  /// tie) without changing the sign of any element; returns the new root
  Index unite(Index i, Index j)
  {
    const Index a = find(i), b = find(j);
    return a == b ? a : unite_roots(a, b);
  }

private:
  std::vector<Index> m_parent;
  std::vector<unsigned char> m_rank;
  std::vector<unsigned char> m_sign;
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SIGNED_UNION_FIND_H
