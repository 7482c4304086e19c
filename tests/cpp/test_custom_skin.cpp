// A skin written in C++ (an analytic sphere, no mesh) drives the planner like the mesh world.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "hugger/planner/planner.hpp"
#include "scenes.hpp"

using namespace hugger;

namespace {

/// A ball of radius R about c, by formulas.
class BallSkin : public Sensing {
 public:
  BallSkin(Vec3 c, double R) : c_(std::move(c)), R_(R) {}

  Touch capsule(const Vec3& a, const Vec3& b, double radius, double /*cap*/) const override {
    const Vec3 ab = b - a;
    const double L2 = ab.squaredNorm();
    const double t = L2 > 0 ? std::clamp((c_ - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
    Touch out;
    out.on_hand = a + t * ab;
    const Vec3 d = out.on_hand - c_;
    out.normal = d.norm() > 0 ? Vec3(d.normalized()) : Vec3::UnitZ();
    out.gap = d.norm() - R_ - radius;
    out.on_object = c_ + R_ * out.normal;
    return out;
  }

  double palm(const Pose& pose, double radius, double thickness, double /*cap*/) const override {
    const Vec3 q = pose.inverse() * c_;  // the centre in the palm frame
    const double dr = std::hypot(q.x(), q.y()) - radius, dz = std::max(q.z(), -thickness - q.z());
    return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0)) + std::min(std::max(dr, dz), 0.0) - R_;
  }

  mutable long calls = 0;

 protected:
  Vec3 c_;
  double R_;
};

/// Fails after a number of capsule queries, as a driver that loses its sensor would.
class FailingSkin : public BallSkin {
 public:
  FailingSkin(long after) : BallSkin(Vec3::Zero(), 0.04), after_(after) {}
  Touch capsule(const Vec3& a, const Vec3& b, double radius, double cap) const override {
    if (++calls > after_) throw std::runtime_error("sensor lost");
    return BallSkin::capsule(a, b, radius, cap);
  }

 private:
  long after_;
};

}  // namespace

TEST(CustomSkin, AnalyticSphereAgreesWithAFineMesh) {
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  const Pose start = test::facing_down(0.2);
  Planner analytic(hand, std::make_shared<BallSkin>(Vec3::Zero(), 0.04), Vec3::Zero(), start);
  Planner mesh(hand, test::sphere_world(0.04, 6), Vec3::Zero(), start);
  EXPECT_EQ(analytic.plan(), Status::kDone);
  EXPECT_EQ(mesh.plan(), Status::kDone);
  const Vec3 pa = analytic.history().back().palm.translation(), pm = mesh.history().back().palm.translation();
  EXPECT_LE((pa - pm).norm(), 1e-3);
}

TEST(CustomSkin, AnExceptionInTheSkinReachesTheCaller) {
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  Planner planner(hand, std::make_shared<FailingSkin>(2000), Vec3::Zero(), test::facing_down(0.2));
  const std::size_t before = planner.history().size();
  EXPECT_THROW(planner.plan(), std::runtime_error);
  // configurations are appended only when an iteration completes
  EXPECT_GE(planner.history().size(), before);
  for (const auto& c : planner.history()) EXPECT_EQ(static_cast<int>(c.joints.size()), 5 * 6);
}
