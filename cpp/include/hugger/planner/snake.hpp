/// \file snake.hpp
/// Follow-the-leader propagation of a planar finger (the snake procedures of Reznik &
/// Lumelsky's algorithm A_m): Head2Tail and Tail2Head with the clinging collision rule.
#pragma once

#include <cmath>
#include <vector>

#include "hugger/sensing/sensing.hpp"

namespace hugger {

/// Joint positions of one finger in its plane, tail (index 0) to tip (index N); N is at most
/// kMaxLinks (the hand's).
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
  /// Joint limits (rad), N each, of the relative angles theta_n (theta_0 from the palm normal);
  /// nullptr: unlimited. Tail2Head holds each joint within them (see joint_within_limits).
  const double* lower = nullptr;
  const double* upper = nullptr;
  /// > 0: Tail2Head gives up (returns false) as soon as a link it places comes within this of a
  /// link of the chain not next to it (link_clear_of_chain), a chain the caller would refuse
  /// anyway. 0: the chain is placed whole.
  double self_separation = 0.0;
  /// With self_separation > 0: Tail2Head also gives up before it asks the skin about a link whose
  /// first joint already lies that close to the link before the last (every link from that joint
  /// folds): it returns false as it would have once that link was placed (up to rounding at an
  /// exact tie), and `folded` is set even where the skin would have refused the link first.
  /// Worth it where most chains fold (the hug rules' opening steps); elsewhere the test costs
  /// more than the queries it spares.
  bool fold_early = false;
};

/// True when link b of the chain (joints chain[b], chain[b + 1]) is at least `separation` from
/// each of the links 0 .. b - 2 before it (links next to each other share a joint): the test of
/// a finger against itself, one link at a time.
bool link_clear_of_chain(const Vec2* chain, int b, double separation);

/// Slack (rad) on the joint limits: rounding of angles recomputed from joint positions.
constexpr double kLimitSlack = 1e-12;

/// The angle (rad, counter-clockwise in (xi, eta)) from direction `from` to direction `to`.
inline double signed_angle(const Vec2& from, const Vec2& to) {
  return std::atan2(from.x() * to.y() - from.y() * to.x(), from.dot(to));
}

/// Joint `joint`'s angle (rad, positive = flexion = counter-clockwise in (xi, eta)) when link
/// `joint` points along `dir`: relative to link joint - 1 of `chain`, or to the palm normal.
double relative_angle(const Chain& chain, int joint, const Vec2& dir);

/// The limit test both propagations use: true when the angle from `base` to `dir` (rad,
/// counter-clockwise) lies within [lo, hi] (beyond kLimitSlack: false); with `clamp`, instead
/// turns `dir` (keeping its length) onto the nearer limit and returns true.
bool angle_within_limits(double lo, double hi, const Vec2& base, Vec2& dir, bool clamp);

/// Tail2Head's limit test. With `dir` the direction wanted for link `joint` (its tail
/// joint already placed in `chain`), returns false when the angle lies outside [lower, upper]
/// of that joint (beyond kLimitSlack); with `clamp`, instead turns `dir` onto the nearer limit
/// and returns true. Always true without limits.
bool joint_within_limits(const SnakeRequest& req, const Chain& chain, int joint, Vec2& dir, bool clamp);

/// Head2Tail (docs/algorithm.md, decision 6): tip to `head`, then each joint on the ray toward its old
/// position at the link's length (turned, with joint limits, so that the joint just passed is
/// within them); a link that would hit O is rotated about its distal joint by
/// the smallest angle that frees it (Sensing::rotate_until_free), at most `max_rotation`. Returns false (chain partly
/// updated) if none frees it.
bool head_to_tail(const Sensing& sensing, const SnakeRequest& req, const Vec2& head, Chain& chain);

/// Tail2Head (decision 7): tail to `root`, then each joint toward its old position, rotating
/// about the proximal joint when a link would hit O. With joint limits, a link whose ray
/// breaks a limit is turned onto it first, and a freeing rotation that ends beyond a limit
/// fails. Returns false if no free position within the limits exists, or (req.self_separation
/// > 0) at the first link that comes that close to its own chain. `turned` (N entries, or
/// nullptr; all set when it returns true): 1 where the link was turned free by clinging, so that
/// it rests on O (its gap at most the tolerance: Sensing::rotate_until_free), else 0.
/// `folded` (or nullptr): set to whether it gave up because the chain folds onto itself.
bool tail_to_head(const Sensing& sensing, const SnakeRequest& req, const Vec2& root, Chain& chain,
                  char* turned = nullptr, bool* folded = nullptr);

}  // namespace hugger
