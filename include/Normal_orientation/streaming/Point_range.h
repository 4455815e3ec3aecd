// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_POINT_RANGE_H
#define NORMAL_ORIENTATION_STREAMING_POINT_RANGE_H

/// \file Point_range.h
/// The streaming pipeline over the user's own points: a source that hands
/// out the points of an iterator range (read through property maps) in
/// chunks and checks their order as it reads, and a sink that writes the
/// oriented normals back into a random-access range.

#include <Normal_orientation/parameters.h>
#include <Normal_orientation/Point_record.h>

#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/property_map.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {
namespace streaming {

/// \ingroup PkgNormalOrientationStreaming
/// A streaming source (the concept `streaming_orient_normals()` and
/// `sweep()` read: `read(chunk, maximum)`, `rewind()`) over the points of
/// the range [first, last): point i has the position `get(point_map, *it)`
/// and the normal `get(normal_map, *it)` of the i-th element and the index
/// i.  Nothing is copied but the chunk being read.
///
/// When `checked_axis` is 0, 1 or 2, the points must be sorted by
/// non-decreasing x, y or z: `read()` checks it as it goes and throws
/// `std::runtime_error` naming the first point out of order (and also for a
/// non-finite coordinate along that axis).  With -1 (the default) nothing
/// is checked here (`streaming_orient_normals()` checks a presorted input
/// in its first pass, and sorts any other).
///
/// \tparam ForwardIterator a forward iterator (the range is read several
///         times)
/// \tparam PointMap a readable property map to a CGAL `Point_3`
/// \tparam NormalMap a readable property map to a CGAL `Vector_3`
template <typename ForwardIterator, typename PointMap, typename NormalMap>
class Point_range_source
{
public:
  /// the source of [first, last)
  Point_range_source(ForwardIterator first, ForwardIterator last, PointMap point_map, NormalMap normal_map,
                     int checked_axis = -1)
    : m_first(first), m_last(last), m_current(first), m_point_map(point_map), m_normal_map(normal_map),
      m_axis(checked_axis)
  {
    if (checked_axis < -1 || checked_axis > 2)
      throw std::invalid_argument("Point_range_source: the checked axis must be -1, 0, 1 or 2");
  }

  /// appends up to `maximum` records to `chunk`; returns how many, 0 at the
  /// end
  /// \throw std::runtime_error when the order along the checked axis is broken
  std::size_t read(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    std::size_t got = 0;
    for (; got < maximum && m_current != m_last; ++m_current, ++got, ++m_index) {
      const auto& p = get(m_point_map, *m_current);
      const auto& n = get(m_normal_map, *m_current);
      Point_record r;
      for (int d = 0; d < 3; ++d) {
        r.position[d] = CGAL::to_double(p[d]);
        r.normal[d] = CGAL::to_double(n[d]);
      }
      r.index = m_index;
      if (m_axis >= 0) {
        const double key = r.position[m_axis];
        if (!std::isfinite(key) || key < m_last_key) {
          std::ostringstream msg;
          msg << "Point_range_source: the points are not sorted by increasing " << "xyz"[m_axis] << " at point "
              << m_index << " (" << key << " after " << m_last_key << ")";
          throw std::runtime_error(msg.str());
        }
        m_last_key = key;
      }
      chunk.push_back(r);
    }
    return got;
  }

  /// starts again from the first point
  void rewind()
  {
    m_current = m_first;
    m_index = 0;
    m_last_key = -std::numeric_limits<double>::infinity();
  }

  /// the number of points of the range
  std::size_t size() const { return std::size_t(std::distance(m_first, m_last)); }

private:
  ForwardIterator m_first, m_last, m_current;
  PointMap m_point_map;
  NormalMap m_normal_map;
  int m_axis;
  std::uint64_t m_index = 0;
  double m_last_key = -std::numeric_limits<double>::infinity();
};

/// \ingroup PkgNormalOrientationStreaming
/// The source of the points of `points` (a range of a CGAL point set
/// processing style: `CGAL::Point_set_3`, a vector of pairs...), with the
/// named parameters `point_map` and `normal_map` (required), and the
/// argument `checked_axis`: -1 (default), 0, 1 or 2 (see `Point_range_source`).
template <typename PointRange, typename NamedParameters = parameters::Default_named_parameters>
Point_range_source<typename PointRange::const_iterator,
                   typename CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>::Const_point_map,
                   typename CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>::Normal_map>
make_point_range_source(const PointRange& points, const NamedParameters& np = parameters::default_values(),
                        int checked_axis = -1)
{
  typedef CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters> NP_helper;
  static_assert(NP_helper::has_normal_map(), "make_point_range_source: the normal_map named parameter is required");
  return Point_range_source<typename PointRange::const_iterator, typename NP_helper::Const_point_map,
                            typename NP_helper::Normal_map>(points.begin(), points.end(),
                                                            NP_helper::get_const_point_map(points, np),
                                                            NP_helper::get_normal_map(points, np), checked_axis);
}

/// \ingroup PkgNormalOrientationStreaming
/// A sink for `streaming_orient_normals()` that writes each oriented
/// normal back into the element of index `record.index` of the range
/// starting at `first` (the range the source read), through `normal_map`:
/// the user's points are oriented in place, in their own order.
///
/// \tparam RandomAccessIterator a mutable random-access iterator
/// \tparam NormalMap a read-write property map to a CGAL `Vector_3`
template <typename RandomAccessIterator, typename NormalMap>
class Normal_writer
{
public:
  /// writes through `normal_map` into the elements from `first` on
  Normal_writer(RandomAccessIterator first, NormalMap normal_map) : m_first(first), m_normal_map(normal_map) {}
  /// writes the normal of `record` to element `record.index`
  void operator()(const Point_record& record)
  {
    typedef typename boost::property_traits<NormalMap>::value_type Vector;
    put(m_normal_map, *(m_first + std::ptrdiff_t(record.index)),
        Vector(record.normal[0], record.normal[1], record.normal[2]));
  }

private:
  RandomAccessIterator m_first;
  NormalMap m_normal_map;
};

/// \ingroup PkgNormalOrientationStreaming
/// `Normal_writer` into `points` (the range the source read; same size),
/// through the named parameter `normal_map` (required)
template <typename PointRange, typename NamedParameters = parameters::Default_named_parameters>
Normal_writer<typename PointRange::iterator,
              typename CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>::Normal_map>
make_normal_writer(PointRange& points, const NamedParameters& np = parameters::default_values())
{
  typedef CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters> NP_helper;
  static_assert(NP_helper::has_normal_map(), "make_normal_writer: the normal_map named parameter is required");
  return Normal_writer<typename PointRange::iterator, typename NP_helper::Normal_map>(
    points.begin(), NP_helper::get_normal_map(points, np));
}

} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_POINT_RANGE_H
