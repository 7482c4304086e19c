/// \file quality.hpp
/// Grasp-wrench-space quality of a set of contacts: force closure, the Ferrari-Canny epsilon and
/// the 6D volume of the L1 grasp wrench space (the convex hull of the primitive contact wrenches),
/// computed with Qhull. The same definition as `hugger.analysis.grasp_quality` in Python.
/// Units: metres; forces are unit normal forces; torques are divided by a torque scale (m).
#pragma once

#include "hugger/types.hpp"

namespace hugger::analysis {

/// Parameters of the grasp wrench space.
struct QualityRequest {
  double mu = 0.5;                   ///< Coulomb friction coefficient (>= 0)
  int cone_edges = 8;                ///< edges of the linearised friction cone (3 .. 64; 1 edge is used when mu = 0)
  double torque_scale = 1.0;         ///< length (m) the torques are divided by (> 0)
  double closure_tolerance = 1e-9;   ///< epsilon below this times the largest |wrench coordinate| counts as 0
  bool volume = true;                ///< also the GWS volume: needs the full hull (tens of ms for a hugging
                                     ///< grasp); false finds epsilon by cutting planes over small hulls (~1 ms)
};

/// Figures of the grasp wrench space (GWS).
struct QualityResult {
  bool force_closure = false;  ///< the origin lies strictly inside the GWS (by more than the tolerance)
  double epsilon = 0.0;        ///< radius of the largest origin-centred ball inside the GWS; 0 without closure
  double volume = 0.0;         ///< 6D volume of the GWS; 0 when it is flat or degenerate
  int wrenches = 0;            ///< distinct primitive wrenches the GWS is the hull of
};

/// Primitive contact wrenches (C * E, 6), E = cone_edges (1 when mu = 0), contact-major.
/// Contact i at points.row(i) pushes along d = -normals.row(i) (normalised) with unit normal force;
/// edge j is d + mu (cos a_j t1 + sin a_j t2), a_j = 2 pi j / E, t1 = d x e_k / |d x e_k| with e_k
/// the world axis least aligned with d (lowest index on ties), t2 = d x t1. Columns 3..5 are
/// (points.row(i) - center) x f / torque_scale.
MatrixX primitive_wrenches(const PointsN3& points, const PointsN3& normals, const Vec3& center,
                           const QualityRequest& request);

/// Force closure, epsilon and volume of the contacts' GWS, torques about `center` (m, world).
/// Wrenches that agree to 1e-10 (rounded to 10 decimals) are kept once; fewer than 7 distinct
/// wrenches, or a set flat in R^6 (smallest singular value of the centred set <= 1e-9 of the
/// largest), or a hull Qhull cannot build give no closure, epsilon 0 and volume 0.
/// Qhull runs with joggled input ('QJ', fixed seed): deterministic, and thread-safe (reentrant Qhull).
/// With request.volume false, epsilon and closure come from min_depth_by_cuts (the same values,
/// without building the full hull) and the volume is reported as 0.
/// Throws std::invalid_argument for mismatched shapes, non-finite input or bad parameters.
QualityResult grasp_quality(const PointsN3& points, const PointsN3& normals, const Vec3& center,
                            const QualityRequest& request);

/// Qhull's verdict on a set of wrenches (n, 6) as they are (no de-duplication, no flatness test):
/// epsilon = the smallest facet depth of the origin (negative when outside), volume. Returns false
/// when Qhull fails. Exposed for the tests.
bool wrench_hull(const MatrixX& wrenches, double* min_depth, double* volume);

/// The smallest facet depth of the hull of `wrenches` (n, 6) without building that hull: cutting
/// planes over hulls of growing subsets (see the source). Same value as wrench_hull's min_depth
/// up to the joggle. `hull_runs` counts the Qhull runs. Returns false when Qhull fails.
bool min_depth_by_cuts(const MatrixX& wrenches, double* min_depth, int* hull_runs);

}  // namespace hugger::analysis
