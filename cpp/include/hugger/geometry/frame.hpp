/// \file frame.hpp
/// The rules for the frames a caller gives the engine: rigid poses and plane frames.
#pragma once

#include <string>

#include "hugger/types.hpp"

namespace hugger {

/// Throws std::invalid_argument, saying what is wrong, unless `pose` is a rigid transform:
/// finite, last row (0, 0, 0, 1), and a rotation part R with |R^T R - I| (largest entry) and
/// |det R - 1| at most kRigidTolerance. The one owner of the rule: the planner checks its start
/// pose by it, the binding every pose it is given, and Python calls it as hugger._core.check_pose.
void check_pose(const Eigen::Matrix4d& pose, const std::string& name = "palm_pose");

/// Throws std::invalid_argument unless `origin` is finite and `u`, `v` are orthonormal (within
/// 1e-9): the frame of the plane origin + a u + b v.
void check_plane_frame(const Vec3& origin, const Vec3& u, const Vec3& v);

}  // namespace hugger
