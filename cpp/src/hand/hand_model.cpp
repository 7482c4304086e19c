#include "hugger/hand/hand_model.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace hugger {

namespace {
void check_positive(const char* name, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    std::ostringstream os;
    os << name << " must be a positive finite number, got " << value;
    throw std::invalid_argument(os.str());
  }
}
}  // namespace

HandModel::HandModel(int fingers, int links, const MatrixX& link_lengths, double link_radius, double palm_radius,
                     double palm_thickness)
    : fingers_(fingers),
      links_(links),
      lengths_(link_lengths),
      link_radius_(link_radius),
      palm_radius_(palm_radius),
      palm_thickness_(palm_thickness) {
  if (fingers < 1 || fingers > 64)
    throw std::invalid_argument("fingers must be between 1 and 64, got " + std::to_string(fingers));
  if (links < 1 || links > 256)
    throw std::invalid_argument("links must be between 1 and 256, got " + std::to_string(links));
  if (lengths_.rows() != fingers || lengths_.cols() != links) {
    std::ostringstream os;
    os << "link_length must be a scalar or a (fingers, links) = (" << fingers << ", " << links
       << ") array, got (" << lengths_.rows() << ", " << lengths_.cols() << ")";
    throw std::invalid_argument(os.str());
  }
  for (int m = 0; m < fingers; ++m)
    for (int n = 0; n < links; ++n) check_positive("link_length", lengths_(m, n));
  if (!(link_radius >= 0.0) || !std::isfinite(link_radius)) {
    std::ostringstream os;
    os << "link_radius must be a finite number >= 0, got " << link_radius;
    throw std::invalid_argument(os.str());
  }
  if (links >= 3)
    for (int m = 0; m < fingers; ++m)
      for (int n = 0; n < links; ++n)
        if (lengths_(m, n) <= 2.0 * link_radius) {
          std::ostringstream os;
          os << "link_length (" << lengths_(m, n) << ") must exceed twice link_radius (" << link_radius
             << "), or the links of a straight finger overlap";
          throw std::invalid_argument(os.str());
        }
  check_positive("palm_radius", palm_radius);
  check_positive("palm_thickness", palm_thickness);
  if (link_radius >= palm_radius) {
    std::ostringstream os;
    os << "link_radius (" << link_radius << ") must be smaller than palm_radius (" << palm_radius << ")";
    throw std::invalid_argument(os.str());
  }
  if (fingers > 1) {
    const double gap = 2.0 * palm_radius * std::sin(kPi / fingers);
    if (gap <= 2.0 * link_radius) {
      std::ostringstream os;
      os << "the " << fingers << " finger roots are " << gap << " m apart on a palm of radius " << palm_radius
         << ": too close for links of radius " << link_radius;
      throw std::invalid_argument(os.str());
    }
  }
  for (int m = 0; m < fingers; ++m) finger_angles_.push_back(2.0 * kPi * m / fingers);
}

HandModel HandModel::uniform(int fingers, int links, double link_length, double link_radius, double palm_radius,
                             double palm_thickness) {
  if (fingers < 1 || links < 1)
    return HandModel(fingers, links, MatrixX(), link_radius, palm_radius, palm_thickness);
  return HandModel(fingers, links, MatrixX::Constant(fingers, links, link_length), link_radius, palm_radius,
                   palm_thickness);
}

double HandModel::extended_radius() const {
  double r = std::hypot(palm_radius_, palm_thickness_);
  for (int m = 0; m < fingers_; ++m) r = std::max(r, std::hypot(palm_radius_, finger_length(m)));
  return r;
}

Vec3 HandModel::root(const Pose& palm, int m) const {
  const double phi = finger_angles_[m];
  return palm * Vec3(palm_radius_ * std::cos(phi), palm_radius_ * std::sin(phi), 0.0);
}

FingerPlane HandModel::plane(const Pose& palm, int m) const {
  const double phi = finger_angles_[m];
  FingerPlane pl;
  pl.origin = palm.translation();
  pl.u = palm.linear() * Vec3(std::cos(phi), std::sin(phi), 0.0);
  pl.p = palm.linear().col(2);
  return pl;
}

std::vector<Vec2> HandModel::forward_planar(int m, const Vec2& root, const double* angles) const {
  std::vector<Vec2> j(links_ + 1);
  j[0] = root;
  double theta = 0.0;
  for (int n = 0; n < links_; ++n) {
    theta += angles[n];
    j[n + 1] = j[n] + lengths_(m, n) * Vec2(-std::sin(theta), std::cos(theta));
  }
  return j;
}

void HandModel::planar_angles(const std::vector<Vec2>& joints, double* angles) {
  double prev = 0.0;
  for (std::size_t n = 0; n + 1 < joints.size(); ++n) {
    const Vec2 d = joints[n + 1] - joints[n];
    const double abs_angle = std::atan2(-d.x(), d.y());
    double rel = abs_angle - prev;
    rel = std::remainder(rel, 2.0 * kPi);
    angles[n] = rel;
    prev = abs_angle;
  }
}

std::vector<Vec3> HandModel::forward(const Pose& palm, const MatrixX& angles) const {
  if (angles.rows() != fingers_ || angles.cols() != links_)
    throw std::invalid_argument("angles must be (fingers, links)");
  std::vector<Vec3> out;
  out.reserve(fingers_ * (links_ + 1));
  for (int m = 0; m < fingers_; ++m) {
    const FingerPlane pl = plane(palm, m);
    std::vector<double> a(angles.row(m).data(), angles.row(m).data() + links_);
    for (const Vec2& x : forward_planar(m, Vec2(palm_radius_, 0.0), a.data())) out.push_back(pl.to_world(x));
  }
  return out;
}

MatrixX HandModel::angles_from_joints(const Pose& palm, const std::vector<Vec3>& joints) const {
  if (static_cast<int>(joints.size()) != fingers_ * (links_ + 1))
    throw std::invalid_argument("joints must hold fingers * (links + 1) points");
  MatrixX angles(fingers_, links_);
  for (int m = 0; m < fingers_; ++m) {
    const FingerPlane pl = plane(palm, m);
    std::vector<Vec2> j;
    for (int n = 0; n <= links_; ++n) j.push_back(pl.to_plane(joints[m * (links_ + 1) + n]));
    planar_angles(j, angles.row(m).data());
  }
  return angles;
}

}  // namespace hugger
