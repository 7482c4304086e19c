#include "hugger/planner/snake.hpp"

#include <algorithm>

namespace hugger {

namespace {

/// Place chain[to] at distance L from chain[from], toward the old position of `to`; cling if needed.
/// `pivot_outside`: chain[from] is known to lie outside O.
bool place(const Sensing& sensing, const SnakeRequest& req, const Chain& old, int from, int to, double L,
           bool pivot_outside, Chain& chain) {
  Vec2 dir = old[to] - chain[from];
  if (dir.norm() < 1e-15) dir = old[to] - old[from];
  chain[to] = chain[from] + L * dir.normalized();
  if (sensing.link_free(req.plane, chain[from], chain[to], req.radius, req.front, pivot_outside)) return true;
  RotateRequest rr;
  rr.plane = req.plane;
  rr.pivot = chain[from];
  rr.end = chain[to];
  rr.radius = req.radius;
  rr.front = req.front;
  rr.tolerance = req.tolerance;
  rr.sample_angle = req.sample_angle;
  rr.max_angle = req.max_rotation;
  const RotateResult r = sensing.rotate_until_free(rr);
  if (!r.ok) return false;
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
    if (!place(sensing, req, old, n + 1, n, req.lengths[n], req.start_outside || n + 1 < N, chain)) return false;
  return true;
}

bool tail_to_head(const Sensing& sensing, const SnakeRequest& req, const Vec2& root, Chain& chain) {
  const Chain old = chain;
  const int N = static_cast<int>(chain.size()) - 1;
  chain[0] = root;
  for (int n = 0; n < N; ++n)
    if (!place(sensing, req, old, n, n + 1, req.lengths[n], req.start_outside || n > 0, chain)) return false;
  return true;
}

}  // namespace hugger
