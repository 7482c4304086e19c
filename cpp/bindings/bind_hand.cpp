#include <optional>

#include "common.hpp"
#include "hugger/hand/hand_model.hpp"

namespace py = pybind11;
using namespace hugger;
using namespace hugger::py_helpers;

namespace {
MatrixX optional_matrix(const std::optional<ArrayD>& a, py::ssize_t rows, py::ssize_t cols, const char* name) {
  if (!a) return MatrixX();
  check_shape(*a, {rows, cols}, name);
  return to_matrix(*a);
}

py::array_t<double> matrix_array(const MatrixX& a) {
  py::array_t<double> out({a.rows(), a.cols()});
  auto r = out.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    for (Eigen::Index j = 0; j < a.cols(); ++j) r(i, j) = a(i, j);
  return out;
}
}  // namespace

void bind_hand(py::module_& m) {
  py::class_<HandModel>(m, "HandModel", "Immutable hand: M fingers of N links on a round palm (metres).")
      .def(py::init([](int fingers, int links, const ArrayD& lengths, double link_radius, double palm_radius,
                       double palm_thickness) {
             check_shape(lengths, {fingers, links}, "link_lengths");
             return HandModel(fingers, links, to_matrix(lengths), link_radius, palm_radius, palm_thickness);
           }),
           py::arg("fingers"), py::arg("links"), py::arg("link_lengths"), py::arg("link_radius"),
           py::arg("palm_radius"), py::arg("palm_thickness"))
      .def(py::init([](int fingers, int links, const ArrayD& lengths, double link_radius, double palm_radius,
                       double palm_thickness, const std::optional<ArrayD>& roots,
                       const std::optional<ArrayD>& directions, const std::optional<ArrayD>& rest,
                       const std::optional<ArrayD>& lower, const std::optional<ArrayD>& upper) {
             check_shape(lengths, {fingers, links}, "link_lengths");
             HandLayout layout;
             layout.roots = optional_matrix(roots, fingers, 3, "finger_roots");
             layout.directions = optional_matrix(directions, fingers, 3, "finger_directions");
             layout.rest = optional_matrix(rest, fingers, links, "rest_angles");
             layout.lower = optional_matrix(lower, fingers, links, "lower");
             layout.upper = optional_matrix(upper, fingers, links, "upper");
             return HandModel(fingers, links, to_matrix(lengths), link_radius, palm_radius, palm_thickness, layout);
           }),
           py::arg("fingers"), py::arg("links"), py::arg("link_lengths"), py::arg("link_radius"),
           py::arg("palm_radius"), py::arg("palm_thickness"), py::kw_only(), py::arg("roots") = py::none(),
           py::arg("directions") = py::none(), py::arg("rest") = py::none(), py::arg("lower") = py::none(),
           py::arg("upper") = py::none(),
           "A general layout (palm frame): roots (M, 3) and directions (M, 3) with z = 0, rest angles (M, N), "
           "joint limits lower and upper (M, N) in rad (+-inf: unlimited). None: the rim layout's value.")
      .def_property_readonly("general", &HandModel::general, "True for a general layout")
      .def_property_readonly("finger_roots", [](const HandModel& h) {
        MatrixX a(h.fingers(), 3);
        for (int i = 0; i < h.fingers(); ++i) a.row(i) = h.root_palm(i).transpose();
        return matrix_array(a);
      }, "Roots R_m (M, 3) in the palm frame (m)")
      .def_property_readonly("finger_directions", [](const HandModel& h) {
        MatrixX a(h.fingers(), 3);
        for (int i = 0; i < h.fingers(); ++i) a.row(i) = h.direction_palm(i).transpose();
        return matrix_array(a);
      }, "In-plane outward directions u_m (M, 3) in the palm frame")
      .def_property_readonly("rest_angles", [](const HandModel& h) { return matrix_array(h.rest()); },
                             "Rest (FROZEN) joint angles (M, N), rad")
      .def_property_readonly("lower", [](const HandModel& h) { return matrix_array(h.lower()); },
                             "Lower joint limits (M, N), rad (-inf: unlimited)")
      .def_property_readonly("upper", [](const HandModel& h) { return matrix_array(h.upper()); },
                             "Upper joint limits (M, N), rad (+inf: unlimited)")
      .def_property_readonly("has_limits", &HandModel::has_limits, "True when any joint limit is finite")
      .def_property_readonly("extended_radius", &HandModel::extended_radius,
                             "Largest distance (m) from P_o of the hand at rest")
      .def_property_readonly("fingers", &HandModel::fingers)
      .def_property_readonly("links", &HandModel::links)
      .def_property_readonly("link_lengths", [](const HandModel& h) {
        py::array_t<double> out({h.fingers(), h.links()});
        auto r = out.mutable_unchecked<2>();
        for (int i = 0; i < h.fingers(); ++i)
          for (int j = 0; j < h.links(); ++j) r(i, j) = h.link_length(i, j);
        return out;
      })
      .def_property_readonly("link_radius", &HandModel::link_radius)
      .def_property_readonly("palm_radius", &HandModel::palm_radius)
      .def_property_readonly("palm_thickness", &HandModel::palm_thickness)
      .def_property_readonly("finger_angles", &HandModel::finger_angles)
      .def(
          "forward",
          [](const HandModel& h, const ArrayD& palm, const ArrayD& angles) {
            check_shape(angles, {h.fingers(), h.links()}, "angles");
            const auto joints = h.forward(to_pose(palm, "palm_pose"), to_matrix(angles));
            py::array_t<double> out({h.fingers(), h.links() + 1, 3});
            auto r = out.mutable_unchecked<3>();
            for (int i = 0; i < h.fingers(); ++i)
              for (int j = 0; j <= h.links(); ++j)
                for (int k = 0; k < 3; ++k) r(i, j, k) = joints[i * (h.links() + 1) + j][k];
            return out;
          },
          py::arg("palm_pose"), py::arg("angles"),
          "Joint positions (M, N+1, 3) in the world from palm pose (4, 4) and angles (M, N).")
      .def(
          "angles_from_joints",
          [](const HandModel& h, const ArrayD& palm, const ArrayD& joints) {
            check_shape(joints, {h.fingers(), h.links() + 1, 3}, "joints");
            std::vector<Vec3> j;
            auto r = joints.unchecked<3>();
            for (int i = 0; i < h.fingers(); ++i)
              for (int n = 0; n <= h.links(); ++n) j.emplace_back(r(i, n, 0), r(i, n, 1), r(i, n, 2));
            const MatrixX a = h.angles_from_joints(to_pose(palm, "palm_pose"), j);
            py::array_t<double> out({h.fingers(), h.links()});
            auto w = out.mutable_unchecked<2>();
            for (int i = 0; i < h.fingers(); ++i)
              for (int n = 0; n < h.links(); ++n) w(i, n) = a(i, n);
            return out;
          },
          py::arg("palm_pose"), py::arg("joints"), "Joint angles (M, N) from joint positions (M, N+1, 3).")
      .def(
          "roots",
          [](const HandModel& h, const ArrayD& palm) {
            const Pose p = to_pose(palm, "palm_pose");
            py::array_t<double> out({h.fingers(), 3});
            auto r = out.mutable_unchecked<2>();
            for (int i = 0; i < h.fingers(); ++i) {
              const Vec3 x = h.root(p, i);
              for (int k = 0; k < 3; ++k) r(i, k) = x[k];
            }
            return out;
          },
          py::arg("palm_pose"), "Finger roots R_m (M, 3) in the world.")
      .def(
          "planes",
          [](const HandModel& h, const ArrayD& palm) {
            const Pose p = to_pose(palm, "palm_pose");
            py::array_t<double> out({h.fingers(), 3, 3});
            auto r = out.mutable_unchecked<3>();
            for (int i = 0; i < h.fingers(); ++i) {
              const FingerPlane pl = h.plane(p, i);
              for (int k = 0; k < 3; ++k) r(i, 0, k) = pl.origin[k], r(i, 1, k) = pl.u[k], r(i, 2, k) = pl.p[k];
            }
            return out;
          },
          py::arg("palm_pose"),
          "Finger planes (M, 3, 3): rows origin (the plane's point nearest P_o), outward u_m, palm normal p.");
}
