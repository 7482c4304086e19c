#include "hugger/world/section_skin.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>

#include "hugger/check.hpp"
#include "hugger/geometry/frame.hpp"
#include "hugger/geometry/harmonic.hpp"
#include "hugger/geometry/next.hpp"
#include "hugger/geometry/order.hpp"

namespace hugger {

namespace {

/// A new region's id: 1, 2, ... in the order regions are made, in any thread.
std::uint64_t next_region_id() {
  static std::atomic<std::uint64_t> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

/// Distances at or below this count as touching (closes rounding gaps between pieces).
constexpr double kTouch = 1e-12;
/// Ties between nearest pieces (a shared end point): their normals are summed.
constexpr double kTie = 1e-10;
/// End points of two pieces this close are joined (rounding of the same point computed twice).
constexpr double kJoin = 1e-10;
/// Spans of directions (pseudo-angles) overlapping or closer than this are one blocked run: no
/// link fits through a narrower window.
constexpr double kSpanJoin = 1e-9;
/// A link found free in closed form with at least this clearance (metres) at the blocked run's
/// end needs no check: far above the rounding of the spans.
constexpr double kCertain = 1e-9;
/// The margin (m) by which a convex region's shortcuts (convex_clear, convex_within,
/// convex_inside, convex_shallow) must find their answer, else they leave it to the tree: far
/// above kTouch and the rounding of their heights.
constexpr double kSureApart = 1e-9;
/// The most pockets a non-convex loop's hull may have for its shortcuts to be kept (build_loop).
constexpr int kMaxPockets = 16;

inline double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
/// Points in order of x, then y (monotone_chain's order).
inline bool x_then_y(const Vec2& p, const Vec2& q) { return p.x() < q.x() || (p.x() == q.x() && p.y() < q.y()); }
/// v turned a quarter to the left.
inline Vec2 left_of(const Vec2& v) { return Vec2(-v.y(), v.x()); }

/// A point of the plane with an id, for close_pairs.
struct IdPoint {
  double x, y;
  int id;
};

/// Calls f(i, j) (i < j, indices into pts as reordered here) for every two points of `pts`
/// within kJoin of each other: the same point computed twice, to rounding. The points are
/// ordered by slabs across x of width h >= kJoin (a radix sort of the slabs' numbers, no
/// comparisons); two points within kJoin lie in slabs at most one apart (two, allowing for
/// rounding), so each point is compared with those of its own and the next two slabs.
template <class F>
void close_pairs(std::vector<IdPoint>& pts, F&& f) {
  if (pts.empty()) return;
  double lo = pts[0].x, hi = pts[0].x;
  for (const IdPoint& p : pts) {
    lo = std::min(lo, p.x);
    hi = std::max(hi, p.x);
  }
  const double h = std::max(kJoin, (hi - lo) * 0x1p-30);  // slab numbers below 2^30 + 1
  std::vector<std::uint32_t> slab(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) slab[i] = static_cast<std::uint32_t>((pts[i].x - lo) / h);
  const std::vector<int> order = ascending_order(slab);
  std::vector<IdPoint> sorted(pts.size());
  std::vector<std::uint32_t> sorted_slab(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    sorted[i] = pts[order[i]];
    sorted_slab[i] = slab[order[i]];
  }
  pts.swap(sorted);
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t j = i + 1; j < pts.size() && sorted_slab[j] <= sorted_slab[i] + 2; ++j) {
      const double dx = pts[j].x - pts[i].x, dy = pts[j].y - pts[i].y;
      if (dx * dx + dy * dy <= kJoin * kJoin) f(i, j);
    }
}

/// Union-find over `parent` (each index its own root at first): the root of x's set, halving the
/// path on the way. join() hangs the larger root under the smaller, so a set's root is its least
/// index.
inline int set_root(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}
inline void join_sets(std::vector<int>& parent, int x, int y) {
  x = set_root(parent, x);
  y = set_root(parent, y);
  if (x != y) parent[std::max(x, y)] = std::min(x, y);
}

/// The end a boundary segment leads to when walked with R on the left (along its outward normal
/// turned a quarter to the left), and the end it comes from.
inline const Vec2& head_of(const PlaneRegion::Segment& s) { return (s.b - s.a).dot(left_of(s.normal)) >= 0.0 ? s.b : s.a; }
inline const Vec2& tail_of(const PlaneRegion::Segment& s) { return &head_of(s) == &s.b ? s.a : s.b; }

/// Distance between 2D segments [p1, q1] and [p2, q2], with the closest points.
double segment_distance(const Vec2& p1, const Vec2& q1, const Vec2& p2, const Vec2& q2, Vec2* c1, Vec2* c2) {
  const Vec2 d1 = q1 - p1, d2 = q2 - p2, w = p2 - p1;
  const double denom = cross2(d1, d2);
  if (denom != 0.0) {
    const double s = cross2(w, d2) / denom, t = cross2(w, d1) / denom;
    if (s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0) {
      *c1 = p1 + s * d1;
      *c2 = *c1;
      return 0.0;
    }
  }
  double best = kInf;
  auto point_segment = [&](const Vec2& p, const Vec2& a, const Vec2& b, bool p_on_first) {
    const Vec2 ab = b - a;
    const double l2 = ab.squaredNorm();
    double s = l2 > 0.0 ? (p - a).dot(ab) / l2 : 0.0;
    s = std::clamp(s, 0.0, 1.0);
    const Vec2 q = a + s * ab;
    const double d = (p - q).squaredNorm();
    if (d < best) {
      best = d;
      *c1 = p_on_first ? p : q;
      *c2 = p_on_first ? q : p;
    }
  };
  point_segment(p1, p2, q2, true);
  if (d1.x() != 0.0 || d1.y() != 0.0) {
    point_segment(q1, p2, q2, true);
    point_segment(p2, p1, q1, false);
    point_segment(q2, p1, q1, false);
  }
  return std::sqrt(best);
}

/// A segment query's bounds, for the node test.
struct Query {
  Vec2 a, b, lo, hi, n;
  Vec2 n_abs = Vec2::Zero();  ///< |n|, componentwise
  Vec2 u = Vec2::Zero();      ///< unit direction from a to b (a != b)
  double len = 0.0;       ///< |b - a|
  bool line = false;      ///< n is the unit normal of the query's line (a != b)
  Query(const Vec2& a_, const Vec2& b_) : a(a_), b(b_), lo(a_.cwiseMin(b_)), hi(a_.cwiseMax(b_)) {
    const Vec2 d = b - a;
    len = d.norm();
    if (len > 0.0) {
      n = Vec2(-d.y(), d.x()) / len;
      n_abs = n.cwiseAbs();
      u = d / len;
      line = true;
    }
  }
  /// A margin for rounding in the cheap bounds below, for coordinates up to `extent`. reach()'s
  /// hints rely on it too: a segment within a distance less this margin lies in no node that
  /// node_farther puts beyond that distance (keep it so if the bounds change).
  double slack(double extent) const { return 1e-12 * (extent + std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff())); }
};

/// True when segment [p0, p1] (unit normal `normal` of its line) lies farther than `limit` from
/// the query: a cheap lower bound tried before the exact distance (the larger of the separation
/// across the segment's line and the distance between the two segments' boxes in the query's
/// frame). The caller adds a rounding margin to `limit`: a segment this rejects would have been
/// rejected by its exact distance.
inline bool farther_than(const Query& q, const Vec2& p0, const Vec2& p1, const Vec2& normal, double limit) {
  const double ha = normal.dot(q.a - p0), hb = normal.dot(q.b - p0);
  if ((ha > limit && hb > limit) || (ha < -limit && hb < -limit)) return true;
  double du, dn;
  if (q.line) {
    const Vec2 e0 = p0 - q.a, e1 = p1 - q.a;
    const double u0 = q.u.dot(e0), u1 = q.u.dot(e1), n0 = q.n.dot(e0), n1 = q.n.dot(e1);
    du = std::max({std::min(u0, u1) - q.len, -std::max(u0, u1), 0.0});
    dn = n0 > 0.0 && n1 > 0.0 ? std::min(n0, n1) : (n0 < 0.0 && n1 < 0.0 ? -std::max(n0, n1) : 0.0);
  } else {
    du = std::max({std::min(p0.x(), p1.x()) - q.a.x(), q.a.x() - std::max(p0.x(), p1.x()), 0.0});
    dn = std::max({std::min(p0.y(), p1.y()) - q.a.y(), q.a.y() - std::max(p0.y(), p1.y()), 0.0});
  }
  return du * du + dn * dn > limit * limit;
}

}  // namespace

// --- PlaneRegion --------------------------------------------------------------------------

PlaneRegion::PlaneRegion(std::shared_ptr<const Object> object, const FingerPlane& plane, double radius, double flatten)
    : PlaneRegion(std::move(object), plane, radius, flatten, FirstStage{}) {
  finish();
}

PlaneRegion::PlaneRegion(std::shared_ptr<const Object> object, const FingerPlane& plane, double radius, double flatten,
                         FirstStage)
    : object_(std::move(object)), id_(next_region_id()), plane_(plane), radius_(radius), flatten_(flatten) {
  HUGGER_CHECK_ARGUMENT(object_, "PlaneRegion needs an object");
  check_plane_frame(plane.origin, plane.u, plane.p);
  HUGGER_CHECK_ARGUMENT(radius >= 0.0 && std::isfinite(radius),
                        "PlaneRegion: the link radius must be finite and >= 0, got " << radius);
  HUGGER_CHECK_ARGUMENT(flatten > 0.0 && std::isfinite(flatten),
                        "PlaneRegion: the flattening tolerance must be positive, got " << flatten);
  build_pieces();
  mark_crossings();
  drop_inner_segments();
}

void PlaneRegion::finish() {
  // The chains may move out by what the arcs' flattening left of the tolerance (at least half).
  simplify(flatten_ - std::min(arc_deviation_, 0.5 * flatten_));
  build_bvh();
  build_cells();
  // reach()'s hints: none found yet; cells 8 of the label grid's a side (every query in slot 0
  // where there is no grid)
  for (auto& h : hints_) h.store(-1, std::memory_order_relaxed);
  hint_scale_ = cell_ > 0.0 ? 0.125 / cell_ : 0.0;
  link_segments();
  build_loop();
}

namespace {

/// The pseudo-angles (from +x) of the edges of the closed polygon v (edge i from v[i] to
/// v[i + 1]; convex, counter-clockwise) into `index`, from the edge after they wrap round, made
/// non-decreasing (the roundings of nearly collinear edges) so that a search finds an edge;
/// returns that first edge. The wrap is the largest drop from one edge to the next: 4 less the
/// turn there, rounding elsewhere (the smallest angle is no guide, as two nearly collinear edges
/// may round in the wrong order). `fall` (if given): the most an angle lay below one before it
/// from there, which the index hides; more than rounding where the polygon turns back across
/// the wrap (a right turn at an edge along -x: two drops of about 4).
int index_edge_angles(const std::vector<Vec2>& v, PlaneRegion::AngleIndex* index, double* fall = nullptr) {
  const int k = static_cast<int>(v.size());
  std::vector<double> angle(k, 0.0);
  for (int i = 0; i < k && k > 1; ++i) angle[i] = PlaneRegion::pseudo_angle(Vec2::UnitX(), v[(i + 1) % k] - v[i]);
  int start = 0;
  double drop = -kInf;
  for (int i = 0; i < k; ++i) {
    const double d = angle[(i + k - 1) % k] - angle[i];
    if (d > drop) {
      drop = d;
      start = i;
    }
  }
  std::vector<double> sorted;
  if (fall != nullptr) *fall = 0.0;
  for (int i = 0; i < k; ++i) {
    const double a = angle[(start + i) % k];
    if (i > 0 && fall != nullptr) *fall = std::max(*fall, sorted.back() - a);
    sorted.push_back(i == 0 ? a : std::max(a, sorted.back()));
  }
  index->build(std::move(sorted));
  return start;
}

}  // namespace

namespace {

/// Andrew's monotone chain over n distinct points, at(k) the k-th in order of x, then y: the
/// lower hull left to right, then the upper right to left (counter-clockwise from the first
/// point), as indices k; points on an edge are left out. n <= 2: every point.
template <class At>
std::vector<int> monotone_chain(int n, At&& at) {
  std::vector<int> h;
  if (n <= 2) {
    for (int k = 0; k < n; ++k) h.push_back(k);
    return h;
  }
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t floor = h.size();
    for (int k = 0; k < n; ++k) {
      const int i = pass == 0 ? k : n - 1 - k;
      while (h.size() >= floor + 2 &&
             cross2(at(h[h.size() - 1]) - at(h[h.size() - 2]), at(i) - at(h[h.size() - 2])) <= 0.0)
        h.pop_back();
      h.push_back(i);
    }
    h.pop_back();  // the first point of the other pass
  }
  return h;
}

/// The convex hull of a closed polygon's vertices v as indices into v, in v's order from the
/// smallest (points on a hull edge are left out). v is a counter-clockwise simple polygon (R's
/// boundary: its pieces never cross, drop_inner_segments); false where the hull's vertices do not
/// come in v's order round it, which a clockwise v shows (the order does not prove v simple).
bool hull_of_polygon(const std::vector<Vec2>& v, std::vector<int>* hull) {
  const int n = static_cast<int>(v.size());
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return x_then_y(v[a], v[b]); });
  std::vector<int> h = monotone_chain(n, [&](int k) -> const Vec2& { return v[order[k]]; });
  if (h.size() < 3) return false;
  for (int& i : h) i = order[i];
  std::rotate(h.begin(), std::min_element(h.begin(), h.end()), h.end());
  for (std::size_t k = 1; k < h.size(); ++k)
    if (!(h[k] > h[k - 1])) return false;
  *hull = std::move(h);
  return true;
}

}  // namespace

void PlaneRegion::clear_loop() {
  loop_kind_ = LoopKind::kNone;
  loop_.clear();
  loop_tail_.clear();
  pockets_.clear();
}

void PlaneRegion::build_loop() {
  clear_loop();
  const int n = static_cast<int>(segments_.size());
  if (n < 3) return;
  // One loop through every segment,
  std::vector<int> loop;
  loop.reserve(n);
  int i = 0;
  do {
    loop.push_back(i);
    i = next_[i];
  } while (i > 0 && static_cast<int>(loop.size()) < n);
  if (i != 0 || static_cast<int>(loop.size()) != n) return;
  std::vector<Vec2> all(n);
  for (int k = 0; k < n; ++k) all[k] = tail_of(segments_[loop[k]]);
  // turning left at every vertex (up to a billionth of a radian: rounding): a convex R, whose
  // loop is kept whole. Otherwise the loop of R's convex hull H, whose vertices are some of R's:
  // between two of them either one segment of R, or a pocket of H outside R (under a lid, the
  // hull's edge across it), where the shortcuts do not answer (near_pocket).
  auto turns_right = [](const Vec2& e0, const Vec2& e1) { return cross2(e0, e1) < -1e-9 * e0.norm() * e1.norm(); };
  bool convex = true;
  for (int k = 0; k < n && convex; ++k)
    convex = !turns_right(all[(k + 1) % n] - all[k], all[(k + 2) % n] - all[(k + 1) % n]);
  std::vector<int> keep;  // indices into `loop` of the hull loop's vertices
  if (convex) {
    keep.resize(n);
    for (int k = 0; k < n; ++k) keep[k] = k;
  } else if (!hull_of_polygon(all, &keep)) {
    return;
  }
  const int m = static_cast<int>(keep.size());
  std::vector<Vec2> tail(m);
  std::vector<LoopEdge> edge(m);
  std::vector<Pocket> pockets;
  for (int k = 0; k < m; ++k) {
    const int from = keep[k], to = k + 1 < m ? keep[k + 1] : keep[0] + n;
    tail[k] = all[from];
    if (to == from + 1) {
      const Segment& g = segments_[loop[from]];
      edge[k] = {g.a, g.b, g.normal};
      continue;
    }
    const Vec2 d = all[to % n] - all[from];  // a lid; R lies on its left
    edge[k] = {all[from], all[to % n], Vec2(d.y(), -d.x()).normalized()};
    Pocket p{all[from], all[from]};
    for (int j = from + 1; j <= to; ++j) {
      p.lo = p.lo.cwiseMin(all[j % n]);
      p.hi = p.hi.cwiseMax(all[j % n]);
    }
    pockets.push_back(p);
  }
  // Every query near a pocket goes to the tree, after a test of each pocket's box: H's loop
  // pays only where pockets are few (a closed chain's one notch, where its simplification starts
  // and ends), not where R is bumpy all along.
  if (static_cast<int>(pockets.size()) > kMaxPockets) return;
  Vec2 centre = Vec2::Zero();
  for (int k = 0; k < m; ++k) centre += tail[k];
  centre /= static_cast<double>(m);
  // (The hull turns left at every vertex as monotone_chain builds it; a turn the wrong way by
  // more than rounding would also fail the edges' wrap test below.)
  // ... and once round the centre: the tails' angles about it increase from the smallest.
  std::vector<double> angle(m);
  for (int k = 0; k < m; ++k) angle[k] = pseudo_angle(Vec2::UnitX(), tail[k] - centre);
  const int start = static_cast<int>(std::min_element(angle.begin(), angle.end()) - angle.begin());
  for (int k = 1; k < m; ++k)
    if (!(angle[(start + k) % m] > angle[(start + k - 1) % m])) return;
  std::vector<double> polar;
  for (int k = 0; k < m; ++k) {
    loop_.push_back(edge[(start + k) % m]);
    loop_tail_.push_back(tail[(start + k) % m]);
    polar.push_back(angle[(start + k) % m]);
  }
  loop_polar_.build(std::move(polar));
  loop_centre_ = centre;
  pockets_ = std::move(pockets);
  loop_kind_ = pockets_.empty() ? LoopKind::kConvex : LoopKind::kPockets;
  // The edges' directions turn counter-clockwise along the loop, wrapping round once: where a
  // right turn within rounding takes an edge back across the wrap, they do not (not kept).
  double fall = 0.0;
  loop_edge_first_ = index_edge_angles(loop_tail_, &loop_edges_, &fall);
  if (fall > 1e-9) clear_loop();
}

int PlaneRegion::hint_key(const Vec2& a) const {
  const double x = (a.x() - cells_lo_.x()) * hint_scale_, y = (a.y() - cells_lo_.y()) * hint_scale_;
  auto cell = [](double v) { return v > 0.0 ? static_cast<unsigned>(std::min(v, 1e6)) : 0u; };  // NaN: 0
  // Two large odd multipliers mix the cell's coordinates (a common spatial hash); unsigned
  // arithmetic wraps.
  return static_cast<int>((cell(x) * 73856093u ^ cell(y) * 19349663u) & (kHints - 1));
}

bool PlaneRegion::near_pocket(const Vec2& a, const Vec2& b, double distance) const {
  // The shortcuts' answers depend on R only within their margin of the query's reach: where
  // that is apart from every pocket, R and H agree there, and so do their boundaries.
  if (!(distance >= 0.0)) return true;  // (no caller asks so; the tree answers what it means)
  const double grow = distance + 2.0 * kSureApart;
  const Vec2 lo = a.cwiseMin(b).array() - grow, hi = a.cwiseMax(b).array() + grow;
  for (const Pocket& p : pockets_)
    if (p.lo.x() <= hi.x() && lo.x() <= p.hi.x() && p.lo.y() <= hi.y() && lo.y() <= p.hi.y()) return true;
  return false;
}

void PlaneRegion::link_segments() {
  // Each segment walked along R's boundary with R on the left (the direction of its normal
  // turned a quarter to the left) runs from its tail to its head; a segment's next is the one
  // whose tail is its head, to the bit (a chain's segments share their end points exactly).
  const int n = static_cast<int>(segments_.size());
  next_.assign(n, -1);
  struct Tail {
    double x, y;
    int segment;
    bool operator<(const Tail& o) const { return x < o.x || (x == o.x && (y < o.y || (y == o.y && segment < o.segment))); }
  };
  std::vector<Tail> tails(n);
  for (int i = 0; i < n; ++i) {
    const Vec2& tail = tail_of(segments_[i]);
    tails[i] = {tail.x(), tail.y(), i};
  }
  std::sort(tails.begin(), tails.end());
  for (int i = 0; i < n; ++i) {
    const Vec2& h = head_of(segments_[i]);
    const auto it = std::lower_bound(tails.begin(), tails.end(), Tail{h.x(), h.y(), -1});
    // Exactly one segment leaves this point (two: a junction, where the walk does not guess).
    if (it != tails.end() && it->x == h.x() && it->y == h.y() && it->segment != i &&
        (it + 1 == tails.end() || it[1].x != h.x() || it[1].y != h.y()))
      next_[i] = it->segment;
  }
}

bool PlaneRegion::follow(const Vec2& tip, double level, double step, double max_length, const Vec2& root,
                         double reach, double lowest, Vec2* head, int* pieces) const {
  // The level curve {gap = level} outside R is R's boundary moved out by `level`: each segment
  // moved along its normal, joined at a convex vertex by an arc of radius `level` about it, cut
  // where two moved segments cross at a concave one. Walked from the tip's projection onto it
  // (along the gap's gradient) with R on the left, to the first point `step` from the tip.
  *pieces = 0;
  if (nodes_.empty() || !(level > 0.0) || !(step > 0.0)) return false;
  const Near nr = nearest_noted(tip, tip, kInf);
  if (!(nr.distance > 0.0) || !std::isfinite(nr.distance) || nr.segment < 0 || inside_from(nr, tip)) return false;
  const double l = level;
  auto acceptable = [&](const Vec2& x) { return (x - root).norm() <= reach && x.y() >= lowest; };
  // The walk offsets the chain it is on, not the rest of the boundary: another part of it may come
  // nearer the head than the level (a narrow gap between two parts of R). A head is kept only if
  // its measured gap is the level to within a tenth, as the generic walk's projections are.
  auto on_level = [&](const Vec2& x) {
    const Near hn = nearest(x, x, 2.0 * level);
    return std::isfinite(hn.distance) && std::abs(hn.distance - level) <= 0.1 * level && !inside_from(hn, x);
  };
  double walked = 0.0;
  Vec2 at;  // the walk's current point on the level curve
  // Where the segment from `from` to `to` leaves the circle |x - tip| = step: its parameter t.
  auto cross_segment = [&](const Vec2& from, const Vec2& to, double* t) {
    const Vec2 d = to - from, w = from - tip;
    const double a = d.squaredNorm(), b = w.dot(d), c = w.squaredNorm() - step * step;
    if (!(a > 0.0)) return false;
    const double disc = b * b - a * c;
    if (disc < 0.0) return false;
    const double r = (-b + std::sqrt(disc)) / a;
    if (!(r >= 0.0 && r <= 1.0)) return false;
    *t = r;
    return true;
  };
  // The arc of radius l about c from direction d0, turning left through `sweep`: where it leaves
  // the circle |x - tip| = step, the head (by bisection on the angle: the distance from the tip
  // grows along the arc where it leaves the circle; 1, or -1 if that point is not acceptable),
  // else the walk goes on from the arc's end (0).
  auto arc = [&](const Vec2& c, const Vec2& d0, double sweep) {
    const double th0 = std::atan2(d0.y(), d0.x());
    auto arc_at = [&](double a) { return Vec2(c + l * Vec2(std::cos(th0 + a), std::sin(th0 + a))); };
    if ((arc_at(sweep) - tip).norm() >= step) {
      double lo = 0.0, hi = sweep;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        ((arc_at(mid) - tip).norm() >= step ? hi : lo) = mid;
      }
      const Vec2 x = arc_at(hi);
      if (!acceptable(x) || !on_level(x)) return -1;
      *head = x;
      ++*pieces;
      return 1;
    }
    walked += l * sweep;
    at = arc_at(sweep);
    return 0;
  };
  int k = nr.segment;
  const Segment* s = &segments_[k];
  // The arc about c from direction d0 through `sweep` (none at a concave or straight vertex),
  // then onto segment `onto`: nonzero where the head lies on the arc (1) or is refused there (-1).
  auto turn_onto = [&](const Vec2& c, const Vec2& d0, double sweep, int onto) {
    if (sweep > 0.0) {
      const int done = arc(c, d0, sweep);
      if (done != 0) return done;
    }
    k = onto;
    s = &segments_[k];
    ++*pieces;
    return 0;
  };
  const Vec2 g = (tip - nr.on_region) / nr.distance;
  at = nr.on_region + l * g;
  if (!acceptable(at)) return false;
  // Where the tip's nearest point is a vertex, the walk starts on its arc: finish the arc first.
  const Vec2 h0 = head_of(*s);
  const bool on_head = (nr.on_region - h0).squaredNorm() <= kJoin * kJoin;
  const bool on_tail = !on_head && (nr.on_region - tail_of(*s)).squaredNorm() <= kJoin * kJoin;
  if (on_tail || on_head) {
    // Turning left from g to the normal of the segment the arc leads onto.
    const int onto = on_head ? next_[k] : k;
    if (onto < 0) return false;
    const Vec2 n1 = segments_[onto].normal, c = on_head ? h0 : nr.on_region;
    const double sweep = std::atan2(cross2(g, n1), g.dot(n1));
    if (sweep < -1e-9) return false;  // not a convex corner between them: the generic walk decides
    if (const int done = turn_onto(c, g, sweep, onto)) return done > 0;
  }
  // Then segment by segment: the moved segment from `at` to its end (its head moved out, or the
  // crossing with the next moved segment at a concave vertex), then the arc at a convex vertex.
  for (int guard = 0; guard < 4096; ++guard) {
    const Vec2 n = s->normal, t = left_of(n), hk = head_of(*s);
    const int nx = next_[k];
    Vec2 end = hk + l * n;
    double sweep = 0.0;
    if (nx >= 0) {
      const Vec2 n1 = segments_[nx].normal;
      const double turn = cross2(t, left_of(n1)), dot = n.dot(n1);
      if (turn < 0.0) {
        // Concave: the moved segments cross at hk + l (n + n1) / (1 + n . n1).
        if (!(1.0 + dot > 1e-6)) return false;
        end = hk + (l / (1.0 + dot)) * (n + n1);
      } else {
        sweep = std::atan2(turn, dot);
      }
    }
    if ((end - at).dot(t) < 0.0) return false;  // cut back past the walk: the generic walk decides
    double tc;
    if (cross_segment(at, end, &tc)) {
      const Vec2 x = at + tc * (end - at);
      if (!acceptable(x) || !on_level(x)) return false;
      *head = x;
      ++*pieces;
      return true;
    }
    walked += (end - at).norm();
    at = end;
    // Out of the finger's reach or behind the palm, or a junction of pieces: the generic walk
    // decides (it stops at its last acceptable sample, or steps across the junction).
    if (!acceptable(at) || nx < 0) return false;
    if (walked >= max_length) {
      if (!on_level(at)) return false;
      *head = at;  // as far as the generic walk would go without reaching the chord
      return true;
    }
    if (const int done = turn_onto(hk, n, sweep, nx)) return done > 0;
  }
  return false;
}

void PlaneRegion::simplify(double tol) {
  const int n = static_cast<int>(segments_.size());
  if (n < 3) return;
  std::vector<char> tested(n, 0);  // per segment: a 3D test found it on R's boundary
  // The end points, joined where they lie within kJoin (one vertex).
  auto point = [&](int e) -> const Vec2& { return e % 2 == 0 ? segments_[e / 2].a : segments_[e / 2].b; };
  std::vector<IdPoint> ends(2 * n);  // id: 2 * segment + (0: a, 1: b)
  for (int e = 0; e < 2 * n; ++e) ends[e] = {point(e).x(), point(e).y(), e};
  std::vector<int> parent(2 * n);
  for (int i = 0; i < 2 * n; ++i) parent[i] = i;
  close_pairs(ends, [&](std::size_t i, std::size_t j) { join_sets(parent, ends[i].id, ends[j].id); });
  std::vector<int> vertex(2 * n);  // each end's vertex (its root end)
  for (int e = 0; e < 2 * n; ++e) vertex[e] = set_root(parent, e);
  // A segment whose two ends are one vertex (an arc shorter than kJoin, where two pieces meet)
  // is left out: the chain through its vertex joins its neighbours at one point.
  std::vector<char> used(n, 0);
  for (int e = 0; e < 2 * n; e += 2)
    if (vertex[e] == vertex[e + 1]) used[e / 2] = 1;
  // Per vertex: how many segment ends.
  std::vector<int> degree(2 * n, 0);
  for (int e = 0; e < 2 * n; ++e)
    if (!used[e / 2]) ++degree[vertex[e]];
  // Coincident pieces: where the plane meets the mesh in a degenerate way (through a ring of
  // vertices, perpendicular to the edges there, as a symmetric object's middle plane does), the
  // arcs of two edges and of their shared vertex, or a face's piece and the line of an edge
  // parallel to the plane, are the same segment between the same two vertices. Such a copy with
  // the same outward side adds nothing to R's boundary, but would make each of its vertices a
  // junction (and so every segment a 3D test, and no chain longer than a segment): the first of
  // them is kept, the others left out. A copy is between two vertices of degree 3 or more, so
  // only their segments are compared.
  {
    std::vector<std::array<int, 3>> between;  // the two vertices (lower first) and the segment
    for (int i = 0; i < n; ++i) {
      const int v0 = vertex[2 * i], v1 = vertex[2 * i + 1];
      if (!used[i] && degree[v0] > 2 && degree[v1] > 2) between.push_back({std::min(v0, v1), std::max(v0, v1), i});
    }
    std::sort(between.begin(), between.end());
    for (std::size_t k = 0; k < between.size();) {
      std::size_t end = k + 1;
      while (end < between.size() && between[end][0] == between[k][0] && between[end][1] == between[k][1]) ++end;
      for (std::size_t j = k + 1; j < end; ++j) {
        const int i = between[j][2];
        if (segments_[i].normal.dot(segments_[between[k][2]].normal) <= 0.0) continue;  // R on both sides: kept
        used[i] = 1;
        --degree[between[j][0]];
        --degree[between[j][1]];
      }
      k = end;
    }
  }
  // With the crossings cut and the parts on a crossing piece's inner side dropped, the segments
  // left form runs joined end to end, two at each inner vertex; a run lies wholly on R's boundary
  // or wholly inside R (no segment has parts on both sides: a crossing the search misses, within
  // 1e-9 of a segment's end or at an angle below 1e-9, could leave a gap of about that size; and
  // where two joined segments are on different sides, R's boundary goes on along a third, which
  // makes their vertex a junction). A run inside R (pieces that another feature covers, with or
  // without crossing anything) is left with a loose end (a vertex of one segment) where it joined
  // a dropped part, or meets R's boundary at a junction (a vertex of three or more); on R's
  // boundary, the runs close into loops. So each segment with such an end, not tested yet, is
  // tested once and dropped if inside R, which may leave its neighbour loose in turn, and each
  // loop once below: a few tests per plane, rather than one per part of a crossed piece. A
  // segment is tested at its middle. For r = 0 the pieces are O's own section, which has no runs
  // inside O, and lie on its surface, where the test cannot tell.
  std::vector<int> queue;
  for (int e = 0; e < 2 * n && radius_ > 0.0; ++e)
    if (!used[e / 2] && degree[vertex[e]] != 2 && !tested[e / 2]) queue.push_back(e / 2);
  if (!queue.empty()) {
    std::vector<int> start(2 * n + 1, 0), at(2 * n);  // the segment ends of each vertex
    for (int e = 0; e < 2 * n; ++e)
      if (!used[e / 2]) ++start[vertex[e] + 1];
    for (int v = 0; v < 2 * n; ++v) start[v + 1] += start[v];
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (int e = 0; e < 2 * n; ++e)
        if (!used[e / 2]) at[fill[vertex[e]]++] = e;
    }
    while (!queue.empty()) {
      const int i = queue.back();
      queue.pop_back();
      if (tested[i]) continue;
      tested[i] = 1;
      if (!strictly_inside_3d(0.5 * (segments_[i].a + segments_[i].b))) continue;
      used[i] = 1;  // dropped
      ++dropped_;
      for (const int e : {2 * i, 2 * i + 1}) {
        const int v = vertex[e];
        if (--degree[v] == 2) continue;
        for (int k = start[v]; k < start[v + 1]; ++k)
          if (!used[at[k] / 2] && !tested[at[k] / 2]) queue.push_back(at[k] / 2);
      }
    }
  }
  // Per vertex: the first two segment ends left (degree is its count of them).
  std::vector<int> first(2 * n, -1), second(2 * n, -1);
  for (int e = 0; e < 2 * n; ++e) {
    if (used[e / 2]) continue;
    const int v = vertex[e];
    if (first[v] < 0) first[v] = e;
    else if (second[v] < 0) second[v] = e;
  }
  // Chains: runs of segments through vertices where exactly two meet, walked from a vertex
  // where some other number meet (or, for a closed loop, from any vertex).
  std::vector<Segment> out;
  out.reserve(n);
  std::vector<Vec2> P;
  std::vector<int> seg;
  // A closed loop (every vertex of it joins two segments) that crosses nothing lies wholly on
  // R's boundary or wholly inside R (a separate part of O within r of another gives one): unless
  // a segment of it was tested already, the middle of its longest segment is tested, and a loop
  // inside R is dropped (not for r = 0: see the run test above).
  auto walk = [&](int e0, bool closed) {  // e0: the end of the first segment the chain leaves from
    P.assign(1, point(e0));
    seg.clear();
    for (int e = e0;;) {
      const int i = e / 2;
      used[i] = 1;
      seg.push_back(i);
      const int other = e ^ 1;  // the segment's other end
      P.push_back(point(other));
      const int v = vertex[other];
      if (degree[v] != 2) break;
      const int next = first[v] == other ? second[v] : first[v];
      if (used[next / 2]) {
        if (next == e0) P.back() = P[0];  // a closed loop, back at its start: the same point
        break;
      }
      e = next;
    }
    if (closed && radius_ > 0.0 && std::none_of(seg.begin(), seg.end(), [&](int i) { return tested[i]; })) {
      const auto longest = std::max_element(seg.begin(), seg.end(), [&](int a, int b) {
        return (segments_[a].b - segments_[a].a).squaredNorm() < (segments_[b].b - segments_[b].a).squaredNorm();
      });
      if (strictly_inside_3d(0.5 * (segments_[*longest].a + segments_[*longest].b))) {
        dropped_ += static_cast<long>(seg.size());
        return;
      }
    }
    simplify_chain(P, seg, tol, &out);
  };
  for (int e = 0; e < 2 * n; ++e)
    if (!used[e / 2] && degree[vertex[e]] != 2) walk(e, false);
  for (int e = 0; e < 2 * n; e += 2)
    if (!used[e / 2]) walk(e, true);
  segments_.swap(out);
}

void PlaneRegion::simplify_chain(const std::vector<Vec2>& P, const std::vector<int>& seg, double tol,
                                 std::vector<Segment>* out) const {
  const int k = static_cast<int>(seg.size());
  // R lies on one side of the whole chain: `side` is +1 when the outward normals point to the
  // left of the walk. A chain that is not (it should be) keeps its segments.
  const double side0 = left_of(P[1] - P[0]).dot(segments_[seg[0]].normal) >= 0.0 ? 1.0 : -1.0;
  bool consistent = true;
  for (int i = 0; i < k && consistent; ++i)
    consistent = side0 * left_of(P[i + 1] - P[i]).dot(segments_[seg[i]].normal) > 0.0;
  auto emit = [&](std::vector<Segment>* to, const Vec2& a, const Vec2& b, int piece) {
    const Vec2 d = b - a;
    const double len = d.norm();
    if (!(len > 0.0)) return;
    Segment s;
    s.a = a;
    s.b = b;
    s.normal = side0 * left_of(d) / len;
    s.piece = piece;
    to->push_back(s);
  };
  if (!consistent || k < 2) {
    for (int i = 0; i < k; ++i) out->push_back(segments_[seg[i]]);
    return;
  }
  // Each inner vertex is convex (R's boundary turns toward R there: the outward side bulges)
  // or not. A run of segments whose inner vertices are all convex is replaced by lines of some
  // of its segments (supporting lines: R lies behind each), meeting where they cross; a run whose
  // inner vertices are all concave or straight by chords between some of its vertices (R lies
  // behind each chord). Either way every original vertex lies behind the new segments and within
  // `tol` of them, and runs meet at original vertices.
  // Kind of inner vertex v (0 < v < k): +1 convex, -1 concave, 0 straight to rounding (a piece
  // meeting its tangent neighbour), which either kind of run takes.
  // True when every vertex v0..v1 lies behind the chord from -> to (outward side up to rounding),
  // at most `depth` behind it, and between its ends (to `slack` times its length).
  auto behind = [&](const Vec2& from, const Vec2& to, int v0, int v1, double depth, double slack) {
    const Vec2 d = to - from;
    const double len = d.norm();
    if (!(len > 0.0)) return false;
    const Vec2 nrm = side0 * left_of(d) / len;  // outward
    for (int v = v0; v <= v1; ++v) {
      const double h = (P[v] - from).dot(nrm), t = (P[v] - from).dot(d);
      if (!(h <= 1e-12 && h >= -depth && t >= -slack * len && t <= len * len + slack * len)) return false;
    }
    return true;
  };
  auto kind = [&](int v) {
    const Vec2 d0 = P[v] - P[v - 1], d1 = P[v + 1] - P[v];
    const double c = side0 * cross2(d0, d1);
    if (std::abs(c) <= 1e-9 * d0.norm() * d1.norm()) return 0;
    return c < 0.0 ? 1 : -1;
  };
  for (int s0 = 0; s0 < k;) {
    // The run: segments s0 .. e - 1, inner vertices s0 + 1 .. e - 1 of one kind.
    int e = s0 + 1, run = 0;
    for (; e < k; ++e) {
      const int v = kind(e);
      if (v != 0 && run != 0 && v != run) break;
      if (run == 0) run = v;
    }
    if (run > 0) {
      // R is convex along the run. Two ways to bound it from outside, the one with fewer
      // segments kept: (1) lines of some of its segments (R lies behind each), from the first
      // segment's to the last's, each line to where it crosses the farthest next one whose
      // crossing lies within tol of the chain (ahead of the one and short of the other): a run
      // of long straight stretches keeps them and loses the rounded corners between; (2) chords
      // of the chain moved out by tol: from the current point (the run's start, or a vertex moved
      // out along its normal) to the farthest vertex, moved out too (the run's end as it is),
      // with every vertex between behind the chord and between its ends: a finely divided curve
      // keeps a chord per length its curvature allows. The corners and moved vertices lie within
      // tol of the chain, and so do the segments between them (R is convex there).
      const std::size_t mark = out->size();
      int a = s0;
      Vec2 from = P[s0];
      while (a < e - 1) {
        int best = a + 1;
        Vec2 corner = P[a + 1];
        const Vec2 da = P[a + 1] - P[a];
        for (int b = a + 2; b < e; ++b) {
          const Vec2 db = P[b + 1] - P[b];
          const double den = cross2(da, db);
          // Along a's line (straight to rounding): no corner with it, the next segment may give one.
          if (std::abs(den) <= 1e-9 * da.norm() * db.norm()) continue;
          if (!(side0 * den < 0.0)) break;  // not turning toward R: the lines do not bound it
          const Vec2 w = P[a] + (cross2(P[b] - P[a], db) / den) * da;
          // (Where a straight stretch joins them, w is an end itself, to rounding.)
          if (!w.allFinite() || (w - P[a + 1]).dot(da) < -1e-12 * da.norm() || (P[b] - w).dot(db) < -1e-12 * db.norm())
            break;
          // w within tol of the chain from a to b: the nearest segment is within tol exactly
          // when some segment is (sqrt is monotonic), so the search stops at the first.
          bool near = false;
          for (int i = a; i <= b && !near; ++i) {
            const Vec2 d = P[i + 1] - P[i];
            const double l2 = d.squaredNorm();
            const double t = l2 > 0.0 ? std::clamp((w - P[i]).dot(d) / l2, 0.0, 1.0) : 0.0;
            near = std::sqrt((w - P[i] - t * d).squaredNorm()) <= tol;
          }
          if (!near) break;
          best = b;
          corner = w;
        }
        emit(out, from, corner, segments_[seg[a]].piece);
        from = corner;
        a = best;
      }
      emit(out, from, P[e], segments_[seg[a]].piece);
      const std::size_t by_lines = out->size() - mark;
      auto moved = [&](int v) {
        if (v == s0 || v == e) return P[v];
        const Vec2 nv = segments_[seg[v - 1]].normal + segments_[seg[v]].normal;
        const double len = nv.norm();
        return len > 0.0 ? Vec2(P[v] + (tol / len) * nv) : P[v];
      };
      std::vector<Segment> chords;
      a = s0;
      from = P[s0];
      while (a < e && chords.size() < by_lines) {
        int best = a + 1;
        Vec2 to = moved(a + 1);
        for (int b = a + 2; b <= e; ++b) {
          const Vec2 q = moved(b);
          if (!behind(from, q, a, b, kInf, 1e-12)) break;
          best = b;
          to = q;
        }
        emit(&chords, from, to, segments_[seg[a]].piece);
        from = to;
        a = best;
      }
      if (a == e && chords.size() < by_lines) {
        out->resize(mark);
        out->insert(out->end(), chords.begin(), chords.end());
      }
    } else {
      // Chords: from vertex a, the farthest vertex b with every vertex between behind the chord
      // (or on it), within tol of it, and between its ends.
      int a = s0;
      while (a < e) {
        int best = a + 1;
        for (int b = a + 2; b <= e && behind(P[a], P[b], a + 1, b - 1, tol, 0.0); ++b) best = b;
        emit(out, P[a], P[best], segments_[seg[a]].piece);
        a = best;
      }
    }
    s0 = e;
  }
}

void PlaneRegion::build_cells() {
  cells_.clear();
  if (segments_.empty()) return;
  const Vec2 lo(nodes_[0].lo[0], nodes_[0].lo[1]), hi(nodes_[0].hi[0], nodes_[0].hi[1]);  // the segments' box
  // About 64 cells along the longer side, one cell of padding all round (the outer cells lie
  // outside every segment's box: they belong to the unbounded group, outside R).
  constexpr int kCells = 64;
  const double size = (hi - lo).maxCoeff();
  if (!(size > 0.0) || !std::isfinite(size)) return;
  cell_ = size / kCells;
  cells_lo_ = lo - Vec2::Constant(cell_);
  for (int a = 0; a < 2; ++a) cells_n_[a] = static_cast<int>(std::ceil((hi[a] - lo[a]) / cell_)) + 3;
  const int nx = cells_n_[0], ny = cells_n_[1];
  cells_.assign(static_cast<std::size_t>(nx) * ny, 2);  // 2: free, not yet labelled
  // A segment marks every cell its box, grown by a margin for rounding, meets.
  const double margin = 1e-9 * (1.0 + extent_);
  auto clamp_cell = [&](double x, int a) {
    return std::clamp(static_cast<int>(std::floor((x - cells_lo_[a]) / cell_)), 0, cells_n_[a] - 1);
  };
  for (const Segment& s : segments_) {
    const Vec2 slo = s.a.cwiseMin(s.b).array() - margin, shi = s.a.cwiseMax(s.b).array() + margin;
    const int i0 = clamp_cell(slo.x(), 0), i1 = clamp_cell(shi.x(), 0), j0 = clamp_cell(slo.y(), 1),
              j1 = clamp_cell(shi.y(), 1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) cells_[static_cast<std::size_t>(j) * nx + i] = -1;
  }
  // Each group of free cells joined by shared sides holds no boundary: one test labels it, at its
  // first cell in row-major order. The groups are found row by row: the runs of free cells in a
  // row, each joined to the runs beside it in the row below (union-find; a group's root is its
  // first run).
  struct Run {
    int first, last;  ///< cell indices (row-major), one row
  };
  std::vector<Run> runs;
  std::vector<int> parent;
  int below = 0;  // the first run of the row below still worth comparing
  for (int j = 0; j < ny; ++j) {
    const int row = static_cast<int>(runs.size());
    const signed char* c = &cells_[static_cast<std::size_t>(j) * nx];
    for (int i = 0; i < nx;) {
      if (c[i] != 2) {
        ++i;
        continue;
      }
      int e = i;
      while (e + 1 < nx && c[e + 1] == 2) ++e;
      const int id = static_cast<int>(runs.size());
      runs.push_back({j * nx + i, j * nx + e});
      parent.push_back(id);
      // The runs of the row below that share a column with [i, e] (those ending before i share
      // none with this run or the ones after it in the row).
      while (below < row && runs[below].last - (j - 1) * nx < i) ++below;
      for (int b = below; b < row && runs[b].first - (j - 1) * nx <= e; ++b) join_sets(parent, b, id);
      i = e + 1;
    }
    below = row;
  }
  std::vector<signed char> label(runs.size());
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const int g = set_root(parent, static_cast<int>(k));
    if (g == static_cast<int>(k)) {
      const int start = runs[k].first;
      const Vec2 centre = cells_lo_ + cell_ * Vec2(start % nx + 0.5, start / nx + 0.5);
      label[k] = inside_from(nearest(centre, centre, kInf), centre) ? 1 : 0;
    } else {
      label[k] = label[static_cast<std::size_t>(g)];
    }
    std::fill(cells_.begin() + runs[k].first, cells_.begin() + runs[k].last + 1, label[k]);
  }
}

bool PlaneRegion::strictly_inside_3d(const Vec2& x) const {
  const Object& O = *object_;
  const Vec3 X = plane_.to_world(x);
  if (radius_ > 0.0) {
    // Within r less a margin of O's surface, or inside O: strictly inside R. One search for
    // the nearest triangle within r + flatten answers both: its distance, and where that is
    // beyond the margin, its side (the pseudo-normal's sign, well conditioned that far from
    // the surface). Every point of a piece lies within r + flatten / 2 of its feature, so the
    // search finds a triangle (should it not, Object::nearest signs the point by rays).
    const double margin = std::max(1e-9, 1e-7 * radius_);
    return O.nearest(X, X, radius_ + flatten_).signed_distance < radius_ - margin;
  }
  return O.inside(X);
}

void PlaneRegion::drop_inner_segments() {
  // Crossed segments are cut at their crossings. Then every part lies wholly on R's boundary or
  // wholly inside R; those that start on the inner side of a crossing piece are inside, and
  // dropped here; simplify() tests the runs of the rest.
  std::sort(cuts_.begin(), cuts_.end());
  std::vector<Segment> kept;
  kept.reserve(segments_.size() + cuts_.size());
  std::size_t c = 0;
  std::vector<double> at;
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    const Segment& s = segments_[i];
    if (c == cuts_.size() || cuts_[c].segment != static_cast<int>(i)) {  // not crossed
      kept.push_back(s);
      continue;
    }
    // Its cuts, then one part per interval between them.
    const std::size_t first_cut = c;
    at.assign(1, 0.0);
    for (; c < cuts_.size() && cuts_[c].segment == static_cast<int>(i); ++c) at.push_back(cuts_[c].t);
    at.push_back(1.0);
    Vec2 from = s.a;
    for (std::size_t k = 0; k + 1 < at.size(); ++k) {
      const Vec2 to = k + 2 == at.size() ? s.b : Vec2(s.a + at[k + 1] * (s.b - s.a));
      // The crossings at its two ends: a part that starts on the inner side of the crossing
      // piece is inside R (within r of that piece's feature). The outer side proves nothing (a
      // third feature may still cover the part): such parts are left to simplify()'s run tests.
      const bool inner_before = k > 0 && cuts_[first_cut + k - 1].after_inner;
      const bool inner_after = k + 2 < at.size() && !cuts_[first_cut + k].after_inner;
      if (inner_before || inner_after) {
        ++dropped_;
      } else {
        Segment part = s;
        part.a = from;
        part.b = to;
        kept.push_back(part);
      }
      from = to;
    }
  }
  cuts_.clear();
  cuts_.shrink_to_fit();
  segments_.swap(kept);
}

void PlaneRegion::add_segment(const Vec2& a, const Vec2& b, const Vec2& outward, int piece) {
  const Vec2 d = b - a;
  const double len = d.norm();
  if (!(len > 0.0)) return;
  Segment s;
  s.a = a;
  s.b = b;
  s.normal = Vec2(d.y(), -d.x()) / len;
  if (s.normal.dot(outward) < 0.0) s.normal = -s.normal;
  s.piece = piece;
  segments_.push_back(s);
}

template <class Outward>
void PlaneRegion::add_arcs(Kind kind, std::int64_t feature, const Vec2& centre, const Vec2& U, const Vec2& V,
                           const std::vector<std::array<double, 2>>& allowed, Outward&& outward) {
  const double M = U.norm() + V.norm();
  if (!(M > 0.0) || allowed.empty()) return;
  // Tangent polygons: the tangents at t_j and t_j + dt meet at centre + (U cos + V sin)(t_j +
  // dt/2) / cos(dt/2), at most M (1 / cos(dt/2) - 1) <= flatten / 2 outside the curve (the
  // rest of the tolerance is the simplification's).
  const double dt_max = std::min(kPi / 3.0, 2.0 * std::acos(1.0 / (1.0 + 0.5 * flatten_ / M)));
  for (const auto& iv : allowed) {
    const double t0 = iv[0], t1 = iv[1];
    if (!(t1 - t0 > 1e-15)) continue;
    const int k = std::clamp(static_cast<int>(std::ceil((t1 - t0) / dt_max)), 1, 4096);
    const double dt = (t1 - t0) / k, sec = 1.0 / std::cos(0.5 * dt);
    arc_deviation_ = std::max(arc_deviation_, M * (sec - 1.0));
    const int piece = static_cast<int>(pieces_.size());
    pieces_.push_back({kind, feature});
    auto at = [&](double t, double scale) { return Vec2(centre + scale * (U * std::cos(t) + V * std::sin(t))); };
    Vec2 prev = at(t0, 1.0);
    for (int j = 0; j <= k; ++j) {
      const Vec2 next = j < k ? at(t0 + (j + 0.5) * dt, sec) : at(t1, 1.0);
      add_segment(prev, next, outward(j < k ? t0 + j * dt : t1), piece);
      prev = next;
    }
  }
}

void PlaneRegion::build_pieces() {
  const Object& O = *object_;
  const Vec3 nu = plane_.normal(), o = plane_.origin, u = plane_.u, p = plane_.p;
  const double r = radius_;
  auto height = [&](const Vec3& x) { return nu.dot(x - o); };
  auto to_plane = [&](const Vec3& x) { return plane_.to_plane(x); };
  auto in_plane = [&](const Vec3& d) { return Vec2(d.dot(u), d.dot(p)); };
  const double nabs[3] = {std::abs(nu.x()), std::abs(nu.y()), std::abs(nu.z())};
  // The faces within r of the plane (those whose pieces can meet it), in increasing order (the
  // pieces do not depend on the BVH): marked in a bitmap of the faces, then read off it.
  std::vector<std::uint64_t> in_band((static_cast<std::size_t>(O.faces().rows()) + 63) / 64, 0);
  double bound = r;
  O.bvh().traverse(
      [&](const Aabb& box) {
        const Vec3 c = box.centre(), h = 0.5 * box.extent();
        return std::abs(height(c)) - (nabs[0] * h.x() + nabs[1] * h.y() + nabs[2] * h.z());
      },
      [&](const std::array<Vec3, 3>& t, int id) {
        const double s0 = height(t[0]), s1 = height(t[1]), s2 = height(t[2]);
        if (std::min({s0, s1, s2}) <= r && std::max({s0, s1, s2}) >= -r)
          in_band[id >> 6] |= std::uint64_t{1} << (id & 63);
      },
      bound);
  std::vector<int> band;
  for (std::size_t w = 0; w < in_band.size(); ++w)
    for (std::uint64_t bits = in_band[w]; bits != 0; bits &= bits - 1)
      band.push_back(static_cast<int>(64 * w) + __builtin_ctzll(bits));
  const FacesN3& F = O.faces();
  const PointsN3& X = O.vertices();
  auto vertex = [&](std::int64_t i) { return Vec3(X.row(i).transpose()); };
  std::vector<char> vertex_seen(r > 0.0 ? static_cast<std::size_t>(X.rows()) : 0, 0);
  std::vector<char> vertex_mark(vertex_seen.size(), 0);  ///< an edge of the vertex has an arc
  for (const int f : band) {
    const std::int64_t idx[3] = {F(f, 0), F(f, 1), F(f, 2)};
    const Vec3 P[3] = {vertex(idx[0]), vertex(idx[1]), vertex(idx[2])};
    const Vec3& n = O.face_normal(f);
    // Face: the plane's section of the face moved out by r along its normal.
    const Vec2 n_in = in_plane(n);
    if (n_in.norm() > 1e-12) {
      Vec3 Q[3];
      double s[3];
      for (int k = 0; k < 3; ++k) {
        Q[k] = P[k] + r * n;
        s[k] = height(Q[k]);
        if (s[k] == 0.0) s[k] = 1e-300;  // symbolic perturbation: on the plane counts as above it
      }
      const bool pos[3] = {s[0] > 0, s[1] > 0, s[2] > 0};
      if (!(pos[0] == pos[1] && pos[1] == pos[2])) {
        int k = 0;  // the corner alone on its side
        if (pos[0] == pos[1]) k = 2;
        else if (pos[0] == pos[2]) k = 1;
        auto cut = [&](int i, int j) { return to_plane(Q[i] + (s[i] / (s[i] - s[j])) * (Q[j] - Q[i])); };
        const int piece = static_cast<int>(pieces_.size());
        pieces_.push_back({Kind::kFace, f});
        add_segment(cut(k, (k + 1) % 3), cut(k, (k + 2) % 3), n_in, piece);
      }
    }
    if (!(r > 0.0)) continue;
    // Edges: the plane's section of the cylinder of radius r about each edge, where the edge can
    // be the nearest feature (the outward wedge between its faces) and within the edge's slab.
    for (int k = 0; k < 3; ++k) {
      const std::int64_t ia = idx[k], ib = idx[(k + 1) % 3];
      if (ia > ib) continue;  // each edge once, from the face holding it as (low, high)
      const Vec3 &Pa = P[k], &Pb = P[(k + 1) % 3];
      const double sa = height(Pa), sb = height(Pb);
      if (std::min(sa, sb) > r || std::max(sa, sb) < -r) continue;
      const std::int64_t g = O.face_neighbor(f, k);
      {
        // A cheaper, looser form of the quick rejection below, before the edge's frame is built:
        // 1 - sqrt((1 + c) / 2) <= (1 - c) / 2 bounds the sag.
        const Vec3& nB = O.face_normal(g);
        const double da = n.dot(nu), db = nB.dot(nu), sag = 0.5 * (1.0 - n.dot(nB));
        if (std::min(sa, sb) + r * (std::min(da, db) - sag) - 1e-12 * r > 0.0 ||
            std::max(sa, sb) + r * (std::max(da, db) + sag) + 1e-12 * r < 0.0)
          continue;
      }
      std::int64_t ic = -1;
      for (int j = 0; j < 3; ++j)
        if (F(g, j) != ia && F(g, j) != ib) ic = F(g, j);
      if (ic < 0) continue;
      const Vec3 e = Pb - Pa;
      const double L = e.norm();
      if (!(L > 0.0)) continue;
      const Vec3 eh = e / L;
      auto perp = [&](const Vec3& x) { return Vec3(x - x.dot(eh) * eh); };
      const Vec3 tA = perp(P[(k + 2) % 3] - Pa), tB = perp(vertex(ic) - Pa);
      Vec3 e1 = tA.norm() > 0.0 ? Vec3(tA.normalized()) : Vec3(perp(n).normalized());
      if (!(e1.norm() > 0.5)) continue;
      const Vec3 e2 = eh.cross(e1);
      const Vec3& nB = O.face_normal(g);
      const Vec3 nsum = n + nB;
      // A concave edge is never the nearest feature of an outside point: no piece.
      if ((vertex(ic) - Pa).dot(n) > 0.0) continue;
      {
        // Quick rejection: the plane misses the wedge Pa + t e + r d (t in [0, 1], d on the arc
        // from nA to nB, which stays within 1 - cos(half angle) of their chord).
        const double sag = 1.0 - std::sqrt(std::max(0.0, 0.5 * (1.0 + n.dot(nB))));
        const double da = n.dot(nu), db = nB.dot(nu);
        const double lo = std::min(sa, sb) + r * (std::min(da, db) - sag) - 1e-12 * r;
        const double hi = std::max(sa, sb) + r * (std::max(da, db) + sag) + 1e-12 * r;
        if (lo > 0.0 || hi < 0.0) continue;
      }
      // The plane meets the edge's wedge: its end vertices' arcs may end on it.
      vertex_mark[static_cast<std::size_t>(ia)] = vertex_mark[static_cast<std::size_t>(ib)] = 1;
      Harmonic hs[5];
      int nh = 0;
      hs[nh++] = {0.0, r * e1.dot(tA), r * e2.dot(tA)};
      hs[nh++] = {0.0, r * e1.dot(tB), r * e2.dot(tB)};
      if (nsum.norm() > 1e-12) hs[nh++] = {0.0, -r * e1.dot(nsum), -r * e2.dot(nsum)};
      const double D = e.dot(nu), alpha = e1.dot(nu), beta = e2.dot(nu);
      const Vec2 E1 = in_plane(e1), E2 = in_plane(e2);
      const std::int64_t feature = 3 * static_cast<std::int64_t>(f) + k;
      if (std::abs(D) > 1e-9 * L) {
        // The plane meets the cylinder point Pa + t e + r (cos th e1 + sin th e2) at
        // t(th) = c0 + c1 cos th + c2 sin th: an ellipse, kept where 0 <= t <= 1.
        const double c0 = -sa / D, c1 = -r * alpha / D, c2 = -r * beta / D;
        hs[nh++] = {-c0, -c1, -c2};
        hs[nh++] = {c0 - 1.0, c1, c2};
        const auto allowed = allowed_intervals(hs, nh);
        if (allowed.empty()) continue;
        const Vec3 C3 = Pa + c0 * e, U3 = c1 * e + r * e1, V3 = c2 * e + r * e2;
        add_arcs(Kind::kEdge, feature, to_plane(C3), in_plane(U3), in_plane(V3), allowed,
                 [&](double t) { return Vec2(std::cos(t) * E1 + std::sin(t) * E2); });
      } else {
        // The edge is parallel to the plane: the section is up to two lines along it.
        const double sm = 0.5 * (sa + sb), A = r * std::hypot(alpha, beta);
        if (!(A > 0.0) || std::abs(sm) > A) continue;
        const double phi = std::atan2(beta, alpha), dphi = std::acos(std::clamp(-sm / A, -1.0, 1.0));
        for (int side = 0; side < (dphi > 0.0 ? 2 : 1); ++side) {
          const double th = side == 0 ? phi + dphi : phi - dphi;
          bool ok = true;
          for (int j = 0; j < nh && ok; ++j) ok = hs[j].at(th) <= 1e-12 * hs[j].scale();
          if (!ok) continue;
          const Vec3 d = r * (std::cos(th) * e1 + std::sin(th) * e2);
          const int piece = static_cast<int>(pieces_.size());
          pieces_.push_back({Kind::kEdge, feature});
          add_segment(to_plane(Pa + d), to_plane(Pb + d), in_plane(d), piece);
        }
      }
    }
  }
  if (!(r > 0.0)) return;
  // Vertices: the plane's circle on the sphere of radius r about each vertex, where the vertex
  // can be the nearest feature (the polar cone of its edges, on the outward side). The ends of a
  // vertex's arc lie on the wedges of its (convex) edges: a vertex none of whose edge wedges the
  // plane meets has an arc only when its whole circle lies in the cone.
  std::vector<Harmonic> hs;  // a vertex's constraints: one per edge and its pseudo-normal's
  for (const int f : band) {
    const std::int64_t idx[3] = {F(f, 0), F(f, 1), F(f, 2)};
    const Vec3 P[3] = {vertex(idx[0]), vertex(idx[1]), vertex(idx[2])};
    for (int k = 0; k < 3; ++k) {
      const std::int64_t iv = idx[k];
      if (vertex_seen[static_cast<std::size_t>(iv)]) continue;
      vertex_seen[static_cast<std::size_t>(iv)] = 1;
      const Vec3& V = P[k];
      const double sv = height(V);
      if (!(std::abs(sv) < r)) continue;
      const double rho = std::sqrt((r - sv) * (r + sv));
      if (!(rho > 1e-15)) continue;
      hs.resize(static_cast<std::size_t>(O.ring_end(iv) - O.ring_begin(iv)) + 1);
      int nh = 0;
      // An unmarked vertex's constraints are tested as they are made: each must hold on the
      // whole circle, and most vertices fail the first or second.
      const bool marked = vertex_mark[static_cast<std::size_t>(iv)];
      auto whole = [](const Harmonic& h) { return h.k0 + std::hypot(h.k1, h.k2) <= 0.0; };
      bool open = false;
      for (const std::int64_t* w = O.ring_begin(iv); w != O.ring_end(iv) && !open; ++w) {
        const Vec3 e = vertex(*w) - V;
        hs[nh++] = {-sv * nu.dot(e), rho * u.dot(e), rho * p.dot(e)};
        open = !marked && !whole(hs[nh - 1]);
      }
      if (open) continue;
      const Vec3& nv = O.vertex_normal(iv);
      if (nv.norm() > 1e-12) {
        hs[nh++] = {sv * nu.dot(nv), -rho * u.dot(nv), -rho * p.dot(nv)};
        if (!marked && !whole(hs[nh - 1])) continue;
      }
      if (surely_empty(hs.data(), nh)) continue;  // most marked vertices: their circle misses the cone
      const auto allowed = allowed_intervals(hs.data(), nh);
      if (allowed.empty()) continue;
      add_arcs(Kind::kVertex, iv, to_plane(V - sv * nu), Vec2(rho, 0.0), Vec2(0.0, rho), allowed,
               [](double t) { return Vec2(std::cos(t), std::sin(t)); });
    }
  }
}

int PlaneRegion::build_node(int begin, int end, std::vector<Vec2>& centres, int depth) {
  // centres[i] is the centre of segment order_[i]; the range [begin, end) of order_ is split in
  // place (median along the longer axis of the boxes; ties by index: a fixed order everywhere).
  depth_ = std::max(depth_, depth);
  const int id = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Node nd;
  nd.lo[0] = nd.lo[1] = kInf;
  nd.hi[0] = nd.hi[1] = -kInf;
  for (int i = begin; i < end; ++i) {
    const Segment& s = segments_[order_[i]];
    for (int a = 0; a < 2; ++a) {
      nd.lo[a] = std::min({nd.lo[a], s.a[a], s.b[a]});
      nd.hi[a] = std::max({nd.hi[a], s.a[a], s.b[a]});
    }
  }
  for (int a = 0; a < 2; ++a) {
    nd.c[a] = 0.5 * (nd.lo[a] + nd.hi[a]);
    nd.h[a] = 0.5 * (nd.hi[a] - nd.lo[a]);
  }
  if (end - begin <= 4) {
    nd.first = begin;
    nd.count = end - begin;
    nodes_[id] = nd;
    return id;
  }
  const int axis = (nd.hi[0] - nd.lo[0]) >= (nd.hi[1] - nd.lo[1]) ? 0 : 1;
  const int mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](int x, int y) {
    return centres[x][axis] < centres[y][axis] || (centres[x][axis] == centres[y][axis] && x < y);
  });
  nd.left = build_node(begin, mid, centres, depth + 1);
  nd.right = build_node(mid, end, centres, depth + 1);
  nodes_[id] = nd;
  return id;
}

void PlaneRegion::build_bvh() {
  nodes_.clear();
  if (segments_.empty()) return;
  std::vector<Vec2> centres(segments_.size());
  order_.resize(segments_.size());
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    centres[i] = 0.5 * (segments_[i].a + segments_[i].b);
    order_[i] = static_cast<int>(i);
  }
  nodes_.reserve(segments_.size() + 8);
  build_node(0, static_cast<int>(segments_.size()), centres, 1);
  std::vector<Segment> sorted(segments_.size());
  extent_ = 0.0;
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    sorted[i] = segments_[order_[i]];
    extent_ = std::max({extent_, sorted[i].a.cwiseAbs().maxCoeff(), sorted[i].b.cwiseAbs().maxCoeff()});
  }
  segments_.swap(sorted);
  order_.clear();
  order_.shrink_to_fit();
  if (depth_ + 2 > 96) throw std::runtime_error("PlaneRegion: BVH too deep");
  build_hull();
}

void PlaneRegion::build_hull() {
  std::vector<Vec2> pts;
  pts.reserve(2 * segments_.size());
  for (const Segment& s : segments_) {
    pts.push_back(s.a);
    pts.push_back(s.b);
  }
  std::sort(pts.begin(), pts.end(), x_then_y);
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  std::vector<Vec2> h;
  for (int i : monotone_chain(static_cast<int>(pts.size()), [&](int k) -> const Vec2& { return pts[k]; }))
    h.push_back(pts[i]);
  // The edges' angles, indexed from the edge after their wrap round.
  const int k = static_cast<int>(h.size());
  const int start = index_edge_angles(h, &hull_index_);
  hull_.clear();
  for (int i = 0; i < k; ++i) hull_.push_back(h[(start + i) % k]);
}

void PlaneRegion::AngleIndex::build(std::vector<double> angles) {
  angle = std::move(angles);
  const int n = static_cast<int>(angle.size()), parts = std::max(1, 2 * n);
  scale = parts / 4.0;
  part.assign(parts + 1, n);
  // Each part's entry starts a part early: t's part, computed with rounding, may start past t.
  for (int b = 0, i = 0; b <= parts; ++b) {
    const double start = -2.0 + (b - 1) / scale;
    while (i < n && angle[i] < start) ++i;
    part[b] = i;
  }
}

namespace {

/// Lower bound of the squared distance from the query to anything in the node's box (the
/// larger of the boxes' separation and the box's distance from the query's line), squared so
/// that the search needs no square root per node.
template <class Node>
inline double node_bound2(const Node& nd, const Query& q) {
  const double dx = std::max({nd.lo[0] - q.hi.x(), q.lo.x() - nd.hi[0], 0.0});
  const double dy = std::max({nd.lo[1] - q.hi.y(), q.lo.y() - nd.hi[1], 0.0});
  double lb2 = dx * dx + dy * dy;
  if (q.line) {
    const double l = std::abs(q.n.x() * (nd.c[0] - q.a.x()) + q.n.y() * (nd.c[1] - q.a.y())) -
                     (q.n_abs.x() * nd.h[0] + q.n_abs.y() * nd.h[1]);
    if (l > 0.0) lb2 = std::max(lb2, l * l);
  }
  return lb2;
}

/// True when the node's box lies farther than d from the query (node_bound2 > d^2, the box
/// tests first): the tests of the threshold queries. A lower bound of the distance to every
/// segment in the node, up to rounding far below Query::slack: reach()'s hints rely on that.
template <class Node>
inline bool node_farther(const Node& nd, const Query& q, double d) {
  const double dx = std::max(nd.lo[0] - q.hi.x(), q.lo.x() - nd.hi[0]);
  const double dy = std::max(nd.lo[1] - q.hi.y(), q.lo.y() - nd.hi[1]);
  if (dx > d || dy > d) return true;
  const double ex = std::max(dx, 0.0), ey = std::max(dy, 0.0);
  if (ex * ex + ey * ey > d * d) return true;
  return q.line && std::abs(q.n.x() * (nd.c[0] - q.a.x()) + q.n.y() * (nd.c[1] - q.a.y())) -
                           (q.n_abs.x() * nd.h[0] + q.n_abs.y() * nd.h[1]) >
                       d;
}

}  // namespace

template <class Q>
bool PlaneRegion::hull_apart(const Q& q, double limit) const {
  if (!q.line || hull_.empty()) return false;
  // The hull's vertex farthest along a direction v starts its first edge turned a right angle
  // counter-clockwise from v, or past it (v = n: the edge along -u; v = -n: along u).
  // Found by the angles' index (AngleIndex::first_at_least).
  const auto [along, against] = pseudo_angles_of(q.u);
  auto extreme = [&](double edge) -> const Vec2& { return hull_[hull_index_.first_at_least(edge)]; };
  return q.n.dot(extreme(along) - q.a) > limit || q.n.dot(extreme(against) - q.a) < -limit;
}

template <class Skip, class Visit>
bool PlaneRegion::visit_segments(Skip&& skip, Visit&& visit, bool root_kept) const {
  if (nodes_.empty()) return false;
  int stack[96];
  int top = 0;
  stack[top++] = 0;
  bool ask = !root_kept;  // the root is the first node taken
  while (top > 0) {
    const Node& nd = nodes_[stack[--top]];
    if (ask && skip(nd)) continue;
    ask = true;
    if (nd.left >= 0) {
      stack[top++] = nd.right;
      stack[top++] = nd.left;
      continue;
    }
    for (int i = nd.first; i < nd.first + nd.count; ++i)
      if (visit(i)) return true;
  }
  return false;
}

namespace {

/// This thread's last point query of PlaneRegion::nearest_noted whose first find lay within its
/// cap: the region's id (0: none), the point, the cap, the answer. Out of line, as span_scratch
/// (below) is: a thread-local's address in a shared library is a call.
struct NearMemo {
  std::uint64_t region = 0;
  Vec2 a;
  double cap = 0.0;
  PlaneRegion::Near out;
};
#if defined(__GNUC__)
__attribute__((noinline))
#endif
NearMemo& near_memo() {
  thread_local NearMemo memo;
  return memo;
}

}  // namespace

PlaneRegion::Near PlaneRegion::nearest_noted(const Vec2& a, const Vec2& b, double cap) const {
  if (!(a == b)) return nearest(a, b, cap);
  const double c = std::max(cap, 0.0);
  NearMemo& memo = near_memo();
  if (memo.region == id_ && memo.cap <= c && std::memcmp(memo.a.data(), a.data(), sizeof(Vec2)) == 0)
    return memo.out;
  double first = kInf;
  const Near out = search_nearest(a, b, cap, &first);
  // A search whose first find lies within its cap gives what a search with a larger cap gives,
  // bit for bit: the larger one visits the same nodes in the same order but for nodes only it
  // keeps, whose pieces lie farther than the cap and the tie margin, and the first find within
  // the cap then starts its answer afresh (ties included), as it starts the smaller one's.
  if (first <= c) {
    memo.region = id_;
    memo.a = a;
    memo.cap = c;
    memo.out = out;
  }
  return out;
}

PlaneRegion::Near PlaneRegion::nearest(const Vec2& a, const Vec2& b, double cap) const {
  return search_nearest(a, b, cap, nullptr);
}

PlaneRegion::Near PlaneRegion::search_nearest(const Vec2& a, const Vec2& b, double cap, double* first) const {
  Near out;
  if (nodes_.empty()) return out;
  const Query q(a, b);
  const double slack = q.slack(extent_);
  double best = std::max(cap, 0.0);
  bool found = false;
  struct Item {
    int node;
    double lb2;  ///< node_bound2
  };
  auto reach2 = [&] { return (best + kTie) * (best + kTie); };  // nodes beyond cannot hold the nearest
  Item stack[96];
  int top = 0;
  stack[top++] = {0, node_bound2(nodes_[0], q)};
  while (top > 0) {
    const Item it = stack[--top];
    if (it.lb2 > reach2()) continue;
    const Node& nd = nodes_[it.node];
    if (nd.left < 0) {
      for (int i = nd.first; i < nd.first + nd.count; ++i) {
        const Segment& s = segments_[i];
        if (farther_than(q, s.a, s.b, s.normal, best + kTie + slack)) continue;
        Vec2 c1, c2;
        const double d = segment_distance(a, b, s.a, s.b, &c1, &c2);
        if (d > best + kTie) continue;
        if (!found || d < best - kTie) {
          if (!found && first != nullptr) *first = d;
          found = true;
          out.normal_sum = s.normal;
          out.ties = 1;
          out.at_end = (c2 - s.a).squaredNorm() <= kJoin * kJoin || (c2 - s.b).squaredNorm() <= kJoin * kJoin;
          best = d;
          out.distance = d;
          out.on_query = c1;
          out.on_region = c2;
          out.segment = i;
        } else {
          out.normal_sum += s.normal;
          ++out.ties;
          if (d < best) {
            best = d;
            out.distance = d;
            out.on_query = c1;
            out.on_region = c2;
            out.segment = i;
          }
        }
        if (d <= kTouch) {
          out.distance = 0.0;
          return out;
        }
      }
      continue;
    }
    const double ll = node_bound2(nodes_[nd.left], q), lr = node_bound2(nodes_[nd.right], q), r2 = reach2();
    if (ll < lr) {
      if (lr <= r2) stack[top++] = {nd.right, lr};
      if (ll <= r2) stack[top++] = {nd.left, ll};
    } else {
      if (ll <= r2) stack[top++] = {nd.left, ll};
      if (lr <= r2) stack[top++] = {nd.right, lr};
    }
  }
  if (!found) out = Near();
  return out;
}

bool PlaneRegion::any_within(const Vec2& a, const Vec2& b, double distance) const {
  if (loop_answers(a, b, distance)) {
    const int sure = convex_within(a, b, distance);
    if (sure >= 0) return sure == 1;
  }
  return reach(a, b, distance) == Reach::kWithin;
}

PlaneRegion::Reach PlaneRegion::reach(const Vec2& a, const Vec2& b, double distance) const {
  const Query q(a, b);
  const double limit = distance + q.slack(extent_);
  // The root's box first, then the hull (which a link tangent to a convex R is apart from).
  if (nodes_.empty() || node_farther(nodes_[0], q, distance) || hull_apart(q, limit)) return Reach::kApart;
  auto within = [&](int i, double d) {
    const Segment& s = segments_[i];
    if (farther_than(q, s.a, s.b, s.normal, limit)) return false;
    Vec2 c1, c2;
    return segment_distance(a, b, s.a, s.b, &c1, &c2) <= d;
  };
  // The segment last found within reach of a query starting near a, and its two successors along
  // the boundary (a link that slid on): one within `distance` less a margin for the tree's
  // rounding is one the walk below would reach, so the answer is the walk's. A successor found so
  // becomes the hint, so that a link sliding on keeps up with it. (On the curvy object, a fifth of
  // the walks that found a piece found the hint's second successor.)
  std::atomic<int>& hint = hints_[hint_key(a)];
  const int h = hint.load(std::memory_order_relaxed);
  if (h >= 0) {
    const double sure = distance - q.slack(extent_);
    int c = h;
    for (int i = 0; i < 3 && c >= 0; ++i, c = next_[c])
      if (within(c, sure)) {
        if (i > 0) hint.store(c, std::memory_order_relaxed);
        return Reach::kWithin;
      }
  }
  int found = -1;
  // (The root's box was asked above.)
  const bool hit = visit_segments([&](const Node& nd) { return node_farther(nd, q, distance); },
                                  [&](int i) {
                                    if (!within(i, distance)) return false;
                                    found = i;
                                    return true;
                                  },
                                  true);
  if (!hit) return Reach::kBeyond;
  hint.store(found, std::memory_order_relaxed);
  return Reach::kWithin;
}

namespace {

/// The parameters t in [0, 1] of the points a + t d (d != 0) within r of segment [p, q]: the line
/// meets the capsule of radius r about the segment (convex) in one interval, the hull of its
/// meetings with the two end disks and the slab between them. False when none is.
bool capsule_interval(const Vec2& a, const Vec2& d, const Vec2& p, const Vec2& q, double r, double* t0, double* t1) {
  const double dd = d.squaredNorm();
  double lo = kInf, hi = -kInf;
  for (const Vec2* c : {&p, &q}) {
    const Vec2 w = a - *c;
    const double B = d.dot(w), disc = B * B - dd * (w.squaredNorm() - r * r);
    if (disc < 0.0) continue;
    const double sq = std::sqrt(disc);
    lo = std::min(lo, (-B - sq) / dd);
    hi = std::max(hi, (-B + sq) / dd);
  }
  const Vec2 e = q - p;
  const double len = e.norm();
  if (len > 0.0) {
    // The slab: 0 <= u.(x - p) <= len and |n.(x - p)| <= r, each linear in t.
    const Vec2 u = e / len, n(-u.y(), u.x()), w = a - p;
    double s0 = -kInf, s1 = kInf;
    auto clip = [&](double alpha, double beta, double l, double h) {  // l <= alpha + beta t <= h
      if (beta == 0.0) {
        if (alpha < l || alpha > h) s0 = kInf;
        return;
      }
      double x = (l - alpha) / beta, y = (h - alpha) / beta;
      if (x > y) std::swap(x, y);
      s0 = std::max(s0, x);
      s1 = std::min(s1, y);
    };
    clip(u.dot(w), u.dot(d), 0.0, len);
    clip(n.dot(w), n.dot(d), -r, r);
    if (s0 <= s1) {
      lo = std::min(lo, s0);
      hi = std::max(hi, s1);
    }
  }
  *t0 = std::max(lo, 0.0);
  *t1 = std::min(hi, 1.0);
  return *t0 <= *t1;
}

/// The part of segment [sa, sb] within the disk of squared radius l2 about the pivot, for
/// PlaneRegion::spans: its ends minus the pivot (ends inside the disk kept exactly) in q0, q1.
enum class DiskPart : std::uint8_t { kNone, kPiece, kTouching };
inline DiskPart disk_part(const Vec2& sa, const Vec2& sb, const Vec2& pivot, double l2, Vec2* q0, Vec2* q1) {
  const Vec2 w0 = sa - pivot, w1 = sb - pivot, d = sb - sa;
  const double a = d.squaredNorm(), b = w0.dot(d), c0 = w0.squaredNorm() - l2, c1 = w1.squaredNorm() - l2;
  // Touching the pivot: only where the segment's line passes that close (no division else).
  const double cr = cross2(w0, d);
  if (cr * cr <= kTouch * kTouch * a) {
    const double t_near = a > 0.0 ? std::clamp(-b / a, 0.0, 1.0) : 0.0;
    if ((w0 + t_near * d).squaredNorm() <= kTouch * kTouch) return DiskPart::kTouching;
  }
  // The part within the disk: a t^2 + 2 b t + c0 <= 0 on [0, 1].
  double t0 = 0.0, t1 = 1.0;
  if (c0 > 0.0 || c1 > 0.0) {
    const double disc = b * b - a * c0;
    if (!(a > 0.0) || disc < 0.0) return DiskPart::kNone;
    const double sq = std::sqrt(disc);
    if (c0 > 0.0) t0 = (-b - sq) / a;
    if (c1 > 0.0) t1 = (-b + sq) / a;
    if (t0 < 0.0 || t1 > 1.0 || t0 > t1) return DiskPart::kNone;  // the segment's line meets the disk off it
  }
  *q0 = t0 == 0.0 ? w0 : Vec2(w0 + t0 * d);
  *q1 = t1 == 1.0 ? w1 : Vec2(w0 + t1 * d);
  return DiskPart::kPiece;
}

}  // namespace

int PlaneRegion::loop_extreme(double edge) const {
  // As hull_apart's search: the tail of the first edge turned at least as far as `edge`.
  const int i = loop_edge_first_ + loop_edges_.first_at_least(edge);
  const int n = static_cast<int>(loop_tail_.size());
  return i >= n ? i - n : i;
}

template <class Q>
PlaneRegion::Chord PlaneRegion::convex_chord(const Q& q, int bottom, int top) const {
  // The line crosses R: once on the chain from bottom to top (counter-clockwise; the height
  // rises along it) and once on the way back (it falls). On each, the first tail past the line
  // ends the edge crossed, found by halving.
  const int n = static_cast<int>(loop_tail_.size());
  const Vec2* T = loop_tail_.data();
  auto h = [&](int i) { return q.n.dot(T[i] - q.a); };
  auto crossing = [&](int from, int to, bool rising, double* t, int* edge) {
    int lo = 0, hi = to - from < 0 ? to - from + n : to - from;  // tail from + lo is before the line, from + hi past it
    while (hi - lo > 1) {
      const int mid = lo + (hi - lo) / 2;
      const double hm = h(from + mid >= n ? from + mid - n : from + mid);
      ((rising ? hm >= 0.0 : hm < 0.0) ? hi : lo) = mid;
    }
    const int i0 = from + lo >= n ? from + lo - n : from + lo, i1 = i0 + 1 == n ? 0 : i0 + 1;
    const double h0 = h(i0), h1 = h(i1);
    const Vec2 x = T[i0] + (h0 / (h0 - h1)) * (T[i1] - T[i0]);
    *t = q.u.dot(x - q.a);
    *edge = i0;
  };
  Chord c;
  crossing(bottom, top, true, &c.t_in, &c.e_in);
  crossing(top, bottom, false, &c.t_out, &c.e_out);
  if (c.t_in > c.t_out) {
    std::swap(c.t_in, c.t_out);
    std::swap(c.e_in, c.e_out);
  }
  return c;
}

double PlaneRegion::beyond_edge(int edge, const Vec2& x) const {
  return loop_[edge].normal.dot(x - loop_tail_[edge]);
}

int PlaneRegion::convex_clear(const Vec2& a, const Vec2& b, bool a_outside) const {
  const Query q(a, b);
  if (!q.line) return -1;
  if (node_farther(nodes_[0], q, kTouch)) return 1;  // apart from the boundary's box
  auto h = [&](int i) { return q.n.dot(loop_tail_[i] - a); };  // height above the segment's line
  // The line passes R where R's lowest point lies above it or its highest below (each asked
  // only where the other does not settle it).
  const auto [along, against] = pseudo_angles_of(q.u);
  const int bottom = loop_extreme(along);
  const double h_bottom = h(bottom);
  if (h_bottom > kSureApart) return 1;
  const int top = loop_extreme(against);
  const double h_top = h(top);
  if (h_top < -kSureApart) return 1;
  if (!(h_top > kSureApart && h_bottom < -kSureApart)) return -1;
  // The line crosses R. The edge of b's wedge about the loop's centre settles many segments
  // without the chord (links turned onto R mostly have their end b nearest it): b inside that
  // edge's line lies in R; a and b both beyond it (the line bounds R) are separated from R.
  const int jb = loop_wedge(b);
  if (jb >= 0) {
    const double b_out = beyond_edge(jb, b);
    if (b_out < -kSureApart) return 0;
    if (b_out > kSureApart && beyond_edge(jb, a) > kSureApart) return 1;
  }
  const Chord c = convex_chord(q, bottom, top);
  // The chord through R overlaps the segment: it meets R. (Where it holds the whole segment,
  // the tree answers by a_outside, as told: there it decides.)
  if (c.t_in <= q.len && c.t_out >= 0.0) return a_outside && c.t_in < 0.0 && c.t_out > q.len ? -1 : 0;
  // The segment lies beyond the edge where the chord leaves R (or before the one where it
  // enters), whose line bounds R: by its end nearer that edge's line.
  const bool beyond = c.t_out < 0.0;
  return beyond_edge(beyond ? c.e_out : c.e_in, beyond ? a : b) > kSureApart ? 1 : -1;
}

int PlaneRegion::convex_within(const Vec2& a, const Vec2& b, double distance) const {
  const Query q(a, b);
  if (!q.line) return -1;
  if (node_farther(nodes_[0], q, distance)) return 0;  // as reach: the boundary's box is farther
  const double far = distance + kSureApart, near = distance - kSureApart;
  auto h = [&](int i) { return q.n.dot(loop_tail_[i] - a); };
  // A boundary point within `near` of the segment: a witness that some piece is within distance.
  auto witness = [&](const Vec2& x) {
    const double t = q.u.dot(x - a);
    const Vec2 p = t <= 0.0 ? a : (t >= q.len ? b : Vec2(a + t * q.u));
    return (x - p).squaredNorm() < near * near;
  };
  const auto [along, against] = pseudo_angles_of(q.u);
  const int bottom = loop_extreme(along);
  const double h_bottom = h(bottom);
  if (h_bottom > far) return 0;  // all of R farther above the line
  if (h_bottom > kSureApart) return near > 0.0 && witness(loop_tail_[bottom]) ? 1 : -1;  // R above, its lowest point near
  const int top = loop_extreme(against);
  const double h_top = h(top);
  if (h_top < -far) return 0;
  if (h_top < -kSureApart) return near > 0.0 && witness(loop_tail_[top]) ? 1 : -1;
  if (!(h_top > kSureApart && h_bottom < -kSureApart)) return -1;
  const Chord c = convex_chord(q, bottom, top);
  // A chord end on the segment is a boundary point on it; the segment within the chord lies in
  // R, where only the distance to the boundary tells (the tree).
  if ((c.t_in >= 0.0 && c.t_in <= q.len) || (c.t_out >= 0.0 && c.t_out <= q.len)) return 1;
  if (c.t_in < 0.0 && c.t_out > q.len) return -1;
  // The chord misses the segment: the edge's line there separates them by at least its
  // distance, and the chord's end is a boundary point on the segment's line.
  const bool beyond = c.t_out < 0.0;
  if (beyond_edge(beyond ? c.e_out : c.e_in, beyond ? a : b) > far) return 0;
  const double gap = beyond ? -c.t_out : c.t_in - q.len;
  return gap < near ? 1 : -1;
}

bool PlaneRegion::clear(const Vec2& a, const Vec2& b, bool a_outside) const {
  if (loop_answers(a, b, 0.0)) {
    const int sure = convex_clear(a, b, a_outside);
    if (sure >= 0) return sure == 1;
  }
  // A segment apart from the boundary's box or hull lies outside it: outside R.
  switch (reach(a, b, kTouch)) {
    case Reach::kWithin: return false;
    case Reach::kApart: return true;
    case Reach::kBeyond: break;
  }
  return a_outside || !inside(a);
}

bool PlaneRegion::depth_within(const Vec2& a, const Vec2& b, double allow) const {
  if (nodes_.empty()) return true;  // no boundary: R is empty
  if (loop_kind_ != LoopKind::kNone && convex_shallow(a, b, allow)) return true;
  const Query q(a, b);
  const Vec2 d = b - a;
  const bool point = !(d.squaredNorm() > 0.0);
  const double limit = allow + q.slack(extent_);
  // The axis points within `allow` of each boundary piece: an interval of the axis per piece.
  thread_local std::vector<std::array<double, 2>> near;
  near.clear();
  const bool shallow_point =
      visit_segments([&](const Node& nd) { return node_farther(nd, q, limit); },
                     [&](int i) {
                       const Segment& s = segments_[i];
                       if (farther_than(q, s.a, s.b, s.normal, limit)) return false;
                       if (point) {  // a point: within `allow` of a piece, or not
                         Vec2 c1, c2;
                         return segment_distance(a, a, s.a, s.b, &c1, &c2) <= allow;
                       }
                       double t0, t1;
                       if (capsule_interval(a, d, s.a, s.b, allow, &t0, &t1)) near.push_back({t0, t1});
                       return false;
                     });
  if (shallow_point) return true;
  if (point) return !inside(a);
  // The stretches no piece comes within `allow` of: each wholly inside R (too deep) or outside.
  std::sort(near.begin(), near.end());
  double covered = 0.0;  // the stretches before `covered` are settled
  for (const auto& iv : near) {
    if (iv[0] > covered && inside(a + 0.5 * (covered + iv[0]) * d)) return false;
    covered = std::max(covered, iv[1]);
  }
  return !(covered < 1.0 && inside(a + 0.5 * (covered + 1.0) * d));
}

PlaneRegion::Wedge PlaneRegion::wedge(double within) {
  // One thread-local (in a shared library each reaching of one is a call), asked by the bits of
  // the angle it holds.
  struct Kept {
    bool known = false;
    Wedge w;
  };
  thread_local Kept kept;
  Kept& k = kept;
  if (!k.known || bits_of(within) != bits_of(k.w.within)) {
    k.w.within = within;
    k.w.pm = pseudo_angle_of(within);
    k.w.c = std::cos(within);
    k.w.s = std::sin(within);
    k.w.c_neg = std::cos(-within);
    k.w.s_neg = std::sin(-within);
    k.known = true;
  }
  return k.w;
}

bool PlaneRegion::spans(const Vec2& pivot, const Vec2& u, double length, const Wedge& w,
                        std::vector<Span>* out) const {
  if (nodes_.empty()) return true;
  const double within = w.within;
  bool touching_loop = false;
  if (loop_answers(pivot, pivot, length) && convex_spans(pivot, u, length, w.pm, &touching_loop, out))
    return !touching_loop;
  const double slack = 1e-12 * (extent_ + pivot.cwiseAbs().maxCoeff());
  const double reach = length + slack, l2 = length * length;
  const double margin = slack + kTouch;  // beyond a wedge's side by this: no piece touching the pivot
  const Vec2 behind = -length * u;  // the point at pseudo-angle +-2, for spans cut there
  // The wedge of directions within `within` of u: spans wholly outside it are left out, and
  // where it is convex (within <= pi/2) so are nodes wholly outside one of its two sides.
  const double pm = w.pm;
  const bool convex_wedge = within <= 0.5 * kPi;
  // The wedge's sides: u turned by +-within (rotate_planar(u, +-within), bit for bit).
  const Vec2 e_plus = rotate_planar(u, w.c, w.s), e_minus = rotate_planar(u, w.c_neg, w.s_neg);
  Vec2 last_q(kInf, kInf);  // the last end point seen and its pseudo-angle (neighbours share ends)
  double last_p = 0.0;
  auto add = [&](const Vec2& q0, const Vec2& q1) {
    double p0 = q0 == last_q ? last_p : pseudo_angle(u, q0), p1 = pseudo_angle(u, q1);
    last_q = q1;
    last_p = p1;
    const Vec2 *v0 = &q0, *v1 = &q1;
    if (p1 < p0) {
      std::swap(p0, p1);
      std::swap(v0, v1);
    }
    // A piece not through the pivot spans less than pi: less than 2; the longer way round wraps.
    if (p1 - p0 <= 2.0) {
      if (p1 < -pm || p0 > pm) return;
      // Neighbours along R's boundary come in turn (a leaf holds neighbours) and share an end
      // point: one span for both, which keeps the list short.
      if (!out->empty()) {
        Span& last = out->back();
        if (p0 <= last.hi + kSpanJoin && last.lo <= p1 + kSpanJoin) {
          if (p0 < last.lo) {
            last.lo = p0;
            last.v_lo = *v0;
          }
          if (p1 > last.hi) {
            last.hi = p1;
            last.v_hi = *v1;
          }
          return;
        }
      }
      out->push_back({p0, p1, *v0, *v1});
    } else {
      if (p1 <= pm) out->push_back({p1, 2.0, *v1, behind});
      if (p0 >= -pm) out->push_back({-2.0, p0, behind, *v0});
    }
  };
  auto skip = [&](const Node& nd) {
    const double dx = std::max({nd.lo[0] - pivot.x(), pivot.x() - nd.hi[0], 0.0});
    const double dy = std::max({nd.lo[1] - pivot.y(), pivot.y() - nd.hi[1], 0.0});
    if (dx * dx + dy * dy > reach * reach) return true;
    if (!convex_wedge) return false;
    // cross(e, x - pivot) over the box: its value at the centre -+ the box's half extent; a box
    // within touching distance of the pivot is kept (its segments may touch the pivot).
    const double cx = nd.c[0] - pivot.x(), cy = nd.c[1] - pivot.y();
    const double r_plus = std::abs(e_plus.x()) * nd.h[1] + std::abs(e_plus.y()) * nd.h[0];
    const double r_minus = std::abs(e_minus.x()) * nd.h[1] + std::abs(e_minus.y()) * nd.h[0];
    return e_plus.x() * cy - e_plus.y() * cx - r_plus > margin ||   // beyond +within
           e_minus.x() * cy - e_minus.y() * cx + r_minus < -margin;  // beyond -within
  };
  // Stops (true) at a segment touching the pivot. A segment wholly beyond a side of a convex
  // wedge (as the nodes above) spans no direction within it: its span would be left out.
  const bool touching = visit_segments(skip, [&](int i) {
    const Segment& s = segments_[i];
    if (convex_wedge) {
      const Vec2 a = s.a - pivot, b = s.b - pivot;
      if ((cross2(e_plus, a) > margin && cross2(e_plus, b) > margin) ||
          (cross2(e_minus, a) < -margin && cross2(e_minus, b) < -margin))
        return false;
    }
    Vec2 q0, q1;
    const DiskPart part = disk_part(s.a, s.b, pivot, l2, &q0, &q1);
    if (part == DiskPart::kPiece) add(q0, q1);
    return part == DiskPart::kTouching;
  });
  return !touching;
}

bool PlaneRegion::convex_spans(const Vec2& pivot, const Vec2& u, double length, double pm, bool* touching,
                               std::vector<Span>* out) const {
  const int n = static_cast<int>(loop_tail_.size());
  const Vec2* T = loop_tail_.data();
  const double l2 = length * length;
  auto prev = [n](int i) { return i == 0 ? n - 1 : i - 1; };
  auto next = [n](int i) { return i + 1 == n ? 0 : i + 1; };
  // Segment i of the loop runs from T[i] to T[next(i)] with R on its left: it faces the pivot
  // (shows it its outer side) where the pivot lies to its right. The segments facing the pivot
  // are one run of the loop, along which the distance to the pivot falls and then rises, and
  // the direction from the pivot turns clockwise.
  auto faces = [&](int i) { return cross2(T[next(i)] - T[i], pivot - T[i]) < 0.0; };
  auto d2 = [&](int i) { return (T[i] - pivot).squaredNorm(); };
  // The segment that the ray from the centre through the pivot crosses (the tails' angles about
  // the centre increase along the loop) faces the pivot, unless the pivot lies in R.
  const int j = loop_wedge(pivot);
  if (j < 0 || !faces(j)) return false;
  // The nearest tail of the facing run: walked to from the nearer end of j, the distance falling.
  const bool forward = d2(next(j)) < d2(j);
  int m = forward ? next(j) : j;
  double dm = d2(m);
  for (int k = 0; k < n && faces(forward ? m : prev(m)); ++k) {
    const int c = forward ? next(m) : prev(m);
    const double dc = d2(c);
    if (!(dc < dm)) break;
    m = c;
    dm = dc;
  }
  // The run's points within the disk are one stretch about the nearest point (on the segments
  // on either side of T[m]). Its ends: walked from m while the next tail lies within the disk
  // and its segment faces the pivot; the last tail inside (hi: clockwise along the loop, where
  // the direction turns counter-clockwise; lo: the other way), and the segments about it.
  int hi = m, lo = m;
  if (dm <= l2) {
    for (int k = 0; k < n && faces(prev(hi)) && d2(prev(hi)) <= l2; ++k) hi = prev(hi);
    for (int k = 0; k < n && faces(lo) && d2(next(lo)) <= l2; ++k) lo = next(lo);
  }
  // The spans' ends from the parts within the disk (the same formula as the tree's visit) of
  // the segments ending the stretch, prev(hi) and lo (past the stretch, the part from the
  // crossing; at the facing run's end, the segment that ends it, whose part within the disk ends
  // there), and of the two about T[m], which hold the point nearest the pivot (touching it or
  // not): the most counter-clockwise and the most clockwise of their ends. An end segment with
  // no part within the disk (its tail on the circle, to rounding) leaves that tail to the
  // segment on its other side, hi or prev(lo), asked then.
  Vec2 ends[12];
  int count = 0;
  *touching = false;
  int edges[6] = {prev(m), m, prev(hi), lo, -1, -1};
  for (int e = 0; e < 6; ++e) {
    const int i = edges[e];
    if (i < 0) continue;
    bool asked = false;
    for (int f = 0; f < e; ++f) asked = asked || edges[f] == i;
    if (asked) continue;
    // (A lid lies beyond the disk: spans() asks the loop only where the disk reaches no pocket.)
    const DiskPart part = disk_part(loop_[i].a, loop_[i].b, pivot, l2, &ends[count], &ends[count + 1]);
    if (part == DiskPart::kTouching) {
      *touching = true;
      return true;
    }
    if (part == DiskPart::kPiece) count += 2;
    else if (e == 2) edges[4] = hi;
    else if (e == 3) edges[5] = prev(lo);
  }
  if (count == 0) return true;
  // (Two ends on one ray from the pivot, to rounding, may be told apart otherwise than the
  // tree's pseudo-angles do: the span's end is then the other point of that ray, an ulp of angle
  // apart. Comparing every end's pseudo-angle cost 2% of a convex plan's Phase 2.)
  Vec2 v_lo = ends[0], v_hi = ends[0];
  for (int k = 1; k < count; ++k) {
    if (cross2(v_hi, ends[k]) > 0.0) v_hi = ends[k];
    else if (cross2(v_lo, ends[k]) < 0.0) v_lo = ends[k];
  }
  const double p_lo = pseudo_angle(u, v_lo), p_hi = pseudo_angle(u, v_hi);
  // As the tree's visit gives them: one span, or two where it crosses +-2; none wholly outside
  // the wedge (pm: its bound).
  if (p_lo <= p_hi) {
    if (p_hi >= -pm && p_lo <= pm) out->push_back({p_lo, p_hi, v_lo, v_hi});
  } else {
    const Vec2 behind = -length * u;
    if (p_lo <= pm) out->push_back({p_lo, 2.0, v_lo, behind});
    if (p_hi >= -pm) out->push_back({-2.0, p_hi, behind, v_hi});
  }
  return true;
}

void PlaneRegion::mark_crossings() {
  // (A piece with a loose end, not crossed, goes on inside R: simplify()'s run tests find it.)
  const std::size_t n = segments_.size();
  // Pieces of R's boundary never cross one another; a piece that another crosses (transversally,
  // away from both their end points) has parts inside R, where the side test is unsafe. The
  // pairs to test: segments whose boxes (grown by kTouch) overlap, found on a grid of about one
  // cell per segment; a pair is tested in the one cell that holds the low corner of the overlap.
  if (n < 2) return;
  Vec2 lo = segments_[0].a, hi = lo;
  for (const Segment& sg : segments_) {
    lo = lo.cwiseMin(sg.a.cwiseMin(sg.b));
    hi = hi.cwiseMax(sg.a.cwiseMax(sg.b));
  }
  const int g = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(n))), 1, 256);
  const Vec2 cell = ((hi - lo) / g).cwiseMax(Vec2::Constant(1e-300));
  auto cell_of = [&](double x, int axis) {
    return static_cast<int>(std::clamp(std::floor((x - lo[axis]) / cell[axis]), 0.0, g - 1.0));
  };
  std::vector<std::array<Vec2, 2>> box(n);    // each segment's box, grown by kTouch
  std::vector<std::array<int, 4>> cells(n);  // and the cells it meets: x0, x1, y0, y1
  for (std::size_t i = 0; i < n; ++i) {
    const Segment& sg = segments_[i];
    box[i] = {Vec2(sg.a.cwiseMin(sg.b).array() - kTouch), Vec2(sg.a.cwiseMax(sg.b).array() + kTouch)};
    cells[i] = {cell_of(box[i][0].x(), 0), cell_of(box[i][1].x(), 0), cell_of(box[i][0].y(), 1), cell_of(box[i][1].y(), 1)};
  }
  // The segments of each cell (compressed rows: counted, then filled).
  std::vector<int> start(static_cast<std::size_t>(g) * g + 1, 0), items;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      for (int cy = cells[i][2]; cy <= cells[i][3]; ++cy)
        for (int cx = cells[i][0]; cx <= cells[i][1]; ++cx) {
          const int c = cy * g + cx;
          if (pass == 0) ++start[c + 1];
          else items[fill[c]++] = static_cast<int>(i);
        }
    if (pass == 0) {
      for (std::size_t c = 0; c + 1 < start.size(); ++c) start[c + 1] += start[c];
      items.resize(static_cast<std::size_t>(start.back()));
    }
  }
  for (int c = 0; c < g * g; ++c)
    for (int p = start[c]; p < start[c + 1]; ++p)
      for (int q = p + 1; q < start[c + 1]; ++q) {
        const int i = std::min(items[p], items[q]), j = std::max(items[p], items[q]);
        const Segment &s = segments_[i], &t = segments_[j];
        if (t.piece == s.piece) continue;
        const Vec2 olo = box[i][0].cwiseMax(box[j][0]), ohi = box[i][1].cwiseMin(box[j][1]);
        if (olo.x() > ohi.x() || olo.y() > ohi.y()) continue;              // the boxes do not overlap
        // Tested in the cell of the overlap's low corner, max of the boxes' low corners: cell_of
        // is monotone, so that cell is the larger of their cells, each axis.
        if (std::max(cells[i][2], cells[j][2]) * g + std::max(cells[i][0], cells[j][0]) != c) continue;
        const Vec2 d1 = s.b - s.a, d2 = t.b - t.a, w = t.a - s.a;
        const double denom = cross2(d1, d2);
        if (std::abs(denom) <= 1e-9 * d1.norm() * d2.norm()) continue;  // parallel: a junction
        const double x = cross2(w, d2) / denom, y = cross2(w, d1) / denom;
        const double ex = 1e-9, ey = 1e-9;
        if (x > ex && x < 1.0 - ex && y > ey && y < 1.0 - ey) {
          // The part of s beyond the crossing lies on t's inner side when s runs against t's
          // outward normal there, and likewise for t.
          cuts_.push_back({i, x, d1.dot(t.normal) < 0.0});
          cuts_.push_back({j, y, d2.dot(s.normal) < 0.0});
        }
      }
}

bool PlaneRegion::inside_3d(const Vec2& x) const {
  fallbacks_.fetch_add(1, std::memory_order_relaxed);
  const Vec3 X = plane_.to_world(x);
  const Object& O = *object_;
  if (radius_ > 0.0) return O.bvh().any_within(X, X, radius_) || O.inside_off_surface(X);
  return O.inside(X);
}

bool PlaneRegion::inside_from(const Near& near, const Vec2& x) const {
  if (near.distance == 0.0) return true;
  if (!std::isfinite(near.distance)) return inside_3d(x);
  // A loose end (an end point no other segment shares: rounding, or a gap): no safe side.
  if (near.at_end && near.ties < 2) return inside_3d(near.on_query);
  // Nearest pieces on opposite sides (a point midway between two of them): their normals cancel,
  // and a side test with their sum means nothing.
  if (!(near.normal_sum.norm() > 1e-6 * near.ties)) return inside_3d(near.on_query);
  const double s = (near.on_query - near.on_region).dot(near.normal_sum);
  if (!(std::abs(s) > 1e-9 * near.distance * near.normal_sum.norm())) return inside_3d(near.on_query);
  return s < 0.0;
}

bool PlaneRegion::inside(const Vec2& x) const {
  if (segments_.empty()) return false;  // the plane misses R: no boundary, nothing inside
  if (!cells_.empty()) {
    // A point in a cell no segment touches has its cell's label; beyond the grid, outside R
    // (the label of the outer cells).
    const Vec2 g = (x - cells_lo_) / cell_;
    if (!(g.x() >= 0.0 && g.y() >= 0.0 && g.x() < cells_n_[0] && g.y() < cells_n_[1])) return cells_[0] == 1;
    const signed char label = cells_[static_cast<std::size_t>(g.y()) * cells_n_[0] + static_cast<std::size_t>(g.x())];
    if (label >= 0) return label == 1;
  }
  if (loop_answers(x, x, 0.0)) {
    const int sure = convex_inside(x);
    if (sure >= 0) return sure == 1;
  }
  return inside_from(nearest(x, x, kInf), x);
}

int PlaneRegion::convex_inside(const Vec2& x) const {
  // The loop's edge whose wedge about the centre holds x (the tails' angles about it increase):
  // x lies in R where it lies on the inner side of that edge's line (in the triangle of the
  // wedge), outside R where on the outer side (the line bounds R).
  const int j = loop_wedge(x);
  if (j < 0) return -1;  // x at the centre
  const double out = beyond_edge(j, x);
  return out > kSureApart ? 0 : (out < -kSureApart ? 1 : -1);
}

bool PlaneRegion::convex_shallow(const Vec2& a, const Vec2& b, double allow) const {
  // A point of R lies no deeper than its distance to the line of any edge (the line bounds R),
  // and that distance along the segment is largest at an end. The edges tried: those of the
  // wedges of b and a (the middle's too cost more than they settled).
  const double limit = allow - kSureApart;
  if (!(limit > 0.0)) return false;
  for (const Vec2& x : {b, a}) {
    const int j = loop_wedge(x);
    if (j >= 0 && -beyond_edge(j, a) < limit && -beyond_edge(j, b) < limit) return true;
  }
  return false;
}

int PlaneRegion::loop_wedge(const Vec2& x) const {
  const double angle = pseudo_angle(Vec2::UnitX(), x - loop_centre_);
  if (!(std::abs(angle) <= 2.0)) return -1;
  // The last tail at or before the angle (before the first: the last, the loop wraps round).
  const int i = loop_polar_.first_at_least(angle), n = static_cast<int>(loop_tail_.size());
  return loop_polar_.angle[i] == angle ? i : (i == 0 ? n - 1 : i - 1);
}

// --- SectionSkin --------------------------------------------------------------------------

struct SectionSkin::Entry {
  /// `stage`: none (the whole build) or PlaneRegion::FirstStage.
  template <class... Stage>
  Entry(std::shared_ptr<const Object> object, const FingerPlane& p, double r, double flatten, Stage... stage)
      : plane(p), radius(r), region(std::move(object), p, r, flatten, stage...) {}
  FingerPlane plane;
  double radius;
  PlaneRegion region;
};

SectionSkin::SectionSkin(std::shared_ptr<const Object> object, double flatten)
    : object_(object), mesh_(object), flatten_(flatten) {
  HUGGER_CHECK_ARGUMENT(flatten > 0.0 && std::isfinite(flatten),
                        "SectionSkin: the flattening tolerance must be a positive number of metres, got " << flatten);
}

SectionSkin::~SectionSkin() = default;

namespace {

/// Whether two planes have the same bits (equal bits are equal planes; a zero of the other sign
/// differs): nine word compares without a branch, where memcmp of 72 bytes is a library call.
inline bool same_bits(const FingerPlane& x, const FingerPlane& y) {
  static_assert(sizeof(FingerPlane) == 9 * sizeof(double), "FingerPlane: three Vec3, no padding");
  const auto* px = reinterpret_cast<const unsigned char*>(&x);
  const auto* py = reinterpret_cast<const unsigned char*>(&y);
  std::uint64_t diff = 0;
  for (std::size_t i = 0; i < sizeof(FingerPlane); i += sizeof(std::uint64_t)) {
    std::uint64_t a, b;
    std::memcpy(&a, px + i, sizeof a);
    std::memcpy(&b, py + i, sizeof b);
    diff |= a ^ b;
  }
  return diff == 0;
}

bool same_plane(const FingerPlane& x, double rx, const FingerPlane& y, double ry) {
  // Scalar comparisons that stop at the first difference, u first: a hand's finger planes
  // mostly differ in u (parallel and opposed fingers share it, and differ in the origin) and
  // often share the origin and p (the palm's centre and axis).
  auto same = [](const Vec3& a, const Vec3& b) { return a.x() == b.x() && a.y() == b.y() && a.z() == b.z(); };
  return same(x.u, y.u) && rx == ry && same(x.origin, y.origin) && same(x.p, y.p);
}

/// The slot of a plane and radius in find()'s table: the bits of u, the origin and the radius,
/// each times its own odd constant, summed; the slot is the sum's top bits, which every input
/// bit moves (multiplicative hashing). p is left out: a hand's finger planes share it. Equal
/// planes (same_plane) hash alike but for the sign of a zero, which only sends that query to the
/// scan.
std::size_t plane_slot(const FingerPlane& plane, double radius, int slot_bits) {
  const std::uint64_t h = bits_of(plane.u.x()) * 0x9E3779B97F4A7C15ull + bits_of(plane.u.y()) * 0xC2B2AE3D27D4EB4Full +
                          bits_of(plane.u.z()) * 0x165667B19E3779F9ull + bits_of(plane.origin.x()) * 0xD6E8FEB86659FD93ull +
                          bits_of(plane.origin.y()) * 0xFF51AFD7ED558CCDull +
                          bits_of(plane.origin.z()) * 0xC4CEB9FE1A85EC53ull + bits_of(radius) * 0x27D4EB2F165667C5ull;
  return static_cast<std::size_t>(h >> (64 - slot_bits));
}

bool finite_plane(const FingerPlane& plane, double radius) {
  return radius >= 0.0 && std::isfinite(radius) && plane.origin.allFinite() && plane.u.allFinite() &&
         plane.p.allFinite();
}

}  // namespace

const PlaneRegion* SectionSkin::find(const FingerPlane& plane, double radius) const {
  // (region() has asked the entry found last.) The fingers' queries interleave: the table of
  // hashes answers most of the others with one comparison (a miss or a collision falls back to
  // the scan); the entry found becomes the one found last.
  auto found = [&](const Entry* e) {
    last_.store(e, std::memory_order_release);
    return &e->region;
  };
  const int hinted = by_hash_[plane_slot(plane, radius, kHashBits)].load(std::memory_order_acquire);
  if (hinted > 0) {
    const Entry* e = slots_[hinted - 1].load(std::memory_order_acquire);
    if (same_plane(e->plane, e->radius, plane, radius)) return found(e);
  }
  const int n = count_.load(std::memory_order_acquire);
  for (int i = 0; i < n; ++i) {
    const Entry* e = slots_[i].load(std::memory_order_acquire);
    if (same_plane(e->plane, e->radius, plane, radius)) return found(e);
  }
  return nullptr;
}

const PlaneRegion* SectionSkin::insert(std::unique_ptr<Entry> entry) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const int m = count_.load(std::memory_order_relaxed);
  for (int i = 0; i < m; ++i) {
    const Entry* e = slots_[i].load(std::memory_order_relaxed);
    if (same_plane(e->plane, e->radius, entry->plane, entry->radius)) return &e->region;
  }
  if (m >= kMaxRegions) return nullptr;
  const Entry* raw = entry.get();
  owned_.push_back(std::move(entry));
  slots_[m].store(raw, std::memory_order_release);
  std::atomic<int>& hinted = by_hash_[plane_slot(raw->plane, raw->radius, kHashBits)];
  if (hinted.load(std::memory_order_relaxed) == 0) hinted.store(m + 1, std::memory_order_release);
  count_.store(m + 1, std::memory_order_release);
  return &raw->region;
}

const PlaneRegion* SectionSkin::region(const FingerPlane& plane, double radius) const {
  // A finger's queries come in runs (its propagations, its motion check): the entry found last
  // answers most, by its bits (equal bits are equal planes; a zero of the other sign only sends
  // the query on). Threads that share the skin may overwrite it: each load is checked. That
  // test inline; find() and the build out of line.
  if (const Entry* e = last_.load(std::memory_order_acquire);
      e != nullptr && e->radius == radius && same_bits(e->plane, plane))
    return &e->region;
  return find_or_build(plane, radius);
}

// Out of line (where the compiler supports saying so): inlined, it would give region() the
// frame of the build, which its test of the entry found last does not need.
#if defined(__GNUC__)
__attribute__((noinline))
#endif
const PlaneRegion* SectionSkin::find_or_build(const FingerPlane& plane, double radius) const {
  if (const PlaneRegion* r = find(plane, radius)) return r;
  if (!finite_plane(plane, radius)) return nullptr;
  {
    // Built under the lock, so that two threads asking for the same new plane build it once.
    std::lock_guard<std::mutex> lock(build_mutex_);
    if (const PlaneRegion* r = find(plane, radius)) return r;
    if (count_.load(std::memory_order_acquire) >= kMaxRegions) return nullptr;
    return insert(std::make_unique<Entry>(object_, plane, radius, flatten_));
  }
}

void SectionSkin::prepare(const std::vector<FingerPlane>& planes, double radius) const {
  std::vector<const FingerPlane*> todo;
  for (const FingerPlane& p : planes) {
    if (!finite_plane(p, radius) || find(p, radius)) continue;
    bool twice = false;
    for (const FingerPlane* q : todo) twice = twice || same_plane(*q, radius, p, radius);
    if (!twice) todo.push_back(&p);
  }
  const std::size_t room = static_cast<std::size_t>(std::max(0, kMaxRegions - count_.load(std::memory_order_acquire)));
  if (todo.size() > room) todo.resize(room);
  const unsigned hardware =
      build_threads_ > 0 ? static_cast<unsigned>(build_threads_) : std::thread::hardware_concurrency();
  const std::size_t threads = std::min<std::size_t>(todo.size(), hardware > 1 ? hardware : 1);
  if (threads < 2) {
    for (const FingerPlane* p : todo) region(*p, radius);
    return;
  }
  // Each region in two stages (PlaneRegion::FirstStage): every thread takes first stages while
  // any is left, then second stages in the same order, each once its first stage is done. The
  // short second stages fill the time a thread would otherwise wait for the last first stage
  // (five planes on two threads: about 2.5 regions' time instead of 3).
  std::vector<std::unique_ptr<Entry>> built(todo.size());
  std::vector<std::exception_ptr> errors(todo.size());
  std::vector<char> first_done(todo.size(), 0);  // guarded by `stage`
  std::mutex stage;
  std::condition_variable first_stage_done;
  std::atomic<std::size_t> next_first{0}, next_second{0};
  auto work = [&] {
    for (std::size_t i; (i = next_first.fetch_add(1)) < todo.size();) {
      try {
        built[i] = std::make_unique<Entry>(object_, *todo[i], radius, flatten_, PlaneRegion::FirstStage{});
      } catch (...) {
        errors[i] = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(stage);
        first_done[i] = 1;
      }
      first_stage_done.notify_all();
    }
    for (std::size_t j; (j = next_second.fetch_add(1)) < todo.size();) {
      {
        std::unique_lock<std::mutex> lock(stage);
        first_stage_done.wait(lock, [&] { return first_done[j] != 0; });
      }
      if (errors[j]) continue;
      try {
        built[j]->region.finish();
      } catch (...) {
        errors[j] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(threads - 1);  // no allocation between starting threads and joining them
  for (std::size_t t = 1; t < threads; ++t) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;  // no more threads to be had: this one builds the rest
    }
  }
  work();
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  // In the planes' order (an entry's slot never changes an answer).
  for (std::unique_ptr<Entry>& e : built) insert(std::move(e));
}

Touch SectionSkin::link(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double cap) const {
  const PlaneRegion* R = region(plane, radius);
  if (!R) return Sensing::link(plane, a, b, radius, cap);
  const double c = cap >= 0.0 ? cap : 0.0;
  PlaneRegion::Near nr = R->nearest_noted(a, b, c);
  Touch t;
  auto dir = [&](const Vec2& v) { return Vec3(v.x() * plane.u + v.y() * plane.p); };
  if (nr.distance == 0.0) {
    // Crosses or touches R's boundary: penetrating by an unmeasured depth (as the mesh world).
    t.gap = -radius - std::numeric_limits<double>::min();
    t.on_hand = plane.to_world(nr.on_query);
    t.on_object = t.on_hand;
    const double len = nr.normal_sum.norm();
    t.normal = len > 0.0 ? dir(nr.normal_sum / len) : plane.normal();
    return t;
  }
  bool inside;
  if (!std::isfinite(nr.distance)) {
    // Nothing within the cap: outside (any value above the cap will do) or deep inside.
    inside = R->inside(a);
    if (!inside) {
      t.gap = next_up(c);
      t.on_hand = plane.to_world(a);
      t.on_object = t.on_hand;
      return t;
    }
    nr = R->nearest(a, b, kInf);
    if (!std::isfinite(nr.distance)) {  // no boundary at all (cannot happen for a bounded R)
      t.gap = -kInf;
      return t;
    }
  } else {
    inside = R->inside_from(nr, nr.on_query);
  }
  t.gap = inside ? -nr.distance : nr.distance;
  t.on_hand = plane.to_world(nr.on_query);
  t.on_object = plane.to_world(nr.on_region);
  const Vec2 g = (nr.on_query - nr.on_region) / nr.distance;
  t.normal = dir(inside ? Vec2(-g) : g);
  return t;
}

double SectionSkin::gap_in_space(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                 double cap) const {
  if (!region(plane, radius)) return kInf;  // link() measured in space already
  const double c = std::max(cap, 0.0);
  if (!gap_in_space_below(plane, a, b, radius, c)) return next_up(c);
  return mesh_.capsule(plane.to_world(a), plane.to_world(b), radius, cap).gap;
}

bool SectionSkin::gap_in_space_below(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                     double level) const {
  // The axis is outside R, so outside O: its gap in space exceeds level exactly when no triangle
  // comes within radius + level of it, a test that stops at the first one.
  return object_->bvh().any_within(plane.to_world(a), plane.to_world(b), next_up(radius + level));
}

double SectionSkin::contact_gap_bound(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                      double delta, double need, double far) const {
  if (!region(plane, radius)) return Sensing::contact_gap_bound(plane, a, b, radius, delta, need, far);
  // Exact up to need, capped just above it (beyond the cap only known to be at least the cap).
  // Beyond need, the exact gap in space beside a large flat face is a search of many triangles;
  // two threshold tests that stop at the first piece that close say whether it is at least far:
  // R's boundary (the in-plane gap), then the triangles (the axis then lies outside R).
  const double cap = next_up(need);
  const double g = contact_gap(plane, a, b, radius, delta, cap);
  if (g <= need) return g;
  const bool beyond =
      far > need && !link_gap_below(plane, a, b, radius, far) && !gap_in_space_below(plane, a, b, radius, far);
  return beyond ? far : std::min(g, cap);
}

bool SectionSkin::link_gap_below(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                 double below, bool a_outside) const {
  // A piece of R's boundary closer than `below` to the axis: link() would find the nearest piece
  // at most that close, and report a gap below `below` on either side of it. With none that
  // close, link() reports a gap of at least `below` outside R and a negative one inside: the
  // side of the axis (of its end a) decides: outside where the caller knows a to be.
  const PlaneRegion* R = below > 0.0 ? region(plane, radius) : nullptr;
  if (!R) return link(plane, a, b, radius, below).gap < below;
  return R->any_within(a, b, next_toward_zero(below)) || (!a_outside && R->inside(a));
}

namespace {

/// Signed angle from u to v (radians, in [-pi, pi]).
double angle_between(const Vec2& u, const Vec2& v) { return std::atan2(cross2(u, v), u.dot(v)); }

/// This thread's list of spans for rotate_until_free. Out of line: a thread-local's address in a
/// shared library is a call, which the compiler repeats at each use rather than keep it; the
/// reference returned is kept.
#if defined(__GNUC__)
__attribute__((noinline))
#endif
std::vector<PlaneRegion::Span>& span_scratch() {
  thread_local std::vector<PlaneRegion::Span> spans;
  return spans;
}

}  // namespace

RotateResult SectionSkin::rotate_until_free(const RotateRequest& req) const {
  const Vec2 arm = req.end - req.pivot;
  const double len = arm.norm();
  // A search range beyond pi (the planner's is at most pi) goes round onto itself: generic.
  const PlaneRegion* R = len > 0.0 && req.max_angle <= kPi ? region(req.plane, req.radius) : nullptr;
  if (!R) return Sensing::rotate_until_free(req);
  RotateResult out;
  out.end = req.end;
  if (req.pivot.y() < req.front - kFrontSlack) return out;  // behind the palm: no rotation frees it
  const Vec2 u = arm / len;
  // The end may not pass behind the front: blocked where its height pivot.y + len sin(phi) falls
  // below front, the directions counter-clockwise from (-c, k) to (c, k), c = sqrt(1 - k^2).
  const double k = (req.front - kFrontSlack - req.pivot.y()) / len;
  const double c = std::sqrt(std::max(0.0, 1.0 - k * k));
  const Vec2 f0 = len * Vec2(-c, k), f1 = len * Vec2(c, k);
  // Most links free within a few sample angles: the spans of a narrow wedge about the link are
  // asked first, and those of the whole search range only where a run leaves that wedge.
  const double narrow = std::min(req.max_angle, 4.0 * req.sample_angle);
  std::vector<PlaneRegion::Span>& spans = span_scratch();
  bool unsure = false;
  for (int pass = 0; pass < 2; ++pass) {
    const double within = pass == 0 ? narrow : req.max_angle;
    const PlaneRegion::Wedge wedge = PlaneRegion::wedge(within);
    spans.clear();
    if (!R->spans(req.pivot, u, len, wedge, &spans)) return out;  // touches the pivot: all blocked
    if (pass == 0 && !req.pivot_outside && R->inside(req.pivot)) return out;
    if (k > -1.0) {
      const double p0 = PlaneRegion::pseudo_angle(u, f0), p1 = PlaneRegion::pseudo_angle(u, f1);
      if (p0 <= p1) {
        spans.push_back({p0, p1, f0, f1});
      } else {
        spans.push_back({p0, 2.0, f0, -arm});
        spans.push_back({-2.0, p1, -arm, f1});
      }
    }
    std::sort(spans.begin(), spans.end(), [](const PlaneRegion::Span& x, const PlaneRegion::Span& y) {
      return x.lo < y.lo || (x.lo == y.lo && x.hi < y.hi);
    });
    // The runs (unions of spans; windows narrower than kSpanJoin count as blocked) in increasing
    // order, up to the one through 0: its two ends, and where the neighbouring runs start.
    struct Side {
      double reach = 0.0;        ///< pseudo-angle where the run ends
      Vec2 edge = Vec2::Zero();  ///< the boundary point that ends it
      bool has_next = false;     ///< a run follows beyond the window (within the wedge)
      Vec2 next = Vec2::Zero();  ///< the boundary point where it starts
    };
    Side plus, minus;
    bool through_zero = false;
    bool has_prev = false;
    Vec2 prev_hi = Vec2::Zero();
    for (std::size_t i = 0; i < spans.size();) {
      PlaneRegion::Span run = spans[i++];
      for (; i < spans.size() && spans[i].lo <= run.hi + kSpanJoin; ++i) {
        if (spans[i].hi > run.hi) {
          run.hi = spans[i].hi;
          run.v_hi = spans[i].v_hi;
        }
      }
      if (run.lo > kSpanJoin) break;  // past 0: no run through it
      if (run.hi >= 0.0) {
        through_zero = true;
        minus = {run.lo, run.v_lo, has_prev, prev_hi};
        plus = {run.hi, run.v_hi, i < spans.size(), i < spans.size() ? spans[i].v_lo : Vec2::Zero()};
        break;
      }
      has_prev = true;
      prev_hi = run.v_hi;
    }
    if (!through_zero) return Sensing::rotate_until_free(req);  // free where it is: the generic answer
    // A run end inside the wedge is final (spans left out lie wholly beyond the wedge); one that
    // reaches its edge may go on. Each final end gives a candidate: its true angle plus a margin
    // that moves the link's end half the tolerance on (at most half the free window beyond),
    // within max_angle.
    const double pm = wedge.pm;
    const bool plus_final = plus.reach < pm - kSpanJoin, minus_final = minus.reach > -pm + kSpanJoin;
    struct Candidate {
      double angle = 0.0;
      double clearance = 0.0;  ///< how far the boundary point at the run's end is from the link
    };
    auto candidate = [&](const Side& side, int sign, Candidate* cand) {
      const double edge = std::max(0.0, sign * angle_between(u, side.edge));
      if (!(edge < req.max_angle)) return false;
      const double window = side.has_next ? sign * angle_between(side.edge, side.next) : within - edge;
      const double turn = std::min({edge + std::asin(std::min(1.0, 0.5 * req.tolerance / len)),
                                    edge + 0.5 * window, req.max_angle});
      cand->angle = sign * turn;
      cand->clearance = side.edge.norm() * std::sin(turn - edge);
      return turn > edge;
    };
    Candidate c_plus, c_minus;
    const bool has_plus = plus_final && candidate(plus, 1, &c_plus);
    const bool has_minus = minus_final && candidate(minus, -1, &c_minus);
    // The smaller rotation first (ties: flexion). A side still open in the narrow wedge turns at
    // least as far as the wedge: a final side's candidate is the smaller.
    const Candidate* order[2];
    int n = 0;
    if (has_plus && (!has_minus || c_plus.angle <= -c_minus.angle)) {
      order[n++] = &c_plus;
      if (has_minus) order[n++] = &c_minus;
    } else if (has_minus) {
      order[n++] = &c_minus;
      if (has_plus) order[n++] = &c_plus;
    }
    for (int i = 0; i < n; ++i) {
      const Vec2 end = req.pivot + rotate_planar(arm, order[i]->angle);
      // The spans are exact up to rounding: a link that clears the run's end by more than
      // kCertain is free; a closer one (a narrow window) is checked.
      if (order[i]->clearance < kCertain && !link_free(req.plane, req.pivot, end, req.radius, req.front, true)) {
        unsure = true;
        continue;
      }
      out.ok = true;
      out.angle = order[i]->angle;
      out.end = end;
      out.gap = 0.0;  // not measured: a lower bound
      return out;
    }
    if ((plus_final && minus_final) || within >= req.max_angle) break;  // nothing more to learn
  }
  // No rotation within max_angle frees the link, unless a window too narrow to trust was refused:
  // the generic search decides those.
  if (unsure) return Sensing::rotate_until_free(req);
  return out;
}

FollowResult SectionSkin::follow_boundary(const FollowRequest& req) const {
  const PlaneRegion* R = region(req.plane, req.radius);
  FollowResult out;
  // As far along the curve as the generic walk goes at most.
  const double max_length = kFollowSteps / kFollowDivisions * req.step;
  if (R && R->follow(req.tip, req.level, req.step, max_length, req.root, req.reach, req.front + req.radius,
                     &out.head, &out.steps))
    out.gap = req.level;
  else
    out = Sensing::follow_boundary(req);
  return out;
}

bool SectionSkin::link_depth_within(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                    double allow) const {
  const PlaneRegion* R = allow > 0.0 ? region(plane, radius) : nullptr;
  if (!R) return Sensing::link_depth_within(plane, a, b, radius, allow);
  // Most links asked are clear: the plain clearance test settles them, cheaper than the depth.
  return R->clear(a, b, false) || R->depth_within(a, b, allow);
}

bool SectionSkin::link_free(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double front,
                            bool a_outside) const {
  if (a.y() < front - kFrontSlack || b.y() < front - kFrontSlack) return false;
  const PlaneRegion* R = region(plane, radius);
  if (!R) return Sensing::link_free(plane, a, b, radius, front, a_outside);
  return R->clear(a, b, a_outside);
}

}  // namespace hugger
