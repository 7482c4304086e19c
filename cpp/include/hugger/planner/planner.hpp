/// \file planner.hpp
/// The Hugger algorithm (Reznik & Lumelsky 1994; docs/algorithm.md) as an iterator.
#pragma once

#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hugger/geometry/bvh.hpp"
#include "hugger/hand/hand_model.hpp"
#include "hugger/planner/snake.hpp"
#include "hugger/sensing/sensing.hpp"
#include "hugger/types.hpp"

namespace hugger {

enum class TipState : std::int8_t { kFrozen = 0, kContact = 1, kDone = 2 };
/// How a plan ends: kDone every finger DONE; kStalled nothing can move any more although some
/// finger is not DONE (the plan never repeats an unchanged configuration); kMaxIterations the
/// bound on Phase 2 iterations; kTimeout the wall-clock limit of plan().
enum class Status : std::int8_t { kRunning = 0, kDone = 1, kMaxIterations = 2, kTimeout = 3, kStalled = 4 };
std::string to_string(Status s);

/// The rule set of Phase 2 (docs/algorithm.md). kPaper: the paper's rules with the documented
/// decisions, nothing more (the reference of the 1994 method). kHug: those plus extensions for
/// firmer grasps: touching fingers yield, so the palm advances a full (clipped) step while any
/// finger touches; no finger is DONE while the hand moves; after palm contact, fingers close the
/// joints beyond their distal-most contact (all joints, for a finger that never touched) until
/// they touch, clinging.
enum class Rules : std::int8_t { kPaper = 0, kHug = 1 };
std::string to_string(Rules r);
/// "paper" or "hug"; throws std::invalid_argument for any other name.
Rules rules_from_string(const std::string& name);

/// Largest max_iterations accepted (a plan that long would take hours).
constexpr long kMaxIterations = 1000000000;
/// The most configurations Phase 1's turn, or the approach before any contact, may take: each is
/// one step s of the hand (about 2 KB of history), and each is made within one call, whatever the
/// timeout. A start that needs more is refused (start nearer, or take a larger step).
constexpr long kMaxIncrements = 100000;

/// Planner parameters. NaN selects the documented default; any other value must be positive.
struct PlannerParams {
  double step = std::numeric_limits<double>::quiet_NaN();   ///< fingertip step s (m); default: shortest link / 20
  double epsilon = std::numeric_limits<double>::quiet_NaN();  ///< overextension threshold (m); default: step / 10
  double contact_tolerance = std::numeric_limits<double>::quiet_NaN();  ///< sensing distance delta (m); default kDefaultContactTolerance
  static constexpr double kDefaultContactTolerance = 1e-4;  ///< the default sensing distance delta (m)
  /// contact_tolerance, or the default where it is NaN (not checked: the Planner refuses a bad one).
  double contact_tolerance_or_default() const {
    return std::isnan(contact_tolerance) ? kDefaultContactTolerance : contact_tolerance;
  }
  long max_iterations = 20000;     ///< bound on Phase 2 iterations, 1 .. kMaxIterations
  Rules rules = Rules::kHug;       ///< the rule set of Phase 2
};

/// Throws std::invalid_argument for a parameter no plan can use: a step, epsilon or
/// contact_tolerance that is neither NaN (the default) nor positive and finite, or max_iterations
/// outside 1 .. kMaxIterations. (How they relate to each other and to the hand, resolve_params checks.)
void check_params(const PlannerParams& params);
/// `params` with their defaults resolved for `hand` (step: the shortest link / 20; epsilon:
/// step / 10; contact_tolerance), checked against it: step <= the shortest link,
/// contact_tolerance < step, epsilon <= step (std::invalid_argument otherwise). What a Planner of
/// this hand plans with; callable before any plan (a batch of plans is checked up front).
PlannerParams resolve_params(const HandModel& hand, const PlannerParams& params);

/// Throws std::invalid_argument, saying what is wrong, unless `target` is a finite point within
/// kMaxCoordinate of the origin: the planner's rule for T (that T lies inside an Object is
/// check_target's, where the planner has one).
void check_target_point(const Vec3& target);
/// A wall-clock limit for Planner::plan given by a caller: positive and finite seconds (plan
/// itself takes kInf for no limit). Throws std::invalid_argument otherwise; returns `seconds`.
double check_timeout(double seconds);

/// One hand configuration (docs/model.md).
struct Configuration {
  Pose palm = Pose::Identity();   ///< T_WP
  std::vector<Vec3> joints;       ///< M*(N+1) points in the world, finger-major
  MatrixX angles;                 ///< M x N joint angles (rad)
  std::vector<TipState> tip_state;///< per finger, after this configuration
  int phase = 0;                  ///< 0 for C_init, then 1 or 2
  long iteration = 0;             ///< index of this configuration in the plan
};

/// Counters of one plan, for inspection and benchmarks.
struct PlannerStats {
  long phase1_configurations = 0;
  long phase2_iterations = 0;
  long first_contact_iteration = -1;  ///< Phase 2 iteration of the first touch (-1: none yet)
  long palm_contact_iteration = -1;   ///< Phase 2 iteration at which the palm touched
  long sigma_retries = 0;             ///< palm steps refused (each step asked and refused counts)
  long finger_collisions = 0;         ///< fingers stopped by another finger or themselves
  long clinging_failures = 0;         ///< fingers stopped because no free link position was found
  long motion_rejections = 0;         ///< finger moves refused: a joint would move > 4 s, or the swept motion collides
  long approach_configurations = 0;   ///< configurations emitted by the approach before the first contact
  long fingers_opened = 0;            ///< hug rule H5: iterations in which a finger turned its root joint back
  long reclose_steps = 0;             ///< hug rule H5: steps closing an opened finger's root joint again
};

/// The search of hug rule H5's opening (Planner::open_step) over the candidates 0..count-1, in
/// order of preference: coarse to fine. It asks candidate 0, every stride-th (>= 1) after it and
/// the last; past the first of those that passes, it asks the ones skipped before it in turn,
/// and takes the first of them that passes, else that one. `passes(k)` asks candidate k and
/// leaves its result in the caller's slot; before the skipped ones are asked, `keep()` sets the
/// slot's result aside, and `restore()` brings it back when none of them passes, so that the slot
/// holds the result of the candidate returned. Returns that candidate, or -1 when none of those
/// asked passes. No candidate is asked twice. Where the candidates that pass form one run holding
/// a candidate asked first (a run of stride or more, or one reaching the last), the one returned
/// is the first that passes; a shorter run between two of those is missed.
template <class Passes, class Keep, class Restore>
int coarse_to_fine(int count, int stride, Passes&& passes, Keep&& keep, Restore&& restore) {
  int failed = -1;  // the last candidate asked that failed
  for (long long c = 0;; c += stride) {  // (wide: c passes the last candidate by up to 2 strides)
    const int k = c < count - 1 ? static_cast<int>(c) : count - 1;
    if (k <= failed) return -1;  // the last has failed (or there is none)
    if (!passes(k)) {
      failed = k;
      continue;
    }
    if (k > failed + 1) {
      keep();
      for (int j = failed + 1; j < k; ++j)
        if (passes(j)) return j;
      restore();
    }
    return k;
  }
}

class Planner {
 public:
  /// Checks the inputs and plans Phase 1, then hands the skin the finger planes of Phase 2
  /// (Sensing::prepare: the section skin builds their regions, a few milliseconds on its
  /// threads; what it throws, such as std::bad_alloc, propagates from here). Throws
  /// std::invalid_argument when the palm pose is not rigid, a parameter is out of range, or the
  /// hand touches O at C_init or during Phase 1.
  Planner(HandModel hand, std::shared_ptr<const Sensing> sensing, const Vec3& target, const Pose& palm_pose,
          PlannerParams params = {});

  /// The next configuration, or nothing when the plan has ended.
  std::optional<Configuration> step();
  /// Configuration k of the plan, planning on until it exists; nothing when the plan ends before
  /// it. step() goes on after it. (The Python binding hands out configurations by their index, so
  /// that one whose delivery a signal's exception cut short is handed out again.)
  std::optional<Configuration> configuration(std::size_t k);
  /// Runs one Phase 2 iteration and appends its configurations to history() (step() hands them
  /// out later): one, several for the approach before the first contact (each palm step <= s),
  /// none for an iteration that ends the plan because nothing could move. Returns false, doing
  /// nothing, once the plan has ended.
  bool advance();
  /// Runs to the end; returns the final status. With a finite `timeout` (seconds, > 0) the plan
  /// stops with Status::kTimeout once that much wall-clock time has passed since the call: the
  /// deadline is checked before every Phase 2 iteration, so the history stays a valid (partial)
  /// trajectory and the overrun is at most one iteration (Phase 1 and the skin's preparation,
  /// done by the constructor, are not counted). A timed-out plan has ended for good.
  /// Throws std::invalid_argument when `timeout` is NaN or not positive.
  /// `pause`, when given, is asked before every Phase 2 iteration too: true stops the call there
  /// with the plan still running (a later call goes on from there, as if never stopped).
  Status plan(double timeout = kInf, const std::function<bool()>& pause = {});

  Status status() const { return status_; }
  bool finished() const { return status_ != Status::kRunning && next_ >= history_.size(); }
  const std::vector<Configuration>& history() const { return history_; }
  /// The finger planes of Phase 2, one per finger, fixed where Phase 1 leaves the palm.
  const std::vector<FingerPlane>& planes() const { return planes_; }
  const HandModel& hand() const { return hand_; }
  const PlannerParams& params() const { return params_; }
  const PlannerStats& stats() const { return stats_; }
  const Vec3& target() const { return target_; }

 private:
  void plan_phase1(const Pose& start);
  void check_clear(const Configuration& c, const char* when) const;
  Configuration make_configuration(int phase) const;
  void phase2_iteration();
  bool chain_free(int m, const Chain& chain) const;
  /// Finger m's propagation settings with the palm's front at `front`; `stop_folding`: Tail2Head
  /// stops at a link that comes within finger_separation() of its own chain (the caller refuses
  /// such a chain).
  SnakeRequest snake_request(int m, double front, bool stop_folding = false) const;
  /// Clinging's resolution (m of link-end motion): an eighth of the sensing distance.
  double snake_tolerance() const { return params_.contact_tolerance / 8.0; }
  /// Finger m's root in its plane with the palm moved eta along p.
  Vec2 root2d(int m, double eta) const;
  /// The approach before any contact (decision 1): translate by the free distance, emitting as
  /// many configurations (each <= s) as that takes. Returns false when the hand could not move.
  bool approach();
  /// The largest t in [0, sigma] (from a grid of samples) such that chain m translated by every
  /// t' <= t along p stays clear of O (it may stay in contact): the palm step a DONE finger allows.
  double translation_free(int m, const Chain& chain, double sigma) const;
  /// The motion old -> next of finger m (root moved by d_eta, joint angles interpolated
  /// linearly, as a robot executes it) keeps every joint within 4 s and is collision-free.
  /// `turned` (N entries, or nullptr): tail_to_head's for next, the links known to rest on O;
  /// given, next is tail_to_head's chain, every link of it found free.
  bool motion_ok(int m, const Chain& old, const Chain& next, const char* turned = nullptr) const;
  /// A link sampled on such a motion: clear of O, or into it by at most a quarter of the
  /// collision tolerance.
  bool swept_link_ok(int m, const Vec2& a, const Vec2& b) const;
  /// Hug rule: one close-until-contact step of finger m (every joint distal to the proximal-most
  /// touching link flexes). Returns false when it cannot flex any more.
  bool close_step(int m, Chain& chain) const;
  /// Hug rule H4: sigma clipped to the distance the palm, the FROZEN fingers and the roots may
  /// translate along p staying clear of O (sampled; at least their gaps allow).
  double free_along_p(const Pose& palm, double palm_gap, double sigma);
  /// Hug rule H5: finger m, which cannot follow the palm to new_eta otherwise, opens: its root
  /// joint turns back (extension) by a sampled angle at which Tail2Head from the moved root finds
  /// a free chain (into `out`) whose motion is allowed and which clears the other fingers, the
  /// angles asked coarse to fine (coarse_to_fine, with planner.cpp's kOpenStride). Returns false
  /// when none of the angles asked passes (`out` is then unspecified).
  bool open_step(int m, const Chain& old, double new_eta, const std::vector<Chain>& others, Chain& out);
  /// Hug rule H5: one step of closing finger m's root joint again after it opened (Tail2Head
  /// clinging for the rest). Returns false when the finger moves less than epsilon or the motion
  /// rules or the `others` fingers refuse the step.
  bool reclose_step(int m, Chain& chain, const std::vector<Chain>& others) const;
  /// Chain m clears itself (links not next to each other, in its plane) and the `others`
  /// fingers (in the world) by finger_separation(). `placed` (or nullptr): the request
  /// Tail2Head placed the chain with; where it refused folds by finger_separation() or more
  /// (snake_request's stop_folding), the chain clears itself and is not asked again.
  bool fingers_clear(int m, const Chain& chain, const std::vector<Chain>& others,
                     const SnakeRequest* placed = nullptr) const;
  /// How far apart two links of the hand must stay: two link radii (at least 0.1 µm).
  double finger_separation() const;
  /// HandModel::planar_angles of finger m's `chain`, bit for bit, remembered for the last two
  /// chains of each finger (the one it holds and the one tried last): the motion check and the
  /// configuration ask about the same chains in turn. Valid until the next call for finger m.
  const double* chain_angles(int m, const Chain& chain) const;
  std::vector<double> joint_angles(int m, const Chain& chain) const;  ///< chain_angles, copied
  /// Finger k's `chain` in the world (its plane's to_world of each joint, bit for bit) and their
  /// box, remembered for the chain asked last: fingers_clear asks about the other fingers'
  /// chains, which mostly stay as they were, and about the finger's own candidate, which once
  /// accepted is what the fingers after it are tested against. Valid until the next call for
  /// finger k.
  struct WorldChain {
    Chain chain;
    std::vector<Vec3> joints;
    Aabb box;
  };
  const WorldChain& chain_in_world(int k, const Chain& chain) const;
  /// plane_pair of the finger planes m and k of Phase 2, at pairs_[m * M + k]: fingers_clear's
  /// first test.
  std::vector<PlanePair> pairs_;
  double pairs_slack_ = 0.0;  ///< planes_keep_apart's slack: the world test's rounding, bounded
  double link_gap(int m, const Vec2& a, const Vec2& b, double cap) const;
  /// Remembers CONTACT finger m's chain of this iteration, the palm still, and returns for how
  /// many iterations running the finger has come back to within epsilon (every joint) of one of
  /// its last kCycleMemory chains (0: somewhere new).
  int note_chain(int m, const Chain& chain);
  /// Forgets finger m's remembered chains (the palm moved, or the finger starts closing).
  void forget_chains(int m);
  /// Starts finger m's overextension window and cycle memory afresh, its tip at `tip`.
  void restart_windows(int m, const Vec2& tip);
  /// Sensing::contact_gap of finger m's link [a, b] at the contact tolerance: at most that
  /// tolerance exactly when the link touches O.
  double contact_gap(int m, const Vec2& a, const Vec2& b, double cap) const;
  /// A lower bound of the gap (`contact`: of the contact gap) of a part that moves rigidly with the
  /// palm: FROZEN finger m's link n, or (n == N) finger m's root, as a sphere, in any state; exact
  /// when at most `need`: from the bound kept since the last query when that exceeds `need`.
  double rigid_gap(int m, int n, double need, bool contact = false);
  /// The first of finger m's parts n (as rigid_gap's) that move rigidly with the palm, to N: every
  /// link and the root while the finger is FROZEN, else its root alone (a root moves with the palm
  /// whatever its finger's state).
  int first_rigid_part(int m) const { return states_[m] == TipState::kFrozen ? 0 : hand_.links(); }
  /// A part's lasting gap bound `lb` (a FROZEN link's, a root's, the palm's: parts that move
  /// rigidly with the palm): `lb` while above `need`, else `ask(cap)` with a cap of kGapFarSteps steps (at
  /// least `need`), kept as the new bound (capped: above the cap only a value above it is known).
  template <class Ask>
  double lasting_gap(double& lb, double need, Ask&& ask) const;
  /// The palm (and the FROZEN fingers and the roots with it) moved `moved` along p: every lasting
  /// bound drops by as much.
  void lower_lasting_gaps(double moved);

  HandModel hand_;
  std::shared_ptr<const Sensing> sensing_;
  Vec3 target_;
  PlannerParams params_;
  Status status_ = Status::kRunning;
  std::vector<Configuration> history_;
  std::size_t next_ = 0;  ///< next configuration step() hands out
  PlannerStats stats_;

  // Phase 2 state: each finger lives in a fixed plane; the palm has moved eta_ along p.
  Pose palm2_ = Pose::Identity();  ///< palm pose when Phase 2 started
  std::vector<FingerPlane> planes_;
  std::vector<Chain> chains_;
  std::vector<TipState> states_;
  std::vector<Vec2> anchors_;  ///< per finger, where its tip was when it last made progress
  std::vector<int> stalled_;   ///< per finger, iterations since then
  std::vector<std::vector<Chain>> recent_chains_;  ///< note_chain: per finger, its last chains, the palm still
  std::vector<std::size_t> recent_next_;           ///< note_chain: per finger, the oldest once full
  std::vector<int> cycle_repeats_;                 ///< note_chain: per finger, returns running
  /// Per finger, N + 1 lower bounds of the gaps of its links while it is FROZEN and of its root
  /// in every state (they move rigidly with the palm: each palm step sigma lowers them by sigma),
  /// then as many of their contact gaps. -inf: unknown.
  std::vector<double> rigid_lb_;
  /// A lower bound of the palm's gap, lowered by each palm step as rigid_lb_ (-inf: unknown).
  double palm_lb_ = -kInf;
  double eta_ = 0.0;
  /// How far the palm may advance along p before anything is felt: until its front plane reaches
  /// T. T lies inside O, so the palm touches O first; a skin whose object is elsewhere (a
  /// displaced object, a wrong T) would otherwise let the hand approach forever.
  double eta_target_ = kInf;
  bool palm_touched_ = false;
  bool any_contact_ = false;
  /// The last iteration asked a palm step and took none (the hand blocked by its fingers): the
  /// next iteration asks the shortest step first. An iteration that asks none clears it.
  bool steps_refused_ = false;
  bool felt_ = false;  ///< some part of the hand has sensed O (a FROZEN finger or the palm touched)
  std::vector<char> closing_;  ///< hug rule: per finger, closing until contact
  std::vector<char> closed_;   ///< hug rule: per finger, has closed (or is closing) once
  std::vector<char> opened_;   ///< hug rule: per finger, opened to yield and not closed again yet
  std::vector<char> reclosing_;  ///< hug rule: per finger, closing again at rest before palm contact
  /// chain_angles' memory: per finger, two chains (bits compared) and their joint angles.
  struct AngleMemo {
    Chain chain[2];
    std::vector<double> angles[2];
    int last = 0;  ///< the slot used last; a new chain takes the other
  };
  mutable std::vector<AngleMemo> angle_memo_;
  mutable std::vector<WorldChain> world_memo_;  ///< chain_in_world's memory, per finger
  /// phase2_iteration's new chains and states, kept between iterations for their room.
  struct Scratch {
    std::vector<Chain> cand, next;
    std::vector<TipState> next_states;
    Chain chain;
    Chain kept;                      ///< open_step: a coarse angle's chain that passed, while finer ones are tried
    std::vector<double> open_angles;  ///< open_step: its sampled angles
  };
  Scratch scratch_;
};

}  // namespace hugger
