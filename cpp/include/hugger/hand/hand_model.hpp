/// \file hand_model.hpp
/// The hand (docs/model.md): a round palm and M planar fingers of N revolute links.
#pragma once

#include <algorithm>
#include <vector>

#include "hugger/types.hpp"

namespace hugger {

/// Largest number of fingers M and of links per finger N. The planner checks every pair of
/// fingers each iteration (O(M^2 N^2)), so a hand with more would be unusably slow. The one
/// owner of the limits: Python reads them as hugger._core.MAX_FINGERS and MAX_LINKS.
constexpr int kMaxFingers = 64;
constexpr int kMaxLinks = 256;

/// A finger plane: origin, the radial unit vector u (xi axis) and the palm normal p (eta axis).
/// In-plane coordinates (xi, eta) map to origin + xi * u + eta * p.
struct FingerPlane {
  Vec3 origin = Vec3::Zero();
  Vec3 u = Vec3::UnitX();
  Vec3 p = Vec3::UnitZ();
  Vec3 to_world(const Vec2& x) const { return origin + x.x() * u + x.y() * p; }
  Vec2 to_plane(const Vec3& x) const { return Vec2((x - origin).dot(u), (x - origin).dot(p)); }
  Vec3 normal() const { return p.cross(u); }
};

/// Where two finger planes a and b meet, as plane a sees it: a point x of plane a (its plane
/// coordinates) lies at signed distance s = w.x - offset from that line, within the plane. A
/// point of plane a at distance s_a and one of plane b at s_b (b's PlanePair toward a) are at
/// least sqrt(sin2) max(|s_a|, |s_b|) apart, sin2 being the squared sine of the planes' angle;
/// sin2 = 0 (no bound) for planes within 1e-3 rad of parallel.
struct PlanePair {
  Vec2 w = Vec2::Zero();
  double offset = 0.0;
  double sin2 = 0.0;
};
PlanePair plane_pair(const FingerPlane& a, const FingerPlane& b);
/// How far the segments between `count` points of a plane keep from the line of `pair`: the
/// distance of 0 from the range of the points' signed distances. (Inline: the planner asks it
/// for every pair of fingers it tests.)
inline double apart_from_line(const Vec2* points, int count, const PlanePair& pair) {
  double lo = kInf, hi = -kInf;
  for (int i = 0; i < count; ++i) {
    const double d = pair.w.dot(points[i]) - pair.offset;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  return lo > 0.0 ? lo : (hi < 0.0 ? -hi : 0.0);
}
/// True when the segments between the `na` points `pa` of plane a and the `nb` points `pb` of
/// plane b are sure to be more than `distance` apart: by plane_pair's bound, with a margin of
/// 1e-9 of the distance plus `slack` (the caller's bound on the rounding of the test it spares).
/// ab = plane_pair(a, b), ba = plane_pair(b, a). False where the bound does not decide.
inline bool planes_keep_apart(const PlanePair& ab, const Vec2* pa, int na, const PlanePair& ba, const Vec2* pb,
                              int nb, double distance, double slack) {
  if (!(ab.sin2 > 0.0)) return false;
  const double need = distance * (1.0 + 1e-9) + slack;
  const double need2 = need * need;
  const double da = apart_from_line(pa, na, ab);
  if (ab.sin2 * da * da >= need2) return true;
  const double db = apart_from_line(pb, nb, ba);
  return ab.sin2 * db * db >= need2;
}

/// A general finger layout (real hands). Every matrix has one row per finger; all in the palm
/// frame P. Empty matrices select the defaults: the rim layout, rest all 0, no limits.
struct HandLayout {
  MatrixX roots;       ///< M x 3 finger roots R_m on the palm's front face (z = 0, within palm_radius)
  MatrixX directions;  ///< M x 3 in-plane outward directions u_m (z = 0; normalised here)
  MatrixX rest;        ///< M x N rest (FROZEN) joint angles (rad); 0 = straight along the palm normal
  MatrixX lower;       ///< M x N lower joint limits (rad); -inf = unlimited
  MatrixX upper;       ///< M x N upper joint limits (rad); +inf = unlimited
};

/// Immutable description of the hand. Sizes in metres.
class HandModel {
 public:
  /// Throws std::invalid_argument for counts outside 1..kMaxFingers and 1..kMaxLinks,
  /// non-positive sizes, negative radius, or a `link_lengths` matrix that is not fingers x links.
  HandModel(int fingers, int links, const MatrixX& link_lengths, double link_radius, double palm_radius,
            double palm_thickness);
  /// A general layout (roots, directions, rest angles, joint limits). Throws
  /// std::invalid_argument, saying why, for what the planner cannot handle: a root off the
  /// palm's front face, a direction not in the palm plane, a limit pair with lower > upper, rest
  /// angles outside their limits or behind the palm's front plane, fingers that intersect
  /// (each other, or themselves) at rest.
  HandModel(int fingers, int links, const MatrixX& link_lengths, double link_radius, double palm_radius,
            double palm_thickness, const HandLayout& layout);
  /// All links of equal length.
  static HandModel uniform(int fingers, int links, double link_length, double link_radius, double palm_radius,
                           double palm_thickness);

  int fingers() const { return fingers_; }
  int links() const { return links_; }
  /// Index of joint n of finger m in a configuration's joints (finger by finger, root first).
  int joint_index(int m, int n) const { return m * (links_ + 1) + n; }
  double link_length(int m, int n) const { return lengths_(m, n); }
  const MatrixX& link_lengths() const { return lengths_; }
  double finger_length(int m) const { return lengths_.row(m).sum(); }
  double link_radius() const { return link_radius_; }
  double palm_radius() const { return palm_radius_; }
  double palm_thickness() const { return palm_thickness_; }
  /// phi_m = 2 pi m / M, the angle of finger m's root about the palm normal.
  double finger_angle(int m) const { return finger_angles_[m]; }
  const std::vector<double>& finger_angles() const { return finger_angles_; }
  /// Largest distance from P_o of any joint of the hand at rest, or of the palm's rim.
  double extended_radius() const;

  /// True when the hand was given a general layout (roots, directions, rest or limits).
  bool general() const { return general_; }
  /// Root R_m in the palm frame (z = 0).
  Vec3 root_palm(int m) const;
  /// In-plane outward direction u_m in the palm frame (unit, z = 0).
  Vec3 direction_palm(int m) const;
  /// Root R_m in its finger plane's (xi, eta) coordinates (eta = 0: the palm's front face).
  Vec2 root2d(int m) const;
  /// Rest (FROZEN) joint angles, M x N (rad).
  const MatrixX& rest() const { return rest_; }
  /// Finger m at rest in its plane (N + 1 joints, tail first, the tail at root2d(m)).
  std::vector<Vec2> rest_chain(int m) const;
  /// Joint limits, M x N each (rad; +-inf: unlimited). has_limits(): any finite limit.
  const MatrixX& lower() const { return lower_; }
  const MatrixX& upper() const { return upper_; }
  bool has_limits() const { return has_limits_; }

  /// Root R_m in the world for palm pose T_WP.
  Vec3 root(const Pose& palm, int m) const;
  /// Finger m's plane for palm pose T_WP. Its origin is the point of the plane nearest P_o
  /// (P_o itself for the rim layout), so that root2d(m) = (R_m . u_m, 0).
  FingerPlane plane(const Pose& palm, int m) const;

  /// Forward kinematics: joints (M*(N+1) points, finger-major) from angles (M x N).
  std::vector<Vec3> forward(const Pose& palm, const MatrixX& angles) const;
  /// In-plane forward kinematics of one finger from its root (xi, eta) and its angles.
  std::vector<Vec2> forward_planar(int m, const Vec2& root, const double* angles) const;
  /// The same into `out` (resized to N+1; no allocation once it has the room). `root` must not
  /// be an element of `*out`.
  void forward_planar(int m, const Vec2& root, const double* angles, std::vector<Vec2>* out) const;
  /// Joint angles of one finger from its in-plane joint positions (N+1 points).
  static void planar_angles(const std::vector<Vec2>& joints, double* angles);
  /// Joint angles (M x N) from world joint positions (finger-major, M*(N+1)).
  MatrixX angles_from_joints(const Pose& palm, const std::vector<Vec3>& joints) const;

 private:
  /// The sizes' checks, and with `rim` the rim layout's root spacing.
  HandModel(int fingers, int links, const MatrixX& link_lengths, double link_radius, double palm_radius,
            double palm_thickness, bool rim);

  int fingers_, links_;
  MatrixX lengths_;
  double link_radius_, palm_radius_, palm_thickness_;
  std::vector<double> finger_angles_;
  bool general_ = false, has_limits_ = false;
  MatrixX roots_, dirs_;      ///< M x 3 each, palm frame (general layouts only)
  MatrixX rest_, lower_, upper_;
};

}  // namespace hugger
