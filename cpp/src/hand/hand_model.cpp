#include "hugger/hand/hand_model.hpp"

#include <algorithm>
#include <cmath>

#include "hugger/check.hpp"
#include "hugger/geometry/distance.hpp"

namespace hugger {

namespace {
void check_positive(const char* name, double value) {
  HUGGER_CHECK_ARGUMENT(value > 0.0 && std::isfinite(value), name << " must be a positive finite number, got " << value);
}

/// An optional layout matrix: empty (the default), or rows x cols.
void check_layout_shape(const MatrixX& a, int rows, int cols, const char* name) {
  if (a.size() != 0) HUGGER_CHECK_ARGUMENT_SHAPE(a, rows, cols, name);
}

/// Tolerance (m, or relative for unit vectors) on z = 0 and on a root's distance from the palm
/// centre; the independent checker allows 1e-9.
constexpr double kLayoutTolerance = 1e-10;

}  // namespace

HandModel::HandModel(int fingers, int links, const MatrixX& link_lengths, double link_radius, double palm_radius,
                     double palm_thickness, const HandLayout& layout)
    : HandModel(fingers, links, link_lengths, link_radius, palm_radius, palm_thickness, false) {
  // The base constructor checked the sizes and the rim layout; a general layout replaces the
  // rim and is checked on its own.
  const int M = fingers, N = links;
  check_layout_shape(layout.roots, M, 3, "finger_roots");
  check_layout_shape(layout.directions, M, 3, "finger_directions");
  check_layout_shape(layout.rest, M, N, "rest_angles");
  check_layout_shape(layout.lower, M, N, "lower joint limits");
  check_layout_shape(layout.upper, M, N, "upper joint limits");
  general_ = true;
  roots_.resize(M, 3);
  dirs_.resize(M, 3);
  for (int m = 0; m < M; ++m) {
    const double phi = finger_angles_[m];
    Vec3 r = layout.roots.size() ? Vec3(layout.roots.row(m).transpose())
                                 : Vec3(palm_radius * std::cos(phi), palm_radius * std::sin(phi), 0.0);
    Vec3 d = layout.directions.size() ? Vec3(layout.directions.row(m).transpose())
                                      : Vec3(std::cos(phi), std::sin(phi), 0.0);
    HUGGER_CHECK_ARGUMENT(r.allFinite(), "the root of finger " << m << " holds non-finite numbers");
    HUGGER_CHECK_ARGUMENT(std::abs(r.z()) <= kLayoutTolerance,
                          "the root of finger " << m << " must lie on the palm's front face (z = 0 in the palm frame), got z = "
                                                << r.z() << " m");
    const double rho = std::hypot(r.x(), r.y());
    HUGGER_CHECK_ARGUMENT(rho <= palm_radius + kLayoutTolerance,
                          "the root of finger " << m << " is " << rho << " m from the palm centre: off the palm (palm_radius "
                                                << palm_radius << " m)");
    HUGGER_CHECK_ARGUMENT(d.allFinite(), "the direction of finger " << m << " holds non-finite numbers");
    const double dl = std::hypot(d.x(), d.y());
    HUGGER_CHECK_ARGUMENT(dl > 1e-12 && std::abs(d.z()) <= kLayoutTolerance * std::max(1.0, d.norm()),
                          "the direction of finger " << m << " must be a non-zero vector in the palm plane (z = 0), got ("
                                                     << d.x() << ", " << d.y() << ", " << d.z() << ")");
    r.z() = 0.0;
    d = Vec3(d.x() / dl, d.y() / dl, 0.0);
    roots_.row(m) = r.transpose();
    dirs_.row(m) = d.transpose();
    finger_angles_[m] = std::atan2(d.y(), d.x());
  }
  rest_ = layout.rest.size() ? layout.rest : MatrixX::Zero(M, N);
  lower_ = layout.lower.size() ? layout.lower : MatrixX::Constant(M, N, -kInf);
  upper_ = layout.upper.size() ? layout.upper : MatrixX::Constant(M, N, kInf);
  for (int m = 0; m < M; ++m)
    for (int n = 0; n < N; ++n) {
      const std::string j = "joint " + std::to_string(n) + " of finger " + std::to_string(m);
      const double lo = lower_(m, n), hi = upper_(m, n), q = rest_(m, n);
      HUGGER_CHECK_ARGUMENT(lo <= hi && lo != kInf && hi != -kInf,  // false for NaN
                            "the limits of " << j << " must be lower <= upper (rad, +-inf: unlimited), got [" << lo << ", "
                                             << hi << "]");
      HUGGER_CHECK_ARGUMENT(std::isfinite(q) && std::abs(q) <= kPi,
                            "the rest angle of " << j << " must be a finite angle in [-pi, pi] rad, got " << q);
      HUGGER_CHECK_ARGUMENT(q >= lo && q <= hi,
                            "the rest angle of " << j << " (" << q << " rad) is outside its limits [" << lo << ", " << hi << "]");
      if (std::isfinite(lo) || std::isfinite(hi)) has_limits_ = true;
    }
  // At rest: no joint behind the palm's front plane, no finger through another or itself.
  std::vector<std::vector<Vec3>> rest3(M);
  for (int m = 0; m < M; ++m) {
    const std::vector<Vec2> c = rest_chain(m);
    const Vec3 o = roots_.row(m).transpose() - root2d(m).x() * direction_palm(m);
    for (int n = 0; n <= N; ++n) {
      HUGGER_CHECK_ARGUMENT(c[n].y() >= -1e-12, "at rest, joint " << n << " of finger " << m << " lies " << -c[n].y()
                                                                  << " m behind the palm's front plane: the rest angles bend it too far");
      rest3[m].push_back(o + c[n].x() * direction_palm(m) + c[n].y() * Vec3::UnitZ());
    }
  }
  const double sep = std::max(2.0 * link_radius, 1e-7), sep2 = sep * sep;
  for (int m = 0; m < M; ++m)
    for (int k = m; k < M; ++k)
      for (int a = 0; a < N; ++a)
        for (int b = (k == m ? a + 2 : 0); b < N; ++b) {
          const double d2 = segment_segment_squared(rest3[m][a], rest3[m][a + 1], rest3[k][b], rest3[k][b + 1]);
          HUGGER_CHECK_ARGUMENT(d2 >= sep2, "at rest, link " << a << " of finger " << m << " and link " << b << " of finger "
                                                             << k << " are " << std::sqrt(d2) << " m apart (axis to axis), less than "
                                                             << sep << ": the fingers intersect");
        }
}

HandModel::HandModel(int fingers, int links, const MatrixX& link_lengths, double link_radius, double palm_radius,
                     double palm_thickness)
    : HandModel(fingers, links, link_lengths, link_radius, palm_radius, palm_thickness, true) {}

HandModel::HandModel(int fingers, int links, const MatrixX& link_lengths, double link_radius, double palm_radius,
                     double palm_thickness, bool rim)
    : fingers_(fingers),
      links_(links),
      lengths_(link_lengths),
      link_radius_(link_radius),
      palm_radius_(palm_radius),
      palm_thickness_(palm_thickness) {
  HUGGER_CHECK_ARGUMENT(fingers >= 1 && fingers <= kMaxFingers,
                        "fingers must be between 1 and " << kMaxFingers << ", got " << fingers);
  HUGGER_CHECK_ARGUMENT(links >= 1 && links <= kMaxLinks, "links must be between 1 and " << kMaxLinks << ", got " << links);
  HUGGER_CHECK_ARGUMENT(lengths_.rows() == fingers && lengths_.cols() == links,
                        "link_length must be a scalar or a (fingers, links) = (" << fingers << ", " << links
                                                                                 << ") array, got (" << lengths_.rows()
                                                                                 << ", " << lengths_.cols() << ")");
  for (int m = 0; m < fingers; ++m)
    for (int n = 0; n < links; ++n) check_positive("link_length", lengths_(m, n));
  HUGGER_CHECK_ARGUMENT(link_radius >= 0.0 && std::isfinite(link_radius),
                        "link_radius must be a finite number >= 0, got " << link_radius);
  if (links >= 3)
    for (int m = 0; m < fingers; ++m)
      for (int n = 0; n < links; ++n)
        HUGGER_CHECK_ARGUMENT(lengths_(m, n) > 2.0 * link_radius,
                              "link_length (" << lengths_(m, n) << ") must exceed twice link_radius (" << link_radius
                                              << "), or the links of a straight finger overlap");
  check_positive("palm_radius", palm_radius);
  check_positive("palm_thickness", palm_thickness);
  HUGGER_CHECK_ARGUMENT(link_radius < palm_radius,
                        "link_radius (" << link_radius << ") must be smaller than palm_radius (" << palm_radius << ")");
  if (rim && fingers > 1) {
    const double gap = 2.0 * palm_radius * std::sin(kPi / fingers);
    HUGGER_CHECK_ARGUMENT(gap > 2.0 * link_radius, "the " << fingers << " finger roots are " << gap
                                                          << " m apart on a palm of radius " << palm_radius
                                                          << ": too close for links of radius " << link_radius);
  }
  for (int m = 0; m < fingers; ++m) finger_angles_.push_back(2.0 * kPi * m / fingers);
  rest_ = MatrixX::Zero(fingers, links);
  lower_ = MatrixX::Constant(fingers, links, -kInf);
  upper_ = MatrixX::Constant(fingers, links, kInf);
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
  if (!general_) {
    for (int m = 0; m < fingers_; ++m) r = std::max(r, std::hypot(palm_radius_, finger_length(m)));
    return r;
  }
  for (int m = 0; m < fingers_; ++m) {
    const std::vector<Vec2> c = rest_chain(m);
    const Vec3 o = root_palm(m) - c[0].x() * direction_palm(m);
    for (const Vec2& x : c) r = std::max(r, (o + x.x() * direction_palm(m) + x.y() * Vec3::UnitZ()).norm());
  }
  return r;
}

Vec3 HandModel::root_palm(int m) const {
  if (general_) return roots_.row(m).transpose();
  const double phi = finger_angles_[m];
  return Vec3(palm_radius_ * std::cos(phi), palm_radius_ * std::sin(phi), 0.0);
}

Vec3 HandModel::direction_palm(int m) const {
  if (general_) return dirs_.row(m).transpose();
  const double phi = finger_angles_[m];
  return Vec3(std::cos(phi), std::sin(phi), 0.0);
}

Vec2 HandModel::root2d(int m) const {
  if (!general_) return Vec2(palm_radius_, 0.0);
  return Vec2(roots_.row(m).dot(dirs_.row(m)), 0.0);
}

std::vector<Vec2> HandModel::rest_chain(int m) const { return forward_planar(m, root2d(m), rest_.row(m).data()); }

Vec3 HandModel::root(const Pose& palm, int m) const { return palm * root_palm(m); }

FingerPlane HandModel::plane(const Pose& palm, int m) const {
  FingerPlane pl;
  const Vec3 u = direction_palm(m);
  pl.origin = general_ ? Vec3(palm * (root_palm(m) - root2d(m).x() * u)) : Vec3(palm.translation());
  pl.u = palm.linear() * u;
  pl.p = palm.linear().col(2);
  return pl;
}

std::vector<Vec2> HandModel::forward_planar(int m, const Vec2& root, const double* angles) const {
  std::vector<Vec2> j;
  forward_planar(m, root, angles, &j);
  return j;
}

void HandModel::forward_planar(int m, const Vec2& root, const double* angles, std::vector<Vec2>* out) const {
  out->resize(links_ + 1);
  Vec2* j = out->data();
  j[0] = root;
  double theta = 0.0;
  for (int n = 0; n < links_; ++n) {
    theta += angles[n];
    j[n + 1] = j[n] + lengths_(m, n) * Vec2(-std::sin(theta), std::cos(theta));
  }
}

PlanePair plane_pair(const FingerPlane& a, const FingerPlane& b) {
  PlanePair out;
  const Vec3 na = a.normal().normalized(), nb = b.normal().normalized();
  const Vec3 e = na.cross(nb);  // along the line where the planes meet
  const double sin2 = e.squaredNorm();  // the squared sine of the planes' angle
  if (!(sin2 >= 1e-6)) return out;      // within 1e-3 rad of parallel: no bound
  // In each plane the unit normal to that line, w = e x n. A point of plane a, x = q + l e/|e| +
  // s wa, and one of plane b, y = q + l' e/|e| + s' wb, are at least |s wa - s' wb| apart, which
  // is at least sin(angle) max(|s|, |s'|): wa and wb make the planes' angle.
  const Vec3 wa = e.cross(na).normalized();
  const Vec3 q = (na.dot(a.origin) * nb.cross(e) + nb.dot(b.origin) * e.cross(na)) / sin2;  // in both planes
  out.w = Vec2(wa.dot(a.u), wa.dot(a.p));
  out.offset = wa.dot(q - a.origin);
  out.sin2 = sin2;
  return out;
}

void HandModel::planar_angles(const std::vector<Vec2>& joints, double* angles) {
  double prev = 0.0;
  for (std::size_t n = 0; n + 1 < joints.size(); ++n) {
    const Vec2 d = joints[n + 1] - joints[n];
    // A link along p (the rest chains of a rim hand, and their translations) needs no call:
    // atan2(+-0, y > 0) is +-0, the sign of -d.x() (C Annex F), bit for bit.
    const double abs_angle = d.x() == 0.0 && d.y() > 0.0 ? -d.x() : std::atan2(-d.x(), d.y());
    // Into [-pi, pi]: both angles lie in [-pi, pi], so rel lies in [-2 pi, 2 pi], where one
    // turn taken off its magnitude is exact (Sterbenz) and gives std::remainder(rel, 2 pi) bit
    // for bit, the sign of a zero included.
    double rel = abs_angle - prev;
    if (rel > kPi) rel -= 2.0 * kPi;
    else if (rel < -kPi) rel = -(-rel - 2.0 * kPi);
    angles[n] = rel;
    prev = abs_angle;
  }
}

std::vector<Vec3> HandModel::forward(const Pose& palm, const MatrixX& angles) const {
  HUGGER_CHECK_ARGUMENT_SHAPE(angles, fingers_, links_, "angles");
  std::vector<Vec3> out;
  out.reserve(fingers_ * (links_ + 1));
  for (int m = 0; m < fingers_; ++m) {
    const FingerPlane pl = plane(palm, m);
    std::vector<double> a(angles.row(m).data(), angles.row(m).data() + links_);
    for (const Vec2& x : forward_planar(m, root2d(m), a.data())) out.push_back(pl.to_world(x));
  }
  return out;
}

MatrixX HandModel::angles_from_joints(const Pose& palm, const std::vector<Vec3>& joints) const {
  HUGGER_CHECK_ARGUMENT_SIZE(joints.size(), static_cast<std::size_t>(fingers_) * (links_ + 1), "joints",
                             "points (fingers * (links + 1))");
  MatrixX angles(fingers_, links_);
  for (int m = 0; m < fingers_; ++m) {
    const FingerPlane pl = plane(palm, m);
    std::vector<Vec2> j;
    for (int n = 0; n <= links_; ++n) j.push_back(pl.to_plane(joints[joint_index(m, n)]));
    planar_angles(j, angles.row(m).data());
  }
  return angles;
}

}  // namespace hugger
