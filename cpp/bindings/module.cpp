// hugger._core: the compiled engine. One bind_<area> per area of the C++ tree.
#include <pybind11/pybind11.h>

#include "hugger/types.hpp"

namespace py = pybind11;

void bind_hand(py::module_& m);
void bind_world(py::module_& m);
void bind_sensing(py::module_& m);
void bind_planner(py::module_& m);
void bind_analysis(py::module_& m);

PYBIND11_MODULE(_core, m) {
  m.doc() = "Hugger engine: hand kinematics, the simulated world and the planner (C++17)";
  m.attr("RIGID_TOLERANCE") = hugger::kRigidTolerance;
  bind_hand(m);
  bind_world(m);
  bind_sensing(m);
  bind_planner(m);
  bind_analysis(m);
}
