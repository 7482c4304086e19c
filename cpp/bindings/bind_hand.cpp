#include <optional>
#include <vector>

#include "common.hpp"
#include "hugger/hand/hand_model.hpp"

namespace py = pybind11;
using namespace hugger;
using namespace hugger::py_helpers;

void bind_hand(py::module_& m) {
  py::class_<HandModel>(m, "HandModel", "Immutable hand: M fingers of N links on a round palm (metres).")
      .def(py::init([](int fingers, int links, const ArrayD& lengths, double link_radius, double palm_radius,
                       double palm_thickness) {
             return HandModel(fingers, links, to_matrix(lengths, "link_lengths"), link_radius, palm_radius, palm_thickness);
           }),
           py::arg("fingers"), py::arg("links"), py::arg("link_lengths"), py::arg("link_radius"),
           py::arg("palm_radius"), py::arg("palm_thickness"))
      .def(py::init([](int fingers, int links, const ArrayD& lengths, double link_radius, double palm_radius,
                       double palm_thickness, const std::optional<ArrayD>& roots,
                       const std::optional<ArrayD>& directions, const std::optional<ArrayD>& rest,
                       const std::optional<ArrayD>& lower, const std::optional<ArrayD>& upper) {
             HandLayout layout;
             layout.roots = optional_matrix(roots, "finger_roots");
             layout.directions = optional_matrix(directions, "finger_directions");
             layout.rest = optional_matrix(rest, "rest_angles");
             layout.lower = optional_matrix(lower, "lower");
             layout.upper = optional_matrix(upper, "upper");
             return HandModel(fingers, links, to_matrix(lengths, "link_lengths"), link_radius, palm_radius, palm_thickness,
                              layout);
           }),
           py::arg("fingers"), py::arg("links"), py::arg("link_lengths"), py::arg("link_radius"),
           py::arg("palm_radius"), py::arg("palm_thickness"), py::kw_only(), py::arg("roots") = py::none(),
           py::arg("directions") = py::none(), py::arg("rest") = py::none(), py::arg("lower") = py::none(),
           py::arg("upper") = py::none(),
           "A general layout (palm frame): roots (M, 3) and directions (M, 3) with z = 0, rest angles (M, N), "
           "joint limits lower and upper (M, N) in rad (+-inf: unlimited). None: the rim layout's value.")
      .def_property_readonly("general", &HandModel::general, "True for a general layout")
      .def_property_readonly("finger_roots", [](const HandModel& h) {
        PointsN3 a(h.fingers(), 3);
        for (int i = 0; i < h.fingers(); ++i) a.row(i) = h.root_palm(i).transpose();
        return a;
      }, "Roots R_m (M, 3) in the palm frame (m)")
      .def_property_readonly("finger_directions", [](const HandModel& h) {
        PointsN3 a(h.fingers(), 3);
        for (int i = 0; i < h.fingers(); ++i) a.row(i) = h.direction_palm(i).transpose();
        return a;
      }, "In-plane outward directions u_m (M, 3) in the palm frame")
      .def_property_readonly("rest_angles", [](const HandModel& h) { return h.rest(); },
                             "Rest (FROZEN) joint angles (M, N), rad")
      .def_property_readonly("lower", [](const HandModel& h) { return h.lower(); },
                             "Lower joint limits (M, N), rad (-inf: unlimited)")
      .def_property_readonly("upper", [](const HandModel& h) { return h.upper(); },
                             "Upper joint limits (M, N), rad (+inf: unlimited)")
      .def_property_readonly("has_limits", &HandModel::has_limits, "True when any joint limit is finite")
      .def_property_readonly("extended_radius", &HandModel::extended_radius,
                             "Largest distance (m) from P_o of the hand at rest")
      .def_property_readonly("fingers", &HandModel::fingers)
      .def_property_readonly("links", &HandModel::links)
      .def_property_readonly("link_lengths", [](const HandModel& h) { return h.link_lengths(); })
      .def_property_readonly("link_radius", &HandModel::link_radius)
      .def_property_readonly("palm_radius", &HandModel::palm_radius)
      .def_property_readonly("palm_thickness", &HandModel::palm_thickness)
      .def_property_readonly("finger_angles", &HandModel::finger_angles)
      .def(
          "forward",
          [](const HandModel& h, const ArrayD& palm, const ArrayD& angles) {
            const auto joints = h.forward(to_pose(palm, "palm_pose"), to_matrix(angles, "angles"));
            return vec3s_array(joints, {h.fingers(), h.links() + 1, 3});
          },
          py::arg("palm_pose"), py::arg("angles"),
          "Joint positions (M, N+1, 3) in the world from palm pose (4, 4) and angles (M, N).")
      .def(
          "angles_from_joints",
          [](const HandModel& h, const ArrayD& palm, const ArrayD& joints) {
            check_shape(joints, {h.fingers(), h.links() + 1, 3}, "joints");
            return h.angles_from_joints(to_pose(palm, "palm_pose"), to_vec3s(joints));
          },
          py::arg("palm_pose"), py::arg("joints"), "Joint angles (M, N) from joint positions (M, N+1, 3).")
      .def(
          "roots",
          [](const HandModel& h, const ArrayD& palm) {
            const Pose p = to_pose(palm, "palm_pose");
            PointsN3 out(h.fingers(), 3);
            for (int i = 0; i < h.fingers(); ++i) out.row(i) = h.root(p, i).transpose();
            return out;
          },
          py::arg("palm_pose"), "Finger roots R_m (M, 3) in the world.")
      .def(
          "planes",
          [](const HandModel& h, const ArrayD& palm) {
            const Pose p = to_pose(palm, "palm_pose");
            std::vector<Vec3> rows;
            for (int i = 0; i < h.fingers(); ++i) {
              const FingerPlane pl = h.plane(p, i);
              rows.insert(rows.end(), {pl.origin, pl.u, pl.p});
            }
            return vec3s_array(rows, {h.fingers(), 3, 3});
          },
          py::arg("palm_pose"),
          "Finger planes (M, 3, 3): rows origin (the plane's point nearest P_o), outward u_m, palm normal p.");
}
