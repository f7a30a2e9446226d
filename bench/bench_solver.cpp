// Cost of a step on the inclined-plane scene, per vertex-substep, once the cloth has landed and slides.
// Run: build/bench/bench_solver --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// slopeStep: 50x80 at several substeps x iterations, one thread. slopeSize: 50x80 against 256x256 on one and on
// two threads (substeps 5, iterations 1): the size and thread ratios come from one run of this binary.
// meshDrop: a cloth dropped on meshed solids (grid fields), landing included.
// ballDrop: a cloth dropped on a ball, landing included, with and without continuous contact.
// ballScene: a cloth settled on a ball and the floor, the face method against vertex contacts, at two sizes on
// one and two threads, and with the smaller one's footprint meshed finer on one. capsuleScene: the same over a
// capsule lying on the floor.
// undoableStep: the slope (faces, 10 substeps) stepped with an observer that may throw, so each step keeps its
// start to be undone, against a noexcept one.
// keptSpin: the slope and the ball scene without and with Settings::keepAngularMomentum.
// hungByCorners: a sheet hanging from its four pinned corners without and with Settings::tethers.
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

void undoableStep(benchmark::State& state) {
  drape::scenes::SlopeConfig c;
  c.subSteps = 10;
  c.base.threadCount = 1;
  auto solver = drape::scenes::makeSlope<float>(c);
  for (int f = 0; f < 90; ++f) solver.step(c.dt);
  int substeps = 0;
  for (auto _ : state) {
    if (state.range(0) != 0)
      solver.step(c.dt, [&](const auto&) { ++substeps; });
    else
      solver.step(c.dt, [&](const auto&) noexcept { ++substeps; });
    benchmark::ClobberMemory();
  }
  state.counters["vertex_substep"] = benchmark::Counter(double(solver.vertexCount()) * c.subSteps,
                                                        benchmark::Counter::kIsIterationInvariantRate |
                                                            benchmark::Counter::kInvert);
  benchmark::DoNotOptimize(substeps);
}

void slopeSize(benchmark::State& state) {
  const int side = int(state.range(0));
  runSlope<float>(state, drape::CollisionMethod::Faces, 5, 1, side == 50 ? 50 : side, side == 50 ? 80 : side,
                  int(state.range(1)));
}

/// A 40 x 40 cloth (2 cm) dropped from 4 cm above a meshed solid (64-cell grid; friction 0.3, default
/// settings) and left to settle, 60 frames of 1/60 s, landing included: the face search on a grid field as a
/// scene uses it, exact or by descent. shape 0: a torus (R 0.15, r 0.05); 1: a box turned corner up; 2: an L
/// block, concave edge up.
void meshDrop(benchmark::State& state) {
  const int shape = int(state.range(0));
  drape::Settings settings;
  settings.exactGridSearch = state.range(1) != 0;
  static const auto torus = drape::buildDistanceGrid(drape::makeTorus(0.15, 0.05, 48, 24), {64});
  static const auto box = drape::buildDistanceGrid(drape::makeBoxMesh(Eigen::Vector3d(0.12, 0.1, 0.08)), {64});
  static const auto block = drape::buildDistanceGrid(drape::makeLBlock(0.4, 0.15, 0.1), {64});
  drape::Solid<drape::MeshShape> solid;
  solid.shape.grid = shape == 0 ? torus : shape == 1 ? box : block;
  if (shape == 1) solid.pose.rotation = Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 1, 0).normalized());
  solid.staticFriction = solid.dynamicFriction = 0.3;
  const double top = shape == 0 ? 0.05 : shape == 1 ? 0.17 : 0.1;
  drape::SheetDesc sheet;
  sheet.nx = sheet.ny = 40;
  sheet.spacing = 0.02;
  sheet.placement.position = {0.01, -0.02, top + 0.04};
  const auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(sheet));
  constexpr int kFrames = 60;
  long long faceContacts = 0;
  for (auto _ : state) {
    drape::Solver<float> solver(asset, settings, 0.2);
    solver.addSolid(solid);
    for (int f = 0; f < kFrames; ++f) {
      solver.step(1.0 / 60);
      faceContacts += solver.stats().faceContacts;
    }
    benchmark::DoNotOptimize(solver.state().x.data());
  }
  const double items = double(asset->vertexCount()) * drape::Settings{}.subStepCount * kFrames;
  state.counters["vertex_substep"] =
      benchmark::Counter(items, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["face_contacts_per_frame"] = double(faceContacts) / double(kFrames * state.iterations());
}

/// A 40 x 40 cloth (2 cm) dropped onto a ball of radius 0.2 m (friction 0.3, default settings otherwise) from
/// 4 cm (landing at 0.9 m/s: 1.5 mm per substep, under the sweeps' gate of 2.5 mm, though the edges whip faster
/// as they fold down) or from 50 cm (3.1 m/s: 5.2 mm per substep), 60 frames of 1/60 s, with continuous contact
/// off or on (Settings::continuousContact). settled 1: the same 60 frames after 4 s of settling, timed alone.
void ballDrop(benchmark::State& state) {
  const double drop = double(state.range(0)) / 100;
  const bool settled = state.range(2) != 0;
  drape::Settings settings;
  settings.continuousContact = state.range(1) != 0;
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = 0.2;
  ball.staticFriction = ball.dynamicFriction = 0.3;
  drape::SheetDesc sheet;
  sheet.nx = sheet.ny = 40;
  sheet.spacing = 0.02;
  sheet.placement.position = {0.01, -0.02, 0.2 + drop};
  const auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(sheet));
  constexpr int kFrames = 60;
  long long swept = 0;
  drape::Solver<float> landed(asset, settings, 0.2);
  landed.addSolid(ball);
  if (settled)
    for (int f = 0; f < 240; ++f) landed.step(1.0 / 60);
  for (auto _ : state) {
    state.PauseTiming();
    drape::Solver<float> solver = landed;
    state.ResumeTiming();
    for (int f = 0; f < kFrames; ++f)
      solver.step(1.0 / 60, [&](const auto& s) { swept += s.stats().vertexSweeps + s.stats().faceSweeps; });
    benchmark::DoNotOptimize(solver.state().x.data());
  }
  const double items = double(asset->vertexCount()) * drape::Settings{}.subStepCount * kFrames;
  state.counters["vertex_substep"] =
      benchmark::Counter(items, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["swept_per_frame"] = double(swept) / double(kFrames * state.iterations());
}

/// A 50 x 80 cloth (2 cm) draped over a ball of radius 0.3 m resting on the floor (friction 0.3 on both, 10
/// substeps, area density 0.1 kg/m^2), timed after 2 s of settling, step after step: the first scene most users
/// try, with the default face method (method 0) against vertex contacts only (method 1). Side 256: a 256 x 256
/// cloth of 5 mm spacing over the same ball, nearly the same area, for the cost per vertex as the cloth grows.
/// Sides 100 and 200: the 50 x 80 cloth's own footprint meshed finer, 100 x 160 of 1 cm and 200 x 320 of 5 mm (a
/// finer cloth lies closer along the ball, so the share of its faces in contact grows: docs/benchmarks.md).
drape::Solver<float> settledOnBall(const drape::Settings& settings, int side, bool capsule = false) {
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = 0.3;
  ball.pose.position = {0, 0, 0.3};
  ball.staticFriction = ball.dynamicFriction = 0.3;
  // The capsule: an arm's or a rail's shape, lying along y on the floor under the cloth's long side.
  drape::Solid<drape::Capsule> bar;
  bar.shape.radius = 0.15;
  bar.shape.halfHeight = 0.45;
  bar.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * 3.14159265358979, Eigen::Vector3d::UnitX()));
  bar.pose.position = {0, 0, 0.15};
  bar.staticFriction = bar.dynamicFriction = 0.3;
  drape::Solid<drape::Plane> floor;
  floor.staticFriction = floor.dynamicFriction = 0.3;
  drape::SheetDesc sheet;
  const bool square = side == 256;
  sheet.nx = side;
  sheet.ny = square ? side : side * 8 / 5;
  sheet.spacing = square ? 0.005 : 1.0 / side;
  sheet.placement.position = {0.01, -0.02, 0.65};
  const auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(sheet));
  drape::Solver<float> solver(asset, settings, 0.1);
  if (capsule)
    solver.addSolid(bar);
  else
    solver.addSolid(ball);
  solver.addSolid(floor);
  for (int f = 0; f < 120; ++f) solver.step(1.0 / 60);
  return solver;
}

void curvedScene(benchmark::State& state, bool capsule) {
  drape::Settings settings;
  settings.collisionMethod = state.range(0) == 0 ? drape::CollisionMethod::Faces : drape::CollisionMethod::Vertices;
  settings.threadCount = int(state.range(2));
  drape::Solver<float> solver = settledOnBall(settings, int(state.range(1)), capsule);
  long long faceContacts = 0, vertexContacts = 0, facesTested = 0, facesCulled = 0, keptClear = 0, steps = 0;
  for (auto _ : state) {
    solver.step(1.0 / 60, [&](const auto& s) {
      faceContacts += s.stats().faceContacts;
      vertexContacts += s.stats().vertexContacts;
      facesTested += s.stats().facesTested;
      facesCulled += s.stats().facesCulled;
      keptClear += s.stats().facesKeptClear;
    });
    ++steps;
    benchmark::ClobberMemory();
  }
  state.counters["vertex_substep"] =
      benchmark::Counter(double(solver.vertexCount()) * settings.subStepCount,
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  const double substeps = double(steps) * settings.subStepCount;
  state.counters["face_contacts"] = double(faceContacts) / substeps;
  state.counters["vertex_contacts"] = double(vertexContacts) / substeps;
  state.counters["faces_tested"] = double(facesTested) / substeps;
  state.counters["faces_culled"] = double(facesCulled) / substeps;
  state.counters["faces_kept_clear"] = double(keptClear) / substeps;
}
void ballScene(benchmark::State& state) { curvedScene(state, false); }
void capsuleScene(benchmark::State& state) { curvedScene(state, true); }

/// What Settings::keepAngularMomentum costs (docs/design.md §4), on one thread: scene 0 is the slope (faces, 10
/// substeps, settled), scene 1 the 50 x 80 cloth settled on the ball; keep 0 without it, 1 with it.
void keptSpin(benchmark::State& state) {
  const bool keep = state.range(1) != 0;
  drape::Settings settings;
  settings.keepAngularMomentum = keep;
  settings.threadCount = 1;
  auto run = [&](auto& solver, double dt, int substeps) {
    for (auto _ : state) {
      solver.step(dt);
      benchmark::ClobberMemory();
    }
    state.counters["vertex_substep"] =
        benchmark::Counter(double(solver.vertexCount()) * substeps,
                           benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  };
  if (state.range(0) == 0) {
    drape::scenes::SlopeConfig c;
    c.subSteps = 10;
    c.base = settings;
    auto solver = drape::scenes::makeSlope<float>(c);
    for (int f = 0; f < 90; ++f) solver.step(c.dt);
    run(solver, c.dt, c.subSteps);
  } else {
    drape::Solver<float> solver = settledOnBall(settings, 50);
    run(solver, 1.0 / 60, settings.subStepCount);
  }
}

/// What Settings::tethers costs (docs/design.md §1), on one thread: a 50 x 80 sheet (2 cm) hung by its four corners,
/// 10 substeps, after 1 s of falling into its hammock; tethers 0 off, 1 on.
void hungByCorners(benchmark::State& state) {
  drape::Settings settings;
  settings.tethers = state.range(0) != 0;
  settings.threadCount = 1;
  drape::SheetDesc sheet;
  sheet.nx = 50;
  sheet.ny = 80;
  sheet.spacing = 0.02;
  sheet.placement.position = {0, 0, 0.5};
  drape::Solver<float> solver(
      std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(sheet)), settings, 0.1);
  for (const drape::Index i : {0, 49, 79 * 50, 80 * 50 - 1}) solver.pin(i);
  for (int f = 0; f < 100; ++f) solver.step(0.01);
  for (auto _ : state) {
    solver.step(0.01);
    benchmark::ClobberMemory();
  }
  state.counters["vertex_substep"] =
      benchmark::Counter(double(solver.vertexCount()) * settings.subStepCount,
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void substepsAndIterations(benchmark::internal::Benchmark* b) {
  b->ArgNames({"substeps", "iterations"})->Args({5, 1})->Args({10, 1})->Args({5, 5})->Unit(benchmark::kMillisecond);
}

using drape::CollisionMethod;
BENCHMARK(slopeStep<float, CollisionMethod::Faces>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<float, CollisionMethod::InSolve>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<float, CollisionMethod::Vertices>)->Apply(substepsAndIterations);
BENCHMARK(slopeStep<double, CollisionMethod::Faces>)->Apply(substepsAndIterations);
// undoable 1: an observer that may throw; 0: a noexcept one.
BENCHMARK(undoableStep)->ArgName("undoable")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// side 50 means the 50x80 cloth; threads 1 or 2. Real time: with two threads, CPU time would count both.
BENCHMARK(slopeSize)
    ->ArgNames({"side", "threads"})
    ->Args({50, 1})
    ->Args({256, 1})
    ->Args({256, 2})
    ->Args({50, 2})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// exact 1: the branch and bound (the default); 0: the projected gradient descent (Settings::exactGridSearch).
BENCHMARK(meshDrop)
    ->ArgNames({"shape", "exact"})
    ->ArgsProduct({{0, 1, 2}, {1, 0}})
    ->Unit(benchmark::kMillisecond);

// drop in cm; continuous 1: Settings::continuousContact on; settled 1: timed after 4 s of settling.
BENCHMARK(ballDrop)
    ->ArgNames({"drop", "continuous", "settled"})
    ->Args({4, 0, 0})
    ->Args({4, 1, 0})
    ->Args({50, 0, 0})
    ->Args({50, 1, 0})
    ->Args({4, 0, 1})
    ->Args({4, 1, 1})
    ->Unit(benchmark::kMillisecond);

// method 0: faces (the default); 1: vertices. The two in one run give the ratio. side 50 means the 50x80 cloth;
// threads 1 or 2 (real time).
BENCHMARK(ballScene)
    ->ArgNames({"method", "side", "threads"})
    ->ArgsProduct({{0, 1}, {50, 256}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
// The 50 x 80 cloth's footprint meshed finer, on one thread: the cost per vertex as one footprint's mesh grows.
BENCHMARK(ballScene)
    ->ArgNames({"method", "side", "threads"})
    ->ArgsProduct({{0, 1}, {100, 200}, {1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// The same over a capsule of radius 0.15 m lying on the floor under the cloth, on one thread.
BENCHMARK(capsuleScene)
    ->ArgNames({"method", "side", "threads"})
    ->ArgsProduct({{0, 1}, {50}, {1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// scene 0: the slope, 1: the ball; keep 1: Settings::keepAngularMomentum on.
BENCHMARK(keptSpin)->ArgNames({"scene", "keep"})->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);

BENCHMARK(hungByCorners)->ArgNames({"tethers"})->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
