#include "hugger/sensing/sensing.hpp"

#include <cmath>

namespace hugger {

namespace {

Vec2 rotate(const Vec2& v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return Vec2(c * v.x() - s * v.y(), s * v.x() + c * v.y());
}

}  // namespace

bool Sensing::link_free(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double front) const {
  constexpr double kSlack = 1e-12;
  if (a.y() < front - kSlack || b.y() < front - kSlack) return false;
  return capsule_clear(plane.to_world(a), plane.to_world(b), radius);
}

FollowResult Sensing::follow_boundary(const FollowRequest& req) const {
  FollowResult out;
  out.head = req.tip;
  const double h = req.step / 3.0;
  // f(x) = gap of the tip sphere at x minus the level; grad from the sensed normal.
  auto eval = [&](const Vec2& x, double* f, Vec2* g) {
    const Touch t = link(req.plane, x, x, req.radius, kInf);
    *f = t.gap - req.level;
    *g = Vec2(t.normal.dot(req.plane.u), t.normal.dot(req.plane.p));
    return g->norm() > 1e-3;  // the surface must not be (nearly) parallel to the plane
  };
  auto project = [&](Vec2 x, Vec2* out_x, double* out_f) {
    for (int it = 0; it < 12; ++it) {
      double f;
      Vec2 g;
      if (!eval(x, &f, &g)) return false;
      *out_x = x;
      *out_f = f;
      if (std::abs(f) <= 0.1 * req.level) return true;
      Vec2 dx = -f * g / g.squaredNorm();
      if (dx.norm() > h) dx *= h / dx.norm();
      x += dx;
    }
    return *out_f >= -0.5 * req.level && *out_f <= req.level;
  };
  auto acceptable = [&](const Vec2& x) {
    return (x - req.root).norm() <= req.reach && x.y() >= req.front + req.radius;
  };
  Vec2 x;
  double fx;
  if (!project(req.tip, &x, &fx) || !acceptable(x)) return out;
  for (int i = 0; i < 48; ++i) {
    double f;
    Vec2 g;
    if (!eval(x, &f, &g)) break;
    const Vec2 t = Vec2(-g.y(), g.x()).normalized();
    Vec2 y;
    double fy;
    if (!project(x + h * t, &y, &fy) || !acceptable(y)) break;
    ++out.steps;
    if ((y - req.tip).norm() >= req.step) {
      // Bisect between x (chord < step) and y (chord >= step) for the chord == step point.
      Vec2 lo = x, hi = y;
      for (int k = 0; k < 30; ++k) {
        const Vec2 mid = 0.5 * (lo + hi);
        Vec2 pm;
        double fm;
        if (!project(mid, &pm, &fm)) break;
        if ((pm - req.tip).norm() >= req.step) hi = pm; else lo = pm;
        if ((hi - lo).norm() < 1e-3 * req.step) break;
      }
      x = hi;
      break;
    }
    if ((y - x).norm() < 1e-3 * h) break;  // stuck (a cusp): stop here
    x = y;
  }
  const Touch t = link(req.plane, x, x, req.radius, kInf);
  if (t.gap < 0.0) return out;  // never hand back a penetrating head
  out.head = x;
  out.gap = t.gap;
  return out;
}

RotateResult Sensing::rotate_until_touch(const RotateRequest& req) const {
  RotateResult out;
  const Vec2 arm = req.end - req.pivot;
  const double len = arm.norm();
  out.end = req.end;
  double angle = 0.0;
  for (int it = 0; it < 200; ++it) {
    const Vec2 end = req.pivot + rotate(arm, angle);
    const double gap = link(req.plane, req.pivot, end, req.radius, kInf).gap;
    if (gap < 0.0) break;  // cannot happen when starting free; keep the last free position
    out.end = end;
    out.angle = angle;
    out.gap = gap;
    if (gap <= req.touch_gap) {
      out.ok = true;
      break;
    }
    // Conservative advancement: no point of the link moves more than len * d_angle.
    double d = (gap - req.level) / len;
    d = std::min(d, req.max_angle - angle);
    if (d <= 1e-15) break;
    const Vec2 next = req.pivot + rotate(arm, angle + d);
    if (next.y() < req.front) break;
    angle += d;
  }
  return out;
}

RotateResult Sensing::rotate_until_free(const RotateRequest& req) const {
  RotateResult out;
  const Vec2 arm = req.end - req.pivot;
  const double len = arm.norm();
  auto end_at = [&](double a) { return Vec2(req.pivot + rotate(arm, a)); };
  auto free_at = [&](double a) { return link_free(req.plane, req.pivot, end_at(a), req.radius, req.front); };
  if (free_at(0.0)) {
    out.ok = true;
    out.end = req.end;
    out.gap = link(req.plane, req.pivot, req.end, req.radius).gap;
    return out;
  }
  const double da = std::max(req.sample_angle, 1e-6);
  const int samples = static_cast<int>(std::ceil(req.max_angle / da));
  auto refine = [&](double bad, double good) {
    while (len * std::abs(good - bad) > req.tolerance) {
      const double mid = 0.5 * (bad + good);
      if (free_at(mid)) good = mid; else bad = mid;
    }
    return good;
  };
  for (int k = 1; k <= samples; ++k) {
    const double a = std::min(k * da, req.max_angle), prev = std::min((k - 1) * da, req.max_angle);
    const bool plus = free_at(a), minus = free_at(-a);
    if (!plus && !minus) continue;
    double best = 0.0;
    bool have = false;
    if (plus) best = refine(prev, a), have = true;
    if (minus) {
      const double m = refine(-prev, -a);
      if (!have || std::abs(m) < std::abs(best)) best = m;
    }
    out.ok = true;
    out.angle = best;
    out.end = end_at(best);
    out.gap = link(req.plane, req.pivot, out.end, req.radius).gap;
    return out;
  }
  return out;
}

}  // namespace hugger
