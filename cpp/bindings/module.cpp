// hugger._core: the compiled engine. One bind_<area> per area of the C++ tree.
#include <pybind11/pybind11.h>

#include "common.hpp"
#include "hugger/hand/hand_model.hpp"
#include "hugger/planner/planner.hpp"
#include "hugger/types.hpp"
#include "hugger/world/object.hpp"

namespace py = pybind11;
using hugger::py_helpers::ArrayD;
using hugger::py_helpers::to_pose;
using hugger::py_helpers::to_vec3;

void bind_hand(py::module_& m);
void bind_world(py::module_& m);
void bind_sensing(py::module_& m);
void bind_planner(py::module_& m);
void bind_analysis(py::module_& m);

PYBIND11_MODULE(_core, m) {
  m.doc() = "Hugger engine: hand kinematics, the simulated world and the planner (C++17)";
  // The engine's limits, each owned by its C++ constant.
  m.attr("RIGID_TOLERANCE") = hugger::kRigidTolerance;
  m.attr("MAX_COORDINATE") = hugger::kMaxCoordinate;
  m.attr("MAX_FINGERS") = hugger::kMaxFingers;
  m.attr("MAX_LINKS") = hugger::kMaxLinks;
  m.attr("MAX_ITERATIONS") = hugger::kMaxIterations;
  m.attr("DEFAULT_CONTACT_TOLERANCE") = hugger::PlannerParams::kDefaultContactTolerance;
  // The names the planner accepts, owned by the engine (rules) and the binding (skins).
  m.attr("RULES") = py::make_tuple(to_string(hugger::Rules::kPaper), to_string(hugger::Rules::kHug));
  m.attr("SKINS") = py::make_tuple(hugger::py_helpers::kSkins[0], hugger::py_helpers::kSkins[1]);
  m.def("check_pose", [](const ArrayD& pose, const std::string& name) { to_pose(pose, name.c_str()); },
        py::arg("pose"), py::arg("name") = "palm_pose",
        "Raise ValueError, saying what is wrong, unless ``pose`` is a rigid (4, 4) transform: finite, last row "
        "(0, 0, 0, 1), rotation orthonormal with determinant +1 within RIGID_TOLERANCE (the engine's rule).");
  m.def(
      "check_target",
      [](const ArrayD& target, const py::object& obj) {
        const hugger::Vec3 t = to_vec3(target, "target");
        hugger::check_target_point(t);
        if (py::isinstance<hugger::Object>(obj)) {
          const hugger::Object& o = obj.cast<const hugger::Object&>();
          py::gil_scoped_release release;
          hugger::check_target(o, t);
        }
      },
      py::arg("target"), py::arg("obj") = py::none(),
      "Raise ValueError, saying what is wrong, unless ``target`` is a finite point (3,) within MAX_COORDINATE of "
      "the origin, and inside ``obj`` where that is an Object (the planner's rules for T; with a skin, T is "
      "taken as given).");
  bind_hand(m);
  bind_world(m);
  bind_sensing(m);
  bind_planner(m);
  bind_analysis(m);
}
