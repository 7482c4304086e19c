#include "hugger/world/object.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <future>
#include <system_error>
#include <unordered_map>
#include <utility>

#include "hugger/check.hpp"
#include "hugger/geometry/frame.hpp"
#include "hugger/geometry/next.hpp"

namespace hugger {

namespace {

std::uint64_t edge_key(std::int64_t a, std::int64_t b) {
  return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint64_t>(b);
}

}  // namespace

namespace {
std::atomic<std::uint64_t> next_serial{1};

/// Meshes at least this large build their surface (normals, adjacency, checks) on a second
/// thread beside the BVH (a smaller one builds in less time than a thread takes to start).
constexpr std::int64_t kConcurrentSurface = 4096;

/// A directed edge leaving a vertex: its other end and the face holding it.
struct OutEdge {
  std::int32_t to, face;
};

/// A face's area is zero (coincident or collinear vertices) when twice its area is at most this
/// times its longest edge squared (a sliver whose height is 1e-12 of its length: its normal is
/// numerical noise).
constexpr double kDegenerateArea = 1e-12;

/// The checks beyond closed, oriented and positive volume, on a mesh that passed those: no
/// degenerate (zero-area) face, no triangle twice over distinct but coincident vertices, no
/// vertex where the surface touches itself (a non-manifold vertex: more than one fan of faces).
/// `row` and `out`: each vertex's outgoing directed edges, sorted by their other end; `neighbors`:
/// per face, the faces across its edges.
void check_surface(const PointsN3& V, const FacesN3& F, const std::vector<std::int64_t>& row,
                   const std::vector<OutEdge>& out, const std::vector<std::array<std::int64_t, 3>>& neighbors) {
  const std::int64_t nv = V.rows(), nf = F.rows();
  // Edges taken about the bounding box's centre: far from the origin raw coordinates lose digits.
  const Vec3 centre = 0.5 * (V.colwise().minCoeff() + V.colwise().maxCoeff()).transpose();
  std::int64_t flat = 0, first_flat = -1;
  for (std::int64_t f = 0; f < nf; ++f) {
    const Vec3 a = V.row(F(f, 0)).transpose() - centre, b = V.row(F(f, 1)).transpose() - centre,
               c = V.row(F(f, 2)).transpose() - centre;
    const Vec3 ab = b - a, bc = c - b, ca = a - c;
    const double twice_area = ab.cross(ca).norm();
    const double longest = std::max({ab.squaredNorm(), bc.squaredNorm(), ca.squaredNorm()});
    if (twice_area <= kDegenerateArea * longest) {
      if (first_flat < 0) first_flat = f;
      ++flat;
    }
  }
  HUGGER_CHECK_ARGUMENT(first_flat < 0, "object face " << first_flat << " [" << F(first_flat, 0) << ", "
                                                       << F(first_flat, 1) << ", " << F(first_flat, 2)
                                                       << "] is degenerate: zero area (its vertices are coincident "
                                                          "or collinear); "
                                                       << flat << " such face(s)");
  // Duplicate triangles: the same three positions, whatever the vertex indices and orientation.
  // Possible where distinct vertices coincide, or over the same three vertices; then faces are
  // compared by their sorted position triples.
  // Do two distinct vertices coincide? An open-addressing hash of the positions' bits (+ 0.0
  // makes -0 equal to 0): linear in the mesh.
  auto bits = [&](std::int64_t i, int k) { return bits_of(V(i, k) + 0.0); };
  std::size_t capacity = 16;
  while (capacity < 2 * static_cast<std::size_t>(nv)) capacity *= 2;
  std::vector<std::int64_t> table(capacity, -1);
  bool coincide = false;  // (or the same three vertices twice: below)
  for (std::int64_t i = 0; i < nv && !coincide; ++i) {
    std::uint64_t h = bits(i, 0) * 0x9E3779B97F4A7C15ull;
    h ^= (bits(i, 1) + (h << 6) + (h >> 2)) * 0xC2B2AE3D27D4EB4Full;
    h ^= (bits(i, 2) + (h << 6) + (h >> 2)) * 0x165667B19E3779F9ull;
    for (std::size_t slot = (h ^ (h >> 29)) & (capacity - 1);; slot = (slot + 1) & (capacity - 1)) {
      const std::int64_t j = table[slot];
      if (j < 0) {
        table[slot] = i;
        break;
      }
      if (bits(i, 0) == bits(j, 0) && bits(i, 1) == bits(j, 1) && bits(i, 2) == bits(j, 2)) {
        coincide = true;
        break;
      }
    }
  }
  // Or the same three vertices twice, in opposite turns (a zero-volume pillow, closed and
  // oriented): then the face across a face's first edge holds its three vertices.
  for (std::int64_t f = 0; f < nf && !coincide; ++f) {
    const std::int64_t g = neighbors[f][0], third = F(f, 2);
    coincide = F(g, 0) == third || F(g, 1) == third || F(g, 2) == third;
  }
  if (coincide) {
    // Vertices sorted by position, each given the index of its position.
    struct Position {
      double x, y, z;
      std::int64_t i;
      bool operator<(const Position& o) const {
        return x < o.x || (x == o.x && (y < o.y || (y == o.y && (z < o.z || (z == o.z && i < o.i)))));
      }
      bool same(const Position& o) const { return x == o.x && y == o.y && z == o.z; }
    };
    std::vector<Position> by_position(static_cast<std::size_t>(nv));
    for (std::int64_t i = 0; i < nv; ++i) by_position[i] = {V(i, 0) + 0.0, V(i, 1) + 0.0, V(i, 2) + 0.0, i};
    std::sort(by_position.begin(), by_position.end());
    std::vector<std::int64_t> place(static_cast<std::size_t>(nv));
    std::int64_t id = 0;
    for (std::int64_t k = 0; k < nv; ++k) {
      if (k > 0 && !by_position[k].same(by_position[k - 1])) ++id;
      place[by_position[k].i] = id;
    }
    std::vector<std::array<std::int64_t, 4>> keys(static_cast<std::size_t>(nf));
    for (std::int64_t f = 0; f < nf; ++f) {
      std::array<std::int64_t, 3> k3 = {place[F(f, 0)], place[F(f, 1)], place[F(f, 2)]};
      std::sort(k3.begin(), k3.end());
      keys[f] = {k3[0], k3[1], k3[2], f};
    }
    std::sort(keys.begin(), keys.end());
    for (std::size_t k = 1; k < keys.size(); ++k)
      HUGGER_CHECK_ARGUMENT(!(keys[k][0] == keys[k - 1][0] && keys[k][1] == keys[k - 1][1] && keys[k][2] == keys[k - 1][2]),
                            "object faces " << keys[k - 1][3] << " and " << keys[k][3]
                                            << " are the same triangle (duplicate faces over coincident vertices)");
  }
  // Non-manifold vertices: around a vertex v the corners of its faces chain into cycles (from
  // the corner at v of face f, whose edges leave v along k and arrive along k + 2, the next is
  // the corner at v of the face across edge k + 2); a manifold vertex has one cycle.
  auto next_face = [&](std::int64_t f, std::int64_t v) {
    const int corner = F(f, 0) == v ? 0 : (F(f, 1) == v ? 1 : 2);
    return neighbors[f][(corner + 2) % 3];
  };
  for (std::int64_t v = 0; v < nv; ++v) {
    const std::int64_t degree = row[v + 1] - row[v];
    if (degree == 0) continue;
    const std::int64_t start = out[row[v]].face;
    std::int64_t f = start, steps = 0;
    do {
      f = next_face(f, v);
      ++steps;
    } while (f != start && steps <= degree);
    if (steps == degree) continue;
    // How many fans: the cycles among the vertex's faces (its outgoing edges, in order).
    std::vector<char> seen(static_cast<std::size_t>(degree), 0);
    auto slot = [&](std::int64_t face) {
      for (std::int64_t e = row[v]; e < row[v + 1]; ++e)
        if (out[e].face == face) return e - row[v];
      return std::int64_t{0};
    };
    std::int64_t fans = 0;
    for (std::int64_t s = 0; s < degree; ++s) {
      if (seen[s]) continue;
      ++fans;
      for (std::int64_t e = s; !seen[e]; e = slot(next_face(out[row[v] + e].face, v))) seen[e] = 1;
    }
    HUGGER_CHECK_ARGUMENT(false, "object mesh is not manifold at vertex "
                                     << v << ": " << fans
                                     << " separate fans of faces meet there (the surface touches itself at a point)");
  }
}

/// Each vertex's angle-weighted pseudo-normal (not normalised): the sum over its faces of the
/// face's unit normal times the face's angle at the vertex.
std::vector<Vec3> angle_weighted_normals(const PointsN3& V, const FacesN3& F, const std::vector<Vec3>& face_normals) {
  std::vector<Vec3> normals(static_cast<std::size_t>(V.rows()), Vec3::Zero());
  for (std::int64_t f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = V.row(F(f, k)), q = V.row(F(f, (k + 1) % 3)), r = V.row(F(f, (k + 2) % 3));
      const Vec3 e1 = q - p, e2 = r - p;
      const double l1 = e1.norm(), l2 = e2.norm();
      if (l1 > 0 && l2 > 0) {
        const double angle = std::acos(std::clamp(e1.dot(e2) / (l1 * l2), -1.0, 1.0));
        normals[F(f, k)] += angle * face_normals[f];
      }
    }
  return normals;
}

}  // namespace

Object::Object(PointsN3 vertices, FacesN3 faces)
    : vertices_(std::move(vertices)), faces_(std::move(faces)), serial_(next_serial.fetch_add(1)) {
  const std::int64_t nv = vertices_.rows(), nf = faces_.rows();
  HUGGER_CHECK_ARGUMENT(nv != 0 && nf != 0, "object mesh is empty: it needs vertices (V,3) and faces (F,3), got V="
                                                 << nv << ", F=" << nf);
  HUGGER_CHECK_ARGUMENT(nv < (std::int64_t(1) << 31), "object mesh has too many vertices");
  HUGGER_CHECK_ARGUMENT(nf < (std::int64_t(1) << 31), "object mesh has too many faces");
  for (std::int64_t i = 0; i < nv; ++i)
    HUGGER_CHECK_ARGUMENT(vertices_.row(i).allFinite(), "object vertex " << i << " is not finite (" << vertices_(i, 0)
                                                                         << ", " << vertices_(i, 1) << ", "
                                                                         << vertices_(i, 2) << ")");
  for (std::int64_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k)
      HUGGER_CHECK_ARGUMENT(faces_(f, k) >= 0 && faces_(f, k) < nv,
                            "object face " << f << " indexes vertex " << faces_(f, k) << ", outside 0.." << nv - 1);
    HUGGER_CHECK_ARGUMENT(faces_(f, 0) != faces_(f, 1) && faces_(f, 1) != faces_(f, 2) && faces_(f, 2) != faces_(f, 0),
                          "object face " << f << " repeats a vertex (degenerate triangle)");
  }
  // The BVH needs only valid indices; a large mesh's surface (normals, adjacency and the checks
  // below) is built on a second thread beside it (the same results on any number of threads).
  // A check that fails there is rethrown here once the BVH is built; should the BVH throw, the
  // future's destructor waits for the other thread first.
  std::future<void> surface;
  if (nf >= kConcurrentSurface) {
    try {
      surface = std::async(std::launch::async, [this] { build_surface(); });
    } catch (const std::system_error&) {  // no thread to be had: built below, on this one
    }
  }
  bvh_ = TriangleBvh(vertices_, faces_, 8, 1);
  if (surface.valid())
    surface.get();
  else
    build_surface();
}

void Object::build_surface() {
  const std::int64_t nv = vertices_.rows(), nf = faces_.rows();
  // Unit face normals and the volume, a sum of tetrahedra on a reference point inside the
  // bounding box (taken about the origin, the terms of an object far from it are huge and cancel
  // to rounding noise). Its sign is checked below, after the checks that come before it.
  face_normals_.resize(nf);
  const Vec3 ref = 0.5 * (vertices_.colwise().minCoeff() + vertices_.colwise().maxCoeff()).transpose();
  for (std::int64_t f = 0; f < nf; ++f) {
    const Vec3 a = vertices_.row(faces_(f, 0)), b = vertices_.row(faces_(f, 1)), c = vertices_.row(faces_(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    volume_ += (a - ref).dot((b - ref).cross(c - ref)) / 6.0;
    const double len = n.norm();
    face_normals_[f] = len > 0.0 ? Vec3(n / len) : Vec3::Zero();
  }
  // Closed and consistently oriented: every directed edge once, and its reverse once. The
  // directed edges leaving each vertex, sorted by their other end (compressed rows: linear in
  // the mesh, no hash table).
  std::vector<std::int64_t> row(static_cast<std::size_t>(nv) + 1, 0);
  for (std::int64_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++row[static_cast<std::size_t>(faces_(f, k)) + 1];
  for (std::int64_t i = 0; i < nv; ++i) row[i + 1] += row[i];
  std::vector<OutEdge> out(static_cast<std::size_t>(3 * nf));
  {
    std::vector<std::int64_t> fill(row.begin(), row.end() - 1);
    for (std::int64_t f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k)
        out[fill[faces_(f, k)]++] = {static_cast<std::int32_t>(faces_(f, (k + 1) % 3)), static_cast<std::int32_t>(f)};
  }
  const auto by_end = [](const OutEdge& x, const OutEdge& y) { return x.to < y.to || (x.to == y.to && x.face < y.face); };
  for (std::int64_t a = 0; a < nv; ++a) {
    const auto first = out.begin() + row[a], last = out.begin() + row[a + 1];
    std::sort(first, last, by_end);
    for (auto it = first; it + 1 < last; ++it)
      HUGGER_CHECK_ARGUMENT(it->to != (it + 1)->to,
                            "object mesh is not consistently oriented or not manifold: edge ("
                                << a << ", " << it->to << ") is used in the same direction by faces " << it->face
                                << " and " << (it + 1)->face);
  }
  // The face across directed edge (a, b): the one holding (b, a); -1 when there is none.
  const auto across = [&](std::int64_t a, std::int64_t b) -> std::int64_t {
    const auto first = out.begin() + row[b], last = out.begin() + row[b + 1];
    const auto it = std::lower_bound(first, last, OutEdge{static_cast<std::int32_t>(a), -1}, by_end);
    return it != last && it->to == a ? it->face : -1;
  };
  // The one-ring of each vertex: the other ends of its outgoing directed edges (on a closed,
  // consistently oriented mesh every neighbour is the end of exactly one outgoing edge).
  ring_start_.assign(row.begin(), row.end());
  ring_.reserve(out.size());
  for (const OutEdge& e : out) ring_.push_back(e.to);
  neighbors_.reserve(nf);
  for (std::int64_t f = 0; f < nf; ++f) {
    std::array<std::int64_t, 3> across_edges;
    for (int k = 0; k < 3; ++k) {
      const std::int64_t a = faces_(f, k), b = faces_(f, (k + 1) % 3);
      across_edges[k] = across(a, b);
      HUGGER_CHECK_ARGUMENT(across_edges[k] >= 0, "object mesh is not closed: edge ("
                                                      << a << ", " << b << ") of face " << f
                                                      << " has no neighbouring face (a hole or a boundary)");
    }
    neighbors_.push_back(across_edges);
  }
  HUGGER_CHECK_ARGUMENT(volume_ > 0.0, "object mesh encloses a non-positive volume ("
                                           << volume_ << " m^3): its faces point inward (reverse the winding) or it is flat");
  check_surface(vertices_, faces_, row, out, neighbors_);
  vertex_normals_ = angle_weighted_normals(vertices_, faces_, face_normals_);
}

bool Object::beyond_bounds(const Vec3& p) const {
  const Aabb& box = bounds();
  return (p.array() < box.lo.array()).any() || (p.array() > box.hi.array()).any();
}

double Object::sign_at(const Vec3& query, const Vec3& on_mesh, int triangle, TriangleFeature f) const {
  // Outside O's box is outside O. (Far away, at 1e15 m, every triangle is as near as any other
  // to rounding, and the nearest one found could face away.)
  if (beyond_bounds(query)) return 1.0;
  // The feature's pseudo-normal: a face's own, an edge's the sum of its two faces' (edge k runs
  // from corner k to k + 1, its other face is neighbors_[k]), a vertex's angle-weighted one.
  const int k = static_cast<int>(f);
  const Vec3 n = f == TriangleFeature::kFace ? face_normals_[triangle]
                 : f <= TriangleFeature::kEdgeCA
                     ? Vec3(face_normals_[triangle] + face_normals_[neighbors_[triangle][k - 1]])
                     : vertex_normals_[faces_(triangle, k - static_cast<int>(TriangleFeature::kVertexA))];
  return (query - on_mesh).dot(n) < 0.0 ? -1.0 : 1.0;
}

SignedNearest Object::nearest(const Vec3& a, const Vec3& b, double max_distance) const {
  const NearestResult r = bvh_.nearest(a, b, max_distance);
  SignedNearest out;
  out.crosses = r.crosses;
  if (r.triangle < 0) {
    // Nothing within the bound: the sign is that of any point of the query.
    out.signed_distance = (max_distance > 0.0 ? inside_off_surface(a) : inside(a)) ? -kInf : kInf;
    return out;
  }
  out.on_query = r.on_query;
  out.on_object = r.on_mesh;
  out.triangle = r.triangle;
  if (r.crosses) {
    // A point on the surface is at distance 0; a segment crossing it penetrates by an unmeasured
    // depth, reported as the smallest negative number.
    out.signed_distance = a == b ? 0.0 : -std::numeric_limits<double>::min();
    return out;
  }
  out.signed_distance = sign_at(r.on_query, r.on_mesh, r.triangle, r.feature) * r.distance;
  return out;
}

bool Object::inside(const Vec3& p) const {
  if (beyond_bounds(p)) return false;
  const NearestResult r = bvh_.nearest(p, p);
  if (r.triangle < 0 || r.distance == 0.0) return false;
  return sign_at(p, r.on_mesh, r.triangle, r.feature) < 0.0;
}

bool Object::inside_off_surface(const Vec3& p) const {
  // The last answer of this thread, for this object: the planner asks about one pivot many times
  // in a row while it turns a link about it (a memo of a pure function: same answers).
  struct Memo {
    std::uint64_t object = 0;
    Vec3 point = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
    bool inside = false;
  };
  thread_local Memo memo;
  if (memo.object == serial_ && memo.point == p) return memo.inside;
  const bool in = inside_by_rays(p);
  memo.object = serial_;
  memo.point = p;
  memo.inside = in;
  return in;
}

bool Object::inside_by_rays(const Vec3& p) const {
  if (beyond_bounds(p)) return false;
  // Three fixed, generic directions: a ray grazing an edge or a vertex can miscount; two rays
  // cannot both do so at a generic point.
  static const Vec3 dirs[3] = {Vec3(0.5377, 0.8622, 0.3188).normalized(), Vec3(-0.7269, 0.1423, -0.6718).normalized(),
                               Vec3(0.2311, -0.6064, 0.7608).normalized()};
  const bool first = bvh_.ray_crossings(p, dirs[0]) % 2 == 1;
  const bool second = bvh_.ray_crossings(p, dirs[1]) % 2 == 1;
  if (first == second) return first;
  return bvh_.ray_crossings(p, dirs[2]) % 2 == 1;
}

bool Object::capsule_clear(const Vec3& a, const Vec3& b, double radius, bool a_outside) const {
  if (bvh_.any_within(a, b, radius)) return false;
  if (a_outside) return true;
  // Nothing within radius (> 0) of the axis, or nothing touching it: wholly inside or outside.
  return radius > 0.0 ? !inside_off_surface(a) : !inside(a);
}

void check_target(const Object& object, const Vec3& target) {
  HUGGER_CHECK_ARGUMENT(target.allFinite(), "target must be a finite 3-vector, got (" << target.x() << ", " << target.y()
                                                                                      << ", " << target.z() << ")");
  // Off the surface (no triangle touches T) and inside by ray parity: both cheap where T lies deep
  // inside, unlike a nearest search, which from the centre of a round object (every triangle about
  // as near as every other) visits nearly all of them. The signed distance, for the message, only
  // where the rays say otherwise.
  if (!object.bvh().any_within(target, target, 0.0) && object.inside_off_surface(target)) return;
  const double depth = object.nearest(target, target).signed_distance;
  HUGGER_CHECK_ARGUMENT(depth < 0.0, "target T = (" << target.x() << ", " << target.y() << ", " << target.z()
                                                    << ") is not inside the object (its distance to the surface is "
                                                    << depth << " m, outside or on it)");
}

Section Object::section(const Vec3& origin, const Vec3& u, const Vec3& v) const {
  check_plane_frame(origin, u, v);
  const Vec3 n = u.cross(v);
  const std::int64_t nv = vertices_.rows();
  std::vector<double> d(nv);
  for (std::int64_t i = 0; i < nv; ++i) {
    d[i] = (Vec3(vertices_.row(i)) - origin).dot(n);
    if (d[i] == 0.0) d[i] = 1e-300;  // symbolic perturbation: vertices on the plane count as above it
  }
  std::unordered_map<std::uint64_t, int> point_of_edge, start_of_edge;
  std::vector<Vec2> points;
  std::vector<std::pair<int, int>> segs;  // point indices
  auto edge_point = [&](std::int64_t i, std::int64_t j) {
    if (i > j) std::swap(i, j);
    auto [it, fresh] = point_of_edge.emplace(edge_key(i, j), static_cast<int>(points.size()));
    if (fresh) {
      const Vec3 pi = vertices_.row(i), pj = vertices_.row(j);
      const Vec3 x = pi + (d[i] / (d[i] - d[j])) * (pj - pi) - origin;
      points.emplace_back(x.dot(u), x.dot(v));
    }
    return it->second;
  };
  for (std::int64_t f = 0; f < faces_.rows(); ++f) {
    const std::int64_t idx[3] = {faces_(f, 0), faces_(f, 1), faces_(f, 2)};
    const bool pos[3] = {d[idx[0]] > 0, d[idx[1]] > 0, d[idx[2]] > 0};
    if (pos[0] == pos[1] && pos[1] == pos[2]) continue;
    int k = 0;  // the vertex alone on its side
    if (pos[0] == pos[1]) k = 2;
    else if (pos[0] == pos[2]) k = 1;
    const std::int64_t prev = idx[(k + 2) % 3], me = idx[k], next = idx[(k + 1) % 3];
    const int p_prev = edge_point(prev, me), p_next = edge_point(me, next);
    if (pos[k]) segs.emplace_back(p_next, p_prev);
    else segs.emplace_back(p_prev, p_next);
  }
  std::unordered_map<int, int> seg_from;  // start point -> segment
  for (int s = 0; s < static_cast<int>(segs.size()); ++s) seg_from[segs[s].first] = s;
  std::vector<char> used(segs.size(), 0);
  std::vector<std::vector<Vec2>> loops;
  for (int s0 = 0; s0 < static_cast<int>(segs.size()); ++s0) {
    if (used[s0]) continue;
    std::vector<Vec2> loop;
    int s = s0;
    bool closed = false;
    while (!used[s]) {
      used[s] = 1;
      loop.push_back(points[segs[s].first]);
      auto it = seg_from.find(segs[s].second);
      if (it == seg_from.end()) break;
      s = it->second;
      if (s == s0) closed = true;
    }
    if (closed && loop.size() >= 3) loops.push_back(std::move(loop));
  }
  return Section(std::move(loops));
}

}  // namespace hugger
