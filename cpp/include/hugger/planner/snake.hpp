/// \file snake.hpp
/// Follow-the-leader propagation of a planar finger (the snake procedures of Reznik &
/// Lumelsky's algorithm A_m): Head2Tail and Tail2Head with the clinging collision rule.
#pragma once

#include <vector>

#include "hugger/sensing/sensing.hpp"

namespace hugger {

/// Joint positions of one finger in its plane, tail (index 0) to tip (index N).
using Chain = std::vector<Vec2>;

/// Settings of one propagation.
struct SnakeRequest {
  FingerPlane plane;
  const double* lengths = nullptr;  ///< N link lengths (m)
  double radius = 0.0;              ///< link radius (m)
  double front = -kInf;             ///< no joint may pass behind this eta (the palm's front plane)
  double tolerance = 1e-5;          ///< clinging resolution: metres of link-end motion
  double sample_angle = 0.05;       ///< coarse angular search increment for clinging (rad)
  double max_rotation = kPi;        ///< largest clinging rotation (rad); beyond it the link is stuck
  /// The chain's first pivot (the head for Head2Tail, the root for Tail2Head) is known to lie
  /// outside O. Every later pivot is the end of a link just placed free, so outside as well.
  bool start_outside = false;
};

/// Head2Tail (DESIGN.md decision 6): tip to `head`, then each joint on the ray toward its old
/// position at the link's length; a link that would hit O is rotated about its distal joint by
/// the smallest angle that frees it (Sensing::rotate_until_free), at most `max_rotation`. Returns false (chain partly
/// updated) if none frees it.
bool head_to_tail(const Sensing& sensing, const SnakeRequest& req, const Vec2& head, Chain& chain);

/// Tail2Head (decision 7): tail to `root`, then each joint toward its old position, rotating
/// about the proximal joint when a link would hit O. Returns false if no free position exists.
bool tail_to_head(const Sensing& sensing, const SnakeRequest& req, const Vec2& root, Chain& chain);

}  // namespace hugger
