/// \file next.hpp
/// A double's bits, and its neighbouring doubles, inline: std::nextafter is an out-of-line libm
/// call, and the section skin asks for a neighbour in most of its capped queries (a gap "just
/// above the cap").
#pragma once

#include <cstdint>
#include <cstring>
#include <limits>

namespace hugger {

/// The bits of x (equal bits: the same double; -0 and +0 differ, as NaNs of different payloads).
inline std::uint64_t bits_of(double x) {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return bits;
}

/// The double of these bits.
inline double from_bits(std::uint64_t bits) {
  double x;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}

/// std::nextafter(x, +inf), bit for bit: the least double above x (NaN and +inf unchanged; a
/// signalling NaN, which no arithmetic makes, comes back unquieted).
inline double next_up(double x) {
  if (x != x || x == std::numeric_limits<double>::infinity()) return x;
  if (x == 0.0) return std::numeric_limits<double>::denorm_min();  // from -0 as from +0
  const std::uint64_t bits = bits_of(x);
  return from_bits(x > 0.0 ? bits + 1 : bits - 1);  // the magnitude grows above 0, shrinks below
}

/// std::nextafter(x, 0.0), bit for bit: the neighbour of x toward zero (NaN unchanged; a zero
/// of either sign gives +0, the target, as nextafter's x == y).
inline double next_toward_zero(double x) {
  if (x != x) return x;
  if (x == 0.0) return 0.0;
  return from_bits(bits_of(x) - 1);  // the sign is apart from the magnitude: one ulp nearer zero either side
}

}  // namespace hugger
