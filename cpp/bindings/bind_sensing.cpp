// The skin as a plug-in: hugger::Sensing implementable in Python (a pybind11 trampoline), its
// Touch result, and the simulated mesh world as a ready-made C++ skin.
//
// The planner runs with the GIL released; a Python skin takes the GIL only inside its own
// callbacks (gil_scoped_acquire in each override). A Python exception raised in a callback
// leaves the C++ code as py::error_already_set and reaches the caller of step()/plan() as the
// original exception.
#include <cmath>
#include <memory>
#include <sstream>

#include "common.hpp"
#include "hugger/sensing/sensing.hpp"
#include "hugger/world/simulated_world.hpp"

namespace py = pybind11;
using namespace hugger;
using namespace hugger::py_helpers;

namespace {

Vec3 vec3_of(const py::handle& h, const char* name) { return to_vec3(py::cast<ArrayD>(h), name); }

/// A skin's answer to a capsule query: a Touch (checked by the engine, its normal normalised).
Touch checked_touch(const py::object& r) {
  if (!py::isinstance<Touch>(r))
    throw py::type_error("Sensing.capsule must return a hugger.Touch, got " +
                         py::str(py::type::of(r).attr("__name__")).cast<std::string>());
  return check_touch(r.cast<Touch>(), "Sensing.capsule returned");
}

/// The trampoline: each override takes the GIL for the duration of the Python call only.
class PySensing : public Sensing {
 public:
  Touch capsule(const Vec3& a, const Vec3& b, double radius, double cap) const override {
    py::gil_scoped_acquire gil;
    py::function f = py::get_override(static_cast<const Sensing*>(this), "capsule");
    if (!f) throw py::type_error("a hugger.Sensing subclass must define capsule(a, b, radius, cap) -> Touch");
    return checked_touch(f(a, b, radius, cap));
  }

  double palm(const Pose& pose, double radius, double thickness, double cap) const override {
    py::gil_scoped_acquire gil;
    py::function f = py::get_override(static_cast<const Sensing*>(this), "palm");
    if (!f) throw py::type_error("a hugger.Sensing subclass must define palm(pose, radius, thickness, cap) -> float");
    const py::object r = f(from_pose(pose), radius, thickness, cap);
    double g = 0.0;
    try {
      // A bool, Python's or NumPy's (a scalar of dtype kind 'b'), is an answer to another question
      // (capsule_clear's), not a gap.
      const py::object kind = py::getattr(py::getattr(r, "dtype", py::none()), "kind", py::none());
      if (py::isinstance<py::bool_>(r) || (py::isinstance<py::str>(kind) && kind.cast<std::string>() == "b"))
        throw py::cast_error();
      g = r.cast<double>();
    } catch (const py::cast_error&) {
      throw py::type_error("Sensing.palm must return a float (the gap in m), got " +
                           py::str(py::type::of(r).attr("__name__")).cast<std::string>());
    }
    return check_gap(g, "Sensing.palm returned");
  }

  bool capsule_clear(const Vec3& a, const Vec3& b, double radius, bool a_outside) const override {
    {
      py::gil_scoped_acquire gil;
      py::function f = py::get_override(static_cast<const Sensing*>(this), "capsule_clear");
      if (f) {
        // pybind11's bool caster without conversion takes Python's bool and NumPy's, nothing else:
        // None, a string or a number is a mistake, not an answer.
        const py::object r = f(a, b, radius, a_outside);
        py::detail::make_caster<bool> answer;
        if (answer.load(r, /*convert=*/false)) return py::detail::cast_op<bool>(answer);
        throw py::type_error("Sensing.capsule_clear must return a bool (whether the capsule is clear of the "
                             "object), got " + py::str(py::type::of(r).attr("__name__")).cast<std::string>());
      }
    }
    return Sensing::capsule_clear(a, b, radius, a_outside);
  }
};

}  // namespace

void bind_sensing(py::module_& m) {
  py::class_<Touch>(m, "Touch",
                    "What a piece of skin senses. ``gap`` (m) between the part's surface and O: signed, "
                    "negative when the part penetrates O (FCL's convention); exact when <= the query's cap, "
                    "otherwise any value above cap (+inf: nothing sensed). ``on_hand`` (3,): nearest point of the "
                    "capsule's axis; ``on_object`` (3,): nearest point of O; ``normal`` (3,): unit gradient of the "
                    "signed distance at on_hand, pointing out of O toward the hand.")
      .def(py::init([](double gap, const ArrayD& on_hand, const ArrayD& on_object, const ArrayD& normal) {
             Touch t;
             t.gap = check_gap(gap, "Touch was given");
             t.on_hand = to_vec3(on_hand, "on_hand");
             t.on_object = to_vec3(on_object, "on_object");
             t.normal = to_vec3(normal, "normal");
             return t;
           }),
           py::arg("gap"), py::arg("on_hand") = Vec3::Zero().eval(), py::arg("on_object") = Vec3::Zero().eval(),
           py::arg("normal") = Vec3::UnitZ().eval())
      .def_property(
          "gap", [](const Touch& t) { return t.gap; },
          [](Touch& t, double gap) { t.gap = check_gap(gap, "Touch was given"); })
      .def_property(
          "on_hand", [](const Touch& t) { return t.on_hand; },
          [](Touch& t, const py::object& v) { t.on_hand = vec3_of(v, "on_hand"); })
      .def_property(
          "on_object", [](const Touch& t) { return t.on_object; },
          [](Touch& t, const py::object& v) { t.on_object = vec3_of(v, "on_object"); })
      .def_property(
          "normal", [](const Touch& t) { return t.normal; },
          [](Touch& t, const py::object& v) { t.normal = vec3_of(v, "normal"); })
      .def("__repr__", [](const Touch& t) {
        std::ostringstream os;
        os << "Touch(gap=" << t.gap << ", on_hand=[" << t.on_hand.transpose() << "], on_object=["
           << t.on_object.transpose() << "], normal=[" << t.normal.transpose() << "])";
        return os.str();
      });

  py::class_<Sensing, PySensing, std::shared_ptr<Sensing>>(
      m, "Sensing",
      "The whole-sensitive skin: the planner learns the object only through it. Subclass it (calling "
      "``super().__init__()``) and define ``capsule(a, b, radius, cap) -> Touch`` and ``palm(pose, radius, "
      "thickness, cap) -> float``; ``capsule_clear(a, b, radius, a_outside) -> bool`` may be overridden. A "
      "skin whose answers depend on the queries before them sets the class attribute ``keeps_state = True`` "
      "(hugger.plan_many then plans the cases sharing it one after another).")
      .def(py::init<>())
      .def(
          "capsule",
          [](const Sensing& s, const ArrayD& a, const ArrayD& b, double radius, double cap) {
            const Vec3 pa = to_vec3(a, "a"), pb = to_vec3(b, "b");
            check_capsule_query(pa, pb, radius, cap);
            py::gil_scoped_release release;
            return s.capsule(pa, pb, radius, cap);
          },
          py::arg("a"), py::arg("b"), py::arg("radius"), py::arg("cap") = kInf,
          "Gap between the capsule of axis [a, b] (3,) and ``radius`` (m) and O, as a Touch (a == b: a sphere).")
      .def(
          "palm",
          [](const Sensing& s, const ArrayD& pose, double radius, double thickness, double cap) {
            const Pose p = to_pose(pose, "pose");
            check_palm_query(radius, thickness, cap);
            py::gil_scoped_release release;
            return s.palm(p, radius, thickness, cap);
          },
          py::arg("pose"), py::arg("radius"), py::arg("thickness"), py::arg("cap") = kInf,
          "Gap (m) between the palm disk (``radius``, ``thickness`` behind the front face of pose T_WP (4, 4)) "
          "and O; negative when they overlap (the depth need not be exact).")
      .def(
          "capsule_clear",
          [](const Sensing& s, const ArrayD& a, const ArrayD& b, double radius, bool a_outside) {
            const Vec3 pa = to_vec3(a, "a"), pb = to_vec3(b, "b");
            check_capsule_query(pa, pb, radius, 0.0);
            py::gil_scoped_release release;
            return s.capsule_clear(pa, pb, radius, a_outside);
          },
          py::arg("a"), py::arg("b"), py::arg("radius"), py::arg("a_outside") = false,
          "True when the capsule does not penetrate O (gap >= 0). The default asks capsule(..., cap=0).");

  py::class_<SimulatedWorld, Sensing, std::shared_ptr<SimulatedWorld>>(
      m, "SimulatedWorld", "The simulated mesh world: exact 3D queries on a BVH of the object (the reference skin).",
      py::dynamic_attr())  // hugger.skins.MeshSkin records its hugger.Object on it
      .def(py::init([](std::shared_ptr<Object> object) { return std::make_shared<SimulatedWorld>(object); }),
           py::arg("object"));
}
