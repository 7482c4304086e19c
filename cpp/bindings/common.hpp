// Shared helpers of the binding files. The binding converts: numpy arrays to Eigen types (it
// checks the number of dimensions and the sizes a type fixes, naming the argument), Python
// numbers to C++ numbers (refusing bools and non-numbers), and engine results back through
// pybind11's Eigen casters (row-major types give C-ordered arrays). The values' rules are the
// engine's (hugger/check.hpp): std::invalid_argument reaches Python as ValueError.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hugger/geometry/frame.hpp"
#include "hugger/types.hpp"

namespace hugger::py_helpers {

namespace py = pybind11;

/// How a Planner senses an Object (exported as hugger._core.SKINS): "mesh", 3D queries on the
/// mesh (the reference), or "section", 2D geometry in each finger plane.
inline constexpr const char* kSkins[] = {"mesh", "section"};
using ArrayD = py::array_t<double, py::array::c_style | py::array::forcecast>;
using ArrayI = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
using RowMatrix4 = Eigen::Matrix<double, 4, 4, Eigen::RowMajor>;

/// A ValueError unless `a` has shape `shape` (-1: any size along that axis).
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
  return Eigen::Map<const Vec3>(a.data());
}

/// A 2-D array as a matrix; which shape it must have, the engine checks.
inline MatrixX to_matrix(const ArrayD& a, const char* name) {
  if (a.ndim() != 2)
    throw py::value_error(std::string(name) + " must be a 2-D array, got " + std::to_string(a.ndim()) + " dimensions");
  return Eigen::Map<const MatrixX>(a.data(), a.shape(0), a.shape(1));
}

/// An optional 2-D array: None gives the empty matrix (the engine's default).
inline MatrixX optional_matrix(const std::optional<ArrayD>& a, const char* name) {
  return a ? to_matrix(*a, name) : MatrixX();
}

/// An (n, 3) array as rows: points (PointsN3 from ArrayD) or triangles (FacesN3 from ArrayI).
template <class Rows, class Array>
Rows to_rows(const Array& a, const char* name) {
  check_shape(a, {-1, 3}, name);
  return Eigen::Map<const Rows>(a.data(), a.shape(0), 3);
}

/// An (n, 3) array of query points, each finite (a NaN or infinite point has no answer).
inline PointsN3 finite_points(const ArrayD& a, const char* name) {
  PointsN3 p = to_rows<PointsN3>(a, name);
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    if (!p.row(i).allFinite())
      throw py::value_error(std::string(name) + " must be finite, got a NaN or infinite coordinate at row " +
                            std::to_string(i));
  return p;
}

/// An array of shape (..., 3) as its points in order (finger-major joints, say).
inline std::vector<Vec3> to_vec3s(const ArrayD& a) {
  std::vector<Vec3> out;
  const double* p = a.data();
  for (py::ssize_t i = 0; i + 2 < a.size(); i += 3) out.emplace_back(p[i], p[i + 1], p[i + 2]);
  return out;
}

/// A (4, 4) array as a pose, which must be rigid (hugger::check_pose).
inline Pose to_pose(const ArrayD& a, const char* name) {
  check_shape(a, {4, 4}, name);
  const Eigen::Matrix4d m = Eigen::Map<const RowMatrix4>(a.data());
  check_pose(m, name);
  Pose p = Pose::Identity();
  p.matrix() = m;
  return p;
}

inline RowMatrix4 from_pose(const Pose& p) { return p.matrix(); }

/// `points` (each a Vec3) as an array of `shape` (its last axis 3).
inline py::array_t<double> vec3s_array(const std::vector<Vec3>& points, std::vector<py::ssize_t> shape) {
  py::array_t<double> out(std::move(shape));
  double* w = out.mutable_data();
  for (const Vec3& x : points) w[0] = x[0], w[1] = x[1], w[2] = x[2], w += 3;
  return out;
}

/// `value` as a double: a real number (int, float, a numpy number: numbers.Real), not a bool;
/// otherwise a ValueError "<name> must be a number, got ...". Its range is the engine's to check.
inline double real_number(const py::handle& value, const char* name) {
  const py::object real = py::module_::import("numbers").attr("Real");
  if (PyBool_Check(value.ptr()) || !py::isinstance(value, real))
    throw py::value_error(std::string(name) + " must be a number, got " + py::repr(value).cast<std::string>());
  const double x = PyFloat_AsDouble(value.ptr());
  if (x == -1.0 && PyErr_Occurred()) throw py::error_already_set();  // e.g. an int beyond any double
  return x;
}

/// `value` as a long: a whole number (numbers.Integral: int, a numpy integer), not a bool;
/// otherwise a ValueError "<name> must be a whole number, got ...".
inline long whole_number(const py::handle& value, const char* name) {
  const py::object integral = py::module_::import("numbers").attr("Integral");
  const std::string got = py::repr(value).cast<std::string>();
  if (PyBool_Check(value.ptr()) || !py::isinstance(value, integral))
    throw py::value_error(std::string(name) + " must be a whole number, got " + got);
  const py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  if (!i) throw py::error_already_set();
  int overflow = 0;
  const long x = PyLong_AsLongAndOverflow(i.ptr(), &overflow);
  if (overflow) throw py::value_error(std::string(name) + " must be a whole number of at most 64 bits, got " + got);
  return x;
}

}  // namespace hugger::py_helpers
