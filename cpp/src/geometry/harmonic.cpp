#include "hugger/geometry/harmonic.hpp"

#include <algorithm>
#include <utility>

#include "hugger/types.hpp"

namespace hugger {

namespace {

constexpr double kTwoPi = 2.0 * kPi;

/// Intervals kept on the stack, per buffer. Intersecting with one arc adds at most one interval
/// (a wrapping arc's gap lies inside at most one of them), so n constraints leave at most n + 1:
/// surely_empty's buffers hold that for up to 37 constraints; allowed_intervals keeps 2 n + 2 on
/// the stack for up to 18 (a vertex of degree 17).
constexpr int kSmall = 2 * 18 + 2;

/// A pseudo-angle of the direction (x, y) != 0 in [0, 4] (4 only for directions just below +x,
/// rounded; 0 and 4 are the same direction): increasing with its angle from +x
/// (counterclockwise), by a slope between 1/2 and 1, without trigonometry.
inline double pseudo_angle(double x, double y) {
  const double t = y / (std::abs(x) + std::abs(y));
  if (x < 0.0) return 2.0 - t;
  return t >= 0.0 ? t : 4.0 + t;
}

/// Intersects the sorted disjoint intervals cur[0, nc) of [0, full] with the arc from s round to
/// e (through full, that is 0, when s > e) into next, at most `room` of them; `touching`: keep
/// the intervals of a single point. Returns their count.
int intersect_arc(const std::array<double, 2>* cur, int nc, double s, double e, double full, bool touching,
                  std::array<double, 2>* next, int room) {
  std::array<double, 2> arc[2];
  int na = 0;
  if (s < e) {
    arc[na++] = {s, e};
  } else {
    arc[na++] = {0.0, e};
    arc[na++] = {s, full};
  }
  int nn = 0;
  for (int a = 0; a < na; ++a)
    for (int j = 0; j < nc; ++j) {
      const double lo = std::max(cur[j][0], arc[a][0]), hi = std::min(cur[j][1], arc[a][1]);
      if ((touching ? hi >= lo : hi > lo) && nn < room) next[nn++] = {lo, hi};
    }
  return nn;
}

}  // namespace

/// True only when no angle satisfies every constraint (then allowed_intervals(hs, n) is empty):
/// the intersection of each constraint's arc, grown by a margin far above the rounding of either
/// computation, is empty. Without trigonometry: each arc's ends by its half-angle's cosine and
/// sine, ordered by pseudo-angle. A constraint it cannot judge safely is left out (that only adds
/// angles): an arc narrower than the margin allows for, an amplitude whose square would lose
/// precision or overflow. False when unsure, and for many constraints: allowed_intervals decides.
bool surely_empty(const Harmonic* hs, int n) {
  constexpr double kMargin = 1e-9;  // pseudo-angle, at least 1e-9 rad: rounding is ~1e-13 here
  constexpr double kNarrow = 1e-6;  // cos of the half-angle within this of +1 (an arc under
                                    // 2.8e-3 rad) or of -1 (nearly the whole circle)
  if (n + 1 > kSmall) return false;  // one interval more per arc at most
  std::array<double, 2> buf[2][kSmall];
  std::array<double, 2>*cur = buf[0], *next = buf[1];
  int nc = 0;
  cur[nc++] = {0.0, 4.0};
  for (int i = 0; i < n; ++i) {
    const Harmonic& h = hs[i];
    if (h.k1 == 0.0 && h.k2 == 0.0) {
      if (h.k0 > 0.0) return true;  // nowhere, as allowed_intervals finds too
      continue;
    }
    // Below about 2^-511 the squares' sum is subnormal and the root loses digits (too small an A
    // would narrow the arc), so 2^-450 keeps a wide margin; above 2^512 the sum overflows.
    // allowed_intervals uses hypot.
    const double A = std::sqrt(h.k1 * h.k1 + h.k2 * h.k2);
    if (!(A >= 0x1p-450) || !(A <= 0x1p510)) continue;
    const double c = h.k0 / A;  // allowed within the half-angle acos(c) of the direction -(k1, k2)
    if (c <= -1.0 + kNarrow) continue;  // (nearly) everywhere: leaving it out only adds angles
    if (c >= 1.0 + kNarrow) return true;  // k0 > A: nowhere
    if (c >= 1.0 - kNarrow) continue;  // too narrow to judge with the margin: left out
    const double mx = -h.k1 / A, my = -h.k2 / A, sn = std::sqrt((1.0 - c) * (1.0 + c));
    // The arc from the middle turned back by the half-angle to it turned on by it.
    double s = pseudo_angle(c * mx + sn * my, c * my - sn * mx) - kMargin;
    double e = pseudo_angle(c * mx - sn * my, c * my + sn * mx) + kMargin;
    if (s < 0.0) s += 4.0;
    if (e >= 4.0) e -= 4.0;
    const int nn = intersect_arc(cur, nc, s, e, 4.0, true, next, kSmall);
    if (nn == 0) return true;
    std::swap(cur, next);
    nc = nn;
  }
  return false;
}

/// The closed intervals of [0, 2 pi) (an interval may run past 2 pi when it wraps) where every
/// constraint holds. Each constraint allows one arc of the circle (or all of it, or at most a
/// point): the intersection of those arcs, as sorted disjoint intervals of [0, 2 pi].
std::vector<std::array<double, 2>> allowed_intervals(const Harmonic* hs, int n) {
  std::vector<std::array<double, 2>> out;
  // A constraint that holds nowhere (k0 > its amplitude) empties the set: checked first, cheaply.
  for (int i = 0; i < n; ++i) {
    const Harmonic& h = hs[i];
    if (h.k0 > 0.0 && h.k0 * h.k0 > (h.k1 * h.k1 + h.k2 * h.k2) * (1.0 + 1e-12)) return out;
  }
  // 2 n + 2 intervals suffice: on the stack up to kSmall, beyond on the heap.
  const int room = 2 * n + 2;
  std::array<double, 2> small[2][kSmall];
  std::vector<std::array<double, 2>> large(room > kSmall ? 2 * static_cast<std::size_t>(room) : 0);
  std::array<double, 2>* cur = room > kSmall ? large.data() : small[0];
  std::array<double, 2>* next = room > kSmall ? large.data() + room : small[1];
  int nc = 0;
  cur[nc++] = {0.0, kTwoPi};
  // Into [0, 2 pi): t = phi +- dphi lies in [-2 pi, 2 pi], where one turn taken off its
  // magnitude is exact (Sterbenz) and gives std::fmod(t, 2 pi) bit for bit, a zero's sign
  // included.
  auto wrap = [](double t) {
    if (t >= kTwoPi) t -= kTwoPi;
    else if (t <= -kTwoPi) t = -(-t - kTwoPi);
    return t < 0.0 ? t + kTwoPi : t;
  };
  for (int i = 0; i < n && nc > 0; ++i) {
    const Harmonic& h = hs[i];
    const double A = std::hypot(h.k1, h.k2);
    if (!(A > 0.0) || h.k0 <= -A) {
      if (h.k0 > 0.0) return out;  // no amplitude, and positive: nowhere
      continue;                    // everywhere
    }
    if (h.k0 >= A) return out;  // at most the point where cos = -1
    // Allowed where cos(t - phi) <= -k0 / A: from phi + dphi round to phi - dphi (+ 2 pi).
    const double phi = std::atan2(h.k2, h.k1), dphi = std::acos(std::clamp(-h.k0 / A, -1.0, 1.0));
    const double s = wrap(phi + dphi), e = wrap(phi - dphi);
    if (s == e) continue;  // all but one point
    const int nn = intersect_arc(cur, nc, s, e, kTwoPi, false, next, room);
    std::copy(next, next + nn, cur);
    nc = nn;
  }
  for (int j = 0; j < nc; ++j) {
    if (!out.empty() && out.back()[1] == cur[j][0]) out.back()[1] = cur[j][1];
    else out.push_back(cur[j]);
  }
  if (out.size() >= 2 && out.front()[0] == 0.0 && out.back()[1] == kTwoPi) {
    out.back()[1] = kTwoPi + out.front()[1];
    out.erase(out.begin());
  }
  return out;
}

}  // namespace hugger
