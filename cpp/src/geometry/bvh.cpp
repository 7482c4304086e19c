#include "hugger/geometry/bvh.hpp"

#include <algorithm>
#include <cmath>

namespace hugger {

TriangleBvh::TriangleBvh(const PointsN3& vertices, const FacesN3& faces, int leaf_size) {
  const int n = static_cast<int>(faces.rows());
  std::vector<Vec3> centroids(n);
  std::vector<Aabb> boxes(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) boxes[i].grow(Vec3(vertices.row(faces(i, k)).transpose()));
    centroids[i] = boxes[i].centre();
  }
  std::vector<int> ids(n), order;
  for (int i = 0; i < n; ++i) ids[i] = i;
  order.reserve(n);
  nodes_.reserve(2 * std::max(1, n / std::max(1, leaf_size)) + 1);
  build(ids, 0, n, centroids, boxes, std::max(1, leaf_size), order);
  tris_.resize(n);
  ids_ = order;
  for (int i = 0; i < n; ++i) {
    const int f = order[i];
    for (int k = 0; k < 3; ++k) tris_[i][k] = vertices.row(faces(f, k)).transpose();
  }
}

int TriangleBvh::build(std::vector<int>& ids, int begin, int end, const std::vector<Vec3>& centroids,
                       const std::vector<Aabb>& boxes, int leaf_size, std::vector<int>& order) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Aabb box, cbox;
  for (int i = begin; i < end; ++i) {
    box.grow(boxes[ids[i]]);
    cbox.grow(centroids[ids[i]]);
  }
  nodes_[index].box = box;
  if (end - begin <= leaf_size) {
    nodes_[index].first = static_cast<int>(order.size());
    nodes_[index].count = end - begin;
    for (int i = begin; i < end; ++i) order.push_back(ids[i]);
    return index;
  }
  int axis = 0;
  cbox.extent().maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(ids.begin() + begin, ids.begin() + mid, ids.begin() + end, [&](int x, int y) {
    return centroids[x][axis] < centroids[y][axis] || (centroids[x][axis] == centroids[y][axis] && x < y);
  });
  const int left = build(ids, begin, mid, centroids, boxes, leaf_size, order);
  const int right = build(ids, mid, end, centroids, boxes, leaf_size, order);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

namespace {

/// A lower bound of the squared distance between segment [a, b] (with box sbox) and a box.
inline double segment_box_lower_bound(const Vec3& a, const Vec3& b, const Aabb& sbox, const Aabb& box) {
  const double d_boxes = box.squared_distance(sbox);
  const Vec3 c = box.centre();
  const double half_diag = 0.5 * box.extent().norm();
  const double dc = (closest_point_on_segment(c, a, b) - c).norm() - half_diag;
  return dc > 0.0 ? std::max(d_boxes, dc * dc) : d_boxes;
}

}  // namespace

NearestResult TriangleBvh::nearest(const Vec3& a, const Vec3& b, double max_distance) const {
  NearestResult best;
  if (tris_.empty()) return best;
  double best_sq = std::isfinite(max_distance) ? max_distance * max_distance : kInf;
  Aabb sbox;
  sbox.grow(a);
  sbox.grow(b);
  const bool is_point = (a - b).squaredNorm() == 0.0;
  struct Item {
    int node;
    double lb;
  };
  Item stack[128];
  int top = 0;
  stack[top++] = {0, segment_box_lower_bound(a, b, sbox, nodes_[0].box)};
  while (top > 0) {
    const Item it = stack[--top];
    if (it.lb > best_sq || (best.triangle >= 0 && it.lb == best_sq)) continue;
    const Node& nd = nodes_[it.node];
    if (nd.count > 0) {
      for (int i = nd.first; i < nd.first + nd.count; ++i) {
        const auto& t = tris_[i];
        Vec3 on_seg, on_tri;
        TriangleFeature f;
        double d;
        if (is_point) {
          on_seg = a;
          on_tri = closest_point_on_triangle(a, t[0], t[1], t[2], &f);
          d = (on_tri - a).squaredNorm();
        } else {
          d = segment_triangle_squared(a, b, t[0], t[1], t[2], &on_seg, &on_tri, &f);
        }
        if (d < best_sq || (best.triangle < 0 && d <= best_sq)) {
          best_sq = d;
          best.on_query = on_seg;
          best.on_mesh = on_tri;
          best.triangle = ids_[i];
          best.feature = f;
          if (d == 0.0) {
            best.distance = 0.0;
            best.crosses = true;
            return best;
          }
        }
      }
      continue;
    }
    const double ll = segment_box_lower_bound(a, b, sbox, nodes_[nd.left].box);
    const double lr = segment_box_lower_bound(a, b, sbox, nodes_[nd.right].box);
    if (top + 2 > 128) continue;  // cannot happen for a median-split tree of < 2^60 triangles
    if (ll < lr) {
      stack[top++] = {nd.right, lr};
      stack[top++] = {nd.left, ll};
    } else {
      stack[top++] = {nd.left, ll};
      stack[top++] = {nd.right, lr};
    }
  }
  if (best.triangle >= 0) best.distance = std::sqrt(best_sq);
  return best;
}

int TriangleBvh::ray_crossings(const Vec3& origin, const Vec3& dir) const {
  if (tris_.empty()) return 0;
  const Vec3 inv = dir.cwiseInverse();
  int crossings = 0;
  int stack[128];
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
    if (top + 2 <= 128) {
      stack[top++] = nd.left;
      stack[top++] = nd.right;
    }
  }
  return crossings;
}

}  // namespace hugger
