/// \file sensing.hpp
/// The whole-sensitive skin: every fact the planner learns about the object comes through
/// this interface (docs/skins.md). The simulated world implements its two primitive
/// queries; the higher-level queries (tip contact, boundary following, rotating a link until
/// it touches or frees) are built on them here and may be overridden by a faster or a real
/// implementation.
#pragma once

#include <cmath>
#include <vector>

#include "hugger/hand/hand_model.hpp"
#include "hugger/types.hpp"

namespace hugger {

/// What a piece of skin senses: the gap to the object and where. Signed: gap < 0 when the part
/// penetrates O or lies inside it (FCL's convention). Exact when gap <= the query's `cap`;
/// otherwise any value above cap may be returned (the planner decides "within cap" by gap <= cap).
struct Touch {
  double gap = kInf;               ///< metres between the part's surface and O
  Vec3 on_hand = Vec3::Zero();     ///< nearest point of the part's axis (capsules) or centre
  Vec3 on_object = Vec3::Zero();   ///< nearest point of O
  Vec3 normal = Vec3::UnitZ();     ///< gradient of the signed distance at on_hand (unit, outward)
};

/// A link end at most this far behind the palm's front plane (metres) still counts as in front of
/// it (rounding of positions computed in the plane).
constexpr double kFrontSlack = 1e-12;

/// v turned counter-clockwise by the angle of cosine c and sine s, in a finger plane.
inline Vec2 rotate_planar(const Vec2& v, double c, double s) { return Vec2(c * v.x() - s * v.y(), s * v.x() + c * v.y()); }

/// v turned counter-clockwise by `angle` (radians), in a finger plane.
inline Vec2 rotate_planar(const Vec2& v, double angle) { return rotate_planar(v, std::cos(angle), std::sin(angle)); }

/// The generic boundary following (Sensing::follow_boundary) marches at most kFollowSteps steps
/// of step / kFollowDivisions along the level curve.
constexpr int kFollowSteps = 48;
constexpr double kFollowDivisions = 3.0;

/// Boundary following in a finger plane (docs/algorithm.md, decision 5).
struct FollowRequest {
  FingerPlane plane;
  Vec2 tip = Vec2::Zero();       ///< current fingertip (xi, eta)
  double radius = 0.0;           ///< link radius
  double step = 1e-3;            ///< chord length from the tip to the head H
  double level = 5e-5;           ///< gap the head keeps from O while sliding (> 0)
  Vec2 root = Vec2::Zero();      ///< finger root; H stays within `reach` of it
  double reach = kInf;
  double front = -kInf;          ///< eta of the palm's front plane: H stays in front of it
};
struct FollowResult {
  Vec2 head = Vec2::Zero();  ///< H
  double gap = kInf;         ///< gap of the tip sphere at H
  int steps = 0;             ///< marching steps used
};

/// Rotating a link [pivot, end] about pivot.
struct RotateRequest {
  FingerPlane plane;
  Vec2 pivot = Vec2::Zero();
  Vec2 end = Vec2::Zero();
  double radius = 0.0;
  double front = -kInf;          ///< neither end may pass behind this eta
  double max_angle = kPi;        ///< search range (radians)
  double tolerance = 1e-5;       ///< rotate_until_free: the result's gap (or end motion) resolution, metres
  double touch_gap = 1e-4;       ///< rotate_until_touch: stop on contact (a gap at most this)
  double level = 5e-5;           ///< rotate_until_touch: never come closer than this
  double sample_angle = 0.05;    ///< rotate_until_free: coarse search increment (radians)
  bool pivot_outside = false;    ///< rotate_until_free: the caller knows the pivot's ball of `radius`
                                 ///< is clear of O (the end of a link found free), as link_free's a_outside
};
struct RotateResult {
  bool ok = false;         ///< a free position was found (until_free) / the link touched (until_touch)
  Vec2 end = Vec2::Zero(); ///< the link's new free end
  double angle = 0.0;      ///< signed rotation, counter-clockwise positive (= flexion)
  double gap = kInf;       ///< gap of the link at its new position; rotate_until_free: the generic
                           ///< search's is exact up to 4 tolerance (beyond that any larger value);
                           ///< the section skin does not measure it and reports 0, a lower bound;
                           ///< rotate_until_touch: exact up to 2 (level + the length the end may
                           ///< still sweep) + touch_gap (beyond that any larger value)
};

class Sensing {
 public:
  virtual ~Sensing() = default;

  /// Gap between the capsule of axis [a, b] and `radius` and O (a == b: a sphere).
  virtual Touch capsule(const Vec3& a, const Vec3& b, double radius, double cap = kInf) const = 0;
  /// Gap between the palm (a disk of `radius` and `thickness` behind the front face of pose
  /// T_WP) and O.
  virtual double palm(const Pose& palm, double radius, double thickness, double cap = kInf) const = 0;

  /// Gap of a link given in finger-plane coordinates. The default asks `capsule` in the world; a
  /// skin that knows the plane (the section skin) answers in the plane itself, and may then
  /// report the gap measured within the plane (never smaller than the gap in 3D).
  virtual Touch link(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double cap = kInf) const {
    return capsule(plane.to_world(a), plane.to_world(b), radius, cap);
  }
  /// True when the link's gap (as `link` reports it) is below `below` (> 0). Override with a test
  /// that can stop at the first piece of O closer than that; the default asks `link`.
  /// `a_outside`: as link_free's (a is the end of a link found free), which spares an override
  /// the inside test where nothing is that close; the default has no use for it.
  virtual bool link_gap_below(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double below,
                              bool a_outside = false) const {
    (void)a_outside;
    return link(plane, a, b, radius, below).gap < below;
  }
  /// The gap that decides contact (the sensing distance `delta` > 0): at most delta exactly when
  /// the link lies within delta of O in space (whatever the cap: one below delta is taken as
  /// delta), and where it exceeds delta it shrinks no faster than the link moves within its plane
  /// (a FROZEN finger's bound lasts while it moves less than the bound's excess over delta).
  /// Exact when at most `cap`; otherwise any value above cap. It is link()'s gap where that is at
  /// most delta, else the smaller of it and gap_in_space() (nothing more for a skin whose link()
  /// measures in space).
  double contact_gap(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double delta,
                     double cap = kInf) const;
  /// A lower bound of contact_gap() that lasts: the gap itself where it is at most `need`
  /// (>= delta), else a value above `need` and at most the gap, and at least `far` (> need) where
  /// the gap is. The planner keeps it for a FROZEN finger's link while the link moves less than
  /// its excess over `need`. The default asks contact_gap capped at max(nextafter(need), far) (the
  /// planner's bounds before this query existed); a skin whose exact gap beyond `need` is dear
  /// may answer with threshold tests (the section skin does).
  virtual double contact_gap_bound(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                   double delta, double need, double far) const;
  /// True when the capsule does not penetrate O (gap >= 0). `a_outside`: the caller knows that
  /// the point a lies outside O (the end of a link just found free, say), so a capsule that
  /// comes no closer than `radius` to O's surface is clear without an inside test. Override
  /// with a test that can stop early; the default asks `capsule`.
  virtual bool capsule_clear(const Vec3& a, const Vec3& b, double radius, bool a_outside) const {
    (void)a_outside;
    return capsule(a, b, radius, 0.0).gap >= 0.0;
  }
  /// True when the link is collision-free (gap >= 0) and in front of the palm's front plane.
  /// Virtual so that a skin that knows the plane can answer it there (the default converts to the
  /// world and asks capsule_clear).
  virtual bool link_free(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double front,
                         bool a_outside = false) const;

  /// True when the link penetrates O by at most `allow` (> 0): its gap, as `link` measures it, is
  /// at least -allow, and where the axis crosses O (the depth is not measured), every point of
  /// the axis is within `allow` of leaving O. The default samples points along a crossing axis
  /// (16 pieces, refined where the depth between two could exceed twice the allowance); a skin
  /// that knows the plane answers exactly.
  virtual bool link_depth_within(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                 double allow) const;

  /// A hint, once when Phase 1 has ended (in the Planner's constructor, before Phase 2): link
  /// queries in these finger planes, for links of `radius`, follow. A skin that builds a
  /// structure per plane (the section skin) may build them now, side by side; the default does
  /// nothing. Answers never depend on it.
  virtual void prepare(const std::vector<FingerPlane>& planes, double radius) const {
    (void)planes;
    (void)radius;
  }

  /// Slide the fingertip along O's boundary in its plane, counter-clockwise (interior on the
  /// left), to the first point whose chord from the tip is `step`.
  virtual FollowResult follow_boundary(const FollowRequest& req) const;
  /// Flex the link about its pivot (counter-clockwise) until it touches O, up to max_angle: the
  /// gap link() measures, or gap_in_space(), is at most touch_gap.
  virtual RotateResult rotate_until_touch(const RotateRequest& req) const;
  /// Rotate a colliding link about its pivot by the smallest angle (at most max_angle) that frees
  /// it, leaving it resting on O (gap at most `tolerance`, or the end within `tolerance` of the
  /// boundary angle). Newton steps on the sensed gap turn it the way that opens the gap; where
  /// the gap is not measured (the axis crosses O, or the front plane blocks) both ways are
  /// searched in steps of `sample_angle` and the nearer free side is taken; false position then
  /// refines. Smallest up to `sample_angle`: a free window narrower than it may be missed, and a
  /// Newton result beyond one sample angle is kept only if no sample nearer zero is free.
  virtual RotateResult rotate_until_free(const RotateRequest& req) const;

 protected:
  /// For a skin whose link() gaps are measured within the finger plane (larger than in space
  /// where O's surface is oblique to it): the link's gap in space, asked only where link()'s gap
  /// is positive (the axis lies outside O). Exact when at most `cap`; otherwise any value above
  /// cap. The default, for a skin whose link() measures in space already: +inf, nothing to add.
  virtual double gap_in_space(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                              double cap) const {
    (void)plane;
    (void)a;
    (void)b;
    (void)radius;
    (void)cap;
    return kInf;
  }
};

// The checks of what crosses the interface from outside the engine (a Python caller's query, a
// Python skin's answer); the planner's own queries are valid by construction and go unchecked.
// Each throws std::invalid_argument.

/// A capsule query: a and b finite, radius finite and >= 0, cap a number (m) or +inf.
void check_capsule_query(const Vec3& a, const Vec3& b, double radius, double cap);
/// A palm query: radius and thickness finite and >= 0, cap a number (m) or +inf.
void check_palm_query(double radius, double thickness, double cap);
/// A gap that is a number (m) or +-inf, not NaN; `source` says where it came from ("Sensing.palm
/// returned"). Returns the gap.
double check_gap(double gap, const char* source);
/// A skin's answer to a capsule query: a gap (check_gap), finite points and a finite non-zero
/// normal. Returns it with the normal normalised.
Touch check_touch(Touch touch, const char* source);

}  // namespace hugger
