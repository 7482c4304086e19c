#include "hugger/planner/snake.hpp"

#include <algorithm>
#include <cmath>

namespace hugger {

double relative_angle(const Chain& chain, int joint, const Vec2& dir) {
  const Vec2 prev = joint == 0 ? Vec2(0.0, 1.0) : Vec2(chain[joint] - chain[joint - 1]);
  return std::atan2(prev.x() * dir.y() - prev.y() * dir.x(), prev.dot(dir));
}

bool joint_within_limits(const SnakeRequest& req, const Chain& chain, int joint, Vec2& dir, bool clamp) {
  if (req.lower == nullptr || req.upper == nullptr) return true;
  const double lo = req.lower[joint], hi = req.upper[joint];
  if (lo == -kInf && hi == kInf) return true;
  const double q = relative_angle(chain, joint, dir);
  if (q >= lo - kLimitSlack && q <= hi + kLimitSlack) return true;
  if (!clamp) return false;
  const double target = q < lo ? lo : hi;
  const Vec2 prev = joint == 0 ? Vec2(0.0, 1.0) : Vec2((chain[joint] - chain[joint - 1]).normalized());
  const double c = std::cos(target), s = std::sin(target);
  dir = dir.norm() * Vec2(c * prev.x() - s * prev.y(), s * prev.x() + c * prev.y());
  return true;
}

namespace {

/// Place chain[to] at distance L from chain[from], toward the old position of `to`; cling if needed.
/// `pivot_outside`: chain[from] is known to lie outside O.
/// `limited`: the joint at `from` is held within its limits (Tail2Head: to == from + 1).
bool place(const Sensing& sensing, const SnakeRequest& req, const Chain& old, int from, int to, double L,
           bool pivot_outside, bool limited, Chain& chain) {
  Vec2 dir = old[to] - chain[from];
  if (dir.norm() < 1e-15) dir = old[to] - old[from];
  dir.normalize();
  if (limited) joint_within_limits(req, chain, from, dir, true);
  chain[to] = chain[from] + L * dir;
  if (sensing.link_free(req.plane, chain[from], chain[to], req.radius, req.front, pivot_outside)) return true;
  RotateRequest rr;
  rr.plane = req.plane;
  rr.pivot = chain[from];
  rr.end = chain[to];
  rr.radius = req.radius;
  rr.front = req.front;
  rr.tolerance = req.tolerance;
  rr.sample_angle = req.sample_angle;
  const RotateResult r = sensing.rotate_until_free(rr);
  if (!r.ok) return false;
  Vec2 freed = r.end - chain[from];
  if (limited && !joint_within_limits(req, chain, from, freed, false)) return false;
  chain[to] = r.end;
  return true;
}

}  // namespace

bool head_to_tail(const Sensing& sensing, const SnakeRequest& req, const Vec2& head, Chain& chain) {
  const Chain old = chain;
  const int N = static_cast<int>(chain.size()) - 1;
  chain[N] = head;
  for (int n = N - 1; n >= 0; --n)
    // Every pivot after the first is the end of a link just placed free: outside O.
    if (!place(sensing, req, old, n + 1, n, req.lengths[n], req.start_outside || n + 1 < N, false, chain)) return false;
  return true;
}

bool tail_to_head(const Sensing& sensing, const SnakeRequest& req, const Vec2& root, Chain& chain) {
  const Chain old = chain;
  const int N = static_cast<int>(chain.size()) - 1;
  chain[0] = root;
  for (int n = 0; n < N; ++n)
    if (!place(sensing, req, old, n, n + 1, req.lengths[n], req.start_outside || n > 0, true, chain)) return false;
  return true;
}

}  // namespace hugger
