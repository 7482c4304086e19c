// The Phase 2 rules of issue 16: DONE fingers at rest, a tip on a face facing the palm, the
// smallest freeing rotation, and the motion between configurations.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "hugger/geometry/distance.hpp"
#include "hugger/planner/planner.hpp"
#include "hugger/world/section_skin.hpp"
#include "hugger/world/simulated_world.hpp"
#include "meshes.hpp"
#include "scenes.hpp"

using namespace hugger;

namespace {

/// An axis-aligned box of half-extents h about `centre`, 12 outward triangles.
std::shared_ptr<SimulatedWorld> box_world(const Vec3& h, const Vec3& centre = Vec3::Zero()) {
  const test::Mesh m = test::box(h, centre);
  return std::make_shared<SimulatedWorld>(std::make_shared<Object>(m.vertices, m.faces));
}

/// Every emitted configuration: DONE fingers keep their angles; in Phase 2 no joint moves more
/// than 4 s between consecutive configurations; no configuration repeats the one before.
void expect_motion_rules(const Planner& p) {
  const auto& h = p.history();
  const int M = p.hand().fingers(), N = p.hand().links();
  const double s = p.params().step;
  for (std::size_t k = 1; k < h.size(); ++k) {
    for (int m = 0; m < M; ++m)
      if (h[k - 1].tip_state[m] == TipState::kDone)
        for (int n = 0; n < N; ++n) EXPECT_EQ(h[k].angles(m, n), h[k - 1].angles(m, n)) << "k " << k << " m " << m;
    if (h[k].phase != 2) continue;
    double worst = 0.0;
    for (std::size_t j = 0; j < h[k].joints.size(); ++j) worst = std::max(worst, (h[k].joints[j] - h[k - 1].joints[j]).norm());
    EXPECT_LE(worst, 4.0 * s) << "configuration " << k;
    bool same = h[k].palm.matrix() == h[k - 1].palm.matrix() && h[k].tip_state == h[k - 1].tip_state;
    for (std::size_t j = 0; j < h[k].joints.size() && same; ++j) same = h[k].joints[j] == h[k - 1].joints[j];
    EXPECT_FALSE(same) << "configuration " << k << " repeats the one before";
  }
}

double palm_height(const Configuration& c) { return c.palm.translation().z(); }

/// The plan of `hand` about `world` with `rules` from 20 cm above, facing down at the origin; it
/// does not end max_iterations and keeps the motion rules.
std::unique_ptr<Planner> plan_from_above(const HandModel& hand, const std::shared_ptr<SimulatedWorld>& world, Rules rules) {
  PlannerParams params;
  params.rules = rules;
  auto p = std::make_unique<Planner>(hand, world, Vec3::Zero(), test::facing_down(0.2), params);
  EXPECT_NE(p->plan(), Status::kMaxIterations) << to_string(rules);
  expect_motion_rules(*p);
  return p;
}

}  // namespace

// A straight finger whose tip lands on a flat face that faces the palm. The paper's rules: the
// tip can only slide outward, the tail drifts radially, sigma is 0: the finger is DONE at once,
// straight, and (a DONE finger being rigid) it holds the palm off the face. The hug rule: the
// finger yields, so the palm keeps advancing after the first contact.
TEST(Rules, TipOnAFaceFacingThePalm) {
  const HandModel hand = HandModel::uniform(3, 4, 0.02, 0.0, 0.02, 0.01);
  // The box's top face z = 0.02 is 12 cm wide: every tip lands on it, none passes its edge.
  auto world = box_world(Vec3(0.06, 0.06, 0.02));
  Pose start = test::facing_down(0.2);
  double end_height[2] = {0.0, 0.0};
  bool palm_contact[2] = {false, false};
  for (Rules rules : {Rules::kPaper, Rules::kHug}) {
    PlannerParams params;
    params.rules = rules;
    Planner p(hand, world, Vec3::Zero(), start, params);
    const Status st = p.plan();
    EXPECT_TRUE(st == Status::kDone || st == Status::kStalled) << to_string(st);
    expect_motion_rules(p);
    const auto& h = p.history();
    end_height[static_cast<int>(rules)] = palm_height(h.back());
    palm_contact[static_cast<int>(rules)] = p.stats().palm_contact_iteration >= 0;
  }
  // the face is at z = 0.02; the straight fingers are 8 cm long
  EXPECT_GT(end_height[0], 0.02 + 0.04) << "paper: the DONE fingers hold the palm off the face";
  EXPECT_FALSE(palm_contact[0]);
  EXPECT_LT(end_height[1], 0.02 + 0.001) << "hug: the fingers yield and the palm lands on the face";
}

// Hug rule H5: the same face tilted toward the palm (the palm comes at it from 15 and 35 degrees
// off its normal). The uphill fingertips could slide outward only toward the palm; Tail2Head
// folded those fingers into a Z that held the palm 3 cm off the face. Such a finger opens (its
// root joint turns back) while the palm advances, and closes again once the palm lands.
TEST(Rules, FingersOpenOnATiltedFace) {
  const HandModel hand = HandModel::uniform(3, 4, 0.02, 0.0, 0.02, 0.01);
  auto world = box_world(Vec3(0.06, 0.06, 0.02));
  for (double degrees : {15.0, 35.0}) {
    const double a = degrees * kPi / 180.0;
    Pose start = Pose::Identity();
    start.linear() = Eigen::AngleAxisd(kPi - a, Vec3::UnitX()).toRotationMatrix();  // p at the origin
    start.translation() = 0.2 * Vec3(0.0, std::sin(a), std::cos(a));
    PlannerParams params;
    params.rules = Rules::kHug;
    Planner p(hand, world, Vec3::Zero(), start, params);
    EXPECT_EQ(p.plan(), Status::kDone) << degrees;
    expect_motion_rules(p);
    const auto& h = p.history();
    double most_open = 0.0;  // the smallest root joint angle (extension is negative)
    for (const Configuration& c : h)
      for (int m = 0; m < hand.fingers(); ++m) most_open = std::min(most_open, c.angles(m, 0));
    EXPECT_LT(most_open, -1.0) << degrees << " degrees: a finger opened";
    const double gap = world->palm(h.back().palm, hand.palm_radius(), hand.palm_thickness(), 1.0);
    EXPECT_LT(gap, 0.01) << degrees << " degrees: the palm comes within 1 cm of the face";
  }
}

// Hug rule H4: a FROZEN finger sliding past a sphere's flank, 0.2 mm from it, does not hold the
// palm to its gap. Two opposite fingers whose roots lie just outside the sphere's silhouette pass
// beside it while the palm comes down onto its top: the paper's rules clip every palm step to
// the fingers' gap (0.15 mm of the 1.5 mm step), the hug rules to the free distance along p.
TEST(Rules, PalmStepIsTheFreeDistanceAlongP) {
  const double rho = 0.03, r = 0.004;
  const HandModel hand = HandModel::uniform(2, 3, 0.03, r, rho + r + 2e-4, 0.01);
  auto world = test::sphere_world(rho, 4);
  long to_palm[2] = {0, 0};
  for (Rules rules : {Rules::kPaper, Rules::kHug}) {
    const auto p = plan_from_above(hand, world, rules);
    EXPECT_GE(p->stats().palm_contact_iteration, 0) << to_string(rules) << ": the palm lands on the sphere";
    to_palm[static_cast<int>(rules)] = p->stats().palm_contact_iteration;
  }
  // the fingers pass the flank for about 6 cm (the sphere's height and more): 40 steps of s
  EXPECT_GT(to_palm[0], 150) << "paper: the palm crawls at the fingers' gap";
  EXPECT_LT(to_palm[1], 80) << "hug: the palm moves its free distance along p";
}

// A DONE finger keeps its joint angles while the palm still advances: the 5 x 5 hand on an
// ellipsoid of 10 x 8 x 6 cm from above (turned 30 degrees about the vertical), where some
// fingers are DONE before the palm lands (with the paper's rules; under the hug rules they open
// instead, H5, and the rule is checked all the same).
TEST(Rules, DoneFingerAtRestWhileThePalmAdvances) {
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  const auto mesh = test::icosphere(4, Vec3(0.05, 0.04, 0.03));
  auto world = std::make_shared<SimulatedWorld>(std::make_shared<Object>(mesh.vertices, mesh.faces));
  Pose start = test::facing_down(0.2);
  start.linear() = Eigen::AngleAxisd(kPi / 6.0, Vec3::UnitZ()).toRotationMatrix() * start.linear();
  bool exercised = false;
  for (Rules rules : {Rules::kPaper, Rules::kHug}) {
    PlannerParams params;
    params.rules = rules;
    const auto p = std::make_unique<Planner>(hand, world, Vec3::Zero(), start, params);
    EXPECT_NE(p->plan(), Status::kMaxIterations) << to_string(rules);
    expect_motion_rules(*p);
    // some finger is DONE while the palm still moves (with either rule set): the rule is exercised
    const auto& h = p->history();
    for (std::size_t k = 1; k < h.size() && !exercised; ++k)
      for (int m = 0; m < 5; ++m)
        if (h[k - 1].tip_state[m] == TipState::kDone &&
            (h[k].palm.translation() - h[k - 1].palm.translation()).norm() > 0.0)
          exercised = true;
  }
  EXPECT_TRUE(exercised);
}

// No finger folds onto itself: at every configuration of hug-rule plans, from 16 approaches
// about a cylinder and a box (where fingers' chains often fold while the palm steps: the palm
// step's Tail2Head refuses them as it places them, and open_step's and reclose_step's too), every
// two links of a finger not next to each other stay two link radii apart, as fingers_clear asks.
TEST(Rules, NoFingerFoldsOntoItself) {
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  const int M = hand.fingers(), N = hand.links();
  const double sep = 2.0 * hand.link_radius();
  long plans = 0, refused = 0, configurations = 0;
  for (const test::Mesh& mesh : {test::cylinder(0.035, 0.05, 48), test::box(Vec3(0.03, 0.02, 0.05))}) {
    auto skin = std::make_shared<SectionSkin>(std::make_shared<Object>(mesh.vertices, mesh.faces));
    for (int k = 0; k < 16; ++k) {
      // approaches spread over the sphere (a spiral), the palm 20 cm from the centre, facing it
      const double z = 1.0 - (2.0 * k + 1.0) / 16.0, phi = 2.399963229728653 * k;
      const Vec3 d(std::sqrt(1.0 - z * z) * std::cos(phi), std::sqrt(1.0 - z * z) * std::sin(phi), z);
      Pose start = Pose::Identity();
      start.linear() = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), -d).toRotationMatrix();
      start.translation() = 0.2 * d;
      PlannerParams params;
      params.rules = Rules::kHug;
      std::unique_ptr<Planner> p;
      try {
        p = std::make_unique<Planner>(hand, skin, Vec3::Zero(), start, params);
      } catch (const std::invalid_argument&) {
        continue;  // the hand touches O at the start or while it turns
      }
      EXPECT_NE(p->plan(), Status::kMaxIterations);
      ++plans;
      refused += p->stats().finger_collisions;
      for (const Configuration& c : p->history()) {
        ++configurations;
        for (int m = 0; m < M; ++m) {
          const Vec3* j = &c.joints[static_cast<std::size_t>(m * (N + 1))];
          for (int b = 2; b < N; ++b)
            for (int a = 0; a + 2 <= b; ++a)
              ASSERT_GE(segment_segment_squared(j[a], j[a + 1], j[b], j[b + 1]), sep * sep * (1.0 - 1e-9))
                  << "approach " << k << " configuration " << c.iteration << " finger " << m << " links " << a
                  << ", " << b;
        }
      }
    }
  }
  std::printf("  %ld plans, %ld configurations, %ld chains refused for a collision or a fold\n", plans,
              configurations, refused);
  EXPECT_GE(plans, 20);
  EXPECT_GE(refused, 20);  // the rule is exercised
}

// rotate_until_free turns a colliding link by the smallest angle that frees it: against a
// brute-force sweep of fine angles both ways, on a sphere and on a box, random links.
TEST(Rules, SmallestFreeingRotationMatchesBruteForce) {
  std::mt19937 rng(16);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const std::shared_ptr<SimulatedWorld> worlds[2] = {test::sphere_world(0.03, 4), box_world(Vec3(0.03, 0.02, 0.025))};
  FingerPlane plane;  // z = 0
  plane.u = Vec3::UnitX();
  plane.p = Vec3::UnitY();
  int checked = 0;
  for (const auto& world : worlds)
    for (double radius : {0.0, 0.003})
      for (int trial = 0; trial < 300; ++trial) {
        // a pivot outside O near its surface, a link of 2 cm pointing somewhere, colliding
        const double a = kPi * U(rng), d = 0.036 + 0.01 * (U(rng) + 1.0);
        const Vec2 pivot(d * std::cos(a), d * std::sin(a));
        if (!world->link_free(plane, pivot, pivot, radius, -kInf)) continue;
        const double b = kPi * U(rng);
        const Vec2 end = pivot + 0.02 * Vec2(std::cos(b), std::sin(b));
        if (world->link_free(plane, pivot, end, radius, -kInf)) continue;
        const RotateRequest rr = test::rotate_request(plane, pivot, end, radius, -kInf, kPi);
        const RotateResult res = world->rotate_until_free(rr);
        // brute force: the smallest |angle| on a grid of 1e-4 rad at which the link is free
        const double brute = test::smallest_free_angle(*world, rr, 1e-4);
        ASSERT_EQ(res.ok, std::isfinite(brute));
        if (!res.ok) continue;
        ++checked;
        EXPECT_TRUE(world->link_free(plane, pivot, res.end, radius, -kInf));
        // never farther than the smallest free angle by more than the refinement resolution
        // (tolerance / length, and the grid), unless the link then rests on O within the
        // tolerance (grazing: the gap grows slowly with the angle) -- and then by less than one
        // sample angle; never nearer than a free angle can be
        if (res.gap > rr.tolerance) EXPECT_LE(std::abs(res.angle), brute + 1e-3 + 1e-4) << "trial " << trial;
        EXPECT_LE(std::abs(res.angle), brute + rr.sample_angle) << "trial " << trial;
        EXPECT_GE(std::abs(res.angle), brute - 1e-4 - 1e-9) << "trial " << trial;
      }
  EXPECT_GE(checked, 150);
}
