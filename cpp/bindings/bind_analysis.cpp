// Grasp quality (hugger/analysis/quality.hpp): force closure, Ferrari-Canny epsilon, GWS volume.
#include "common.hpp"
#include "hugger/analysis/quality.hpp"

namespace py = pybind11;
using namespace hugger;
using namespace hugger::py_helpers;

void bind_analysis(py::module_& m) {
  py::class_<analysis::QualityResult>(m, "QualityResult", "Grasp-wrench-space figures of a set of contacts.")
      .def_readonly("force_closure", &analysis::QualityResult::force_closure,
                    "The origin lies strictly inside the grasp wrench space.")
      .def_readonly("epsilon", &analysis::QualityResult::epsilon,
                    "Ferrari-Canny epsilon: radius of the largest origin-centred ball in the GWS (0 without closure).")
      .def_readonly("volume", &analysis::QualityResult::volume, "6D volume of the GWS (0 when flat).")
      .def_readonly("wrenches", &analysis::QualityResult::wrenches, "Distinct primitive wrenches of the GWS.")
      .def("__repr__", [](const analysis::QualityResult& r) {
        return "QualityResult(force_closure=" + std::string(r.force_closure ? "True" : "False") +
               ", epsilon=" + std::to_string(r.epsilon) + ", volume=" + std::to_string(r.volume) +
               ", wrenches=" + std::to_string(r.wrenches) + ")";
      });

  m.def(
      "grasp_quality",
      [](const ArrayD& points, const ArrayD& normals, const ArrayD& center, double mu, int cone_edges,
         double torque_scale, bool volume) {
        const PointsN3 p = to_rows<PointsN3>(points, "points");
        const PointsN3 n = to_rows<PointsN3>(normals, "normals");
        const Vec3 c = to_vec3(center, "center");
        analysis::QualityRequest req;
        req.mu = mu;
        req.cone_edges = cone_edges;
        req.torque_scale = torque_scale;
        req.volume = volume;
        py::gil_scoped_release release;
        return analysis::grasp_quality(p, n, c, req);
      },
      py::arg("points"), py::arg("normals"), py::arg("center"), py::arg("mu") = 0.5, py::arg("cone_edges") = 8,
      py::arg("torque_scale") = 1.0, py::arg("volume") = true,
      "Force closure, epsilon and volume of the L1 grasp wrench space of contacts at points (C, 3) (m, world) "
      "with outward normals (C, 3), torques about center (3,) divided by torque_scale (m). Qhull, GIL released. volume=False skips the full hull (volume reported 0): epsilon by cutting planes, ~1 ms.");
}
