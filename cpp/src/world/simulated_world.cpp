#include "hugger/world/simulated_world.hpp"

#include <fcl/geometry/shape/cylinder.h>
#include <fcl/narrowphase/detail/gjk_solver_libccd.h>

#include <cmath>

#include "hugger/check.hpp"
#include "hugger/geometry/next.hpp"

namespace hugger {

SimulatedWorld::SimulatedWorld(std::shared_ptr<const Object> object) : object_(std::move(object)) {
  HUGGER_CHECK_ARGUMENT(object_, "SimulatedWorld needs an object");
}

Touch SimulatedWorld::capsule(const Vec3& a, const Vec3& b, double radius, double cap) const {
  const SignedNearest sn = object_->nearest(a, b, cap + radius);
  Touch t;
  t.gap = sn.signed_distance - radius;
  t.on_hand = sn.on_query;
  t.on_object = sn.on_object;
  if (sn.triangle >= 0) {
    const Vec3 d = sn.on_query - sn.on_object;
    const double len = d.norm();
    if (len > 1e-12 && !sn.crosses) {
      t.normal = (sn.signed_distance < 0.0 ? -d : d) / len;
    } else {
      t.normal = object_->face_normal(sn.triangle);
    }
  }
  return t;
}

bool SimulatedWorld::link_gap_below(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                    double below, bool /*a_outside*/) const {
  const Vec3 wa = plane.to_world(a), wb = plane.to_world(b);
  // A triangle closer than radius + below (less a relative margin, far above rounding): the
  // nearest one is at least that close, and capsule() reports a gap below `below`.
  if (below > 0.0 && object_->bvh().any_within(wa, wb, (radius + below) * (1.0 - 1e-9))) return true;
  return capsule(wa, wb, radius, below).gap < below;
}

double SimulatedWorld::palm(const Pose& palm, double radius, double thickness, double cap) const {
  const Vec3 centre = palm * Vec3(0.0, 0.0, -0.5 * thickness);
  const Vec3 n = palm.linear().col(2);
  const double half = 0.5 * thickness;
  const double bound = std::hypot(radius, half);
  // Which side of O the palm is on, and a first lower bound, from its centre. Nothing within
  // bound + cap of the centre: the palm is clear by more than cap (or the centre is deep inside).
  const double reach = std::isfinite(cap) ? bound + std::max(cap, 0.0) : kInf;
  const SignedNearest sn = object_->nearest(centre, centre, reach);
  if (sn.signed_distance <= 0.0) return sn.signed_distance - bound;  // centre inside O
  const double lower = sn.signed_distance - bound;
  // Nothing within cap: the gap exceeds cap, and the smallest double above cap is a lower bound.
  const double above_cap = next_up(cap);
  if (lower > cap) return std::isfinite(lower) ? lower : above_cap;
  // The palm's world box (a disk of `radius` about n, thickened by `thickness` along n) and its
  // slab along n: together a lower bound of the distance to any box or triangle.
  const Vec3 extent = (radius * (Vec3::Ones() - n.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt() + half * n.cwiseAbs());
  Aabb pbox;
  pbox.lo = centre - extent;
  pbox.hi = centre + extent;
  const double cn = centre.dot(n), nabs[3] = {std::abs(n.x()), std::abs(n.y()), std::abs(n.z())};
  auto box_bound = [&](const Aabb& b) {
    const double d_box = std::sqrt(pbox.squared_distance(b));
    const Vec3 bc = b.centre(), bh = 0.5 * b.extent();
    const double spread = nabs[0] * bh.x() + nabs[1] * bh.y() + nabs[2] * bh.z();
    const double d_slab = std::abs(bc.dot(n) - cn) - spread - half;
    return std::max(d_box, d_slab);
  };
  // The exact distance per triangle from FCL's GJK (libccd), as fcl::distance would compute it
  // for this cylinder against a BVHModel of O, but culled by our own BVH: no FCL model of O.
  const fcl::Cylinderd cylinder(radius, thickness);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = palm.linear();
  tf.translation() = centre;
  fcl::detail::GJKSolver_libccd<double> solver;
  double best = kInf;
  bool touching = false;
  double limit = std::isfinite(cap) ? std::max(cap, 0.0) : kInf;
  object_->bvh().traverse(
      box_bound,
      [&](const std::array<Vec3, 3>& t, int) {
        Aabb tb;
        tb.grow(t[0]);
        tb.grow(t[1]);
        tb.grow(t[2]);
        if (box_bound(tb) > limit) return;
        double d = kInf;
        if (!solver.shapeTriangleDistance(cylinder, tf, t[0], t[1], t[2], &d) || !(d > 0.0)) {
          touching = true;
          limit = -1.0;  // stop
          return;
        }
        if (d < best) {
          best = d;
          limit = std::min(limit, best);
        }
      },
      limit);
  if (touching) return -std::numeric_limits<double>::min();  // touching or overlapping
  if (best <= cap || !std::isfinite(cap)) return best;
  return std::max(above_cap, lower);  // nothing within cap: a value > cap and <= the gap
}

}  // namespace hugger
