#include "hugger/analysis/quality.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

#include "hugger/check.hpp"

namespace hugger::analysis {
namespace {

void check_inputs(const PointsN3& points, const PointsN3& normals, const Vec3& center, const QualityRequest& r) {
  HUGGER_CHECK_ARGUMENT(points.rows() == normals.rows(), "points and normals must both be (C, 3), got "
                                                             << points.rows() << " and " << normals.rows() << " rows");
  HUGGER_CHECK_ARGUMENT(points.allFinite() && normals.allFinite() && center.allFinite(),
                        "contact points, normals and the centre must be finite");
  HUGGER_CHECK_ARGUMENT(r.mu >= 0 && std::isfinite(r.mu), "mu must be finite and >= 0, got " << r.mu);
  HUGGER_CHECK_ARGUMENT(r.cone_edges >= 3 && r.cone_edges <= 64, "cone_edges must be 3 .. 64, got " << r.cone_edges);
  HUGGER_CHECK_ARGUMENT(r.torque_scale > 0 && std::isfinite(r.torque_scale),
                        "torque_scale must be finite and > 0, got " << r.torque_scale);
  HUGGER_CHECK_ARGUMENT(r.closure_tolerance >= 0, "closure_tolerance must be >= 0, got " << r.closure_tolerance);
  for (Eigen::Index i = 0; i < normals.rows(); ++i)
    HUGGER_CHECK_ARGUMENT(normals.row(i).norm() > 1e-12, "normal " << i << " is zero");
}

FILE* quiet_stream() {
  static FILE* sink = [] {
    FILE* f = std::fopen("/dev/null", "w");
    return f != nullptr ? f : stderr;
  }();
  return sink;
}

}  // namespace

MatrixX primitive_wrenches(const PointsN3& points, const PointsN3& normals, const Vec3& center,
                           const QualityRequest& request) {
  check_inputs(points, normals, center, request);
  const Eigen::Index c = points.rows();
  const int edges = request.mu == 0 ? 1 : request.cone_edges;
  MatrixX w(c * edges, 6);
  for (Eigen::Index i = 0; i < c; ++i) {
    const Vec3 d = -normals.row(i).transpose().normalized();
    const Vec3 arm = points.row(i).transpose() - center;
    Vec3 t1 = Vec3::Zero(), t2 = Vec3::Zero();
    if (edges > 1) {
      int axis = 0;  // the world axis least aligned with d, lowest index on ties (numpy argmin)
      for (int k = 1; k < 3; ++k)
        if (std::abs(d[k]) < std::abs(d[axis])) axis = k;
      t1 = d.cross(Vec3::Unit(axis));
      t1 /= t1.norm();
      t2 = d.cross(t1);
    }
    for (int j = 0; j < edges; ++j) {
      Vec3 f = d;
      if (edges > 1) {
        const double a = 2 * kPi * j / edges;
        const Vec3 tangent = std::cos(a) * t1 + std::sin(a) * t2;
        f = d + request.mu * tangent;
      }
      const Vec3 tau = arm.cross(f) / request.torque_scale;
      w.row(i * edges + j) << f[0], f[1], f[2], tau[0], tau[1], tau[2];
    }
  }
  return w;
}

namespace {

/// One Qhull run over the rows of w (n, 6): the smallest facet depth (-offset: the origin's
/// distance inside the facet, negative outside; -inf without facets) and, when asked, the volume.
bool run_qhull(const MatrixX& w, bool want_volume, double* min_depth, double* volume) {
  const int n = static_cast<int>(w.rows());
  if (n < 7) return false;
  std::vector<coordT> pts(static_cast<std::size_t>(n) * 6);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 6; ++k) pts[static_cast<std::size_t>(i) * 6 + k] = w(i, k);
  qhT qh_qh;
  qhT* qh = &qh_qh;
  FILE* err = quiet_stream();
  qh_zero(qh, err);
  // 'QJ': joggled input, every facet simplicial (no merging), as the reference definition. The
  // joggle draws from Qhull's own generator in qhT (qh_RANDOMtype 5), seeded the same way on every
  // call: the result does not depend on the time or the thread.
  char cmd[] = "qhull QJ";
  const int code = qh_new_qhull(qh, 6, n, pts.data(), False, cmd, nullptr, err);
  const bool ok = code == 0;
  if (ok) {
    double depth = kInf;
    bool any = false;
    facetT* facet;
    FORALLfacets {
      depth = std::min(depth, -facet->offset);
      any = true;
    }
    *min_depth = any ? depth : -kInf;
    if (want_volume) {
      qh_getarea(qh, qh->facet_list);
      *volume = qh->totvol;
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  return ok;
}

}  // namespace

bool wrench_hull(const MatrixX& wrenches, double* min_depth, double* volume) {
  HUGGER_CHECK_ARGUMENT(wrenches.cols() == 6, "wrenches must be (n, 6), got " << wrenches.cols() << " columns");
  return run_qhull(wrenches, true, min_depth, volume);
}

namespace {

/// The incremental part of min_depth_by_cuts, kept apart because Qhull reports errors by longjmp:
/// only plain data lives in this frame, and every Qhull call happens after the setjmp.
struct CutState {
  const double* pts = nullptr;  // (n, 6) row-major, the seed rows first
  int n = 0;
  char* in = nullptr;
  double slack = 0;
  double depth = 0;
  int added = 0;
};

bool grow_hull(qhT* qh, CutState* st) {
  if (setjmp(qh->errexit)) {
    qh->NOerrexit = True;
    return false;
  }
  qh->NOerrexit = False;
  for (int round = 0; round <= st->n; ++round) {
    facetT* facet;
    facetT* low = nullptr;
    double low_depth = kInf;
    FORALLfacets {
      const double d = -facet->offset;
      if (d < low_depth) low_depth = d, low = facet;
    }
    if (low == nullptr) break;
    double support = -kInf;
    int best = -1;
    for (int i = 0; i < st->n; ++i) {
      const double* w = st->pts + static_cast<std::size_t>(i) * 6;
      double dot = 0;
      for (int k = 0; k < 6; ++k) dot += w[k] * low->normal[k];
      if (dot > support) support = dot, best = i;
    }
    if (support <= low_depth + st->slack) {
      st->depth = low_depth;
      qh->NOerrexit = True;
      return true;
    }
    if (st->in[best]) break;  // rounding: let the full hull decide
    st->in[best] = 1;
    ++st->added;
    qh_addpoint(qh, const_cast<double*>(st->pts + static_cast<std::size_t>(best) * 6), low, False);
  }
  qh->NOerrexit = True;
  return false;
}

}  // namespace

bool min_depth_by_cuts(const MatrixX& w, double* min_depth, int* hull_runs) {
  // The hull of a subset S of the wrenches lies inside the hull of all of them. Let (u, d) be the
  // facet of hull(S) of least depth d. If no wrench lies beyond it (max_i w_i . u <= d), it is a
  // supporting hyperplane of hull(all): with the origin inside hull(S) the origin's distance to
  // the boundary of hull(all) is then exactly d (>= d by containment, <= d by the hyperplane), and
  // with the origin outside (d < 0) it is outside hull(all) too. Otherwise the wrench furthest
  // beyond is added to hull(S) (Qhull's incremental qh_addpoint) and the facet of least depth is
  // found again; S grows every round, so this ends (at worst with S = all the wrenches).
  const Eigen::Index n = w.rows();
  const double scale = std::max(w.cwiseAbs().maxCoeff(), 1e-300);
  std::vector<char> in(static_cast<std::size_t>(n), 0);
  std::vector<Eigen::Index> s;
  auto add = [&](Eigen::Index i) {
    if (!in[i]) in[i] = 1, s.push_back(i);
  };
  for (int k = 0; k < 6; ++k) {  // seed: the extreme wrenches along the 12 coordinate directions
    Eigen::Index hi = 0, lo = 0;
    w.col(k).maxCoeff(&hi);
    w.col(k).minCoeff(&lo);
    add(hi);
    add(lo);
  }
  std::sort(s.begin(), s.end());
  if (static_cast<Eigen::Index>(s.size()) >= 7 && static_cast<Eigen::Index>(s.size()) < n) {
    // All rows in one array, the seed first, so that Qhull's point pointers stay valid.
    std::vector<double> pts(static_cast<std::size_t>(n) * 6);
    std::vector<char> flag(static_cast<std::size_t>(n), 0);
    std::vector<Eigen::Index> order = s;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!in[i]) order.push_back(i);
    for (Eigen::Index i = 0; i < n; ++i)
      for (int k = 0; k < 6; ++k) pts[static_cast<std::size_t>(i) * 6 + k] = w(order[i], k);
    for (std::size_t i = 0; i < s.size(); ++i) flag[i] = 1;
    qhT qh_qh;
    qhT* qh = &qh_qh;
    FILE* err = quiet_stream();
    qh_zero(qh, err);
    // Default Qhull (merged facets; 'Qx' exact pre-merges in 6D): points are added one by one, so
    // the joggle ('QJ') of the full hull does not apply; the two agree to ~1e-9 relative.
    char cmd[] = "qhull";
    bool ok = false;
    CutState st;
    if (qh_new_qhull(qh, 6, static_cast<int>(s.size()), pts.data(), False, cmd, nullptr, err) == 0) {
      ++*hull_runs;
      st.pts = pts.data();
      st.n = static_cast<int>(n);
      st.in = flag.data();
      st.slack = 1e-9 * scale;
      ok = grow_hull(qh, &st);
    }
    qh_freeqhull(qh, !qh_ALL);
    int curlong = 0, totlong = 0;
    qh_memfreeshort(qh, &curlong, &totlong);
    if (ok) {
      *min_depth = st.depth;
      return true;
    }
  }
  double unused = 0.0;
  if (!run_qhull(w, false, min_depth, &unused)) return false;
  ++*hull_runs;
  return true;
}

QualityResult grasp_quality(const PointsN3& points, const PointsN3& normals, const Vec3& center,
                            const QualityRequest& request) {
  const MatrixX all = primitive_wrenches(points, normals, center, request);
  // Keep the first of each group of wrenches that agree when rounded to 10 decimals, in order.
  const Eigen::Index rows = all.rows();
  std::vector<std::array<double, 6>> key(static_cast<std::size_t>(rows));
  for (Eigen::Index i = 0; i < rows; ++i)
    for (int k = 0; k < 6; ++k) key[i][k] = std::nearbyint(all(i, k) * 1e10) / 1e10;
  std::vector<Eigen::Index> order(static_cast<std::size_t>(rows));
  std::iota(order.begin(), order.end(), Eigen::Index(0));
  std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return key[a] < key[b]; });
  std::vector<Eigen::Index> keep;
  for (std::size_t i = 0; i < order.size(); ++i)
    if (i == 0 || key[order[i]] != key[order[i - 1]]) keep.push_back(order[i]);
  std::sort(keep.begin(), keep.end());
  MatrixX w(static_cast<Eigen::Index>(keep.size()), 6);
  for (std::size_t i = 0; i < keep.size(); ++i) w.row(static_cast<Eigen::Index>(i)) = all.row(keep[i]);

  QualityResult none;
  none.wrenches = static_cast<int>(w.rows());
  if (w.rows() < 7) return none;
  const MatrixX centred = w.rowwise() - w.colwise().mean();
  const Eigen::VectorXd spread = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  if (spread[spread.size() - 1] <= 1e-9 * std::max(spread[0], 1e-300)) return none;  // flat in R^6
  double depth = 0, volume = 0;
  if (request.volume) {
    if (!wrench_hull(w, &depth, &volume)) return none;
  } else {
    int runs = 0;
    if (!min_depth_by_cuts(w, &depth, &runs)) return none;
  }
  const double tol = request.closure_tolerance * w.cwiseAbs().maxCoeff();
  QualityResult out = none;
  out.force_closure = depth > tol;
  out.epsilon = out.force_closure ? depth : 0.0;
  out.volume = volume;
  return out;
}

}  // namespace hugger::analysis
