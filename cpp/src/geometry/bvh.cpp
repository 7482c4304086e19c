#include "hugger/geometry/bvh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <future>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "hugger/geometry/order.hpp"

namespace hugger {

TriangleBvh::Builder::Builder(const PointsN3& vertices_, const FacesN3& faces_, int leaf_size_, int presorted_)
    : vertices(vertices_), faces(faces_), leaf_size(leaf_size_), presorted(std::max(presorted_, leaf_size_)) {
  const int n = static_cast<int>(faces.rows());
  if (n <= presorted) return;  // presorted from the root: no selection, no items
  items.resize(n);
  for (int i = 0; i < n; ++i) {
    const Vec3 c = box(i).centre();
    items[i] = {{c.x(), c.y(), c.z()}, i};
  }
}

Aabb TriangleBvh::Builder::box(int t) const {
  Aabb b;
  for (int k = 0; k < 3; ++k) b.grow(Vec3(vertices.row(faces(t, k)).transpose()));
  return b;
}

namespace {

/// Axis of the longest extent of a box (lo, hi), the first on ties (as Eigen's maxCoeff).
int longest_axis(const double lo[3], const double hi[3]) {
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  return axis;
}

}  // namespace

int TriangleBvh::Builder::split(int begin, int end) {
  // An inner node's box is its children's union (the same box: min and max are exact), so only
  // the centroids' box is gathered here, for the split axis.
  double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  for (int i = begin; i < end; ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], items[i].c[k]);
      hi[k] = std::max(hi[k], items[i].c[k]);
    }
  const int axis = longest_axis(lo, hi);
  const int mid = (begin + end) / 2;
  std::nth_element(items.begin() + begin, items.begin() + mid, items.begin() + end,
                   [axis](const BuildItem& x, const BuildItem& y) {
                     return x.c[axis] < y.c[axis] || (x.c[axis] == y.c[axis] && x.id < y.id);
                   });
  return mid;
}

namespace {

/// A node's box, with the centre and half extent its tests use.
template <class Node>
void set_box(Node& nd, const Aabb& box) {
  nd.box = box;
  nd.centre = box.centre();
  nd.half = 0.5 * box.extent();
}

/// A node of the tree from its children (an inner node's box is their union).
template <class Node>
int inner_node(std::vector<Node>& nodes, int index, int left, int right) {
  Node& nd = nodes[index];
  nd.left = left;
  nd.right = right;
  Aabb box = nodes[left].box;
  box.grow(nodes[right].box);
  set_box(nd, box);
  return index;
}

}  // namespace

int TriangleBvh::Builder::build(int begin, int end, BuildOut& out, int depth) {
  if (end - begin <= presorted) {
    // The range's triangles in increasing index order (so that the stable sorts break ties by
    // index), with their centres: all of them from the root, else the items' in order of id.
    const int m = end - begin;
    std::vector<int> ids(static_cast<std::size_t>(m));
    std::array<std::vector<double>, 3> centres;
    for (std::vector<double>& c : centres) c.resize(m);
    if (items.empty()) {
      for (int i = 0; i < m; ++i) {
        ids[i] = begin + i;
        const Vec3 c = box(ids[i]).centre();
        for (int k = 0; k < 3; ++k) centres[k][i] = c[k];
      }
    } else {
      std::vector<std::uint32_t> id_of(static_cast<std::size_t>(m));
      for (int i = 0; i < m; ++i) id_of[i] = static_cast<std::uint32_t>(items[begin + i].id);
      const std::vector<int> by_id = ascending_order(id_of);
      for (int i = 0; i < m; ++i) {
        const BuildItem& it = items[begin + by_id[i]];
        ids[i] = it.id;
        for (int k = 0; k < 3; ++k) centres[k][i] = it.c[k];
      }
    }
    return Presorted(*this, std::move(ids), std::move(centres)).build(0, m, out, depth);
  }
  out.depth = std::max(out.depth, depth);
  const int index = static_cast<int>(out.nodes.size());
  out.nodes.emplace_back();
  const int mid = split(begin, end);
  const int left = build(begin, mid, out, depth + 1);
  const int right = build(mid, end, out, depth + 1);
  return inner_node(out.nodes, index, left, right);
}

TriangleBvh::Presorted::Presorted(const Builder& builder_, std::vector<int> ids_,
                                  std::array<std::vector<double>, 3> centres_)
    : builder(builder_), ids(std::move(ids_)), centres(std::move(centres_)) {
  for (int k = 0; k < 3; ++k) sorted[k] = ascending_order(centres[k]);
  scratch.resize(ids.size());
  lower.resize(ids.size());
}

int TriangleBvh::Presorted::split(int begin, int end) {
  // The centroids' box from the ends of each axis's list.
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = centres[k][sorted[k][begin]];
    hi[k] = centres[k][sorted[k][end - 1]];
  }
  const int axis = longest_axis(lo, hi);
  const int mid = (begin + end) / 2;
  // Raw pointers: stores through the flags (chars) could otherwise alias the vectors' own.
  char* const low_flag = lower.data();
  const int* const by_axis = sorted[axis].data();
  for (int i = begin; i < mid; ++i) low_flag[by_axis[i]] = 1;
  for (int i = mid; i < end; ++i) low_flag[by_axis[i]] = 0;
  // The other two lists, each split into its lower and upper half in order (stable).
  int* const out = scratch.data();
  for (int k = 0; k < 3; ++k) {
    if (k == axis) continue;
    int* const list = sorted[k].data();
    int low = begin, high = mid;
    for (int i = begin; i < end; ++i) {
      const int t = list[i];
      const int is_low = low_flag[t];
      // The slot by arithmetic, not a conditional the compiler may turn into a branch (taken
      // at random: half of them mispredicted).
      out[high + ((low - high) & -is_low)] = t;
      low += is_low;
      high += 1 - is_low;
    }
    std::copy(out + begin, out + end, list + begin);
  }
  return mid;
}

int TriangleBvh::Presorted::build(int begin, int end, BuildOut& out, int depth) {
  out.depth = std::max(out.depth, depth);
  const int index = static_cast<int>(out.nodes.size());
  out.nodes.emplace_back();
  if (end - begin <= builder.leaf_size) {
    Aabb box;
    for (int i = begin; i < end; ++i) box.grow(builder.box(ids[sorted[0][i]]));
    Node& nd = out.nodes[index];
    set_box(nd, box);
    nd.first = static_cast<int>(out.order.size());
    nd.count = end - begin;
    for (int i = begin; i < end; ++i) out.order.push_back(ids[sorted[0][i]]);
    return index;
  }
  const int mid = split(begin, end);
  const int left = build(begin, mid, out, depth + 1);
  const int right = build(mid, end, out, depth + 1);
  return inner_node(out.nodes, index, left, right);
}

TriangleBvh::TriangleBvh(const PointsN3& vertices, const FacesN3& faces, int leaf_size, int threads,
                         int presorted) {
  const int n = static_cast<int>(faces.rows());
  leaf_size = std::max(1, leaf_size);
  Builder builder(vertices, faces, leaf_size, presorted);
  // A median split makes leaves of more than leaf_size / 2 triangles: at most n / that leaves,
  // and one fewer inner nodes.
  const std::size_t capacity = 2 * static_cast<std::size_t>(std::max(1, n / ((leaf_size + 1) / 2))) + 1;
  BuildOut out;
  if (threads == 0) threads = std::thread::hardware_concurrency() >= 2 ? 2 : 1;
  if (threads >= 2 && n > builder.presorted) {
    // The root's halves side by side, then laid out as the single-threaded build lays them out
    // (root, the left subtree, the right subtree; leaves in the same order): the same tree.
    const int mid = builder.split(0, n);
    BuildOut left, right;
    left.nodes.reserve(capacity / 2 + 1);
    right.nodes.reserve(capacity / 2 + 1);
    std::future<void> half;
    try {
      half = std::async(std::launch::async, [&] { builder.build(0, mid, left, 1); });
    } catch (const std::system_error&) {  // no thread to be had: this one builds both halves
    }
    builder.build(mid, n, right, 1);
    if (half.valid())
      half.get();
    else
      builder.build(0, mid, left, 1);
    const int nl = static_cast<int>(left.nodes.size()), first_right = static_cast<int>(left.order.size());
    out.nodes.reserve(1 + left.nodes.size() + right.nodes.size());
    out.nodes.emplace_back();
    for (Node nd : left.nodes) {
      if (nd.count == 0) {
        nd.left += 1;
        nd.right += 1;
      }
      out.nodes.push_back(nd);
    }
    for (Node nd : right.nodes) {
      if (nd.count == 0) {
        nd.left += 1 + nl;
        nd.right += 1 + nl;
      } else {
        nd.first += first_right;
      }
      out.nodes.push_back(nd);
    }
    Node& root = out.nodes[0];
    root.left = 1;
    root.right = 1 + nl;
    root.box = out.nodes[1].box;
    root.box.grow(out.nodes[1 + nl].box);
    root.centre = root.box.centre();
    root.half = 0.5 * root.box.extent();
    out.order = std::move(left.order);
    out.order.insert(out.order.end(), right.order.begin(), right.order.end());
    out.depth = std::max(left.depth, right.depth);
  } else {
    out.nodes.reserve(capacity);
    out.order.reserve(n);
    builder.build(0, n, out, 0);
  }
  nodes_ = std::move(out.nodes);
  depth_ = out.depth;
  if (depth_ + 2 > kStackSize) throw std::length_error("TriangleBvh: tree too deep for the traversal stack");
  const std::vector<int>& order = out.order;
  tris_.reserve(n);  // filled below, not zeroed first
  ids_ = order;
  planes_.resize(n);
  for (int i = 0; i < n; ++i) {
    const int f = order[i];
    tris_.push_back({Vec3(vertices.row(faces(f, 0)).transpose()), Vec3(vertices.row(faces(f, 1)).transpose()),
                     Vec3(vertices.row(faces(f, 2)).transpose())});
    const Vec3 nrm = (tris_[i][1] - tris_[i][0]).cross(tris_[i][2] - tris_[i][0]);
    const double len = nrm.norm();
    // A degenerate triangle gets no plane (normal 0): the plane test below never rejects it.
    const Vec3 unit = len > 0.0 ? Vec3(nrm / len) : Vec3::Zero();
    planes_[i] = Eigen::Vector4d(unit.x(), unit.y(), unit.z(), len > 0.0 ? unit.dot(tris_[i][0]) : 0.0);
  }
}

bool TriangleBvh::same_tree(const TriangleBvh& other) const {
  if (nodes_.size() != other.nodes_.size() || ids_ != other.ids_ || depth_ != other.depth_) return false;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node &x = nodes_[i], &y = other.nodes_[i];
    if (x.box.lo != y.box.lo || x.box.hi != y.box.hi || x.left != y.left || x.right != y.right ||
        x.first != y.first || x.count != y.count)
      return false;
  }
  return true;
}

namespace {

/// Lower bounds of the squared distance between segment [a, b] (a == b: a point) and boxes:
/// the distance to the segment's box, and where that is below `useful` (a bound that would not
/// prune the box), the gap between the projections of the segment and the box onto the
/// direction d from the segment's point nearest the box centre to that centre (any direction
/// gives a bound; this one is nearly the best; gap = num / |d|, no square root).
struct SegmentBound {
  Vec3 a, b, ab;
  double inv_len2 = 0.0;
  Aabb sbox;
  bool is_point;

  SegmentBound(const Vec3& a_, const Vec3& b_) : a(a_), b(b_), ab(b_ - a_), is_point(a_ == b_) {
    sbox.grow(a);
    sbox.grow(b);
    if (!is_point) inv_len2 = 1.0 / ab.squaredNorm();
  }
  /// `c` and `h`: the box's centre and half extent.
  double operator()(const Aabb& box, const Vec3& c, const Vec3& h, double useful) const {
    const double d_boxes = box.squared_distance(sbox);
    if (d_boxes >= useful || is_point) return d_boxes;  // for a point the box distance is exact
    const double t = std::clamp((c - a).dot(ab) * inv_len2, 0.0, 1.0);
    const Vec3 d = c - (a + t * ab);
    const double dc = d.dot(c), dh = d.cwiseAbs().dot(h), da = d.dot(a), dab = d.dot(ab);
    // Less a rounding margin: the bound must never exceed the true distance.
    const double slack = 1e-14 * (std::abs(dc) + dh + std::abs(da) + std::abs(dab));
    const double num = (dc - dh) - (dab > 0.0 ? da + dab : da) - slack;
    if (!(num > 0.0)) return d_boxes;
    return std::max(d_boxes, num * num / d.squaredNorm());
  }
};

/// A separating direction: every point x of the query has nu . x >= low. Anything whose
/// points all have nu . y <= h lies at least low - h from the query (projection onto a unit
/// vector never lengthens a distance). The direction of the closest pair of the nearest
/// triangle found so far is nearly the tangent plane's normal there: on convex stretches of O
/// it certifies almost every other triangle, and whole subtrees, as farther away at once.
struct Witness {
  Vec3 nu = Vec3::Zero();
  double low = 0.0;
  double from_sq = kInf;  ///< squared distance of the triangle it came from
  bool valid = false;

  void offer(const Vec3& a, const Vec3& b, const Vec3& on_query, const Vec3& on_mesh, double d_sq) {
    if (!(d_sq > 0.0) || d_sq >= from_sq) return;
    const Vec3 d = on_query - on_mesh;
    const double len = d.norm();
    if (!(len > 0.0)) return;
    nu = d / len;
    low = std::min(nu.dot(a), nu.dot(b));
    from_sq = d_sq;
    valid = true;
  }
  /// Lower bound of the distance from the query to anything whose nu-projection is <= high
  /// (a little rounding slack subtracted); -inf when there is no witness yet.
  double bound(double high) const {
    if (!valid) return -kInf;
    return (low - high) - 1e-14 * (std::abs(low) + std::abs(high));
  }
  /// For a box of centre c and half extent h.
  double box_bound(const Vec3& c, const Vec3& h) const {
    if (!valid) return -kInf;
    return bound(nu.dot(c) + nu.cwiseAbs().dot(h));
  }
  double triangle_bound(const std::array<Vec3, 3>& t) const {
    if (!valid) return -kInf;
    return bound(std::max(nu.dot(t[0]), std::max(nu.dot(t[1]), nu.dot(t[2]))));
  }
};

// Squared distance between the query (the point a when is_point, else the segment ab) and
// triangle t, with the closest points and the triangle feature that holds its point.
double closest_pair(const Vec3& a, const Vec3& b, bool is_point, const std::array<Vec3, 3>& t, Vec3* on_seg,
                    Vec3* on_tri, TriangleFeature* f) {
  if (!is_point) return segment_triangle_squared(a, b, t[0], t[1], t[2], on_seg, on_tri, f);
  *on_seg = a;
  *on_tri = closest_point_on_triangle(a, t[0], t[1], t[2], f);
  return (*on_tri - a).squaredNorm();
}

}  // namespace

NearestResult TriangleBvh::nearest(const Vec3& a, const Vec3& b, double max_distance) const {
  NearestResult best;
  // The squared distance of the nearest triangle so far (the search bound); -1 once touching.
  double best_sq = std::isfinite(max_distance) ? max_distance * max_distance : kInf;
  const SegmentBound node_bound(a, b);
  Witness w;
  // A node or triangle whose witness bound exceeds the best distance cannot hold the nearest.
  auto beyond = [&](double wb) { return wb > 0.0 && wb * wb > best_sq; };
  walk([&](const Node& n) { return node_bound(n.box, n.centre, n.half, best_sq); },
       [&](const Node& n) { return beyond(w.box_bound(n.centre, n.half)); },
       [&](int i) {
         const auto& t = tris_[i];
         if (beyond(w.triangle_bound(t))) return;
         Vec3 on_seg, on_tri;
         TriangleFeature f;
         const double d = closest_pair(a, b, node_bound.is_point, t, &on_seg, &on_tri, &f);
         // Exact ties go to the lowest input index: the answer does not depend on the tree's order.
         if (!(d < best_sq || (d == best_sq && (best.triangle < 0 || ids_[i] < best.triangle)))) return;
         best.on_query = on_seg;
         best.on_mesh = on_tri;
         best.triangle = ids_[i];
         best.feature = f;
         if (d == 0.0) {
           best.crosses = true;
           best_sq = -1.0;  // touching: nothing can be nearer; stop
           return;
         }
         best_sq = d;
         w.offer(a, b, on_seg, on_tri, d);
       },
       best_sq);
  if (best.crosses) {
    best.distance = best.squared_distance = 0.0;
  } else if (best.triangle >= 0) {
    best.squared_distance = best_sq;
    best.distance = std::sqrt(best_sq);
  }
  return best;
}

bool TriangleBvh::any_within(const Vec3& a, const Vec3& b, double distance) const {
  if (tris_.empty() || !(distance >= 0.0)) return false;
  const double bound_sq = distance * distance;
  const SegmentBound node_bound(a, b);
  Witness w;
  // A node can hold such a triangle only if its lower bound is below bound_sq (or 0 for a touch)
  // and the witness does not put it farther than `distance`; one that cannot gets bound +inf.
  double bound = bound_sq;  // set below 0 to stop once one is found
  bool found = false;
  walk(
      [&](const Node& n) {
        const double lb = node_bound(n.box, n.centre, n.half, bound_sq);
        return lb < bound_sq || lb == 0.0 ? lb : kInf;
      },
      [&](const Node& n) { return w.box_bound(n.centre, n.half) > distance; },
      [&](int i) {
        const auto& t = tris_[i];
        // Both ends farther than `distance` on one side of the triangle's plane: too far.
        const Eigen::Vector4d& pl = planes_[i];
        const double da = pl.x() * a.x() + pl.y() * a.y() + pl.z() * a.z() - pl.w();
        const double db = pl.x() * b.x() + pl.y() * b.y() + pl.z() * b.z() - pl.w();
        if ((da > distance && db > distance) || (da < -distance && db < -distance)) return;
        if (w.triangle_bound(t) > distance) return;
        Vec3 on_seg, on_tri;
        TriangleFeature f;
        const double d = closest_pair(a, b, node_bound.is_point, t, &on_seg, &on_tri, &f);
        if (d < bound_sq || d == 0.0) {
          found = true;
          bound = -1.0;
          return;
        }
        w.offer(a, b, on_seg, on_tri, d);
      },
      bound);
  return found;
}

int TriangleBvh::ray_crossings(const Vec3& origin, const Vec3& dir) const {
  if (tris_.empty()) return 0;
  const Vec3 inv = dir.cwiseInverse();
  int crossings = 0;
  int stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& nd = nodes_[stack[--top]];
    // slab test
    double t0 = 0.0, t1 = kInf;
    bool hit = true;
    for (int k = 0; k < 3 && hit; ++k) {
      double ta = (nd.box.lo[k] - origin[k]) * inv[k];
      double tb = (nd.box.hi[k] - origin[k]) * inv[k];
      if (std::isnan(ta) || std::isnan(tb)) {  // dir[k] == 0 and origin on the slab plane
        if (origin[k] < nd.box.lo[k] || origin[k] > nd.box.hi[k]) hit = false;
        continue;
      }
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) hit = false;
    }
    if (!hit) continue;
    if (nd.count > 0) {
      for (int i = nd.first; i < nd.first + nd.count; ++i) {
        const auto& t = tris_[i];
        const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
        const Vec3 h = dir.cross(e2);
        const double det = e1.dot(h);
        if (det == 0.0) continue;
        const double f = 1.0 / det;
        const Vec3 s = origin - t[0];
        const double u = f * s.dot(h);
        if (u < 0.0 || u > 1.0) continue;
        const Vec3 q = s.cross(e1);
        const double v = f * dir.dot(q);
        if (v < 0.0 || u + v > 1.0) continue;
        if (f * e2.dot(q) > 0.0) ++crossings;
      }
      continue;
    }
    if (top + 2 <= kStackSize) {
      stack[top++] = nd.left;
      stack[top++] = nd.right;
    }
  }
  return crossings;
}

}  // namespace hugger
