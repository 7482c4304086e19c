#include "hugger/planner/snake.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "hugger/geometry/distance.hpp"

namespace hugger {

namespace {

/// The direction joint `joint`'s angle is measured from: link joint - 1, or the palm normal.
Vec2 base_of(const Chain& chain, int joint) {
  return joint == 0 ? Vec2(0.0, 1.0) : Vec2(chain[joint] - chain[joint - 1]);
}

}  // namespace

bool link_clear_of_chain(const Vec2* chain, int b, double separation) {
  const double sep2 = separation * separation;
  const Vec2 lo_b = chain[b].cwiseMin(chain[b + 1]), hi_b = chain[b].cwiseMax(chain[b + 1]);
  for (int a = 0; a + 2 <= b; ++a) {
    // Two links whose boxes are `separation` apart are at least that far apart: most pairs are
    // settled by their boxes, cheaper than the distance. A relative margin far above rounding
    // leaves the pairs at a tie to the distance, so that the answer is the distance's.
    const Vec2 lo_a = chain[a].cwiseMin(chain[a + 1]), hi_a = chain[a].cwiseMax(chain[a + 1]);
    if ((lo_b - hi_a).cwiseMax(lo_a - hi_b).cwiseMax(0.0).squaredNorm() >= sep2 * (1.0 + 1e-9)) continue;
    if (segment_segment_squared_2d(chain[a], chain[a + 1], chain[b], chain[b + 1]) < sep2) return false;
  }
  return true;
}

double relative_angle(const Chain& chain, int joint, const Vec2& dir) {
  return signed_angle(base_of(chain, joint), dir);
}

bool angle_within_limits(double lo, double hi, const Vec2& base, Vec2& dir, bool clamp) {
  if (lo == -kInf && hi == kInf) return true;
  const double q = signed_angle(base, dir);
  if (q >= lo - kLimitSlack && q <= hi + kLimitSlack) return true;
  if (!clamp) return false;
  const double target = q < lo ? lo : hi;
  dir = dir.norm() * rotate_planar(base.normalized(), target);
  return true;
}

bool joint_within_limits(const SnakeRequest& req, const Chain& chain, int joint, Vec2& dir, bool clamp) {
  if (req.lower == nullptr || req.upper == nullptr) return true;
  return angle_within_limits(req.lower[joint], req.upper[joint], base_of(chain, joint), dir, clamp);
}

namespace {

/// Place chain[to] at distance L from chain[from], toward the old position of `to`; cling if needed.
/// `pivot_outside`: chain[from] is known to lie outside O.
/// Limits: Tail2Head (to == from + 1) holds the joint at `from` within its limits, turning
/// the ray onto a limit it breaks and refusing a freeing rotation that ends beyond one;
/// Head2Tail (to == from - 1) turns the ray of link `to` so that joint `from` (between it and
/// the link placed before it) is within its limits, and leaves the freeing rotation free:
/// Tail2Head, whose chain is the one emitted, enforces them.
/// `turned` (or nullptr): set to whether clinging turned the link.
bool place(const Sensing& sensing, const SnakeRequest& req, const Vec2* old, int from, int to, double L,
           bool pivot_outside, Chain& chain, char* turned) {
  Vec2 dir = old[to] - chain[from];
  if (dir.norm() < 1e-15) dir = old[to] - old[from];
  dir.normalize();
  const int N = static_cast<int>(chain.size()) - 1;
  if (to > from) {
    joint_within_limits(req, chain, from, dir, true);
  } else if (req.lower != nullptr && req.upper != nullptr && from < N) {
    // theta_from is the angle from link `to` (= -dir) to link `from`: within [lo, hi] exactly
    // when the angle from link `from` to -dir is within [-hi, -lo].
    Vec2 e = -dir;
    angle_within_limits(-req.upper[from], -req.lower[from], chain[from + 1] - chain[from], e, true);
    dir = -e;
  }
  chain[to] = chain[from] + L * dir;
  if (turned != nullptr) *turned = 0;
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
  rr.pivot_outside = pivot_outside;
  const RotateResult r = sensing.rotate_until_free(rr);
  if (!r.ok) return false;
  Vec2 freed = r.end - chain[from];
  if (to > from && !joint_within_limits(req, chain, from, freed, false)) return false;
  chain[to] = r.end;
  if (turned != nullptr) *turned = 1;
  return true;
}

/// True when joint `j` lies closer than sqrt(d2) to the link [a, b] that ends at `a`, the joint
/// before it. Most chains bend less than a right angle at `a`, where the nearest point is `a`.
inline bool joint_near_link(const Vec2& j, const Vec2& a, const Vec2& b, double d2) {
  const Vec2 d = j - a, e = b - a;
  const double de = d.dot(e);
  if (!(de > 0.0)) return d.squaredNorm() < d2;
  const double ee = e.squaredNorm();
  return de >= ee ? (j - b).squaredNorm() < d2 : (d - e * (de / ee)).squaredNorm() < d2;
}

/// The chain before a propagation, on the stack: the propagations run for every finger, every
/// iteration.
std::array<Vec2, kMaxLinks + 1> stack_copy(const Chain& chain) {
  std::array<Vec2, kMaxLinks + 1> out;
  std::copy(chain.begin(), chain.end(), out.begin());
  return out;
}

}  // namespace

bool head_to_tail(const Sensing& sensing, const SnakeRequest& req, const Vec2& head, Chain& chain) {
  const int N = static_cast<int>(chain.size()) - 1;
  const auto old = stack_copy(chain);
  chain[N] = head;
  for (int n = N - 1; n >= 0; --n)
    // Every pivot after the first is the end of a link just placed free: outside O.
    if (!place(sensing, req, old.data(), n + 1, n, req.lengths[n], req.start_outside || n + 1 < N, chain, nullptr))
      return false;
  return true;
}

bool tail_to_head(const Sensing& sensing, const SnakeRequest& req, const Vec2& root, Chain& chain, char* turned,
                  bool* folded) {
  const int N = static_cast<int>(chain.size()) - 1;
  const auto old = stack_copy(chain);
  chain[0] = root;
  if (folded != nullptr) *folded = false;
  // fold_early's squared separation, less a margin far above rounding that leaves ties to the test
  // of the placed link below (0: no early test)
  const double early2 = req.fold_early && req.self_separation > 0.0
                            ? req.self_separation * req.self_separation * (1.0 - 1e-9)
                            : 0.0;
  for (int n = 0; n < N; ++n) {
    // A joint already that close to the link before the last (the others were tested against the
    // link ending at it) folds every link from it: refused before the link is asked of the skin.
    if (n >= 2 && early2 > 0.0 && joint_near_link(chain[n], chain[n - 1], chain[n - 2], early2)) {
      if (folded != nullptr) *folded = true;
      return false;
    }
    if (!place(sensing, req, old.data(), n, n + 1, req.lengths[n], req.start_outside || n > 0, chain,
               turned != nullptr ? turned + n : nullptr))
      return false;
    // (Links 0 and 1 have no link before them but their neighbours.)
    if (n >= 2 && req.self_separation > 0.0 && !link_clear_of_chain(chain.data(), n, req.self_separation)) {
      if (folded != nullptr) *folded = true;
      return false;
    }
  }
  return true;
}

}  // namespace hugger
