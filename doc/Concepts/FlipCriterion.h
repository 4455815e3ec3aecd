// SPDX-License-Identifier: GPL-3.0-or-later
// Documentation only: the concept FlipCriterion (not compiled, not installed).

/*!
\ingroup PkgNormalOrientationConcepts
\cgalConcept
\headerfile Flip_criteria.h <Normal_orientation/Flip_criteria.h>

A flip criterion judges one edge of the neighbour graph: given two neighbouring points
with their unoriented normals, it returns a signed certainty \f$ \phi(i, j) \in [-1, 1] \f$
that the two normals are consistently oriented as they are.

- \f$ \phi > 0 \f$: the two normals agree (both labels should be equal);
- \f$ \phi < 0 \f$: one of the two should be flipped (the labels should differ);
- \f$ |\phi| \f$: how sure the criterion is; 0 means "nothing can be said".

The neighbour graph multiplies \f$ \phi \f$ by the distance weight
\f$ \omega = 1 - d^2 / r^2 \f$ to obtain the signed edge weight \f$ w_{ij} \f$ of the
orientation energy (see \ref NormalOrientationSecCriteria).

A model must be

- symmetric: exchanging \f$ (p_i, n_i) \f$ and \f$ (p_j, n_j) \f$ gives the same value;
- invariant when both normals flip: \f$ \phi(p_i, -n_i, p_j, -n_j) = \phi(p_i, n_i, p_j, n_j) \f$
  (so that the value does not depend on the arbitrary signs of the input, only on their
  relation), and odd when one of them flips;
- finite on degenerate input: normals of any length, zero normals (return 0) and
  coincident points;
- thread safe: `operator()` is `const` and is called concurrently on different edges;
- copy constructible (it is stored by value in the named-parameter pack).

Both drivers call the same `operator()`: `Normal_orientation::orient_normals()` on the edges
of the in-core graph, `Normal_orientation::streaming_orient_normals()` on the edges the sweep
finds.

\cgalHasModelsBegin
\cgalHasModels{Normal_orientation::Hoppe_criterion}
\cgalHasModels{Normal_orientation::Xie_criterion}
\cgalHasModels{Normal_orientation::Konig_criterion}
\cgalHasModelsEnd

\sa the named parameter `flip_criterion` of `Normal_orientation::orient_normals()` and
    `Normal_orientation::streaming_orient_normals()` (\ref NormalOrientationNamedParameters)
\sa `Normal_orientation::build_neighbor_graph()`
*/
class FlipCriterion
{
public:
  /// returns \f$ \phi \in [-1, 1] \f$ for the edge between the point `p_i` of normal `n_i`
  /// and the point `p_j` of normal `n_j` (normals of any length, possibly zero).
  /// `Point_3` and `Vector_3` are the point and vector types of the kernel in use.
  /// \param p_i the position of the first point
  /// \param n_i its normal, as given
  /// \param p_j the position of the second point
  /// \param n_j its normal, as given
  /// \return \f$ \phi \f$: > 0 for consistent normals, < 0 when one should flip, 0 when unknown
  template <typename Point_3, typename Vector_3>
  double operator()(const Point_3& p_i, const Vector_3& n_i, const Point_3& p_j, const Vector_3& n_j) const;

  /// Optional: the name of the criterion, reported in
  /// `Normal_orientation::Orientation_summary::criterion` of both drivers' results ("user"
  /// when the model has no such function; a non-static member function does too).
  /// \return a string literal, such as "hoppe"
  static const char* name();
};
