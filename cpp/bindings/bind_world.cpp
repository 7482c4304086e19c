#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>

#include "common.hpp"
#include "hugger/check.hpp"
#include "hugger/world/object.hpp"
#include "hugger/world/section_skin.hpp"
#include "hugger/world/simulated_world.hpp"

namespace py = pybind11;
using namespace hugger;
using namespace hugger::py_helpers;

namespace {

using Points2 = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;

Points2 rows_of(const std::vector<Vec2>& points) {
  Points2 out(static_cast<Eigen::Index>(points.size()), 2);
  for (std::size_t i = 0; i < points.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  return out;
}

}  // namespace

void bind_world(py::module_& m) {
  py::class_<Object, std::shared_ptr<Object>>(m, "Object", "A closed, consistently oriented triangle mesh O.")
      .def(py::init([](const ArrayD& vertices, const ArrayI& faces) {
             PointsN3 v = to_rows<PointsN3>(vertices, "vertices");
             FacesN3 f = to_rows<FacesN3>(faces, "faces");
             py::gil_scoped_release release;
             return std::make_shared<Object>(std::move(v), std::move(f));  // kept, not copied
           }),
           py::arg("vertices"), py::arg("faces"))
      .def_property_readonly("volume", &Object::volume, "Enclosed volume (m^3).")
      .def_property_readonly("bounds", [](const Object& o) {
        PointsN3 out(2, 3);
        out << o.bounds().lo.transpose(), o.bounds().hi.transpose();
        return out;
      }, "Axis-aligned bounds (2, 3): min and max corners.")
      .def(
          "inside",
          [](const Object& o, const ArrayD& points) {
            const PointsN3 p = finite_points(points, "points");
            Eigen::Array<bool, Eigen::Dynamic, 1> out(p.rows());
            for (Eigen::Index i = 0; i < p.rows(); ++i) out(i) = o.inside(p.row(i).transpose());
            return out;
          },
          py::arg("points"), "True for each point (n, 3) strictly inside O.")
      .def(
          "signed_distance",
          [](const Object& o, const ArrayD& points) {
            const PointsN3 p = finite_points(points, "points");
            Eigen::VectorXd out(p.rows());
            for (Eigen::Index i = 0; i < p.rows(); ++i) out(i) = o.nearest(p.row(i), p.row(i)).signed_distance;
            return out;
          },
          py::arg("points"), "Signed distance (n,) of each point (n, 3) to O's surface; negative inside.")
      .def(
          "closest",
          [](const Object& o, const ArrayD& points, double max_distance) {
            const PointsN3 p = finite_points(points, "points");
            HUGGER_CHECK_ARGUMENT(max_distance >= 0.0, "max_distance must be >= 0, got " << max_distance);
            const Eigen::Index n = p.rows();
            Eigen::VectorXd dist(n);
            PointsN3 on(n, 3), normal(n, 3);
            Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1> tri(n);
            {
              py::gil_scoped_release release;  // queries of a const Object: other threads may query too
              const double nan = std::numeric_limits<double>::quiet_NaN();
              for (Eigen::Index i = 0; i < n; ++i) {
                const SignedNearest sn = o.nearest(p.row(i), p.row(i), max_distance);
                dist(i) = sn.signed_distance;
                tri(i) = sn.triangle;
                if (sn.triangle < 0) {  // nothing within max_distance
                  on.row(i).setConstant(nan);
                  normal.row(i).setConstant(nan);
                } else {
                  on.row(i) = sn.on_object.transpose();
                  normal.row(i) = o.face_normal(sn.triangle).transpose();
                }
              }
            }
            py::dict d;
            d["distance"] = dist;
            d["point"] = on;
            d["normal"] = normal;
            d["triangle"] = tri;
            return d;
          },
          py::arg("points"), py::arg("max_distance") = kInf,
          "For points (n, 3): signed distance (n,), closest surface point (n, 3), the outward unit normal "
          "of its triangle (n, 3) and the triangle index (n,). Points farther than `max_distance` from "
          "the surface may get distance +inf or -inf (the sign still says outside or inside), NaN point "
          "and normal, and triangle -1.")
      .def(
          "segment_distance",
          [](const Object& o, const ArrayD& a, const ArrayD& b) {
            const PointsN3 pa = finite_points(a, "a");
            check_shape(b, {pa.rows(), 3}, "b");
            const PointsN3 pb = finite_points(b, "b");
            Eigen::VectorXd out(pa.rows());
            py::gil_scoped_release release;
            for (Eigen::Index i = 0; i < pa.rows(); ++i) out(i) = o.nearest(pa.row(i), pb.row(i)).signed_distance;
            return out;
          },
          py::arg("a"), py::arg("b"),
          "Signed distance (n,) of each segment [a_i, b_i] to O; <= 0 when it crosses the surface.")
      .def(
          "section",
          [](const Object& o, const ArrayD& origin, const ArrayD& u, const ArrayD& v) {
            const Section s = o.section(to_vec3(origin, "origin"), to_vec3(u, "u"), to_vec3(v, "v"));
            std::vector<Points2> loops;
            for (const auto& loop : s.loops()) loops.push_back(rows_of(loop));
            return loops;
          },
          py::arg("origin"), py::arg("u"), py::arg("v"),
          "Section of O by the plane origin + a u + b v: a list of closed loops (k, 2) in (a, b); "
          "outer loops counter-clockwise.")
      .def(
          "section_region",
          [](std::shared_ptr<Object> o, const ArrayD& origin, const ArrayD& u, const ArrayD& v, double radius,
             double flatten) {
            FingerPlane plane;
            plane.origin = to_vec3(origin, "origin");
            plane.u = to_vec3(u, "u");
            plane.p = to_vec3(v, "v");
            std::unique_ptr<PlaneRegion> region;
            {
              py::gil_scoped_release release;
              region = std::make_unique<PlaneRegion>(o, plane, radius, flatten);
            }
            const auto& segs = region->segments();
            const Eigen::Index n = static_cast<Eigen::Index>(segs.size());
            Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> ends(n, 4);  // a then b, as (k, 2, 2)
            Points2 normals(n, 2);
            for (Eigen::Index i = 0; i < n; ++i) {
              const auto& sg = segs[static_cast<std::size_t>(i)];
              ends.row(i) << sg.a.transpose(), sg.b.transpose();
              normals.row(i) = sg.normal.transpose();
            }
            py::dict d;
            d["segments"] = py::cast(ends).attr("reshape")(n, 2, 2);
            d["normals"] = normals;
            return d;
          },
          py::arg("origin"), py::arg("u"), py::arg("v"), py::arg("radius"), py::arg("flatten") = PlaneRegion::kDefaultFlatten,
          "The section skin's region of the plane origin + a u + b v for links of `radius`: the points "
          "within `radius` of O. Returns its boundary as flattened segments (k, 2, 2) in (a, b), at most "
          "`flatten` m outside the exact curve, and their outward unit normals (k, 2).")
      .def(
          "palm_gap",
          [](std::shared_ptr<Object> o, const ArrayD& pose, double radius, double thickness) {
            check_palm_query(radius, thickness, kInf);
            const Pose p = to_pose(pose, "palm_pose");
            py::gil_scoped_release release;
            return SimulatedWorld(o).palm(p, radius, thickness);
          },
          py::arg("palm_pose"), py::arg("radius"), py::arg("thickness"),
          "Gap (m) between the palm disk of pose (4, 4) and O; negative when they overlap.");
}
