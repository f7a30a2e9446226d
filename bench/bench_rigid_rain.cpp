// The rigid-body rain on a cloth (the thesis's Fig 6.6, issue 4 item 6; scenes/rigid_rain.hpp): wall time of
// one stepCoupled (the 50x80 cloth, 10 substeps, and the world's substeps) against the number of bodies, on one
// thread. Each repetition builds the scene (seed 42, all five shapes, the corners never let go), runs 50 steps
// so the bodies are on or near the cloth, then times 100 steps; the median over the repetitions is reported.
// At the end, a least-squares line ms = a + b N through the medians (b: the cost per body per step; a: what is
// left at N = 0, to compare with the cloth alone, N = 0), and each count's cost per body over the cloth alone.
//
//   build/bench/bench_rigid_rain

#include "rigid_rain.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <vector>

namespace {

void BM_RainOnCloth(benchmark::State& state) {
  drape::scenes::RainConfig c;
  c.bodies = static_cast<int>(state.range(0));
  c.seed = 42;
  // All five shapes once the solver takes them all; until then the ones it takes (named in the label).
  c.shapes = drape::scenes::supportedRainShapes<drape::Solver<float>>();
  c.release = std::numeric_limits<double>::infinity();  // the cloth stays up: the bodies keep on it
  c.base.threadCount = 1;
  drape::scenes::RigidRain<float> scene(c);
  for (int s = 0; s < 50; ++s) scene.step();
  std::int64_t vertexContacts = 0, faceContacts = 0, facesTested = 0, facesCulled = 0, evaluations = 0, manifolds = 0,
               steps = 0;
  for (auto _ : state) {
    scene.step();
    vertexContacts += scene.cloth().stats().vertexContacts;
    faceContacts += scene.cloth().stats().faceContacts;
    facesTested += scene.cloth().stats().facesTested;
    facesCulled += scene.cloth().stats().facesCulled;
    evaluations += scene.cloth().stats().sdfEvaluations;
    manifolds += std::int64_t(scene.world().contacts().size());
    ++steps;
  }
  state.SetLabel(drape::scenes::rainShapeNames(c.shapes));
  state.counters["bodies"] = c.bodies;
  state.counters["vertex_contacts"] = double(vertexContacts) / double(steps);  // in the last substep of a step
  state.counters["face_contacts"] = double(faceContacts) / double(steps);
  // What the broad phase handed the solids (with it, faces and field evaluations near each body only).
  state.counters["faces_tested"] = double(facesTested) / double(steps);
  state.counters["faces_culled"] = double(facesCulled) / double(steps);
  state.counters["sdf_evaluations"] = double(evaluations) / double(steps);
  state.counters["manifolds"] = double(manifolds) / double(steps);  // body-body and body-ground
}
BENCHMARK(BM_RainOnCloth)
    ->Arg(0)->Arg(1)->Arg(5)->Arg(10)->Arg(20)->Arg(40)->Arg(80)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(100)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true)
    ->UseRealTime();

/// The console reporter, keeping each body count's median real time (ms per step) for the fit.
class FitReporter : public benchmark::ConsoleReporter {
 public:
  FitReporter() : ConsoleReporter(OO_Tabular) {}  // counters in columns, no colour codes

  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      if (!median && r.run_type == Run::RT_Aggregate) continue;
      const auto it = r.counters.find("bodies");
      if (it == r.counters.end() || r.error_occurred) continue;
      // One value per count: the median when there are repetitions, else the last single run.
      if (median || !medians_.count(int(it->second.value))) ms_[int(it->second.value)] = r.GetAdjustedRealTime();
      if (median) medians_[int(it->second.value)] = true;
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    if (ms_.size() < 2) return;
    double mx = 0, my = 0;
    for (const auto& [n, t] : ms_) mx += n, my += t;
    mx /= double(ms_.size());
    my /= double(ms_.size());
    double sxy = 0, sxx = 0, syy = 0;
    for (const auto& [n, t] : ms_) sxy += (n - mx) * (t - my), sxx += (n - mx) * (n - mx), syy += (t - my) * (t - my);
    const double b = sxy / sxx, a = my - b * mx, r2 = syy > 0 ? sxy * sxy / (sxx * syy) : 1;
    std::printf("\nLeast-squares fit of the median time per step: ms = %.3f + %.4f N  (R^2 = %.4f)\n", a, b, r2);
    std::printf("  intercept %.3f ms per step; each body %.1f us per step (%.1f us per substep)\n", a, b * 1e3,
                b * 1e3 / 10);
    const auto zero = ms_.find(0);
    for (const auto& [n, t] : ms_) {
      std::printf("  N = %3d: %8.3f ms measured, %8.3f ms fitted", n, t, a + b * n);
      if (zero != ms_.end() && n > 0) std::printf(", %.3f ms per body over the cloth alone", (t - zero->second) / n);
      std::printf("\n");
    }
  }

 private:
  std::map<int, double> ms_;
  std::map<int, bool> medians_;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  FitReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
