/// \file next.hpp
/// The neighbouring doubles, inline: std::nextafter is an out-of-line libm call, and the section
/// skin asks for a neighbour in most of its capped queries (a gap "just above the cap").
#pragma once

#include <cstdint>
#include <cstring>
#include <limits>

namespace hugger {

/// std::nextafter(x, +inf), bit for bit: the least double above x (NaN and +inf unchanged; a
/// signalling NaN, which no arithmetic makes, comes back unquieted).
inline double next_up(double x) {
  if (x != x || x == std::numeric_limits<double>::infinity()) return x;
  if (x == 0.0) return std::numeric_limits<double>::denorm_min();  // from -0 as from +0
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  bits = x > 0.0 ? bits + 1 : bits - 1;  // the magnitude grows above 0, shrinks below
  std::memcpy(&x, &bits, sizeof bits);
  return x;
}

/// std::nextafter(x, 0.0), bit for bit: the neighbour of x toward zero (NaN unchanged; a zero
/// of either sign gives +0, the target, as nextafter's x == y).
inline double next_toward_zero(double x) {
  if (x != x) return x;
  if (x == 0.0) return 0.0;
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  --bits;  // the sign is apart from the magnitude: one less is one ulp nearer zero either side
  std::memcpy(&x, &bits, sizeof bits);
  return x;
}

}  // namespace hugger
