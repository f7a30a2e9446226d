#pragma once
// The two per-vertex passes around the constraint solve (docs/design.md §1, steps 1 and 3): the prediction,
// which writes the packed positions the solve works on, and the velocity update, which reads them back.

#include <drape/detail/simd.hpp>
#include <drape/math.hpp>

#include <algorithm>

namespace drape {

#if DRAPE_SSE2
namespace detail {

/// Four consecutive Vec3<float> are twelve floats in three registers, (x0 y0 z0 x1) (y1 z1 x2 y2) (z2 x3 y3 z3).
/// The prediction and the update treat every coordinate alike, so they work on the registers as loaded; a
/// per-vertex value is spread to its three coordinates' lanes.
struct SpreadFour {
  __m128 a, b, c;
  explicit SpreadFour(__m128 m)
      : a(_mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 0, 0))),
        b(_mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 2, 1, 1))),
        c(_mm_shuffle_ps(m, m, _MM_SHUFFLE(3, 3, 3, 2))) {}
  SpreadFour(__m128 a_, __m128 b_, __m128 c_) : a(a_), b(b_), c(c_) {}
};

/// The three registers of four vertices as four packed (x, y, z, 0), stored aligned.
inline void storePackedFour(Vec4<float>* xw, __m128 a, __m128 b, __m128 c) {
  const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
  const __m128i ai = _mm_castps_si128(a), bi = _mm_castps_si128(b), ci = _mm_castps_si128(c);
  float* f = xw->data();
  _mm_store_ps(f, _mm_and_ps(a, xyz));
  _mm_store_ps(f + 4, _mm_and_ps(_mm_castsi128_ps(_mm_or_si128(_mm_srli_si128(ai, 12), _mm_slli_si128(bi, 4))), xyz));
  _mm_store_ps(f + 8, _mm_and_ps(_mm_castsi128_ps(_mm_or_si128(_mm_srli_si128(bi, 8), _mm_slli_si128(ci, 8))), xyz));
  _mm_store_ps(f + 12, _mm_castsi128_ps(_mm_srli_si128(ci, 4)));
}

/// Four packed (x, y, z, w) as the three registers of four Vec3 (w dropped), loaded aligned.
inline void loadPackedFour(const Vec4<float>* xw, __m128& a, __m128& b, __m128& c) {
  const float* f = xw->data();
  const __m128 p0 = _mm_load_ps(f), p1 = _mm_load_ps(f + 4), p2 = _mm_load_ps(f + 8), p3 = _mm_load_ps(f + 12);
  a = _mm_shuffle_ps(p0, _mm_shuffle_ps(p1, p0, _MM_SHUFFLE(2, 2, 0, 0)), _MM_SHUFFLE(0, 2, 1, 0));
  b = _mm_shuffle_ps(p1, p2, _MM_SHUFFLE(1, 0, 2, 1));
  c = _mm_shuffle_ps(_mm_shuffle_ps(p2, p3, _MM_SHUFFLE(0, 0, 2, 2)), p3, _MM_SHUFFLE(2, 1, 2, 0));
}

/// predictPositions for vertices i .. i + 3: lane by lane the scalar loop's operations, so its bits.
template <bool kKeepStart, bool kDamp>
inline void predictFour(Index i, const Vec3<float>* x, Vec3<float>* v, const float* w, const SpreadFour& gh, __m128 h,
                        __m128 keep, Vec3<float>* x0, Vec3<float>* xp, Vec4<float>* xw) {
  const SpreadFour free(_mm_cmpneq_ps(_mm_loadu_ps(w + i), _mm_setzero_ps()));
  const float* px = x[i].data();
  float* pv = v[i].data();
  const __m128 xa = _mm_loadu_ps(px), xb = _mm_loadu_ps(px + 4), xc = _mm_loadu_ps(px + 8);
  if constexpr (kKeepStart) {
    float* p0 = x0[i].data();
    _mm_storeu_ps(p0, xa), _mm_storeu_ps(p0 + 4, xb), _mm_storeu_ps(p0 + 8, xc);
  }
  auto part = [&](__m128 xs, float* vs, __m128 g, __m128 m) {
    const __m128 vOld = _mm_loadu_ps(vs);
    __m128 vNew = _mm_add_ps(vOld, g);
    if constexpr (kDamp) vNew = _mm_mul_ps(vNew, keep);
    _mm_storeu_ps(vs, select(m, vNew, _mm_setzero_ps()));
    return select(m, _mm_add_ps(xs, _mm_mul_ps(h, vNew)), xs);
  };
  const __m128 pa = part(xa, pv, gh.a, free.a), pb = part(xb, pv + 4, gh.b, free.b),
               pc = part(xc, pv + 8, gh.c, free.c);
  float* pp = xp[i].data();
  _mm_storeu_ps(pp, pa), _mm_storeu_ps(pp + 4, pb), _mm_storeu_ps(pp + 8, pc);
  storePackedFour(xw + i, pa, pb, pc);
}

/// updateVelocities (without the drift) for vertices i .. i + 3, the scalar loop's bits.
template <bool kKeepSolved>
inline void updateFour(Index i, const Vec4<float>* xw, Vec3<float>* xp, Vec3<float>* x, Vec3<float>* v, __m128 invH) {
  __m128 p[3];
  loadPackedFour(xw + i, p[0], p[1], p[2]);
  float* pv = v[i].data();
  float* pp = xp[i].data();
  float* px = x[i].data();
  for (int k = 0; k < 3; ++k) {
    _mm_storeu_ps(pv + 4 * k,
                  _mm_add_ps(_mm_loadu_ps(pv + 4 * k), _mm_mul_ps(_mm_sub_ps(p[k], _mm_loadu_ps(pp + 4 * k)), invH)));
    _mm_storeu_ps(px + 4 * k, p[k]);
    if constexpr (kKeepSolved) _mm_storeu_ps(pp + 4 * k, p[k]);
  }
}

}  // namespace detail
#endif

/// Step 1 for vertices [begin, end): a free vertex (inverse mass w != 0) gains gh = h g of velocity and moves
/// h v. A pinned one stays, its velocity set to zero, so that the update's v + (x - x_predicted) / h gives it the
/// velocity of the move its pin makes in the substep (kept, a moving pin's velocity added up frame after frame:
/// 3 m/s more each frame of a pull at 0.3 m/s). With kDamp the velocity is then scaled by `keep` =
/// exp(-airDamping h). The predicted position goes to xp (for the velocity update) and, as (p, 0), to the packed
/// positions xw. The start positions x are not changed; with kKeepStart they are also copied to x0 (for friction
/// and the energy estimate, which read them after x is updated). A `level` other than Scalar lets float take four
/// vertices at a time where i is a multiple of four, with the same bits.
template <bool kKeepStart, bool kDamp, Scalar S>
void predictPositions(Index begin, Index end, const Vec3<S>* x, Vec3<S>* v, const S* w, const Vec3<S>& gh, S h,
                      Vec3<S>* x0, Vec3<S>* xp, Vec4<S>* xw, [[maybe_unused]] S keep = S(1),
                      [[maybe_unused]] SimdLevel level = SimdLevel::Scalar) {
  Index i = begin;
#if DRAPE_SSE2
  if constexpr (std::is_same_v<S, float>) {
    if (level != SimdLevel::Scalar) {
      const detail::SpreadFour g(_mm_setr_ps(gh.x(), gh.y(), gh.z(), gh.x()),
                                 _mm_setr_ps(gh.y(), gh.z(), gh.x(), gh.y()),
                                 _mm_setr_ps(gh.z(), gh.x(), gh.y(), gh.z()));
      const __m128 hv = _mm_set1_ps(h), keepV = _mm_set1_ps(keep);
      for (; i < end && i % 4 != 0; ++i)
        predictPositions<kKeepStart, kDamp>(i, i + 1, x, v, w, gh, h, x0, xp, xw, keep);
      for (; i + 4 <= end; i += 4) detail::predictFour<kKeepStart, kDamp>(i, x, v, w, g, hv, keepV, x0, xp, xw);
    }
  }
#endif
  // Written coordinate by coordinate: in a large solver the compiler called Eigen's p += h v out of line, a
  // tenth of a step on the slope.
  for (; i < end; ++i) {
    if constexpr (kKeepStart) x0[i] = x[i];
    S px = x[i].x(), py = x[i].y(), pz = x[i].z();
    if (w[i] != S(0)) {
      S vx = v[i].x() + gh.x(), vy = v[i].y() + gh.y(), vz = v[i].z() + gh.z();
      if constexpr (kDamp) vx *= keep, vy *= keep, vz *= keep;
      v[i] = Vec3<S>(vx, vy, vz);
      px += h * vx, py += h * vy, pz += h * vz;
    } else {
      v[i] = Vec3<S>::Zero();  // a pinned vertex moves only where its pin takes it: the update measures that
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
/// phase's binned positions), else 0. A `level` other than Scalar lets float without kDrift take four vertices
/// at a time where i is a multiple of four, with the same bits.
template <bool kKeepSolved, bool kDrift, Scalar S>
S updateVelocities(Index begin, Index end, const Vec4<S>* xw, Vec3<S>* xp, Vec3<S>* x, Vec3<S>* v, S invH,
                   const Vec3<S>* reference = nullptr, [[maybe_unused]] SimdLevel level = SimdLevel::Scalar) {
  S far = 0;
  Index i = begin;
#if DRAPE_SSE2
  if constexpr (std::is_same_v<S, float> && !kDrift) {
    if (level != SimdLevel::Scalar) {
      for (; i < end && i % 4 != 0; ++i) updateVelocities<kKeepSolved, false>(i, i + 1, xw, xp, x, v, invH);
      const __m128 invHv = _mm_set1_ps(invH);
      for (; i + 4 <= end; i += 4) detail::updateFour<kKeepSolved>(i, xw, xp, x, v, invHv);
    }
  }
#endif
  for (; i < end; ++i) {
    const Vec3<S> p = xw[i].template head<3>();
    v[i] += (p - xp[i]) * invH;
    x[i] = p;
    if constexpr (kKeepSolved) xp[i] = p;
    if constexpr (kDrift) far = std::max(far, (p - reference[i]).squaredNorm());
  }
  return far;
}

}  // namespace drape
