#pragma once
// Keeping the angular momentum that the constraint solve must not change (Settings::keepAngularMomentum,
// docs/design.md §4, "Spin from the discretisation").
//
// A distance constraint's correction is a pair of equal and opposite pushes along the edge at the predicted
// positions. The velocity update v = (x - x_start) / h then changes the cloth's angular momentum sum m x × v by
// sum m x_start × dx / h, which is zero only if each push runs along the edge at the start positions: XPBD's
// pushes add a moment from nothing, and the sheet's diagonals and the colour order give it a sign. Here that
// moment is measured after the solve and taken out again by a rotation of the vertices the solve moved.
//
// What the solve adds is measured per vertex, sum m x_start × (x_solved - x_predicted), less what external
// pushes inside the solve added (pins pulling vertices, the in-solve baseline's contacts). Kinematic vertices
// (inverse mass 0) push back on the cloth with forces no one records. Their moments vanish about their own
// point, or along the line they lie on. So about that point, or along that line, the measured moment is all
// the solve's. Where the kinematic vertices span a plane, they can take any moment, and nothing is restored.
//
// The rotation turns the free vertices as one body about their centre of mass, which keeps the linear
// momentum.

#include <drape/math.hpp>

#include <cmath>
#include <vector>

namespace drape {

/// Kinematic vertices within this many metres of one point (or of one line) hold the cloth there only.
inline constexpr double kFixedPointTolerance = 1e-6;

/// The sums over some vertices that the restoring rotation is made from, in double.
struct SpinSums {
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  ///< sum m x_start × dx (kg m^2)
  Eigen::Vector3d push = Eigen::Vector3d::Zero();    ///< sum m dx (kg m)
  double weight = 0;                                 ///< sum m (kg)
  Eigen::Vector3d first = Eigen::Vector3d::Zero();   ///< sum m x
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  ///< sum m x x^T

  void add(const SpinSums& o) {
    moment += o.moment;
    push += o.push;
    weight += o.weight;
    first += o.first;
    second += o.second;
  }
  /// A push dx that something outside the cloth gave a vertex of inverse mass w, starting at xStart.
  template <Scalar S> void addExternal(const Vec3<S>& xStart, const Vec3<S>& dx, S w) {
    const Eigen::Vector3d m = dx.template cast<double>() / double(w);
    moment += xStart.template cast<double>().cross(m);
    push += m;
  }
};

/// The solve's pushes dx = x_solved - x_predicted of the free vertices [begin, end), and their masses' moments.
/// Written out by component in double: Eigen's mixed-type expressions cost several times as much here.
template <Scalar S>
SpinSums sumSolvePushes(Index begin, Index end, const Vec4<S>* solved, const Vec3<S>* predicted,
                        const Vec3<S>* start, const S* invMass) {
  double mx = 0, my = 0, mz = 0, px = 0, py = 0, pz = 0, w = 0, fx = 0, fy = 0, fz = 0;
  double sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
  for (Index i = begin; i < end; ++i) {
    if (!(invMass[i] > S(0))) continue;
    const double m = 1.0 / double(invMass[i]);
    const S* x = solved[i].data();
    const double x0 = double(x[0]), x1 = double(x[1]), x2 = double(x[2]);
    const double d0 = m * (x0 - double(predicted[i][0])), d1 = m * (x1 - double(predicted[i][1])),
                 d2 = m * (x2 - double(predicted[i][2]));
    const double s0 = double(start[i][0]), s1 = double(start[i][1]), s2 = double(start[i][2]);
    mx += s1 * d2 - s2 * d1, my += s2 * d0 - s0 * d2, mz += s0 * d1 - s1 * d0;
    px += d0, py += d1, pz += d2;
    w += m;
    const double m0 = m * x0, m1 = m * x1, m2 = m * x2;
    fx += m0, fy += m1, fz += m2;
    sxx += m0 * x0, sxy += m0 * x1, sxz += m0 * x2, syy += m1 * x1, syz += m1 * x2, szz += m2 * x2;
  }
  SpinSums s;
  s.moment = {mx, my, mz};
  s.push = {px, py, pz};
  s.weight = w;
  s.first = {fx, fy, fz};
  s.second << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  return s;
}

/// The axes about which the kinematic vertices cannot turn the cloth: every axis through their common point,
/// the line they lie on, or none.
struct FreeAxes {
  enum class Kind { All, Line, None } kind = Kind::All;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< on every free axis
  Eigen::Vector3d line = Eigen::Vector3d::Zero();   ///< the free axis' direction (Kind::Line)
};

/// From the kinematic vertices' positions: all axes through the origin if there are none, through their point
/// if they coincide, along their line if they are collinear (within `tolerance`, metres), else none.
template <Scalar S>
FreeAxes freeAxes(const std::vector<Index>& fixed, const Vec4<S>* x, double tolerance) {
  FreeAxes axes;
  if (fixed.empty()) return axes;
  const auto at = [&](Index i) -> Eigen::Vector3d { return x[i].template head<3>().template cast<double>(); };
  axes.point = at(fixed.front());
  double far = 0;
  for (Index i : fixed) {
    const double d = (at(i) - axes.point).norm();
    if (d > far) far = d, axes.line = at(i) - axes.point;
  }
  if (far <= tolerance) return axes;  // one point
  axes.line /= far;
  for (Index i : fixed) {
    const Eigen::Vector3d r = at(i) - axes.point;
    if ((r - r.dot(axes.line) * axes.line).norm() > tolerance) {
      axes.kind = FreeAxes::Kind::None;
      return axes;
    }
  }
  axes.kind = FreeAxes::Kind::Line;
  return axes;
}

/// The restoring rotation: the angular velocity omega and the centre it turns about, such that the velocity
/// changes omega × (x - centre) take the solve's moment about the free axes out of the cloth's angular momentum
/// over the substep h. False where there is nothing to restore.
inline bool restoringSpin(const SpinSums& s, const FreeAxes& axes, double h, Eigen::Vector3d& omega,
                          Eigen::Vector3d& centre) {
  if (axes.kind == FreeAxes::Kind::None || !(s.weight > 0)) return false;
  // The moment about the free axes' point: the kinematic vertices' pushes have none there.
  const Eigen::Vector3d moment = s.moment - axes.point.cross(s.push);
  centre = s.first / s.weight;
  const Eigen::Matrix3d spread = s.second - s.weight * centre * centre.transpose();
  const Eigen::Matrix3d inertia = spread.trace() * Eigen::Matrix3d::Identity() - spread;
  if (axes.kind == FreeAxes::Kind::Line) {
    const double about = axes.line.dot(inertia * axes.line);
    if (!(about > 0)) return false;
    omega = -(axes.line.dot(moment) / (h * about)) * axes.line;
  } else {
    const Eigen::LDLT<Eigen::Matrix3d> solve(inertia);
    if (solve.info() != Eigen::Success || !(solve.vectorD().minCoeff() > 0)) return false;
    omega = solve.solve(-moment / h);
  }
  return omega.allFinite();
}

/// v += omega × (x - centre) for the free vertices [begin, end): omega × x less omega × centre, in S.
template <Scalar S>
void applySpin(Index begin, Index end, const Vec4<S>* solved, const S* invMass, Vec3<S>* v,
               const Eigen::Vector3d& omega, const Eigen::Vector3d& centre) {
  const Vec3<S> o = omega.cast<S>(), base = omega.cross(centre).cast<S>();
  for (Index i = begin; i < end; ++i) {
    if (!(invMass[i] > S(0))) continue;
    const S* x = solved[i].data();
    v[i][0] += o[1] * x[2] - o[2] * x[1] - base[0];
    v[i][1] += o[2] * x[0] - o[0] * x[2] - base[1];
    v[i][2] += o[0] * x[1] - o[1] * x[0] - base[2];
  }
}

}  // namespace drape
