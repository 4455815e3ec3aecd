// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Cli_sign_policy.h
/// The component sign policy of the command line, chosen at run time
/// (--sign outward|keep, --viewpoint X,Y,Z), and the viewpoint prior of
/// --prior-weight as a property map over the streamed records: one policy
/// type for both drivers, so the pipeline is compiled once per criterion
/// and solver, not once per sign policy too.
#ifndef NORMAL_ORIENTATION_EXAMPLES_CLI_SIGN_POLICY_H
#define NORMAL_ORIENTATION_EXAMPLES_CLI_SIGN_POLICY_H

#include "Cli_options.h"

#include <Normal_orientation/Component_sign.h>
#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Point_record.h>

#include <boost/property_map/property_map.hpp>

#include <array>
#include <cmath>
#include <utility>
#include <variant>
#include <vector>

namespace Cli {

/// A model of `ComponentSignPolicy` that runs the policy the options name:
/// `Viewpoint_component_sign` with --viewpoint, `Keep_component_sign` with
/// --sign keep, else `Outward_component_sign`.
class Component_sign
{
public:
  /// the policy of the options `o`
  explicit Component_sign(const Options& o)
    : m_mode(o.has_viewpoint ? Mode::VIEWPOINT : o.sign == "keep" ? Mode::KEEP : Mode::OUTWARD),
      m_viewpoint(o.viewpoint[0], o.viewpoint[1], o.viewpoint[2])
  {}
  /// the name of the policy run ("outward", "viewpoint" or "keep")
  const char* name() const
  {
    return m_mode == Mode::VIEWPOINT ? Normal_orientation::Viewpoint_component_sign::name()
           : m_mode == Mode::KEEP    ? Normal_orientation::Keep_component_sign::name()
                                     : Normal_orientation::Outward_component_sign::name();
  }

  /// the accumulator of the policy run
  class Accumulator
  {
  public:
    /// the passes over the points it needs
    unsigned int number_of_passes() const
    {
      return std::visit([](const auto& a) { return a.number_of_passes(); }, m_accumulator);
    }
    /// adds point `p` in pass `pass`
    void add(unsigned int pass, const Normal_orientation::Component_sign_point& p)
    {
      std::visit([&](auto& a) { a.add(pass, p); }, m_accumulator);
    }
    /// for each component, whether to flip it
    std::vector<char> decide() const
    {
      return std::visit([](const auto& a) { return a.decide(); }, m_accumulator);
    }

  private:
    friend class Component_sign;
    template <typename A>
    explicit Accumulator(A&& a) : m_accumulator(std::forward<A>(a))
    {}
    std::variant<Normal_orientation::Outward_component_sign::Accumulator,
                 Normal_orientation::Viewpoint_component_sign::Accumulator,
                 Normal_orientation::Keep_component_sign::Accumulator>
      m_accumulator;
  };
  /// begins the accumulation
  Accumulator begin(const Normal_orientation::Component_sign_setup& setup) const
  {
    if (m_mode == Mode::VIEWPOINT)
      return Accumulator(m_viewpoint.begin(setup));
    if (m_mode == Mode::KEEP)
      return Accumulator(Normal_orientation::Keep_component_sign().begin(setup));
    return Accumulator(Normal_orientation::Outward_component_sign().begin(setup));
  }

private:
  enum class Mode { OUTWARD, VIEWPOINT, KEEP };
  Mode m_mode;
  Normal_orientation::Viewpoint_component_sign m_viewpoint;
};

/// The global stage of --global: `VISIBILITY_AND_WINDING` for "visibility",
/// and for "auto" when the components face outward (no --viewpoint, no
/// --sign keep); `WINDING` for "winding"; `NONE` otherwise.
inline Normal_orientation::Global_orientation global_orientation(const Options& o)
{
  typedef Normal_orientation::Global_orientation G;
  const bool automatic = o.global == "auto" && !o.has_viewpoint && o.sign == "outward" && o.prior_weight == 0.0;
  if (o.global == "visibility" || automatic)
    return G::VISIBILITY_AND_WINDING;
  return o.global == "winding" ? G::WINDING : G::NONE;
}

/// a_i = W cos(angle between n_i and p_i -> viewpoint), or 0 when n_i or
/// p_i -> viewpoint is zero: the prior of --prior-weight W
inline double viewpoint_prior(const std::array<double, 3>& viewpoint, double weight, const double* p,
                              const double* n)
{
  double to[3], dot = 0.0, lt = 0.0, ln = 0.0;
  for (int d = 0; d < 3; ++d) {
    to[d] = viewpoint[d] - p[d];
    dot += to[d] * n[d];
    lt += to[d] * to[d];
    ln += n[d] * n[d];
  }
  return lt > 0.0 && ln > 0.0 ? weight * dot / std::sqrt(lt * ln) : 0.0;
}

/// The viewpoint prior of a streamed record, as a readable property map.
struct Record_viewpoint_prior
{
  typedef Normal_orientation::Point_record key_type;   ///< the record
  typedef double value_type;                           ///< its prior
  typedef double reference;                            ///< by value
  typedef boost::readable_property_map_tag category;   ///< read only
  std::array<double, 3> viewpoint;                     ///< the viewpoint
  double weight;                                       ///< W
  /// the prior of `r`
  friend double get(const Record_viewpoint_prior& m, const Normal_orientation::Point_record& r)
  {
    return viewpoint_prior(m.viewpoint, m.weight, r.position, r.normal);
  }
};

} // namespace Cli

#endif // NORMAL_ORIENTATION_EXAMPLES_CLI_SIGN_POLICY_H
