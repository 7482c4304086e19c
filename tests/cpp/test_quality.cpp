// Grasp quality: the cutting-plane epsilon equals the full hull's, on random grasps; closure cases.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "hugger/analysis/quality.hpp"

using namespace hugger;
using namespace hugger::analysis;

namespace {

void random_grasp(std::mt19937& rng, int contacts, PointsN3* points, PointsN3* normals) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> r(0.02, 0.06);
  const Vec3 radii(r(rng), r(rng), r(rng));
  points->resize(contacts, 3);
  normals->resize(contacts, 3);
  for (int i = 0; i < contacts; ++i) {
    const Vec3 d = Vec3(g(rng), g(rng), g(rng)).normalized();
    points->row(i) = d.cwiseProduct(radii).transpose();
    normals->row(i) = d.cwiseQuotient(radii.cwiseProduct(radii)).normalized().transpose();
  }
}

}  // namespace

TEST(Quality, CuttingPlanesMatchTheFullHull) {
  std::mt19937 rng(15);
  int closures = 0;
  for (int trial = 0; trial < 200; ++trial) {
    PointsN3 p, n;
    random_grasp(rng, 2 + trial % 14, &p, &n);
    QualityRequest full;
    full.mu = (trial % 3) * 0.4;
    full.cone_edges = 4 + trial % 5;
    full.torque_scale = 0.06;
    QualityRequest fast = full;
    fast.volume = false;
    const QualityResult a = grasp_quality(p, n, Vec3::Zero(), full);
    const QualityResult b = grasp_quality(p, n, Vec3::Zero(), fast);
    ASSERT_EQ(a.force_closure, b.force_closure) << trial;
    ASSERT_EQ(a.wrenches, b.wrenches) << trial;
    ASSERT_NEAR(a.epsilon, b.epsilon, 1e-6 * std::max(a.epsilon, 1e-6)) << trial;
    EXPECT_EQ(b.volume, 0.0);
    if (a.force_closure) {
      ++closures;
      EXPECT_GT(a.volume, 0.0);
    }
  }
  EXPECT_GT(closures, 40);
  EXPECT_LT(closures, 190);
}

TEST(Quality, OpposedFrictionlessPairIsNotClosureSixAxisContactsAre) {
  // Two opposed frictionless contacts: no closure. Contacts on all six faces of a cube with
  // friction: closure, and the same answer on every call (fixed joggle seed).
  PointsN3 p(2, 3), n(2, 3);
  p << 0.05, 0, 0, -0.05, 0, 0;
  n << 1, 0, 0, -1, 0, 0;
  QualityRequest req;
  req.mu = 0.0;
  EXPECT_FALSE(grasp_quality(p, n, Vec3::Zero(), req).force_closure);
  PointsN3 q(12, 3), m(12, 3);
  int row = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (int s : {-1, 1})
      for (double off : {-0.01, 0.01}) {
        Vec3 c = Vec3::Zero(), o = Vec3::Zero();
        c[axis] = 0.05 * s;
        o[(axis + 1) % 3] = off;
        q.row(row) = (c + o).transpose();
        m.row(row) = Vec3::Unit(axis).transpose() * s;
        ++row;
      }
  req.mu = 0.5;
  req.torque_scale = 0.05;
  const QualityResult a = grasp_quality(q, m, Vec3::Zero(), req);
  EXPECT_TRUE(a.force_closure);
  for (int i = 0; i < 3; ++i) {
    const QualityResult b = grasp_quality(q, m, Vec3::Zero(), req);
    EXPECT_EQ(a.epsilon, b.epsilon);
    EXPECT_EQ(a.volume, b.volume);
  }
}

TEST(Quality, BadInputThrows) {
  PointsN3 p(3, 3), n(2, 3);
  p.setZero();
  n.setOnes();
  EXPECT_THROW(grasp_quality(p, n, Vec3::Zero(), QualityRequest{}), std::invalid_argument);
  PointsN3 z = PointsN3::Zero(3, 3);
  EXPECT_THROW(grasp_quality(p, z, Vec3::Zero(), QualityRequest{}), std::invalid_argument);
  QualityRequest bad;
  bad.cone_edges = 2;
  PointsN3 ones = PointsN3::Ones(3, 3);
  EXPECT_THROW(grasp_quality(p, ones, Vec3::Zero(), bad), std::invalid_argument);
  bad = QualityRequest{};
  bad.torque_scale = 0.0;
  EXPECT_THROW(grasp_quality(p, ones, Vec3::Zero(), bad), std::invalid_argument);
}
