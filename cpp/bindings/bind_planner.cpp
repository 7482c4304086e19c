// The planner and its typed results: PlannerParams, PlannerStats, Configuration and History (a
// plan's configurations as stacked arrays).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>

#include "common.hpp"
#include "hugger/planner/planner.hpp"
#include "hugger/world/object.hpp"
#include "hugger/world/section_skin.hpp"
#include "hugger/world/simulated_world.hpp"

namespace py = pybind11;
using namespace hugger;
using namespace hugger::py_helpers;

namespace {

/// PlannerStats' counters in their order: their Python attributes, and the JSON a trajectory
/// records (stats_json).
struct StatsField {
  const char* name;
  long PlannerStats::*member;
  const char* doc;
};
constexpr StatsField kStatsFields[] = {
    {"phase1_configurations", &PlannerStats::phase1_configurations, "Configurations of Phase 1"},
    {"phase2_iterations", &PlannerStats::phase2_iterations, "Phase 2 iterations"},
    {"first_contact_iteration", &PlannerStats::first_contact_iteration,
     "Phase 2 iteration of the first touch (-1: none yet)"},
    {"palm_contact_iteration", &PlannerStats::palm_contact_iteration,
     "Phase 2 iteration at which the palm touched (-1: none yet)"},
    {"sigma_retries", &PlannerStats::sigma_retries, "Palm steps refused (each step asked and refused counts)"},
    {"finger_collisions", &PlannerStats::finger_collisions, "Fingers stopped by another finger or themselves"},
    {"clinging_failures", &PlannerStats::clinging_failures, "Fingers stopped because no free link position was found"},
    {"motion_rejections", &PlannerStats::motion_rejections,
     "Finger moves refused: a joint would move > 4 s, or the swept motion collides"},
    {"approach_configurations", &PlannerStats::approach_configurations,
     "Configurations emitted by the approach before the first contact"},
    {"fingers_opened", &PlannerStats::fingers_opened,
     "Hug rule H5: iterations in which a finger turned its root joint back to let the palm land"},
    {"reclose_steps", &PlannerStats::reclose_steps, "Hug rule H5: steps closing an opened finger's root joint again"},
};

/// The counters as Python's json.dumps writes their dict: {"name": value, ...}, in order.
std::string stats_json(const PlannerStats& stats) {
  std::string out = "{";
  for (const StatsField& f : kStatsFields) {
    if (out.size() > 1) out += ", ";
    out += '"';
    out += f.name;
    out += "\": ";
    out += std::to_string(stats.*f.member);
  }
  return out + "}";
}

/// A planner with a lock: one thread at a time may advance it; others get a clear error.
struct PyPlanner {
  std::unique_ptr<Planner> planner;
  py::object source;  ///< the Object or Sensing given: keeps a Python skin (and its overrides) alive
  std::string skin = "section";  ///< how an Object is sensed: "mesh" (3D queries on the BVH) or "section" (2D per finger plane)
  std::mutex busy;
  /// An exception left the planner in the middle of an iteration (a skin's callback raised): the
  /// plan has ended with status "error"; history() holds every configuration completed before.
  bool failed = false;
  /// interrupt() asks a running plan() (in any thread) to stop as a Ctrl-C would.
  std::atomic<bool> interrupt{false};
};

/// How often plan() looks for a signal (Ctrl-C) while it runs with the GIL released.
constexpr std::chrono::milliseconds kSignalPoll{50};

/// Runs f (planner work); an exception ends the plan (status "error") and propagates unchanged.
template <class F>
auto guarded(PyPlanner& p, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (...) {
    p.failed = true;
    throw;
  }
}

std::string status_of(const PyPlanner& p) { return p.failed ? "error" : to_string(p.planner->status()); }

class Busy {
 public:
  explicit Busy(PyPlanner& p) : lock_(p.busy, std::try_to_lock) {
    if (!lock_.owns_lock()) throw std::runtime_error("this planner is already running (in another thread, or its own skin called it)");
  }

 private:
  std::unique_lock<std::mutex> lock_;
};

py::array_t<std::int8_t> states_array(const std::vector<TipState>& states) {
  py::array_t<std::int8_t> out(static_cast<py::ssize_t>(states.size()));
  std::int8_t* w = out.mutable_data();
  for (TipState s : states) *w++ = static_cast<std::int8_t>(s);
  return out;
}

/// A plan's configurations [start, stop) as stacked arrays (K configurations of M fingers, N links).
struct History {
  py::array_t<double> palm_pose, joints, angles;  ///< (K, 4, 4), (K, M, N+1, 3), (K, M, N)
  py::array_t<std::int8_t> tip_state, phase;      ///< (K, M), (K,)
};

History history_of(const Planner& p, std::size_t start, std::size_t stop) {
  const auto& h = p.history();
  stop = std::min(stop, h.size());
  start = std::min(start, stop);
  const py::ssize_t K = static_cast<py::ssize_t>(stop - start), M = p.hand().fingers(), N = p.hand().links();
  History out{py::array_t<double>({K, py::ssize_t(4), py::ssize_t(4)}),
              py::array_t<double>({K, M, N + 1, py::ssize_t(3)}), py::array_t<double>({K, M, N}),
              py::array_t<std::int8_t>({K, M}), py::array_t<std::int8_t>(K)};
  double* palm = out.palm_pose.mutable_data();
  double* joints = out.joints.mutable_data();
  double* angles = out.angles.mutable_data();
  std::int8_t* states = out.tip_state.mutable_data();
  std::int8_t* phase = out.phase.mutable_data();
  {
    py::gil_scoped_release release;
    for (std::size_t k = start; k < stop; ++k) {  // each configuration's arrays in C order, one after another
      const Configuration& c = h[k];
      Eigen::Map<RowMatrix4>{palm} = c.palm.matrix();
      palm += 16;
      for (const Vec3& x : c.joints) joints[0] = x[0], joints[1] = x[1], joints[2] = x[2], joints += 3;
      Eigen::Map<MatrixX>{angles, M, N} = c.angles;
      angles += M * N;
      for (TipState s : c.tip_state) *states++ = static_cast<std::int8_t>(s);
      *phase++ = static_cast<std::int8_t>(c.phase);
    }
  }
  return out;
}

/// A length parameter: None selects the default (NaN in the engine), so NaN itself is refused.
double optional_length(const py::object& value, const char* name) {
  if (value.is_none()) return std::numeric_limits<double>::quiet_NaN();
  const double x = real_number(value, name);
  if (std::isnan(x)) throw py::value_error(std::string(name) + " must be a number or None (the default), got nan");
  return x;
}

/// A length parameter as Python sees it: None for the default (NaN).
std::optional<double> length_or_none(double x) { return std::isnan(x) ? std::nullopt : std::optional<double>(x); }

}  // namespace

void bind_planner(py::module_& m) {
  py::class_<PlannerParams>(m, "PlannerParams",
                            "The planner's parameters (docs/python.md). None selects the documented default: step = "
                            "shortest link / 20, epsilon = step / 10, contact_tolerance = 1e-4 m, rules = hug. The "
                            "engine checks them (hugger/planner/planner.hpp: check_params); a Planner's params have "
                            "the defaults resolved.")
      .def(py::init([](const py::object& step, const py::object& epsilon, const py::object& contact_tolerance,
                       const py::object& max_iterations, const py::object& rules) {
             PlannerParams p;
             p.step = optional_length(step, "step");
             p.epsilon = optional_length(epsilon, "epsilon");
             p.contact_tolerance = optional_length(contact_tolerance, "contact_tolerance");
             if (!max_iterations.is_none()) p.max_iterations = whole_number(max_iterations, "max_iterations");
             // None: the default, as for the others; not a string: the engine's message, with the
             // value as Python shows it
             if (!rules.is_none())
               p.rules = rules_from_string(py::isinstance<py::str>(rules) ? rules.cast<std::string>()
                                                                         : py::repr(rules).cast<std::string>());
             check_params(p);
             return p;
           }),
           py::kw_only(), py::arg("step") = py::none(), py::arg("epsilon") = py::none(),
           py::arg("contact_tolerance") = py::none(), py::arg("max_iterations") = py::none(), py::arg("rules") = "hug")
      .def_property_readonly("step", [](const PlannerParams& p) { return length_or_none(p.step); },
                             "Fingertip step s (m); None: the default")
      .def_property_readonly("epsilon", [](const PlannerParams& p) { return length_or_none(p.epsilon); },
                             "Overextension threshold (m); None: the default")
      .def_property_readonly("contact_tolerance", [](const PlannerParams& p) { return length_or_none(p.contact_tolerance); },
                             "Sensing distance delta (m); None: the default")
      .def_readonly("max_iterations", &PlannerParams::max_iterations, "Bound on Phase 2 iterations")
      .def_property_readonly("rules", [](const PlannerParams& p) { return to_string(p.rules); },
                             "The rule set of Phase 2: 'hug' or 'paper'")
      .def("__repr__", [](const PlannerParams& p) {
        std::ostringstream os;
        const auto length = [&os](double x) -> std::ostream& { return std::isnan(x) ? os << "None" : os << x; };
        os << "PlannerParams(step=";
        length(p.step) << ", epsilon=";
        length(p.epsilon) << ", contact_tolerance=";
        length(p.contact_tolerance) << ", max_iterations=" << p.max_iterations << ", rules='" << to_string(p.rules) << "')";
        return os.str();
      });

  py::class_<PlannerStats> stats(m, "PlannerStats", "Counters of one plan, for inspection and benchmarks.");
  for (const StatsField& f : kStatsFields) stats.def_readonly(f.name, f.member, f.doc);

  py::class_<Configuration>(m, "Configuration", "One hand configuration of a plan (docs/model.md).")
      .def_property_readonly("palm_pose", [](const Configuration& c) { return from_pose(c.palm); }, "(4, 4) T_WP")
      .def_property_readonly(
          "joints",
          [](const Configuration& c) { return vec3s_array(c.joints, {c.angles.rows(), c.angles.cols() + 1, 3}); },
          "(M, N+1, 3) joint positions in the world, tail first")
      .def_property_readonly("angles", [](const Configuration& c) { return c.angles; }, "(M, N) joint angles (rad)")
      .def_property_readonly("tip_state", [](const Configuration& c) { return states_array(c.tip_state); },
                             "(M,) int8: 0 FROZEN, 1 CONTACT, 2 DONE")
      .def_readonly("phase", &Configuration::phase, "0 for C_init, then 1 or 2")
      .def_readonly("iteration", &Configuration::iteration, "Index of this configuration in the plan");

  py::class_<History>(m, "History", "Configurations [start, stop) of a plan as stacked arrays.")
      .def_readonly("palm_pose", &History::palm_pose, "(K, 4, 4)")
      .def_readonly("joints", &History::joints, "(K, M, N+1, 3)")
      .def_readonly("angles", &History::angles, "(K, M, N)")
      .def_readonly("tip_state", &History::tip_state, "(K, M) int8")
      .def_readonly("phase", &History::phase, "(K,) int8");

  py::class_<PyPlanner>(m, "Planner", "The Hugger planner (docs/algorithm.md) over a simulated world.")
      .def(py::init([](const HandModel& hand, const py::object& source, const ArrayD& target,
                       const ArrayD& palm_pose, const PlannerParams& params, const py::object& skin_name) {
             auto out = std::make_unique<PyPlanner>();
             if (source.is_none()) throw py::value_error("the object or skin must not be None");
             const std::string skin = py::isinstance<py::str>(skin_name) ? skin_name.cast<std::string>() : "";
             if (std::find(std::begin(kSkins), std::end(kSkins), skin) == std::end(kSkins)) {
               std::string names;
               for (const char* name : kSkins) names += (names.empty() ? "'" : ", '") + std::string(name) + "'";
               throw py::value_error("skin must be one of " + names + ", got " + py::repr(skin_name).cast<std::string>());
             }
             out->skin = skin;
             std::shared_ptr<Object> object;
             std::shared_ptr<Sensing> sensing;
             if (py::isinstance<Object>(source)) {
               object = source.cast<std::shared_ptr<Object>>();
             } else if (py::isinstance<Sensing>(source)) {
               sensing = source.cast<std::shared_ptr<Sensing>>();
               out->skin = "custom";
             } else {
               throw py::type_error("expected a hugger Object or Sensing skin, got " +
                                    py::str(py::type::of(source).attr("__name__")).cast<std::string>());
             }
             const Vec3 t = to_vec3(target, "target");
             const Pose pose = to_pose(palm_pose, "palm_pose");
             out->source = source;
             py::gil_scoped_release release;
             if (sensing) {  // a skin that need not have a mesh: T is taken as given
               out->planner = std::make_unique<Planner>(hand, std::move(sensing), t, pose, params);
               return out;
             }
             check_target(*object, t);
             std::shared_ptr<const Sensing> world;
             if (skin == "section") {
               // The skin keeps links off O by at most its flattening: a tenth of delta at most.
               world = std::make_shared<SectionSkin>(object, PlaneRegion::flatten_for(params.contact_tolerance_or_default()));
             } else {
               world = std::make_shared<SimulatedWorld>(object);
             }
             out->planner = std::make_unique<Planner>(hand, world, t, pose, params);
             return out;
           }),
           py::arg("hand"), py::arg("sensing"), py::arg("target"), py::arg("palm_pose"),
           py::arg("params") = PlannerParams(), py::arg("skin") = "section")
      .def(
          "configuration",
          [](PyPlanner& p, std::size_t k) -> std::optional<Configuration> {
            Busy busy(p);
            if (p.failed) return std::nullopt;
            py::gil_scoped_release release;
            return guarded(p, [&] { return p.planner->configuration(k); });
          },
          py::arg("k"),
          "Configuration k (from 0, C_init), planning on until it exists (as step() does); None when the plan "
          "ends before it. step() goes on after it.")
      .def(
          "plan",
          [](PyPlanner& p, const py::object& timeout) {
            const double limit = timeout.is_none() ? kInf : check_timeout(real_number(timeout, "timeout"));
            Busy busy(p);
            if (p.failed) return status_of(p);
            bool stopped = false;  // by a signal (its handler's exception is set) or by interrupt()
            // Python runs signal handlers in the main thread only: other threads (plan_many's,
            // the search's) are stopped by interrupt() alone, and never take the GIL to look.
            const bool main_thread = py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>() ==
                                     PyThread_get_thread_ident();
            {
              py::gil_scoped_release release;
              using Clock = std::chrono::steady_clock;
              auto polled = Clock::now();
              // Between iterations: interrupt(), or every kSignalPoll a look for signals, which
              // Python's handlers (Ctrl-C's KeyboardInterrupt) take only with the GIL.
              auto pause = [&] {
                if (p.interrupt.exchange(false)) return stopped = true;
                if (!main_thread) return false;
                const auto now = Clock::now();
                if (now - polled < kSignalPoll) return false;
                polled = now;
                py::gil_scoped_acquire gil;
                return stopped = PyErr_CheckSignals() != 0;
              };
              guarded(p, [&] { return p.planner->plan(limit, pause); });
            }
            if (stopped) {  // the plan is still running: plan() or step() goes on from here
              if (!PyErr_Occurred()) PyErr_SetNone(PyExc_KeyboardInterrupt);
              throw py::error_already_set();
            }
            return status_of(p);
          },
          py::arg("timeout") = py::none(),
          "Run to the end (GIL released); returns the status. With ``timeout`` (seconds, positive finite) the "
          "plan stops with status 'timeout' once that much wall-clock time has passed. An exception raised by the "
          "skin propagates unchanged and ends the plan (status 'error'). A signal's exception (Ctrl-C: "
          "KeyboardInterrupt) or interrupt() stops it between iterations, still running: a later call goes on (one "
          "raised inside a Python skin's callback ends it, status 'error', as any exception of the skin).")
      .def("interrupt", [](PyPlanner& p) { p.interrupt = true; },
           "Ask a plan() running in another thread to stop between iterations, raising KeyboardInterrupt there "
           "(the plan still running). Without one running, the next plan() stops at once.")
      .def("history", [](PyPlanner& p, std::size_t start, std::size_t stop) {
            Busy busy(p);
            return history_of(*p.planner, start, stop);
          },
          py::arg("start") = 0, py::arg("stop") = static_cast<std::size_t>(-1),
          "Configurations [start, stop) so far, as a History of stacked arrays.")
      .def_property_readonly("size", [](PyPlanner& p) { return p.planner->history().size(); })
      .def_property_readonly("status", [](PyPlanner& p) { return status_of(p); })
      .def_property_readonly("skin", [](PyPlanner& p) { return p.skin; },
                             "How the object is sensed: 'mesh', 'section', or 'custom' (a Sensing skin)")
      .def_property_readonly("params", [](PyPlanner& p) { return p.planner->params(); },
                             "The parameters in force, defaults resolved")
      .def_property_readonly("stats", [](PyPlanner& p) { return p.planner->stats(); }, "The plan's counters")
      .def_property_readonly("stats_json", [](PyPlanner& p) { return stats_json(p.planner->stats()); },
                             "The plan's counters as the JSON a trajectory records (json.dumps of their dict)");

  m.def("resolve_params", [](const HandModel& hand, const PlannerParams& params) { return resolve_params(hand, params); },
        py::arg("hand"), py::arg("params"),
        "The parameters a Planner of ``hand`` plans with, defaults resolved; ValueError for a step longer "
        "than the hand's shortest link, a contact_tolerance not below the step, an epsilon above it.");
  m.def("check_timeout", [](const py::object& seconds) { return check_timeout(real_number(seconds, "timeout")); },
        py::arg("seconds"), "``seconds`` as a float: raise ValueError unless it is a positive finite number.");
}
