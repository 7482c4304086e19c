/// \file distance.hpp
/// Exact closest-point primitives in 2D and 3D (after Ericson, "Real-Time Collision
/// Detection", ch. 5). All distances are Euclidean, in the units of the inputs.
#pragma once

#include "hugger/types.hpp"

namespace hugger {

/// Which feature of a triangle (a, b, c) a closest point lies on.
enum class TriangleFeature : std::uint8_t { kFace, kEdgeAB, kEdgeBC, kEdgeCA, kVertexA, kVertexB, kVertexC };

/// Closest point of triangle (a, b, c) to p, and the feature it lies on.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               TriangleFeature* feature = nullptr);

/// Closest point of segment [a, b] to p; `t` in [0, 1] is its parameter.
template <class V>
V closest_point_on_segment(const V& p, const V& a, const V& b, double* t = nullptr) {
  const V ab = b - a;
  const double len2 = ab.squaredNorm();
  double s = len2 > 0.0 ? (p - a).dot(ab) / len2 : 0.0;
  s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
  if (t) *t = s;
  return a + s * ab;
}

/// Squared distance between segments [p1, q1] and [p2, q2]; c1 and c2 receive the closest points.
double segment_segment_squared(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3* c1 = nullptr,
                               Vec3* c2 = nullptr);
double segment_segment_squared_2d(const Vec2& p1, const Vec2& q1, const Vec2& p2, const Vec2& q2);

/// True when segment [p, q] crosses or touches triangle (a, b, c); `at` receives the crossing.
bool segment_intersects_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                                 Vec3* at = nullptr);

/// Squared distance between segment [p, q] and triangle (a, b, c); on_seg and on_tri receive the
/// closest points (on_tri also its feature).
double segment_triangle_squared(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                                Vec3* on_seg, Vec3* on_tri, TriangleFeature* feature);

}  // namespace hugger
