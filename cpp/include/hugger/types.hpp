/// \file types.hpp
/// Aliases every part of Hugger uses. Units: metres, radians.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>

namespace hugger {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Pose = Eigen::Isometry3d;  ///< rigid transform, the same type as fcl::Transform3d
using PointsN3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using FacesN3 = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3, Eigen::RowMajor>;
using MatrixX = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
/// The largest coordinate or size (m) a query of a skin takes, and an object's vertex (Python's
/// hugger.world.MAX_COORDINATE, which checks the vertices, is this): beyond it the absolute
/// tolerances (1e-7 .. 1e-4 m) are below the spacing of doubles, and squares overflow long
/// before 1e308.
constexpr double kMaxCoordinate = 1e6;
/// A palm pose is rigid when |R^T R - I| (largest entry) and |det R - 1| are at most this.
/// The one owner of the rule: Python reads it as hugger._core.RIGID_TOLERANCE.
constexpr double kRigidTolerance = 1e-6;

}  // namespace hugger
