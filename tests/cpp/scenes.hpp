// Planner test scenes shared by the C++ tests: a simulated sphere and a palm facing down at it.
#pragma once

#include <memory>

#include "hugger/world/simulated_world.hpp"
#include "meshes.hpp"

namespace hugger::test {

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

}  // namespace hugger::test
