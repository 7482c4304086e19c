/// \file harmonic.hpp
/// Angles where constraints of the form k0 + k1 cos t + k2 sin t <= 0 all hold: the arcs of a
/// circle that the section skin's region build keeps of a cylinder's ellipse or a sphere's circle.
#pragma once

#include <array>
#include <cmath>
#include <vector>

namespace hugger {

/// A constraint on an angle t: allowed where k0 + k1 cos t + k2 sin t <= 0 (one arc of the
/// circle, all of it, or at most a point).
struct Harmonic {
  double k0, k1, k2;
  double at(double t) const { return k0 + k1 * std::cos(t) + k2 * std::sin(t); }
  double scale() const { return std::abs(k0) + std::abs(k1) + std::abs(k2); }
};

/// The closed intervals of [0, 2 pi) (an interval may run past 2 pi when it wraps) where all `n`
/// constraints hold, as sorted disjoint intervals: the intersection of each one's arc.
std::vector<std::array<double, 2>> allowed_intervals(const Harmonic* hs, int n);

/// True only when no angle satisfies all `n` constraints, so that allowed_intervals(hs, n) is
/// empty; without trigonometry (for the many calls that find nothing). False when unsure.
bool surely_empty(const Harmonic* hs, int n);

}  // namespace hugger
