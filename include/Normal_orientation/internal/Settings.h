// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_SETTINGS_H
#define NORMAL_ORIENTATION_INTERNAL_SETTINGS_H

/// \file Settings.h
/// The named parameters that both drivers share, read and checked in one
/// place with one set of limits, and the helpers both drivers run with.

#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/parameters.h>

#include <CGAL/Named_function_parameters.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/task_arena.h>
#endif

#include <chrono>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace Normal_orientation {

namespace internal {

/// The shared settings of a run, as read from its named parameters.
struct Settings
{
  unsigned int number_of_neighbors = default_number_of_neighbors; ///< k
  double neighbor_radius = 0.0;      ///< r; 0: estimate it
  int number_of_threads = 0;         ///< at most this many threads; 0: all
  unsigned long random_seed = 0;     ///< the seed of randomised solvers
  bool layer_edges = true;           ///< negate the edges across two layers
  Progress_reporter progress;        ///< the callback, wrapped
};

/// Throws `std::invalid_argument` naming `caller` when k, r or the thread
/// count is out of range.
inline void check_settings(const Settings& s, const char* caller)
{
  if (s.number_of_neighbors < 1 || s.number_of_neighbors > maximum_number_of_neighbors)
    throw std::invalid_argument(std::string(caller) + ": number_of_neighbors must be between 1 and " +
                                std::to_string(maximum_number_of_neighbors));
  if (s.neighbor_radius != 0.0 && !(s.neighbor_radius > 0.0 && std::isfinite(s.neighbor_radius)))
    throw std::invalid_argument(std::string(caller) + ": neighbor_radius must be a finite number > 0");
  if (s.number_of_threads < 0)
    throw std::invalid_argument(std::string(caller) + ": number_of_threads must be >= 0");
}

/// Reads k, r, the thread count, the seed, the layer edges and the callback of `np`, and
/// checks them (see `check_settings()`).
template <typename NamedParameters>
Settings read_settings(const NamedParameters& np, const char* caller)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  Settings s;
  const long long k = (long long)(choose_parameter(get_parameter(np, internal_np::number_of_neighbors),
                                                   default_number_of_neighbors));
  s.number_of_neighbors = k < 0 || k > (long long)(maximum_number_of_neighbors) ? 0u : unsigned(k);
  s.neighbor_radius = double(choose_parameter(get_parameter(np, CGAL::internal_np::neighbor_radius), 0.0));
  s.number_of_threads = int(choose_parameter(get_parameter(np, internal_np::number_of_threads), 0));
  s.random_seed = (unsigned long)(choose_parameter(get_parameter(np, CGAL::internal_np::random_seed), 0u));
  s.layer_edges = bool(choose_parameter(get_parameter(np, internal_np::layer_edges), true));
  if constexpr (!CGAL::parameters::is_default_parameter<NamedParameters, CGAL::internal_np::callback_t>::value)
    s.progress = Progress_reporter(get_parameter(np, CGAL::internal_np::callback));
  check_settings(s, caller);
  return s;
}


template <typename T, typename = void>
struct Has_name : std::false_type {};
template <typename T>
struct Has_name<T, std::void_t<decltype(std::declval<const T&>().name())>> : std::true_type {};

/// true when `Solver` has the 4-argument solve(graph, weight, unary, labels)
template <typename Solver, typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap, typename = void>
struct Accepts_unary : std::false_type {};
template <typename Solver, typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
struct Accepts_unary<Solver, Graph, WeightMap, UnaryMap, LabelMap,
                     std::void_t<decltype(std::declval<const Solver&>().solve(
                       std::declval<const Graph&>(), std::declval<WeightMap>(), std::declval<UnaryMap>(),
                       std::declval<LabelMap>()))>> : std::true_type {};

template <typename T>
std::string name_of(const T& t)
{
  if constexpr (Has_name<T>::value)
    return t.name();
  else
    return "user";
}

inline double seconds_since(std::chrono::steady_clock::time_point t)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

/// runs `f` with at most `threads` threads (0: all)
template <typename F>
void run_with_threads(int threads, const F& f)
{
#ifdef CGAL_LINKED_WITH_TBB
  if (threads > 0) {
    tbb::task_arena arena(threads);
    arena.execute(f);
    return;
  }
#endif
  (void)threads;
  f();
}

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_SETTINGS_H
