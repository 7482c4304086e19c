#include "hugger/sensing/sensing.hpp"

#include <algorithm>
#include <cmath>

#include "hugger/check.hpp"
#include "hugger/geometry/next.hpp"

namespace hugger {

namespace {

void check_size(double x, const char* name) {
  HUGGER_CHECK_ARGUMENT(std::isfinite(x) && x >= 0.0 && x <= kMaxCoordinate,
                        name << " must be a number from 0 to " << kMaxCoordinate << " (m), got " << x);
}

void check_cap(double cap) { HUGGER_CHECK_ARGUMENT(!std::isnan(cap), "cap must be a number (m) or inf, got nan"); }

}  // namespace

void check_capsule_query(const Vec3& a, const Vec3& b, double radius, double cap) {
  HUGGER_CHECK_ARGUMENT(a.allFinite() && b.allFinite() && a.cwiseAbs().maxCoeff() <= kMaxCoordinate &&
                            b.cwiseAbs().maxCoeff() <= kMaxCoordinate,
                        "a and b must be finite, each coordinate within " << kMaxCoordinate << " m of the origin");
  check_size(radius, "radius");
  check_cap(cap);
}

void check_palm_query(double radius, double thickness, double cap) {
  check_size(radius, "radius");
  check_size(thickness, "thickness");
  check_cap(cap);
}

double check_gap(double gap, const char* source) {
  HUGGER_CHECK_ARGUMENT(!std::isnan(gap), source << " a gap of nan; expected a number (m) or +-inf");
  return gap;
}

Touch check_touch(Touch touch, const char* source) {
  check_gap(touch.gap, source);
  HUGGER_CHECK_ARGUMENT(touch.on_hand.allFinite() && touch.on_object.allFinite() && touch.normal.allFinite() &&
                            touch.normal.cwiseAbs().maxCoeff() > 0.0,
                        source << " non-finite points or a zero or non-finite normal");
  // A normal whose squared length would overflow or lose its precision is scaled first (the
  // ordinary ones are normalized as they come, bit for bit as before).
  const double n2 = touch.normal.squaredNorm();
  if (!(n2 >= 1e-200 && n2 <= 1e200)) touch.normal /= touch.normal.cwiseAbs().maxCoeff();
  touch.normal.normalize();
  return touch;
}

bool Sensing::link_free(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double front,
                        bool a_outside) const {
  if (a.y() < front - kFrontSlack || b.y() < front - kFrontSlack) return false;
  return capsule_clear(plane.to_world(a), plane.to_world(b), radius, a_outside);
}

bool Sensing::link_depth_within(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                double allow) const {
  const double g = link(plane, a, b, radius, allow).gap;
  if (g >= 0.0) return true;
  if (g > -radius) return g >= -allow;  // the axis is outside O: the depth is measured
  // The axis crosses O (depth not measured): points along it, refined where the depth between
  // two of them could exceed twice the allowance (a point's gap changes no faster than the
  // point moves), at most kRefine halvings below 16 pieces.
  constexpr int kPieces = 16, kRefine = 6;
  const double length = (b - a).norm();
  // The refinement reads the gaps, not only their sign, but a gap of at least a piece's length
  // (length / 16, the longest piece) never asks for refinement: a piece with one end that far
  // out needs none whatever the other end's gap (>= -allow, else the check has failed). So the
  // gaps are asked exactly up to that cap, which prunes most of each query.
  const double cap = length / kPieces;
  auto gap_at = [&](double u) {
    const Vec2 x = a + (b - a) * u;
    return link(plane, x, x, radius, cap).gap;
  };
  struct Piece {
    double u0, u1, g0, g1;
    int level;
  };
  std::vector<Piece> todo;
  double u_prev = 0.0, g_prev = gap_at(0.0);
  if (g_prev < -allow) return false;
  for (int i = 1; i <= kPieces; ++i) {
    const double u = static_cast<double>(i) / kPieces, g = gap_at(u);
    if (g < -allow) return false;
    todo.push_back({u_prev, u, g_prev, g, 0});
    u_prev = u;
    g_prev = g;
  }
  while (!todo.empty()) {
    const Piece p = todo.back();
    todo.pop_back();
    if (0.5 * (p.g0 + p.g1 - (p.u1 - p.u0) * length) >= -2.0 * allow || p.level >= kRefine) continue;
    const double u = 0.5 * (p.u0 + p.u1), g = gap_at(u);
    if (g < -allow) return false;
    todo.push_back({p.u0, u, p.g0, g, p.level + 1});
    todo.push_back({u, p.u1, g, p.g1, p.level + 1});
  }
  return true;
}

FollowResult Sensing::follow_boundary(const FollowRequest& req) const {
  FollowResult out;
  out.head = req.tip;
  const double h = req.step / kFollowDivisions;
  // A point of the level curve gap = level, sensed: f = gap - level, g = its gradient in the plane.
  struct Level {
    Vec2 x = Vec2::Zero();
    double f = kInf;
    Vec2 g = Vec2::Zero();
  };
  auto eval = [&](const Vec2& x, Level* at) {
    const Touch t = link(req.plane, x, x, req.radius, kInf);
    at->x = x;
    at->f = t.gap - req.level;
    at->g = Vec2(t.normal.dot(req.plane.u), t.normal.dot(req.plane.p));
    // Off the level curve's reach: a gap of -inf (a skin may answer it once the axis is inside
    // O) or +inf gives no Newton step. And the surface must not be (nearly) parallel to the plane.
    return std::isfinite(at->f) && at->g.norm() > 1e-3;
  };
  // Newton steps along the gradient back onto the level curve (each at most h long).
  auto project = [&](Vec2 x, Level* at) {
    for (int it = 0; it < 12; ++it) {
      if (!eval(x, at)) return false;
      if (std::abs(at->f) <= 0.1 * req.level) return true;
      Vec2 dx = -at->f * at->g / at->g.squaredNorm();
      if (dx.norm() > h) dx *= h / dx.norm();
      x += dx;
    }
    return at->f >= -0.5 * req.level && at->f <= req.level;
  };
  auto acceptable = [&](const Vec2& x) {
    return (x - req.root).norm() <= req.reach && x.y() >= req.front + req.radius;
  };
  Level x;
  if (!project(req.tip, &x) || !acceptable(x.x)) return out;
  for (int i = 0; i < kFollowSteps; ++i) {
    const Vec2 t = Vec2(-x.g.y(), x.g.x()).normalized();
    Level y;
    if (!project(x.x + h * t, &y) || !acceptable(y.x)) break;
    ++out.steps;
    if ((y.x - req.tip).norm() >= req.step) {
      // The chord reaches `step` between x and y: take the point of [x, y] at chord `step`
      // (|x + t (y - x) - tip| = step) and put it back on the level curve.
      const Vec2 d = y.x - x.x, w = x.x - req.tip;
      const double a = d.squaredNorm(), b = w.dot(d), c = w.squaredNorm() - req.step * req.step;
      const double s = a > 0.0 ? std::clamp((-b + std::sqrt(std::max(0.0, b * b - a * c))) / a, 0.0, 1.0) : 1.0;
      Level z;
      x = project(x.x + s * d, &z) && acceptable(z.x) ? z : y;
      break;
    }
    if ((y.x - x.x).norm() < 1e-3 * h) break;  // stuck (a cusp): stop here
    x = y;
  }
  const double gap = x.f + req.level;
  if (!(gap >= 0.0)) return out;  // never hand back a penetrating head
  out.head = x.x;
  out.gap = gap;
  return out;
}

double Sensing::contact_gap(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius, double delta,
                            double cap) const {
  // Below delta a capped answer would not decide contact: the cap is at least delta.
  cap = std::max(cap, delta);
  // link()'s gap is never below the gap in space (less a skin's flattening): at most delta, the
  // link touches. Beyond it, a skin that measures within the plane adds the gap in space.
  const double g = link(plane, a, b, radius, cap).gap;
  if (g <= delta || !(g > 0.0)) return g;
  return std::min(g, gap_in_space(plane, a, b, radius, cap));
}

double Sensing::contact_gap_bound(const FingerPlane& plane, const Vec2& a, const Vec2& b, double radius,
                                  double delta, double need, double far) const {
  // Beyond the cap the answer is only known to be above the cap (so above need).
  const double cap = std::max(next_up(need), far);
  return std::min(contact_gap(plane, a, b, radius, delta, cap), cap);
}

RotateResult Sensing::rotate_until_touch(const RotateRequest& req) const {
  RotateResult out;
  const Vec2 arm = req.end - req.pivot;
  const double len = arm.norm();
  out.end = req.end;
  double angle = 0.0;
  for (int it = 0; it < 200; ++it) {
    const Vec2 end = req.pivot + rotate_planar(arm, angle);
    // A gap beyond the rest of the arc (plus the level) only lets the link turn to its end: it
    // is asked with a cap twice that, past which its size changes nothing below. (A request
    // outside the planner's, with a negative or NaN arc, level or touch_gap, is asked with no cap.)
    const double rest = req.max_angle - angle;
    const double cap = rest >= 0.0 && req.level >= 0.0 && req.touch_gap >= 0.0
                           ? 2.0 * (rest * len + req.level) + req.touch_gap
                           : kInf;
    const double gap = link(req.plane, req.pivot, end, req.radius, cap).gap;
    if (gap < 0.0) break;  // cannot happen when starting free; keep the last free position
    out.end = end;
    out.angle = angle;
    out.gap = gap;
    if (gap <= req.touch_gap ||
        (gap > 0.0 && gap_in_space(req.plane, req.pivot, end, req.radius, req.touch_gap) <= req.touch_gap)) {
      out.ok = true;
      break;
    }
    // Conservative advancement: no point of the link moves more than len * d_angle.
    double d = (gap - req.level) / len;
    d = std::min(d, req.max_angle - angle);
    if (d <= 1e-15) break;
    const Vec2 next = req.pivot + rotate_planar(arm, angle + d);
    if (next.y() < req.front) break;
    angle += d;
  }
  return out;
}

RotateResult Sensing::rotate_until_free(const RotateRequest& req) const {
  RotateResult out;
  const Vec2 arm = req.end - req.pivot;
  const double len = arm.norm();
  // Gaps are resolved exactly up to this cap; a free position with a larger gap is free enough.
  const double cap = std::max(req.radius, 4.0 * req.tolerance);
  struct Probe {
    double angle = 0.0;
    bool free = false;
    double gap = -kInf;      ///< gap of the link (>= cap: at least cap)
    double slope = 0.0;      ///< d gap / d angle at this angle
    bool measured = false;   ///< gap and slope are exact (the axis is outside O, within cap)
  };
  auto end_at = [&](double a) { return Vec2(req.pivot + rotate_planar(arm, a)); };
  auto probe = [&](double a) {
    Probe pr;
    pr.angle = a;
    const Vec2 e = end_at(a);
    if (req.pivot.y() < req.front - kFrontSlack || e.y() < req.front - kFrontSlack) return pr;  // behind the palm
    const Touch t = link(req.plane, req.pivot, e, req.radius, cap);
    pr.gap = t.gap;
    pr.free = t.gap >= 0.0;
    // The nearest axis point q turns about the pivot: d gap / d angle = grad . perp(q - pivot).
    const Vec2 q = req.plane.to_plane(t.on_hand) - req.pivot;
    const Vec2 grad(t.normal.dot(req.plane.u), t.normal.dot(req.plane.p));
    pr.slope = grad.dot(Vec2(-q.y(), q.x()));
    pr.measured = t.gap > -req.radius && t.gap < cap;  // an axis crossing O reports a gap of -radius
    return pr;
  };
  auto finish = [&](const Probe& good) {
    out.ok = true;
    out.angle = good.angle;
    out.end = end_at(good.angle);
    out.gap = good.gap;
    return out;
  };
  const Probe start = probe(0.0);
  if (start.free) return finish(start);
  // Between a colliding and a free angle, the free one nearest to the boundary: false position
  // on the measured gap (Illinois), bisection where it is not measured; done once the free end
  // rests within `tolerance` of O or the bracket is that narrow.
  auto refine = [&](Probe bad, Probe good) {
    const double target = 0.5 * req.tolerance;
    double f_bad = bad.gap - target, f_good = good.gap - target;
    int last = 0;  // which end the last probe replaced: +1 the free one, -1 the colliding one
    for (int guard = 0; guard < 200 && len * std::abs(good.angle - bad.angle) > req.tolerance &&
                        good.gap > req.tolerance;
         ++guard) {
      double a = 0.5 * (bad.angle + good.angle);
      if (bad.measured && good.gap < cap) {
        const double x = bad.angle - f_bad * (good.angle - bad.angle) / (f_good - f_bad);
        const double lo = std::min(bad.angle, good.angle), hi = std::max(bad.angle, good.angle), w = hi - lo;
        if (x > lo + 1e-3 * w && x < hi - 1e-3 * w) a = x;
      }
      const Probe m = probe(a);
      if (m.free) {
        good = m;
        f_good = m.gap - target;
        if (last == 1) f_bad *= 0.5;  // Illinois: the colliding end kept twice
        last = 1;
      } else {
        bad = m;
        f_bad = m.gap - target;
        if (last == -1) f_good *= 0.5;
        last = -1;
      }
    }
    return good;
  };
  // The coarse two-way search: the first sample angle below `limit` at which either way is
  // free, refined on each free side; the smaller rotation wins (ties: flexion).
  const double da = std::max(req.sample_angle, 1e-6);
  auto coarse = [&](double limit, Probe* best) {
    const int samples = static_cast<int>(std::ceil(limit / da - 1e-9));
    Probe prev_plus = start, prev_minus = start;
    for (int k = 1; k <= samples; ++k) {
      const double a = std::min(k * da, limit);
      const Probe plus = probe(a), minus = probe(-a);
      if (plus.free || minus.free) {
        if (plus.free) *best = refine(prev_plus, plus);
        if (minus.free) {
          const Probe m = refine(prev_minus, minus);
          if (!plus.free || std::abs(m.angle) < std::abs(best->angle)) *best = m;
        }
        return true;
      }
      prev_plus = plus;
      prev_minus = minus;
    }
    return false;
  };
  // Newton steps on the measured gap, toward the side that opens it: a link resting a little
  // inside a smooth surface is freed in two or three probes. A step longer than a few sample
  // angles could pass over a thin part of O or the first free side: the sampled search decides.
  // The rotation must be the smallest that frees the link (docs/algorithm.md, decision 6): a Newton result
  // beyond the first sample angle is kept only if no sample nearer zero, either way, is free.
  Probe bad = start;
  int dir = 0;
  for (int it = 0; it < 4 && bad.measured && std::abs(bad.slope) > 1e-12; ++it) {
    const double a = bad.angle + (0.5 * req.tolerance - bad.gap) / bad.slope;
    const int d = a > bad.angle ? 1 : -1;
    if ((dir != 0 && d != dir) || !(std::abs(a) <= req.max_angle) || std::abs(a - bad.angle) > 4.0 * da)
      break;  // turned back, out of range, or too long a step
    dir = d;
    const Probe m = probe(a);
    if (m.free) {
      Probe best = refine(bad, m);
      Probe nearer;
      if (std::abs(best.angle) > da && coarse(std::abs(best.angle) - 0.5 * da, &nearer) &&
          std::abs(nearer.angle) < std::abs(best.angle))
        best = nearer;
      return finish(best);
    }
    bad = m;
  }
  Probe best;
  if (coarse(req.max_angle, &best)) return finish(best);
  return out;
}

}  // namespace hugger
