#pragma once
// What the [gpu] tests share: one context for the process (made on first use; the backend from
// DRAPE_GPU_BACKEND, which ctest sets to osmesa so CI runs on llvmpipe through OSMesa as issue 5 asks), and
// comparisons of CPU and GPU arrays.

#include <drape/gpu/solver.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace drape::test {

inline gpu::Context& gpuContext() {
  static gpu::Context context;
  return context;
}

/// The largest |a_i - b_i| over every coordinate of two arrays of equal length (infinity if either holds a NaN).
template <class A, class B> double largestDifference(const A& a, const B& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const double d = std::abs(double(a[i][k]) - double(b[i][k]));
      worst = std::isnan(d) ? std::numeric_limits<double>::infinity() : std::max(worst, d);
    }
  return worst;
}

}  // namespace drape::test
