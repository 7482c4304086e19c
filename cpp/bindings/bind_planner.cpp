#include <cmath>
#include <memory>
#include <mutex>

#include "common.hpp"
#include "hugger/planner/planner.hpp"
#include "hugger/world/section_skin.hpp"
#include "hugger/world/simulated_world.hpp"

namespace py = pybind11;
using namespace hugger;
using namespace hugger::py_helpers;

namespace {

/// A planner with a lock: one thread at a time may advance it; others get a clear error.
struct PyPlanner {
  std::unique_ptr<Planner> planner;
  py::object source;  ///< the Object or Sensing given: keeps a Python skin (and its overrides) alive
  std::string skin = "mesh";  ///< how an Object is sensed: "mesh" (3D queries on the BVH) or "section" (2D per finger plane)
  std::mutex busy;
  /// An exception left the planner in the middle of an iteration (a skin's callback raised): the
  /// plan has ended with status "error"; history() holds every configuration completed before.
  bool failed = false;
};

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
    if (!lock_.owns_lock()) throw std::runtime_error("this planner is already running in another thread");
  }

 private:
  std::unique_lock<std::mutex> lock_;
};

py::dict configuration_dict(const Configuration& c, int M, int N) {
  py::array_t<double> joints({M, N + 1, 3});
  py::array_t<double> angles({M, N});
  py::array_t<std::int8_t> states(M);
  auto j = joints.mutable_unchecked<3>();
  auto a = angles.mutable_unchecked<2>();
  auto s = states.mutable_unchecked<1>();
  for (int m = 0; m < M; ++m) {
    s(m) = static_cast<std::int8_t>(c.tip_state[m]);
    for (int n = 0; n <= N; ++n)
      for (int k = 0; k < 3; ++k) j(m, n, k) = c.joints[m * (N + 1) + n][k];
    for (int n = 0; n < N; ++n) a(m, n) = c.angles(m, n);
  }
  py::dict d;
  d["palm_pose"] = from_pose(c.palm);
  d["joints"] = joints;
  d["angles"] = angles;
  d["tip_state"] = states;
  d["phase"] = c.phase;
  d["iteration"] = c.iteration;
  return d;
}

py::dict history_arrays(const Planner& p, std::size_t start, std::size_t stop) {
  const auto& h = p.history();
  stop = std::min(stop, h.size());
  start = std::min(start, stop);
  const py::ssize_t K = static_cast<py::ssize_t>(stop - start);
  const int M = p.hand().fingers(), N = p.hand().links();
  py::array_t<double> palm({K, py::ssize_t(4), py::ssize_t(4)});
  py::array_t<double> joints({K, py::ssize_t(M), py::ssize_t(N + 1), py::ssize_t(3)});
  py::array_t<double> angles({K, py::ssize_t(M), py::ssize_t(N)});
  py::array_t<std::int8_t> states({K, py::ssize_t(M)});
  py::array_t<std::int8_t> phase(K);
  {
    auto P = palm.mutable_unchecked<3>();
    auto J = joints.mutable_unchecked<4>();
    auto A = angles.mutable_unchecked<3>();
    auto S = states.mutable_unchecked<2>();
    auto F = phase.mutable_unchecked<1>();
    py::gil_scoped_release release;
    for (py::ssize_t k = 0; k < K; ++k) {
      const Configuration& c = h[start + k];
      for (int i = 0; i < 4; ++i)
        for (int jj = 0; jj < 4; ++jj) P(k, i, jj) = c.palm.matrix()(i, jj);
      for (int m = 0; m < M; ++m) {
        S(k, m) = static_cast<std::int8_t>(c.tip_state[m]);
        for (int n = 0; n <= N; ++n)
          for (int x = 0; x < 3; ++x) J(k, m, n, x) = c.joints[m * (N + 1) + n][x];
        for (int n = 0; n < N; ++n) A(k, m, n) = c.angles(m, n);
      }
      F(k) = static_cast<std::int8_t>(c.phase);
    }
  }
  py::dict d;
  d["palm_pose"] = palm;
  d["joints"] = joints;
  d["angles"] = angles;
  d["tip_state"] = states;
  d["phase"] = phase;
  return d;
}

double optional_param(const py::object& value, const char* name) {
  if (value.is_none()) return std::numeric_limits<double>::quiet_NaN();
  const double v = value.cast<double>();
  if (!std::isfinite(v) || v <= 0.0)
    throw py::value_error(std::string(name) + " must be a positive finite number, got " + py::str(value).cast<std::string>());
  return v;
}

}  // namespace

void bind_planner(py::module_& m) {
  py::class_<PyPlanner>(m, "Planner", "The Hugger planner (docs/algorithm.md) over a simulated world.")
      .def(py::init([](const HandModel& hand, const py::object& source, const ArrayD& target,
                       const ArrayD& palm_pose, const py::object& step, const py::object& epsilon,
                       const py::object& contact_tolerance, const py::object& max_iterations,
                       const std::string& rules, const std::string& skin) {
             auto out = std::make_unique<PyPlanner>();
             if (source.is_none()) throw py::value_error("the object or skin must not be None");
             if (skin != "mesh" && skin != "section")
               throw py::value_error("skin must be 'mesh' or 'section', got '" + skin + "'");
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
             if (!t.allFinite()) throw py::value_error("target must be finite");
             const Pose pose = to_pose(palm_pose, "palm_pose");
             PlannerParams params;
             params.step = optional_param(step, "step");
             params.epsilon = optional_param(epsilon, "epsilon");
             params.contact_tolerance = optional_param(contact_tolerance, "contact_tolerance");
             if (!max_iterations.is_none()) params.max_iterations = max_iterations.cast<long>();  // checked by Planner
             params.rules = rules_from_string(rules);  // std::invalid_argument -> ValueError
             out->source = source;
             py::gil_scoped_release release;
             if (sensing) {  // a skin that need not have a mesh: T is taken as given
               out->planner = std::make_unique<Planner>(hand, std::move(sensing), t, pose, params);
               return out;
             }
             const double depth = object->nearest(t, t).signed_distance;
             if (!(depth < 0.0)) {
               std::ostringstream os;
               os << "target T = (" << t.x() << ", " << t.y() << ", " << t.z()
                  << ") is not inside the object (its distance to the surface is " << depth << " m, outside or on it)";
               throw std::invalid_argument(os.str());
             }
             std::shared_ptr<const Sensing> world;
             if (skin == "section") world = std::make_shared<SectionSkin>(object);
             else world = std::make_shared<SimulatedWorld>(object);
             out->planner = std::make_unique<Planner>(hand, world, t, pose, params);
             return out;
           }),
           py::arg("hand"), py::arg("sensing"), py::arg("target"), py::arg("palm_pose"), py::arg("step") = py::none(),
           py::arg("epsilon") = py::none(), py::arg("contact_tolerance") = py::none(),
           py::arg("max_iterations") = py::none(), py::arg("rules") = "hug", py::arg("skin") = "mesh")
      .def(
          "step",
          [](PyPlanner& p) -> py::object {
            Busy busy(p);
            std::optional<Configuration> c;
            {
              if (p.failed) return py::none();
              py::gil_scoped_release release;
              c = guarded(p, [&] { return p.planner->step(); });
            }
            if (!c) return py::none();
            return configuration_dict(*c, p.planner->hand().fingers(), p.planner->hand().links());
          },
          "Advance by one configuration; a dict of arrays, or None when the plan has ended. An exception "
          "raised by the skin propagates unchanged and ends the plan (status 'error').")
      .def(
          "plan",
          [](PyPlanner& p, const py::object& timeout) {
            double limit = kInf;
            if (!timeout.is_none()) {
              if (py::isinstance<py::bool_>(timeout) || (!py::isinstance<py::float_>(timeout) && !py::isinstance<py::int_>(timeout)))
                throw py::value_error("timeout must be a number of seconds or None, got " + py::repr(timeout).cast<std::string>());
              limit = timeout.cast<double>();
              if (!std::isfinite(limit) || limit <= 0.0)
                throw py::value_error("timeout must be a positive finite number of seconds or None, got " +
                                      py::repr(timeout).cast<std::string>());
            }
            Busy busy(p);
            if (p.failed) return status_of(p);
            {
              py::gil_scoped_release release;
              guarded(p, [&] { return p.planner->plan(limit); });
            }
            return status_of(p);
          },
          py::arg("timeout") = py::none(),
          "Run to the end (GIL released); returns the status. With ``timeout`` (seconds, positive finite) the "
          "plan stops with status 'timeout' once that much wall-clock time has passed. An exception raised by the "
          "skin propagates unchanged and ends the plan (status 'error').")
      .def("history", [](PyPlanner& p, std::size_t start, std::size_t stop) {
            Busy busy(p);
            return history_arrays(*p.planner, start, stop);
          },
          py::arg("start") = 0, py::arg("stop") = static_cast<std::size_t>(-1),
          "Configurations [start, stop) so far as arrays: palm_pose (K,4,4), joints (K,M,N+1,3), "
          "angles (K,M,N), tip_state (K,M) int8, phase (K,) int8.")
      .def_property_readonly("size", [](PyPlanner& p) { return p.planner->history().size(); })
      .def_property_readonly("status", [](PyPlanner& p) { return status_of(p); })
      .def_property_readonly("params", [](PyPlanner& p) {
        const PlannerParams& q = p.planner->params();
        py::dict d;
        d["step"] = q.step;
        d["epsilon"] = q.epsilon;
        d["contact_tolerance"] = q.contact_tolerance;
        d["max_iterations"] = q.max_iterations;
        d["rules"] = to_string(q.rules);
        d["skin"] = p.skin;
        return d;
      })
      .def_property_readonly("stats", [](PyPlanner& p) {
        const PlannerStats& s = p.planner->stats();
        py::dict d;
        d["phase1_configurations"] = s.phase1_configurations;
        d["phase2_iterations"] = s.phase2_iterations;
        d["first_contact_iteration"] = s.first_contact_iteration;
        d["palm_contact_iteration"] = s.palm_contact_iteration;
        d["sigma_retries"] = s.sigma_retries;
        d["finger_collisions"] = s.finger_collisions;
        d["clinging_failures"] = s.clinging_failures;
        d["motion_rejections"] = s.motion_rejections;
        d["approach_configurations"] = s.approach_configurations;
        return d;
      });
}
