// SPDX-License-Identifier: GPL-3.0-or-later
// Documentation only: the concept ComponentSignPolicy (not compiled, not installed).

/*!
\ingroup PkgNormalOrientationConcepts
\cgalConcept
\headerfile Component_sign.h <Normal_orientation/Component_sign.h>

Without unary terms, the orientation energy does not change when every label of a
connected component of the neighbour graph flips: the solver makes each component
consistent, but the global sign of each one is still free.  A component sign policy
chooses it, after the solve, from the positions, the normals and the labels
(see \ref NormalOrientationSecSign).

The policy is called once per run, from the calling thread, with a
`Normal_orientation::Component_sign_input`; it returns one entry per component, non-zero
to flip every normal of that component.  Components that hold a point with a unary term
(a constraint or a non-zero prior) are not flipped, whatever the policy returns: the
solver has already chosen their sign.

The policy must be copy constructible (it is stored by value).

\cgalHasModelsBegin
\cgalHasModels{Normal_orientation::Outward_component_sign}
\cgalHasModels{Normal_orientation::Viewpoint_component_sign}
\cgalHasModels{Normal_orientation::Constrained_component_sign}
\cgalHasModels{Normal_orientation::Keep_component_sign}
\cgalHasModelsEnd

\sa the named parameter `component_sign` of `Normal_orientation::orient_normals()`
    (\ref NormalOrientationNamedParameters)
*/
class ComponentSignPolicy
{
public:
  /// returns, for each component `c` in 0 ... `input.number_of_components` - 1, whether to
  /// flip it (non-zero) or not (0)
  /// \param input the positions, normals, labels and components of the run
  /// \return one entry per component, `input.number_of_components` in all
  template <typename Kernel>
  std::vector<char> operator()(const Normal_orientation::Component_sign_input<Kernel>& input) const;

  /// Optional: the name of the policy, reported in
  /// `Normal_orientation::Orientation_result::component_sign` ("user" when the model has no
  /// such function).
  /// \return a string literal, such as "outward"
  static const char* name();
};
