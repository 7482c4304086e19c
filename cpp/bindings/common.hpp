// Shared helpers of the binding files: numpy <-> Eigen conversions with shape checks.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>

#include "hugger/types.hpp"

namespace hugger::py_helpers {

namespace py = pybind11;
using ArrayD = py::array_t<double, py::array::c_style | py::array::forcecast>;

inline void check_shape(const py::array& a, std::initializer_list<py::ssize_t> shape, const char* name) {
  bool ok = a.ndim() == static_cast<py::ssize_t>(shape.size());
  int i = 0;
  for (py::ssize_t s : shape) {
    if (!ok) break;
    if (s >= 0 && a.shape(i) != s) ok = false;
    ++i;
  }
  if (!ok) {
    std::string want = "(", got = "(";
    i = 0;
    for (py::ssize_t s : shape) want += (i++ ? ", " : "") + (s < 0 ? std::string("n") : std::to_string(s));
    for (py::ssize_t k = 0; k < a.ndim(); ++k) got += (k ? ", " : "") + std::to_string(a.shape(k));
    throw py::value_error(std::string(name) + " must have shape " + want + "), got " + got + ")");
  }
}

inline Vec3 to_vec3(const ArrayD& a, const char* name) {
  check_shape(a, {3}, name);
  return Vec3(a.at(0), a.at(1), a.at(2));
}

inline Pose to_pose(const ArrayD& a, const char* name) {
  check_shape(a, {4, 4}, name);
  Eigen::Matrix4d m;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m(i, j) = a.at(i, j);
  if (!m.allFinite()) throw py::value_error(std::string(name) + " holds non-finite numbers");
  if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0)
    throw py::value_error(std::string(name) + " must be a homogeneous transform with last row (0, 0, 0, 1)");
  Pose p = Pose::Identity();
  p.matrix() = m;
  return p;
}

inline py::array_t<double> from_pose(const Pose& p) {
  py::array_t<double> out({4, 4});
  auto r = out.mutable_unchecked<2>();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r(i, j) = p.matrix()(i, j);
  return out;
}

inline MatrixX to_matrix(const ArrayD& a) {
  MatrixX m(a.shape(0), a.shape(1));
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    for (py::ssize_t j = 0; j < a.shape(1); ++j) m(i, j) = r(i, j);
  return m;
}

}  // namespace hugger::py_helpers
