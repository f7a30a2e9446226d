#pragma once
// Threads. The solver opens one OpenMP team per substep and every per-vertex or per-constraint loop inside it
// is a work-shared loop over items that write only their own vertices (one colour of constraints, one vertex
// of the contact response), so the result does not depend on how many threads share the work. Compiled
// without OpenMP, the directives vanish and everything runs on the calling thread.

#ifdef _OPENMP
#include <omp.h>
#define DRAPE_PRAGMA(x) _Pragma(#x)
#define DRAPE_OMP(x) DRAPE_PRAGMA(omp x)
#else
#define DRAPE_OMP(x)
#endif

// A small function on a per-vertex path that the compiler would otherwise call (it weighs the rarely taken
// parts of the caller too).
#if defined(__GNUC__) || defined(__clang__)
#define DRAPE_ALWAYS_INLINE inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define DRAPE_ALWAYS_INLINE __forceinline
#else
#define DRAPE_ALWAYS_INLINE inline
#endif

#include <type_traits>

namespace drape {

/// How many threads a solver with threadCount 0 uses: OpenMP's default team size, or 1 without OpenMP.
inline int hardwareThreads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

/// Calls f with each runtime flag as a std::bool_constant, so that a kernel templated on a scene's features is
/// compiled once per combination and the choice is made once, outside its per-vertex loop:
///   withFlags([&](auto friction) { respond<decltype(friction)::value>(...); }, hasFriction);
template <class F> decltype(auto) withFlags(F&& f) { return f(); }
template <class F, class... Rest> decltype(auto) withFlags(F&& f, bool flag, Rest... rest) {
  if (flag) return withFlags([&](auto... more) -> decltype(auto) { return f(std::true_type{}, more...); }, rest...);
  return withFlags([&](auto... more) -> decltype(auto) { return f(std::false_type{}, more...); }, rest...);
}

/// Whether drape was compiled with OpenMP (threadCount above 1 has an effect).
constexpr bool threadsAvailable() {
#ifdef _OPENMP
  return true;
#else
  return false;
#endif
}

}  // namespace drape
