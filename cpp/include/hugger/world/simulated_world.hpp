/// \file simulated_world.hpp
/// The simulated world: answers the whole-sensitive skin's queries from a known mesh.
#pragma once

#include <memory>

#include "hugger/sensing/sensing.hpp"
#include "hugger/world/object.hpp"

namespace hugger {

class SimulatedWorld final : public Sensing {
 public:
  explicit SimulatedWorld(std::shared_ptr<const Object> object);

  Touch capsule(const Vec3& a, const Vec3& b, double radius, double cap = kInf) const override;
  double palm(const Pose& palm, double radius, double thickness, double cap = kInf) const override;
  /// Answered by a clearance test that stops at the first triangle within the radius.
  bool capsule_clear(const Vec3& a, const Vec3& b, double radius, bool a_outside) const override {
    return object_->capsule_clear(a, b, radius, a_outside);
  }
  /// As link(...).gap < below, stopping at the first triangle clearly closer than that.
  bool link_gap_below(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double below,
                      bool a_outside = false) const override;
  /// The generic answer, after a clearance test that settles the links that are clear (most of
  /// those asked), cheaper than their gap.
  bool link_depth_within(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                         double allow) const override {
    return link_free(plane, a, b, radius, -kInf) || Sensing::link_depth_within(plane, a, b, radius, allow);
  }

  const Object& object() const { return *object_; }

 private:
  std::shared_ptr<const Object> object_;
};

}  // namespace hugger
