// Geometry primitives against brute force.
#include <gtest/gtest.h>

#include <random>

#include "hugger/geometry/distance.hpp"
#include "hugger/geometry/harmonic.hpp"
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

// surely_empty (the region build's quick answer for a vertex's arc) says "empty" only where
// allowed_intervals finds no angle, and says it for nearly every set that allows none: random
// sets of arcs, and pairs of arcs that overlap, touch or miss by 1e-14 to 1e-6 rad (where the
// margin must keep it from answering).
TEST(Harmonic, SurelyEmptyOnlyWhereNoAngleIsAllowed) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double two_pi = 2.0 * kPi;
  // The constraint allowing the arc of half-angle w about angle theta, scaled by `scale`.
  auto arc = [](double theta, double w, double scale) {
    return Harmonic{scale * std::cos(w), -scale * std::cos(theta), -scale * std::sin(theta)};
  };
  int empty = 0, caught = 0, near_pairs = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<Harmonic> hs;
    const bool pair = trial % 2 == 1;
    if (pair) {
      // Two arcs whose ends meet, apart by a gap of -1e-6 .. 1e-6 rad (negative: they overlap).
      const double theta = two_pi * unit(rng), w1 = 0.01 + 1.5 * unit(rng), w2 = 0.01 + 1.5 * unit(rng);
      const double gap = (unit(rng) < 0.5 ? -1.0 : 1.0) * std::pow(10.0, -14.0 + 8.0 * unit(rng));
      hs.push_back(arc(theta, w1, 0.1 + unit(rng)));
      hs.push_back(arc(theta + w1 + gap + w2, w2, 1e-3 + unit(rng)));
      ++near_pairs;
    } else {
      const int n = 1 + static_cast<int>(8 * unit(rng));
      for (int i = 0; i < n; ++i) {
        const double c = -1.2 + 2.4 * unit(rng);  // k0 / A: past +-1 the arc is all or nothing
        const double A = std::pow(10.0, -3.0 + 4.0 * unit(rng)), t = two_pi * unit(rng);
        hs.push_back({c * A, A * std::cos(t), A * std::sin(t)});
      }
    }
    const int n = static_cast<int>(hs.size());
    const bool quick = surely_empty(hs.data(), n);
    const bool none = allowed_intervals(hs.data(), n).empty();
    if (quick) EXPECT_TRUE(none) << "trial " << trial << ": surely_empty, but allowed_intervals finds angles";
    if (none && !pair) {
      ++empty;
      caught += quick ? 1 : 0;
    }
  }
  EXPECT_GT(near_pairs, 5000);
  EXPECT_GT(empty, 3000);
  EXPECT_GE(caught, 0.99 * empty) << caught << " of " << empty << " empty sets answered quickly";
}
