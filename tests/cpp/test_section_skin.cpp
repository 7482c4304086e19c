// The section skin against the mesh world (the reference skin): clearance decisions, gaps and
// inside tests on random queries in random planes, and plans made with it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "hugger/planner/planner.hpp"
#include "hugger/world/section_skin.hpp"
#include "hugger/world/simulated_world.hpp"
#include "meshes.hpp"
#include "scenes.hpp"

using namespace hugger;

namespace {

constexpr double kFlatten = 2e-7;

/// A Wavefront OBJ (v and f lines; polygons fanned), or an empty mesh if the file is absent.
test::Mesh load_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) return {};
  std::vector<Vec3> v;
  std::vector<std::array<std::int64_t, 3>> f;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream is(line);
    std::string tag;
    is >> tag;
    if (tag == "v") {
      Vec3 p;
      is >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    } else if (tag == "f") {
      std::vector<std::int64_t> idx;
      std::string tok;
      while (is >> tok) idx.push_back(std::stoll(tok.substr(0, tok.find('/'))) - 1);
      for (std::size_t k = 1; k + 1 < idx.size(); ++k) f.push_back({idx[0], idx[k], idx[k + 1]});
    }
  }
  return test::to_mesh(v, f);
}

std::string shared_dir() {
  for (const char* d : {"../shared", "../../shared", "../../../shared", "/work/shared"}) {
    std::ifstream probe(std::string(d) + "/data/objects/ycb_apple.obj");
    if (probe) return d;
  }
  return "";
}

/// A mesh's object, its section skin and the mesh world, the object's centre and size, and a
/// seeded generator: what random queries about it need.
struct Scene {
  Scene(const test::Mesh& m, unsigned seed)
      : object(std::make_shared<Object>(m.vertices, m.faces)),
        skin(object, kFlatten),
        mesh(skin.mesh_world()),
        c(object->bounds().centre()),
        size(object->bounds().extent().maxCoeff()),
        rng(seed) {}
  double u() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng); }  ///< uniform in [0, 1)
  std::shared_ptr<const Object> object;
  SectionSkin skin;
  const SimulatedWorld& mesh;
  Vec3 c;
  double size;
  std::mt19937 rng;
};

struct Tally {
  long queries = 0, clear_disagree = 0, blocked_disagree = 0, inside_disagree = 0;
  double worst_clear_penetration = 0.0;  ///< deepest 3D penetration of a link the skin called clear
};

/// Random planes through the object; random links and points in them, near the object.
void compare(const std::shared_ptr<const Object>& object, unsigned seed, int planes, int per_plane, Tally* tally) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const SectionSkin skin(object, kFlatten);
  const SimulatedWorld& mesh = skin.mesh_world();
  const Aabb box = object->bounds();
  const Vec3 c = box.centre(), ext = box.extent();
  const double size = ext.maxCoeff();
  const double radii[3] = {0.0, 0.02 * size, 0.06 * size};
  for (int k = 0; k < planes; ++k) {
    const Vec3 origin = c + Vec3(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5).cwiseProduct(ext) * 0.8;
    const FingerPlane pl = test::random_plane(rng, origin);
    const double r = radii[k % 3];
    const Vec2 lo = pl.to_plane(c) - Vec2::Constant(0.7 * size), span = Vec2::Constant(1.4 * size);
    for (int q = 0; q < per_plane; ++q) {
      const Vec2 a = lo + Vec2(U(rng) * span.x(), U(rng) * span.y());
      const double len = (q % 4 == 0) ? 0.0 : U(rng) * 0.4 * size, ang = U(rng) * 2 * kPi;
      const Vec2 b = a + len * Vec2(std::cos(ang), std::sin(ang));
      const Vec3 A = pl.to_world(a), B = pl.to_world(b);
      // Reference: the exact 3D capsule test and gap.
      const bool clear3 = mesh.capsule_clear(A, B, r, false);
      const double gap3 = mesh.capsule(A, B, r).gap;
      const bool clear2 = skin.link_free(pl, a, b, r, -kInf, false);
      ++tally->queries;
      if (clear2 && !clear3) {
        ++tally->clear_disagree;
        tally->worst_clear_penetration = std::max(tally->worst_clear_penetration, -gap3);
      }
      if (!clear2 && clear3 && gap3 > kFlatten + 1e-9) ++tally->blocked_disagree;
      // In-plane gaps are never smaller than 3D gaps (less the flattening), and exact in sign.
      const Touch t2 = skin.link(pl, a, b, r);
      if (gap3 > kFlatten + 1e-9) {
        EXPECT_GE(t2.gap, gap3 - kFlatten - 1e-9) << "plane " << k << " query " << q;
      }
      if (gap3 < -1e-9) {
        EXPECT_LT(t2.gap, 0.0) << "plane " << k << " query " << q << " gap3 " << gap3;
      }
      // Point inside R: the side test against the exact 3D test.
      const PlaneRegion* R = skin.region(pl, r);
      ASSERT_NE(R, nullptr);
      const double d3 = object->nearest(A, A).signed_distance;
      if (std::abs(std::max(d3, 0.0) - r) > kFlatten + 1e-9 && (R->inside(a) != (d3 <= r)))
        ++tally->inside_disagree;
    }
  }
}

}  // namespace

TEST(SectionSkin, AgreesWithTheMeshWorldOnRandomQueries) {
  struct Case {
    const char* name;
    test::Mesh mesh;
  };
  std::vector<Case> cases = {{"sphere", test::icosphere(3, Vec3::Constant(0.04))},
                             {"ellipsoid", test::icosphere(3, Vec3(0.05, 0.03, 0.02), Vec3(0.01, 0.0, -0.02))},
                             {"box", test::box(Vec3(0.03, 0.02, 0.05))},
                             {"curvy", test::curvy(4)},
                             {"cylinder", test::cylinder(0.035, 0.05, 48)}};
  Tally total;
  unsigned seed = 1;
  for (const auto& c : cases) {
    Tally t;
    compare(std::make_shared<Object>(c.mesh.vertices, c.mesh.faces), seed++, 30, 100, &t);
    std::printf("  %-10s %ld queries: %ld clear-but-penetrating (worst %.3g m), %ld blocked-but-clear, %ld inside\n",
                c.name, t.queries, t.clear_disagree, t.worst_clear_penetration, t.blocked_disagree, t.inside_disagree);
    total.queries += t.queries;
    total.clear_disagree += t.clear_disagree;
    total.blocked_disagree += t.blocked_disagree;
    total.inside_disagree += t.inside_disagree;
    total.worst_clear_penetration = std::max(total.worst_clear_penetration, t.worst_clear_penetration);
  }
  EXPECT_GE(total.queries, 10000);
  EXPECT_LE(total.worst_clear_penetration, 5e-6);
  EXPECT_EQ(total.blocked_disagree, 0);
  EXPECT_EQ(total.inside_disagree, 0);
}

TEST(SectionSkin, AgreesWithTheMeshWorldOnSharedMeshes) {
  const std::string dir = shared_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/data/objects (the shared YCB meshes) is absent";
  Tally total;
  unsigned seed = 100;
  for (const char* name : {"ycb_apple", "ycb_banana", "ycb_cracker_box", "ycb_lemon"}) {
    const test::Mesh m = load_obj(dir + "/data/objects/" + name + ".obj");
    ASSERT_GT(m.faces.rows(), 0) << name;
    std::shared_ptr<Object> obj;
    try {
      obj = std::make_shared<Object>(m.vertices, m.faces);
    } catch (const std::invalid_argument& e) {
      std::printf("  %s: not a closed mesh here (%s), skipped\n", name, e.what());
      continue;
    }
    Tally t;
    compare(obj, seed++, 15, 100, &t);
    std::printf("  %-16s %ld queries: %ld clear-but-penetrating (worst %.3g m), %ld blocked-but-clear, %ld inside\n",
                name, t.queries, t.clear_disagree, t.worst_clear_penetration, t.blocked_disagree, t.inside_disagree);
    total.queries += t.queries;
    total.worst_clear_penetration = std::max(total.worst_clear_penetration, t.worst_clear_penetration);
    total.blocked_disagree += t.blocked_disagree;
    total.inside_disagree += t.inside_disagree;
  }
  EXPECT_LE(total.worst_clear_penetration, 5e-6);
  EXPECT_EQ(total.blocked_disagree, 0);
  EXPECT_EQ(total.inside_disagree, 0);
}

namespace {

/// Plans with the given skin; returns the deepest 3D penetration of any link in any configuration
/// (0 when none), measured against the mesh world, and checks the plan's basic properties.
double plan_and_measure(const std::shared_ptr<const Sensing>& skin, const SimulatedWorld& mesh, const HandModel& hand,
                        const Pose& start, Status* status, std::vector<Configuration>* history) {
  Planner planner(hand, skin, Vec3::Zero(), start);
  *status = planner.plan();
  *history = planner.history();
  double worst = 0.0;
  const int M = hand.fingers(), N = hand.links();
  for (const Configuration& c : planner.history())
    for (int m = 0; m < M; ++m)
      for (int n = 0; n < N; ++n) {
        const Vec3& a = c.joints[m * (N + 1) + n];
        const Vec3& b = c.joints[m * (N + 1) + n + 1];
        EXPECT_NEAR((b - a).norm(), hand.link_length(m, n), 1e-9);
        worst = std::max(worst, -mesh.capsule(a, b, hand.link_radius()).gap);
      }
  for (std::size_t k = 1; k < planner.history().size(); ++k)
    for (int m = 0; m < M; ++m) EXPECT_GE(planner.history()[k].tip_state[m], planner.history()[k - 1].tip_state[m]);
  return worst;
}

}  // namespace

TEST(SectionSkin, PlansAreCollisionFreeIn3DAndDeterministic) {
  struct Case {
    const char* name;
    test::Mesh mesh;
  };
  std::vector<Case> cases = {{"sphere", test::icosphere(4, Vec3::Constant(0.04))}, {"curvy", test::curvy(5)},
                             {"box", test::box(Vec3(0.03, 0.025, 0.04))}};
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  for (const auto& c : cases) {
    auto object = std::make_shared<const Object>(c.mesh.vertices, c.mesh.faces);
    const SimulatedWorld mesh(object);
    Pose start = Pose::Identity();
    start.linear() = Eigen::AngleAxisd(kPi, Vec3::UnitX()).toRotationMatrix();
    start.translation() = Vec3(0, 0, 0.2);
    start.linear() = Eigen::AngleAxisd(0.7, Vec3::UnitY()).toRotationMatrix() * start.linear();
    Status s1, s2, s3;
    std::vector<Configuration> h1, h2, h3;
    const double pen = plan_and_measure(std::make_shared<SectionSkin>(object), mesh, hand, start, &s1, &h1);
    plan_and_measure(std::make_shared<SectionSkin>(object), mesh, hand, start, &s2, &h2);
    const double pen_mesh = plan_and_measure(std::make_shared<SimulatedWorld>(object), mesh, hand, start, &s3, &h3);
    std::printf("  %-7s section skin: %s, %zu configurations, deepest 3D penetration %.3g m; mesh world: %s, %zu, %.3g m\n",
                c.name, to_string(s1).c_str(), h1.size(), pen, to_string(s3).c_str(), h3.size(), pen_mesh);
    EXPECT_LE(pen, 5e-6) << c.name;
    EXPECT_EQ(s1, Status::kDone) << c.name;
    ASSERT_EQ(h1.size(), h2.size()) << c.name;
    for (std::size_t k = 0; k < h1.size(); ++k)
      for (std::size_t j = 0; j < h1[k].joints.size(); ++j)
        ASSERT_TRUE(h1[k].joints[j] == h2[k].joints[j]) << c.name << " configuration " << k;
  }
}

// The Planner's constructor hands the skin the Phase 2 planes once Phase 1 has fixed them
// (Sensing::prepare): the section skin builds their regions then, so that no Phase 2 iteration
// carries that work, and Phase 2 asks in no other plane.
TEST(SectionSkin, TheConstructorBuildsThePhase2Regions) {
  const test::Mesh m = test::curvy(4);
  auto object = std::make_shared<const Object>(m.vertices, m.faces);
  const HandModel hand = HandModel::uniform(5, 5, 0.02, 0.004, 0.03, 0.01);
  Pose start = Pose::Identity();
  start.linear() = Eigen::AngleAxisd(0.7, Vec3::UnitY()).toRotationMatrix() *
                   Eigen::AngleAxisd(kPi, Vec3::UnitX()).toRotationMatrix();
  start.translation() = Vec3(0, 0, 0.2);
  auto skin = std::make_shared<SectionSkin>(object);
  ASSERT_EQ(skin->regions(), 0);
  Planner planner(hand, skin, Vec3::Zero(), start);
  EXPECT_EQ(skin->regions(), hand.fingers());  // five fingers, five planes: none shared
  ASSERT_TRUE(planner.advance());               // the first Phase 2 iteration
  EXPECT_EQ(skin->regions(), hand.fingers());
  EXPECT_EQ(planner.plan(), Status::kDone);
  EXPECT_EQ(skin->regions(), hand.fingers());
}

TEST(SectionSkin, RegionSizeBarelyGrowsWithTheMesh) {
  // A plane through a sphere of radius 4 cm, link radius 4 mm: the boundary pieces are one ring
  // of features, so their number grows with the square root of the triangle count, and the
  // segments left once chains are simplified (whose count is set by the curvature of R and the
  // tolerance, not the mesh) barely at all.
  FingerPlane pl;
  pl.origin = Vec3(0.0, 0.005, 0.0);
  pl.u = Vec3(1, 0, 0);
  pl.p = Vec3(0, 0.6, 0.8);
  std::vector<std::size_t> counts;
  for (int s : {3, 5, 6}) {
    const auto m = test::icosphere(s, Vec3::Constant(0.04));
    auto obj = std::make_shared<Object>(m.vertices, m.faces);
    const PlaneRegion R(obj, pl, 0.004, 1e-6);
    std::printf("  sphere %ld triangles: %zu pieces, %zu segments (%ld dropped as inside R)\n",
                static_cast<long>(m.faces.rows()), R.pieces().size(), R.segments().size(), R.dropped());
    EXPECT_EQ(R.dropped(), 0);  // a convex object: no piece of its region lies inside it
    counts.push_back(R.segments().size());
  }
  // Chains of pieces are simplified to the flattening tolerance: 64 times the triangles, less
  // than twice the segments (unsimplified, 2.7 times).
  EXPECT_LT(counts.back(), 2 * counts.front());
}

namespace {

/// The distance between segments [p, q] and [s, t] in the plane, plainly: zero where they cross,
/// else the least of the four end-point-to-segment distances.
double segments_apart(const Vec2& p, const Vec2& q, const Vec2& s, const Vec2& t) {
  auto cross = [](const Vec2& x, const Vec2& y) { return x.x() * y.y() - x.y() * y.x(); };
  auto to_segment = [](const Vec2& x, const Vec2& a, const Vec2& b) {
    const Vec2 d = b - a;
    const double dd = d.squaredNorm();
    const double t = dd > 0.0 ? std::clamp((x - a).dot(d) / dd, 0.0, 1.0) : 0.0;
    return (a + t * d - x).norm();
  };
  const double d1 = cross(q - p, s - p), d2 = cross(q - p, t - p), d3 = cross(t - s, p - s), d4 = cross(t - s, q - s);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 0.0;
  return std::min({to_segment(p, s, t), to_segment(q, s, t), to_segment(s, p, q), to_segment(t, p, q)});
}

/// The least segments_apart from [a, b] to R's boundary segments.
double boundary_apart(const std::vector<PlaneRegion::Segment>& segs, const Vec2& a, const Vec2& b) {
  double best = kInf;
  for (const auto& e : segs) best = std::min(best, segments_apart(a, b, e.a, e.b));
  return best;
}

/// x inside the boundary segments: crossings of a ray to +x, counted by parity (R as its
/// segments bound it).
bool inside_by_parity(const std::vector<PlaneRegion::Segment>& segs, const Vec2& x) {
  bool in = false;
  for (const auto& e : segs)
    if ((e.a.y() > x.y()) != (e.b.y() > x.y()) &&
        x.x() < e.a.x() + (x.y() - e.a.y()) / (e.b.y() - e.a.y()) * (e.b.x() - e.a.x()))
      in = !in;
  return in;
}

}  // namespace

// any_within (the clearance tests' question) against every segment of R's boundary, on links
// laid along the boundary (tangent to it, a hair to a few millimetres off, either side: the
// links resting on O that the tree and the hull test settle) and on random ones, for thresholds
// from touching to millimetres. Cases within a picometre of the threshold are left to rounding.
TEST(SectionSkin, AnyWithinMatchesEverySegment) {
  long checked = 0, hits = 0;
  for (const test::Mesh& m : {test::icosphere(3, Vec3::Constant(0.04)), test::curvy(4),
                              test::cylinder(0.035, 0.05, 48), test::box(Vec3(0.03, 0.02, 0.05)), test::curvy(2)}) {
    Scene s(m, 11);
    for (int k = 0; k < 8; ++k) {
      const FingerPlane pl = test::random_plane(s.rng, s.c);
      const PlaneRegion* R = s.skin.region(pl, (k % 2) * 0.004);
      ASSERT_NE(R, nullptr);
      const auto& segs = R->segments();
      if (segs.empty()) continue;
      for (int q = 0; q < 400; ++q) {
        Vec2 a, b;
        if (q % 4 != 3) {  // along a boundary segment, off it along its normal by 10^-13 to 10^-2.5 m
          const PlaneRegion::Segment& g = segs[static_cast<std::size_t>(s.u() * segs.size())];
          const double off = std::pow(10.0, -13.0 + 10.5 * s.u()) * (q % 4 == 2 ? -1.0 : 1.0);
          const Vec2 at = g.a + s.u() * (g.b - g.a) + off * g.normal;
          const double tilt = (s.u() - 0.5) * 0.02, len = (0.1 + s.u()) * 0.02;
          const Vec2 along = rotate_planar((g.b - g.a).normalized(), tilt);
          const double back = s.u() * len;
          a = at - back * along;
          b = at + (len - back) * along;
        } else {
          a = Vec2(s.u() - 0.5, s.u() - 0.5) * 1.4 * s.size;
          b = a + s.u() * 0.4 * s.size * Vec2(std::cos(s.u() * 2 * kPi), std::sin(s.u() * 2 * kPi));
        }
        const double best = boundary_apart(segs, a, b);
        // and half a nanometre either side of the distance itself, where a shortcut with a
        // margin must leave the answer to the exact test
        for (double d : {1e-12, 1e-9, 1e-6, 1e-4, 3e-3, best - 5e-10, best + 5e-10}) {
          if (!(d > 0.0) || std::abs(best - d) < 1e-12) continue;
          ASSERT_EQ(R->any_within(a, b, d), best <= d) << "plane " << k << " query " << q << " d " << d << " best " << best;
          ++checked;
          hits += best <= d;
        }
      }
    }
  }
  std::printf("  %ld decisions, %ld within\n", checked, hits);
  EXPECT_GE(checked, 40000);
  EXPECT_GE(hits, 5000);
}

// reach()'s hints (the segment last found within reach of a query starting near the same
// point) are taken only where the tree's walk would answer the same: links that slide along R's
// boundary in small steps, as a finger's do from one iteration to the next, crossing it or a hair
// to millimetres off it, forward and then back over stale hints. Each answer of any_within() and
// clear() against every segment (cases within a picometre of the threshold left to rounding);
// then the same questions, thresholds at the nearest segment's distance and a rounding step
// either side included, asked in a shuffled order of a twin region (the same object and plane,
// other hints): every answer the same.
TEST(SectionSkin, ReachHintsLeaveEveryAnswerAsTheWalkGives) {
  long checked = 0, hits = 0, twins = 0;
  // Regions the convex loop's shortcuts do not settle: a torus's two loops, two balls, dents.
  for (const test::Mesh& m : {test::torus(0.03, 0.012, 48, 24), test::curvy(4),
                              test::join(test::icosphere(3, Vec3::Constant(0.02), Vec3(-0.025, 0, 0)),
                                         test::icosphere(3, Vec3::Constant(0.02), Vec3(0.025, 0, 0)))}) {
    Scene s(m, 31);
    const SectionSkin twin(s.object, kFlatten);
    for (int k = 0; k < 6; ++k) {
      const FingerPlane pl = test::random_plane(s.rng, s.c);
      const double radius = (k % 2) * 0.004;
      const PlaneRegion* R = s.skin.region(pl, radius);
      const PlaneRegion* T = twin.region(pl, radius);
      ASSERT_NE(R, nullptr);
      ASSERT_NE(T, nullptr);
      const auto& segs = R->segments();
      if (segs.empty()) continue;
      struct Asked {
        Vec2 a, b;
        double d;  ///< any_within's threshold; negative: clear()
        bool answer;
      };
      std::vector<Asked> asked;
      for (int slide = 0; slide < 12; ++slide) {
        const PlaneRegion::Segment& g = segs[static_cast<std::size_t>(s.u() * segs.size())];
        const Vec2 along = (g.b - g.a).normalized();
        // Off the boundary along its normal: across it (negative) or outside, 10^-13 to 10^-2.5 m.
        const double off = slide % 3 == 0 ? -0.002 * s.u() : std::pow(10.0, -13.0 + 10.5 * s.u());
        const Vec2 dir = rotate_planar(along, (s.u() - 0.5) * 0.6), start = g.a + off * g.normal;
        const double len = 0.02, step = 2e-4 * (s.u() < 0.5 ? 1.0 : -1.0);
        for (int pass = 0; pass < 2; ++pass)
          for (int i = 0; i < 40; ++i) {
            const int t = pass == 0 ? i : 39 - i;
            const Vec2 a = start + (t * step) * along - 0.5 * len * dir, b = a + len * dir;
            const double best = boundary_apart(segs, a, b);
            for (double d : {1e-12, 1e-6, 1e-4}) {
              const bool answer = R->any_within(a, b, d);
              asked.push_back({a, b, d, answer});
              if (std::abs(best - d) < 1e-12) continue;
              ASSERT_EQ(answer, best <= d) << "plane " << k << " slide " << slide << " at " << t;
              ++checked;
              hits += best <= d;
            }
            if (best > 0.0)  // at the nearest distance and a rounding step or a few either side
              for (double d : {best, std::nextafter(best, 0.0), std::nextafter(best, kInf), best * (1.0 - 1e-15),
                               best * (1.0 + 1e-15), best - 1e-13, best + 1e-13, 1.5 * best})
                if (d > 0.0) asked.push_back({a, b, d, R->any_within(a, b, d)});
            const bool clear = R->clear(a, b, false);
            asked.push_back({a, b, -1.0, clear});
            if (best > 2e-12) {
              ASSERT_EQ(clear, !inside_by_parity(segs, a)) << "plane " << k << " slide " << slide;
              ++checked;
            } else if (best == 0.0) {
              ASSERT_FALSE(clear) << "plane " << k << " slide " << slide << " at " << t;
              ++checked;
            }
          }
      }
      std::shuffle(asked.begin(), asked.end(), s.rng);
      for (const Asked& q : asked) {
        ASSERT_EQ(q.d < 0.0 ? T->clear(q.a, q.b, false) : T->any_within(q.a, q.b, q.d), q.answer)
            << "plane " << k << " threshold " << q.d;
        ++twins;
      }
    }
  }
  std::printf("  %ld decisions against every segment, %ld within; %ld asked again of the twin\n", checked, hits,
              twins);
  EXPECT_GE(checked, 20000);
  EXPECT_GE(hits, 5000);
  EXPECT_GE(twins, 100000);
}

// The hull settles a query only where every segment agrees. Lines across each region's hull (at
// fractions of its width, in random and axis directions and along its own segments, where
// nearly collinear hull edges lie) and lines just outside it, on boxes (flat faces: collinear
// boundary segments), a cylinder and a sphere, in axis-aligned and random planes: any_within
// against every segment, and clear() against the test it shortcuts (no segment touching, a
// outside R). One box plane where two collinear edges' pseudo-angles round in the wrong order is
// asked first: there the hull started at the wrong edge and called a crossing line apart.
TEST(SectionSkin, HullSettlesOnlyWhatEverySegmentSays) {
  {
    const test::Mesh m = test::box(Vec3(0.04, 0.04, 0.01), Vec3(0.01, 0.0, 0.02));
    FingerPlane pl;
    pl.origin = Vec3(0.012786536585010411, 0.005175785164235309, 0.017614383141039747);
    pl.u = Vec3(0.35343720609972001, -0.79492588510811368, -0.49312775071933046);
    pl.p = Vec3(0.79730224577810538, -0.019733635020856254, 0.6032575838943538);
    const PlaneRegion R(std::make_shared<Object>(m.vertices, m.faces), pl, 0.0, kFlatten);
    const Vec2 a(0.0064364275191014118, -0.032941890050551433), b(-0.04317482144392118, -0.039164749226926088);
    ASSERT_EQ(R.nearest(a, b).distance, 0.0);  // the line crosses the boundary
    EXPECT_TRUE(R.any_within(a, b, 1e-6));
    EXPECT_FALSE(R.clear(a, b, false));
  }
  long checked = 0, crossing = 0, outside = 0;
  for (const test::Mesh& m : {test::box(Vec3(0.03, 0.02, 0.05)), test::box(Vec3(0.04, 0.04, 0.01), Vec3(0.01, 0.0, 0.02)),
                              test::cylinder(0.035, 0.05, 48), test::icosphere(3, Vec3::Constant(0.04))}) {
    Scene s(m, 21);
    const Vec3 axes[3] = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
    for (int k = 0; k < 24; ++k) {
      FingerPlane pl;
      const Vec3 at = s.c + Vec3(s.u() - 0.5, s.u() - 0.5, s.u() - 0.5) * 0.02;
      if (k % 2 == 0) {  // a face's normal in the plane, or the plane along a face
        const int ax = (k / 2) % 3;
        const double t = (k % 4 == 0) ? 0.0 : s.u() * 2 * kPi;
        pl.origin = at;
        pl.p = axes[ax];
        pl.u = (std::cos(t) * axes[(ax + 1) % 3] + std::sin(t) * axes[(ax + 2) % 3]).normalized();
      } else {
        pl = test::random_plane(s.rng, at);
      }
      const PlaneRegion* R = s.skin.region(pl, (k % 3 == 0) ? 0.0 : (k % 3 == 1 ? 0.001 : 0.004));
      ASSERT_NE(R, nullptr);
      const auto& segs = R->segments();
      if (segs.empty()) continue;
      std::vector<Vec2> dirs = {Vec2(1, 0), Vec2(0, 1), Vec2(-1, 0), Vec2(0, -1)};
      for (int i = 0; i < 8; ++i) dirs.push_back(rotate_planar(Vec2(1, 0), s.u() * 2 * kPi));
      for (std::size_t i = 0; i < segs.size(); i += std::max<std::size_t>(1, segs.size() / 24))
        if (segs[i].b != segs[i].a) dirs.push_back((segs[i].b - segs[i].a).normalized());
      for (const Vec2& u : dirs) {
        const Vec2 n(-u.y(), u.x());
        double lo = kInf, hi = -kInf;
        for (const auto& g : segs) lo = std::min({lo, n.dot(g.a), n.dot(g.b)}), hi = std::max({hi, n.dot(g.a), n.dot(g.b)});
        for (double f : {0.02, 0.3, 0.5, 0.7, 0.98, -1e-9, -1e-6, 1.0 + 1e-9, 1.0 + 1e-6}) {
          const double off = f < 0.0 ? lo + f : (f > 1.0 ? hi + (f - 1.0) : lo + f * (hi - lo));
          const Vec2 a = off * n + (s.u() - 0.5) * 0.1 * u, b = a + 0.05 * u;
          const double best = boundary_apart(segs, a, b);
          if (std::abs(best - 1e-6) > 1e-12) {
            ASSERT_EQ(R->any_within(a, b, 1e-6), best <= 1e-6) << "plane " << k << " offset " << f << " best " << best;
            ++checked;
          }
          if (best > 2e-12) {
            ASSERT_EQ(R->clear(a, b, false), !R->inside(a)) << "plane " << k << " offset " << f << " best " << best;
            ++checked;
            outside += f < 0.0 || f > 1.0;
          } else if (best == 0.0) {
            ASSERT_FALSE(R->clear(a, b, false)) << "plane " << k << " offset " << f;
            ++crossing;
          }
        }
      }
    }
  }
  std::printf("  %ld decisions, %ld crossing lines, %ld lines outside the hull\n", checked, crossing, outside);
  EXPECT_GE(checked, 20000);
  EXPECT_GE(crossing, 3000);
  EXPECT_GE(outside, 3000);
}

// link_gap_below (the motion check's question) gives link(...).gap < below with both skins, also
// for bounds at and next to the link's own gap, where a shortcut would first disagree; and told
// that a lies outside (a_outside, for links found free), the same.
TEST(SectionSkin, LinkGapBelowAgreesWithLink) {
  for (const test::Mesh& m : {test::icosphere(3, Vec3::Constant(0.04)), test::curvy(4)}) {
    Scene s(m, 7);
    long checked = 0, told_outside = 0;  // the section skin's answers told so, with no piece that close
    for (int k = 0; k < 12; ++k) {
      const FingerPlane pl = test::random_plane(s.rng, s.c);
      const double r = (k % 3) * 0.03 * s.size;
      for (int q = 0; q < 60; ++q) {
        const Vec2 a = Vec2(s.u() - 0.5, s.u() - 0.5) * 1.4 * s.size;
        const double len = q % 3 == 0 ? 0.0 : s.u() * 0.4 * s.size, ang = s.u() * 2 * kPi;
        const Vec2 b = a + len * Vec2(std::cos(ang), std::sin(ang));
        for (const Sensing* sense : {static_cast<const Sensing*>(&s.skin), static_cast<const Sensing*>(&s.mesh)}) {
          const double g = sense->link(pl, a, b, r).gap;
          const bool found_free = sense->link_free(pl, a, b, r, -kInf);
          for (double below : {0.01 * s.size, 0.1 * s.size, g, std::nextafter(g, kInf), std::nextafter(g, 0.0)}) {
            if (!(below > 0.0) || !std::isfinite(below)) continue;
            const bool want = sense->link(pl, a, b, r, below).gap < below;
            EXPECT_EQ(sense->link_gap_below(pl, a, b, r, below), want)
                << "plane " << k << " query " << q << " below " << below;
            ++checked;
            if (found_free) {
              EXPECT_EQ(sense->link_gap_below(pl, a, b, r, below, true), want)
                  << "plane " << k << " query " << q << " below " << below << " (a outside)";
              // where the section skin skips its inside test: no piece within `below`
              if (sense == &s.skin && !want) ++told_outside;
            }
          }
        }
      }
    }
    EXPECT_GE(checked, 2000);
    std::printf("  %ld decisions, %ld of the section skin's told a lies outside\n", checked, told_outside);
    EXPECT_GE(told_outside, 800);
  }
}

// rotate_until_touch asks each gap capped just beyond what the rest of the arc can use. A skin
// that forwards every query uncapped (link() with no cap: the search as it was) gives the same
// rotation, bit for bit, on random links swinging near the sphere and curvy, for the section skin
// and the mesh world, with a level of 0 too and on requests outside the planner's; the gap it
// reports is exact up to 2 level + touch_gap.
TEST(SectionSkin, RotateUntilTouchIsTheUncappedSearchToTheBit) {
  // (gap_in_space: the mesh world's exact 3D gap where the skin measures in the plane; only
  // whether it is at most touch_gap, exact either way, matters to the search.)
  struct Uncapped final : Sensing {
    Uncapped(const Sensing& s, const SimulatedWorld* space) : inner(s), in_space(space) {}
    Touch capsule(const Vec3& a, const Vec3& b, double radius, double) const override {
      return inner.capsule(a, b, radius, kInf);
    }
    double palm(const Pose& palm, double radius, double thickness, double) const override {
      return inner.palm(palm, radius, thickness, kInf);
    }
    Touch link(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double) const override {
      return inner.link(plane, a, b, radius, kInf);
    }
    double gap_in_space(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                        double cap) const override {
      return in_space ? in_space->capsule(plane.to_world(a), plane.to_world(b), radius, cap).gap : kInf;
    }
    const Sensing& inner;
    const SimulatedWorld* in_space;
  };
  long asked = 0, touched = 0, capped = 0;
  for (const test::Mesh& m : {test::icosphere(3, Vec3::Constant(0.04)), test::curvy(4)}) {
    Scene s(m, 11);
    for (int k = 0; k < 8; ++k) {
      const FingerPlane pl = test::random_plane(s.rng, s.c);
      const double r = (k % 3) * 0.03 * s.size;
      for (const Sensing* sense : {static_cast<const Sensing*>(&s.skin), static_cast<const Sensing*>(&s.mesh)}) {
        const Uncapped reference(*sense, sense == &s.skin ? &s.mesh : nullptr);
        for (int q = 0; q < 40; ++q) {
          // About the object's centre, the link across the radius (either way round), so that
          // flexion swings it toward the surface or away from it.
          const double around = s.u() * 2 * kPi;
          const Vec2 radial(std::cos(around), std::sin(around));
          const Vec2 pivot = pl.to_plane(s.c) + ((0.52 + 0.1 * s.u()) * s.size + r) * radial;
          const double len = (0.2 + 0.2 * s.u()) * s.size;
          const double ang = around + (s.u() < 0.5 ? 0.5 : -0.5) * kPi + (s.u() - 0.5);
          RotateRequest req;
          req.plane = pl;
          req.pivot = pivot;
          req.end = pivot + len * Vec2(std::cos(ang), std::sin(ang));
          req.radius = r;
          req.max_angle = 0.05 + 0.95 * s.u();
          req.touch_gap = 1e-3 * s.size;
          req.level = q % 4 == 0 ? 0.0 : 0.5 * req.touch_gap;
          // Now and then a request outside the planner's: no arc left, a negative or NaN one, a
          // negative level (each asked with no cap).
          if (q % 10 == 9) {
            const double odd[4] = {0.0, -1e-3, std::numeric_limits<double>::quiet_NaN(), req.max_angle};
            req.max_angle = odd[(q / 10) % 4];
            if ((q / 10) % 4 == 3) req.level = -1e-3;
          }
          const RotateResult got = sense->rotate_until_touch(req), want = reference.rotate_until_touch(req);
          ++asked;
          ASSERT_EQ(got.ok, want.ok) << "plane " << k << " query " << q;
          ASSERT_EQ(bits_of(got.angle), bits_of(want.angle)) << "plane " << k << " query " << q;
          ASSERT_EQ(bits_of(got.end.x()), bits_of(want.end.x())) << "plane " << k << " query " << q;
          ASSERT_EQ(bits_of(got.end.y()), bits_of(want.end.y())) << "plane " << k << " query " << q;
          touched += got.ok;
          if (want.gap <= 2.0 * req.level + req.touch_gap) {
            EXPECT_EQ(bits_of(got.gap), bits_of(want.gap)) << "plane " << k << " query " << q;
          } else {
            EXPECT_GT(got.gap, 2.0 * req.level + req.touch_gap) << "plane " << k << " query " << q;
            capped += bits_of(got.gap) != bits_of(want.gap);
          }
        }
      }
    }
  }
  std::printf("  %ld rotations, %ld touched, %ld gaps capped\n", asked, touched, capped);
  EXPECT_GE(touched, 50);  // some links reach the surface ...
  EXPECT_GE(capped, 50);   // ... and some are asked far from it, where the cap answers
}

// Contact is decided in space: on random links in random planes (not through the centre, so that
// O's surface is oblique to them) at sensing distances from 0.1 mm to 2% of the object's size,
// the section skin's contact_gap is at most delta exactly when the mesh world's 3D gap is (up to
// the flattening, contact early), though the in-plane gap alone misses some of those
// contacts; capped, it keeps its decision, and where it says no contact, it shrinks no faster
// than the link moves in the plane (the FROZEN fingers' bounds rely on it); and its lasting
// bounds (contact_gap_bound) are exact up to need and never above the gap.
TEST(SectionSkin, ContactGapDecidesContactInSpace) {
  long contacts = 0, missed_in_plane = 0, checked = 0, oblique = 0;
  long bounded[2] = {0, 0}, unbounded[2] = {0, 0};  // section skin, mesh world
  for (const test::Mesh& m : {test::curvy(4), test::icosphere(3, Vec3(0.05, 0.03, 0.02)), test::box(Vec3(0.03, 0.02, 0.05))}) {
    Scene s(m, 5);
    for (int k = 0; k < 12; ++k) {
      const FingerPlane pl = test::random_plane(s.rng, s.c + 0.3 * s.size * Vec3(s.u() - 0.5, s.u() - 0.5, s.u() - 0.5));
      const double r = 0.05 * s.size, delta = k % 3 == 0 ? 1e-4 : (k % 3 == 1 ? 1e-3 : 0.02 * s.size);
      for (int q = 0; q < 80; ++q) {
        Vec2 a = pl.to_plane(s.c) + Vec2(s.u() - 0.5, s.u() - 0.5) * 1.4 * s.size;
        // Every other point query near contact: a point whose 3D gap is within 2 delta.
        for (int tries = 0; q % 2 == 0 && tries < 400; ++tries) {
          const Vec3 A = pl.to_world(a);
          const double g = s.mesh.capsule(A, A, r).gap;
          if (g >= 0.0 && g <= 2.0 * delta) break;
          a = pl.to_plane(s.c) + Vec2(s.u() - 0.5, s.u() - 0.5) * 1.4 * s.size;
        }
        const double len = q % 2 == 0 ? 0.0 : s.u() * 0.3 * s.size, ang = s.u() * 2 * kPi;
        const Vec2 b = a + len * Vec2(std::cos(ang), std::sin(ang));
        const double g3 = s.mesh.capsule(pl.to_world(a), pl.to_world(b), r).gap;
        const double g = s.skin.contact_gap(pl, a, b, r, delta);
        ++checked;
        EXPECT_EQ(s.mesh.contact_gap(pl, a, b, r, delta), s.mesh.link(pl, a, b, r).gap);
        if (g <= delta) {
          ++contacts;
          EXPECT_LE(g3, delta + kFlatten + 1e-9) << "plane " << k << " query " << q;
          if (s.skin.link(pl, a, b, r).gap > delta) ++missed_in_plane;
        } else {
          EXPECT_GT(g3, delta) << "plane " << k << " query " << q;
        }
        // Capped: exact up to the cap, above it beyond; the decision whatever the cap (one below
        // delta included). (A cap equal to the gap may fall on either side by rounding.)
        for (const double cap : {-1.0, 0.0, 0.5 * delta, delta, 0.5 * g, 1.5 * g}) {
          const double capped = s.skin.contact_gap(pl, a, b, r, delta, cap);
          EXPECT_EQ(capped <= delta, g <= delta) << "cap " << cap;
          if (g <= std::max(cap, delta)) EXPECT_EQ(capped, g) << "cap " << cap;
          else EXPECT_GT(capped, cap) << "cap " << cap;
        }
        // Bounds that last (Sensing::contact_gap_bound): exact up to need, beyond it above need and
        // at most the gap, and at least far where the gap is; in both skins, also where the
        // in-plane gap alone would pass far.
        for (const double far : {1.5 * delta, 0.5 * (g + delta), 0.999 * g, 1.001 * g, 2.0 * g}) {
          const double need = delta;
          for (int which = 0; which < 2; ++which) {
            const Sensing* skin = which == 0 ? static_cast<const Sensing*>(&s.skin) : &s.mesh;
            const double exact = skin->contact_gap(pl, a, b, r, delta);
            const double bound = skin->contact_gap_bound(pl, a, b, r, delta, need, far);
            if (exact <= need) {  // the gap itself (a link deep in O may be told -inf by a capped query)
              EXPECT_LE(bound, need) << "plane " << k << " query " << q;
              if (exact >= 0.0) EXPECT_EQ(bound, exact) << "plane " << k << " query " << q;
              continue;
            }
            EXPECT_GT(bound, need) << "plane " << k << " query " << q;
            EXPECT_LE(bound, exact + 1e-12) << "plane " << k << " query " << q << " far " << far;
            if (far > need && exact >= far + 1e-9) ++(bound >= far ? bounded[which] : unbounded[which]);
          }
          if (far > delta && s.skin.link(pl, a, b, r).gap >= far && g < far) ++oblique;
        }
        // Moved within the plane by v: where g - |v| still says no contact, the gap shrank by at
        // most |v|.
        const Vec2 v = 0.01 * s.size * Vec2(s.u() - 0.5, s.u() - 0.5);
        if (g - v.norm() > delta) EXPECT_GE(s.skin.contact_gap(pl, a + v, b + v, r, delta), g - v.norm() - 1e-12);
      }
    }
  }
  std::printf("  %ld queries, %ld contacts, %ld of them with an in-plane gap beyond delta; bounds at far: section "
              "skin %ld (below far %ld), mesh world %ld (%ld); %ld cases the in-plane gap alone would bound wrongly\n",
              checked, contacts, missed_in_plane, bounded[0], unbounded[0], bounded[1], unbounded[1], oblique);
  EXPECT_GE(contacts, 100);
  EXPECT_GE(missed_in_plane, 20);  // the case the gap in space is measured for
  for (int which = 0; which < 2; ++which) {
    EXPECT_GE(bounded[which], 500) << "skin " << which;  // the bounds reach far where the gap does
    EXPECT_EQ(unbounded[which], 0) << "skin " << which;
  }
  EXPECT_GE(oblique, 20);  // and the gap in space is tested where it decides
}

// prepare() builds the regions of several planes side by side, each in two stages, on 1, 2 and 3
// threads (more planes than threads): the same regions as region() builds one at a time, segment
// for segment and answer for answer (nearest pieces and inside tests of random points: the tree,
// cells and links of the second stage); a plane given twice is built once; a plane that cannot
// be built makes prepare() throw, and the skin still answers in the other planes.
TEST(SectionSkin, PrepareBuildsTheSameRegionsSideBySide) {
  const auto m = test::curvy(4);
  const auto object = std::make_shared<Object>(m.vertices, m.faces);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<FingerPlane> planes;
  for (int k = 0; k < 6; ++k) {
    planes.push_back(test::random_plane(rng, object->bounds().centre()));
  }
  planes.push_back(planes[2]);
  const double r = 0.004, delta = 1e-4, size = object->bounds().extent().maxCoeff();
  const SectionSkin alone(object, kFlatten);
  for (const int threads : {1, 2, 3}) {
    SectionSkin together(object, kFlatten);
    together.set_build_threads(threads);
    together.prepare(planes, r);
    EXPECT_EQ(together.regions(), 6) << threads << " threads";  // 6 planes, one given twice
    for (std::size_t k = 0; k < planes.size(); ++k) {
      const PlaneRegion* a = together.region(planes[k], r);
      const PlaneRegion* b = alone.region(planes[k], r);
      ASSERT_NE(a, nullptr);
      ASSERT_NE(b, nullptr);
      ASSERT_EQ(a->segments().size(), b->segments().size()) << "plane " << k << ", " << threads << " threads";
      for (std::size_t i = 0; i < a->segments().size(); ++i) {
        EXPECT_EQ(a->segments()[i].a, b->segments()[i].a);
        EXPECT_EQ(a->segments()[i].b, b->segments()[i].b);
        EXPECT_EQ(a->segments()[i].normal, b->segments()[i].normal);
      }
      for (int q = 0; q < 50; ++q) {
        const Vec2 x = 0.6 * size * Vec2(U(rng), U(rng)), y = x + 0.1 * size * Vec2(U(rng), U(rng));
        const PlaneRegion::Near na = a->nearest(x, y), nb = b->nearest(x, y);
        EXPECT_EQ(na.distance, nb.distance);
        EXPECT_EQ(na.segment, nb.segment);
        EXPECT_EQ(a->inside(x), b->inside(x));
      }
    }
    EXPECT_EQ(together.region(planes[2], r), together.region(planes[6], r));
    EXPECT_NE(together.region(planes[2], r), together.region(planes[2], r + delta));  // another radius, built now
    EXPECT_EQ(together.regions(), 7);
    FingerPlane bad = planes[0];
    bad.u = bad.p;  // not a frame
    SectionSkin skin(object, kFlatten);
    skin.set_build_threads(threads);
    EXPECT_THROW(skin.prepare({planes[0], bad, planes[1]}, r), std::invalid_argument);
    EXPECT_NE(skin.region(planes[1], r), nullptr);
  }
}

// Every query looks up its plane's region (a table of slots hashed from u, the origin and the
// radius, then a scan of every region): planes that share u (parallel fingers) and planes of
// another radius each get their own region, in any order of queries. The skin is filled to its
// kMaxRegions regions first, so that a lookup that failed would find no room to build the region
// again and return nullptr: 64 regions in 128 slots share some (the scan's path), and a zero's
// sign (an equal plane, hashed elsewhere) is found by the scan too.
TEST(SectionSkin, FindsEachPlanesRegionWhateverItsSlot) {
  const auto m = test::curvy(3);
  const auto object = std::make_shared<Object>(m.vertices, m.faces);
  const double r = 0.004;
  std::vector<FingerPlane> planes;
  std::vector<double> radii;
  for (int k = 0; k < SectionSkin::kMaxRegions; ++k) {
    FingerPlane f;  // u = x, p = z: the normal is -y
    f.origin = object->bounds().centre() + Vec3(0.0, 0.0005 * (k / 2), 0.0);
    planes.push_back(f);
    radii.push_back(k % 2 == 0 ? r : 2.0 * r);  // each origin with two radii
  }
  SectionSkin skin(object, kFlatten);
  skin.set_build_threads(1);
  std::vector<const PlaneRegion*> first;
  for (std::size_t k = 0; k < planes.size(); ++k) first.push_back(skin.region(planes[k], radii[k]));
  ASSERT_EQ(skin.regions(), SectionSkin::kMaxRegions);
  FingerPlane beyond = planes[0];
  beyond.origin.y() -= 0.0005;
  EXPECT_EQ(skin.region(beyond, r), nullptr);  // full: a plane not built yet gets no region
  for (std::size_t k = 0; k < planes.size(); ++k) {
    ASSERT_NE(first[k], nullptr) << k;
    for (std::size_t j = 0; j < k; ++j) ASSERT_NE(first[k], first[j]) << k << " " << j;
  }
  for (const std::size_t k : {std::size_t{0}, std::size_t{1}, std::size_t{40}}) {
    // The region is that plane's: a skin of its own builds the same boundary.
    const SectionSkin alone(object, kFlatten);
    const PlaneRegion* own = alone.region(planes[k], radii[k]);
    ASSERT_EQ(first[k]->segments().size(), own->segments().size()) << k;
    EXPECT_EQ(first[k]->segments().front().a, own->segments().front().a) << k;
  }
  std::mt19937 rng(5);
  for (int q = 0; q < 1000; ++q) {
    const std::size_t k = rng() % planes.size();
    ASSERT_EQ(skin.region(planes[k], radii[k]), first[k]) << q;
  }
  FingerPlane signed_zero = planes[3];
  signed_zero.u.y() = -0.0;
  EXPECT_EQ(skin.region(signed_zero, radii[3]), first[3]);
  EXPECT_EQ(skin.regions(), SectionSkin::kMaxRegions);
}

// The planner's skin flattens to a tenth of its contact tolerance, at most the default: a link
// the skin keeps off O stays well within the sensing distance however small it is set.
TEST(SectionSkin, FlattensToATenthOfTheContactTolerance) {
  EXPECT_EQ(PlaneRegion::flatten_for(PlannerParams::kDefaultContactTolerance), PlaneRegion::kDefaultFlatten);
  EXPECT_EQ(PlaneRegion::flatten_for(1.0), PlaneRegion::kDefaultFlatten);
  EXPECT_DOUBLE_EQ(PlaneRegion::flatten_for(2e-6), 2e-7);
  for (const double bad : {0.0, -1e-4, kInf, std::numeric_limits<double>::quiet_NaN()})
    EXPECT_EQ(PlaneRegion::flatten_for(bad), PlaneRegion::kDefaultFlatten) << bad;
}

// rotate_until_free in closed form: against a brute-force sweep of fine angles both ways (the
// section skin's own clearance test), on random colliding links in random planes, with and
// without a front plane: the result is free, never nearer than the smallest free angle, at most
// half the tolerance of end motion beyond it, and rests on R (gap at most the tolerance).
TEST(SectionSkin, RotateUntilFreeIsTheSmallestFreeingRotation) {
  for (const test::Mesh& m : {test::icosphere(3, Vec3(0.04, 0.03, 0.035)), test::curvy(4), test::curvy(2)}) {
    const auto object = std::make_shared<Object>(m.vertices, m.faces);
    const SectionSkin skin(object, kFlatten);
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    const Vec3 c = object->bounds().centre();
    const double size = object->bounds().extent().maxCoeff();
    int checked = 0, fronts = 0;
    std::vector<FingerPlane> planes(16);  // a skin keeps at most kMaxRegions regions
    for (FingerPlane& pl : planes) pl = test::random_plane(rng, c);
    for (int trial = 0; trial < 400; ++trial) {
      const FingerPlane& pl = planes[trial % planes.size()];
      const double r = (trial / planes.size()) % 2 * 0.004;
      // a pivot outside R near it: along a random ray from the centre, just past the boundary
      const double a = 2 * kPi * U(rng);
      const Vec2 dir(std::cos(a), std::sin(a));
      double t = 0.0;
      while (t < 2 * size && !skin.link_free(pl, t * dir, t * dir, r, -kInf)) t += 1e-3;
      const Vec2 pivot = (t + 1e-4 * U(rng)) * dir;
      if (!skin.link_free(pl, pivot, pivot, r, -kInf)) continue;
      const double len = (0.2 + 0.3 * U(rng)) * size, b = 2 * kPi * U(rng);
      const Vec2 end = pivot + len * Vec2(std::cos(b), std::sin(b));
      const double front = trial % 3 == 0 ? pivot.y() - 0.5 * len * U(rng) : -kInf;
      fronts += std::isfinite(front);
      if (skin.link_free(pl, pivot, end, r, front)) continue;
      const RotateRequest rr = test::rotate_request(pl, pivot, end, r, front, trial % 4 == 0 ? 0.4 : kPi);
      const RotateResult res = skin.rotate_until_free(rr);
      constexpr double kGrid = 1e-4;
      const double brute = test::smallest_free_angle(skin, rr, kGrid);
      if (std::isfinite(brute)) EXPECT_TRUE(res.ok) << "trial " << trial;
      if (!res.ok) continue;
      ++checked;
      EXPECT_NEAR((res.end - pivot).norm(), len, 1e-12);
      EXPECT_TRUE(skin.link_free(pl, pivot, res.end, r, front)) << "trial " << trial;
      // resting on R, unless the front stopped it (its end then rests on the front)
      const double gap = skin.link(pl, pivot, res.end, r).gap;
      EXPECT_GE(gap, 0.0) << "trial " << trial;
      if (res.end.y() > front + rr.tolerance) EXPECT_LE(gap, rr.tolerance) << "trial " << trial;
      EXPECT_LE(std::abs(res.angle), rr.max_angle + 1e-15);
      if (!std::isfinite(brute)) continue;  // a window narrower than the grid: found, and free
      EXPECT_GE(std::abs(res.angle), brute - kGrid - 1e-12) << "trial " << trial;
      EXPECT_LE(std::abs(res.angle), brute + std::asin(0.5 * rr.tolerance / len) + 1e-12) << "trial " << trial;
    }
    EXPECT_GE(checked, 150);
    EXPECT_GE(fronts, 50);
  }
}

// The regions the convex-loop tests ask about: 12 random planes near the centre of an ellipsoid,
// a 48-sided cylinder and a box (convex loops) and of curvy (the tree), for links of
// radius(k); f(scene, k, region) for each region with a boundary.
template <class Radius, class F>
void for_each_test_region(unsigned seed, Radius&& radius, F&& f) {
  // (Convex loops: most planes of the sphere, the cylinder and the box. One loop but not convex,
  // its hull's loop with pockets: a few planes of the cylinder (one pocket each, where a closed
  // chain's simplification starts and ends) and of curvy(4), most of curvy(2)'s (its dents).
  // Neither: curvy(4)'s other planes, with many pockets or several loops.)
  for (const test::Mesh& m : {test::icosphere(3, Vec3(0.04, 0.03, 0.035)), test::cylinder(0.035, 0.05, 48),
                              test::box(Vec3(0.03, 0.02, 0.05)), test::curvy(4), test::curvy(2)}) {
    Scene s(m, seed);
    for (int k = 0; k < 12; ++k) {
      const FingerPlane pl = test::random_plane(s.rng, s.c + Vec3(s.u() - 0.5, s.u() - 0.5, s.u() - 0.5) * 0.01);
      const PlaneRegion* R = s.skin.region(pl, radius(k));
      ASSERT_NE(R, nullptr);
      if (!R->segments().empty()) f(s, k, *R);
    }
  }
}

// spans() against every segment's part within the disk, on convex regions (one loop: spans()
// walks it) and others (the tree): pivots outside R near its boundary and farther, and inside
// it; lengths from a tenth of the object to past its size; wedges narrow and whole. Every
// direction in the wedge is blocked by the spans exactly where it is by some segment (away from
// the run ends, within 1e-10 of which rounding decides), every run end inside the wedge is one
// of the segments' ends to 1e-12, and a pivot touching a segment is found.
TEST(SectionSkin, SpansAreTheUnionOfTheSegmentsParts) {
  auto pieces_of = [](const PlaneRegion& R, const Vec2& pivot, const Vec2& u, double len, bool* touching) {
    // Each segment's part within the disk, by bisection on the distance along it (independent
    // of the closed form), as pseudo-angle intervals, split at +-2.
    std::vector<std::array<double, 2>> out;
    *touching = false;
    for (const auto& g : R.segments()) {
      const Vec2 d = g.b - g.a;
      const double dd = d.squaredNorm();
      const double tn = dd > 0.0 ? std::clamp((pivot - g.a).dot(d) / dd, 0.0, 1.0) : 0.0;
      const double dn = (g.a + tn * d - pivot).norm();
      if (dn <= 1e-12) *touching = true;
      if (dn > len) continue;
      auto edge = [&](double inside_t, double outside_t) {  // the crossing between them
        if ((g.a + outside_t * d - pivot).norm() <= len) return outside_t;
        for (int i = 0; i < 100; ++i) {
          const double mid = 0.5 * (inside_t + outside_t);
          ((g.a + mid * d - pivot).norm() <= len ? inside_t : outside_t) = mid;
        }
        return inside_t;
      };
      const double t0 = edge(tn, 0.0), t1 = edge(tn, 1.0);
      double p0 = PlaneRegion::pseudo_angle(u, g.a + t0 * d - pivot), p1 = PlaneRegion::pseudo_angle(u, g.a + t1 * d - pivot);
      if (p1 < p0) std::swap(p0, p1);
      if (p1 - p0 <= 2.0) {
        out.push_back({p0, p1});
      } else {
        out.push_back({p1, 2.0});
        out.push_back({-2.0, p0});
      }
    }
    return out;
  };
  auto covered = [](const std::vector<std::array<double, 2>>& spans, double x) {
    for (const auto& s : spans)
      if (s[0] <= x && x <= s[1]) return true;
    return false;
  };
  long checked = 0, convex_queries = 0, pocket_queries = 0, tree_queries = 0, touching = 0, directions = 0;
  for_each_test_region(33, [](int k) { return (k % 2) * 0.004; }, [&](Scene& s, int k, const PlaneRegion& region) {
    const PlaneRegion* R = &region;
    for (int q = 0; q < 150; ++q) {
      // a pivot off a boundary point along its normal (outside by 1e-13 to 1 size; inside for
      // one in six), or on a boundary vertex
      const auto& g = R->segments()[static_cast<std::size_t>(s.u() * R->segments().size())];
      const double off = std::pow(10.0, -13.0 + 12.0 * s.u()) * s.size * (q % 6 == 5 ? -1.0 : 1.0);
      const Vec2 pivot = q % 25 == 0 ? g.a : Vec2(g.a + s.u() * (g.b - g.a) + off * g.normal);
      const double len = (0.1 + 1.2 * s.u()) * s.size, t = s.u() * 2 * kPi;
      const Vec2 u(std::cos(t), std::sin(t));
      const double within = q % 3 == 0 ? kPi : (q % 3 == 1 ? 0.5 : 0.05);
      std::vector<PlaneRegion::Span> got;
      const bool free_pivot = R->spans(pivot, u, len, PlaneRegion::wedge(within), &got);
      bool touch = false;
      const auto want = pieces_of(*R, pivot, u, len, &touch);
      ++(R->convex() ? convex_queries : tree_queries);
      pocket_queries += R->pockets() > 0 && R->loop_answers(pivot, pivot, len);  // asked of a hull's loop
      ++checked;
      if (touch) {
        ++touching;
        EXPECT_FALSE(free_pivot) << "plane " << k << " query " << q;
        continue;
      }
      ASSERT_TRUE(free_pivot) << "plane " << k << " query " << q;
      std::vector<std::array<double, 2>> spans;
      for (const auto& sp : got) {
        spans.push_back({sp.lo, sp.hi});
        EXPECT_NEAR(PlaneRegion::pseudo_angle(u, sp.v_lo), sp.lo == -2.0 ? -2.0 : sp.lo, sp.lo == -2.0 ? 4.0 : 0.0);
        EXPECT_NEAR(PlaneRegion::pseudo_angle(u, sp.v_hi), sp.hi, sp.hi == 2.0 ? 4.0 : 0.0);
      }
      const double pm = PlaneRegion::pseudo_angle_of(within);
      std::vector<double> ends;
      for (const auto& w : want) ends.insert(ends.end(), {w[0], w[1]});
      auto near_end = [&](double x) {
        for (double e : ends)
          if (std::abs(x - e) < 1e-10) return true;
        return false;
      };
      std::vector<double> probes;
      for (int i = 0; i < 32; ++i) probes.push_back((2.0 * s.u() - 1.0) * pm);
      for (double e : ends)
        if (std::abs(e) < pm + 1e-9) probes.insert(probes.end(), {e - 1e-9, e + 1e-9});
      for (double x : probes) {
        if (x < -pm || x > pm || near_end(x)) continue;
        ASSERT_EQ(covered(spans, x), covered(want, x)) << "plane " << k << " query " << q << " direction " << x;
        ++directions;
      }
      for (const auto& sp : spans)
        for (double e : sp) {
          if (e <= -pm || e >= pm) continue;
          double best = kInf;
          for (double w : ends) best = std::min(best, std::abs(w - e));
          EXPECT_LE(best, 1e-12) << "plane " << k << " query " << q;
        }
    }
  });
  std::printf("  %ld queries (%ld on convex loops, %ld others, of which %ld asked of a hull's loop with pockets), "
              "%ld touching, %ld directions\n",
              checked, convex_queries, tree_queries, pocket_queries, touching, directions);
  EXPECT_GE(convex_queries, 2000);
  EXPECT_GE(pocket_queries, 200);
  EXPECT_GE(tree_queries, 1000);
  EXPECT_GE(touching, 50);
}

// AngleIndex (the hull's and a convex loop's searches by direction) against std::lower_bound,
// on sorted angles in [-2, 2] with runs of equal ones, few and many, and queries at the angles,
// next to them, between them, at +-2 and beyond.
TEST(SectionSkin, AngleIndexFindsTheFirstAngleAtOrPast) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-2.0, 2.0);
  long checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<double> a(1 + trial % 60);
    for (double& x : a) x = U(rng);
    if (trial % 3 == 0)  // runs of equal angles (collinear edges)
      for (std::size_t i = 1; i < a.size(); i += 2) a[i] = a[i - 1];
    if (trial % 5 == 0) a.front() = -2.0, a.back() = 2.0;
    std::sort(a.begin(), a.end());
    PlaneRegion::AngleIndex index;
    index.build(a);
    std::vector<double> ts = {-2.0, 2.0, -2.5, 2.5, std::nextafter(-2.0, 0.0), std::nextafter(2.0, 0.0)};
    for (double x : a) ts.insert(ts.end(), {x, std::nextafter(x, -3.0), std::nextafter(x, 3.0)});
    for (int i = 0; i < 20; ++i) ts.push_back(U(rng));
    for (double t : ts) {
      const auto it = std::lower_bound(a.begin(), a.end(), t);
      const int want = it == a.end() ? 0 : static_cast<int>(it - a.begin());
      ASSERT_EQ(index.first_at_least(t), want) << "trial " << trial << " t " << t;
      ++checked;
    }
  }
  EXPECT_GE(checked, 30000);
}

// The wedge kept per thread: asked again, and asked in turn for angles of other bits (+0 after -0,
// a neighbour, beyond pi), it answers as computed afresh, to the bit.
TEST(SectionSkin, WedgeAnswersToTheBit) {
  auto formula = [](double angle) {
    return std::abs(angle) >= kPi ? (angle < 0.0 ? -2.0 : 2.0)
                                  : PlaneRegion::pseudo_angle(Vec2::UnitX(), Vec2(std::cos(angle), std::sin(angle)));
  };
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-4.0, 4.0);
  std::vector<double> asked = {0.0, -0.0, 0.0, -0.0, -0.0, 0.3, 0.3, std::nextafter(0.3, 1.0), 0.3, kPi, -kPi, 1e-300};
  for (int i = 0; i < 200; ++i) {
    const double x = U(rng);
    asked.insert(asked.end(), {x, x, -x, x});
  }
  for (double x : asked) {
    const PlaneRegion::Wedge w = PlaneRegion::wedge(x);
    EXPECT_EQ(bits_of(w.within), bits_of(x)) << x;
    EXPECT_EQ(bits_of(w.pm), bits_of(formula(x))) << x;
    EXPECT_EQ(bits_of(w.c), bits_of(std::cos(x))) << x;
    EXPECT_EQ(bits_of(w.s), bits_of(std::sin(x))) << x;
    EXPECT_EQ(bits_of(w.c_neg), bits_of(std::cos(-x))) << x;
    EXPECT_EQ(bits_of(w.s_neg), bits_of(std::sin(-x))) << x;
  }
}

// pseudo_angles_of(v) is pseudo_angle(UnitX, v) and pseudo_angle(UnitX, -v) but for the sign of a
// zero, so that every AngleIndex lookup of either is the same: random directions, the axes and
// diagonals, zero and signed-zero components, tiny and huge ones.
TEST(SectionSkin, PseudoAnglesOfBothWaysAreTheSingleOnes) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<Vec2> vs;
  for (double x : {0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 3e300, -3e300})
    for (double y : {0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 3e300, -3e300})
      if (x != 0.0 || y != 0.0) vs.emplace_back(x, y);
  for (int i = 0; i < 5000; ++i) vs.push_back(Vec2(U(rng), U(rng)) * std::pow(10.0, U(rng) * 6.0));
  std::vector<double> angles;
  for (int i = 0; i < 41; ++i) angles.push_back(-2.0 + 0.1 * i);
  PlaneRegion::AngleIndex index;
  index.build(angles);
  for (const Vec2& v : vs) {
    const auto [along, against] = PlaneRegion::pseudo_angles_of(v);
    const double p = PlaneRegion::pseudo_angle(Vec2::UnitX(), v), q = PlaneRegion::pseudo_angle(Vec2::UnitX(), -v);
    ASSERT_TRUE(along == p && against == q) << v.transpose();  // == : +0 and -0 alike
    if (p != 0.0) ASSERT_EQ(bits_of(along), bits_of(p)) << v.transpose();
    if (q != 0.0) ASSERT_EQ(bits_of(against), bits_of(q)) << v.transpose();
    ASSERT_EQ(index.first_at_least(along), index.first_at_least(p));
    ASSERT_EQ(index.first_at_least(against), index.first_at_least(q));
  }
}

// clear() against every segment and a parity test of them, on convex regions (one loop:
// clear() asks the loop, PlaneRegion::convex_clear) and others (the tree): segments along the
// boundary a hair to millimetres off it either side, chords across R and segments wholly inside
// it, lines along R's edges (a box's faces) and random ones. Where the segment passes within a
// nanometre of the boundary without touching it (within rounding of the threshold) no answer is
// asserted; elsewhere clear() is: no segment within touching distance, and a outside the
// boundary (R as its segments bound it, which lies within flatten outside the exact R). And
// inside(a), for a more than a nanometre off the boundary, is that parity test's answer.
TEST(SectionSkin, ClearMatchesEverySegment) {
  long checked = 0, convex_checked = 0, pocket_checked = 0, blocked = 0, inside_checked = 0;
  for_each_test_region(41, [](int k) { return (k % 3) * 0.002; }, [&](Scene& s, int k, const PlaneRegion& region) {
    const PlaneRegion* R = &region;
    const auto& segs = R->segments();
    for (int q = 0; q < 300; ++q) {
      const auto& g = segs[static_cast<std::size_t>(s.u() * segs.size())];
      const Vec2 at = g.a + s.u() * (g.b - g.a);
      Vec2 a, b;
      if (q % 3 == 0) {  // along the segment, off it by 10^-13 to 10^-2.5 m, either side
        const double off = std::pow(10.0, -13.0 + 10.5 * s.u()) * (q % 2 ? -1.0 : 1.0);
        const Vec2 along = rotate_planar((g.b - g.a).normalized(), (s.u() - 0.5) * 0.02);
        a = at + off * g.normal - s.u() * 0.02 * along;
        b = a + (0.005 + 0.02 * s.u()) * along;
      } else if (q % 6 == 1) {  // ending 10^-13 to 10^-6 m short of the boundary point, heading into R
        const Vec2 in = rotate_planar(-g.normal, (s.u() - 0.5) * 2.0);
        b = at - std::pow(10.0, -13.0 + 7.0 * s.u()) * in;
        a = b - (0.002 + 0.03 * s.u()) * in;
      } else if (q % 3 == 1) {  // from near the boundary point, in a random direction
        const double t = 2 * kPi * s.u();
        a = at + std::pow(10.0, -9.0 + 6.5 * s.u()) * (q % 2 ? -1.0 : 1.0) * g.normal;
        b = a + (0.002 + 0.05 * s.u()) * Vec2(std::cos(t), std::sin(t));
      } else {  // between two boundary points (a chord), shortened or lengthened
        const auto& h = segs[static_cast<std::size_t>(s.u() * segs.size())];
        const Vec2 other = h.a + s.u() * (h.b - h.a), mid = 0.5 * (at + other);
        const double f = 0.2 + 1.2 * s.u();
        a = mid + f * (at - mid);
        b = mid + f * (other - mid);
      }
      const double best = boundary_apart(segs, a, b);
      if (best > 1e-12 && best < 2e-9) continue;  // within rounding of the threshold
      const bool in = inside_by_parity(segs, a);  // a in R
      const bool want = best > 1e-12 && !in;
      const double a_off = boundary_apart(segs, a, a);  // a's distance to the boundary
      if (a_off > 2e-9) {
        ASSERT_EQ(R->inside(a), in) << "plane " << k << " query " << q << " a " << a_off << " off the boundary";
        ++inside_checked;
      }
      ASSERT_EQ(R->clear(a, b, false), want) << "plane " << k << " query " << q << " best " << best;
      ++checked;
      convex_checked += R->convex();
      pocket_checked += R->pockets() > 0 && R->loop_answers(a, b, 0.0);  // asked of a hull's loop
      blocked += !want;
    }
  });
  std::printf("  %ld decisions (%ld on convex loops, %ld asked of hulls' loops with pockets), %ld not clear; %ld inside tests\n",
              checked, convex_checked, pocket_checked, blocked, inside_checked);
  EXPECT_GE(pocket_checked, 3000);
  EXPECT_GE(inside_checked, 8000);
  EXPECT_GE(checked, 10000);
  EXPECT_GE(convex_checked, 5000);
  EXPECT_GE(blocked, 3000);
  EXPECT_GE(checked - blocked, 2000);
}

// inside() at points midway between two parallel sides of R (a box's section: the nearest
// pieces tie on opposite sides, where their normals cancel) and just off the middle: the exact
// 3D test's answer.
TEST(SectionSkin, InsideMidwayBetweenParallelSides) {
  // The box turned (about a slanted axis): its opposite faces' normals, and so the sides', are
  // then opposite only to rounding, not to the bit.
  test::Mesh m = test::box(Vec3(0.03, 0.02, 0.05));
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  for (Eigen::Index i = 0; i < m.vertices.rows(); ++i) m.vertices.row(i) = (turn * m.vertices.row(i).transpose()).transpose();
  Scene s(m, 43);
  long checked = 0;
  for (int k = 0; k < 16; ++k) {
    // planes through the box's centre holding its z axis, turned about it (sections are
    // rectangles), with their in-plane axes turned too (the rectangle's sides slant in plane
    // coordinates, so that long sides' boxes cover the cells between them)
    const double t = 2 * kPi * s.u(), beta = (k % 4 == 0) ? 0.0 : 2 * kPi * s.u();
    const Vec3 h = turn * Vec3(std::cos(t), std::sin(t), 0.0), z = turn * Vec3::UnitZ();
    FingerPlane pl;
    pl.origin = s.c;
    pl.u = std::cos(beta) * h + std::sin(beta) * z;
    pl.p = -std::sin(beta) * h + std::cos(beta) * z;
    const PlaneRegion* R = s.skin.region(pl, (k % 2) * 0.003);
    ASSERT_NE(R, nullptr);
    ASSERT_FALSE(R->segments().empty());
    const double width = std::abs(0.03 * std::cos(t)) + std::abs(0.02 * std::sin(t));  // half the width along h
    auto at = [&](double along_h, double along_z) {  // the plane coordinates of c + along_h h + along_z z
      const Vec3 x = along_h * h + along_z * z;
      return Vec2(x.dot(pl.u), x.dot(pl.p));
    };
    for (int q = 0; q < 50; ++q) {
      // midway between the two sides along z, then between the two across it, at exactly the
      // middle or up to 1e-7 m off it, anywhere along them
      const double off = q % 2 ? 0.0 : (s.u() - 0.5) * 2e-7;
      for (const Vec2& x : {at(off, (2.0 * s.u() - 1.0) * 0.045), at((2.0 * s.u() - 1.0) * 0.9 * width, off)}) {
        // inside() (on these convex regions its loop answers first) and the nearest piece's
        // side test itself
        EXPECT_EQ(R->inside(x), R->inside_3d(x)) << "plane " << k << " point " << q;
        EXPECT_EQ(R->inside_from(R->nearest(x, x), x), R->inside_3d(x)) << "plane " << k << " point " << q;
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 800);
}

// Regions whose loops turn right by a rounding where an edge runs along -x (vertical planes
// through a 600-sided cylinder: a top side split by a collinear vertex an ulp lower): the edges'
// angles then cross the wrap twice, and a search by direction found the wrong extremes (a segment
// crossing the top side was called clear). And a pivot whose link reaches a loop vertex exactly:
// the stretch's end segment has no part within the disk, and the span lost its end (the link
// turned into R). Both found in review; clear() and any_within() are checked against every
// segment on p = z planes as well.
TEST(SectionSkin, ConvexShortcutsOnRoundingTurnsAndVerticesOnTheCircle) {
  const test::Mesh m = test::cylinder(0.035, 0.05, 600);
  const auto object = std::make_shared<Object>(m.vertices, m.faces);
  {
    SectionSkin skin(object, 2e-7);
    FingerPlane pl;
    pl.origin = Vec3(0.0046703851087754062, 0.0068471528134885027, -0.0064341936655412839);
    pl.u = Vec3(-0.31131682680437966, -0.95030617873843792, 0);
    pl.p = Vec3(0, 0, 1);
    const PlaneRegion* R = skin.region(pl, 0.0);
    const Vec2 a(0.0071780162569404504, 0.056494332520531987), b(0.034182365498839004, 0.01409289983481544);
    ASSERT_FALSE(R->inside(a));
    ASSERT_TRUE(R->inside(b));
    EXPECT_FALSE(R->clear(a, b, false));
    EXPECT_TRUE(R->any_within(a, b, 1e-3));
  }
  {
    SectionSkin skin(object, 2e-7);
    FingerPlane pl;
    pl.origin = Vec3::Zero();
    pl.u = Vec3(1, 0, 0);
    pl.p = Vec3(0, 0.6, 0.8);
    const PlaneRegion* R = skin.region(pl, 0.0);
    const Vec2 pivot(0, 0.070000000000000007), end(6.8698568884673227e-05, 0.056219429022451271);
    RotateRequest rr = test::rotate_request(pl, pivot, end, 0.0, -kInf, 1.0);
    rr.pivot_outside = true;
    const RotateResult r = skin.rotate_until_free(rr);
    ASSERT_TRUE(r.ok);
    EXPECT_GT(R->nearest(pivot, r.end).distance, 0.0);
    EXPECT_TRUE(R->clear(pivot, r.end, true));
  }
  // p = z planes (and tilted a hair) through the 600-sided cylinder and a box: clear() and
  // any_within() against every segment, away from the thresholds' rounding.
  long checked = 0;
  for (const test::Mesh& mm : {m, test::box(Vec3(0.03, 0.02, 0.05))}) {
    Scene s(mm, 51);
    for (int k = 0; k < 16; ++k) {
      FingerPlane pl;
      const double t = 2 * kPi * s.u();
      pl.origin = s.c + Vec3(s.u() - 0.5, s.u() - 0.5, 0.0) * 0.02;
      pl.u = Vec3(std::cos(t), std::sin(t), 0.0);
      pl.p = k % 2 ? Vec3::UnitZ() : Vec3(1e-9 * s.u(), 0.0, 1.0).normalized();
      pl.p = (pl.p - pl.p.dot(pl.u) * pl.u).normalized();
      const PlaneRegion* R = s.skin.region(pl, (k % 3) * 0.002);
      ASSERT_NE(R, nullptr);
      const auto& segs = R->segments();
      if (segs.empty()) continue;
      for (int q = 0; q < 200; ++q) {
        const auto& g = segs[static_cast<std::size_t>(s.u() * segs.size())];
        const Vec2 a = g.a + s.u() * (g.b - g.a) + (s.u() - 0.3) * 0.01 * g.normal;
        const double dir = 2 * kPi * s.u();
        const Vec2 b = a + (0.002 + 0.05 * s.u()) * Vec2(std::cos(dir), std::sin(dir));
        const double best = boundary_apart(segs, a, b);
        if (best > 1e-12 && best < 2e-9) continue;
        ASSERT_EQ(R->clear(a, b, false), best > 1e-12 && !inside_by_parity(segs, a)) << "plane " << k << " query " << q;
        for (double d : {1e-6, 1e-3})
          if (std::abs(best - d) > 2e-9) ASSERT_EQ(R->any_within(a, b, d), best <= d) << "plane " << k << " query " << q;
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 5000);
}

// PlaneRegion::depth_within (the exact swept-link test): against the depth sampled densely along
// the segment (a point's depth in R changes no faster than the point moves), on chords across
// R's boundary at depths about the allowance, in random planes.
TEST(SectionSkin, DepthWithinMatchesDenseSampling) {
  for (const test::Mesh& m : {test::icosphere(3, Vec3(0.04, 0.03, 0.035)), test::curvy(4), test::curvy(2)}) {
    const auto object = std::make_shared<Object>(m.vertices, m.faces);
    const SectionSkin skin(object, kFlatten);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    const Vec3 c = object->bounds().centre();
    int yes = 0, no = 0;
    for (int k = 0; k < 16; ++k) {
      const FingerPlane pl = test::random_plane(rng, c);
      const PlaneRegion* R = skin.region(pl, (k % 2) * 0.004);
      ASSERT_NE(R, nullptr);
      if (R->segments().empty()) continue;
      for (int q = 0; q < 40; ++q) {
        const double allow = q % 2 ? 2e-5 : 1e-3;
        const auto& s = R->segments()[static_cast<std::size_t>(U(rng) * R->segments().size()) % R->segments().size()];
        const Vec2 p = s.a + U(rng) * (s.b - s.a), t(-s.normal.y(), s.normal.x());
        const double h = (4.0 * U(rng) - 1.0) * allow, len = 0.002 + 0.03 * U(rng), tilt = 0.2 * (U(rng) - 0.5);
        const Vec2 dir = std::cos(tilt) * t + std::sin(tilt) * s.normal, mid = p - h * s.normal;
        const Vec2 a = mid - 0.5 * len * dir, b = mid + 0.5 * len * dir;
        constexpr int kSamples = 4000;
        double deepest = -kInf;
        for (int i = 0; i <= kSamples; ++i) {
          const Vec2 x = a + (b - a) * (static_cast<double>(i) / kSamples);
          const PlaneRegion::Near nr = R->nearest(x, x);
          deepest = std::max(deepest, R->inside(x) ? nr.distance : -nr.distance);
        }
        const bool within = R->depth_within(a, b, allow);
        (within ? yes : no)++;
        if (within)
          EXPECT_LE(deepest, allow + 1e-12) << "plane " << k << " query " << q;
        else
          EXPECT_GT(deepest, allow - len / kSamples - 1e-12) << "plane " << k << " query " << q;
      }
    }
    EXPECT_GE(yes, 100);
    EXPECT_GE(no, 100);
  }
}

// Clinging into a window narrower than the margin: two boxes 4 um apart, a link of 5 cm from a
// pivot on the slit's midline, turned 0.01 rad into one box. The free directions through the slit
// are +-40 urad wide, less than the margin of half the tolerance of end motion (100 urad): the
// link turns to the middle of the window (half of it beyond the run's end) and is free there.
TEST(SectionSkin, RotateUntilFreeFitsANarrowWindow) {
  constexpr double w = 4e-6;
  test::Mesh left = test::box(Vec3(0.01, 0.02, 0.02), Vec3(-0.01 - 0.5 * w, 0, 0));
  const test::Mesh right = test::box(Vec3(0.01, 0.02, 0.02), Vec3(0.01 + 0.5 * w, 0, 0));
  const Eigen::Index nv = left.vertices.rows(), nf = left.faces.rows();
  PointsN3 V(nv + right.vertices.rows(), 3);
  FacesN3 F(nf + right.faces.rows(), 3);
  V << left.vertices, right.vertices;
  F << left.faces, right.faces.array() + nv;
  const SectionSkin skin(std::make_shared<Object>(V, F), kFlatten);
  FingerPlane pl;  // z = 0: x along the boxes, y along the slit
  pl.u = Vec3::UnitX();
  pl.p = Vec3::UnitY();
  const Vec2 pivot(0.0, 0.03);
  for (double side : {1.0, -1.0}) {
    const double start = side * 0.01;  // turned into one box, then the other
    const Vec2 end = pivot + 0.05 * Vec2(std::sin(start), -std::cos(start));
    ASSERT_FALSE(skin.link_free(pl, pivot, end, 0.0, -kInf));
    const RotateRequest rr = test::rotate_request(pl, pivot, end, 0.0, -kInf, kPi);
    const RotateResult res = skin.rotate_until_free(rr);
    ASSERT_TRUE(res.ok);
    EXPECT_TRUE(skin.link_free(pl, pivot, res.end, 0.0, -kInf));
    EXPECT_LT(std::abs(res.end.x()), 0.5 * w);           // through the slit
    EXPECT_NEAR(res.angle, -start, 0.5 * w / 0.05 + 1e-9);  // the smallest rotation, into the window
  }
}

// The pieces the skin keeps are R's boundary: every segment's ends and points along it are, in
// 3D, at most r + flatten from O (also where chains of them were simplified), and no closer than
// r less 10 nm: the parts of pieces that lie inside R are all dropped, also runs of pieces beyond
// a crossing that cross nothing themselves (curvy's dents; they lay up to 83 um inside R before),
// the parts of crossed pieces that a third feature covers (the torus's hole, curvy's dents: one
// 3D test per run of them decides), and the arcs of vertices of high degree (the cylinder's cap
// centres).
TEST(SectionSkin, BoundaryLiesJustOutsideRIn3D) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  double worst_in = 0.0, worst_out = 0.0;
  long samples = 0;
  for (const test::Mesh& m : {test::icosphere(5, Vec3::Constant(0.04)), test::icosphere(3, Vec3(0.05, 0.03, 0.02)),
                              test::curvy(4), test::curvy(5), test::box(Vec3(0.03, 0.02, 0.05)),
                              test::cylinder(0.035, 0.05, 48), test::torus(0.03, 0.012, 48, 24)}) {
    auto object = std::make_shared<Object>(m.vertices, m.faces);
    const Aabb box = object->bounds();
    for (int k = 0; k < 12; ++k) {
      const Vec3 origin = box.centre() + Vec3(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5).cwiseProduct(box.extent()) * 0.6;
      const FingerPlane pl = test::random_plane(rng, origin);
      const double r = k % 2 == 0 ? 0.004 : 0.001;
      const PlaneRegion R(object, pl, r, kFlatten);
      for (const auto& s : R.segments())
        for (double t : {0.0, 0.25, 0.5, 0.75, 1.0}) {
          const Vec3 X = pl.to_world(s.a + t * (s.b - s.a));
          const double d = object->nearest(X, X).signed_distance;
          worst_in = std::max(worst_in, r - d);
          worst_out = std::max(worst_out, d - r);
          ++samples;
        }
    }
  }
  std::printf("  %ld boundary samples: deepest inside R %.3g m, farthest outside %.3g m (flatten %.3g m)\n", samples,
              worst_in, worst_out, kFlatten);
  EXPECT_GT(samples, 10000);
  EXPECT_LE(worst_out, kFlatten + 1e-12);
  EXPECT_LE(worst_in, 1e-8);
}

// Planes that meet the mesh in a degenerate way, as a symmetric object's middle planes do: the
// plane z = 0 through the middle ring of a banded cylinder (perpendicular to the side's edges
// there, so that the arcs of the two edges above and below each ring vertex and the vertex's own
// arc coincide) and planes through the axis that hold side edges (each edge's line and a face's
// piece coincide). Coincident copies are left out: R's boundary has no two segments between the
// same end points on the same side, it lies at r from O (to the flattening), the side test agrees
// with 3D, and the boundary is about as small as that of a plane moved off the degenerate place
// by a hair (with the copies, every vertex was a junction: no chain was simplified, and every
// segment asked a 3D test).
TEST(SectionSkin, DegeneratePlanesGiveNoCoincidentPieces) {
  const test::Mesh m = test::cylinder(0.035, 0.0125, 48, 2);
  auto object = std::make_shared<Object>(m.vertices, m.faces);
  const double r = 0.004;
  auto plane = [](const Vec3& origin, const Vec3& u, const Vec3& p) {
    FingerPlane pl;
    pl.origin = origin;
    pl.u = u.normalized();
    pl.p = p.normalized();
    return pl;
  };
  const double tilt = 1e-3;  // a hair off: no longer through the ring or the edges
  const std::vector<std::pair<FingerPlane, FingerPlane>> cases = {
      {plane(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()), plane(Vec3(0, 0, 1e-4), Vec3(1, 0, tilt), Vec3::UnitY())},
      {plane(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitZ()), plane(Vec3::Zero(), Vec3(1, tilt, 0), Vec3::UnitZ())},
      {plane(Vec3::Zero(), Vec3(std::cos(kPi / 8), std::sin(kPi / 8), 0), Vec3::UnitZ()),
       plane(Vec3::Zero(), Vec3(std::cos(kPi / 8 + tilt), std::sin(kPi / 8 + tilt), 0), Vec3::UnitZ())}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-0.05, 0.05);
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const PlaneRegion R(object, cases[k].first, r, kFlatten), near(object, cases[k].second, r, kFlatten);
    const FingerPlane& pl = cases[k].first;
    const auto& segs = R.segments();
    ASSERT_FALSE(segs.empty());
    long copies = 0;
    for (std::size_t i = 0; i < segs.size(); ++i)
      for (std::size_t j = i + 1; j < segs.size(); ++j) {
        const auto &x = segs[i], &y = segs[j];
        const bool same = ((x.a - y.a).norm() < 1e-9 && (x.b - y.b).norm() < 1e-9) ||
                          ((x.a - y.b).norm() < 1e-9 && (x.b - y.a).norm() < 1e-9);
        copies += same && x.normal.dot(y.normal) > 0.0;
      }
    double worst_in = 0.0, worst_out = 0.0;
    for (const auto& sg : segs)
      for (double t : {0.0, 0.5, 1.0}) {
        const Vec3 X = pl.to_world(sg.a + t * (sg.b - sg.a));
        const double d = object->nearest(X, X).signed_distance;
        worst_in = std::max(worst_in, r - d);
        worst_out = std::max(worst_out, d - r);
      }
    long sides = 0, disagree = 0;
    for (int q = 0; q < 2000; ++q) {
      const Vec2 x(U(rng), U(rng));
      const Vec3 X = pl.to_world(x);
      const double d = std::max(object->nearest(X, X).signed_distance, 0.0);
      if (std::abs(d - r) <= 1e-6) continue;
      ++sides;
      disagree += R.inside(x) != (d <= r);
    }
    std::printf("  plane %zu: %zu segments (%zu a hair off), %ld copies, inside R by %.3g m, outside by %.3g m, "
                "%ld of %ld side tests disagree\n",
                k, segs.size(), near.segments().size(), copies, worst_in, worst_out, disagree, sides);
    EXPECT_EQ(copies, 0) << "plane " << k;
    EXPECT_LE(worst_in, 1e-8) << "plane " << k;
    EXPECT_LE(worst_out, kFlatten + 1e-12) << "plane " << k;
    EXPECT_EQ(disagree, 0) << "plane " << k;
    EXPECT_GT(sides, 1500) << "plane " << k;
    EXPECT_LE(static_cast<double>(segs.size()), 1.5 * static_cast<double>(near.segments().size()) + 8.0)
        << "plane " << k;
  }
}

// A closed loop of pieces that crosses nothing can lie inside R: a sphere of radius 8 mm in the
// hole of a torus (tube from 10 to 30 mm from the axis) gives, in the torus's plane with r = 4 mm,
// the sphere's circle at 12 mm (inside the torus) and the torus's inner circle at 6 mm (inside
// the sphere), while R is the whole disk to 34 mm. Both loops are dropped, and the side test
// knows the gap between the two parts for inside R.
TEST(SectionSkin, ClosedLoopsInsideRAreDropped) {
  test::Mesh ball = test::icosphere(3);
  ball.vertices *= 0.008;
  const test::Mesh m = test::join(test::torus(0.02, 0.01, 64, 32), ball);
  auto object = std::make_shared<Object>(m.vertices, m.faces);
  FingerPlane pl;
  pl.origin = Vec3::Zero();
  pl.u = Vec3::UnitX();
  pl.p = Vec3::UnitY();
  const double r = 0.004;
  const PlaneRegion R(object, pl, r, kFlatten);
  ASSERT_FALSE(R.segments().empty());
  double nearest_to_axis = kInf, worst_in = 0.0;
  for (const auto& s : R.segments())
    for (double t : {0.0, 0.5, 1.0}) {
      const Vec2 x = s.a + t * (s.b - s.a);
      nearest_to_axis = std::min(nearest_to_axis, x.norm());
      const Vec3 X = pl.to_world(x);
      worst_in = std::max(worst_in, r - object->nearest(X, X).signed_distance);
    }
  std::printf("  %zu segments, the nearest %.4g m from the axis, deepest inside R %.3g m\n", R.segments().size(),
              nearest_to_axis, worst_in);
  EXPECT_GT(nearest_to_axis, 0.033);  // only the outer circle, at about 34 mm, is left
  EXPECT_LE(worst_in, 1e-8);
  for (double x : {0.0, 0.005, 0.009, 0.012, 0.02, 0.032}) EXPECT_TRUE(R.inside(Vec2(x, 0.0))) << x;
  EXPECT_FALSE(R.inside(Vec2(0.036, 0.0)));
}

// Boundary following in closed form (the level curve walked exactly) against the generic
// marching procedure, on random tips just outside R in random planes: where the closed form
// answers, its head lies on the level curve and `step` from the tip (to rounding), and within
// 2% of a step of the generic head (whose projections stop within 10% of the level).
TEST(SectionSkin, FollowBoundaryMatchesTheGenericWalk) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  long asked = 0, closed = 0;
  double worst = 0.0;
  for (const test::Mesh& m : {test::icosphere(4, Vec3::Constant(0.04)), test::curvy(4), test::box(Vec3(0.03, 0.02, 0.05))}) {
    auto object = std::make_shared<Object>(m.vertices, m.faces);
    const SectionSkin skin(object);
    const Aabb box = object->bounds();
    for (int k = 0; k < 20; ++k) {
      const FingerPlane pl = test::random_plane(rng, box.centre() + 0.3 * Vec3(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5).cwiseProduct(box.extent()));
      const double r = k % 2 == 0 ? 0.004 : 0.0;
      const PlaneRegion* R = skin.region(pl, r);
      ASSERT_NE(R, nullptr);
      if (R->segments().empty()) continue;
      for (int q = 0; q < 40; ++q) {
        // A tip at a random gap up to twice the level off a random boundary point.
        const auto& sg = R->segments()[static_cast<std::size_t>(U(rng) * R->segments().size()) % R->segments().size()];
        FollowRequest fr;
        fr.plane = pl;
        fr.radius = r;
        fr.step = 1e-3;
        fr.level = 5e-5;
        fr.tip = sg.a + U(rng) * (sg.b - sg.a) + (0.1 + 1.9 * U(rng)) * fr.level * sg.normal;
        if (R->inside(fr.tip)) continue;
        ++asked;
        Vec2 head;
        int pieces = 0;
        if (!R->follow(fr.tip, fr.level, fr.step, 16 * fr.step, fr.root, fr.reach, fr.front, &head, &pieces)) continue;
        ++closed;
        const Touch t = skin.link(pl, head, head, r);
        EXPECT_NEAR(t.gap, fr.level, 1e-9) << "plane " << k << " tip " << q;
        const double chord = (head - fr.tip).norm();
        EXPECT_TRUE(std::abs(chord - fr.step) <= 1e-9 || chord < fr.step) << chord;
        const FollowResult g = skin.Sensing::follow_boundary(fr);  // the generic procedure
        if (g.steps > 0 && std::abs((g.head - fr.tip).norm() - fr.step) < 1e-6 && std::abs(chord - fr.step) < 1e-9) {
          worst = std::max(worst, (g.head - head).norm());
          EXPECT_LE((g.head - head).norm(), 0.02 * fr.step) << "plane " << k << " tip " << q;
        }
      }
    }
  }
  std::printf("  %ld tips: %ld walked in closed form, farthest from the generic head %.3g m (step 1 mm)\n", asked,
              closed, worst);
  EXPECT_GT(asked, 1000);
  EXPECT_GT(closed, asked / 2);
}

// Boundary following where another part of R comes nearer than the level: two boxes with a slot
// between their regions 15 um wide (r = 1 mm, level 50 um), the tip in the slot. The chain the
// walk offsets is not the only boundary near the head: the head it hands back must still have
// the level for gap (else no step, as the generic walk gives), never a gap below zero.
TEST(SectionSkin, FollowBoundaryKeepsItsLevelInANarrowSlot) {
  const double r = 0.001, level = 5e-5, slot = 2 * r + 0.3 * level;
  const test::Mesh A = test::box(Vec3(0.01, 0.01, 0.01)), B = test::box(Vec3(0.01, 0.01, 0.01), Vec3(0.02 + slot, 0, 0));
  test::Mesh M;
  M.vertices.resize(A.vertices.rows() + B.vertices.rows(), 3);
  M.faces.resize(A.faces.rows() + B.faces.rows(), 3);
  M.vertices << A.vertices, B.vertices;
  M.faces << A.faces, (B.faces.array() + A.vertices.rows()).matrix();
  auto object = std::make_shared<Object>(M.vertices, M.faces);
  FingerPlane pl;
  pl.origin = Vec3::Zero();
  pl.u = Vec3::UnitX();
  pl.p = Vec3::UnitY();
  const SectionSkin skin(object);
  FollowRequest fr;
  fr.plane = pl;
  fr.radius = r;
  fr.step = 1e-3;
  fr.level = level;
  for (const double y : {-0.005, 0.0, 0.004}) {
    fr.tip = Vec2(0.01 + r + 0.25 * level, y);  // in the slot, outside R
    ASSERT_GT(skin.link(pl, fr.tip, fr.tip, r).gap, 0.0);
    const FollowResult res = skin.follow_boundary(fr);
    const double gap = skin.link(pl, res.head, res.head, r).gap;
    EXPECT_GE(gap, 0.0) << "y " << y;
    if (res.head != fr.tip) EXPECT_NEAR(gap, level, 0.1 * level) << "y " << y;
  }
}
