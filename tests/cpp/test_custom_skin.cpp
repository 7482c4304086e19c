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

/// The ball, answering every gap above the query's cap with `beyond(cap)`: the least a skin may
/// say there (the next double above the cap), or +inf ("nothing within cap").
class CappedBallSkin : public BallSkin {
 public:
  CappedBallSkin(Vec3 c, double R, bool infinite) : BallSkin(std::move(c), R), infinite_(infinite) {}
  Touch capsule(const Vec3& a, const Vec3& b, double radius, double cap) const override {
    Touch t = BallSkin::capsule(a, b, radius, cap);
    if (t.gap > cap) t.gap = beyond(cap);
    return t;
  }
  double palm(const Pose& pose, double radius, double thickness, double cap) const override {
    const double g = BallSkin::palm(pose, radius, thickness, cap);
    return g > cap ? beyond(cap) : g;
  }

 private:
  double beyond(double cap) const { return infinite_ ? kInf : std::nextafter(cap, kInf); }
  bool infinite_;
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

// The planner decides nothing from a gap beyond the cap it asked with (the start's check, contact,
// the palm step, the lasting bounds of the palm's and the FROZEN fingers' gaps): a skin that
// answers those with the least value it may (the next double above the cap: the cap itself
// would read as a gap within it), or with +inf, gives the same plan, bit for bit, from starts
// above and tilted towards the ball, the palm landing on it.
TEST(CustomSkin, AnswersBeyondTheCapLeaveThePlanAsItIs) {
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  Pose tilted = test::facing_down(0.2);
  tilted.linear() = tilted.linear() * Eigen::AngleAxisd(0.3, Vec3::UnitX()).toRotationMatrix();
  tilted.translation() = Vec3(0.01, -0.02, 0.2);
  int compared = 0;
  for (const Pose& start : {test::facing_down(0.2), test::facing_down(0.3), tilted}) {
    Planner exact(hand, std::make_shared<BallSkin>(Vec3::Zero(), 0.04), Vec3::Zero(), start);
    const Status done = exact.plan();
    EXPECT_GT(exact.history().size(), 20u);
    EXPECT_GE(exact.stats().palm_contact_iteration, 0);  // the palm lands: its gap was asked to the end
    for (bool infinite : {false, true}) {
      Planner capped(hand, std::make_shared<CappedBallSkin>(Vec3::Zero(), 0.04, infinite), Vec3::Zero(), start);
      EXPECT_EQ(capped.plan(), done);
      ASSERT_EQ(exact.history().size(), capped.history().size()) << (infinite ? "+inf" : "next above the cap");
      for (std::size_t i = 0; i < exact.history().size(); ++i) {
        const Configuration &x = exact.history()[i], &y = capped.history()[i];
        EXPECT_TRUE(x.palm.matrix() == y.palm.matrix()) << "configuration " << i;
        EXPECT_TRUE(x.angles == y.angles) << "configuration " << i;
        EXPECT_TRUE(x.tip_state == y.tip_state) << "configuration " << i;
      }
      ++compared;
    }
  }
  EXPECT_EQ(compared, 6);
}
