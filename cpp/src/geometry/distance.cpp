#include "hugger/geometry/distance.hpp"

#include <algorithm>

namespace hugger {

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               TriangleFeature* feature) {
  auto set = [feature](TriangleFeature f) {
    if (feature) *feature = f;
  };
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return set(TriangleFeature::kVertexA), a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return set(TriangleFeature::kVertexB), b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return set(TriangleFeature::kEdgeAB), Vec3(a + v * ab);
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return set(TriangleFeature::kVertexC), c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return set(TriangleFeature::kEdgeCA), Vec3(a + w * ac);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return set(TriangleFeature::kEdgeBC), Vec3(b + w * (c - b));
  }
  const double denom = va + vb + vc;
  if (!(denom > 0.0)) {  // degenerate triangle: fall back to its longest edge
    Vec3 best = closest_point_on_segment(p, a, b);
    TriangleFeature f = TriangleFeature::kEdgeAB;
    for (auto [s, e, g] : {std::make_tuple(b, c, TriangleFeature::kEdgeBC), std::make_tuple(c, a, TriangleFeature::kEdgeCA)}) {
      const Vec3 q = closest_point_on_segment(p, s, e);
      if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q, f = g;
    }
    return set(f), best;
  }
  const double v = vb / denom, w = vc / denom;
  return set(TriangleFeature::kFace), Vec3(a + ab * v + ac * w);
}

namespace {

template <class V>
double segment_segment_impl(const V& p1, const V& q1, const V& p2, const V& q2, V* c1, V* c2) {
  const V d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double kEps = 1e-300;
  double s = 0.0, t = 0.0;
  if (a <= kEps && e <= kEps) {
    s = t = 0.0;
  } else if (a <= kEps) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kEps) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  const V x1 = p1 + d1 * s, x2 = p2 + d2 * t;
  if (c1) *c1 = x1;
  if (c2) *c2 = x2;
  return (x1 - x2).squaredNorm();
}

}  // namespace

double segment_segment_squared(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3* c1, Vec3* c2) {
  return segment_segment_impl<Vec3>(p1, q1, p2, q2, c1, c2);
}

double segment_segment_squared_2d(const Vec2& p1, const Vec2& q1, const Vec2& p2, const Vec2& q2) {
  return segment_segment_impl<Vec2>(p1, q1, p2, q2, nullptr, nullptr);
}

bool segment_intersects_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                                 Vec3* at) {
  // Moller-Trumbore on the segment's parameter range [0, 1].
  const Vec3 dir = q - p, e1 = b - a, e2 = c - a;
  const Vec3 h = dir.cross(e2);
  const double det = e1.dot(h);
  const double scale = e1.norm() * e2.norm() * dir.norm();
  if (std::abs(det) <= 1e-14 * scale) return false;  // parallel: the edge tests catch a touch
  const double inv = 1.0 / det;
  const Vec3 s = p - a;
  const double u = inv * s.dot(h);
  if (u < 0.0 || u > 1.0) return false;
  const Vec3 qv = s.cross(e1);
  const double v = inv * dir.dot(qv);
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = inv * e2.dot(qv);
  if (t < 0.0 || t > 1.0) return false;
  if (at) *at = p + t * dir;
  return true;
}

double segment_triangle_squared(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                                Vec3* on_seg, Vec3* on_tri, TriangleFeature* feature) {
  Vec3 x;
  if (segment_intersects_triangle(p, q, a, b, c, &x)) {
    *on_seg = x;
    *on_tri = x;
    *feature = TriangleFeature::kFace;
    return 0.0;
  }
  double best = kInf;
  auto consider_point = [&](const Vec3& s) {
    TriangleFeature f;
    const Vec3 t = closest_point_on_triangle(s, a, b, c, &f);
    const double d = (t - s).squaredNorm();
    if (d < best) best = d, *on_seg = s, *on_tri = t, *feature = f;
  };
  consider_point(p);
  consider_point(q);
  const Vec3* v[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    Vec3 cs, ct;
    const double d = segment_segment_squared(p, q, *v[i], *v[(i + 1) % 3], &cs, &ct);
    if (d < best) {
      best = d;
      *on_seg = cs;
      // Classify the triangle feature of the edge point exactly as the point query would.
      *on_tri = closest_point_on_triangle(cs, a, b, c, feature);
      best = (*on_tri - cs).squaredNorm();
    }
  }
  return best;
}

}  // namespace hugger
