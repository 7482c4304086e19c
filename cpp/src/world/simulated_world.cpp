#include "hugger/world/simulated_world.hpp"

#include <fcl/geometry/shape/cylinder.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/distance.h>

#include <cmath>
#include <stdexcept>

namespace hugger {

SimulatedWorld::SimulatedWorld(std::shared_ptr<const Object> object) : object_(std::move(object)) {
  if (!object_) throw std::invalid_argument("SimulatedWorld needs an object");
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
      const auto& f = object_->faces();
      const auto& v = object_->vertices();
      const Vec3 p0 = v.row(f(sn.triangle, 0)), p1 = v.row(f(sn.triangle, 1)), p2 = v.row(f(sn.triangle, 2));
      t.normal = (p1 - p0).cross(p2 - p0).normalized();
    }
  }
  return t;
}

double SimulatedWorld::palm(const Pose& palm, double radius, double thickness, double cap) const {
  const Vec3 centre = palm * Vec3(0.0, 0.0, -0.5 * thickness);
  const double bound = std::hypot(radius, 0.5 * thickness);
  const SignedNearest sn = object_->nearest(centre, centre, kInf);
  if (sn.signed_distance <= 0.0) return sn.signed_distance - bound;  // centre inside O
  const double lower = sn.signed_distance - bound;
  if (lower > cap) return lower;
  auto cyl = std::make_shared<fcl::Cylinderd>(radius, thickness);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = palm.linear();
  tf.translation() = centre;
  fcl::CollisionObjectd palm_object(cyl, tf);
  fcl::DistanceRequestd request;
  fcl::DistanceResultd result;
  const double d = fcl::distance(&palm_object, &object_->fcl_object(), request, result);
  if (!(d > 0.0)) return -std::numeric_limits<double>::min();  // touching or overlapping
  return d;
}

}  // namespace hugger
