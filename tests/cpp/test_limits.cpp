// Joint limits and general layouts: the limit check of the snake propagation, the hand model's
// refusals, and plans that keep every angle within its limits.
#include <gtest/gtest.h>

#include <random>

#include "hugger/planner/planner.hpp"
#include "hugger/planner/snake.hpp"
#include "hugger/world/simulated_world.hpp"
#include "scenes.hpp"

using namespace hugger;

namespace {

Vec2 unit(double theta_abs) { return Vec2(-std::sin(theta_abs), std::cos(theta_abs)); }

/// The 3-finger rim hand with the given limits on every joint.
HandModel limited_hand(int M, int N, double lo, double hi, double radius = 0.003) {
  HandLayout layout;
  layout.lower = MatrixX::Constant(M, N, lo);
  layout.upper = MatrixX::Constant(M, N, hi);
  return HandModel(M, N, MatrixX::Constant(M, N, 0.02), radius, 0.03, 0.01, layout);
}

/// A 4-link chain with limits on every joint, for the propagation tests.
struct LimitedChain {
  static constexpr int N = 4;
  double lengths[N] = {0.02, 0.015, 0.02, 0.01};
  double lower[N] = {-0.3, 0.0, -0.2, 0.1}, upper[N] = {0.6, 1.2, 0.9, 1.5};
  SnakeRequest request() const {
    SnakeRequest req;
    req.lengths = lengths;
    req.lower = lower;
    req.upper = upper;
    return req;
  }
  /// A random chain rooted at (0.03, 0), each link turned by up to 2 rad from the last.
  Chain random_chain(std::mt19937_64& rng, std::uniform_real_distribution<double>& u) const {
    Chain c(N + 1);
    c[0] = Vec2(0.03, 0.0);
    double theta = 0.0;
    for (int n = 0; n < N; ++n) c[n + 1] = c[n] + lengths[n] * unit(theta += 2.0 * u(rng));
    return c;
  }
  /// Every link keeps its exact length, and joints `first`..N-1 are within their limits.
  void expect_lengths_and_limits(const Chain& c, int first) const {
    double angles[N];
    HandModel::planar_angles(c, angles);
    for (int n = 0; n < N; ++n) EXPECT_NEAR((c[n + 1] - c[n]).norm(), lengths[n], 1e-15);
    for (int n = first; n < N; ++n) {
      EXPECT_GE(angles[n], lower[n] - 1e-12);
      EXPECT_LE(angles[n], upper[n] + 1e-12);
    }
  }
};

}  // namespace

TEST(Limits, RelativeAngleSignIsFlexion) {
  Chain c = {Vec2(0, 0), Vec2(0, 1), Vec2(0, 2)};
  EXPECT_NEAR(relative_angle(c, 0, unit(0.3)), 0.3, 1e-15);
  EXPECT_NEAR(relative_angle(c, 1, unit(-0.4)), -0.4, 1e-15);
  c[1] = unit(0.5);
  EXPECT_NEAR(relative_angle(c, 1, unit(0.5 + 0.2)), 0.2, 1e-15);
}

TEST(Limits, WithinLimitsClampsToTheNearerLimit) {
  const double lower[2] = {-0.1, 0.0}, upper[2] = {0.2, 1.0};
  SnakeRequest req;
  req.lower = lower;
  req.upper = upper;
  Chain c = {Vec2(0, 0), Vec2(0, 1), Vec2(0, 2)};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  for (int i = 0; i < 2000; ++i) {
    const int joint = i % 2;
    const double q = angle(rng);
    Vec2 dir = unit(q);
    const bool inside = q >= lower[joint] && q <= upper[joint];
    EXPECT_EQ(joint_within_limits(req, c, joint, dir, false), inside) << q;
    EXPECT_TRUE(dir == unit(q));  // untouched without clamp
    ASSERT_TRUE(joint_within_limits(req, c, joint, dir, true));
    const double got = relative_angle(c, joint, dir);
    EXPECT_NEAR(dir.norm(), 1.0, 1e-15);
    if (inside) {
      EXPECT_NEAR(got, q, 1e-15);
    } else {
      EXPECT_NEAR(got, q < lower[joint] ? lower[joint] : upper[joint], 1e-12) << q;
    }
  }
  SnakeRequest free;  // no limits: always within
  Vec2 dir = unit(2.5);
  EXPECT_TRUE(joint_within_limits(free, c, 0, dir, false));
}

TEST(Limits, TailToHeadHoldsEveryJointWithinItsLimits) {
  // With nothing to collide with, Tail2Head from random chains and roots ends within the limits,
  // with exact link lengths, and unchanged where the rays already were within them.
  const test::EmptySkin skin;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const LimitedChain lc;
  const SnakeRequest req = lc.request();
  for (int i = 0; i < 500; ++i) {
    Chain c = lc.random_chain(rng, u);
    const Vec2 root(0.03, 0.004 * (u(rng) + 1.0));
    ASSERT_TRUE(tail_to_head(skin, req, root, c));
    EXPECT_TRUE(c[0] == root);
    lc.expect_lengths_and_limits(c, 0);
  }
}

TEST(Limits, HeadToTailHoldsTheJointsItPassesWithinTheirLimits) {
  // Head2Tail decides joints N-1 .. 1 (joint 0, at the root, is Tail2Head's): with nothing to
  // collide with they end within their limits, with exact link lengths and the tip at the head.
  const test::EmptySkin skin;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const LimitedChain lc;
  const int N = LimitedChain::N;
  const SnakeRequest req = lc.request();
  for (int i = 0; i < 500; ++i) {
    Chain c = lc.random_chain(rng, u);
    const Vec2 head = c[N] + 0.003 * Vec2(u(rng), u(rng));
    ASSERT_TRUE(head_to_tail(skin, req, head, c));
    EXPECT_TRUE(c[N] == head);
    lc.expect_lengths_and_limits(c, 1);  // joint 0, at the root, is Tail2Head's
  }
}

TEST(Limits, HandModelRefusesBadLayouts) {
  const MatrixX L = MatrixX::Constant(2, 3, 0.02);
  auto make = [&](const HandLayout& l) { return HandModel(2, 3, L, 0.003, 0.03, 0.01, l); };
  HandLayout ok;
  ok.roots = MatrixX(2, 3);
  ok.roots << 0.02, 0, 0, -0.02, 0, 0;
  ok.directions = MatrixX(2, 3);
  ok.directions << 1, 0, 0, -2, 0, 0;  // normalised
  const HandModel h = make(ok);
  EXPECT_TRUE(h.general());
  EXPECT_DOUBLE_EQ(h.direction_palm(1).x(), -1.0);
  EXPECT_DOUBLE_EQ(h.root2d(1).x(), 0.02);
  HandLayout off = ok;
  off.roots(0, 0) = 0.031;
  EXPECT_THROW(make(off), std::invalid_argument);  // root off the palm
  HandLayout up = ok;
  up.roots(1, 2) = 0.001;
  EXPECT_THROW(make(up), std::invalid_argument);  // root off the front face
  HandLayout tilted = ok;
  tilted.directions(0, 2) = 0.1;
  EXPECT_THROW(make(tilted), std::invalid_argument);  // direction not in the palm plane
  HandLayout zero = ok;
  zero.directions.row(0).setZero();
  EXPECT_THROW(make(zero), std::invalid_argument);
  HandLayout outside = ok;
  outside.lower = MatrixX::Constant(2, 3, 0.1);
  outside.upper = MatrixX::Constant(2, 3, 1.0);
  EXPECT_THROW(make(outside), std::invalid_argument);  // rest 0 outside [0.1, 1]
  HandLayout crossed = outside;
  crossed.rest = MatrixX::Constant(2, 3, 0.5);
  crossed.lower(0, 1) = 2.0;
  EXPECT_THROW(make(crossed), std::invalid_argument);  // lower > upper
  HandLayout behind = ok;
  behind.rest = MatrixX::Zero(2, 3);
  behind.rest(0, 0) = 1.7;  // link 0 dips behind the palm
  EXPECT_THROW(make(behind), std::invalid_argument);
  HandLayout meet = ok;  // both fingers lie along the palm toward each other: they meet
  meet.rest = MatrixX::Zero(2, 3);
  meet.rest(0, 0) = meet.rest(1, 0) = kPi / 2;
  EXPECT_THROW(make(meet), std::invalid_argument);
  try {
    make(meet);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("intersect"), std::string::npos) << e.what();
  }
}

TEST(Limits, RimLayoutThroughTheGeneralConstructorIsTheSameHand) {
  // The rim layout given explicitly plans bit-identically to the default hand.
  const int M = 4, N = 3;
  const HandModel rim = HandModel::uniform(M, N, 0.02, 0.003, 0.03, 0.01);
  HandLayout layout;  // every field defaulted: the rim's roots and directions
  const HandModel general(M, N, MatrixX::Constant(M, N, 0.02), 0.003, 0.03, 0.01, layout);
  for (int m = 0; m < M; ++m) {
    EXPECT_NEAR((rim.root(Pose::Identity(), m) - general.root(Pose::Identity(), m)).norm(), 0.0, 1e-15);
    EXPECT_NEAR((rim.plane(Pose::Identity(), m).u - general.plane(Pose::Identity(), m).u).norm(), 0.0, 1e-15);
  }
  auto world = test::sphere_world(0.035, 3);
  Planner a(rim, world, Vec3::Zero(), test::facing_down(0.15));
  Planner b(general, world, Vec3::Zero(), test::facing_down(0.15));
  EXPECT_EQ(a.plan(), b.plan());
  ASSERT_EQ(a.history().size(), b.history().size());
  for (std::size_t k = 0; k < a.history().size(); ++k)
    for (std::size_t j = 0; j < a.history()[k].joints.size(); ++j)
      EXPECT_NEAR((a.history()[k].joints[j] - b.history()[k].joints[j]).norm(), 0.0, 1e-12);
}

TEST(Limits, PlansRespectLimitsOnASphere) {
  // Tight limits: the fingers cannot move as far as they would (they slide outward on the
  // sphere, against the lower limit, or wrap it, against the upper), yet every configuration
  // keeps every angle within its limits and the plan ends, under both rule sets.
  auto world = test::sphere_world(0.04, 4);
  for (Rules rules : {Rules::kPaper, Rules::kHug})
    for (double hi : {0.15, 0.4, 0.8}) {
      const HandModel hand = limited_hand(3, 3, -0.05, hi);
      PlannerParams params;
      params.rules = rules;
      Planner planner(hand, world, Vec3::Zero(), test::facing_down(0.2), params);
      const Status st = planner.plan();
      EXPECT_TRUE(st == Status::kDone || st == Status::kStalled) << to_string(st);
      double closest = kInf;  // how near any joint came to one of its limits
      for (const Configuration& c : planner.history())
        for (int m = 0; m < 3; ++m)
          for (int n = 0; n < 3; ++n) {
            EXPECT_GE(c.angles(m, n), -0.05 - 1e-9);
            EXPECT_LE(c.angles(m, n), hi + 1e-9);
            closest = std::min({closest, std::abs(c.angles(m, n) + 0.05), std::abs(c.angles(m, n) - hi)});
          }
      // The limits acted: with the paper's rules a joint comes to rest on one (the fingers slide
      // outward until the lower limit stops them); the hug rules let the finger yield first, so a
      // joint stops within a clinging tolerance of it.
      EXPECT_LE(closest, rules == Rules::kPaper ? 1e-9 : 1e-3) << to_string(rules) << " " << hi;
    }
}

TEST(Limits, SidewaysRestFingerStaysAtRestWhileFrozen) {
  // A two-finger gripper plus a thumb lying along the palm (rest 90 degrees at joint 0).
  const int M = 3, N = 3;
  HandLayout layout;
  layout.roots = MatrixX(M, 3);
  layout.roots << 0.025, 0.01, 0, -0.025, 0.01, 0, 0.0, -0.025, 0;
  layout.directions = MatrixX(M, 3);
  layout.directions << 1, 0, 0, -1, 0, 0, 0, 1, 0;
  layout.rest = MatrixX::Zero(M, N);
  layout.rest(2, 0) = -kPi / 2;  // the thumb lies on the palm's front face, along +u (across the palm)
  layout.lower = MatrixX::Constant(M, N, -kPi / 2);
  layout.upper = MatrixX::Constant(M, N, kPi / 2);
  const HandModel hand(M, N, MatrixX::Constant(M, N, 0.015), 0.003, 0.035, 0.01, layout);
  auto world = test::sphere_world(0.03, 4);
  Planner planner(hand, world, Vec3::Zero(), test::facing_down(0.15));
  planner.plan();
  for (const Configuration& c : planner.history())
    for (int m = 0; m < M; ++m) {
      if (c.tip_state[m] != TipState::kFrozen) continue;
      for (int n = 0; n < N; ++n) EXPECT_NEAR(c.angles(m, n), layout.rest(m, n), 1e-12);
    }
  const Configuration& first = planner.history().front();
  // the thumb's link 0 lies in the palm's front plane
  const Vec3 p = first.palm.linear().col(2);
  EXPECT_NEAR((first.joints[2 * (N + 1) + 1] - first.palm.translation()).dot(p), 0.0, 1e-12);
}
