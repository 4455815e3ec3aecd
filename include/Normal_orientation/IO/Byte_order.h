// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Byte_order.h
/// \brief Binary values in either byte order: the order of this machine, byte swaps,
/// and loading and storing a value through its bit pattern.

#ifndef NORMAL_ORIENTATION_IO_BYTE_ORDER_H
#define NORMAL_ORIENTATION_IO_BYTE_ORDER_H

#include <cstdint>
#include <cstring>

namespace Normal_orientation {
namespace IO {
namespace internal {

/// \brief Returns `true` if this machine stores integers little-endian.
inline bool host_is_little_endian()
{
  const std::uint16_t one = 1;
  unsigned char first_byte = 0;
  std::memcpy(&first_byte, &one, 1);
  return first_byte == 1;
}

/// \brief Byte-swapped `value`.
inline std::uint16_t byte_swap(std::uint16_t value)
{
  return static_cast<std::uint16_t>((value >> 8) | (value << 8));
}
/// \brief Byte-swapped `value`.
inline std::uint32_t byte_swap(std::uint32_t value)
{
  return ((value & 0x000000FFu) << 24) | ((value & 0x0000FF00u) << 8) |
         ((value & 0x00FF0000u) >> 8) | ((value & 0xFF000000u) >> 24);
}
/// \brief Byte-swapped `value`.
inline std::uint64_t byte_swap(std::uint64_t value)
{
  return (std::uint64_t(byte_swap(std::uint32_t(value))) << 32) |
         std::uint64_t(byte_swap(std::uint32_t(value >> 32)));
}

/// \brief Reads a value of type `Stored` (via its bit pattern `Bits`) at `source`.
template <class Stored, class Bits>
inline Stored load_bits(const char* source, bool swap)
{
  Bits bits;
  std::memcpy(&bits, source, sizeof(Bits));
  if(swap) bits = byte_swap(bits);
  Stored value;
  std::memcpy(&value, &bits, sizeof(Stored));
  return value;
}

/// \brief Writes `value` (of type `Stored`, via its bit pattern `Bits`) at `target`.
template <class Stored, class Bits>
inline void store_bits(char* target, Stored value, bool swap)
{
  Bits bits;
  std::memcpy(&bits, &value, sizeof(Bits));
  if(swap) bits = byte_swap(bits);
  std::memcpy(target, &bits, sizeof(Bits));
}

} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_BYTE_ORDER_H
