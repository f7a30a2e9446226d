#pragma once
// Threads. The solver opens one OpenMP team per substep and runs every per-vertex or per-constraint loop inside
// it through teamFor: each thread calls the kernel on its share of the items, which write only their own
// vertices (one colour of constraints, one vertex of the contact response), so the result does not depend on
// how many threads share the work. Kernels take an index range and hold no directive. Compiled without
// OpenMP, the directives vanish and everything runs on the calling thread.

#ifdef _OPENMP
#include <omp.h>
#define DRAPE_PRAGMA(x) _Pragma(#x)
#define DRAPE_OMP(x) DRAPE_PRAGMA(omp x)
#else
#define DRAPE_OMP(x)
#endif

#include <drape/detail/attributes.hpp>

#include <type_traits>
#include <utility>

namespace drape {

/// How many threads a solver with threadCount 0 uses: OpenMP's default team size, or 1 without OpenMP.
inline int hardwareThreads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

/// How many threads the calling thread's team has (1 outside a team), and the calling thread's number in it.
inline int teamThreads() {
#ifdef _OPENMP
  return omp_get_num_threads();
#else
  return 1;
#endif
}
inline int teamThread() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

/// The calling thread's share [begin, end) of n items: inside a team, contiguous shares in thread order, the
/// first n % T threads one item more (the split of OpenMP's static schedule); outside a team, all n.
template <class I> std::pair<I, I> teamShare(I n) {
#ifdef _OPENMP
  const I threads = I(omp_get_num_threads()), t = I(omp_get_thread_num());
#else
  const I threads = 1, t = 0;
#endif
  const I q = n / threads, r = n % threads;
  const I begin = t * q + (t < r ? t : r);
  return {begin, begin + q + (t < r ? I(1) : I(0))};
}

/// The solver's parallel loop, called by every thread of its team: f(begin, end) on this thread's share of n
/// items (teamShare), then a barrier, so that the next stage may read what any thread wrote. Kernels take
/// such a range and never open a team, share a loop or wait for one themselves; outside a team this is
/// f(0, n). Items of one loop must write disjoint data, so the result does not depend on the thread count.
template <class I, class F> void teamFor(I n, F&& f) {
  const auto [begin, end] = teamShare(n);
  if (begin < end) f(begin, end);
  DRAPE_OMP(barrier)
}
/// teamFor without the barrier, for a loop whose per-thread results are added up (teamAdd) before one.
template <class I, class F> void teamForNoWait(I n, F&& f) {
  const auto [begin, end] = teamShare(n);
  if (begin < end) f(begin, end);
}
/// Adds one thread's part to a total the team shares (an atomic add; a total of floating-point parts then
/// depends on the order the threads arrive in, so only bounds and counts are summed this way).
template <class T> void teamAdd(T& total, T mine) {
  DRAPE_OMP(atomic)
  total += mine;
}
/// Raises a maximum the team shares to one thread's part, so that a bound read after the barrier is the largest
/// over all the items, whatever the thread count (a sum of the threads' parts would grow with it).
template <class T> void teamMax(T& most, T mine) {
  DRAPE_OMP(critical(drape_team_max))
  most = most < mine ? mine : most;
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
