// Hand model: forward kinematics and the inverse (angles from joints) round trip.
#include <gtest/gtest.h>

#include <random>

#include "hugger/hand/hand_model.hpp"
#include "meshes.hpp"

using namespace hugger;

namespace {
Pose random_pose(std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-1, 1);
  Pose p = Pose::Identity();
  p.linear() = Eigen::Quaterniond(U(rng), U(rng), U(rng), U(rng)).normalized().toRotationMatrix();
  p.translation() = Vec3(U(rng), U(rng), U(rng));
  return p;
}
}  // namespace

TEST(Kinematics, RoundTripAndInvariants) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const int M = 2 + trial % 7, N = 2 + (trial / 7) % 7;
    MatrixX lengths(M, N);
    for (int m = 0; m < M; ++m)
      for (int n = 0; n < N; ++n) lengths(m, n) = 0.01 + 0.02 * (U(rng) + 1);
    const HandModel hand(M, N, lengths, 0.002, 0.03, 0.01);
    const Pose palm = random_pose(rng);
    MatrixX angles(M, N);
    for (int m = 0; m < M; ++m)
      for (int n = 0; n < N; ++n) angles(m, n) = 3.0 * U(rng);
    const auto joints = hand.forward(palm, angles);
    const MatrixX back = hand.angles_from_joints(palm, joints);
    for (int m = 0; m < M; ++m) {
      EXPECT_NEAR((joints[m * (N + 1)] - hand.root(palm, m)).norm(), 0.0, 1e-14);  // tail on the root
      const FingerPlane pl = hand.plane(palm, m);
      for (int n = 0; n <= N; ++n) EXPECT_NEAR((joints[m * (N + 1) + n] - pl.origin).dot(pl.normal()), 0.0, 1e-14);
      for (int n = 0; n < N; ++n) {
        EXPECT_NEAR((joints[m * (N + 1) + n + 1] - joints[m * (N + 1) + n]).norm(), lengths(m, n), 1e-14);
        EXPECT_NEAR(std::remainder(back(m, n) - angles(m, n), 2 * kPi), 0.0, 1e-9);
      }
    }
  }
}

TEST(Kinematics, ConventionsOfDesignSection2) {
  const HandModel hand = HandModel::uniform(4, 3, 0.02, 0.0, 0.03, 0.01);
  const Pose palm = Pose::Identity();
  // finger 0's root on +x, fingers counter-clockwise about z
  EXPECT_TRUE(hand.root(palm, 0).isApprox(Vec3(0.03, 0, 0)));
  EXPECT_NEAR(hand.root(palm, 1).y(), 0.03, 1e-15);
  // extended finger points along the palm normal
  const auto ext = hand.forward(palm, MatrixX::Zero(4, 3));
  EXPECT_TRUE(ext[3].isApprox(Vec3(0.03, 0, 0.06)));
  // positive flexion turns toward the palm axis (-u)
  MatrixX a = MatrixX::Zero(4, 3);
  a(0, 0) = 0.5;
  EXPECT_LT(hand.forward(palm, a)[1].x(), 0.03);
}

TEST(Kinematics, RejectsBadHands) {
  EXPECT_THROW(HandModel::uniform(0, 3, 0.02, 0.0, 0.03, 0.01), std::invalid_argument);
  EXPECT_THROW(HandModel::uniform(3, 0, 0.02, 0.0, 0.03, 0.01), std::invalid_argument);
  EXPECT_THROW(HandModel::uniform(3, 3, -0.02, 0.0, 0.03, 0.01), std::invalid_argument);
  EXPECT_THROW(HandModel::uniform(3, 3, 0.02, -0.001, 0.03, 0.01), std::invalid_argument);
  EXPECT_THROW(HandModel::uniform(3, 3, 0.02, 0.0, 0.0, 0.01), std::invalid_argument);
  EXPECT_THROW(HandModel::uniform(3, 3, 0.02, 0.0, 0.03, std::nan("")), std::invalid_argument);
  EXPECT_THROW(HandModel::uniform(3, 3, 0.005, 0.003, 0.03, 0.01), std::invalid_argument);  // links overlap
  EXPECT_THROW(HandModel::uniform(32, 3, 0.02, 0.004, 0.03, 0.01), std::invalid_argument);  // roots collide
}
