// Geometry primitives against brute force.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "hugger/geometry/distance.hpp"
#include "hugger/geometry/harmonic.hpp"
#include "hugger/geometry/next.hpp"
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

TEST(Geometry, NextUpAndTowardZeroAreNextafterToTheBit) {
  const double big = std::numeric_limits<double>::max(), tiny = std::numeric_limits<double>::denorm_min();
  std::vector<double> xs = {0.0, -0.0, tiny, -tiny, 1.0, -1.0, big, -big, kInf, -kInf,
                            std::numeric_limits<double>::min(), -std::numeric_limits<double>::min(),
                            std::numeric_limits<double>::quiet_NaN()};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mant(-1.0, 1.0);
  std::uniform_int_distribution<int> exps(-1074, 1023);
  for (int i = 0; i < 20000; ++i) xs.push_back(std::ldexp(mant(rng), exps(rng)));
  for (double x : xs) {
    EXPECT_EQ(bits_of(next_up(x)), bits_of(std::nextafter(x, kInf))) << x;
    EXPECT_EQ(bits_of(next_toward_zero(x)), bits_of(std::nextafter(x, 0.0))) << x;
  }
}

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
// allowed_intervals finds no angle, and says it for nearly every random set that allows none.
// The sets, by kind: random arcs; pairs of arcs whose ends overlap, touch or miss by 1e-14 to
// 1e-6 rad (below ~1e-9 the margin must keep it from answering); narrow arcs (half-angles 1e-8
// to 5e-3) beside a neighbour within 1e-8 rad; arcs of nearly the whole circle (1 + cos of the
// half-angle down to 1e-16) with one in or across their gap; constraints without amplitude
// beside arcs ending on multiples of pi/4; 19 to 40 arcs about one direction; 36 nearly whole
// arcs with disjoint gaps (37 intervals) and a probe in or near a gap. Each set also with every
// constraint scaled by its own factor, tiny (2^-545 to 2^-430) or huge (2^490 to 2^521), where
// surely_empty leaves some of them out (a positive factor changes no constraint's arc).
TEST(Harmonic, SurelyEmptyOnlyWhereNoAngleIsAllowed) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double two_pi = 2.0 * kPi;
  auto log_uniform = [&](double lo, double hi) { return lo * std::pow(hi / lo, unit(rng)); };
  auto sign = [&] { return unit(rng) < 0.5 ? -1.0 : 1.0; };
  // The constraint allowing the arc of half-angle w about angle theta, scaled by `scale`.
  auto arc = [](double theta, double w, double scale) {
    return Harmonic{scale * std::cos(w), -scale * std::cos(theta), -scale * std::sin(theta)};
  };
  constexpr int kKinds = 7;
  int empty = 0, caught = 0;
  int none_of_kind[kKinds] = {}, some_of_kind[kKinds] = {}, quick_of_kind[kKinds] = {};
  for (int trial = 0; trial < 35000; ++trial) {
    std::vector<Harmonic> hs;
    const int kind = trial % kKinds;
    if (kind == 0) {  // random
      const int n = 1 + static_cast<int>(8 * unit(rng));
      for (int i = 0; i < n; ++i) {
        const double c = -1.2 + 2.4 * unit(rng);  // k0 / A: past +-1 the arc is all or nothing
        const double A = std::pow(10.0, -3.0 + 4.0 * unit(rng)), t = two_pi * unit(rng);
        hs.push_back({c * A, A * std::cos(t), A * std::sin(t)});
      }
    } else if (kind == 1) {  // two arcs whose ends meet, apart by -1e-6 .. 1e-6 rad (< 0: overlap)
      const double theta = two_pi * unit(rng), w1 = 0.01 + 1.5 * unit(rng), w2 = 0.01 + 1.5 * unit(rng);
      const double gap = sign() * log_uniform(1e-14, 1e-6);
      hs.push_back(arc(theta, w1, 0.1 + unit(rng)));
      hs.push_back(arc(theta + w1 + gap + w2, w2, 1e-3 + unit(rng)));
    } else if (kind == 2) {  // a narrow arc beside a neighbour
      const double theta = two_pi * unit(rng), w1 = log_uniform(1e-8, 5e-3), w2 = log_uniform(1e-8, 1.5);
      const double gap = sign() * log_uniform(1e-13, 1e-8);
      hs.push_back(arc(theta, w1, 0.1 + unit(rng)));
      hs.push_back(arc(theta + w1 + gap + w2, w2, 0.1 + unit(rng)));
    } else if (kind == 3) {  // nearly the whole circle, and an arc in (or across) its gap
      const double theta = two_pi * unit(rng), w1 = std::acos(-1.0 + log_uniform(1e-16, 1e-4));
      const double gap = kPi - w1, w2 = gap * (0.2 + 0.6 * unit(rng));
      const double off = (gap - w2) * (1.0 + sign() * log_uniform(1e-9, 1e-2));  // from the gap's middle
      hs.push_back(arc(theta, w1, 0.1 + unit(rng)));
      hs.push_back(arc(theta + kPi + sign() * off, w2, 0.1 + unit(rng)));
    } else if (kind == 4) {  // arcs ending on multiples of pi/4, and constraints without amplitude
      const int n = 1 + static_cast<int>(4 * unit(rng));
      for (int i = 0; i < n; ++i) {
        const int a = static_cast<int>(8 * unit(rng)), b = 1 + static_cast<int>(4 * unit(rng));
        hs.push_back(arc((a + 0.5 * b) * kPi / 4.0, 0.5 * b * kPi / 4.0, 0.1 + unit(rng)));
      }
      hs.insert(hs.begin() + static_cast<long>(unit(rng) * hs.size()), Harmonic{unit(rng) < 0.8 ? -1.0 : 1.0, 0.0, 0.0});
    } else if (kind == 5) {  // many constraints: arcs about one direction, some missing it
      const int n = 19 + static_cast<int>(22 * unit(rng));
      const double theta = two_pi * unit(rng);
      for (int i = 0; i < n; ++i) {
        const double w = 0.05 + 1.4 * unit(rng), off = (unit(rng) < 0.97 ? 0.9 : 1.05) * w * sign() * unit(rng);
        hs.push_back(arc(theta + off, w, 0.1 + unit(rng)));
      }
      // Half of them with an arc on the far side too (most of those allow no angle).
      if (unit(rng) < 0.5) hs.back() = arc(theta + kPi + 0.3 * (2.0 * unit(rng) - 1.0), 0.05 + 1.35 * unit(rng), 1.0);
    } else {  // 36 gaps cut from the circle, then a probe about one of them
      constexpr int kGaps = 36;
      const double cell = two_pi / kGaps, turn = two_pi * unit(rng);
      double centre[kGaps], width[kGaps];
      for (int i = 0; i < kGaps; ++i) {
        width[i] = cell * (0.05 + 0.45 * unit(rng));
        centre[i] = turn + cell * i + 0.2 * cell * (2.0 * unit(rng) - 1.0);
        hs.push_back(arc(centre[i] + kPi, kPi - 0.5 * width[i], 0.1 + unit(rng)));
      }
      const int j = static_cast<int>(kGaps * unit(rng));
      const double w = 0.5 * width[j] * log_uniform(0.05, 3.0), off = sign() * width[j] * unit(rng);
      hs.push_back(arc(centre[j] + off, w, 0.1 + unit(rng)));
    }
    const int n = static_cast<int>(hs.size());
    for (int variant = 0; variant < 3; ++variant) {
      std::vector<Harmonic> scaled = hs;
      for (Harmonic& h : scaled) {
        // Each constraint its own factor (not a power of two): about 2^-545 .. 2^-430 (the
        // squares turn subnormal below about 2^-511) or 2^490 .. 2^521 (they overflow above
        // 2^512), either side of where surely_empty leaves a constraint out.
        const double f = variant == 0 ? 1.0
                                      : std::ldexp(1.0 + unit(rng), variant == 1 ? -545 + static_cast<int>(115 * unit(rng))
                                                                                 : 490 + static_cast<int>(31 * unit(rng)));
        h = {h.k0 * f, h.k1 * f, h.k2 * f};
      }
      const bool quick = surely_empty(scaled.data(), n);
      const bool none = allowed_intervals(scaled.data(), n).empty();
      if (quick) {
        EXPECT_TRUE(none) << "kind " << kind << ", trial " << trial << ", variant " << variant
                          << ": surely_empty, but allowed_intervals finds angles";
      }
      if (variant != 0) continue;
      ++(none ? none_of_kind : some_of_kind)[kind];
      quick_of_kind[kind] += quick ? 1 : 0;
      if (kind == 0 && none) {
        ++empty;
        caught += quick ? 1 : 0;
      }
    }
  }
  // Every kind has sets with and without angles, and sets surely_empty answers.
  for (int kind = 0; kind < kKinds; ++kind) {
    EXPECT_GT(none_of_kind[kind], 100) << "kind " << kind;
    EXPECT_GT(some_of_kind[kind], 100) << "kind " << kind;
    EXPECT_GT(quick_of_kind[kind], kind == 2 ? 0 : 50) << "kind " << kind;  // narrow arcs: mostly left out
  }
  EXPECT_GT(empty, 1500);
  EXPECT_GE(caught, 0.99 * empty) << caught << " of " << empty << " empty random sets answered quickly";
}
