/// \file bvh.hpp
/// An axis-aligned bounding-volume hierarchy over a triangle soup, answering exact
/// nearest-feature queries for points and segments, and ray-crossing counts.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hugger/geometry/distance.hpp"
#include "hugger/types.hpp"

namespace hugger {

struct Aabb {
  Vec3 lo = Vec3::Constant(kInf);
  Vec3 hi = Vec3::Constant(-kInf);
  void grow(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void grow(const Aabb& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  Vec3 centre() const { return 0.5 * (lo + hi); }
  Vec3 extent() const { return hi - lo; }
  /// Squared distance from p to the box (0 inside).
  double squared_distance(const Vec3& p) const {
    return (lo - p).cwiseMax(p - hi).cwiseMax(0.0).squaredNorm();
  }
  /// Squared distance between two boxes (0 when they overlap).
  double squared_distance(const Aabb& b) const {
    return (lo - b.hi).cwiseMax(b.lo - hi).cwiseMax(0.0).squaredNorm();
  }
};

/// Result of a nearest-feature query: which triangle, which feature of it, both points.
struct NearestResult {
  double distance = kInf;  ///< Euclidean distance (>= 0); 0 when the query touches or crosses the mesh
  double squared_distance = kInf;  ///< its square as computed (distance is its square root)
  Vec3 on_query = Vec3::Zero();  ///< closest point of the query primitive
  Vec3 on_mesh = Vec3::Zero();   ///< closest point of the mesh
  int triangle = -1;             ///< index of the triangle in the input faces (-1: nothing within the bound)
  TriangleFeature feature = TriangleFeature::kFace;
  bool crosses = false;  ///< the query segment crosses (or touches) a triangle
};

class TriangleBvh {
 public:
  TriangleBvh() = default;
  /// Ranges of at most this many triangles are presorted while building (below).
  static constexpr int kPresorted = 1 << 15;

  /// Builds over triangles `faces` of `vertices` (indices already validated). `presorted`:
  /// ranges of at most this many triangles are split by sorted lists, larger ones by selection.
  /// `threads`: 1 builds on this thread; 2 or more builds the root's two halves side by side
  /// when the root is split by selection (more than `presorted` triangles); 0 chooses two where
  /// the hardware has two threads. The tree is the same whatever the choices: they trade speed
  /// alone.
  TriangleBvh(const PointsN3& vertices, const FacesN3& faces, int leaf_size = 8, int threads = 0,
              int presorted = kPresorted);

  /// Nearest mesh point to segment [a, b] (a == b: a point query). Triangles farther than
  /// `max_distance` may be skipped; then `triangle` is -1 and `distance` is infinite.
  NearestResult nearest(const Vec3& a, const Vec3& b, double max_distance = kInf) const;

  /// True when some triangle comes closer than `distance` to segment [a, b] (a == b: a point),
  /// or touches or crosses it. Stops at the first such triangle: cheaper than nearest().
  bool any_within(const Vec3& a, const Vec3& b, double distance) const;

  /// Number of triangles crossed by the ray origin + t * dir, t > 0.
  int ray_crossings(const Vec3& origin, const Vec3& dir) const;

  /// Best-first traversal for custom queries. Visits every triangle of every node whose
  /// `node_bound(box)` is at most `bound`; `leaf(triangle, index)` may lower `bound` (for a
  /// nearest-style search) or set it below 0 to stop.
  template <class NodeBound, class Leaf>
  void traverse(NodeBound&& node_bound, Leaf&& leaf, double& bound) const {
    walk([&](const Node& n) { return node_bound(n.box); }, [](const Node&) { return false; },
         [&](int i) { leaf(tris_[i], ids_[i]); }, bound);
  }

  /// True when `other` is the same tree: the same nodes (boxes, children, leaf ranges) and the
  /// triangles in the same leaf order.
  bool same_tree(const TriangleBvh& other) const;

  const Aabb& bounds() const { return nodes_.front().box; }
  std::size_t size() const { return tris_.size(); }

 private:
  /// The best-first traversal every query shares. Children are visited nearer first by
  /// `node_bound(node)` (computed when pushed); a node is skipped when that bound exceeds `bound`,
  /// or when `skip(node)` says so as it is popped (a test that may have sharpened meanwhile);
  /// `leaf(i)` sees tris_[i] and may lower `bound`, or set it below 0 to stop.
  template <class NodeBound, class Skip, class Leaf>
  void walk(NodeBound&& node_bound, Skip&& skip, Leaf&& leaf, double& bound) const {
    if (tris_.empty()) return;
    struct Item {
      int node;
      double lb;
    };
    Item stack[kStackSize];
    int top = 0;
    stack[top++] = {0, node_bound(nodes_[0])};
    while (top > 0) {
      const Item it = stack[--top];
      if (it.lb > bound) continue;
      const Node& nd = nodes_[it.node];
      if (skip(nd)) continue;
      if (nd.count > 0) {
        for (int i = nd.first; i < nd.first + nd.count && bound >= 0.0; ++i) leaf(i);
        if (bound < 0.0) return;
        continue;
      }
      const double ll = node_bound(nodes_[nd.left]), lr = node_bound(nodes_[nd.right]);
      if (top + 2 > kStackSize) continue;  // unreachable: the depth is checked when built
      if (ll < lr) {  // nearer child last, so that it is visited first
        stack[top++] = {nd.right, lr};
        stack[top++] = {nd.left, ll};
      } else {
        stack[top++] = {nd.left, ll};
        stack[top++] = {nd.right, lr};
      }
    }
  }

  struct Node {
    Aabb box;
    Vec3 centre, half;  ///< box.centre() and box.extent() / 2, kept for the traversals' bounds
    int left = -1, right = -1;  ///< children (internal node)
    int first = 0, count = 0;   ///< range in tris_ (leaf when count > 0)
  };
  /// Where a build writes: its nodes (children by index into `nodes`), the triangles of its
  /// leaves in leaf order, and the deepest level reached.
  struct BuildOut {
    std::vector<Node> nodes;
    std::vector<int> order;
    int depth = 0;
  };
  /// A triangle while building: its box's centre and its index (kept together, contiguous).
  struct BuildItem {
    double c[3];
    int id;
  };
  /// Every split is about the median of a node's triangles along the longest axis of their
  /// centres' box, by (centre, index): a strict total order, so the halves do not depend on how
  /// they are found. A range of more than `presorted` triangles is split in place by selection
  /// (nth_element: its memory is read in order); a smaller one is sorted once along each axis,
  /// then each split keeps the halves' lists in order by a stable partition (linear per level,
  /// without the mispredicted comparisons of a selection per node). A leaf's triangles are in
  /// (centre along x, index) order either way.
  struct Builder {
    const PointsN3& vertices;
    const FacesN3& faces;
    std::vector<BuildItem> items;  ///< empty when the root's range is presorted
    int leaf_size = 1, presorted = kPresorted;

    Builder(const PointsN3& vertices, const FacesN3& faces, int leaf_size, int presorted);
    /// Triangle t's bounding box.
    Aabb box(int t) const;
    /// Orders items [begin, end) about their median; returns the middle.
    int split(int begin, int end);
    /// Builds the subtree of items [begin, end) at `depth` into `out`; returns its root's index.
    int build(int begin, int end, BuildOut& out, int depth);
  };
  /// The triangles of one range, presorted: their indices `ids` in increasing order, their
  /// centres and per axis their positions in `ids` in (centre along the axis, index) order; each
  /// node's triangles a range of all three lists.
  struct Presorted {
    const Builder& builder;
    std::vector<int> ids;
    std::array<std::vector<double>, 3> centres;  ///< per axis
    std::array<std::vector<int>, 3> sorted;
    std::vector<int> scratch;          ///< partition space, the same ranges as `sorted`
    std::vector<char> lower;           ///< per triangle: in the lower half of the last split

    Presorted(const Builder& builder, std::vector<int> ids, std::array<std::vector<double>, 3> centres);
    int split(int begin, int end);
    int build(int begin, int end, BuildOut& out, int depth);
  };

  /// Traversal stacks hold at most depth + 1 entries; the constructor checks the depth (a
  /// median split gives about log2(F / leaf_size), 18 at 1.3M triangles).
  static constexpr int kStackSize = 128;
  int depth_ = 0;

  std::vector<Node> nodes_;
  std::vector<std::array<Vec3, 3>> tris_;  ///< triangles in leaf order
  std::vector<Eigen::Vector4d> planes_;    ///< per triangle in tris_: unit normal and offset (0 if degenerate)
  std::vector<int> ids_;                   ///< input index of each triangle in tris_
};

}  // namespace hugger
