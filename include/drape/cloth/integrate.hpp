#pragma once
// The two per-vertex passes around the constraint solve (docs/design.md §1, steps 1 and 3): the prediction,
// which writes the packed positions the solve works on, and the velocity update, which reads them back.

#include <drape/math.hpp>

#include <algorithm>

namespace drape {

/// Step 1 for vertices [begin, end): a free vertex (inverse mass w != 0) gains gh = h g of velocity and moves
/// h v; a pinned one stays. With kDamp the velocity is then scaled by `keep` = exp(-airDamping h). The predicted
/// position goes to xp (for the velocity update) and, as (p, 0), to the packed positions xw. The start positions
/// x are not changed; with kKeepStart they are also copied to x0 (for friction and the energy estimate, which
/// read them after x is updated).
template <bool kKeepStart, bool kDamp, Scalar S>
void predictPositions(Index begin, Index end, const Vec3<S>* x, Vec3<S>* v, const S* w, const Vec3<S>& gh, S h,
                      Vec3<S>* x0, Vec3<S>* xp, Vec4<S>* xw, [[maybe_unused]] S keep = S(1)) {
  // Written coordinate by coordinate: in a large solver the compiler called Eigen's p += h v out of line, a
  // tenth of a step on the slope.
  for (Index i = begin; i < end; ++i) {
    if constexpr (kKeepStart) x0[i] = x[i];
    S px = x[i].x(), py = x[i].y(), pz = x[i].z();
    if (w[i] != S(0)) {
      S vx = v[i].x() + gh.x(), vy = v[i].y() + gh.y(), vz = v[i].z() + gh.z();
      if constexpr (kDamp) vx *= keep, vy *= keep, vz *= keep;
      v[i] = Vec3<S>(vx, vy, vz);
      px += h * vx, py += h * vy, pz += h * vz;
    }
    xp[i] = Vec3<S>(px, py, pz);
    xw[i] = Vec4<S>(px, py, pz, S(0));
  }
}

/// Step 3 for vertices [begin, end): v = (x - x_start) / h, computed as v + (x - x_predicted) / h so that the
/// rounding of the prediction x_start + h v (in float, an ulp of the position, i.e. ulp / h of speed: 4e-4 m/s
/// at 0.5 m and h = 1/1200 s) does not enter the velocity; free flight keeps v exact. The solved positions xw go
/// back to x, and with kKeepSolved also to xp (where the pinched vertices' least-squares placement starts
/// from). With kDrift, returns the largest squared distance of these vertices from `reference` (the broad
/// phase's binned positions), else 0.
template <bool kKeepSolved, bool kDrift, Scalar S>
S updateVelocities(Index begin, Index end, const Vec4<S>* xw, Vec3<S>* xp, Vec3<S>* x, Vec3<S>* v, S invH,
                   const Vec3<S>* reference = nullptr) {
  S far = 0;
  for (Index i = begin; i < end; ++i) {
    const Vec3<S> p = xw[i].template head<3>();
    v[i] += (p - xp[i]) * invH;
    x[i] = p;
    if constexpr (kKeepSolved) xp[i] = p;
    if constexpr (kDrift) far = std::max(far, (p - reference[i]).squaredNorm());
  }
  return far;
}

}  // namespace drape
