// Planner test scenes shared by the C++ tests: a simulated sphere and a palm facing down at it.
#pragma once

#include <cmath>
#include <memory>
#include <random>

#include "hugger/world/simulated_world.hpp"
#include "meshes.hpp"

namespace hugger::test {

/// A sensing stub with no object: every gap is infinite, every link free.
class EmptySkin : public Sensing {
 public:
  Touch capsule(const Vec3&, const Vec3&, double, double) const override { return Touch{}; }
  double palm(const Pose&, double, double, double) const override { return kInf; }
};

/// A simulated world holding a sphere of radius R about the origin (20 * 4^subdivisions triangles).
inline std::shared_ptr<SimulatedWorld> sphere_world(double R, int subdivisions) {
  const auto mesh = icosphere(subdivisions, Vec3::Constant(R));
  return std::make_shared<SimulatedWorld>(std::make_shared<Object>(mesh.vertices, mesh.faces));
}

/// The palm at (0, 0, height), its normal (z axis) turned to -z, facing the origin.
inline Pose facing_down(double height) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(kPi, Vec3::UnitX()).toRotationMatrix();
  p.translation() = Vec3(0, 0, height);
  return p;
}

/// A finger plane through `origin` with a random orientation.
inline FingerPlane random_plane(std::mt19937& rng, const Vec3& origin) {
  FingerPlane pl;
  pl.origin = origin;
  pl.p = random_unit(rng);
  pl.u = random_unit(rng).cross(pl.p).normalized();
  return pl;
}

/// A request to turn link [pivot, end] about pivot (RotateRequest), with the tolerance and sample
/// angle the rotation tests use (1e-5 m, 0.025 rad).
inline RotateRequest rotate_request(const FingerPlane& plane, const Vec2& pivot, const Vec2& end, double radius,
                                    double front, double max_angle) {
  RotateRequest rr;
  rr.plane = plane;
  rr.pivot = pivot;
  rr.end = end;
  rr.radius = radius;
  rr.front = front;
  rr.max_angle = max_angle;
  rr.tolerance = 1e-5;
  rr.sample_angle = 0.025;
  return rr;
}

/// Brute force: the smallest |angle| on a grid of `grid` radians, up to the request's max_angle,
/// at which the turned link is free (link_free, front included), trying both ways at each step;
/// +inf when none is.
inline double smallest_free_angle(const Sensing& skin, const RotateRequest& rr, double grid) {
  const Vec2 arm = rr.end - rr.pivot;
  auto free_at = [&](double ang) {
    const Vec2 e = rr.pivot + Vec2(std::cos(ang) * arm.x() - std::sin(ang) * arm.y(),
                                   std::sin(ang) * arm.x() + std::cos(ang) * arm.y());
    return skin.link_free(rr.plane, rr.pivot, e, rr.radius, rr.front);
  };
  for (int k = 1; k * grid <= rr.max_angle; ++k)
    for (double sgn : {1.0, -1.0})
      if (free_at(sgn * grid * k)) return grid * k;
  return kInf;
}

}  // namespace hugger::test
