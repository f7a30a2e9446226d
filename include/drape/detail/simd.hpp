#pragma once
// What SIMD the build has on x86, and which level a kernel runs at. Every SIMD kernel does lane by lane exactly
// the scalar kernel's operations in the same order, so all levels give the same bits (tests compare them).

#include <drape/math.hpp>

#include <type_traits>

#if defined(__SSE2__) || defined(_M_X64) || (defined(_M_IX86_FP) && _M_IX86_FP >= 2)
#include <emmintrin.h>
#define DRAPE_SSE2 1
#else
#define DRAPE_SSE2 0
#endif
// GCC and Clang on x86 also compile AVX2 kernels whatever the build's flags, and take them where the processor
// has AVX2. They are compiled without FMA, so they round exactly as the others.
#if DRAPE_SSE2 && (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define DRAPE_AVX2 1
#define DRAPE_TARGET_AVX2 __attribute__((target("avx2")))
#else
#define DRAPE_AVX2 0
#endif

namespace drape {

/// The widest kernel the build and the processor allow, or a narrower one on request (tests compare them,
/// benches time them): Scalar is one item at a time, Sse2 four, Avx2 eight (constraints and the contact response;
/// a plane's vertex test takes four at either). Double always runs the scalar kernel.
enum class SimdLevel { Scalar, Sse2, Avx2 };

/// The widest level this build can run here (checked once).
inline SimdLevel bestSimdLevel() {
#if DRAPE_AVX2
  static const bool avx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return avx2 ? SimdLevel::Avx2 : SimdLevel::Sse2;
#elif DRAPE_SSE2
  return SimdLevel::Sse2;
#else
  return SimdLevel::Scalar;
#endif
}

/// The kernel a solve at `level` runs for scalar type S: a level this build or processor lacks falls back to the
/// next narrower one; double always runs the scalar kernel.
template <Scalar S> SimdLevel simdLevelFor(SimdLevel level) {
  if constexpr (!std::is_same_v<S, float>) return SimdLevel::Scalar;
  return level > bestSimdLevel() ? bestSimdLevel() : level;
}

#if DRAPE_SSE2
namespace detail {
/// (m ? a : b) lane by lane, from a comparison mask.
inline __m128 select(__m128 m, __m128 a, __m128 b) { return _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)); }

/// Four consecutive Vec3<float> (12 floats) as three registers, one per coordinate, and back.
inline void loadVec3Four(const Vec3<float>* p, __m128& vx, __m128& vy, __m128& vz) {
  const float* f = p->data();
  const __m128 a = _mm_loadu_ps(f), b = _mm_loadu_ps(f + 4), c = _mm_loadu_ps(f + 8);  // x0y0z0x1 y1z1x2y2 z2x3y3z3
  vx = _mm_shuffle_ps(a, _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 0, 3, 2)), _MM_SHUFFLE(3, 0, 3, 0));
  vy = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1)), _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3)),
                      _MM_SHUFFLE(2, 0, 2, 0));
  vz = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2)), _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0)),
                      _MM_SHUFFLE(2, 0, 2, 0));
}
inline void storeVec3Four(Vec3<float>* p, __m128 vx, __m128 vy, __m128 vz) {
  float* f = p->data();
  _mm_storeu_ps(f, _mm_shuffle_ps(_mm_unpacklo_ps(vx, vy), _mm_shuffle_ps(vz, vx, _MM_SHUFFLE(1, 1, 0, 0)),
                                  _MM_SHUFFLE(2, 0, 1, 0)));
  _mm_storeu_ps(f + 4, _mm_shuffle_ps(_mm_shuffle_ps(vy, vz, _MM_SHUFFLE(1, 1, 1, 1)),
                                      _mm_shuffle_ps(vx, vy, _MM_SHUFFLE(2, 2, 2, 2)), _MM_SHUFFLE(2, 0, 2, 0)));
  _mm_storeu_ps(f + 8, _mm_shuffle_ps(_mm_shuffle_ps(vz, vx, _MM_SHUFFLE(3, 3, 2, 2)),
                                      _mm_shuffle_ps(vy, vz, _MM_SHUFFLE(3, 3, 3, 3)), _MM_SHUFFLE(2, 0, 2, 0)));
}
/// Eigen's order for a 3-vector's dot product: a0 b0 + (a1 b1 + a2 b2).
inline __m128 dotFour(__m128 ax, __m128 ay, __m128 az, __m128 bx, __m128 by, __m128 bz) {
  return _mm_add_ps(_mm_mul_ps(ax, bx), _mm_add_ps(_mm_mul_ps(ay, by), _mm_mul_ps(az, bz)));
}
}  // namespace detail
#endif

}  // namespace drape
