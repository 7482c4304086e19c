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

py::array_t<double> vec3_array(const Vec3& v) {
  py::array_t<double> out(3);
  auto w = out.mutable_unchecked<1>();
  for (int k = 0; k < 3; ++k) w(k) = v[k];
  return out;
}

Vec3 vec3_of(const py::handle& h, const char* name) {
  const ArrayD a = py::cast<ArrayD>(h);
  return to_vec3(a, name);
}

/// A skin's answer, checked: a gap that is a number (not NaN; +inf: nothing sensed within the cap;
/// -inf: inside, depth not measured),
/// finite points, a finite non-zero normal (normalised here).
Touch checked_touch(const py::object& r) {
  if (!py::isinstance<Touch>(r))
    throw py::type_error("Sensing.capsule must return a hugger.Touch, got " +
                         py::str(py::type::of(r).attr("__name__")).cast<std::string>());
  Touch t = r.cast<Touch>();
  if (std::isnan(t.gap)) throw py::value_error("Sensing.capsule returned a gap of nan; expected a number (m) or +-inf");
  if (!t.on_hand.allFinite() || !t.on_object.allFinite() || !t.normal.allFinite() || !(t.normal.norm() > 0.0))
    throw py::value_error("Sensing.capsule returned non-finite points or a zero or non-finite normal");
  t.normal.normalize();
  return t;
}

/// The trampoline: each override takes the GIL for the duration of the Python call only.
class PySensing : public Sensing {
 public:
  Touch capsule(const Vec3& a, const Vec3& b, double radius, double cap) const override {
    py::gil_scoped_acquire gil;
    py::function f = py::get_override(static_cast<const Sensing*>(this), "capsule");
    if (!f) throw py::type_error("a hugger.Sensing subclass must define capsule(a, b, radius, cap) -> Touch");
    return checked_touch(f(vec3_array(a), vec3_array(b), radius, cap));
  }

  double palm(const Pose& pose, double radius, double thickness, double cap) const override {
    py::gil_scoped_acquire gil;
    py::function f = py::get_override(static_cast<const Sensing*>(this), "palm");
    if (!f) throw py::type_error("a hugger.Sensing subclass must define palm(pose, radius, thickness, cap) -> float");
    const py::object r = f(from_pose(pose), radius, thickness, cap);
    double g = 0.0;
    try {
      g = r.cast<double>();
    } catch (const py::cast_error&) {
      throw py::type_error("Sensing.palm must return a float (the gap in m), got " +
                           py::str(py::type::of(r).attr("__name__")).cast<std::string>());
    }
    if (std::isnan(g)) throw py::value_error("Sensing.palm returned a gap of nan; expected a number (m) or +-inf");
    return g;
  }

  bool capsule_clear(const Vec3& a, const Vec3& b, double radius, bool a_outside) const override {
    {
      py::gil_scoped_acquire gil;
      py::function f = py::get_override(static_cast<const Sensing*>(this), "capsule_clear");
      if (f) return f(vec3_array(a), vec3_array(b), radius, a_outside).cast<bool>();
    }
    return Sensing::capsule_clear(a, b, radius, a_outside);
  }
};

double checked_size(double x, const char* name) {
  if (!std::isfinite(x) || x < 0.0)
    throw py::value_error(std::string(name) + " must be a finite number >= 0 (m), got " + std::to_string(x));
  return x;
}

double checked_cap(double cap) {
  if (std::isnan(cap)) throw py::value_error("cap must be a number (m) or inf, got nan");
  return cap;
}

}  // namespace

void bind_sensing(py::module_& m) {
  py::class_<Touch>(m, "Touch",
                    "What a piece of skin senses. ``gap`` (m) between the part's surface and O: signed, "
                    "negative when the part penetrates O (FCL's convention); exact when <= the query's cap, "
                    "otherwise any value >= cap (+inf: nothing sensed). ``on_hand`` (3,): nearest point of the "
                    "capsule's axis; ``on_object`` (3,): nearest point of O; ``normal`` (3,): unit gradient of the "
                    "signed distance at on_hand, pointing out of O toward the hand.")
      .def(py::init([](double gap, const ArrayD& on_hand, const ArrayD& on_object, const ArrayD& normal) {
             if (std::isnan(gap)) throw py::value_error("gap must be a number (m) or inf, got nan");
             Touch t;
             t.gap = gap;
             t.on_hand = to_vec3(on_hand, "on_hand");
             t.on_object = to_vec3(on_object, "on_object");
             t.normal = to_vec3(normal, "normal");
             return t;
           }),
           py::arg("gap"), py::arg("on_hand") = vec3_array(Vec3::Zero()), py::arg("on_object") = vec3_array(Vec3::Zero()),
           py::arg("normal") = vec3_array(Vec3::UnitZ()))
      .def_readwrite("gap", &Touch::gap)
      .def_property(
          "on_hand", [](const Touch& t) { return vec3_array(t.on_hand); },
          [](Touch& t, const py::object& v) { t.on_hand = vec3_of(v, "on_hand"); })
      .def_property(
          "on_object", [](const Touch& t) { return vec3_array(t.on_object); },
          [](Touch& t, const py::object& v) { t.on_object = vec3_of(v, "on_object"); })
      .def_property(
          "normal", [](const Touch& t) { return vec3_array(t.normal); },
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
      "thickness, cap) -> float``; ``capsule_clear(a, b, radius, a_outside) -> bool`` may be overridden.")
      .def(py::init<>())
      .def(
          "capsule",
          [](const Sensing& s, const ArrayD& a, const ArrayD& b, double radius, double cap) {
            const Vec3 pa = to_vec3(a, "a"), pb = to_vec3(b, "b");
            if (!pa.allFinite() || !pb.allFinite()) throw py::value_error("a and b must be finite");
            checked_size(radius, "radius");
            checked_cap(cap);
            py::gil_scoped_release release;
            return s.capsule(pa, pb, radius, cap);
          },
          py::arg("a"), py::arg("b"), py::arg("radius"), py::arg("cap") = kInf,
          "Gap between the capsule of axis [a, b] (3,) and ``radius`` (m) and O, as a Touch (a == b: a sphere).")
      .def(
          "palm",
          [](const Sensing& s, const ArrayD& pose, double radius, double thickness, double cap) {
            const Pose p = to_pose(pose, "pose");
            checked_size(radius, "radius");
            checked_size(thickness, "thickness");
            checked_cap(cap);
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
            checked_size(radius, "radius");
            py::gil_scoped_release release;
            return s.capsule_clear(pa, pb, radius, a_outside);
          },
          py::arg("a"), py::arg("b"), py::arg("radius"), py::arg("a_outside") = false,
          "True when the capsule does not penetrate O (gap >= 0). The default asks capsule(..., cap=0).");

  py::class_<SimulatedWorld, Sensing, std::shared_ptr<SimulatedWorld>>(
      m, "SimulatedWorld", "The simulated mesh world: exact 3D queries on a BVH of the object (the reference skin).")
      .def(py::init([](std::shared_ptr<Object> object) {
             if (!object) throw py::value_error("object must not be None");
             return std::make_shared<SimulatedWorld>(object);
           }),
           py::arg("object"));
}
