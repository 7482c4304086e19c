// The object's sensing queries (BVH, signs, inside, sections) against brute force and analytic shapes.
#include <string>
#include <gtest/gtest.h>

#include <random>

#include "hugger/geometry/order.hpp"
#include "hugger/world/object.hpp"
#include "hugger/world/simulated_world.hpp"
#include "meshes.hpp"

using namespace hugger;

namespace {

double brute_segment_mesh(const test::Mesh& m, const Vec3& a, const Vec3& b) {
  double best = kInf;
  for (int f = 0; f < m.faces.rows(); ++f) {
    Vec3 s, t;
    TriangleFeature ft;
    best = std::min(best, segment_triangle_squared(a, b, m.vertices.row(m.faces(f, 0)), m.vertices.row(m.faces(f, 1)),
                                                   m.vertices.row(m.faces(f, 2)), &s, &t, &ft));
  }
  return std::sqrt(best);
}

}  // namespace

TEST(Object, NearestMatchesLinearScan) {
  const auto mesh = test::icosphere(3, Vec3(0.05, 0.04, 0.03));
  const Object obj(mesh.vertices, mesh.faces);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-0.08, 0.08);
  for (int trial = 0; trial < 300; ++trial) {
    const Vec3 a(U(rng), U(rng), U(rng));
    const Vec3 b = trial % 3 == 0 ? a : Vec3(a + 0.3 * Vec3(U(rng), U(rng), U(rng)));
    const SignedNearest sn = obj.nearest(a, b);
    const double brute = brute_segment_mesh(mesh, a, b);
    EXPECT_NEAR(std::abs(sn.signed_distance), brute, 1e-12) << trial;
  }
}

TEST(Object, ClearanceQueriesMatchLinearScan) {
  // any_within and capsule_clear against brute force, on segments placed near the surface (the
  // planner's case: distances within a few radii), both with and without a known-outside start.
  const auto mesh = test::icosphere(3, Vec3(0.05, 0.04, 0.03));
  const Object obj(mesh.vertices, mesh.faces);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0), R(0.0, 0.006);
  int near = 0, outside = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const Vec3 dir = Vec3(U(rng), U(rng), U(rng)).normalized();
    const Vec3 a = obj.nearest(dir, dir).on_object + (0.004 * U(rng)) * dir;  // about the surface
    const Vec3 b = trial % 4 == 0 ? a : Vec3(a + 0.02 * Vec3(U(rng), U(rng), U(rng)).normalized());
    const double radius = R(rng);
    const double brute = brute_segment_mesh(mesh, a, b);
    if (std::abs(brute - radius) < 1e-9) continue;  // too close to call in floating point
    near += brute < 2.0 * radius;
    EXPECT_EQ(obj.bvh().any_within(a, b, radius), brute < radius) << trial;
    const bool a_in = obj.inside(a);
    const bool clear = brute > radius && !a_in;
    EXPECT_EQ(obj.capsule_clear(a, b, radius), clear) << trial;
    if (!a_in) {
      ++outside;
      EXPECT_EQ(obj.capsule_clear(a, b, radius, /*a_outside=*/true), clear) << trial;
    }
  }
  EXPECT_GT(near, 100);
  EXPECT_GT(outside, 200);
}

// The tree built on two threads is the tree built on one (node for node, leaves in the same
// order), on meshes of several sizes and shapes; a different tree is told apart.
TEST(TriangleBvh, TwoThreadsBuildTheSameTree) {
  for (const test::Mesh& m : {test::icosphere(2, Vec3(0.05, 0.04, 0.03)), test::icosphere(5, Vec3(0.05, 0.04, 0.03)),
                              test::curvy(4)}) {
    const TriangleBvh one(m.vertices, m.faces, 8, 1), two(m.vertices, m.faces, 8, 2), chosen(m.vertices, m.faces);
    EXPECT_TRUE(one.same_tree(two)) << m.faces.rows() << " triangles";
    EXPECT_TRUE(one.same_tree(chosen)) << m.faces.rows() << " triangles";
    const TriangleBvh coarser(m.vertices, m.faces, 4, 2);
    EXPECT_FALSE(one.same_tree(coarser));
  }
}

// Splitting by selection and by presorted lists finds the same halves and leaves in the same
// order: the tree is the same wherever the build switches from one to the other (all selection,
// all presorted, and switches at several depths), on one thread or two, on meshes with many tied
// centres (an axis-aligned box, a sphere) and without.
TEST(TriangleBvh, SelectionAndPresortedListsBuildTheSameTree) {
  for (const test::Mesh& m : {test::icosphere(5, Vec3(0.05, 0.05, 0.05)), test::curvy(4), test::box(Vec3(0.03, 0.02, 0.01)),
                              test::torus(0.05, 0.02, 128, 64), test::cylinder(0.03, 0.05, 48)}) {
    const TriangleBvh reference(m.vertices, m.faces, 8, 1);
    for (int presorted : {0, 1, 9, 100, 5000, 1 << 30})
      for (int threads : {1, 2}) {
        const TriangleBvh other(m.vertices, m.faces, 8, threads, presorted);
        EXPECT_TRUE(reference.same_tree(other)) << m.faces.rows() << " triangles, presorted " << presorted << ", "
                                                << threads << " thread(s)";
      }
  }
}

// ascending_order (the BVH build's, the joining of points') is a comparison sort by (value, index), over values with
// many ties, both zeros, subnormals, infinities and values of every magnitude and sign.
TEST(Order, AscendingOrderIsSortByValueThenIndex) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 9);
  const double specials[] = {0.0, -0.0, 5e-324, -5e-324, 2.2e-308, kInf, -kInf, 1e300, -1e300, 0.25};
  for (int n : {0, 1, 2, 7, 100, 5000, 40000}) {
    std::vector<double> values(static_cast<std::size_t>(n));
    for (double& v : values) {
      const int kind = pick(rng);
      if (kind < 3) v = specials[pick(rng)];                        // ties and edge cases
      else if (kind < 5) v = std::ldexp(unit(rng), pick(rng) * 60 - 300);  // any magnitude
      else v = std::round(unit(rng) * 50.0) / 50.0;                 // a few distinct values, tied
    }
    std::vector<int> expected(values.size());
    for (int i = 0; i < n; ++i) expected[i] = i;
    std::sort(expected.begin(), expected.end(),
              [&](int a, int b) { return values[a] < values[b] || (values[a] == values[b] && a < b); });
    EXPECT_EQ(ascending_order(values), expected) << n << " values";
    // Values alike in their high bits (the radix passes' digits), differing in the low ones only:
    // long runs, in falling order of index, that the whole keys must put in order.
    std::vector<double> alike(values.size());
    for (int i = 0; i < n; ++i)
      alike[i] = std::ldexp(1.0 + std::ldexp(static_cast<double>((n - i) % 97 + (pick(rng) < 2 ? 0 : 3 * (i % 5))), -45),
                            pick(rng) < 8 ? -3 : -4) * (pick(rng) < 9 ? 1.0 : -1.0);
    for (int i = 0; i < n; ++i) expected[i] = i;
    std::sort(expected.begin(), expected.end(),
              [&](int a, int b) { return alike[a] < alike[b] || (alike[a] == alike[b] && a < b); });
    EXPECT_EQ(ascending_order(alike), expected) << n << " values alike in their high bits";
    // Unsigned integers: many ties, and values that differ in one digit of the sort only.
    std::vector<std::uint32_t> whole(static_cast<std::size_t>(n));
    for (std::uint32_t& w : whole) w = pick(rng) < 5 ? static_cast<std::uint32_t>(pick(rng)) << (11 * pick(rng) % 32) : static_cast<std::uint32_t>(rng());
    for (int i = 0; i < n; ++i) expected[i] = i;
    std::stable_sort(expected.begin(), expected.end(), [&](int a, int b) { return whole[a] < whole[b]; });
    EXPECT_EQ(ascending_order(whole), expected) << n << " integers";
  }
}

TEST(Object, SignAgreesWithRayParityAndAnalyticEllipsoid) {
  const Vec3 radii(0.05, 0.04, 0.03);
  const auto mesh = test::icosphere(4, radii);
  const Object obj(mesh.vertices, mesh.faces);
  const TriangleBvh bvh(mesh.vertices, mesh.faces);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> U(-0.07, 0.07);
  int inside = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const Vec3 p(U(rng), U(rng), U(rng));
    const double level = p.cwiseQuotient(radii).squaredNorm();
    if (std::abs(level - 1.0) < 0.05) continue;  // too close to call against the faceted mesh
    const bool analytic = level < 1.0;
    const bool parity = bvh.ray_crossings(p, Vec3(0.5377, 0.8622, 0.3188).normalized()) % 2 == 1;
    EXPECT_EQ(obj.inside(p), analytic) << trial;
    EXPECT_EQ(parity, analytic) << trial;
    EXPECT_EQ(obj.nearest(p, p).signed_distance < 0.0, analytic);
    inside += analytic;
  }
  EXPECT_GT(inside, 20);
}

// Every refusal, on a mesh small enough to be checked on the calling thread and one whose checks
// run on a second thread beside the BVH (4,096 triangles or more: the error is rethrown).
TEST(Object, RejectsBadMeshes) {
  for (const test::Mesh& mesh : {test::icosphere(1), test::icosphere(4)}) {
    auto expect_invalid = [](const PointsN3& v, const FacesN3& f, const std::string& what) {
      try {
        Object o(v, f);
        ADD_FAILURE() << "accepted: " << what;
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      }
    };
    expect_invalid(PointsN3(0, 3), FacesN3(0, 3), "empty");
    PointsN3 nan = mesh.vertices;
    nan(3, 1) = std::numeric_limits<double>::quiet_NaN();
    expect_invalid(nan, mesh.faces, "not finite");
    FacesN3 out_of_range = mesh.faces;
    out_of_range(2, 2) = mesh.vertices.rows() + 1000;
    expect_invalid(mesh.vertices, out_of_range, "outside");
    FacesN3 open = mesh.faces.topRows(mesh.faces.rows() - 1);
    expect_invalid(mesh.vertices, open, "not closed");
    FacesN3 flipped = mesh.faces;
    std::swap(flipped(0, 1), flipped(0, 2));
    expect_invalid(mesh.vertices, flipped, "consistently oriented");
    FacesN3 inward = mesh.faces;
    inward.col(1).swap(inward.col(2));
    expect_invalid(mesh.vertices, inward, "inward");
    // A face of zero area: one vertex moved onto another.
    PointsN3 flat = mesh.vertices;
    flat.row(mesh.faces(0, 0)) = flat.row(mesh.faces(0, 1));
    expect_invalid(flat, mesh.faces, "degenerate: zero area");
    // The same triangle twice over three new coincident vertices (a zero-volume pillow).
    {
      const Eigen::Index n = mesh.vertices.rows(), m = mesh.faces.rows();
      PointsN3 v(n + 3, 3);
      v << mesh.vertices, mesh.vertices.row(mesh.faces(0, 0)), mesh.vertices.row(mesh.faces(0, 1)),
          mesh.vertices.row(mesh.faces(0, 2));
      FacesN3 f(m + 2, 3);
      f << mesh.faces, n, n + 1, n + 2, n, n + 2, n + 1;
      expect_invalid(v, f, "same triangle");
      // The same over three new vertices of their own (nothing coincides): the same indices twice.
      v.bottomRows(3) *= 1.5;
      expect_invalid(v, f, "same triangle");
    }
    // Two spheres sharing one vertex: the surface touches itself there (two fans of faces).
    {
      const Eigen::Index n = mesh.vertices.rows(), m = mesh.faces.rows();
      Eigen::Index i = 0, j = 0;
      mesh.vertices.col(0).maxCoeff(&i);
      mesh.vertices.col(0).minCoeff(&j);
      PointsN3 v(2 * n, 3);
      v.topRows(n) = mesh.vertices;
      v.bottomRows(n) = mesh.vertices.rowwise() + (mesh.vertices.row(i) - mesh.vertices.row(j));
      FacesN3 f(2 * m, 3);
      f.topRows(m) = mesh.faces;
      f.bottomRows(m) = mesh.faces.array() + n;
      for (Eigen::Index r = m; r < 2 * m; ++r)
        for (int k = 0; k < 3; ++k)
          if (f(r, k) == j + n) f(r, k) = i;
      expect_invalid(v, f, "not manifold at vertex " + std::to_string(i) + ": 2 separate fans");
    }
  }
}

TEST(Section, SphereSectionIsACircle) {
  const double R = 0.04;
  const auto mesh = test::icosphere(5, Vec3::Constant(R));
  const Object obj(mesh.vertices, mesh.faces);
  std::mt19937 rng(7);
  for (int trial = 0; trial < 10; ++trial) {
    const Vec3 n = test::random_unit(rng);
    const double offset = 0.6 * R * (trial / 10.0);
    const Vec3 u = n.unitOrthogonal(), v = n.cross(u);
    const Section s = obj.section(offset * n, u, v);
    ASSERT_EQ(s.loops().size(), 1u);
    const double rho = std::sqrt(R * R - offset * offset);
    EXPECT_NEAR(s.area(), kPi * rho * rho, 0.01 * kPi * rho * rho);  // > 0: counter-clockwise
    EXPECT_NEAR(s.perimeter(), 2 * kPi * rho, 0.01 * 2 * kPi * rho);
    for (const Vec2& p : s.loops()[0]) EXPECT_NEAR(p.norm(), rho, 2e-4);
    for (int k = 0; k < 20; ++k) {
      const Vec2 q(0.03 * std::cos(k), 0.05 * std::sin(2.0 * k));
      EXPECT_NEAR(s.boundary_distance(q), std::abs(q.norm() - rho), 2e-4);
      if (std::abs(q.norm() - rho) > 1e-3) {
        EXPECT_EQ(s.inside(q), q.norm() < rho);
      }
    }
  }
}

TEST(Section, EllipsoidSectionIsAnEllipse) {
  const Vec3 radii(0.05, 0.03, 0.02);
  const auto mesh = test::icosphere(5, radii);
  const Object obj(mesh.vertices, mesh.faces);
  // The plane z = 0 cuts the ellipse x^2/a^2 + y^2/b^2 = 1.
  const Section s = obj.section(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY());
  ASSERT_EQ(s.loops().size(), 1u);
  EXPECT_NEAR(s.area(), kPi * 0.05 * 0.03, 0.01 * kPi * 0.05 * 0.03);
  for (const Vec2& p : s.loops()[0]) EXPECT_NEAR(std::hypot(p.x() / 0.05, p.y() / 0.03), 1.0, 5e-3);
  // The plane y = 0 (u = z, v = x) cuts x^2/a^2 + z^2/c^2 = 1.
  const Section t = obj.section(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX());
  EXPECT_NEAR(t.area(), kPi * 0.05 * 0.02, 0.01 * kPi * 0.05 * 0.02);
}

TEST(SimulatedWorld, CapsuleAndPalmGapsMatchGeometry) {
  const double R = 0.04;
  const auto mesh = test::icosphere(5, Vec3::Constant(R));
  auto obj = std::make_shared<Object>(mesh.vertices, mesh.faces);
  SimulatedWorld world(obj);
  std::mt19937 rng(8);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 d = test::random_unit(rng);
    const double h = 0.005 + 0.02 * trial / 50.0;
    // a capsule tangent to the sphere's normal direction at distance h from the surface
    const Vec3 t = d.unitOrthogonal();
    const Touch touch = world.capsule((R + h) * d - 0.01 * t, (R + h) * d + 0.01 * t, 0.002);
    EXPECT_NEAR(touch.gap, h - 0.002, 2e-4);  // the mesh is inscribed: at most 0.2 mm farther
    EXPECT_GT(touch.normal.dot(d), 0.99);
    // the palm facing the sphere's centre at distance h
    Pose palm = Pose::Identity();
    palm.linear().col(2) = -d;
    palm.linear().col(0) = t;
    palm.linear().col(1) = (-d).cross(t);
    palm.translation() = (R + h) * d;
    EXPECT_NEAR(world.palm(palm, 0.03, 0.01), h, 2e-4);
  }
  // inside: negative
  EXPECT_LT(world.capsule(Vec3::Zero(), Vec3(0.001, 0, 0), 0.0).gap, 0.0);
  Pose inside = Pose::Identity();
  EXPECT_LT(world.palm(inside, 0.01, 0.005), 0.0);
}
