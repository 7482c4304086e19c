#include "hugger/geometry/section.hpp"

#include <algorithm>
#include <cmath>

#include "hugger/geometry/distance.hpp"

namespace hugger {

Section::Section(std::vector<std::vector<Vec2>> loops) : loops_(std::move(loops)) {
  Vec2 lo = Vec2::Constant(kInf), hi = Vec2::Constant(-kInf);
  for (const auto& loop : loops_) {
    for (std::size_t i = 0; i < loop.size(); ++i) {
      segments_.push_back({loop[i], loop[(i + 1) % loop.size()]});
      lo = lo.cwiseMin(loop[i]);
      hi = hi.cwiseMax(loop[i]);
    }
  }
  if (segments_.empty()) return;
  const int side = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(segments_.size()))), 1, 512);
  nx_ = ny_ = side;
  const Vec2 span = (hi - lo).cwiseMax(1e-12);
  lo_ = lo - 1e-9 * span;
  cell_ = (span * (1.0 + 2e-9)) / side;
  grid_.assign(static_cast<std::size_t>(nx_) * ny_, {});
  std::vector<int> cells;
  for (int s = 0; s < static_cast<int>(segments_.size()); ++s) {
    cells_of(segments_[s].a, segments_[s].b, cells);
    for (int c : cells) grid_[c].push_back(s);
  }
}

void Section::cells_of(const Vec2& a, const Vec2& b, std::vector<int>& out) const {
  out.clear();
  const Vec2 lo = a.cwiseMin(b), hi = a.cwiseMax(b);
  const int x0 = std::clamp(static_cast<int>((lo.x() - lo_.x()) / cell_.x()), 0, nx_ - 1);
  const int x1 = std::clamp(static_cast<int>((hi.x() - lo_.x()) / cell_.x()), 0, nx_ - 1);
  const int y0 = std::clamp(static_cast<int>((lo.y() - lo_.y()) / cell_.y()), 0, ny_ - 1);
  const int y1 = std::clamp(static_cast<int>((hi.y() - lo_.y()) / cell_.y()), 0, ny_ - 1);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) out.push_back(y * nx_ + x);
}

double Section::boundary_distance(const Vec2& p) const {
  if (segments_.empty()) return kInf;
  const int cx = std::clamp(static_cast<int>(std::floor((p.x() - lo_.x()) / cell_.x())), 0, nx_ - 1);
  const int cy = std::clamp(static_cast<int>(std::floor((p.y() - lo_.y()) / cell_.y())), 0, ny_ - 1);
  const double cmin = std::min(cell_.x(), cell_.y());
  double best_sq = kInf;
  for (int k = 0; k <= std::max(nx_, ny_); ++k) {
    const double lb = (k - 1) * cmin;
    if (k > 0 && lb > 0 && lb * lb > best_sq) break;
    for (int y = cy - k; y <= cy + k; ++y) {
      if (y < 0 || y >= ny_) continue;
      const bool edge_row = (y == cy - k || y == cy + k);
      for (int x = cx - k; x <= cx + k; x += (edge_row ? 1 : 2 * std::max(k, 1))) {
        if (x < 0 || x >= nx_) continue;
        for (int s : grid_[y * nx_ + x]) {
          const Vec2 q = closest_point_on_segment(p, segments_[s].a, segments_[s].b);
          best_sq = std::min(best_sq, (q - p).squaredNorm());
        }
      }
    }
  }
  return std::sqrt(best_sq);
}

bool Section::inside(const Vec2& p) const {
  if (segments_.empty()) return false;
  const int cy = static_cast<int>(std::floor((p.y() - lo_.y()) / cell_.y()));
  if (cy < 0 || cy >= ny_) return false;
  const int cx = std::max(0, static_cast<int>(std::floor((p.x() - lo_.x()) / cell_.x())));
  std::vector<int> seen;
  for (int x = cx; x < nx_; ++x)
    for (int s : grid_[cy * nx_ + x]) seen.push_back(s);
  std::sort(seen.begin(), seen.end());
  seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
  bool in = false;
  for (int s : seen) {
    const Vec2& a = segments_[s].a;
    const Vec2& b = segments_[s].b;
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (x > p.x()) in = !in;
    }
  }
  return in;
}

double Section::area() const {
  double a = 0.0;
  for (const auto& s : segments_) a += 0.5 * (s.a.x() * s.b.y() - s.b.x() * s.a.y());
  return a;
}

double Section::perimeter() const {
  double l = 0.0;
  for (const auto& s : segments_) l += (s.b - s.a).norm();
  return l;
}

}  // namespace hugger
