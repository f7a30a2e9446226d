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

#include <drape/detail/parallel.hpp>
#include <drape/detail/simd.hpp>
#include <drape/math.hpp>

#include <array>
#include <cmath>
#include <type_traits>
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

namespace detail {
/// The sixteen sums of sumSolvePushes, in four lanes: the moment (3), the push (3), the mass, the first moment (3)
/// and the second (xx, xy, xz, yy, yz, zz).
using SpinLanes = std::array<std::array<double, 4>, 16>;

/// Vertex i's terms into lane `lane`, in double, written out by component: Eigen's mixed-type expressions cost
/// several times as much here. A vertex that is not free (inverse mass 0) adds terms of mass 0 rather than being
/// passed over, as the lanes of the SIMD kernel do.
template <Scalar S>
DRAPE_ALWAYS_INLINE void addSpinTerms(SpinLanes& a, int lane, const S* x, const S* predicted, const S* start, S w) {
  const double m = w > S(0) ? 1.0 / double(w) : 0.0;
  const double x0 = double(x[0]), x1 = double(x[1]), x2 = double(x[2]);
  const double d0 = m * (x0 - double(predicted[0])), d1 = m * (x1 - double(predicted[1])),
               d2 = m * (x2 - double(predicted[2]));
  const double s0 = double(start[0]), s1 = double(start[1]), s2 = double(start[2]);
  a[0][lane] += s1 * d2 - s2 * d1, a[1][lane] += s2 * d0 - s0 * d2, a[2][lane] += s0 * d1 - s1 * d0;
  a[3][lane] += d0, a[4][lane] += d1, a[5][lane] += d2;
  a[6][lane] += m;
  const double m0 = m * x0, m1 = m * x1, m2 = m * x2;
  a[7][lane] += m0, a[8][lane] += m1, a[9][lane] += m2;
  a[10][lane] += m0 * x0, a[11][lane] += m0 * x1, a[12][lane] += m0 * x2;
  a[13][lane] += m1 * x1, a[14][lane] += m1 * x2, a[15][lane] += m2 * x2;
}

#if DRAPE_AVX2
/// Vertices i .. i + 3 into lanes 0 .. 3: lane by lane addSpinTerms' operations (float positions).
DRAPE_TARGET_AVX2 inline void addSpinTermsFour(__m256d (&a)[16], Index i, const Vec4<float>* solved,
                                               const Vec3<float>* predicted, const Vec3<float>* start,
                                               const float* invMass) {
  __m128 r0 = _mm_load_ps(solved[i].data()), r1 = _mm_load_ps(solved[i + 1].data()),
         r2 = _mm_load_ps(solved[i + 2].data()), r3 = _mm_load_ps(solved[i + 3].data());
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  __m128 px, py, pz, sx, sy, sz;
  loadVec3Four(predicted + i, px, py, pz);
  loadVec3Four(start + i, sx, sy, sz);
  const __m256d w = _mm256_cvtps_pd(_mm_loadu_ps(invMass + i));
  // A kinematic vertex's lane divides 1 by 1, not by 0 (which may trap), and takes mass 0.
  const __m256d isFree = _mm256_cmp_pd(w, _mm256_setzero_pd(), _CMP_GT_OQ), one = _mm256_set1_pd(1.0);
  const __m256d m = _mm256_and_pd(isFree, _mm256_div_pd(one, _mm256_blendv_pd(one, w, isFree)));
  const __m256d x0 = _mm256_cvtps_pd(r0), x1 = _mm256_cvtps_pd(r1), x2 = _mm256_cvtps_pd(r2);
  const __m256d d0 = _mm256_mul_pd(m, _mm256_sub_pd(x0, _mm256_cvtps_pd(px))),
                d1 = _mm256_mul_pd(m, _mm256_sub_pd(x1, _mm256_cvtps_pd(py))),
                d2 = _mm256_mul_pd(m, _mm256_sub_pd(x2, _mm256_cvtps_pd(pz)));
  const __m256d s0 = _mm256_cvtps_pd(sx), s1 = _mm256_cvtps_pd(sy), s2 = _mm256_cvtps_pd(sz);
  // Written out: a lambda would not take the function's target.
  a[0] = _mm256_add_pd(a[0], _mm256_sub_pd(_mm256_mul_pd(s1, d2), _mm256_mul_pd(s2, d1)));
  a[1] = _mm256_add_pd(a[1], _mm256_sub_pd(_mm256_mul_pd(s2, d0), _mm256_mul_pd(s0, d2)));
  a[2] = _mm256_add_pd(a[2], _mm256_sub_pd(_mm256_mul_pd(s0, d1), _mm256_mul_pd(s1, d0)));
  a[3] = _mm256_add_pd(a[3], d0), a[4] = _mm256_add_pd(a[4], d1), a[5] = _mm256_add_pd(a[5], d2);
  a[6] = _mm256_add_pd(a[6], m);
  const __m256d m0 = _mm256_mul_pd(m, x0), m1 = _mm256_mul_pd(m, x1), m2 = _mm256_mul_pd(m, x2);
  a[7] = _mm256_add_pd(a[7], m0), a[8] = _mm256_add_pd(a[8], m1), a[9] = _mm256_add_pd(a[9], m2);
  a[10] = _mm256_add_pd(a[10], _mm256_mul_pd(m0, x0)), a[11] = _mm256_add_pd(a[11], _mm256_mul_pd(m0, x1));
  a[12] = _mm256_add_pd(a[12], _mm256_mul_pd(m0, x2)), a[13] = _mm256_add_pd(a[13], _mm256_mul_pd(m1, x1));
  a[14] = _mm256_add_pd(a[14], _mm256_mul_pd(m1, x2)), a[15] = _mm256_add_pd(a[15], _mm256_mul_pd(m2, x2));
}

/// The whole fours of [begin, end) into `lanes` (vertex begin + k in lane k % 4); returns where they stop.
DRAPE_TARGET_AVX2 inline Index spinLanesAvx2(Index begin, Index end, const Vec4<float>* solved,
                                             const Vec3<float>* predicted, const Vec3<float>* start,
                                             const float* invMass, SpinLanes& lanes) {
  __m256d a[16];
  for (int k = 0; k < 16; ++k) a[k] = _mm256_loadu_pd(lanes[std::size_t(k)].data());
  Index i = begin;
  for (; i + 4 <= end; i += 4) addSpinTermsFour(a, i, solved, predicted, start, invMass);
  for (int k = 0; k < 16; ++k) _mm256_storeu_pd(lanes[std::size_t(k)].data(), a[k]);
  return i;
}
#endif
}  // namespace detail

/// The solve's pushes dx = x_solved - x_predicted of the free vertices [begin, end), and their masses' moments.
/// The sums run in four lanes (vertex begin + k in lane k % 4), added lane by lane at the end, so that the AVX2
/// kernel (float) and the scalar loop give the same bits; a `level` of Scalar keeps to the scalar loop.
template <Scalar S>
SpinSums sumSolvePushes(Index begin, Index end, const Vec4<S>* solved, const Vec3<S>* predicted,
                        const Vec3<S>* start, const S* invMass, SimdLevel level = bestSimdLevel()) {
  detail::SpinLanes a{};
  Index i = begin;
#if DRAPE_AVX2
  if constexpr (std::is_same_v<S, float>)
    if (level == SimdLevel::Avx2) i = detail::spinLanesAvx2(begin, end, solved, predicted, start, invMass, a);
#else
  (void)level;
#endif
  for (; i < end; ++i)
    detail::addSpinTerms(a, int((i - begin) % 4), solved[i].data(), predicted[i].data(), start[i].data(), invMass[i]);
  double t[16];
  for (std::size_t k = 0; k < 16; ++k) t[k] = ((a[k][0] + a[k][1]) + a[k][2]) + a[k][3];
  SpinSums s;
  s.moment = {t[0], t[1], t[2]};
  s.push = {t[3], t[4], t[5]};
  s.weight = t[6];
  s.first = {t[7], t[8], t[9]};
  s.second << t[10], t[11], t[12], t[11], t[13], t[14], t[12], t[14], t[15];
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

/// v += omega × (x - centre) for the free vertices [begin, end): omega × x less omega × centre, in S. Float takes
/// four vertices at a time in SSE2 lanes (the whole fours from begin), lane by lane the scalar loop's operations.
template <Scalar S>
void applySpin(Index begin, Index end, const Vec4<S>* solved, const S* invMass, Vec3<S>* v,
               const Eigen::Vector3d& omega, const Eigen::Vector3d& centre, SimdLevel level = bestSimdLevel()) {
  const Vec3<S> o = omega.cast<S>(), base = omega.cross(centre).cast<S>();
  Index i = begin;
#if DRAPE_SSE2
  if constexpr (std::is_same_v<S, float>) {
    if (level != SimdLevel::Scalar) {
      const __m128 o0 = _mm_set1_ps(o[0]), o1 = _mm_set1_ps(o[1]), o2 = _mm_set1_ps(o[2]);
      const __m128 b0 = _mm_set1_ps(base[0]), b1 = _mm_set1_ps(base[1]), b2 = _mm_set1_ps(base[2]);
      for (; i + 4 <= end; i += 4) {
        __m128 x0 = _mm_load_ps(solved[i].data()), x1 = _mm_load_ps(solved[i + 1].data()),
               x2 = _mm_load_ps(solved[i + 2].data()), x3 = _mm_load_ps(solved[i + 3].data());
        _MM_TRANSPOSE4_PS(x0, x1, x2, x3);
        __m128 vx, vy, vz;
        detail::loadVec3Four(v + i, vx, vy, vz);
        const __m128 isFree = _mm_cmpgt_ps(_mm_loadu_ps(invMass + i), _mm_setzero_ps());
        const __m128 nx = _mm_add_ps(vx, _mm_sub_ps(_mm_sub_ps(_mm_mul_ps(o1, x2), _mm_mul_ps(o2, x1)), b0));
        const __m128 ny = _mm_add_ps(vy, _mm_sub_ps(_mm_sub_ps(_mm_mul_ps(o2, x0), _mm_mul_ps(o0, x2)), b1));
        const __m128 nz = _mm_add_ps(vz, _mm_sub_ps(_mm_sub_ps(_mm_mul_ps(o0, x1), _mm_mul_ps(o1, x0)), b2));
        detail::storeVec3Four(v + i, detail::select(isFree, nx, vx), detail::select(isFree, ny, vy),
                              detail::select(isFree, nz, vz));
      }
    }
  }
#else
  (void)level;
#endif
  for (; i < end; ++i) {
    if (!(invMass[i] > S(0))) continue;
    const S* x = solved[i].data();
    v[i][0] += o[1] * x[2] - o[2] * x[1] - base[0];
    v[i][1] += o[2] * x[0] - o[0] * x[2] - base[1];
    v[i][2] += o[0] * x[1] - o[1] * x[0] - base[2];
  }
}

}  // namespace drape
