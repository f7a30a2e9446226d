// Cost of a step on the inclined-plane scene, per vertex-substep, once the cloth has landed and slides.
// Run: build/bench/bench_solver --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// slopeStep: 50x80 at several substeps x iterations, one thread. slopeSize: 50x80 against 256x256 on one and on
// two threads (substeps 5, iterations 1): the size and thread ratios come from one run of this binary.
#include "slope.hpp"

#include <benchmark/benchmark.h>

namespace {

template <class S>
void runSlope(benchmark::State& state, drape::CollisionMethod method, int substeps, int iterations, int nx, int ny,
              int threads) {
  drape::scenes::SlopeConfig c;
  c.subSteps = substeps;
  c.iterations = iterations;
  c.method = method;
  c.nx = nx;
  c.ny = ny;
  c.base.threadCount = threads;
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
  state.counters["contacts"] = double(solver.stats().vertexContacts);
}

template <class S, drape::CollisionMethod kMethod> void slopeStep(benchmark::State& state) {
  runSlope<S>(state, kMethod, int(state.range(0)), int(state.range(1)), 50, 80, 1);
}

void slopeSize(benchmark::State& state) {
  const int side = int(state.range(0));
  runSlope<float>(state, drape::CollisionMethod::Faces, 5, 1, side == 50 ? 50 : side, side == 50 ? 80 : side,
                  int(state.range(1)));
}

void substepsAndIterations(benchmark::internal::Benchmark* b) {
  b->ArgNames({"substeps", "iterations"})->Args({5, 1})->Args({10, 1})->Args({5, 5})->Unit(benchmark::kMillisecond);
}

using drape::CollisionMethod;
BENCHMARK(slopeStep<float, CollisionMethod::Faces>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<float, CollisionMethod::InSolve>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<float, CollisionMethod::Vertices>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<double, CollisionMethod::Faces>)->Apply(substepsAndIterations);
// side 50 means the 50x80 cloth; threads 1 or 2. Real time: with two threads, CPU time would count both.
BENCHMARK(slopeSize)
    ->ArgNames({"side", "threads"})
    ->Args({50, 1})
    ->Args({256, 1})
    ->Args({256, 2})
    ->Args({50, 2})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
