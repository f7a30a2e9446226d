// Cost of a step on the inclined-plane scene, per vertex-substep, once the cloth has landed and slides.
// Run: build/bench/bench_solver --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "slope.hpp"

#include <benchmark/benchmark.h>

namespace {

template <class S, drape::CollisionMethod kMethod> void slopeStep(benchmark::State& state) {
  drape::scenes::SlopeConfig c;
  c.subSteps = int(state.range(0));
  c.iterations = int(state.range(1));
  c.method = kMethod;
  auto solver = drape::scenes::makeSlope<S>(c);
  for (int f = 0; f < 90; ++f) solver.step(c.dt);  // landed: every vertex in contact
  for (auto _ : state) {
    solver.step(c.dt);
    benchmark::ClobberMemory();
  }
  const double items = double(solver.vertexCount()) * c.subSteps;
  state.counters["vertex_substep"] =
      benchmark::Counter(items, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["vertices"] = solver.vertexCount();
}

void substepsAndIterations(benchmark::internal::Benchmark* b) {
  b->ArgNames({"substeps", "iterations"})->Args({5, 1})->Args({10, 1})->Args({5, 5})->Unit(benchmark::kMillisecond);
}

using drape::CollisionMethod;
BENCHMARK(slopeStep<float, CollisionMethod::Improved>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<float, CollisionMethod::Baseline>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<float, CollisionMethod::Vertex>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<double, CollisionMethod::Improved>)->Apply(substepsAndIterations);

}  // namespace

BENCHMARK_MAIN();
