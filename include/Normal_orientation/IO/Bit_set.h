// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Bit_set.h
/// \brief `Bit_set`: a set of point indices, one bit per point, as
/// `transcode_with_flips()` takes the points whose normal it negates and the points it
/// keeps.

#ifndef NORMAL_ORIENTATION_IO_BIT_SET_H
#define NORMAL_ORIENTATION_IO_BIT_SET_H

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace Normal_orientation {
namespace IO {

/// \addtogroup PkgNormalOrientationIO
/// @{

/// \brief A set of point indices `0 ... size() - 1`, one bit per point (12.5 MB for
/// 100 million points): the points whose normal `transcode_with_flips()` negates, or
/// the points it keeps.
///
/// Bit `i` is bit `i % 64` of word `i / 64` of `words()`; the bits of the last word at
/// and beyond `size()` are always clear.
class Bit_set
{
public:
  /// \brief An empty set (no index).
  Bit_set() = default;

  /// \brief A set of `size` indices, all with the bit `value`.
  explicit Bit_set(std::uint64_t size, bool value = false) { resize(size, value); }

  /// \brief Number of indices (bits), set or clear.
  std::uint64_t size() const { return size_; }

  /// \brief Returns `true` if the set has no index at all (`size() == 0`).
  bool empty() const { return size_ == 0; }

  /// \brief Changes the number of indices to `size`; the bits of the new indices are
  /// `value`, the others keep theirs.
  void resize(std::uint64_t size, bool value = false)
  {
    const std::uint64_t old_size = size_;
    words_.resize(static_cast<std::size_t>((size + 63) / 64), 0);
    size_ = size;
    if(value && size > old_size) {
      // the bits [old_size, size): the rest of the old last word, then whole words
      std::uint64_t i = old_size;
      for(; i < size && i % 64 != 0; ++i) words_[static_cast<std::size_t>(i / 64)] |= std::uint64_t(1) << (i % 64);
      for(std::size_t w = static_cast<std::size_t>(i / 64); w < words_.size(); ++w) words_[w] = ~std::uint64_t(0);
    }
    clear_tail();
  }

  /// \brief The bit of index `i`; `false` if `i >= size()`.
  bool test(std::uint64_t i) const
  {
    return i < size_ && ((words_[static_cast<std::size_t>(i / 64)] >> (i % 64)) & 1u) != 0;
  }

  /// \brief Sets the bit of index `i` to `value`.
  /// \throws std::out_of_range if `i >= size()`.
  void set(std::uint64_t i, bool value = true)
  {
    if(i >= size_)
      throw std::out_of_range("Bit_set::set: index " + std::to_string(i) + " out of a set of " +
                              std::to_string(size_));
    const std::uint64_t mask = std::uint64_t(1) << (i % 64);
    std::uint64_t& word = words_[static_cast<std::size_t>(i / 64)];
    word = value ? (word | mask) : (word & ~mask);
  }

  /// \brief Clears the bit of index `i`.
  /// \throws std::out_of_range if `i >= size()`.
  void reset(std::uint64_t i) { set(i, false); }

  /// \brief Sets every bit to `value`.
  void assign_all(bool value)
  {
    std::fill(words_.begin(), words_.end(), value ? ~std::uint64_t(0) : std::uint64_t(0));
    clear_tail();
  }

  /// \brief Number of set bits.
  std::uint64_t count() const
  {
    std::uint64_t total = 0;
    for(std::uint64_t word : words_) total += population(word);
    return total;
  }

  /// \brief Returns `true` if some bit is set.
  bool any() const
  {
    return std::any_of(words_.begin(), words_.end(), [](std::uint64_t word) { return word != 0; });
  }

  /// \brief Returns `true` if every bit is set (also when the set is empty).
  bool all() const { return count() == size_; }

  /// \brief The bits, 64 to a word (see the class description).
  const std::vector<std::uint64_t>& words() const { return words_; }

  /// \brief Returns `true` if the sets have the same size and the same bits.
  friend bool operator==(const Bit_set& a, const Bit_set& b) { return a.size_ == b.size_ && a.words_ == b.words_; }
  /// \brief Returns `true` if the sets differ in size or in some bit.
  friend bool operator!=(const Bit_set& a, const Bit_set& b) { return !(a == b); }

private:
  static std::uint64_t population(std::uint64_t x)
  {
    x = x - ((x >> 1) & 0x5555555555555555ull);
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
    return (x * 0x0101010101010101ull) >> 56;
  }

  void clear_tail()
  {
    if(size_ % 64 != 0) words_.back() &= (std::uint64_t(1) << (size_ % 64)) - 1;
  }

  std::uint64_t size_ = 0;
  std::vector<std::uint64_t> words_;
};

/// @}

} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_BIT_SET_H
