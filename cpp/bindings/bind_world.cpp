#include <cmath>
#include <memory>
#include <string>

#include "common.hpp"
#include "hugger/world/object.hpp"
#include "hugger/world/section_skin.hpp"
#include "hugger/world/simulated_world.hpp"

namespace py = pybind11;
using namespace hugger;
using namespace hugger::py_helpers;

void bind_world(py::module_& m) {
  py::class_<Object, std::shared_ptr<Object>>(m, "Object", "A closed, consistently oriented triangle mesh O.")
      .def(py::init([](const ArrayD& vertices, const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>& faces) {
             check_shape(vertices, {-1, 3}, "vertices");
             check_shape(faces, {-1, 3}, "faces");
             PointsN3 v(vertices.shape(0), 3);
             std::copy(vertices.data(), vertices.data() + vertices.size(), v.data());
             FacesN3 f(faces.shape(0), 3);
             std::copy(faces.data(), faces.data() + faces.size(), f.data());
             py::gil_scoped_release release;
             return std::make_shared<Object>(v, f);
           }),
           py::arg("vertices"), py::arg("faces"))
      .def_property_readonly("volume", &Object::volume, "Enclosed volume (m^3).")
      .def_property_readonly("bounds", [](const Object& o) {
        py::array_t<double> out({2, 3});
        auto r = out.mutable_unchecked<2>();
        for (int k = 0; k < 3; ++k) r(0, k) = o.bounds().lo[k], r(1, k) = o.bounds().hi[k];
        return out;
      }, "Axis-aligned bounds (2, 3): min and max corners.")
      .def(
          "inside",
          [](const Object& o, const ArrayD& points) {
            check_shape(points, {-1, 3}, "points");
            py::array_t<bool> out(points.shape(0));
            auto r = points.unchecked<2>();
            auto w = out.mutable_unchecked<1>();
            for (py::ssize_t i = 0; i < points.shape(0); ++i) w(i) = o.inside(Vec3(r(i, 0), r(i, 1), r(i, 2)));
            return out;
          },
          py::arg("points"), "True for each point (n, 3) strictly inside O.")
      .def(
          "signed_distance",
          [](const Object& o, const ArrayD& points) {
            check_shape(points, {-1, 3}, "points");
            py::array_t<double> out(points.shape(0));
            auto r = points.unchecked<2>();
            auto w = out.mutable_unchecked<1>();
            for (py::ssize_t i = 0; i < points.shape(0); ++i) {
              const Vec3 p(r(i, 0), r(i, 1), r(i, 2));
              w(i) = o.nearest(p, p).signed_distance;
            }
            return out;
          },
          py::arg("points"), "Signed distance (n,) of each point (n, 3) to O's surface; negative inside.")
      .def(
          "closest",
          [](const Object& o, const ArrayD& points) {
            check_shape(points, {-1, 3}, "points");
            const py::ssize_t n = points.shape(0);
            py::array_t<double> dist(n), on({n, py::ssize_t(3)}), normal({n, py::ssize_t(3)});
            py::array_t<std::int64_t> tri(n);
            auto r = points.unchecked<2>();
            auto wd = dist.mutable_unchecked<1>();
            auto wp = on.mutable_unchecked<2>();
            auto wn = normal.mutable_unchecked<2>();
            auto wt = tri.mutable_unchecked<1>();
            for (py::ssize_t i = 0; i < n; ++i) {
              const Vec3 p(r(i, 0), r(i, 1), r(i, 2));
              const SignedNearest sn = o.nearest(p, p);
              const int t = sn.triangle;
              const Vec3& fn = o.face_normal(t);
              wd(i) = sn.signed_distance;
              wt(i) = t;
              for (int k = 0; k < 3; ++k) wp(i, k) = sn.on_object[k], wn(i, k) = fn[k];
            }
            py::dict d;
            d["distance"] = dist;
            d["point"] = on;
            d["normal"] = normal;
            d["triangle"] = tri;
            return d;
          },
          py::arg("points"),
          "For points (n, 3): signed distance (n,), closest surface point (n, 3), the outward unit normal "
          "of its triangle (n, 3) and the triangle index (n,).")
      .def(
          "segment_distance",
          [](const Object& o, const ArrayD& a, const ArrayD& b) {
            check_shape(a, {-1, 3}, "a");
            check_shape(b, {a.shape(0), 3}, "b");
            py::array_t<double> out(a.shape(0));
            auto ra = a.unchecked<2>();
            auto rb = b.unchecked<2>();
            auto w = out.mutable_unchecked<1>();
            for (py::ssize_t i = 0; i < a.shape(0); ++i)
              w(i) = o.nearest(Vec3(ra(i, 0), ra(i, 1), ra(i, 2)), Vec3(rb(i, 0), rb(i, 1), rb(i, 2))).signed_distance;
            return out;
          },
          py::arg("a"), py::arg("b"),
          "Signed distance (n,) of each segment [a_i, b_i] to O; <= 0 when it crosses the surface.")
      .def(
          "section",
          [](const Object& o, const ArrayD& origin, const ArrayD& u, const ArrayD& v) {
            const Vec3 uu = to_vec3(u, "u"), vv = to_vec3(v, "v");
            if (std::abs(uu.norm() - 1) > 1e-9 || std::abs(vv.norm() - 1) > 1e-9 || std::abs(uu.dot(vv)) > 1e-9)
              throw py::value_error("u and v must be orthonormal");
            const Section s = o.section(to_vec3(origin, "origin"), uu, vv);
            py::list loops;
            for (const auto& loop : s.loops()) {
              py::array_t<double> a({static_cast<py::ssize_t>(loop.size()), py::ssize_t(2)});
              auto w = a.mutable_unchecked<2>();
              for (std::size_t i = 0; i < loop.size(); ++i) w(i, 0) = loop[i].x(), w(i, 1) = loop[i].y();
              loops.append(a);
            }
            return loops;
          },
          py::arg("origin"), py::arg("u"), py::arg("v"),
          "Section of O by the plane origin + a u + b v: a list of closed loops (k, 2) in (a, b); "
          "outer loops counter-clockwise.")
      .def(
          "section_region",
          [](std::shared_ptr<Object> o, const ArrayD& origin, const ArrayD& u, const ArrayD& v, double radius,
             double flatten) {
            const Vec3 uu = to_vec3(u, "u"), vv = to_vec3(v, "v"), oo = to_vec3(origin, "origin");
            if (!oo.allFinite()) throw py::value_error("origin must be finite");
            if (std::abs(uu.norm() - 1) > 1e-9 || std::abs(vv.norm() - 1) > 1e-9 || std::abs(uu.dot(vv)) > 1e-9)
              throw py::value_error("u and v must be orthonormal");
            if (!(radius >= 0.0) || !std::isfinite(radius))
              throw py::value_error("radius must be finite and >= 0, got " + std::to_string(radius));
            if (!(flatten > 0.0) || !std::isfinite(flatten))
              throw py::value_error("flatten must be positive, got " + std::to_string(flatten));
            FingerPlane plane;
            plane.origin = oo;
            plane.u = uu;
            plane.p = vv;
            std::unique_ptr<PlaneRegion> region;
            {
              py::gil_scoped_release release;
              region = std::make_unique<PlaneRegion>(o, plane, radius, flatten);
            }
            const auto& segs = region->segments();
            const py::ssize_t n = static_cast<py::ssize_t>(segs.size());
            py::array_t<double> seg({n, py::ssize_t(2), py::ssize_t(2)}), nrm({n, py::ssize_t(2)});
            auto ws = seg.mutable_unchecked<3>();
            auto wn = nrm.mutable_unchecked<2>();
            for (py::ssize_t i = 0; i < n; ++i) {
              const auto& sg = segs[static_cast<std::size_t>(i)];
              ws(i, 0, 0) = sg.a.x(), ws(i, 0, 1) = sg.a.y(), ws(i, 1, 0) = sg.b.x(), ws(i, 1, 1) = sg.b.y();
              wn(i, 0) = sg.normal.x(), wn(i, 1) = sg.normal.y();
            }
            py::dict d;
            d["segments"] = seg;
            d["normals"] = nrm;
            return d;
          },
          py::arg("origin"), py::arg("u"), py::arg("v"), py::arg("radius"), py::arg("flatten") = 1e-6,
          "The section skin's region of the plane origin + a u + b v for links of `radius`: the points "
          "within `radius` of O. Returns its boundary as flattened segments (k, 2, 2) in (a, b), at most "
          "`flatten` m outside the exact curve, and their outward unit normals (k, 2).")
      .def(
          "palm_gap",
          [](std::shared_ptr<Object> o, const ArrayD& pose, double radius, double thickness) {
            if (!(radius > 0) || !(thickness > 0)) throw py::value_error("palm radius and thickness must be positive");
            const Pose p = to_pose(pose, "palm_pose");
            py::gil_scoped_release release;
            return SimulatedWorld(o).palm(p, radius, thickness);
          },
          py::arg("palm_pose"), py::arg("radius"), py::arg("thickness"),
          "Gap (m) between the palm disk of pose (4, 4) and O; negative when they overlap.");
}
