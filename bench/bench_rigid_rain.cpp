// The rigid-body rain on a cloth (the cloth-rigid coupling thesis's Fig 6.6; scenes/rigid_rain.hpp): wall time of
// one stepCoupled (the 50x80 cloth and the world, in the same substeps) against the number of bodies, on one
// thread. Each repetition builds the scene (seed 42, all five shapes, the corners never let go), runs 50 steps
// so the bodies are on or near the cloth, then times 100 steps; the median over the repetitions is reported.
// Arguments: bodies, substeps per step, collision method (0 faces: vertex and face contacts, the default;
// 1 vertex: vertex contacts only, the thesis's method), continuous contact (1: on, the scene's default). The
// first series is the scene's defaults (10 substeps, faces, continuous contact); the others measure what leaving
// out continuous contact, fewer substeps and vertex-only contacts save (the speed side of the trade; the accuracy
// side is the rain sample's, docs/benchmarks.md, "Many bodies: cost per body").
// At the end, for each series, a least-squares line ms = a + b N through the medians (b: the cost per body per
// step; a: what is left at N = 0, to compare with the cloth alone, N = 0), and each count's cost per body over
// the cloth alone.
//
//   build/bench/bench_rigid_rain                                   # every series
//   build/bench/bench_rigid_rain --benchmark_filter='Cloth/[0-9]+/10/0/1/'   # the defaults only

#include "rigid_rain.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>
#include <tuple>
#include <utility>
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
  c.subSteps = static_cast<int>(state.range(1));
  c.base.collisionMethod = state.range(2) == 0 ? drape::CollisionMethod::Faces : drape::CollisionMethod::Vertices;
  c.base.continuousContact = state.range(3) != 0;  // on in the scene's defaults
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
  state.SetLabel(drape::scenes::rainShapeNames(c.shapes) + ", " + drape::toString(c.base.collisionMethod));
  state.counters["bodies"] = c.bodies;
  state.counters["substeps"] = c.subSteps;
  state.counters["method"] = double(state.range(2));
  state.counters["continuous"] = double(state.range(3));
  state.counters["vertex_contacts"] = double(vertexContacts) / double(steps);  // in the last substep of a step
  state.counters["face_contacts"] = double(faceContacts) / double(steps);
  // What the broad phase handed the solids (with it, faces and field evaluations near each body only).
  state.counters["faces_tested"] = double(facesTested) / double(steps);
  state.counters["faces_culled"] = double(facesCulled) / double(steps);
  state.counters["sdf_evaluations"] = double(evaluations) / double(steps);
  state.counters["manifolds"] = double(manifolds) / double(steps);  // body-body and body-ground
}
/// The series (substeps, method, continuous contact): the defaults first, then the defaults without continuous
/// contact, then fewer substeps with either method.
void rainSeries(benchmark::internal::Benchmark* b) {
  const int series[][3] = {{10, 0, 1}, {10, 0, 0}, {10, 1, 1}, {5, 0, 1}, {2, 0, 1}, {1, 0, 1}, {2, 1, 1}, {1, 1, 1}};
  for (const auto& [substeps, method, continuous] : series)
    for (int bodies : {0, 1, 5, 10, 20, 40, 80}) b->Args({bodies, substeps, method, continuous});
}
BENCHMARK(BM_RainOnCloth)
    ->Apply(rainSeries)
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
      const Series key{int(r.counters.at("substeps").value), int(r.counters.at("method").value),
                       int(r.counters.at("continuous").value)};
      const int n = int(it->second.value);
      // One value per count: the median when there are repetitions, else the last single run.
      if (median || !medians_[key].count(n)) ms_[key][n] = r.GetAdjustedRealTime();
      if (median) medians_[key][n] = true;
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    for (const auto& [key, ms] : ms_) fit(key, ms);
  }

 private:
  using Series = std::tuple<int, int, int>;  // substeps, method (0 faces, 1 vertices), continuous contact

  static void fit(const Series& key, const std::map<int, double>& ms) {
    if (ms.size() < 2) return;
    double mx = 0, my = 0;
    for (const auto& [n, t] : ms) mx += n, my += t;
    mx /= double(ms.size());
    my /= double(ms.size());
    double sxy = 0, sxx = 0, syy = 0;
    for (const auto& [n, t] : ms) sxy += (n - mx) * (t - my), sxx += (n - mx) * (n - mx), syy += (t - my) * (t - my);
    const double b = sxy / sxx, a = my - b * mx, r2 = syy > 0 ? sxy * sxy / (sxx * syy) : 1;
    const auto [substeps, method, continuous] = key;
    std::printf("\n%d substeps, %s contacts%s: least-squares fit of the median time per step: ms = %.3f + %.4f N "
                "(R^2 = %.4f)\n", substeps, method == 0 ? "vertex and face" : "vertex-only",
                continuous != 0 ? ", continuous contact" : "", a, b, r2);
    std::printf("  intercept %.3f ms per step; each body %.1f us per step (%.2f us per substep)\n", a, b * 1e3,
                b * 1e3 / substeps);
    const auto zero = ms.find(0);
    for (const auto& [n, t] : ms) {
      std::printf("  N = %3d: %8.3f ms measured, %8.3f ms fitted", n, t, a + b * n);
      if (zero != ms.end() && n > 0) std::printf(", %.4f ms per body over the cloth alone", (t - zero->second) / n);
      std::printf("\n");
    }
  }

 private:
  std::map<Series, std::map<int, double>> ms_;
  std::map<Series, std::map<int, bool>> medians_;
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
