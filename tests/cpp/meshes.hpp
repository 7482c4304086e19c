// Test meshes generated in C++: icospheres, scaled into ellipsoids.
#pragma once

#include <map>
#include <random>
#include <utility>
#include <vector>

#include "hugger/types.hpp"

namespace hugger::test {

struct Mesh {
  PointsN3 vertices;
  FacesN3 faces;
};

inline Mesh icosphere(int subdivisions, const Vec3& radii = Vec3::Ones(), const Vec3& centre = Vec3::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                       {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                       {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> cache;
    auto mid = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = cache.find(key);
      if (it != cache.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return cache[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (auto [a, b, c] : f) {
      const int ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      g.push_back({a, ab, ca});
      g.push_back({b, bc, ab});
      g.push_back({c, ca, bc});
      g.push_back({ab, bc, ca});
    }
    f = g;
  }
  Mesh m;
  m.vertices.resize(v.size(), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.vertices.row(i) = (v[i].cwiseProduct(radii) + centre).transpose();
  m.faces.resize(f.size(), 3);
  for (std::size_t i = 0; i < f.size(); ++i)
    for (int k = 0; k < 3; ++k) m.faces(i, k) = f[i][k];
  return m;
}

inline Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Vec3 v(n(rng), n(rng), n(rng));
  return v.normalized();
}

}  // namespace hugger::test
