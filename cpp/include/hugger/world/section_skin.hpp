/// \file section_skin.hpp
/// The section skin: Phase 2 sensing as exact 2D geometry in each finger plane.
///
/// In Phase 2 every finger moves in a fixed plane. A capsule link of radius r lying in the plane
/// is clear of O exactly when its axis segment stays out of the plane's region
///   R = { x in the plane : the 3D distance from x to O (a solid) is at most r }.
/// PlaneRegion builds the boundary of R from the mesh: the plane's sections of the faces of O
/// moved out by r along their normals (segments), of the cylinders of radius r about O's convex
/// edges (ellipse arcs) and of the spheres of radius r about its vertices (circle arcs), each
/// piece kept only where its feature can be the nearest one. Every piece lies in R (its points
/// are at distance r from a feature of O) and together they cover R's boundary; arcs are
/// flattened *outward* (tangent polygons, at most flatten / 2 out), so the pieces form a barrier
/// that no segment starting outside R can cross unseen. Parts of pieces that other pieces cross
/// into R are dropped, and so are the runs of pieces that lie inside R (tested in 3D from their
/// loose ends and junctions) and the closed loops of pieces inside R, so that the pieces left
/// are R's boundary (to within nanometres inside it); joined end to end into chains, they are
/// simplified outward with what remains of the tolerance (every point at most `flatten` outside
/// R), so that their number follows R's curvature rather than the mesh. A 2D BVH over the
/// segments answers every query of a link in the plane in about a thousand instructions, nearly
/// independently of the mesh size; the boundary's convex hull settles first the clearance tests
/// of links with the whole boundary on one side of their line (links tangent to a convex R).
/// Gaps it reports are measured within the plane (never smaller than the 3D gap).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <atomic>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "hugger/geometry/next.hpp"
#include "hugger/sensing/sensing.hpp"
#include "hugger/world/object.hpp"
#include "hugger/world/simulated_world.hpp"

namespace hugger {

/// The region R of one plane for one link radius (see the file comment). Immutable once built.
class PlaneRegion {
 public:
  /// The default flattening tolerance (metres): a tenth of the planner's default contact
  /// tolerance, so that a link the skin keeps off O (by at most this much) is still well inside
  /// the sensing distance. flatten_for() scales it down for smaller contact tolerances.
  static constexpr double kDefaultFlatten = 1e-5;
  /// The flattening tolerance for a planner whose contact tolerance is `delta` (m): a tenth of
  /// it, at most kDefaultFlatten (kDefaultFlatten for a delta that is not a positive number: the
  /// planner refuses it).
  static double flatten_for(double delta) {
    return delta > 0.0 && std::isfinite(delta) ? std::min(kDefaultFlatten, 0.1 * delta) : kDefaultFlatten;
  }
  /// One segment of R's boundary: a segment in plane coordinates with its outward unit normal
  /// (pointing away from R) and the feature of O it comes from.
  struct Segment {
    Vec2 a = Vec2::Zero(), b = Vec2::Zero();
    Vec2 normal = Vec2::UnitX();
    int piece = 0;  ///< index of the feature's piece (one polyline per face, edge or vertex arc);
                    ///< for a simplified segment, the piece of the first segment it replaces
  };
  enum class Kind : std::uint8_t { kFace, kEdge, kVertex };
  struct Piece {
    Kind kind = Kind::kFace;
    std::int64_t feature = 0;  ///< face, vertex or (for edges) 3 * face + k
  };
  /// Nearest piece of R's boundary to a query segment.
  struct Near {
    double distance = kInf;          ///< in-plane distance; 0 when the query crosses or touches
    Vec2 on_query = Vec2::Zero();    ///< nearest point of the query
    Vec2 on_region = Vec2::Zero();   ///< nearest point of the boundary pieces
    Vec2 normal_sum = Vec2::Zero();  ///< sum of the outward normals of the pieces nearest (ties)
    int ties = 0;                    ///< how many segments are nearest (several at a shared end point)
    bool at_end = false;             ///< the nearest point is an end point of the (first) nearest segment
    int segment = -1;                ///< index (segments()) of the segment holding on_region
  };

  /// Builds R for the plane and `radius` (>= 0). `flatten` (> 0): how far outside R the boundary
  /// segments may lie (metres): arcs' tangent polygons and the simplified chains together.
  PlaneRegion(std::shared_ptr<const Object> object, const FingerPlane& plane, double radius, double flatten);
  /// The same build in two stages, for SectionSkin::prepare, which runs the stages of several
  /// regions side by side: the (private) constructor taking FirstStage stops after the pieces,
  /// their crossings and the parts dropped inside R; finish() then simplifies the chains and
  /// builds the tree, the cells and the links.
  struct FirstStage {};

  /// Nearest boundary piece to segment [a, b] (a == b: a point) within `cap`; distance is +inf
  /// when nothing is within cap.
  Near nearest(const Vec2& a, const Vec2& b, double cap = kInf) const;
  /// nearest(), for a point (a == b) answered from the thread's last such query of this region
  /// when that one asked the same point with a cap at most `cap` and found its first piece within
  /// its cap: then the answers agree bit for bit (see there). A tip's contact query (capped at the
  /// contact tolerance) and the boundary walk from it (uncapped) ask it in turn.
  Near nearest_noted(const Vec2& a, const Vec2& b, double cap) const;
  /// True when some boundary piece comes within `distance` of segment [a, b] (or touches it).
  bool any_within(const Vec2& a, const Vec2& b, double distance) const;
  /// True when segment [a, b] stays out of R: no boundary piece touches it and a lies outside R
  /// (`a_outside`: the caller knows so).
  bool clear(const Vec2& a, const Vec2& b, bool a_outside) const;
  /// True when no point of segment [a, b] lies in R deeper than `allow` (> 0) from its boundary:
  /// the points within `allow` of a boundary piece (an interval of the segment per piece) are
  /// that shallow, and each stretch between them lies wholly outside R or wholly inside (one
  /// inside test each).
  bool depth_within(const Vec2& a, const Vec2& b, double allow) const;
  /// The directions, seen from a pivot, in which a segment of a given length starting there
  /// meets a boundary piece: one span per piece part within the length of the pivot, from its
  /// clockwise end to its counter-clockwise end. Angles are pseudo-angles (monotone in the true
  /// angle, in [-2, 2], 0 along `u`, +-2 opposite it); a span across +-2 is split in two.
  struct Span {
    double lo = 0.0, hi = 0.0;                 ///< pseudo-angles, lo <= hi
    Vec2 v_lo = Vec2::Zero(), v_hi = Vec2::Zero();  ///< the piece's points at lo and hi, minus the pivot
  };
  /// The wedge of directions within `within` radians of a direction, as spans and the rotations
  /// use it: its bound in pseudo-angle and the cosines and sines of its two sides' turns.
  struct Wedge {
    double within = 0.0;
    double pm = 0.0;                          ///< pseudo_angle_of(within)
    double c = 1.0, s = 0.0;                  ///< cos(within), sin(within)
    double c_neg = 1.0, s_neg = 0.0;          ///< cos(-within), sin(-within)
  };
  /// The wedge of `within`. The angles asked are few (a rotation's search ranges): the last one
  /// is kept per thread, for the angle of the same bits (-0 is not +0).
  static Wedge wedge(double within);
  /// Appends to `out` the spans of the boundary pieces within `length` of `pivot` (u: a unit
  /// direction) that reach directions within the wedge `w` about u, `w.within` radians either
  /// side (others may be left out). False when a piece comes within touching distance of the
  /// pivot (every direction is blocked; `out` is then incomplete).
  bool spans(const Vec2& pivot, const Vec2& u, double length, const Wedge& w, std::vector<Span>* out) const;
  /// The pseudo-angle of the direction at `angle` radians from u (|angle| <= pi; +-2 beyond).
  static double pseudo_angle_of(double angle) {
    return std::abs(angle) >= kPi ? (angle < 0.0 ? -2.0 : 2.0)
                                  : pseudo_angle(Vec2::UnitX(), Vec2(std::cos(angle), std::sin(angle)));
  }
  /// The pseudo-angle of v (non-zero) relative to the unit direction u (see Span).
  static double pseudo_angle(const Vec2& u, const Vec2& v) {
    // In u's frame: y / (|x| + |y|) runs from -1 to 1 over the half-plane ahead (x >= 0); behind,
    // it is reflected onto (1, 2] and [-2, -1). Monotone in the true angle, and v and -v differ
    // by exactly 2: a span shorter than pi is shorter than 2.
    const double x = u.x() * v.x() + u.y() * v.y(), y = u.x() * v.y() - u.y() * v.x();
    return pseudo_from(x, y, y / (std::abs(x) + std::abs(y)));
  }
  /// pseudo_angle(UnitX, v) and pseudo_angle(UnitX, -v) (v non-zero) from one division: the same
  /// values but for the sign of a zero, which no lookup of an AngleIndex tells apart (-r is -y
  /// over the same sum, 2 - (-r) is 2 + r).
  static std::pair<double, double> pseudo_angles_of(const Vec2& v) {
    const double x = v.x(), y = v.y(), r = y / (std::abs(x) + std::abs(y));
    return {pseudo_from(x, y, r), pseudo_from(-x, -y, -r)};
  }
  /// The pseudo-angle of the direction (x, y) in u's frame, r = y / (|x| + |y|).
  static double pseudo_from(double x, double y, double r) {
    if (x >= 0.0) return r;
    return y >= 0.0 ? 2.0 - r : -2.0 - r;
  }
  /// Non-decreasing pseudo-angles in [-2, 2] (a convex chain's edge directions, from the edge
  /// after they wrap round), with where each of 2n equal parts of [-2, 2] starts among them: the
  /// first angle at or past t is then a lookup and a step or two, where a binary search took
  /// log n steps (its answer, to the index).
  struct AngleIndex {
    std::vector<double> angle;
    std::vector<int> part;  ///< part[b]: the first i with angle[i] at or past the start of part b - 1
    double scale = 0.0;     ///< parts per unit of pseudo-angle
    void build(std::vector<double> angles);
    /// The first i with angle[i] >= t; 0 where none is (the chain goes on round to the first).
    int first_at_least(double t) const {
      const int n = static_cast<int>(angle.size()), parts = static_cast<int>(part.size()) - 1;
      const double x = (t + 2.0) * scale;
      int i = part[x > 0.0 ? (x < parts ? static_cast<int>(x) : parts) : 0];
      while (i < n && angle[i] < t) ++i;
      return i == n ? 0 : i;
    }
  };
  /// True when x lies in R (closed). From its cell's label where no segment touches the cell,
  /// else from the side of the nearest piece; where that is unsafe (a loose end, a side test too
  /// close to call) from one 3D query.
  bool inside(const Vec2& x) const;
  /// Whether a point at the `near` answer of a query (not crossing) lies in R.
  bool inside_from(const Near& near, const Vec2& x) const;
  /// The exact 3D test (x in R: within `radius` of O, or inside O).
  bool inside_3d(const Vec2& x) const;
  /// Boundary following in closed form: from the projection of `tip` (outside R) onto the level
  /// curve {in-plane gap = level} (R's boundary moved out by `level`: moved segments, arcs of
  /// radius `level` at convex vertices, cut at concave ones), walks it with R on the left to the
  /// first point `step` from the tip, or `max_length` along it, and writes it to `head` (with
  /// the pieces walked). False, leaving the walk to the generic procedure, where the tip is not
  /// outside R, the walk meets a junction of pieces or a corner it cannot place, a point it
  /// reaches is farther than `reach` from `root` or below `lowest`, or the head's measured gap is
  /// not the level to within a tenth (another part of the boundary comes nearer).
  bool follow(const Vec2& tip, double level, double step, double max_length, const Vec2& root, double reach,
              double lowest, Vec2* head, int* pieces) const;

  const FingerPlane& plane() const { return plane_; }
  double radius() const { return radius_; }
  const std::vector<Segment>& segments() const { return segments_; }
  const std::vector<Piece>& pieces() const { return pieces_; }
  /// True where the boundary is one convex loop: spans(), clear(), any_within(), inside() and
  /// depth_within() then ask the loop first, and the tree where it does not settle them.
  bool convex() const { return loop_kind_ == LoopKind::kConvex; }
  /// Where the boundary is one loop but not convex: how many pockets its convex hull H has
  /// (stretches where H lies outside R, each under one of H's edges, a lid). The same queries
  /// then ask H's loop first where they reach no pocket (there R and H agree). 0 where R is
  /// convex or not one loop.
  int pockets() const { return static_cast<int>(pockets_.size()); }  // (kept only with the loop)
  /// Whether the loop's shortcuts may answer a query reaching `distance` (>= 0) about segment
  /// [a, b] (a point: a == b): R's loop is convex, or H's pockets lie beyond that reach.
  bool loop_answers(const Vec2& a, const Vec2& b, double distance) const {
    return loop_kind_ == LoopKind::kConvex || (loop_kind_ == LoopKind::kPockets && !near_pocket(a, b, distance));
  }
  /// Segments dropped at build time as lying inside R.
  long dropped() const { return dropped_; }
  /// Number of 3D inside tests asked so far (side tests that were unsafe).
  long fallbacks() const { return fallbacks_.load(std::memory_order_relaxed); }

 private:
  friend class SectionSkin;
  PlaneRegion(std::shared_ptr<const Object> object, const FingerPlane& plane, double radius, double flatten,
              FirstStage);
  /// The second stage of the build (see FirstStage).
  void finish();
  struct Node {
    double lo[2], hi[2];
    double c[2], h[2];  ///< centre and half extent, (lo + hi) / 2 and (hi - lo) / 2
    int left = -1, right = -1;  ///< children; -1 in a leaf
    int first = 0, count = 0;   ///< a leaf's segments
  };
  /// Depth first over the 2D tree (left before right): skips every node `skip(node)` is true of
  /// and calls `visit(i)` on each segment of the leaves reached, stopping when `visit` returns
  /// true. Returns whether it stopped. `root_kept`: the caller has found `skip(root)` false
  /// already, so the walk starts below the root without asking again.
  template <class Skip, class Visit>
  bool visit_segments(Skip&& skip, Visit&& visit, bool root_kept = false) const;
  void build_pieces();
  void build_bvh();
  /// The convex hull of the segments' end points (hull_, hull_index_).
  void build_hull();
  /// True when the whole boundary lies farther than `limit` (> 0, with the rounding margin) from
  /// the line of query `q` (a segment query), all of it on one side: then no segment comes within
  /// `limit` of the query. Two binary searches over the hull, which settle the queries of links
  /// tangent to a convex R without the tree (links resting on O mostly are).
  template <class Q>
  bool hull_apart(const Q& q, double limit) const;
  /// How near segment [a, b] comes to the boundary: within `distance` of a piece; apart from
  /// the boundary's box or hull by more (so outside them: outside R); or beyond `distance` of
  /// every piece, found by the tree. A piece found within is kept as a hint for the next query
  /// starting near a (hints_), which asks it and its two successors before the tree: taken where it
  /// lies within `distance` less the rounding margin of the tree's node bounds (Query::slack),
  /// so that the walk would have reached it. (At coordinates of a metre or more that margin
  /// exceeds clear()'s touching distance, and clear() takes no hint: the same answers, slower.)
  enum class Reach : std::uint8_t { kWithin, kApart, kBeyond };
  Reach reach(const Vec2& a, const Vec2& b, double distance) const;
  /// Drops the runs of segments that lie inside R (found from their loose ends and junctions,
  /// each tested once in 3D) and the closed loops inside R (one test each; neither for r = 0),
  /// then replaces the chains of segments (joined end to end, two at each inner vertex) by fewer
  /// segments that lie outside them, behind which every original vertex lies within `tol`.
  void simplify(double tol);
  /// One chain: points P (P[i], P[i + 1] the ends of segments_[seg[i]]); appends the new
  /// segments to `out`.
  void simplify_chain(const std::vector<Vec2>& P, const std::vector<int>& seg, double tol,
                      std::vector<Segment>* out) const;
  void mark_crossings();
  /// The 3D test of a point of a piece: strictly inside R (within r less a margin of O's
  /// surface, or inside O).
  bool strictly_inside_3d(const Vec2& x) const;
  /// Cuts crossed segments at their crossings and drops the parts that start at a crossing on
  /// the inner side of the crossing piece (whose feature is then nearer than r just past it):
  /// inside R. The other parts lie wholly on R's boundary or wholly inside it: simplify() tests
  /// their runs.
  void drop_inner_segments();
  int build_node(int begin, int end, std::vector<Vec2>& centres, int depth);
  /// The grid of cells that no segment touches, each labelled inside or outside R (one inside
  /// test per connected group of such cells: no boundary separates two of its points).
  void build_cells();
  /// next_: each segment's successor along the boundary (R on the left), or -1 at a junction.
  void link_segments();
  /// loop_ and its companions, where the boundary is one loop: convex, or whose hull has at most
  /// kMaxPockets pockets (else they stay empty).
  ///
  /// The convex_* shortcuts below are written for a convex R. Where R is one loop but not convex
  /// they answer for its hull H, and are asked only where the query's reach (the segment or
  /// pivot grown by the distance asked, plus a margin) meets no pocket's box (loop_answers):
  /// there R and H, and their boundaries, are the same, so H's answer is R's. convex_shallow
  /// needs no such test: a point of R lies no deeper in R than in H.
  void build_loop();
  /// No loop (loop_kind_ kNone, its lists empty).
  void clear_loop();
  /// spans() where R is one convex loop: the pieces within `length` of the pivot are one run of
  /// the loop facing it, and the span of their union is settled by the few segments at its two
  /// ends (found by walking the loop), each by the same formula as in the tree's visit. False
  /// where the pivot is not outside R: the tree decides.
  bool convex_spans(const Vec2& pivot, const Vec2& u, double length, double pm, bool* touching,
                    std::vector<Span>* out) const;
  /// clear() where R is one convex loop: 1 (clear) or 0 (not) where the loop settles it surely,
  /// -1 where the segment passes within kSureApart of R without meeting it, or lies wholly in R
  /// with a_outside told (the tree decides both). The segment meets R (not clear) where b lies
  /// inside the line of its wedge's edge, or the line's chord through R overlaps it; it misses
  /// R where its line passes R, or a supporting line of R (of b's wedge edge, or of the edge
  /// where the chord leaves or enters) separates them, by more than kSureApart.
  int convex_clear(const Vec2& a, const Vec2& b, bool a_outside) const;
  /// any_within() where R is one convex loop: 1 where a boundary point (the lowest or highest
  /// tail across the segment's line, or an end of the line's chord through R) lies within
  /// `distance` less kSureApart of the segment, 0 where R's box, R itself (across the line) or
  /// the supporting line where the chord ends lies farther than `distance` plus kSureApart;
  /// -1 otherwise (the tree decides: a segment within R, or a near call).
  int convex_within(const Vec2& a, const Vec2& b, double distance) const;
  /// Where the line of a query crosses a convex R (convex_chord): along the query from its start,
  /// where the line enters and leaves R, and the loop's edges crossed there.
  struct Chord {
    double t_in = 0.0, t_out = 0.0;
    int e_in = 0, e_out = 0;
  };
  /// The chord of query q's line, which crosses R: its lowest tail `bottom` below the line and
  /// its highest `top` above.
  template <class Q>
  Chord convex_chord(const Q& q, int bottom, int top) const;
  /// How far x lies beyond the line of the loop's edge `edge` (outward).
  double beyond_edge(int edge, const Vec2& x) const;
  /// inside() where R is one convex loop: 1 or 0 where x lies farther than kSureApart inside or
  /// outside the line of the edge whose wedge about the loop's centre holds it; -1 nearer.
  int convex_inside(const Vec2& x) const;
  /// The loop's edge whose wedge about the loop's centre holds x (the last tail at or before x's
  /// angle about it); -1 for x at the centre.
  int loop_wedge(const Vec2& x) const;
  /// depth_within()'s shortcut where R is one convex loop: true where the line of one edge (of
  /// the wedge of b or of a) lies within `allow` less kSureApart of both ends on R's side, so
  /// that no point of the segment lies deeper in R than that; false where neither does
  /// (depth_within then decides).
  bool convex_shallow(const Vec2& a, const Vec2& b, double allow) const;
  /// The loop's tail farthest along the direction of an edge turned a right angle clockwise, for
  /// the edge direction's pseudo-angle (pseudo_angles_of).
  int loop_extreme(double edge) const;
  /// Adds the arcs of x(t) = centre + U cos t + V sin t over the allowed intervals of `allowed`
  /// ([0, 2 pi), sorted, disjoint) as tangent polygons; `out3(t)`: the in-plane outward direction.
  template <class Outward>
  void add_arcs(Kind kind, std::int64_t feature, const Vec2& centre, const Vec2& U, const Vec2& V,
                const std::vector<std::array<double, 2>>& allowed, Outward&& outward);
  void add_segment(const Vec2& a, const Vec2& b, const Vec2& outward, int piece);

  /// nearest(); `first` (or nullptr): set to the distance of the first piece it found (kept
  /// unchanged when it found none).
  Near search_nearest(const Vec2& a, const Vec2& b, double cap, double* first) const;

  std::shared_ptr<const Object> object_;
  /// Unique to this region in the process (nearest_noted's memory names regions by it: an
  /// address may be reused by a later region).
  std::uint64_t id_;
  FingerPlane plane_;
  double radius_ = 0.0, flatten_ = kDefaultFlatten;
  std::vector<Segment> segments_;
  std::vector<int> next_;  ///< link_segments()
  std::vector<Piece> pieces_;
  std::vector<Node> nodes_;
  std::vector<int> order_;                       ///< while building the BVH
  /// The boundary's convex hull, counter-clockwise from the edge after its edges' pseudo-angles
  /// wrap round; hull_index_.angle[i]: the pseudo-angle (pseudo_angle from +x) of the edge from
  /// hull_[i] to the next vertex.
  std::vector<Vec2> hull_;
  AngleIndex hull_index_;
  /// Where the boundary is one loop that turns left at every vertex (a convex R): its segments
  /// in order along it (R on the left: counter-clockwise), loop_tail_[i] the tail of segment
  /// loop_[i] (its head is the next tail), and loop_polar_.angle[i] the pseudo-angle of
  /// loop_tail_[i] about loop_centre_ (the tails' mean, inside R), increasing from i = 0. Where
  /// the boundary is one loop that does not turn left everywhere, the same of the loop of its
  /// convex hull H (build_loop), whose edges are segments of R or lids over pockets_.
  enum class LoopKind : std::uint8_t { kNone, kConvex, kPockets };
  LoopKind loop_kind_ = LoopKind::kNone;
  struct LoopEdge {
    Vec2 a, b;   ///< a segment's ends as in segments_ (a lid's: its tail, then its head)
    Vec2 normal;  ///< outward unit normal
  };
  std::vector<LoopEdge> loop_;
  std::vector<Vec2> loop_tail_;
  /// A pocket of H outside R: the box of its stretch of R's boundary (the lid's ends included).
  struct Pocket {
    Vec2 lo, hi;
  };
  std::vector<Pocket> pockets_;

  /// True when segment [a, b] grown by `distance` (and twice kSureApart) reaches a pocket's box:
  /// the loop's shortcuts then leave the query to the tree.
  bool near_pocket(const Vec2& a, const Vec2& b, double distance) const;
  AngleIndex loop_polar_;
  Vec2 loop_centre_ = Vec2::Zero();
  /// The loop's edges' pseudo-angles (from +x), from edge loop_edge_first_ on (as the hull's),
  /// for loop_extreme.
  int loop_edge_first_ = 0;
  AngleIndex loop_edges_;
  /// A crossing of a segment by a piece of another feature, while building: where, and on which
  /// side of the crossing segment (its inner side: towards its feature) the segment goes on.
  struct Cut {
    int segment = 0;
    double t = 0.0;            ///< parameter along the segment, in (0, 1)
    bool after_inner = false;  ///< the part beyond t (towards b) starts on the inner side
    bool operator<(const Cut& o) const { return segment < o.segment || (segment == o.segment && t < o.t); }
  };
  std::vector<Cut> cuts_;
  int depth_ = 0;
  double arc_deviation_ = 0.0;  ///< while building: how far the flattened arcs lie out, at most
  double extent_ = 0.0;  ///< largest absolute coordinate of a segment's end (for rounding margins)
  // The cell grid (build_cells): cell (i, j) spans lo + cell * [i, i + 1] x [j, j + 1]; cells_
  // holds -1 where a segment's box (grown by a margin) meets the cell, else 1 inside R, 0 outside.
  Vec2 cells_lo_ = Vec2::Zero();
  double cell_ = 0.0;
  int cells_n_[2] = {0, 0};
  std::vector<signed char> cells_;
  long dropped_ = 0;
  mutable std::atomic<long> fallbacks_{0};
  /// reach()'s hints: per coarse cell of a query's start (8 of build_cells' cells a side; the
  /// cells hashed into kHints slots), the segment last found within reach of such a query (-1:
  /// none; reset by finish()). A hint is taken only where the tree's walk would answer the same
  /// (reach), so the answers do not depend on them; shared by threads, relaxed.
  static constexpr int kHints = 256;
  static_assert((kHints & (kHints - 1)) == 0, "hint_key masks with kHints - 1");
  mutable std::array<std::atomic<int>, kHints> hints_{};
  double hint_scale_ = 0.0;  ///< hint cells per metre (0 without cells: every query in slot 0)
  /// The slot of the query starting at a.
  int hint_key(const Vec2& a) const;
};

/// The section skin (docs/performance.md): answers link queries given in finger-plane
/// coordinates from the plane's PlaneRegion (built by prepare(), which the Planner's constructor
/// calls with the Phase 2 planes, or on first use; once per plane and radius);
/// capsule and palm queries in the world, and the higher-level queries' world-frame parts, go
/// to the mesh world. Thread-safe: regions are built under a lock and then only read.
class SectionSkin final : public Sensing {
 public:
  /// `flatten`: how far outside R the boundary may lie (metres, > 0; PlaneRegion).
  explicit SectionSkin(std::shared_ptr<const Object> object, double flatten = PlaneRegion::kDefaultFlatten);
  ~SectionSkin() override;

  Touch capsule(const Vec3& a, const Vec3& b, double radius, double cap = kInf) const override {
    return mesh_.capsule(a, b, radius, cap);
  }
  double palm(const Pose& palm, double radius, double thickness, double cap = kInf) const override {
    return mesh_.palm(palm, radius, thickness, cap);
  }
  bool capsule_clear(const Vec3& a, const Vec3& b, double radius, bool a_outside) const override {
    return mesh_.capsule_clear(a, b, radius, a_outside);
  }
  /// In-plane gap of the link: the distance within the plane from its axis to R (negative inside
  /// R). Exact when at most `cap`; otherwise a value above cap. on_object is the nearest point of
  /// R's boundary (not of O), and the normal lies in the plane.
  Touch link(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double cap = kInf) const override;
  bool link_free(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double front,
                 bool a_outside = false) const override;
  /// As link(...).gap < below, stopping at the first boundary piece closer than `below`.
  bool link_gap_below(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double below,
                      bool a_outside = false) const override;
  /// Exact up to `need`; beyond it `far` where threshold tests (R's boundary, then the object's
  /// BVH in space) find nothing within `far`, else a value just above `need`.
  double contact_gap_bound(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double delta,
                           double need, double far) const override;
  /// Exactly, by PlaneRegion::depth_within: no point of the axis deeper in R than `allow`.
  bool link_depth_within(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                         double allow) const override;
  /// In closed form where it can (PlaneRegion::follow: the level curve walked exactly), else
  /// the generic procedure on this skin's in-plane gaps.
  FollowResult follow_boundary(const FollowRequest& req) const override;
  /// In closed form: the directions in which the link meets R are the union of the spans of R's
  /// boundary pieces seen from the pivot (and, for the end, the half-plane behind the front);
  /// the smallest rotation out of the blocked run containing the link's direction, plus a
  /// margin that leaves the link resting within `tolerance` of R, is checked with one link
  /// query. Falls back to the generic search where the plane has no region or the check fails.
  /// The pivot's inside test is left out where the request says it is outside (pivot_outside).
  RotateResult rotate_until_free(const RotateRequest& req) const override;

  /// Builds the regions of these planes not built yet, for links of `radius`, side by side on up
  /// to one thread per region (at most the hardware's threads), each in its two stages
  /// (PlaneRegion::FirstStage); the regions are those region() builds, whatever the thread count.
  void prepare(const std::vector<FingerPlane>& planes, double radius) const override;

  /// The region of a plane and radius, built on first use; nullptr past kMaxRegions regions
  /// (queries in further planes then go to the mesh world). A skin shared by several planners
  /// spends its regions as they are made (each Planner's constructor prepares its planes, run or
  /// not): past about twelve hands of five fingers, give each planner a skin of its own.
  const PlaneRegion* region(const FingerPlane& plane, double radius) const;
  /// How many regions are built so far.
  int regions() const { return count_.load(std::memory_order_acquire); }
  const Object& object() const { return *object_; }
  const SimulatedWorld& mesh_world() const { return mesh_; }
  double flatten() const { return flatten_; }
  /// How many threads prepare() may use: 0 (the default) as many as the hardware has. The
  /// regions are the same whatever it is.
  void set_build_threads(int threads) { build_threads_ = std::max(threads, 0); }
  static constexpr int kMaxRegions = 64;

 protected:
  /// Contact (Sensing::contact_gap) where the in-plane gap exceeds the sensing distance: the mesh
  /// world's gap in space, after a threshold test on the object's BVH (nothing within radius +
  /// cap: a value above the cap, without the inside test the gap would ask for beyond the cap;
  /// the axis is outside O). +inf in a plane without a region (link() measured in space).
  double gap_in_space(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                      double cap) const override;

 private:
  /// Its threshold test alone, for an axis outside R: some triangle within radius + level (>= 0).
  bool gap_in_space_below(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                          double level) const;
  struct Entry;
  /// The region of the plane and radius if built, else nullptr (no lock).
  const PlaneRegion* find(const FingerPlane& plane, double radius) const;
  /// region() past its test of the entry found last: find(), else build.
  const PlaneRegion* find_or_build(const FingerPlane& plane, double radius) const;
  /// Adds a built region unless one of its plane and radius is there (under the lock); returns
  /// the region kept, or nullptr past kMaxRegions.
  const PlaneRegion* insert(std::unique_ptr<Entry> entry) const;
  std::shared_ptr<const Object> object_;
  SimulatedWorld mesh_;
  double flatten_;
  mutable std::mutex mutex_;        ///< guards owned_ and new slots
  mutable std::mutex build_mutex_;  ///< region(): one thread builds a new plane's region at a time
  mutable std::vector<std::unique_ptr<Entry>> owned_;
  mutable std::array<std::atomic<const Entry*>, kMaxRegions> slots_{};
  /// find()'s table: slot index + 1 of the entry whose plane and radius hash there (0: none; a
  /// later entry of the same hash is found by the scan instead).
  static constexpr int kHashBits = 7, kHashSlots = 1 << kHashBits;
  mutable std::array<std::atomic<int>, kHashSlots> by_hash_{};
  mutable std::atomic<int> count_{0};
  /// find()'s entry found last (nullptr: none yet); entries live as long as the skin.
  mutable std::atomic<const Entry*> last_{nullptr};
  int build_threads_ = 0;
};

}  // namespace hugger
