// Hand model: forward kinematics and the inverse (angles from joints) round trip.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "hugger/geometry/distance.hpp"
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

// planar_angles wraps each relative angle into [-pi, pi] by one exact turn: the same bits as
// std::remainder(rel, 2 pi), the sign of a zero included, on random chains and on chains whose
// links point along the axes (absolute angles of exactly 0, +-pi/2 and +-pi, differences of +-pi
// and +-2 pi).
TEST(Kinematics, PlanarAnglesMatchRemainderBitForBit) {
  long wrapped = 0, turns = 0, negative_zeros = 0;  // the edge cases, counted to show they ran
  auto reference = [&](const std::vector<Vec2>& j, std::vector<double>* out) {
    double prev = 0.0;
    for (std::size_t n = 0; n + 1 < j.size(); ++n) {
      const Vec2 d = j[n + 1] - j[n];
      const double abs_angle = std::atan2(-d.x(), d.y());
      const double rel = abs_angle - prev;
      wrapped += std::abs(rel) > kPi;
      turns += std::abs(rel) == 2.0 * kPi;
      out->push_back(std::remainder(rel, 2.0 * kPi));
      negative_zeros += out->back() == 0.0 && std::signbit(out->back());
      prev = abs_angle;
    }
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  // Joints on a lattice that holds signed zeros: links along the axes, with -0.0 - +0.0 = -0.0
  // giving the direction whose absolute angle is +pi, and +0.0 - +0.0 the one at -pi.
  const double xs[4] = {-0.0, 0.0, -1.0, 1.0}, ys[4] = {-1.0, 0.0, 1.0, 2.0};
  std::uniform_int_distribution<int> pick(0, 3);
  long compared = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<Vec2> j;
    for (int n = 0; n <= 6; ++n)
      j.push_back(trial % 2 ? Vec2(xs[pick(rng)], ys[pick(rng)]) : Vec2(U(rng), U(rng)));
    std::vector<double> want;
    reference(j, &want);
    double got[6];
    HandModel::planar_angles(j, got);
    for (int n = 0; n < 6; ++n) {
      ++compared;
      EXPECT_EQ(std::memcmp(&got[n], &want[n], sizeof(double)), 0) << got[n] << " vs " << want[n];
    }
  }
  EXPECT_EQ(compared, 120000);
  EXPECT_GT(wrapped, 1000);
  EXPECT_GT(turns, 0);
  EXPECT_GT(negative_zeros, 0);
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

// plane_pair's bound: points of two finger planes at signed distances s_a, s_b from the line
// where the planes meet are at least sqrt(sin2) max(|s_a|, |s_b|) apart; so are segments, by
// apart_from_line's distances. Random planes (the rim hand's, sharing the palm axis, and general
// ones), random segments in each, against the segments' distance in the world.
TEST(Kinematics, PlanePairBoundsTheDistanceOfSegmentsInTwoPlanes) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> U(-1, 1);
  int bounded = 0, tight = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    FingerPlane pl[2];
    const bool rim = trial % 2 == 0;  // both through one axis, as the rim hand's planes
    const Pose palm = random_pose(rng);
    for (FingerPlane& f : pl) {
      const double phi = 3.2 * U(rng);
      const Vec3 u_local(std::cos(phi), std::sin(phi), 0.0);
      f.u = palm.linear() * u_local;
      f.p = palm.linear().col(2);
      f.origin = palm.translation() + (rim ? Vec3::Zero() : Vec3(palm.linear() * Vec3(0.05 * U(rng), 0.05 * U(rng), 0.0)));
      if (!rim) {  // a general plane: its own tilt about u
        const Eigen::AngleAxisd tilt(0.6 * U(rng), f.u);
        f.p = tilt * f.p;
      }
    }
    const PlanePair ab = plane_pair(pl[0], pl[1]), ba = plane_pair(pl[1], pl[0]);
    EXPECT_NEAR(ab.sin2, ba.sin2, 1e-12);
    if (ab.sin2 == 0.0) continue;
    ++bounded;
    Vec2 sa[2], sb[2];
    for (Vec2& x : sa) x = Vec2(0.08 * U(rng), 0.08 * U(rng));
    for (Vec2& x : sb) x = Vec2(0.08 * U(rng), 0.08 * U(rng));
    const double d = std::max(apart_from_line(sa, 2, ab), apart_from_line(sb, 2, ba));
    const double world = std::sqrt(segment_segment_squared(pl[0].to_world(sa[0]), pl[0].to_world(sa[1]),
                                                           pl[1].to_world(sb[0]), pl[1].to_world(sb[1])));
    const double bound = std::sqrt(ab.sin2) * d;
    EXPECT_LE(bound, world * (1.0 + 1e-12) + 1e-13) << "trial " << trial;
    if (bound > 0.5 * world) ++tight;
    // On the line itself: a point of plane a there is at distance 0, and lies in plane b too.
    const Vec2 on = ab.offset * ab.w;  // w is a unit vector: w.on - offset = 0
    EXPECT_NEAR(apart_from_line(&on, 1, ab), 0.0, 1e-12);  // (coordinates of about 1 m)
    const Vec3 x = pl[0].to_world(on);
    EXPECT_NEAR((x - pl[1].origin).dot(pl[1].normal().normalized()), 0.0, 1e-12);
  }
  EXPECT_GT(bounded, 3500);  // parallel planes are rare
  EXPECT_GT(tight, 200);     // the bound is not vacuous
}

// planes_keep_apart, as fingers_clear asks it: the finger planes of general layouts (roots
// anywhere on the palm, directions anywhere in its plane: the planes meet in lines along the palm
// normal, off its axis) and of the rim hand, chains of 2 to 6 links, and a separation from a
// millimetre to 5 cm. Wherever it says apart, every pair of links is at least that far apart in
// the world; and it says so often, also where the links come within twice the separation.
TEST(Kinematics, PlanesKeepApartOnlyWhereTheLinksAreApartInTheWorld) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> U(-1, 1);
  int apart = 0, near = 0;
  for (int trial = 0; trial < 6000; ++trial) {
    const Pose palm = random_pose(rng);
    const bool rim = trial % 3 == 0;
    FingerPlane pl[2];
    for (FingerPlane& f : pl) {
      const double phi = 3.2 * U(rng);
      const Vec3 root = rim ? Vec3(0.03 * std::cos(phi), 0.03 * std::sin(phi), 0.0) : Vec3(0.03 * U(rng), 0.03 * U(rng), 0.0);
      const double psi = rim ? phi : 3.2 * U(rng);
      f.origin = palm * root;
      f.u = palm.linear() * Vec3(std::cos(psi), std::sin(psi), 0.0);
      f.p = palm.linear().col(2);
      // Plane coordinates from the root: the hand's own planes may put their origin elsewhere on
      // the plane, which the bound does not mind.
    }
    const PlanePair ab = plane_pair(pl[0], pl[1]), ba = plane_pair(pl[1], pl[0]);
    const int n = 3 + trial % 5;  // joints
    std::vector<Vec2> ca(n), cb(n);
    for (Vec2& x : ca) x = Vec2(0.06 * U(rng), 0.04 + 0.04 * U(rng));
    for (Vec2& x : cb) x = Vec2(0.06 * U(rng), 0.04 + 0.04 * U(rng));
    const double sep = 0.001 + 0.049 * (U(rng) + 1) / 2;
    double world = kInf;
    for (int i = 0; i + 1 < n; ++i)
      for (int j = 0; j + 1 < n; ++j)
        world = std::min(world, std::sqrt(segment_segment_squared(pl[0].to_world(ca[i]), pl[0].to_world(ca[i + 1]),
                                                                  pl[1].to_world(cb[j]), pl[1].to_world(cb[j + 1]))));
    if (planes_keep_apart(ab, ca.data(), n, ba, cb.data(), n, sep, 0.0)) {
      ++apart;
      EXPECT_GT(world, sep) << "trial " << trial;
      if (world < 2.0 * sep) ++near;
    }
  }
  EXPECT_GT(apart, 600) << near;
  EXPECT_GT(near, 60) << apart;
}
