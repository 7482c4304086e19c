// Meshes generated in C++ for the tests and the benchmark: icospheres (scaled into ellipsoids),
// boxes, `curvy`.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <unordered_map>
#include <vector>

#include "hugger/types.hpp"

namespace hugger::test {

struct Mesh {
  PointsN3 vertices;
  FacesN3 faces;
};

/// The mesh of vertices v and triangles f.
inline Mesh to_mesh(const std::vector<Vec3>& v, const std::vector<std::array<std::int64_t, 3>>& f) {
  Mesh m;
  m.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.vertices.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  m.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i)
    for (int k = 0; k < 3; ++k) m.faces(static_cast<Eigen::Index>(i), k) = f[i][k];
  return m;
}

/// The icosphere of `subdivisions`, scaled by `radii` about `centre`. The unit icosphere is built
/// as hugger.objects.icosphere (python/hugger/objects.py) builds it: the same base vertices and
/// faces, the same order of new vertices, normalised as p / sqrt(p . p); the same faces, and
/// vertices equal to the last bit or so (NumPy's norm rounds its own way).
inline Mesh icosphere(int subdivisions, const Vec3& radii = Vec3::Ones(), const Vec3& centre = Vec3::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  auto unit = [](const Vec3& p) { return Vec3(p / std::sqrt(p.x() * p.x() + p.y() * p.y() + p.z() * p.z())); };
  for (auto& p : v) p = unit(p);
  std::vector<std::array<std::int64_t, 3>> f = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
      {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},   {4, 9, 5}, {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::unordered_map<std::uint64_t, std::int64_t> cache;
    cache.reserve(f.size() * 2);
    v.reserve(v.size() + f.size() * 3 / 2 + 2);
    auto mid = [&](std::int64_t a, std::int64_t b) {
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint64_t>(std::max(a, b));
      auto [it, fresh] = cache.emplace(key, static_cast<std::int64_t>(v.size()));
      if (fresh) v.push_back(unit(v[a] + v[b]));
      return it->second;
    };
    std::vector<std::array<std::int64_t, 3>> g;
    g.reserve(f.size() * 4);
    for (auto [a, b, c] : f) {
      const std::int64_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      g.push_back({a, ab, ca});
      g.push_back({b, bc, ab});
      g.push_back({c, ca, bc});
      g.push_back({ab, bc, ca});
    }
    f.swap(g);
  }
  if (radii != Vec3::Ones() || centre != Vec3::Zero())
    for (auto& p : v) p = p.cwiseProduct(radii) + centre;
  return to_mesh(v, f);
}

/// An axis-aligned box of half-extents `half` about `centre` (12 triangles, outward normals).
inline Mesh box(const Vec3& half, const Vec3& centre = Vec3::Zero()) {
  std::vector<Vec3> v(8);
  for (int i = 0; i < 8; ++i)
    v[i] = centre + Vec3((i & 1 ? 1 : -1) * half.x(), (i & 2 ? 1 : -1) * half.y(), (i & 4 ? 1 : -1) * half.z());
  return to_mesh(v, {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                     {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}});
}

/// A cylinder of `radius` and half-height `half` about the z axis: `n` sides, each cap a fan about
/// a centre vertex (of degree n: a vertex of high degree), outward normals. `bands` rings of
/// quads along z (more than one puts rings of vertices inside the side, as the built-in cylinder).
inline Mesh cylinder(double radius, double half, int n, int bands = 1) {
  std::vector<Vec3> v;
  const int rings = bands + 1;
  for (int k = 0; k < n; ++k) {
    const double t = 2.0 * kPi * k / n;
    for (int j = 0; j < rings; ++j)  // rings * k + j: ring j, from the bottom
      v.emplace_back(radius * std::cos(t), radius * std::sin(t), -half + 2.0 * half * j / bands);
  }
  const std::int64_t bottom = static_cast<std::int64_t>(v.size()), top = bottom + 1;
  v.emplace_back(0.0, 0.0, -half);
  v.emplace_back(0.0, 0.0, half);
  std::vector<std::array<std::int64_t, 3>> f;
  for (std::int64_t k = 0; k < n; ++k) {
    const std::int64_t k1 = (k + 1) % n;
    for (std::int64_t j = 0; j < bands; ++j) {
      const std::int64_t b0 = rings * k + j, t0 = b0 + 1, b1 = rings * k1 + j, t1 = b1 + 1;
      f.push_back({b0, b1, t1});
      f.push_back({b0, t1, t0});
    }
    f.push_back({top, rings * k + bands, rings * k1 + bands});
    f.push_back({bottom, rings * k1, rings * k});
  }
  return to_mesh(v, f);
}

/// A torus about the z axis: the circle of radius `minor` about the circle of radius `major` in
/// the plane z = 0, `n` x `m` quads, outward normals.
inline Mesh torus(double major, double minor, int n, int m) {
  std::vector<Vec3> v;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double a = 2.0 * kPi * i / n, b = 2.0 * kPi * j / m;
      const double rho = major + minor * std::cos(b);
      v.emplace_back(rho * std::cos(a), rho * std::sin(a), minor * std::sin(b));
    }
  std::vector<std::array<std::int64_t, 3>> f;
  auto at = [&](int i, int j) { return static_cast<std::int64_t>(((i + n) % n) * m + (j + m) % m); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      f.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      f.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return to_mesh(v, f);
}

/// The union of two meshes (their vertices and faces side by side: two separate parts).
inline Mesh join(const Mesh& x, const Mesh& y) {
  Mesh out;
  out.vertices.resize(x.vertices.rows() + y.vertices.rows(), 3);
  out.vertices << x.vertices, y.vertices;
  out.faces.resize(x.faces.rows() + y.faces.rows(), 3);
  out.faces << x.faces, (y.faces.array() + x.vertices.rows()).matrix();
  return out;
}

/// `curvy` (hugger.objects.curvy; non-convex: concave dents): the unit icosphere of
/// `subdivisions`, each vertex v = (x, y, z) moved to p = v * rho(v) * 0.04 with rho = 1 + 0.20
/// sin(3.0x+0.7) cos(2.5y-0.3) + 0.12 sin(4.0z+1.2) cos(2.0x-0.5) + 0.10 cos(3.5y+0.9) sin(2.5z)
/// - 0.10 exp(-((x-0.1)/0.3)^2), then p.x *= 1.2.
inline Mesh curvy(int subdivisions = 5) {
  Mesh m = icosphere(subdivisions);
  for (Eigen::Index i = 0; i < m.vertices.rows(); ++i) {
    const double x = m.vertices(i, 0), y = m.vertices(i, 1), z = m.vertices(i, 2);
    const double g = (x - 0.1) / 0.3;
    const double rho = 1.0 + 0.20 * std::sin(3.0 * x + 0.7) * std::cos(2.5 * y - 0.3) +
                       0.12 * std::sin(4.0 * z + 1.2) * std::cos(2.0 * x - 0.5) +
                       0.10 * std::cos(3.5 * y + 0.9) * std::sin(2.5 * z) - 0.10 * std::exp(-(g * g));
    const double scale = rho * 0.04;
    m.vertices.row(i) *= scale;
    m.vertices(i, 0) *= 1.2;
  }
  return m;
}

inline Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Vec3 v(n(rng), n(rng), n(rng));
  return v.normalized();
}

}  // namespace hugger::test
