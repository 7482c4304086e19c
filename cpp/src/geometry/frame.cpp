#include "hugger/geometry/frame.hpp"

#include <cmath>
#include <iomanip>

#include "hugger/check.hpp"

namespace hugger {

void check_pose(const Eigen::Matrix4d& pose, const std::string& name) {
  HUGGER_CHECK_ARGUMENT(pose.allFinite(), name << " holds non-finite numbers");
  // Where an object's coordinates may lie (kMaxCoordinate): a pose beyond is no scene's.
  HUGGER_CHECK_ARGUMENT((pose.topRightCorner<3, 1>().cwiseAbs().maxCoeff() <= kMaxCoordinate),
                        name << "'s translation lies beyond " << kMaxCoordinate << " m of the origin");
  HUGGER_CHECK_ARGUMENT(pose(3, 0) == 0.0 && pose(3, 1) == 0.0 && pose(3, 2) == 0.0 && pose(3, 3) == 1.0,
                        name << " must be a homogeneous transform with last row (0, 0, 0, 1), got (" << pose(3, 0)
                             << ", " << pose(3, 1) << ", " << pose(3, 2) << ", " << pose(3, 3) << ")");
  const Mat3 R = pose.topLeftCorner<3, 3>();
  const double orth = (R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff();
  const double det = R.determinant();
  HUGGER_CHECK_ARGUMENT(orth <= kRigidTolerance && std::abs(det - 1.0) <= kRigidTolerance,
                        name << " must be a rigid transform (orthonormal rotation with determinant +1), but it "
                             << (det < 0.0 ? "reflects (det < 0)" : "scales or shears") << ": |R^T R - I| = "
                             << std::setprecision(3) << orth << ", det R = " << std::setprecision(6) << det);
}

void check_plane_frame(const Vec3& origin, const Vec3& u, const Vec3& v) {
  HUGGER_CHECK_ARGUMENT(origin.allFinite(), "origin must be finite");
  HUGGER_CHECK_ARGUMENT(std::abs(u.norm() - 1) <= 1e-9 && std::abs(v.norm() - 1) <= 1e-9 && std::abs(u.dot(v)) <= 1e-9,
                        "u and v must be orthonormal");
}

}  // namespace hugger
