// Planner::plan(timeout) and Planner::advance(): the deadline, refusals, and equivalence with plan().
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hugger/planner/planner.hpp"
#include "hugger/world/simulated_world.hpp"
#include "scenes.hpp"

using namespace hugger;

namespace {

std::shared_ptr<SimulatedWorld> sphere_world(double R) { return test::sphere_world(R, 3); }

using test::facing_down;

}  // namespace

TEST(PlannerTimeout, RefusesNonPositiveOrNaN) {
  Planner p(HandModel::uniform(3, 3, 0.02, 0.003, 0.025, 0.01), sphere_world(0.035), Vec3::Zero(), facing_down(0.15));
  EXPECT_THROW(p.plan(0.0), std::invalid_argument);
  EXPECT_THROW(p.plan(-1.0), std::invalid_argument);
  EXPECT_THROW(p.plan(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_EQ(p.status(), Status::kRunning);
}

TEST(PlannerTimeout, StopsEarlyWithAPrefixOfTheFullPlan) {
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  PlannerParams slow;  // thousands of iterations: far more than a millisecond of work
  slow.step = 5e-5;
  slow.contact_tolerance = 1e-5;
  slow.max_iterations = 100000;
  Planner full(hand, sphere_world(0.04), Vec3::Zero(), facing_down(0.2), slow);
  ASSERT_EQ(full.plan(), Status::kDone);
  Planner part(hand, sphere_world(0.04), Vec3::Zero(), facing_down(0.2), slow);
  EXPECT_EQ(part.plan(1e-3), Status::kTimeout);
  EXPECT_EQ(to_string(part.status()), "timeout");
  const auto& h = part.history();
  ASSERT_GE(h.size(), 1u);
  ASSERT_LT(h.size(), full.history().size());
  for (std::size_t k = 0; k < h.size(); ++k) {
    EXPECT_TRUE(h[k].palm.matrix() == full.history()[k].palm.matrix());
    for (std::size_t j = 0; j < h[k].joints.size(); ++j) EXPECT_TRUE(h[k].joints[j] == full.history()[k].joints[j]);
  }
  // ended for good
  EXPECT_EQ(part.plan(), Status::kTimeout);
  EXPECT_FALSE(part.advance());
  EXPECT_FALSE(part.step().has_value());
  EXPECT_EQ(part.history().size(), h.size());
}

TEST(PlannerTimeout, InfiniteTimeoutAndAdvanceMatchPlan) {
  const HandModel hand = HandModel::uniform(3, 4, 0.02, 0.002, 0.025, 0.01);
  Planner a(hand, sphere_world(0.035), Vec3::Zero(), facing_down(0.15));
  Planner b(hand, sphere_world(0.035), Vec3::Zero(), facing_down(0.15));
  Planner c(hand, sphere_world(0.035), Vec3::Zero(), facing_down(0.15));
  EXPECT_EQ(a.plan(), Status::kDone);
  EXPECT_EQ(b.plan(std::numeric_limits<double>::infinity()), Status::kDone);
  long n = 0;
  while (c.advance()) ++n;
  EXPECT_EQ(n, c.stats().phase2_iterations);
  EXPECT_EQ(c.status(), Status::kDone);
  ASSERT_EQ(a.history().size(), b.history().size());
  ASSERT_EQ(a.history().size(), c.history().size());
  for (std::size_t k = 0; k < a.history().size(); ++k)
    for (std::size_t j = 0; j < a.history()[k].joints.size(); ++j) {
      EXPECT_TRUE(a.history()[k].joints[j] == b.history()[k].joints[j]);
      EXPECT_TRUE(a.history()[k].joints[j] == c.history()[k].joints[j]);
    }
}
