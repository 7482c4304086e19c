/// \file object.hpp
/// The object O: a closed, consistently oriented triangle mesh in the world frame, with
/// the acceleration structures the simulated world answers sensing queries from.
#pragma once

#include <memory>
#include <vector>

#include "hugger/geometry/bvh.hpp"
#include "hugger/geometry/section.hpp"
#include "hugger/types.hpp"

namespace hugger {

/// Signed nearest-feature result: distance < 0 when the query lies inside O.
struct SignedNearest {
  double signed_distance = kInf;  ///< metres; > 0 outside O, < 0 inside (FCL's sign convention)
  Vec3 on_query = Vec3::Zero();   ///< closest point of the query
  Vec3 on_object = Vec3::Zero();  ///< closest point of O's surface
  int triangle = -1;              ///< triangle of O holding on_object (-1: nothing within the bound)
  bool crosses = false;           ///< a segment query crosses O's surface (its depth is not measured)
};

class Object {
 public:
  /// Validates and builds. Throws std::invalid_argument naming what is wrong: empty arrays,
  /// non-finite vertices, indices out of range, degenerate faces (a repeated index, or zero
  /// area: twice the area at most 1e-12 of the longest edge squared), a mesh that is not closed,
  /// not consistently oriented or not manifold (at an edge or a vertex), the same triangle twice
  /// over coincident vertices, or one whose normals point inward. The arrays are kept: moved in
  /// when given as temporaries (no copy), copied otherwise.
  Object(PointsN3 vertices, FacesN3 faces);

  const PointsN3& vertices() const { return vertices_; }
  /// Unit outward normal of face f (zero for a degenerate face).
  const Vec3& face_normal(std::int64_t f) const { return face_normals_[static_cast<std::size_t>(f)]; }
  const FacesN3& faces() const { return faces_; }
  const Aabb& bounds() const { return bvh_.bounds(); }
  double volume() const { return volume_; }

  /// Signed distance query for segment [a, b] (a == b: a point). Features farther than
  /// `max_distance` may be skipped (then signed_distance is +inf or -inf).
  SignedNearest nearest(const Vec3& a, const Vec3& b, double max_distance = kInf) const;
  /// True when p is strictly inside O (the sign of its nearest feature's pseudo-normal).
  bool inside(const Vec3& p) const;
  /// True when p, known to be at a positive distance from O's surface, is inside O: ray parity,
  /// majority of three rays. Much cheaper than inside() for points far from the surface.
  bool inside_off_surface(const Vec3& p) const;
  /// True when the capsule of axis [a, b] and `radius` neither comes closer than `radius` to O's
  /// surface (touching counts as clear only at exactly `radius`) nor lies inside O.
  /// `a_outside`: a is known to lie outside O, and the inside test is skipped.
  bool capsule_clear(const Vec3& a, const Vec3& b, double radius, bool a_outside = false) const;
  /// The planar section of O in the plane through `origin` spanned by orthonormal u, v
  /// (std::invalid_argument otherwise).
  Section section(const Vec3& origin, const Vec3& u, const Vec3& v) const;
  /// The BVH over O's triangles (world frame), for custom queries.
  const TriangleBvh& bvh() const { return bvh_; }
  /// The face across edge k of face f (edge k runs from corner k to corner k + 1).
  std::int64_t face_neighbor(std::int64_t f, int k) const { return neighbors_[static_cast<std::size_t>(f)][k]; }
  /// Angle-weighted pseudo-normal of vertex v (not normalised).
  const Vec3& vertex_normal(std::int64_t v) const { return vertex_normals_[static_cast<std::size_t>(v)]; }
  /// The vertices joined to vertex v by an edge (its one-ring), in no particular order.
  const std::int64_t* ring_begin(std::int64_t v) const { return ring_.data() + ring_start_[static_cast<std::size_t>(v)]; }
  const std::int64_t* ring_end(std::int64_t v) const { return ring_.data() + ring_start_[static_cast<std::size_t>(v) + 1]; }
  /// A number unique to this object among all objects built by this process.
  std::uint64_t serial() const { return serial_; }

 private:
  /// Face and vertex normals, volume, face adjacency and one-rings, and every check of the mesh
  /// past its indices (the constructor's list).
  void build_surface();
  bool inside_by_rays(const Vec3& p) const;
  /// p lies outside O's bounding box (so outside O).
  bool beyond_bounds(const Vec3& p) const;
  double sign_at(const Vec3& query, const Vec3& on_mesh, int triangle, TriangleFeature f) const;

  PointsN3 vertices_;
  FacesN3 faces_;
  TriangleBvh bvh_;
  std::vector<Vec3> face_normals_;            ///< unit (zero for degenerate faces)
  std::vector<Vec3> vertex_normals_;          ///< angle-weighted pseudo-normals
  std::vector<std::array<std::int64_t, 3>> neighbors_;  ///< per face, the face across edges ab, bc, ca
  std::vector<std::int64_t> ring_start_, ring_;          ///< per vertex, its one-ring (compressed rows)
  double volume_ = 0.0;
  std::uint64_t serial_ = 0;  ///< unique per constructed object (keys per-thread memos)
};

/// The planner's target T for object O: finite and strictly inside O (signed distance < 0).
/// Throws std::invalid_argument saying where T is otherwise.
void check_target(const Object& object, const Vec3& target);

}  // namespace hugger
