// SPDX-License-Identifier: GPL-3.0-or-later
// Documentation only: the concept OrientationSolver (not compiled, not installed).

/*!
\ingroup PkgNormalOrientationConcepts
\cgalConcept
\headerfile Solver_report.h <Normal_orientation/solvers/Solver_report.h>

An orientation solver minimises, exactly or heuristically, the orientation energy of a
graph whose edges carry signed weights (see \ref NormalOrientationSecEnergy):
\f[ E(L) = \sum_{e = \{i, j\}} E_e(L_i, L_j) \;+\; \sum_i U_i(L_i), \qquad L_i \in \{+1, -1\}, \f]
where the pairwise term \f$ E_e \f$ is `Normal_orientation::edge_energy()` (\f$ |w_e| \f$ when
the labels do not do what the sign of \f$ w_e \f$ asks, 0 otherwise) and the optional
unary terms \f$ U_i \f$ are given by a map.  It writes one label, +1 (keep the normal)
or -1 (flip it), per vertex.

A solver knows nothing of points: the graph is any Boost graph, and the solver can be used
on its own (the tests run the solvers on random signed graphs).  Requirements on the
arguments of `solve()`:

- `Graph` is a model of `VertexListGraph` and `EdgeListGraph` with an internal
  `vertex_index` map numbering the vertices 0 ... n-1; every edge is one pairwise term,
  whatever its direction (store each neighbour pair once);
- `WeightMap` is a readable edge property map with a floating value type: the signed weight
  \f$ w_e \f$ (> 0: equal labels wanted, < 0: different labels wanted);
- `UnaryMap` is a readable vertex property map whose value has members `first` (the cost of
  label +1) and `second` (the cost of label -1), convertible to `double`, such as
  `std::pair<double, double>`;
- `LabelMap` is a writable vertex property map accepting `Normal_orientation::Label`.

The energy does not change when all the labels of a connected component flip (without unary
terms): a solver may return either sign, and a `ComponentSignPolicy` decides afterwards.
Solvers must be deterministic (random choices come from a seed held by the solver) and
`solve()` is `const`.

The overload with unary terms is optional: both drivers need it only when the named
parameters `point_is_constrained_map` or `orientation_prior_map` are given.
`Normal_orientation::orient_normals()` refuses, at compile time, a solver without it in that
case; `Normal_orientation::streaming_orient_normals()`, which solves the segment graph (with
the unary terms of the points summed per segment), throws `std::invalid_argument`.  Without
unary terms, the streaming driver calls the overload without them, on the segment graph and
in each round of its refinement.

\cgalHasModelsBegin
\cgalHasModels{Normal_orientation::Mst_solver}
\cgalHasModels{Normal_orientation::Qpbo_i_solver}
\cgalHasModels{Normal_orientation::Lsa_tr_solver}
\cgalHasModels{Normal_orientation::Exhaustive_solver}
\cgalHasModelsEnd

\sa the named parameter `solver` of `Normal_orientation::orient_normals()` and
    `Normal_orientation::streaming_orient_normals()` (\ref NormalOrientationNamedParameters)
\sa `Normal_orientation::energy()`, `Normal_orientation::connected_components()`
*/
class OrientationSolver
{
public:
  /// Minimises the energy of the labelling of `g` with the signed edge weights `weight`
  /// and writes +1 or -1 to `labels` for every vertex.  The report gives at least the
  /// energy of the labelling written (`Solver_report::energy`), the edges it leaves
  /// unsatisfied (`Solver_report::frustrated_edges`) and, for a solver that works on a
  /// reduced graph, its number of vertices (`Solver_report::segments`, 0 otherwise).
  /// A solver that improves a starting labelling may report it
  /// (`Solver_report::starting_labels`): the drivers' global stage then never puts
  /// in one patch a vertex that the solver negated against it and one that it kept.
  /// \param g the graph: one pairwise term per edge
  /// \param weight the signed edge weights
  /// \param labels receives the label (+1 or -1) of every vertex
  /// \return the report of the solve
  template <typename Graph, typename WeightMap, typename LabelMap>
  Normal_orientation::Solver_report solve(const Graph& g, WeightMap weight, LabelMap labels) const;

  /// Optional: the same with the unary terms `unary`; `Solver_report::energy` then
  /// includes them.  With every unary cost zero, the labels must be those of the solve
  /// without unary terms.
  /// \param g the graph: one pairwise term per edge
  /// \param weight the signed edge weights
  /// \param unary the costs of the labels +1 (`first`) and -1 (`second`) of every vertex
  /// \param labels receives the label (+1 or -1) of every vertex
  /// \return the report of the solve
  template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
  Normal_orientation::Solver_report solve(const Graph& g, WeightMap weight, UnaryMap unary, LabelMap labels) const;

  /// Optional: the name of the solver, reported in
  /// `Normal_orientation::Orientation_summary::solver` of both drivers' results ("user" when
  /// the model has no such function; a non-static member function does too).
  /// \return a string literal, such as "qpbo-i"
  static const char* name();
};
