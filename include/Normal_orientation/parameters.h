// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_PARAMETERS_H
#define NORMAL_ORIENTATION_PARAMETERS_H

/// \file parameters.h
/// Named parameters of the Normal_orientation package.
///
/// The package reads its options with CGAL's named-parameter machinery, so a
/// pack built with `CGAL::parameters::point_map(pm).normal_map(nm)` is accepted
/// as is.  CGAL's list of names is closed, so the package's own names
/// (`number_of_neighbors`, `flip_criterion`, `solver`, `component_sign`,
/// `number_of_threads`, `orientation_prior_map`, `global_orientation`, `up_direction`, `layer_edges`, and the streaming driver's
/// `presorted_axis`, `temporary_directory`, `sort_memory`,
/// `refinement_rounds`, `minimum_component_size`, `component_files`,
/// `batch_size`; all the names are described
/// on the page \ref NormalOrientationNamedParameters) live in
/// `Normal_orientation::parameters`, whose packs
/// are CGAL packs (derived from `CGAL::Named_function_parameters`) that also
/// offer every CGAL name, so both kinds of names chain freely:
/// \code
/// namespace NP = Normal_orientation::parameters;
/// orient_normals(points, NP::point_map(pm).normal_map(nm).number_of_neighbors(12));
/// orient_normals(points, NP::extend(point_set.parameters()).solver(Mst_solver()));
/// \endcode

#include <CGAL/Named_function_parameters.h>

#include <type_traits>

namespace Normal_orientation {

/// Tags of the package's own named parameters.
namespace internal_np {

/// \cond SKIP_IN_MANUAL
#define NORMAL_ORIENTATION_NAMED_PARAMETERS(X) \
  X(number_of_neighbors_t, number_of_neighbors, number_of_neighbors) \
  X(flip_criterion_t, flip_criterion, flip_criterion) \
  X(solver_t, solver, solver) \
  X(component_sign_t, component_sign, component_sign) \
  X(number_of_threads_t, number_of_threads, number_of_threads) \
  X(orientation_prior_map_t, orientation_prior_map, orientation_prior_map) \
  X(presorted_axis_t, presorted_axis, presorted_axis) \
  X(temporary_directory_t, temporary_directory, temporary_directory) \
  X(sort_memory_t, sort_memory, sort_memory) \
  X(refinement_rounds_t, refinement_rounds, refinement_rounds) \
  X(minimum_component_size_t, minimum_component_size, minimum_component_size) \
  X(component_files_t, component_files, component_files) \
  X(batch_size_t, batch_size, batch_size) \
  X(global_orientation_t, global_orientation, global_orientation) \
  X(up_direction_t, up_direction, up_direction) \
  X(layer_edges_t, layer_edges, layer_edges)

#define NORMAL_ORIENTATION_DECLARE_TAG(X, Y, Z) enum X { Y };
NORMAL_ORIENTATION_NAMED_PARAMETERS(NORMAL_ORIENTATION_DECLARE_TAG)
#undef NORMAL_ORIENTATION_DECLARE_TAG
/// \endcond

} // namespace internal_np

/// \ingroup PkgNormalOrientationParameters
/// A named-parameter pack: a `CGAL::Named_function_parameters` that also has
/// the package's own names as member functions, and whose CGAL member
/// functions return packs of this type again.
template <typename T, typename Tag, typename Base = CGAL::internal_np::No_property>
struct Named_function_parameters : CGAL::Named_function_parameters<T, Tag, Base>
{
  /// the CGAL pack this type extends
  typedef CGAL::Named_function_parameters<T, Tag, Base> Cgal_pack;
  /// this type
  typedef Named_function_parameters<T, Tag, Base> self;

  /// an empty pack
  Named_function_parameters() : Cgal_pack() {}
  /// a pack holding `value`
  Named_function_parameters(const T& value) : Cgal_pack(value) {}
  /// a pack holding `value`, chained to `b`
  Named_function_parameters(const T& value, const Base& b) : Cgal_pack(value, b) {}

/// \cond SKIP_IN_MANUAL
#define CGAL_add_named_parameter(X, Y, Z)                                  \
  template <typename K>                                                  \
  Named_function_parameters<K, CGAL::internal_np::X, self> Z(const K& k) const \
  {                                                                      \
    return Named_function_parameters<K, CGAL::internal_np::X, self>(k, *this); \
  }
#include <CGAL/STL_Extension/internal/parameters_interface.h>
#undef CGAL_add_named_parameter

#define NORMAL_ORIENTATION_MEMBER(X, Y, Z)                                 \
  template <typename K>                                                  \
  Named_function_parameters<K, internal_np::X, self> Z(const K& k) const \
  {                                                                      \
    return Named_function_parameters<K, internal_np::X, self>(k, *this); \
  }
  NORMAL_ORIENTATION_NAMED_PARAMETERS(NORMAL_ORIENTATION_MEMBER)
#undef NORMAL_ORIENTATION_MEMBER
/// \endcond
};

/// Free functions that start a named-parameter pack.
namespace parameters {

/// \ingroup PkgNormalOrientationParameters
/// the empty pack, the default of every function of the package
typedef Named_function_parameters<bool, CGAL::internal_np::all_default_t> Default_named_parameters;

/// \ingroup PkgNormalOrientationParameters
/// returns the empty pack
inline Default_named_parameters default_values() { return Default_named_parameters(); }

/// \cond SKIP_IN_MANUAL
#define CGAL_add_named_parameter(X, Y, Z)                                  \
  template <typename K>                                                  \
  Named_function_parameters<K, CGAL::internal_np::X> Z(const K& k)       \
  {                                                                      \
    return Named_function_parameters<K, CGAL::internal_np::X>(k);        \
  }
#include <CGAL/STL_Extension/internal/parameters_interface.h>
#undef CGAL_add_named_parameter

#define NORMAL_ORIENTATION_FREE(X, Y, Z)                                   \
  template <typename K>                                                  \
  Named_function_parameters<K, internal_np::X> Z(const K& k)             \
  {                                                                      \
    return Named_function_parameters<K, internal_np::X>(k);              \
  }
NORMAL_ORIENTATION_NAMED_PARAMETERS(NORMAL_ORIENTATION_FREE)
#undef NORMAL_ORIENTATION_FREE

namespace internal {
inline Default_named_parameters extend_impl(const CGAL::internal_np::No_property&)
{
  return Default_named_parameters();
}

template <typename T, typename Tag, typename Base>
auto extend_impl(const CGAL::Named_function_parameters<T, Tag, Base>& np)
{
  if constexpr (std::is_same<Base, CGAL::internal_np::No_property>::value) {
    return Named_function_parameters<T, Tag>(np.v);
  } else {
    auto rest = extend_impl(static_cast<const Base&>(np));
    return Named_function_parameters<T, Tag, decltype(rest)>(np.v, rest);
  }
}
} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationParameters
/// Converts a pack of CGAL's (for example `CGAL::Point_set_3::parameters()`)
/// into a pack of this package, so that the package's own names can be
/// chained to it.
template <typename T, typename Tag, typename Base>
auto extend(const CGAL::Named_function_parameters<T, Tag, Base>& np)
{
  return internal::extend_impl(np);
}

using CGAL::parameters::choose_parameter;
using CGAL::parameters::get_parameter;
using CGAL::parameters::is_default_parameter;

} // namespace parameters
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_PARAMETERS_H
