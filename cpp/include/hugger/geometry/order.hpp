/// \file order.hpp
/// Sorting without comparisons, for the builds of the 3D and 2D trees and the joining of points.
#pragma once

#include <cstdint>
#include <vector>

namespace hugger {

/// The indices 0 .. n - 1 of `values` in ascending order of (value, index), with -0 equal to +0
/// (a radix sort of the keys' high bits, then an insertion sort, or std::sort for a long run, of
/// the keys equal in those bits). The values must not be NaN.
std::vector<int> ascending_order(const std::vector<double>& values);
/// The same for unsigned integers: a stable radix sort of all their bits.
std::vector<int> ascending_order(const std::vector<std::uint32_t>& values);

}  // namespace hugger
