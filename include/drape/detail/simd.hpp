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
#else
#define DRAPE_AVX2 0
#endif

namespace drape {

/// The widest kernel the build and the processor allow, or a narrower one on request (tests compare them,
/// benches time them): Scalar is one item at a time, Sse2 four, Avx2 eight (constraints; the contact response
/// takes four at either). Double always runs the scalar kernel.
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
}  // namespace detail
#endif

}  // namespace drape
