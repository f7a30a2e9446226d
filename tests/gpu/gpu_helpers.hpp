#pragma once
// What the [gpu] tests share: one context for the process (made on first use; the backend from
// DRAPE_GPU_BACKEND, which ctest sets to osmesa so CI runs on llvmpipe through OSMesa), and
// comparisons of CPU and GPU arrays.

#include <drape/gpu/solver.hpp>
#include <drape/metrics.hpp>

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

/// What a scene stepped side by side on the CPU and the GPU solver gave: the deepest penetration of each, the
/// largest gap between the cloth centres' heights (over the run, and from frame `settleFrames` on), the CPU cloth's
/// final centre height, and the trembling of each from frame `settleFrames` on.
struct SideBySide {
  double cpuDepth = 0, gpuDepth = 0, heightGap = 0, restHeightGap = 0, cpuZ = 0;
  TrembleMeter cpuMeter, gpuMeter;
};
template <class Cpu> SideBySide stepSideBySide(Cpu& cpu, gpu::Solver& gpu, int frames, int settleFrames, double dt = 1.0 / 60) {
  SideBySide r;
  for (int frame = 1; frame <= frames; ++frame) {
    cpu.step(dt);
    gpu.step(dt);
    r.cpuDepth = std::max(r.cpuDepth, penetration(cpu).depth);
    r.gpuDepth = std::max(r.gpuDepth, penetration(gpu).depth);
    double zc = 0, zg = 0;
    for (Index i = 0; i < cpu.vertexCount(); ++i) zc += cpu.position(i).z(), zg += gpu.position(i).z();
    r.cpuZ = zc / double(cpu.vertexCount());
    r.heightGap = std::max(r.heightGap, std::abs(zc - zg) / double(cpu.vertexCount()));
    if (frame > settleFrames) r.restHeightGap = std::max(r.restHeightGap, std::abs(zc - zg) / double(cpu.vertexCount()));
    r.cpuMeter.frame(cpu, dt, frame > settleFrames);
    r.gpuMeter.frame(gpu, dt, frame > settleFrames);
  }
  return r;
}

}  // namespace drape::test
