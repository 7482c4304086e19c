// Geometry primitives against brute force.
#include <gtest/gtest.h>

#include <random>

#include "hugger/geometry/distance.hpp"
#include "meshes.hpp"

using namespace hugger;

namespace {

double brute_point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  double best = kInf;
  const int n = 200;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double u = double(i) / n, v = double(j) / n;
      best = std::min(best, (a + u * (b - a) + v * (c - a) - p).norm());
    }
  return best;
}

}  // namespace

TEST(Geometry, ClosestPointOnTriangleMatchesSampling) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 60; ++trial) {
    const Vec3 a(U(rng), U(rng), U(rng)), b(U(rng), U(rng), U(rng)), c(U(rng), U(rng), U(rng));
    const Vec3 p(2 * U(rng), 2 * U(rng), 2 * U(rng));
    const Vec3 q = closest_point_on_triangle(p, a, b, c);
    const double exact = (q - p).norm();
    const double sampled = brute_point_triangle(p, a, b, c);
    EXPECT_LE(exact, sampled + 1e-12);
    EXPECT_NEAR(exact, sampled, 0.02);  // the sampling grid is 1/200 of the triangle
  }
}

TEST(Geometry, SegmentSegmentMatchesSampling) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 p1(U(rng), U(rng), U(rng)), q1(U(rng), U(rng), U(rng)), p2(U(rng), U(rng), U(rng)),
        q2(U(rng), U(rng), U(rng));
    Vec3 c1, c2;
    const double d = std::sqrt(segment_segment_squared(p1, q1, p2, q2, &c1, &c2));
    EXPECT_NEAR(d, (c1 - c2).norm(), 1e-12);
    double best = kInf;
    for (int i = 0; i <= 400; ++i)
      for (int j = 0; j <= 400; j += 1) {
        if (j % 4 && i % 4) continue;
        best = std::min(best, (p1 + (q1 - p1) * (i / 400.0) - p2 - (q2 - p2) * (j / 400.0)).norm());
      }
    EXPECT_LE(d, best + 1e-12);
    EXPECT_NEAR(d, best, 0.02);
  }
}

TEST(Geometry, SegmentSegment2dAgreesWith3d) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec2 a(U(rng), U(rng)), b(U(rng), U(rng)), c(U(rng), U(rng)), d(U(rng), U(rng));
    const double d2 = segment_segment_squared_2d(a, b, c, d);
    const double d3 = segment_segment_squared(Vec3(a.x(), a.y(), 0), Vec3(b.x(), b.y(), 0), Vec3(c.x(), c.y(), 0),
                                              Vec3(d.x(), d.y(), 0));
    EXPECT_NEAR(d2, d3, 1e-14);
  }
}

TEST(Geometry, SegmentTriangleMatchesSampling) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(-1, 1);
  int crossings = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Vec3 a(U(rng), U(rng), U(rng)), b(U(rng), U(rng), U(rng)), c(U(rng), U(rng), U(rng));
    const Vec3 p(U(rng), U(rng), U(rng)), q(U(rng), U(rng), U(rng));
    Vec3 s, t;
    TriangleFeature f;
    const double d = std::sqrt(segment_triangle_squared(p, q, a, b, c, &s, &t, &f));
    EXPECT_NEAR(d, (s - t).norm(), 1e-12);
    double best = kInf;
    for (int i = 0; i <= 100; ++i) best = std::min(best, brute_point_triangle(p + (q - p) * (i / 100.0), a, b, c));
    if (d == 0.0) ++crossings;
    EXPECT_LE(d, best + 1e-12);
    EXPECT_NEAR(d, best, 0.03);
  }
  EXPECT_GT(crossings, 0);  // the sample includes crossing segments
}
