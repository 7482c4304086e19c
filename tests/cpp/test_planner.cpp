// The planner end to end on a sphere, and its refusals.
#include <gtest/gtest.h>

#include "hugger/planner/planner.hpp"
#include "hugger/world/simulated_world.hpp"
#include "scenes.hpp"

using namespace hugger;

namespace {

std::shared_ptr<SimulatedWorld> sphere_world(double R) { return test::sphere_world(R, 4); }

using test::facing_down;

}  // namespace

TEST(Planner, HugsASphere) {
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  Pose start = facing_down(0.2);
  start.linear() = Eigen::AngleAxisd(0.7, Vec3::UnitY()).toRotationMatrix() * start.linear();  // turned away
  Planner planner(hand, sphere_world(0.04), Vec3::Zero(), start);
  EXPECT_EQ(planner.plan(), Status::kDone);
  const auto& h = planner.history();
  EXPECT_GT(planner.stats().phase1_configurations, 0);
  EXPECT_GE(planner.stats().palm_contact_iteration, 0);
  // TipState only FROZEN -> CONTACT -> DONE, the palm never moves backward in Phase 2
  for (std::size_t k = 1; k < h.size(); ++k) {
    for (int m = 0; m < 5; ++m) EXPECT_GE(h[k].tip_state[m], h[k - 1].tip_state[m]);
    if (h[k].phase == 2 && h[k - 1].phase == 2) {
      const Vec3 dp = h[k].palm.translation() - h[k - 1].palm.translation();
      EXPECT_GE(dp.dot(h[k].palm.linear().col(2)), -1e-15);
      EXPECT_LE(dp.norm(), planner.params().step * (1 + 1e-9));
      EXPECT_TRUE(h[k].palm.linear() == h[k - 1].palm.linear());
    }
  }
  for (int m = 0; m < 5; ++m) EXPECT_EQ(h.back().tip_state[m], TipState::kDone);
}

TEST(Planner, StepAndPlanAgree) {
  const HandModel hand = HandModel::uniform(3, 4, 0.02, 0.0, 0.025, 0.01);
  Planner a(hand, sphere_world(0.035), Vec3::Zero(), facing_down(0.15));
  Planner b(hand, sphere_world(0.035), Vec3::Zero(), facing_down(0.15));
  a.plan();
  std::size_t count = 0;
  while (auto c = b.step()) {
    ASSERT_LT(count, a.history().size());
    EXPECT_TRUE(c->palm.matrix() == a.history()[count].palm.matrix());
    for (std::size_t j = 0; j < c->joints.size(); ++j) EXPECT_TRUE(c->joints[j] == a.history()[count].joints[j]);
    ++count;
  }
  EXPECT_EQ(count, a.history().size());
  EXPECT_FALSE(b.step().has_value());
}

TEST(Planner, RefusesBadStarts) {
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  auto world = sphere_world(0.04);
  EXPECT_THROW(Planner(hand, world, Vec3::Zero(), facing_down(0.03)), std::invalid_argument);  // inside
  EXPECT_THROW(Planner(hand, world, Vec3::Zero(), facing_down(0.1)), std::invalid_argument);   // fingers in O
  Pose sideways = Pose::Identity();  // palm beside the sphere: turning it would sweep the fingers through O
  sideways.translation() = Vec3(0.075, 0, 0);
  EXPECT_THROW(Planner(hand, world, Vec3::Zero(), sideways), std::invalid_argument);
  Pose skew = facing_down(0.2);
  skew.linear()(0, 1) += 0.01;  // not rigid
  EXPECT_THROW(Planner(hand, world, Vec3::Zero(), skew), std::invalid_argument);
  PlannerParams bad;
  bad.step = -1;
  EXPECT_THROW(Planner(hand, world, Vec3::Zero(), facing_down(0.2), bad), std::invalid_argument);
  bad.step = 0.05;  // longer than a link
  EXPECT_THROW(Planner(hand, world, Vec3::Zero(), facing_down(0.2), bad), std::invalid_argument);
}
