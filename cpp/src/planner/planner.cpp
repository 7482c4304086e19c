#include "hugger/planner/planner.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "hugger/check.hpp"
#include "hugger/geometry/bvh.hpp"
#include "hugger/geometry/distance.hpp"
#include "hugger/geometry/frame.hpp"
#include "hugger/planner/snake.hpp"

namespace hugger {

std::string to_string(Status s) {
  switch (s) {
    case Status::kRunning: return "running";
    case Status::kDone: return "done";
    case Status::kMaxIterations: return "max_iterations";
    case Status::kTimeout: return "timeout";
    case Status::kStalled: return "stalled";
  }
  return "unknown";
}

std::string to_string(Rules r) { return r == Rules::kPaper ? "paper" : "hug"; }

Rules rules_from_string(const std::string& name) {
  if (name == "paper") return Rules::kPaper;
  if (name == "hug") return Rules::kHug;
  throw std::invalid_argument("rules must be one of 'paper', 'hug', got '" + name + "'");
}

namespace {

/// Largest flexion (rad) of the distal joint that a free swing (decision 5) may reach.
constexpr double kMaxSwingFlexion = kPi / 2.0;
/// Iterations a CONTACT tip may stay within 2 steps of one place before it counts as overextended.
constexpr int kStallWindow = 20;
/// How many of a finger's last chains, the palm still, are remembered to recognise a cycle (of at
/// most this many iterations).
constexpr std::size_t kCycleMemory = 64;
/// No joint may move more than this many steps s in one Phase 2 iteration (a little under the
/// checker's 4, for rounding).
constexpr double kMaxJointSteps = 4.0 * (1.0 - 1e-6);
/// Hug rule H5's opening search asks every kOpenStride-th of its sampled angles first.
constexpr int kOpenStride = 3;
/// A clinging rotation turns a link by at most this many s / L (radians): larger turns are jumps.
constexpr double kMaxClingSteps = 8.0;
/// Hug rule: a joint closing until contact flexes at most to this angle (rad).
constexpr double kMaxCloseFlexion = kPi / 2.0;
/// Lasting gap bounds (the FROZEN fingers', the palm's) ask their gaps up to this many steps s:
/// a bound beyond what is needed lasts several palm steps.
constexpr double kGapFarSteps = 4.0;


[[noreturn]] void invalid(const std::string& what) { throw std::invalid_argument(what); }

std::string fmt(double x) {
  std::ostringstream os;
  os << x;
  return os.str();
}

/// A parameter checked by check_params: its value, or `fallback` for NaN (the default).
double resolve(double value, double fallback) { return std::isnan(value) ? fallback : value; }

/// The largest distance a joint moves from chain `a` to chain `b` (of the same size).
double largest_move(const Chain& a, const Chain& b) {
  double moved = 0.0;
  for (std::size_t n = 0; n < a.size(); ++n) moved = std::max(moved, (b[n] - a[n]).norm());
  return moved;
}

/// The distance of a chain's farthest joint from its root (joint 0).
double farthest_joint(const Chain& c) {
  double dist = 0.0;
  for (std::size_t n = 1; n < c.size(); ++n) dist = std::max(dist, (c[n] - c[0]).norm());
  return dist;
}

}  // namespace

PlannerParams resolve_params(const HandModel& hand, const PlannerParams& params) {
  check_params(params);
  PlannerParams out = params;
  double shortest = kInf;
  for (int m = 0; m < hand.fingers(); ++m)
    for (int n = 0; n < hand.links(); ++n) shortest = std::min(shortest, hand.link_length(m, n));
  out.step = resolve(params.step, shortest / 20.0);
  HUGGER_CHECK_ARGUMENT(out.step <= shortest, "step (" << out.step << " m) must not exceed the shortest link ("
                                                       << shortest << " m)");
  out.contact_tolerance = params.contact_tolerance_or_default();
  // Links of 2 mm or less meet the defaults' limit: say which were defaults, and what to give.
  const bool defaulted = std::isnan(params.step) && std::isnan(params.contact_tolerance);
  HUGGER_CHECK_ARGUMENT(out.contact_tolerance < out.step,
                        "contact_tolerance (" << out.contact_tolerance << " m) must be smaller than step ("
                                              << out.step << " m)"
                                              << (defaulted ? " (defaults: step the shortest link / 20, "
                                                              "contact_tolerance 1e-4 m; give a smaller "
                                                              "contact_tolerance for links this short)"
                                                            : ""));
  out.epsilon = resolve(params.epsilon, out.step / 10.0);
  HUGGER_CHECK_ARGUMENT(out.epsilon <= out.step,
                        "epsilon (" << out.epsilon << " m) must not exceed step (" << out.step << " m)");
  return out;
}

void check_target_point(const Vec3& target) {
  HUGGER_CHECK_ARGUMENT(target.allFinite(), "target must be a finite 3-vector, got (" << target.x() << ", "
                                                                                     << target.y() << ", " << target.z() << ")");
  HUGGER_CHECK_ARGUMENT(target.cwiseAbs().maxCoeff() <= kMaxCoordinate,
                        "target lies beyond " << kMaxCoordinate << " m of the origin (where an object's coordinates may lie)");
}

Planner::Planner(HandModel hand, std::shared_ptr<const Sensing> sensing, const Vec3& target, const Pose& palm_pose,
                 PlannerParams params)
    : hand_(std::move(hand)), sensing_(std::move(sensing)), target_(target), params_(params) {
  HUGGER_CHECK_ARGUMENT(sensing_, "the planner needs a sensing interface");
  check_target_point(target_);
  params_ = resolve_params(hand_, params);
  check_pose(palm_pose.matrix(), "palm_pose");
  // Re-orthonormalise so that every emitted pose is rigid to machine precision.
  const Mat3 R = palm_pose.linear();
  Pose start = Pose::Identity();
  start.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  start.translation() = palm_pose.translation();
  HUGGER_CHECK_ARGUMENT((target_ - start.translation()).norm() > 1e-9, "target coincides with the palm origin P_o");
  plan_phase1(start);
}

void Planner::check_clear(const Configuration& c, const char* when) const {
  const double delta = params_.contact_tolerance;
  const int N = hand_.links();
  for (int m = 0; m < hand_.fingers(); ++m)
    for (int n = 0; n < N; ++n) {
      const Touch t = sensing_->capsule(c.joints[hand_.joint_index(m, n)], c.joints[hand_.joint_index(m, n + 1)], hand_.link_radius(), delta);
      // A gap of -r or less is no depth: the skins answer a link whose axis enters O with -r (or
      // -inf where it lies wholly inside), and a skin may answer NaN, refused too.
      if (!(t.gap > delta))
        invalid(std::string("the hand touches or penetrates the object ") + when + ": link " + std::to_string(n) +
                " of finger " + std::to_string(m) +
                (std::isnan(t.gap)                      ? std::string(" has no gap (NaN)")
                 : t.gap <= -hand_.link_radius()        ? std::string("'s axis enters it")
                                                        : " has a gap of " + fmt(t.gap) + " m") +
                "; start the palm farther from the object");
    }
  const double pg = sensing_->palm(c.palm, hand_.palm_radius(), hand_.palm_thickness(), delta);
  if (!(pg > delta))
    invalid(std::string("the palm touches, penetrates or lies inside the object ") + when +
            (std::isfinite(pg) ? " (gap " + fmt(pg) + " m)" : std::string()) +
            "; start the palm farther from the object");
}

void Planner::plan_phase1(const Pose& start) {
  const MatrixX& rest = hand_.rest();  // FROZEN = at rest (all 0: straight along the palm normal)
  auto extended = [&](const Pose& palm, int phase) {
    Configuration c;
    c.palm = palm;
    c.joints = hand_.forward(palm, rest);
    c.angles = rest;
    c.tip_state.assign(hand_.fingers(), TipState::kFrozen);
    c.phase = phase;
    c.iteration = static_cast<long>(history_.size());
    return c;
  };
  history_.push_back(extended(start, 0));
  check_clear(history_.back(), "at the start (C_init)");
  const Vec3 p = start.linear().col(2), t = target_ - start.translation();
  const Vec3 axis_raw = p.cross(t);
  const double alpha = std::atan2(axis_raw.norm(), p.dot(t));
  if (alpha > 1e-12) {
    const Vec3 axis = axis_raw.norm() > 1e-12 * t.norm() ? Vec3(axis_raw.normalized()) : Vec3(start.linear().col(0));
    const double increments = std::ceil(alpha * hand_.extended_radius() / params_.step);  // before any cast
    if (!(increments <= static_cast<double>(kMaxIncrements)))
      invalid("Phase 1 would need more than " + std::to_string(kMaxIncrements) +
              " increments: the step is too small for this hand");
    const long n = std::max(1L, static_cast<long>(increments));
    for (long k = 1; k <= n; ++k) {
      Pose palm = start;
      palm.linear() = Eigen::AngleAxisd(alpha * static_cast<double>(k) / static_cast<double>(n), axis).toRotationMatrix() *
                      start.linear();
      history_.push_back(extended(palm, 1));
      const std::string when = "during Phase 1 (reorientation, increment " + std::to_string(k) + " of " +
                               std::to_string(n) + ")";
      check_clear(history_.back(), when.c_str());
    }
    stats_.phase1_configurations = n;
  }
  // Phase 2 state: each finger in its plane, fixed in the world while the palm translates.
  palm2_ = history_.back().palm;
  eta_target_ = std::max(0.0, (target_ - palm2_.translation()).dot(palm2_.linear().col(2)));
  // The approach advances at most to T, a step s at a time (approach()).
  if (eta_target_ / params_.step > static_cast<double>(kMaxIncrements))
    invalid("the approach would need more than " + std::to_string(kMaxIncrements) + " steps: the palm is " +
            fmt(eta_target_) + " m from T along its normal, with a step of " + fmt(params_.step) +
            " m; start nearer the object or take a larger step");
  for (int m = 0; m < hand_.fingers(); ++m) {
    planes_.push_back(hand_.plane(palm2_, m));
    chains_.push_back(hand_.rest_chain(m));  // the rim hand's rest is straight: (R, 0), (R, L0), ...
  }
  // fingers_clear's first test: the lines where the finger planes meet, and a bound on the
  // rounding of the world test it spares (the scale of the world coordinates and of the planes'
  // signed distances in Phase 2: the planes' origins, the hand's reach, the approach to T, the
  // lines' offsets).
  const int M = hand_.fingers();
  pairs_.assign(static_cast<std::size_t>(M) * M, PlanePair());
  double scale = 0.0, offsets = 0.0;
  for (int m = 0; m < M; ++m) {
    scale = std::max(scale, planes_[m].origin.cwiseAbs().maxCoeff());
    for (int k = 0; k < M; ++k) {
      if (k == m) continue;
      PlanePair& pp = pairs_[static_cast<std::size_t>(m) * M + k];
      pp = plane_pair(planes_[m], planes_[k]);
      offsets = std::max(offsets, std::abs(pp.offset));
    }
  }
  pairs_slack_ = 64.0 * std::numeric_limits<double>::epsilon() *
                 (scale + offsets + hand_.extended_radius() + std::abs(eta_target_));
  states_.assign(hand_.fingers(), TipState::kFrozen);
  anchors_.assign(hand_.fingers(), Vec2(kInf, kInf));
  recent_chains_.assign(hand_.fingers(), {});
  recent_next_.assign(hand_.fingers(), 0);
  cycle_repeats_.assign(hand_.fingers(), 0);
  stalled_.assign(hand_.fingers(), 0);
  rigid_lb_.assign(2 * static_cast<std::size_t>(hand_.fingers()) * (hand_.links() + 1), -kInf);
  palm_lb_ = -kInf;
  closing_.assign(hand_.fingers(), 0);
  angle_memo_.assign(hand_.fingers(), AngleMemo());
  world_memo_.assign(hand_.fingers(), WorldChain());
  closed_.assign(hand_.fingers(), 0);
  opened_.assign(hand_.fingers(), 0);
  reclosing_.assign(hand_.fingers(), 0);
  // The finger planes are fixed from here on: a hint that lets a skin build its per-plane
  // structures now, as setup, so that Phase 2's iterations (streamed one by one) carry none of it.
  sensing_->prepare(planes_, hand_.link_radius());
}

Vec2 Planner::root2d(int m, double eta) const {
  return Vec2(hand_.root2d(m).x(), eta);  // the root on the palm's front face, moved eta along p
}

namespace {

/// (cos x, sin x): their Taylor series for |x| <= 0.1 (the first term left out is below 1e-22;
/// the motion check's turns between samples are at most max(r, s) / 4 over a link's length,
/// 0.05 rad on the default hand, unless its sample count is clamped), else the library's.
Vec2 cos_sin(double x) {
  if (!(std::abs(x) <= 0.1)) return Vec2(std::cos(x), std::sin(x));
  const double x2 = x * x;
  const double sin = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0 * (1.0 - x2 / 110.0)))));
  const double cos =
      1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0 * (1.0 - x2 / 90.0 * (1.0 - x2 / 132.0)))));
  return Vec2(cos, sin);
}

/// The same chain to the bit (the memories' test: chains that differ only in a zero's sign can
/// give different angles and points).
bool same_chain_bits(const Chain& x, const Chain& y) {
  return x.size() == y.size() && (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(Vec2)) == 0);
}

}  // namespace

const double* Planner::chain_angles(int m, const Chain& chain) const {
  AngleMemo& memo = angle_memo_[static_cast<std::size_t>(m)];
  for (int k : {memo.last, 1 - memo.last}) {
    const Chain& c = memo.chain[k];
    if (same_chain_bits(c, chain)) {
      memo.last = k;
      return memo.angles[k].data();
    }
  }
  // The angles first, the chain last: a slot whose angles failed to fit holds an empty chain,
  // which matches no chain asked (a finger's chains are never empty).
  const int k = 1 - memo.last;
  memo.chain[k].clear();
  memo.angles[k].resize(chain.empty() ? 0 : chain.size() - 1);
  HandModel::planar_angles(chain, memo.angles[k].data());
  memo.chain[k] = chain;
  memo.last = k;
  return memo.angles[k].data();
}

const Planner::WorldChain& Planner::chain_in_world(int k, const Chain& chain) const {
  WorldChain& w = world_memo_[static_cast<std::size_t>(k)];
  if (!chain.empty() && same_chain_bits(w.chain, chain)) return w;
  w.chain.clear();  // matches no chain until the joints are in
  w.joints.resize(chain.size());
  w.box = Aabb();
  for (std::size_t n = 0; n < chain.size(); ++n) w.box.grow(w.joints[n] = planes_[k].to_world(chain[n]));
  w.chain = chain;
  return w;
}

std::vector<double> Planner::joint_angles(int m, const Chain& chain) const {
  const double* angles = chain_angles(m, chain);
  return std::vector<double>(angles, angles + hand_.links());
}

Configuration Planner::make_configuration(int phase) const {
  Configuration c;
  c.palm = palm2_;
  c.palm.translation() += eta_ * palm2_.linear().col(2);
  const int M = hand_.fingers(), N = hand_.links();
  c.joints.reserve(M * (N + 1));
  c.angles.resize(M, N);
  for (int m = 0; m < M; ++m) {
    for (const Vec2& x : chains_[m]) c.joints.push_back(planes_[m].to_world(x));
    // A FROZEN or DONE finger moves only rigidly with the palm: from one configuration to the
    // next in the same one of those states it keeps its angles bit for bit (recomputed from the
    // translated joints they could differ by rounding), its rest angles while FROZEN, those it
    // had when it became DONE. (A FROZEN finger that becomes DONE may have touched and moved
    // within the iteration.)
    const TipState st = states_[m];
    if ((st == TipState::kFrozen || st == TipState::kDone) && !history_.empty() &&
        history_.back().tip_state[m] == st)
      c.angles.row(m) = history_.back().angles.row(m);
    else
      std::copy_n(chain_angles(m, chains_[m]), N, c.angles.row(m).data());
  }
  c.tip_state = states_;
  c.phase = phase;
  c.iteration = static_cast<long>(history_.size());
  return c;
}

double Planner::link_gap(int m, const Vec2& a, const Vec2& b, double cap) const {
  return sensing_->link(planes_[m], a, b, hand_.link_radius(), cap).gap;
}

int Planner::note_chain(int m, const Chain& chain) {
  std::vector<Chain>& seen = recent_chains_[m];
  const bool back = std::any_of(seen.begin(), seen.end(),
                                [&](const Chain& c) { return largest_move(c, chain) < params_.epsilon; });
  if (seen.size() < kCycleMemory) {
    seen.push_back(chain);
  } else {  // in place of the oldest
    seen[recent_next_[m]] = chain;
    recent_next_[m] = (recent_next_[m] + 1) % kCycleMemory;
  }
  cycle_repeats_[m] = back ? cycle_repeats_[m] + 1 : 0;
  return cycle_repeats_[m];
}

void Planner::forget_chains(int m) {
  recent_chains_[m].clear();
  recent_next_[m] = 0;
  cycle_repeats_[m] = 0;
}

void Planner::restart_windows(int m, const Vec2& tip) {
  anchors_[m] = tip;
  stalled_[m] = 0;
  forget_chains(m);
}

double Planner::contact_gap(int m, const Vec2& a, const Vec2& b, double cap) const {
  return sensing_->contact_gap(planes_[m], a, b, hand_.link_radius(), params_.contact_tolerance, cap);
}

template <class Ask>
double Planner::lasting_gap(double& lb, double need, Ask&& ask) const {
  if (lb > need) return lb;
  // Asked with a wider cap than needed, so that the bound lasts several palm steps.
  const double cap = std::max(need, kGapFarSteps * params_.step);
  lb = std::min(ask(cap), cap);  // beyond the cap the answer is only known to be above it
  return lb;
}

void Planner::lower_lasting_gaps(double moved) {
  for (double& lb : rigid_lb_) lb -= moved + 1e-12;  // a picometre for rounding
  palm_lb_ -= moved + 1e-12;
}

double Planner::rigid_gap(int m, int n, double need, bool contact) {
  const std::size_t parts = static_cast<std::size_t>(hand_.fingers()) * (hand_.links() + 1);
  double& lb = rigid_lb_[(contact ? parts : 0) + static_cast<std::size_t>(m) * (hand_.links() + 1) + n];
  if (lb > need) return lb;
  const Chain& c = chains_[m];
  const Vec2 &a = n < hand_.links() ? c[n] : c[0], &b = n < hand_.links() ? c[n + 1] : c[0];
  if (contact) {
    // Exact up to `need`, which decides contact.
    lb = sensing_->contact_gap_bound(planes_[m], a, b, hand_.link_radius(), params_.contact_tolerance, need,
                                     kGapFarSteps * params_.step);
    return lb;
  }
  return lasting_gap(lb, need, [&](double cap) { return link_gap(m, a, b, cap); });
}

SnakeRequest Planner::snake_request(int m, double front, bool stop_folding) const {
  SnakeRequest req;
  // A chain that folds onto itself, refused by the caller anyway: Tail2Head stops at the link
  // that does (fingers_clear's self-test).
  if (stop_folding) req.self_separation = finger_separation();
  req.plane = planes_[m];
  req.lengths = hand_.link_lengths().row(m).data();
  req.radius = hand_.link_radius();
  req.front = front;
  req.tolerance = snake_tolerance();
  double shortest = kInf;
  for (int n = 0; n < hand_.links(); ++n) shortest = std::min(shortest, hand_.link_length(m, n));
  req.sample_angle = std::min(0.1, params_.step / (2.0 * shortest));
  req.max_rotation = std::min(kPi, kMaxClingSteps * params_.step / shortest);
  // Both chains start outside O: the head is a point whose gap was sensed (follow_boundary,
  // rotate_until_touch) or the old tip; the root is the old root or one moved by sigma, which
  // is clipped to the root's free distance (its lasting bound: for an object that holds still
  // between queries, as the palm's and the FROZEN fingers' bounds assume).
  req.start_outside = true;
  if (hand_.has_limits()) {
    req.lower = hand_.lower().row(m).data();
    req.upper = hand_.upper().row(m).data();
  }
  return req;
}

double Planner::finger_separation() const { return std::max(2.0 * hand_.link_radius(), 1e-7); }

bool Planner::fingers_clear(int m, const Chain& chain, const std::vector<Chain>& others,
                            const SnakeRequest* placed) const {
  const int M = hand_.fingers(), N = hand_.links();
  const double sep = finger_separation();
  const double sep2 = sep * sep;
  const bool self_clear = placed != nullptr && placed->self_separation >= sep;
  // The finger against itself within its plane (an isometric copy of the world's), then the
  // others: first by the line where their planes meet, else in the world (where its chain is
  // remembered too: accepted, it is the chain the fingers after it are tested against).
  for (int b = 2; b < N && !self_clear; ++b)
    if (!link_clear_of_chain(chain.data(), b, sep)) return false;
  const WorldChain* mine = nullptr;
  for (int k = 0; k < M; ++k) {
    if (k == m) continue;
    // Two fingers either of which keeps away from the line where their planes meet are apart.
    // The bound decides only with a margin above the rounding of the test in the world, which
    // would find those links apart too: the same answers, without world coordinates.
    if (planes_keep_apart(pairs_[static_cast<std::size_t>(m) * M + k], chain.data(), N + 1,
                          pairs_[static_cast<std::size_t>(k) * M + m], others[k].data(), N + 1, sep, pairs_slack_))
      continue;
    if (mine == nullptr) mine = &chain_in_world(m, chain);
    const WorldChain& theirs = chain_in_world(k, others[k]);
    if (mine->box.squared_distance(theirs.box) >= sep2) continue;  // the fingers' boxes are apart
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b)
        if (segment_segment_squared(mine->joints[a], mine->joints[a + 1], theirs.joints[b], theirs.joints[b + 1]) <
            sep2)
          return false;
  }
  return true;
}

double Planner::translation_free(int m, const Chain& chain, double sigma) const {
  if (!(sigma > 0.0)) return 0.0;
  const int N = hand_.links();
  const double r = hand_.link_radius(), level = 0.5 * params_.contact_tolerance;
  // Samples no farther apart than a quarter of max(r, s): between two clear samples a link
  // sliding on O can dip into it only by a sagitta far below the collision tolerance.
  const double h = std::max(r, params_.step) / 4.0;
  const int S = std::max(1, static_cast<int>(std::ceil(sigma / h - 1e-9)));
  double best = sigma;
  for (int n = 0; n < N && best > 0.0; ++n) {
    // A link whose gap exceeds the translation (plus the sensing level) cannot reach O.
    if (link_gap(m, chain[n], chain[n + 1], sigma + params_.contact_tolerance) - level >= best) continue;
    for (int i = 1; i <= S; ++i) {
      const double t = sigma * static_cast<double>(i) / S;
      if (t > best) break;
      const Vec2 d(0.0, t);
      if (!sensing_->link_free(planes_[m], chain[n] + d, chain[n + 1] + d, r, -kInf, false)) {
        best = sigma * static_cast<double>(i - 1) / S;
        break;
      }
    }
  }
  return best;
}

bool Planner::swept_link_ok(int m, const Vec2& a, const Vec2& b) const {
  // A straight line in joint space between two configurations that rest on O dips into it by
  // a sagitta of micrometres; a quarter of the collision tolerance (docs/validation.md:
  // max(2% of r, 0.05 mm)) is allowed there, and no more.
  const double r = hand_.link_radius();
  return sensing_->link_depth_within(planes_[m], a, b, r, 0.25 * std::max(0.02 * r, 5e-5));
}

bool Planner::motion_ok(int m, const Chain& old, const Chain& next, const char* turned) const {
  const int N = hand_.links();
  const double s = params_.step, r = hand_.link_radius();
  if (largest_move(old, next) > kMaxJointSteps * s) return false;
  // On the stack: this runs for every finger that moves, in every iteration (and a skin's
  // callback may plan on this thread meanwhile). chain_angles' memory is shared across calls,
  // but its answers are copied out at once and a hit is the same chain bit for bit.
  std::array<double, kMaxLinks> a0, a1;
  std::copy_n(chain_angles(m, old), N, a0.data());
  std::copy_n(chain_angles(m, next), N, a1.data());
  // How far any joint can move along the straight line in joint space (as the checker bounds it).
  const double d_root = (next[0] - old[0]).norm();
  double cum = 0.0, reach = 0.0, bound = d_root;
  // Link n moves no farther than its distal joint, by at most D_n; a link whose gap at the new
  // configuration is at least D_n is clear all along (the gap shrinks no faster than the link
  // moves), and is not sampled. A link that clinging left resting on O has a gap of at most the
  // clinging tolerance: below a D_n of twice that without asking. (Sampling a link that needed
  // none changes no answer: its samples are clear.)
  const double rest_gap = 2.0 * snake_tolerance();
  // A chain Tail2Head made (`turned` given) has every link found free: its joints lie outside O.
  const bool joints_outside = turned != nullptr;
  std::array<double, kMaxLinks> D, swing;  // swing[n]: how far link n turns (its joints' steps summed)
  for (int n = 0; n < N; ++n) {
    swing[n] = cum += a1[n] - a0[n];
    reach += hand_.link_length(m, n) * std::abs(cum);
    D[n] = d_root + reach;
    bound = std::max(bound, D[n]);
  }
  const double h = std::max(r, s) / 4.0;
  // (Clamped before the cast: a bound beyond INT_MAX samples would not fit an int.)
  const int S = static_cast<int>(std::clamp(std::ceil(bound / h - 1e-9), 1.0, 128.0));
  // No sample between the ends (checked as configurations): no link needs asking.
  if (S == 1) return true;
  int last = -1;  // the distal-most link sampled
  std::array<char, kMaxLinks> sample;  // (set for every link below)
  for (int n = 0; n < N; ++n) {
    sample[n] = (turned != nullptr && turned[n] && D[n] > rest_gap) ||
                sensing_->link_gap_below(planes_[m], next[n], next[n + 1], r, D[n], joints_outside);
    if (sample[n]) last = n;
  }
  if (last < 0) return true;
  // Along the line in joint space every link turns at a constant rate: between two samples link
  // n turns by the same angle, its swing over S. Each link's direction is turned by that
  // rotation from sample to sample, starting from its direction in `old`, rather than computed
  // afresh from the interpolated angles (a sine and a cosine per link and sample).
  // The samples then lie within a few units of rounding of the checker's, far below the depth
  // allowed at them.
  std::array<Vec2, kMaxLinks> dir, turn;  // link n's direction at the sample; its turn (cos, sin)
  for (int n = 0; n <= last; ++n) {
    dir[n] = (old[n + 1] - old[n]) / hand_.link_length(m, n);
    turn[n] = cos_sin(swing[n] / S);
  }
  std::array<Vec2, kMaxLinks + 1> c;  // the joints up to the last sampled link's end
  for (int i = 1; i < S; ++i) {
    const double t = static_cast<double>(i) / S;
    c[0] = old[0] + t * (next[0] - old[0]);
    for (int n = 0; n <= last; ++n) {
      dir[n] = rotate_planar(dir[n], turn[n].x(), turn[n].y());
      c[n + 1] = c[n] + hand_.link_length(m, n) * dir[n];
    }
    for (int n = 0; n <= last; ++n)
      if (sample[n] && !swept_link_ok(m, c[n], c[n + 1])) return false;
  }
  return true;
}

bool Planner::close_step(int m, Chain& chain) const {
  const int N = hand_.links();
  const double s = params_.step, delta = params_.contact_tolerance, r = hand_.link_radius();
  int first = 0;  // the first joint that may flex: distal to the distal-most touching link
  for (int n = N - 1; n >= 0; --n)
    if (contact_gap(m, chain[n], chain[n + 1], delta) <= delta) {
      first = n + 1;
      break;
    }
  if (first >= N) return false;  // the distal link touches: closing is over
  const std::vector<double> a = joint_angles(m, chain);
  // Flexing joints first..N-1 by d moves the tip by at most d * sum_k L_k (k - first + 1).
  double lever = 0.0;
  for (int k = first; k < N; ++k) lever += hand_.link_length(m, k) * (k - first + 1);
  double d = 2.0 * s / lever;
  for (int tries = 0; tries < 8; ++tries, d *= 0.5) {
    std::vector<double> b = a;
    bool moved = false;
    for (int k = first; k < N; ++k) {
      // Flex at most to kMaxCloseFlexion and to the joint's upper limit.
      const double inc = std::clamp(std::min(kMaxCloseFlexion, hand_.upper()(m, k)) - a[k], 0.0, d);
      b[k] += inc;
      moved = moved || inc > 1e-12;
    }
    if (!moved) return false;
    const Chain c = hand_.forward_planar(m, chain[0], b.data());
    bool free = true;
    for (int n = first; n < N && free; ++n) free = sensing_->link_free(planes_[m], c[n], c[n + 1], r, chain[0].y(), false);
    if (free) {
      chain = c;
      return true;
    }
  }
  return false;
}

bool Planner::open_step(int m, const Chain& old, double new_eta, const std::vector<Chain>& others, Chain& out) {
  const double s = params_.step;
  // The joint angles of each angle's chain: the old chain's, its root joint turned back by phi.
  std::vector<double> b = joint_angles(m, old);
  const double root_angle = b[0];
  // The root joint may open to the palm's front plane and its lower limit.
  const double lowest = std::max(-kPi / 2.0, hand_.lower()(m, 0));
  const double dist = farthest_joint(old);
  if (!(dist > 0.0)) return false;
  const double d_eta = new_eta - old[0].y();
  const double budget = kMaxJointSteps * s - d_eta;  // a joint moves at most rotation + the root's step
  if (!(budget > 0.0)) return false;
  const double max_turn = budget / dist, inc = 0.25 * s / dist;
  const Vec2 root = root2d(m, new_eta);
  SnakeRequest req = snake_request(m, new_eta, true);  // a folding chain is refused below
  req.fold_early = true;  // most chains tried here fold (on the cylinder 124 of 212)
  // The sampled angles in turn (each the last plus inc, as the search has always summed them), up
  // to the lower limit: at most 15, the farthest joint moving a quarter of s per angle.
  std::vector<double>& phis = scratch_.open_angles;
  phis.clear();
  for (double phi = inc; phi <= max_turn + 1e-12 && root_angle - phi >= lowest - kLimitSlack; phi += inc)
    phis.push_back(phi);
  const int count = static_cast<int>(phis.size());
  // Each angle's chain is made in `out`'s room (the caller's scratch), not in a new vector.
  auto passes = [&](int k) {
    b[0] = root_angle - phis[k];
    hand_.forward_planar(m, root, b.data(), &out);
    std::array<char, kMaxLinks> turned;
    if (!tail_to_head(*sensing_, req, root, out, turned.data())) return false;
    // The cheap test first: a chain that hits a finger needs no motion check.
    return fingers_clear(m, out, others, &req) && motion_ok(m, old, out, turned.data());
  };
  // Coarse to fine (coarse_to_fine): the angle found is the first that passes wherever those that
  // pass form one run holding an angle asked first. Most searches measured pass at the first
  // angle or at none. A coarse angle's chain waits in the scratch while finer ones are tried.
  Chain& kept = scratch_.kept;
  return coarse_to_fine(count, kOpenStride, passes, [&] { kept.swap(out); }, [&] { out.swap(kept); }) >= 0;
}

bool Planner::reclose_step(int m, Chain& chain, const std::vector<Chain>& others) const {
  const double s = params_.step;
  const std::vector<double> a = joint_angles(m, chain);
  const double dist = farthest_joint(chain);
  if (!(dist > 0.0)) return false;
  const double top = std::min(kMaxCloseFlexion, hand_.upper()(m, 0));
  const double inc = std::min(2.0 * s / dist, top - a[0]);
  if (!(inc > 1e-9)) return false;
  std::vector<double> b = a;
  b[0] += inc;
  Chain c = hand_.forward_planar(m, chain[0], b.data());
  std::array<char, kMaxLinks> turned;
  const SnakeRequest req = snake_request(m, chain[0].y(), true);
  if (!tail_to_head(*sensing_, req, chain[0], c, turned.data())) return false;
  if (largest_move(chain, c) < params_.epsilon) return false;
  // A step the motion rules or the other fingers would refuse ends the closing here, so that the
  // ordinary rules move the finger in this same iteration.
  if (!fingers_clear(m, c, others, &req) || !motion_ok(m, chain, c, turned.data())) return false;
  chain = std::move(c);
  return true;
}

double Planner::free_along_p(const Pose& palm, double palm_gap, double sigma) {
  const int M = hand_.fingers(), N = hand_.links();
  const double s = params_.step, delta = params_.contact_tolerance, level = 0.5 * delta, r = hand_.link_radius();
  const double cap = s + delta;
  // Samples no farther apart than a quarter of max(r, s) (as translation_free); from the last
  // clear sample a part may still move its gap there minus the level.
  const double h = std::max(r, s) / 4.0;
  auto along = [&](double g0, const auto& gap_at) {
    if (g0 - level >= sigma) return;
    const int S = std::max(1, static_cast<int>(std::ceil(sigma / h - 1e-9)));
    double t0 = 0.0, g = g0;
    for (int i = 1; i <= S; ++i) {
      const double t = sigma * static_cast<double>(i) / S;
      const double gt = gap_at(t);
      if (gt < level) break;
      t0 = t;
      g = gt;
    }
    sigma = std::min(sigma, t0 + std::max(0.0, g - level));
  };
  const Vec3 p = palm.linear().col(2);
  along(palm_gap, [&](double t) {
    Pose q = palm;
    q.translation() += t * p;
    return sensing_->palm(q, hand_.palm_radius(), hand_.palm_thickness(), cap);
  });
  const Vec2 up(0.0, 1.0);
  // The parts that move rigidly with the palm: their lasting bounds (rigid_gap) stand for gaps
  // beyond the cap.
  for (int m = 0; m < M && sigma > 0.0; ++m) {
    const Chain& c = chains_[m];
    for (int n = first_rigid_part(m); n <= N && sigma > 0.0; ++n) {
      const Vec2 a = n < N ? c[n] : c[0], b = n < N ? c[n + 1] : c[0];
      along(rigid_gap(m, n, cap), [&](double t) { return link_gap(m, a + t * up, b + t * up, cap); });
    }
  }
  return sigma;
}

bool Planner::approach() {
  const int M = hand_.fingers(), N = hand_.links();
  const double s = params_.step, level = 0.5 * params_.contact_tolerance;
  Pose palm = palm2_;
  palm.translation() += eta_ * palm2_.linear().col(2);
  // The exact free distance of the extended fingers and the palm (each gap bounds how far that
  // part can translate before it touches O). Each gap is asked only up to the smallest so far:
  // beyond that cap a gap is reported as some value above the cap, which leaves the minimum as it
  // is. The palm last, as its query in space is the costliest: not at all while its lasting
  // bound shows it farther than the fingers, else capped at the larger of the fingers' minimum
  // and kGapFarSteps steps (above that cap neither the minimum nor the bound changes). Its bound
  // is held to kGapFarSteps steps, as the FROZEN fingers' are: a skin's object may move between
  // iterations (closed loop), and a bound that lasts longer assumes more.
  double free = kInf;
  for (int m = 0; m < M; ++m) {
    const Chain& c = chains_[m];
    for (int n = 0; n < N; ++n) free = std::min(free, link_gap(m, c[n], c[n + 1], free));
  }
  if (!(palm_lb_ > free)) {
    const double palm_gap =
        sensing_->palm(palm, hand_.palm_radius(), hand_.palm_thickness(), std::max(free, kGapFarSteps * s));
    free = std::min(free, palm_gap);
    palm_lb_ = std::min(palm_gap, kGapFarSteps * s);
  }
  // Never past T (eta_target_): with nothing sensed ahead, the hand advances to T in one iteration.
  const double total = std::min(free - level, eta_target_ - eta_);
  if (!(total >= s) || !std::isfinite(total)) return false;  // within a step of O or T: the regular iteration lands
  const long pieces = static_cast<long>(std::ceil(total / s - 1e-12));
  const double eta0 = eta_;
  for (long k = 1; k <= pieces; ++k) {
    const double eta = k == pieces ? eta0 + total : eta0 + total * static_cast<double>(k) / static_cast<double>(pieces);
    const double d = eta - eta_;
    for (Chain& c : chains_)
      for (Vec2& x : c) x.y() += d;
    eta_ = eta;
    history_.push_back(make_configuration(2));
  }
  lower_lasting_gaps(total);
  stats_.approach_configurations += pieces;
  return true;
}

void Planner::phase2_iteration() {
  const int M = hand_.fingers(), N = hand_.links();
  const double s = params_.step, delta = params_.contact_tolerance, level = 0.5 * delta;
  const double r = hand_.link_radius();
  const bool hug = params_.rules == Rules::kHug;
  const long it = stats_.phase2_iterations;
  // A FROZEN finger becomes CONTACT (palm contact, or the hand blocked); under the hug rules it
  // never touched O, so it closes all its joints until it touches.
  auto release = [&](std::vector<TipState>& st, int m) {
    if (st[m] != TipState::kFrozen) return;
    st[m] = TipState::kContact;
    closing_[m] = hug;
    closed_[m] = hug;
  };

  // Decision 1: before any contact the hand advances by its free distance in one iteration.
  if (!any_contact_ && !palm_touched_ && approach()) {
    ++stats_.phase2_iterations;
    if (stats_.phase2_iterations >= params_.max_iterations) status_ = Status::kMaxIterations;
    return;
  }
  Pose palm = palm2_;
  palm.translation() += eta_ * palm2_.linear().col(2);

  // (a) contact sensing: a FROZEN finger touched anywhere becomes CONTACT (decision 4).
  for (int m = 0; m < M; ++m) {
    if (states_[m] != TipState::kFrozen) continue;
    for (int n = 0; n < N; ++n)
      if (rigid_gap(m, n, delta, true) <= delta) {
        states_[m] = TipState::kContact;
        felt_ = true;
        break;
      }
  }
  double palm_gap = kInf;
  if (!palm_touched_) {
    // Only a gap up to s + delta decides anything below (contact, and the palm step's bound):
    // the palm's lasting bound stands for it above that.
    palm_gap = lasting_gap(palm_lb_, s + delta, [&](double cap) {
      return sensing_->palm(palm, hand_.palm_radius(), hand_.palm_thickness(), cap);
    });
    if (palm_gap <= delta) {
      palm_touched_ = true;
      felt_ = true;
      stats_.palm_contact_iteration = it;
    }
  }
  if (palm_touched_)  // decision 3: the palm stops for good; every finger closes
    for (int m = 0; m < M; ++m) release(states_, m);
  for (auto st : states_)
    if (st != TipState::kFrozen && !any_contact_) any_contact_ = true;  // felt, or released at T (below)
  if (felt_ && stats_.first_contact_iteration < 0) stats_.first_contact_iteration = it;

  // (b) FollowBoundary and Head2Tail for every CONTACT finger (hug rule: a finger that never
  // touched closes until it touches instead).
  // chains_ holds the old chains until the end of the iteration. The new ones are made in the
  // planner's scratch, whose chains are copied into the room they have: a plan makes no
  // allocation per iteration for them. The flags, one per finger, live on the stack.
  Scratch& w = scratch_;
  const std::vector<Chain>& old = chains_;
  w.cand = chains_;
  std::vector<Chain>& cand = w.cand;
  std::array<char, kMaxFingers> touching{};  // the finger touches O (not closing)
  std::array<char, kMaxFingers> prefer_open{};
  for (int m = 0; m < M; ++m) {
    if (states_[m] != TipState::kContact) continue;
    if (closing_[m]) {
      if (close_step(m, cand[m])) continue;
      closing_[m] = 0;  // a link at the tip touches, or no joint can flex: the ordinary rules take over
    }
    touching[m] = 1;
    if (hug && opened_[m] && (palm_touched_ || reclosing_[m])) {
      // Hug rule H5: a finger that opened to let the palm land closes its root joint again once
      // the palm has landed, or once the hand is at rest without it.
      if (reclose_step(m, cand[m], old)) {
        ++stats_.reclose_steps;
        continue;
      }
      opened_[m] = 0;
      reclosing_[m] = 0;
    }
    const Vec2 tip = old[m][N];
    Vec2 head = tip;
    if (contact_gap(m, tip, tip, delta) <= delta) {
      FollowRequest fr;
      fr.plane = planes_[m];
      fr.tip = tip;
      fr.radius = r;
      fr.step = s;
      fr.level = level;
      // H within reach of the root where the palm step may take it this iteration (sigma <= s).
      const Vec2 rm = root2d(m, eta_);
      fr.root = palm_touched_ ? rm : Vec2(rm.x(), rm.y() + s);
      fr.reach = hand_.finger_length(m);
      fr.front = eta_;
      head = sensing_->follow_boundary(fr).head;
      // Hug rule H5: a tip whose slide would take it toward the palm (a face that faces the
      // palm, uphill) opens the finger instead while the palm advances.
      prefer_open[m] = hug && head.y() < tip.y() - 1e-3 * s;  // not by rounding on a face along p
    } else {
      RotateRequest rr;
      rr.plane = planes_[m];
      rr.pivot = old[m][N - 1];
      rr.end = tip;
      rr.radius = r;
      rr.front = eta_;
      // The distal joint flexes at most to kMaxSwingFlexion: a finger that swings free of O
      // stops there (its tip then moves less than epsilon and it becomes DONE).
      const double flexion = relative_angle(old[m], N - 1, old[m][N] - old[m][N - 1]);
      // ... and never beyond the distal joint's upper limit.
      const double reach = std::min(kMaxSwingFlexion, hand_.upper()(m, N - 1));
      rr.max_angle = std::clamp(reach - flexion, 0.0, s / hand_.link_length(m, N - 1));
      rr.touch_gap = delta;
      rr.level = level;
      head = sensing_->rotate_until_touch(rr).end;
    }
    if (!head_to_tail(*sensing_, snake_request(m, eta_), head, cand[m])) {
      cand[m] = old[m];
      ++stats_.clinging_failures;
    }
  }

  // (c) the palm step sigma, clipped to [0, s] and to the free distance of the palm, the FROZEN
  // fingers, the roots and the DONE fingers (which move only rigidly with the palm).
  double sigma = 0.0;
  const double min_sigma = 1e-2 * delta;  // smaller palm steps are rounding, not motion
  if (!palm_touched_) {
    const bool none_in_contact =
        std::none_of(states_.begin(), states_.end(), [](TipState t) { return t == TipState::kContact; });
    if (none_in_contact) {
      sigma = s;  // decision 1: approach until a touch (also once every touching finger is DONE)
    } else if (hug) {
      // Every touching finger yields (it bends, clinging, as the palm advances), so the palm
      // advances a full step, clipped below like the paper's (and by the fingers' motion).
      for (int m = 0; m < M; ++m)
        if (states_[m] == TipState::kContact && touching[m]) sigma = s;
    } else {
      for (int m = 0; m < M; ++m)
        if (states_[m] == TipState::kContact) sigma += (cand[m][0].y() - eta_) / M;
      sigma = std::clamp(sigma, 0.0, s);
    }
    if (sigma > 0.0) {
      double free = palm_gap;
      const double cap = s + delta;
      // Bounds above the cap change nothing: sigma <= s < cap - level.
      for (int m = 0; m < M; ++m)
        for (int n = first_rigid_part(m); n <= N; ++n) free = std::min(free, rigid_gap(m, n, cap));
      if (hug && free - level < sigma) {
        // Hug rule H4: each part may move its free distance along p, not only its gap (a part
        // beside O, moving nearly parallel to its surface, would otherwise crawl).
        sigma = free_along_p(palm, palm_gap, sigma);
      } else {
        sigma = std::min(sigma, std::max(0.0, free - level));
      }
      // Until something is felt the palm stops with its front plane at T: there the hand is
      // blocked (below) and the FROZEN fingers close. (With T inside O the free distance is the
      // smaller; after a touch, an object that moved in simulation may be followed past T.)
      if (!felt_) sigma = std::min(sigma, std::max(0.0, eta_target_ - eta_));
      for (int m = 0; m < M && sigma > 0.0; ++m)
        if (states_[m] == TipState::kDone) sigma = translation_free(m, old[m], sigma);
      // Steps below a hundredth of delta are rounding, not motion (they would crawl forever).
      if (sigma < min_sigma) sigma = 0.0;
    }
  }

  // (d) Tail2Head toward the moved roots; commit finger by finger, checking the motion of each
  // finger (joint steps, swept collision) and the fingers against each other. If anything fails
  // with the palm moved, retry with a shorter palm step, and finally with the palm still.
  std::array<char, kMaxFingers> opened_now{};
  auto attempt = [&](double sig, std::vector<Chain>& out, std::vector<TipState>& st) {
    const bool last = sig == 0.0;  // the palm still: what cannot move stays where it is, DONE
    opened_now.fill(0);
    out = old;
    st = states_;
    const double new_eta = eta_ + sig;
    for (int m = 0; m < M; ++m) {
      Chain& c = w.chain;
      bool checked = false;  // c was found clear of the other fingers and itself, against `out`
      switch (st[m]) {
        case TipState::kFrozen:
        case TipState::kDone:  // rigidly with the palm: the joint angles do not change
          c = old[m];
          for (Vec2& x : c) x.y() += sig;
          break;
        case TipState::kContact: {
          // Its Head2Tail chain re-attached to the moved root; failing that (clinging finds no
          // free position, a joint would jump, the swept motion collides), the old chain
          // re-attached: the finger only yields to the palm step this iteration.
          // Hug rule H5: a touching finger whose tip would slide toward the palm, or that can
          // follow no other way, opens (its root joint turns back) while the palm advances.
          const bool may_open = hug && !last && !palm_touched_ && touching[m] && !closing_[m];
          bool ok = may_open && prefer_open[m] && open_step(m, old[m], new_eta, out, c);
          bool opened = ok;  // open_step checks the fingers itself
          std::array<char, kMaxLinks> turned;  // Tail2Head's turned links, for the motion check
          // Hug rule: a chain that would hit another finger or itself while the palm moves is
          // refused like one whose motion collides (the old chain re-attached is tried next).
          // Tested first, as the cheaper: a chain refused so needs no motion check. A chain
          // that folds onto itself is refused as Tail2Head places it (the same chains pass).
          const bool refuse_folds = hug && !last;
          const SnakeRequest req = snake_request(m, new_eta, refuse_folds);
          for (int pass = 0; pass < 2 && !ok; ++pass) {
            if (pass == 1 && (sig == 0.0 || cand[m] == old[m])) break;  // the same chain again
            c = pass == 0 ? cand[m] : old[m];
            bool folded = false;
            ok = tail_to_head(*sensing_, req, root2d(m, new_eta), c, turned.data(), &folded);
            if (!ok) ++(folded ? stats_.finger_collisions : stats_.clinging_failures);
            if (ok && refuse_folds) {
              checked = fingers_clear(m, c, out, &req);
              if (!checked) {
                ok = false;
                ++stats_.finger_collisions;
              }
            }
            if (ok && !motion_ok(m, old[m], c, turned.data())) {
              ok = false;
              checked = false;
              ++stats_.motion_rejections;
            }
          }
          if (!ok && may_open && !prefer_open[m]) ok = opened = open_step(m, old[m], new_eta, out, c);
          if (opened) {
            opened_now[m] = 1;
            checked = true;
          }
          if (!ok) {
            if (!last) return false;
            c = old[m];  // last: sig == 0, the old chain is still attached to its root
            st[m] = TipState::kDone;
            checked = false;
          }
          break;
        }
      }
      if (!checked && !fingers_clear(m, c, out)) {
        if (!last) return false;
        c = old[m];
        for (Vec2& x : c) x.y() += sig;
        st[m] = TipState::kDone;
        ++stats_.finger_collisions;
      }
      std::swap(out[m], c);  // c keeps out[m]'s room for the next finger
    }
    return true;
  };
  std::vector<Chain>& next = w.next;
  std::vector<TipState>& next_states = w.next_states;
  bool committed = false;
  // After an iteration that refused every palm step, the shortest step is asked first: refused
  // again, the hand is still blocked and the longer ones are not asked (a longer step moves
  // every finger farther; asked anyway, none passed on any object measured, docs/performance-history.md).
  // Passed, the steps are asked from the longest as always (the shortest, asked again last if
  // need be, is the same attempt: its work and counters then come twice, rarely).
  bool still_blocked = false;
  if (steps_refused_ && sigma >= min_sigma) {
    double shortest = sigma;
    while (shortest * 0.25 >= min_sigma) shortest *= 0.25;  // the last step of the loop below
    if (shortest < sigma && !attempt(shortest, next, next_states)) {
      ++stats_.sigma_retries;
      still_blocked = true;
    }
  }
  for (double sig = sigma; sig >= min_sigma && !committed && !still_blocked; sig *= 0.25) {
    committed = attempt(sig, next, next_states);
    if (committed) sigma = sig;
    else ++stats_.sigma_retries;
  }
  steps_refused_ = !committed && sigma >= min_sigma;
  if (!committed) {
    sigma = 0.0;
    attempt(0.0, next, next_states);
  }
  for (int m = 0; m < M; ++m)
    if (opened_now[m]) {
      opened_[m] = 1;
      ++stats_.fingers_opened;
    }
  // Cycles (below) are looked for while the palm is still.
  if (sigma > 0.0)
    for (int m = 0; m < M; ++m) forget_chains(m);
  bool starts_closing = false;  // a finger starts closing: the next iteration moves it
  for (int m = 0; m < M; ++m) {
    if (next_states[m] != TipState::kContact) continue;
    if (closing_[m]) {  // a closing finger ends when it can flex no more (above)
      if (largest_move(old[m], next[m]) >= 1e-3 * params_.epsilon) continue;
      closing_[m] = 0;  // closing in steps this small is rounding, not motion: it has closed
      next_states[m] = TipState::kDone;
      continue;
    }
    // Paper: the tip moved less than epsilon. Hug: the hand is at rest (sigma = 0: while the
    // palm advances, no touching finger is done) and no joint of the finger moved epsilon.
    const double moved = hug ? largest_move(old[m], next[m]) : (next[m][N] - old[m][N]).norm();
    bool rest = moved < params_.epsilon && !(hug && sigma > 0.0);
    // Overextension over a window: a tip that oscillates (pulled off by Tail2Head, swung back)
    // without getting farther than 2 s from where it was kStallWindow iterations ago is DONE.
    if ((next[m][N] - anchors_[m]).norm() > 2.0 * s) {
      anchors_[m] = next[m][N];
      stalled_[m] = 0;
    } else if (++stalled_[m] >= kStallWindow) {
      rest = true;
    }
    // A cycle: with the palm still, the finger comes back to within epsilon (every joint) of one
    // of the last kCycleMemory chains it had since the palm stopped (or it last started closing),
    // kStallWindow iterations running. It goes round without getting anywhere (an oscillation
    // wider than the window's 2 s, which ends those within it first), so it is at rest.
    if (sigma == 0.0 && note_chain(m, next[m]) >= kStallWindow) rest = true;
    if (!rest) continue;
    if (hug && opened_[m] && !reclosing_[m] && !palm_touched_) {
      // Hug rule H5: an opened finger at rest with the palm off O closes again first.
      reclosing_[m] = 1;
      starts_closing = true;
      restart_windows(m, next[m][N]);
    } else if (hug && !closed_[m]) {
      // Hug rule: before it is DONE, a finger closes the joints beyond its distal-most touching
      // link until they touch too (close-until-contact, clinging), once.
      closing_[m] = 1;
      closed_[m] = 1;
      starts_closing = true;
      restart_windows(m, next[m][N]);
    } else {
      next_states[m] = TipState::kDone;
    }
  }
  // The hand is blocked (it cannot advance and no finger is sliding): the remaining FROZEN
  // fingers close, as on palm contact (decision 3).
  const bool blocked = sigma == 0.0 && std::none_of(next_states.begin(), next_states.end(),
                                                    [](TipState t) { return t == TipState::kContact; });
  if (blocked)
    for (int m = 0; m < M; ++m) release(next_states, m);
  ++stats_.phase2_iterations;
  // Never emit an unchanged configuration: when nothing moved and no state changed, nothing
  // can move any more.
  std::swap(chains_, next);  // old (chains_) is the new chains now; next keeps the old ones' room
  std::swap(states_, next_states);
  eta_ += sigma;
  lower_lasting_gaps(sigma);
  const bool all_done = std::all_of(states_.begin(), states_.end(), [](TipState t) { return t == TipState::kDone; });
  Configuration c = make_configuration(2);
  const Configuration& last = history_.back();
  const bool unchanged = c.palm.matrix() == last.palm.matrix() && c.joints == last.joints && c.tip_state == last.tip_state;
  if (unchanged) {
    // Nothing to emit. A finger that starts closing moves in the next iteration (at most once
    // per finger); otherwise nothing can move any more.
    if (starts_closing)
      status_ = stats_.phase2_iterations >= params_.max_iterations ? Status::kMaxIterations : Status::kRunning;
    else
      status_ = all_done ? Status::kDone : Status::kStalled;
    return;
  }
  history_.push_back(std::move(c));
  if (all_done)
    status_ = Status::kDone;
  else if (stats_.phase2_iterations >= params_.max_iterations)
    status_ = Status::kMaxIterations;
}

std::optional<Configuration> Planner::step() { return configuration(next_); }

std::optional<Configuration> Planner::configuration(std::size_t k) {
  while (k >= history_.size()) {  // an iteration that ends the plan may emit nothing
    if (status_ != Status::kRunning) return std::nullopt;
    phase2_iteration();
  }
  next_ = std::max(next_, k + 1);
  return history_[k];
}

bool Planner::advance() {
  if (status_ != Status::kRunning) return false;
  phase2_iteration();
  return true;
}

Status Planner::plan(double timeout, const std::function<bool()>& pause) {
  if (timeout != kInf) check_timeout(timeout);  // kInf: no limit
  using Clock = std::chrono::steady_clock;
  // Past ~292 years (or infinite) the duration would overflow; such a timeout is no timeout.
  const bool bounded = timeout < 9.0e9;
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(bounded ? timeout : 0.0));
  while (status_ == Status::kRunning) {
    if (bounded && Clock::now() >= deadline) {
      status_ = Status::kTimeout;
      break;
    }
    if (pause && pause()) break;
    phase2_iteration();
  }
  next_ = history_.size();
  return status_;
}

}  // namespace hugger
