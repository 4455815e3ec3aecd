// SPDX-License-Identifier: GPL-3.0-or-later
// Documentation only: the concept ComponentSignPolicy (not compiled, not installed).

/*!
\ingroup PkgNormalOrientationConcepts
\cgalConcept
\headerfile Component_sign.h <Normal_orientation/Component_sign.h>

Without unary terms, the orientation energy does not change when every label of a
connected component of the neighbour graph flips: the solver makes each component
consistent, but the global sign of each one is still free.  A component sign policy
chooses it, after the solve, from the positions, the normals and the labels of the points
(see \ref NormalOrientationSecSign).

A policy is an <em>accumulator</em> that both drivers feed in the same way, so that each
rule is written once and works in core and out of core alike:

1. the driver calls `begin()` once per run, from the calling thread, with a
   `Normal_orientation::Component_sign_setup` (the number of components, the number of
   points of each, the neighbour radius r), and gets an `Accumulator`;
2. it asks the accumulator for its `number_of_passes()`, and in each pass hands it every
   point once with `add()`, as a `Normal_orientation::Component_sign_point` (its
   component, position, current orientation, label, and whether it is constrained), in
   the same order in every pass: `Normal_orientation::orient_normals()` through
   `Normal_orientation::component_signs()`, from its vectors, in its internal (Morton)
   order; `Normal_orientation::streaming_orient_normals()` from its record file, in the
   sweep order;
3. it calls `decide()`, which returns one entry per component, non-zero to flip every
   normal of that component.

The order of the points differs between the drivers, so a decision should depend only on
sums over the points of a component (reduced in the order given), not on which point comes
first.  A policy that needs no pass (`number_of_passes()` returns 0) is never given a
point.  Components that hold a point with a unary term (a constraint or a non-zero prior)
are not flipped, whatever `decide()` returns: the solver has already chosen their sign.

The policy must be copy constructible (it is stored by value in the named-parameter pack);
its accumulator must be movable.  `Normal_orientation::component_signs()` runs a policy
over points of the user's own, in memory: \ref orient_mesh_graph.cpp does so on the
vertices of a mesh.

\cgalHasModelsBegin
\cgalHasModels{Normal_orientation::Outward_component_sign}
\cgalHasModels{Normal_orientation::Viewpoint_component_sign}
\cgalHasModels{Normal_orientation::Constrained_component_sign}
\cgalHasModels{Normal_orientation::Keep_component_sign}
\cgalHasModelsEnd

\sa the named parameter `component_sign` of `Normal_orientation::orient_normals()` and
    `Normal_orientation::streaming_orient_normals()` (\ref NormalOrientationNamedParameters)
*/
class ComponentSignPolicy
{
public:
  /// The accumulator of one run: the per-component sums the rule needs.
  class Accumulator
  {
  public:
    /// the number of passes over the points it needs (0 or more); the same value
    /// every time it is asked
    unsigned int number_of_passes() const;

    /// adds one point in pass `pass`, in 0 ... `number_of_passes()` - 1; every point is
    /// added once per pass, in the same order in every pass, and the passes come in order
    /// \param pass the pass
    /// \param point the point: its component, position, current orientation and label
    void add(unsigned int pass, const Normal_orientation::Component_sign_point& point);

    /// returns, for each component `c` in 0 ... `setup.number_of_components` - 1 (the
    /// setup given to `begin()`), whether to flip it (non-zero) or not (0); called once,
    /// after the last pass
    /// \return one entry per component
    std::vector<char> decide() const;
  };

  /// begins the accumulation of a run
  /// \param setup the number of components, their sizes and the neighbour radius
  /// \return an accumulator for these components
  Accumulator begin(const Normal_orientation::Component_sign_setup& setup) const;

  /// Optional: the name of the policy, reported in
  /// `Normal_orientation::Orientation_summary::component_sign` of both drivers' results
  /// ("user" when the model has no such function).
  /// \return a string, such as "outward" (a `static` function does too)
  const char* name() const;
};
