// The argument checks: the macros' messages, and the rules owned by one function each (poses,
// plane frames, planner parameters, timeouts, what a skin answers).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "hugger/check.hpp"
#include "hugger/geometry/frame.hpp"
#include "hugger/hand/hand_model.hpp"
#include "hugger/planner/planner.hpp"
#include "hugger/sensing/sensing.hpp"
#include "hugger/world/object.hpp"
#include "meshes.hpp"

using namespace hugger;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The message f throws as std::invalid_argument ("" when it does not throw).
template <class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Checks, MacrosThrowOneLineMessagesWithTheValues) {
  const double x = -0.5;
  EXPECT_EQ(message_of([&] { HUGGER_CHECK_ARGUMENT(x > 0.0, "x must be positive, got " << x); }),
            "x must be positive, got -0.5");
  EXPECT_EQ(message_of([&] { HUGGER_CHECK_ARGUMENT(x < 0.0, "never"); }), "");
  EXPECT_EQ(message_of([] { HUGGER_CHECK_ARGUMENT_SIZE(4, 6, "joints", "points"); }), "joints must hold 6 points, got 4");
  const MatrixX m(2, 3);
  EXPECT_EQ(message_of([&] { HUGGER_CHECK_ARGUMENT_SHAPE(m, 5, 3, "angles"); }),
            "angles must be a (5, 3) array, got (2, 3)");
  EXPECT_EQ(message_of([&] { HUGGER_CHECK_ARGUMENT_SHAPE(m, 2, 3, "angles"); }), "");
}

TEST(Checks, PoseRuleSaysWhatIsWrong) {
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  EXPECT_EQ(message_of([&] { check_pose(pose); }), "");
  pose(1, 3) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(message_of([&] { check_pose(pose, "T"); }), "T holds non-finite numbers");
  pose = Eigen::Matrix4d::Identity();
  pose(3, 0) = 0.1;
  EXPECT_EQ(message_of([&] { check_pose(pose); }),
            "palm_pose must be a homogeneous transform with last row (0, 0, 0, 1), got (0.1, 0, 0, 1)");
  pose = Eigen::Matrix4d::Identity();
  pose(2, 2) = -1.0;
  EXPECT_NE(message_of([&] { check_pose(pose); }).find("reflects (det < 0)"), std::string::npos);
  pose(2, 2) = 1.001;
  EXPECT_NE(message_of([&] { check_pose(pose); }).find("scales or shears: |R^T R - I| = 0.002, det R = 1.001"),
            std::string::npos);
  pose(2, 2) = 1.0 + 0.4 * kRigidTolerance;  // within the tolerance
  EXPECT_EQ(message_of([&] { check_pose(pose); }), "");
}

TEST(Checks, PlaneFrames) {
  EXPECT_EQ(message_of([] { check_plane_frame(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()); }), "");
  EXPECT_EQ(message_of([] { check_plane_frame(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitX()); }),
            "u and v must be orthonormal");
  EXPECT_EQ(message_of([] { check_plane_frame(Vec3(kNaN, 0, 0), Vec3::UnitX(), Vec3::UnitY()); }),
            "origin must be finite");
}

TEST(Checks, PlannerParametersAndTimeouts) {
  PlannerParams p;
  EXPECT_EQ(message_of([&] { check_params(p); }), "");  // NaN: the defaults
  p.step = -1e-3;
  EXPECT_EQ(message_of([&] { check_params(p); }), "step must be a positive finite number, got -0.001");
  p = PlannerParams();
  p.epsilon = std::numeric_limits<double>::infinity();
  EXPECT_EQ(message_of([&] { check_params(p); }), "epsilon must be a positive finite number, got inf");
  p = PlannerParams();
  p.max_iterations = 0;
  EXPECT_EQ(message_of([&] { check_params(p); }), "max_iterations must be between 1 and 1000000000, got 0");
  p.max_iterations = kMaxIterations + 1;
  EXPECT_NE(message_of([&] { check_params(p); }), "");
  p.max_iterations = kMaxIterations;
  EXPECT_EQ(message_of([&] { check_params(p); }), "");
  EXPECT_EQ(check_timeout(0.5), 0.5);
  for (double bad : {0.0, -1.0, kNaN, std::numeric_limits<double>::infinity()})
    EXPECT_THROW(check_timeout(bad), std::invalid_argument) << bad;
}

TEST(Checks, HandCountsAreBoundedByTheConstants) {
  EXPECT_NO_THROW(HandModel::uniform(kMaxFingers, 2, 0.02, 0.0, 0.03, 0.01));
  EXPECT_EQ(message_of([] { HandModel::uniform(kMaxFingers + 1, 2, 0.02, 0.0, 0.03, 0.01); }),
            "fingers must be between 1 and 64, got 65");
  EXPECT_EQ(message_of([] { HandModel::uniform(2, kMaxLinks + 1, 0.02, 0.0, 0.03, 0.01); }),
            "links must be between 1 and 256, got 257");
}

TEST(Checks, HandLayoutLimitsMustBeNumbers) {
  HandLayout layout;
  layout.lower = MatrixX::Constant(2, 3, -1.0);
  layout.lower(1, 2) = kNaN;
  EXPECT_EQ(message_of([&] { HandModel(2, 3, MatrixX::Constant(2, 3, 0.02), 0.002, 0.03, 0.01, layout); }),
            "the limits of joint 2 of finger 1 must be lower <= upper (rad, +-inf: unlimited), got [nan, inf]");
}

TEST(Checks, WhatCrossesTheSensingInterface) {
  EXPECT_EQ(message_of([] { check_capsule_query(Vec3::Zero(), Vec3::UnitX(), 0.0, kInf); }), "");
  EXPECT_EQ(message_of([] { check_capsule_query(Vec3(kNaN, 0, 0), Vec3::UnitX(), 0.0, kInf); }),
            "a and b must be finite, each coordinate within 1e+06 m of the origin");
  // Far out, squares overflow and the tolerances fall below the spacing of doubles.
  EXPECT_EQ(message_of([] { check_capsule_query(Vec3(1e154, 0, 0), Vec3(-1e154, 0, 0), 0.0, kInf); }),
            "a and b must be finite, each coordinate within 1e+06 m of the origin");
  EXPECT_EQ(message_of([] { check_capsule_query(Vec3::Zero(), Vec3(0, 0, 1e6), 1e6, kInf); }), "");
  EXPECT_EQ(message_of([] { check_capsule_query(Vec3::Zero(), Vec3::UnitX(), 2e6, kInf); }),
            "radius must be a number from 0 to 1e+06 (m), got 2e+06");
  EXPECT_EQ(message_of([] { check_palm_query(0.03, -0.01, 0.0); }),
            "thickness must be a number from 0 to 1e+06 (m), got -0.01");
  EXPECT_EQ(message_of([] { check_palm_query(0.03, 0.01, kNaN); }), "cap must be a number (m) or inf, got nan");
  EXPECT_EQ(message_of([] { check_gap(kNaN, "Sensing.palm returned"); }),
            "Sensing.palm returned a gap of nan; expected a number (m) or +-inf");
  Touch t;
  t.gap = -kInf;  // inside, depth not measured: a valid answer
  t.normal = Vec3(0.0, 3.0, 4.0);
  EXPECT_TRUE(check_touch(t, "Sensing.capsule returned").normal.isApprox(Vec3(0.0, 0.6, 0.8)));
  t.normal = Vec3::Zero();
  EXPECT_EQ(message_of([&] { check_touch(t, "Sensing.capsule returned"); }),
            "Sensing.capsule returned non-finite points or a zero or non-finite normal");
}

TEST(Checks, TheTargetMustBeInsideTheObject) {
  const auto mesh = test::icosphere(2);
  const Object o(mesh.vertices, mesh.faces);
  EXPECT_EQ(message_of([&] { check_target(o, Vec3(0.1, 0.0, 0.0)); }), "");
  EXPECT_EQ(message_of([&] { check_target(o, Vec3(0.0, kNaN, 0.0)); }), "target must be a finite 3-vector, got (0, nan, 0)");
  EXPECT_NE(message_of([&] { check_target(o, Vec3(2.0, 0.0, 0.0)); }).find("target T = (2, 0, 0) is not inside the object"),
            std::string::npos);
}

TEST(Checks, TheTargetCheckAgreesWithTheSignedDistance) {
  // check_target decides by ray parity off the surface; the rule it owns is the signed distance's
  // sign. Random points in and around convex and non-convex meshes, their vertices (on the
  // surface), points just off them, and the symmetric centres (every triangle about as near).
  const std::vector<test::Mesh> meshes = {test::icosphere(3), test::icosphere(2, Vec3(1.0, 0.6, 0.4)),
                                          test::box(Vec3(0.5, 0.3, 0.2)), test::cylinder(0.4, 0.5, 48, 3),
                                          test::torus(0.6, 0.2, 32, 16), test::curvy(3)};
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> U(-1.3, 1.3), tiny(-1e-9, 1e-9);
  int inside = 0, outside = 0, on = 0;
  for (const auto& mesh : meshes) {
    const Object o(mesh.vertices, mesh.faces);
    std::vector<Vec3> points = {Vec3::Zero(), Vec3(0.6, 0.0, 0.0), Vec3(0.0, 0.6, 0.0)};
    for (int i = 0; i < 400; ++i) points.emplace_back(U(rng), U(rng), U(rng));
    for (std::int64_t v = 0; v < mesh.vertices.rows(); v += 7) {
      const Vec3 x = mesh.vertices.row(v).transpose();
      points.push_back(x);
      points.push_back(x + Vec3(tiny(rng), tiny(rng), tiny(rng)));
    }
    for (const Vec3& x : points) {
      const double d = o.nearest(x, x).signed_distance;
      const bool accepted = message_of([&] { check_target(o, x); }).empty();
      EXPECT_EQ(accepted, d < 0.0) << "at (" << x.transpose() << "), signed distance " << d;
      (d < 0.0 ? inside : d == 0.0 ? on : outside) += 1;
    }
  }
  EXPECT_GT(inside, 250);
  EXPECT_GT(outside, 500);
  EXPECT_GT(on, 100);
}
