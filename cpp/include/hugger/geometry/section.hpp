/// \file section.hpp
/// Planar sections of a closed mesh: closed polygons in a plane's 2D frame, with a
/// uniform-grid acceleration structure for distance and inside queries.
#pragma once

#include <vector>

#include "hugger/types.hpp"

namespace hugger {

/// The section of a closed mesh by a plane, as closed loops in the plane's (u, v) frame.
/// Outer boundaries run counter-clockwise (interior on the left), holes clockwise.
class Section {
 public:
  Section() = default;
  explicit Section(std::vector<std::vector<Vec2>> loops);

  const std::vector<std::vector<Vec2>>& loops() const { return loops_; }
  bool empty() const { return segments_.empty(); }
  /// Distance from p to the section's boundary (metres).
  double boundary_distance(const Vec2& p) const;
  /// True when p is inside the section (even-odd over all loops).
  bool inside(const Vec2& p) const;
  /// Signed area (sum over loops; > 0 for outer loops).
  double area() const;
  /// Total length of all loops.
  double perimeter() const;

 private:
  struct Seg {
    Vec2 a, b;
  };
  void cells_of(const Vec2& a, const Vec2& b, std::vector<int>& out) const;

  std::vector<std::vector<Vec2>> loops_;
  std::vector<Seg> segments_;
  Vec2 lo_ = Vec2::Zero(), cell_ = Vec2::Ones();
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<int>> grid_;  ///< segment indices per cell
};

}  // namespace hugger
