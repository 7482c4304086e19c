// The skin's higher-level queries on a sphere, where every answer is known.
#include <gtest/gtest.h>

#include <random>

#include "hugger/geometry/distance.hpp"
#include "hugger/planner/snake.hpp"
#include "hugger/world/simulated_world.hpp"
#include "meshes.hpp"
#include "scenes.hpp"

using namespace hugger;

namespace {

struct SphereWorld {
  double R = 0.04;
  std::shared_ptr<Object> obj;
  std::unique_ptr<SimulatedWorld> world;
  FingerPlane plane;  // the plane z = 0: xi = x, eta = y; the sphere's section is a circle of radius R
  SphereWorld() {
    const auto mesh = test::icosphere(5, Vec3::Constant(R));
    obj = std::make_shared<Object>(mesh.vertices, mesh.faces);
    world = std::make_unique<SimulatedWorld>(obj);
    plane.origin = Vec3::Zero();
    plane.u = Vec3::UnitX();
    plane.p = Vec3::UnitY();
  }
};

/// A chain of N links from (0.5, 0.5) (far from the sphere), lengths 1-2 cm, each joint bent
/// by up to `bend` rad either way, drawn from `rng`; the lengths into `L`.
Chain random_chain(std::mt19937& rng, int N, double bend, std::vector<double>& L) {
  std::uniform_real_distribution<double> U(-1, 1);
  L.assign(N, 0.0);
  Chain chain(N + 1);
  chain[0] = Vec2(0.5, 0.5);
  double theta = 0;
  for (int n = 0; n < N; ++n) {
    L[n] = 0.01 + 0.01 * std::abs(U(rng));
    theta += bend * U(rng);
    chain[n + 1] = chain[n] + L[n] * Vec2(-std::sin(theta), std::cos(theta));
  }
  return chain;
}

}  // namespace

TEST(Sensing, FollowBoundaryStepsCounterClockwiseOnTheGrownCircle) {
  SphereWorld w;
  for (double r : {0.0, 0.004}) {
    for (int k = 0; k < 12; ++k) {
      const double a = -1.5 + 0.25 * k;
      FollowRequest req;
      req.plane = w.plane;
      req.radius = r;
      req.step = 0.001;
      req.level = 5e-5;
      req.tip = (w.R + r + req.level) * Vec2(std::cos(a), std::sin(a));
      const FollowResult res = w.world->follow_boundary(req);
      EXPECT_NEAR((res.head - req.tip).norm(), req.step, 2e-6);       // chord of one step
      EXPECT_NEAR(res.head.norm(), w.R + r + req.level, 2.5e-4);        // on the grown circle
      EXPECT_GE(res.gap, 0.0);                                          // never inside
      const double cross = req.tip.x() * res.head.y() - req.tip.y() * res.head.x();
      EXPECT_GT(cross, 0.0);  // counter-clockwise: interior on the left
    }
  }
}

TEST(Sensing, RotateUntilFreeLeavesTheLinkTangent) {
  SphereWorld w;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0, 2 * kPi);
  int rotated = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const double r = trial % 2 ? 0.003 : 0.0;
    const double a = U(rng);
    RotateRequest req;
    req.plane = w.plane;
    req.radius = r;
    req.pivot = (w.R + r + 2e-4) * Vec2(std::cos(a), std::sin(a));
    const double b = U(rng);
    req.end = req.pivot + 0.02 * Vec2(std::cos(b), std::sin(b));
    req.tolerance = 1e-5;
    const bool was_free = w.world->link_free(req.plane, req.pivot, req.end, r, -kInf);
    const RotateResult res = w.world->rotate_until_free(req);
    ASSERT_TRUE(res.ok);
    EXPECT_NEAR((res.end - req.pivot).norm(), 0.02, 1e-12);
    EXPECT_GE(res.gap, 0.0);
    if (!was_free) {
      ++rotated;
      EXPECT_LE(res.gap, 1e-4);  // resting on the surface
    }
  }
  EXPECT_GT(rotated, 10);
}

TEST(Sensing, RotateUntilTouchStopsOnContact) {
  SphereWorld w;
  RotateRequest req;
  req.plane = w.plane;
  req.radius = 0.002;
  req.pivot = Vec2(0.05, -0.02);
  req.end = Vec2(0.05, 0.0);  // pointing along +eta; flexion swings it toward the sphere
  req.max_angle = kPi / 2;
  req.touch_gap = 1e-4;
  req.level = 5e-5;
  const RotateResult res = w.world->rotate_until_touch(req);
  EXPECT_TRUE(res.ok);
  EXPECT_GT(res.angle, 0.0);
  EXPECT_GE(res.gap, 0.0);
  EXPECT_LE(res.gap, 1e-4);
  // limited to max_angle when nothing is in reach
  req.pivot = Vec2(0.2, 0.0);
  req.end = Vec2(0.2, 0.02);
  req.max_angle = 0.1;
  const RotateResult free = w.world->rotate_until_touch(req);
  EXPECT_FALSE(free.ok);
  EXPECT_NEAR(free.angle, 0.1, 1e-12);
}

TEST(Snake, FollowTheLeaderInFreeSpace) {
  // Far from the object: no clinging; link lengths exact and no joint moves more than the head.
  SphereWorld w;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 100; ++trial) {
    const int N = 2 + trial % 7;
    std::vector<double> L;
    Chain chain = random_chain(rng, N, 0.5, L);
    SnakeRequest req;
    req.plane = w.plane;
    req.lengths = L.data();
    const Chain before = chain;
    const Vec2 head = chain[N] + 0.001 * Vec2(U(rng), U(rng));
    ASSERT_TRUE(head_to_tail(*w.world, req, head, chain));
    const double head_step = (head - before[N]).norm();
    for (int n = 0; n < N; ++n) {
      EXPECT_NEAR((chain[n + 1] - chain[n]).norm(), L[n], 1e-14);
      EXPECT_LE((chain[n] - before[n]).norm(), head_step + 1e-14);  // tail drift <= head step
    }
    ASSERT_TRUE(tail_to_head(*w.world, req, before[0], chain));
    EXPECT_LT((chain[0] - before[0]).norm(), 1e-15);
    for (int n = 0; n < N; ++n) EXPECT_NEAR((chain[n + 1] - chain[n]).norm(), L[n], 1e-14);
  }
}

// A finger against itself, one link at a time (link_clear_of_chain), against every pair's exact
// distance; and Tail2Head with a self-separation gives up exactly on the chains that fold onto
// themselves, placing the others bit for bit as without it, and says so (`folded`), with and
// without fold_early. Chains in free space with joints bent up to 2.9 rad, so that many fold.
TEST(Snake, SelfSeparationStopsExactlyTheChainsThatFold) {
  SphereWorld w;
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> U(-1, 1);
  const double sep = 0.008;
  long folded = 0, whole = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int N = 3 + trial % 6;
    std::vector<double> L;
    const Chain chain = random_chain(rng, N, 2.9, L);
    SnakeRequest req;
    req.plane = w.plane;
    req.lengths = L.data();
    const Vec2 root = chain[0] + 0.002 * Vec2(U(rng), U(rng));
    Chain full = chain;
    ASSERT_TRUE(tail_to_head(*w.world, req, root, full));
    bool clear = true;
    for (int b = 0; b < N; ++b) {
      bool apart = true;
      for (int a = 0; a + 2 <= b; ++a)
        apart = apart && segment_segment_squared_2d(full[a], full[a + 1], full[b], full[b + 1]) >= sep * sep;
      EXPECT_EQ(link_clear_of_chain(full.data(), b, sep), apart) << "trial " << trial << " link " << b;
      clear = clear && apart;
    }
    bool said_folded = clear;  // set to the opposite: the call must write it
    Chain unsaid = chain;
    ASSERT_TRUE(tail_to_head(*w.world, req, root, unsaid, nullptr, &said_folded));
    EXPECT_FALSE(said_folded) << "trial " << trial;  // no self-separation asked: nothing refused
    req.self_separation = sep;
    Chain stopped = chain;
    said_folded = clear;
    EXPECT_EQ(tail_to_head(*w.world, req, root, stopped, nullptr, &said_folded), clear) << "trial " << trial;
    EXPECT_EQ(said_folded, !clear) << "trial " << trial;
    // With fold_early, the same answers (a joint that close only refuses what the link would).
    req.fold_early = true;
    Chain early = chain;
    said_folded = clear;
    EXPECT_EQ(tail_to_head(*w.world, req, root, early, nullptr, &said_folded), clear) << "trial " << trial;
    EXPECT_EQ(said_folded, !clear) << "trial " << trial;
    if (clear) {
      EXPECT_TRUE(stopped == full) << "trial " << trial;
      EXPECT_TRUE(early == full) << "trial " << trial;
      ++whole;
    } else {
      ++folded;
    }
  }
  EXPECT_GE(folded, 50);
  EXPECT_GE(whole, 50);
}

// Tail2Head with a self-separation and fold_early refuses a chain whose next joint already lies
// that close to the link before the last one placed, before it asks the skin about the next link:
// every link from that joint comes as close (the joint is on it).
TEST(Snake, AFoldAtAJointAsksNothingOfTheLinkFromIt) {
  struct Counting final : test::EmptySkin {
    mutable int asked = 0;
    bool link_free(const FingerPlane&, const Vec2&, const Vec2&, double, double, bool) const override {
      ++asked;
      return true;
    }
  };
  const Counting skin;
  // Link 0 up the eta axis, link 1 turned back beside it: joint 2 lies 3 mm from link 0.
  const std::vector<double> L(4, 0.02);
  Chain chain(5);
  chain[0] = Vec2(0.0, 0.0);
  chain[1] = Vec2(0.0, 0.02);
  chain[2] = chain[1] + 0.02 * Vec2(std::sin(0.15), -std::cos(0.15));
  chain[3] = chain[2] + Vec2(0.02, 0.0);
  chain[4] = chain[3] + Vec2(0.0, 0.02);
  SnakeRequest req;
  req.lengths = L.data();
  req.self_separation = 0.008;
  Chain c = chain;
  bool folded = false;
  EXPECT_FALSE(tail_to_head(skin, req, chain[0], c, nullptr, &folded));
  EXPECT_TRUE(folded);
  EXPECT_EQ(skin.asked, 3);  // without fold_early link 2 is placed, then found folding
  req.fold_early = true;
  c = chain;
  skin.asked = 0;
  folded = false;
  EXPECT_FALSE(tail_to_head(skin, req, chain[0], c, nullptr, &folded));
  EXPECT_TRUE(folded);
  EXPECT_EQ(skin.asked, 2);  // links 0 and 1 only
  // Apart by more than the separation, the same chain is placed whole.
  req.self_separation = 0.002;
  c = chain;
  skin.asked = 0;
  EXPECT_TRUE(tail_to_head(skin, req, chain[0], c, nullptr, &folded));
  EXPECT_FALSE(folded);
  EXPECT_EQ(skin.asked, 4);
}
