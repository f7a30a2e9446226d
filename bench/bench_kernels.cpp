// Kernel micro-benchmarks, ns per item (items/s inverted): one distance-constraint set per type and SIMD level,
// the prediction and the velocity update, the cull of a far face, the deepest-point search per shape, the
// contact response and propagation, and the broad phase's rebuild.
// Run: build/bench/bench_kernels --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <drape/drape.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <random>

namespace {

using drape::Index;

template <class S> std::shared_ptr<const drape::ClothAsset<S>> grid(int nx, int ny) {
  drape::SheetDesc g;
  g.nx = nx;
  g.ny = ny;
  g.spacing = 0.02;
  return std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(g));
}

void perItem(benchmark::State& state, double items) {
  state.counters["ns_per_item"] =
      benchmark::Counter(items, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// One pass over the stretch (0), shear (1) or bending (2) set of a 50x80 grid, stretched 1 % (every
/// constraint does its full arithmetic), with the kernel of SIMD level 0 (scalar), 1 (SSE2) or 2 (AVX2); double
/// always runs the scalar kernel.
template <class S> void distanceSet(benchmark::State& state) {
  const auto level = drape::SimdLevel(state.range(1));
  if (level > drape::bestSimdLevel()) {
    state.SkipWithError("this processor lacks that SIMD level");
    return;
  }
  const auto asset = grid<S>(50, 80);
  const drape::DistanceSet<S>& set =
      state.range(0) == 0 ? asset->stretch : state.range(0) == 1 ? asset->shear : asset->bending;
  std::vector<drape::Vec4<S>> x(asset->vertexCount());
  for (Index i = 0; i < asset->vertexCount(); ++i) {
    const drape::Vec3<S> p = S(1.01) * asset->restPositions[i];
    x[i] = drape::Vec4<S>(p.x(), p.y(), p.z(), S(0));
  }
  const std::vector<S> w(x.size(), S(10));
  drape::DistanceBlocks<S> lanes(set);
  lanes.gatherMasses(w.data());
  for (auto _ : state) {
    drape::solveDistanceSet<false>(set, lanes, S(0), static_cast<S*>(nullptr), x.data(), w.data(), level);
    for (auto& p : x) p.template head<3>() *= S(1.0001);  // keep them stretched
    benchmark::ClobberMemory();
  }
  perItem(state, double(set.size()));
}

/// The per-vertex passes around the solve on a 50x80 cloth, ns per vertex: the prediction (0) and the
/// velocity update (1).
template <class S> void integrate(benchmark::State& state) {
  const auto asset = grid<S>(50, 80);
  const Index n = asset->vertexCount();
  std::vector<drape::Vec3<S>> x(asset->restPositions), xp(n), x0(n), v(n, drape::Vec3<S>(0.1, 0, -0.2));
  std::vector<drape::Vec4<S>> xw(n);
  const std::vector<S> w(n, S(10));
  const drape::Vec3<S> gh(0, 0, S(-9.81 / 300));
  const S h = S(1.0 / 300);
  drape::predictPositions<false, false>(0, n, x.data(), v.data(), w.data(), gh, h, x0.data(), xp.data(), xw.data());
  const bool predict = state.range(0) == 0;
  for (auto _ : state) {
    if (predict)
      drape::predictPositions<false, false>(0, n, x.data(), v.data(), w.data(), gh, h, x0.data(), xp.data(), xw.data());
    else
      drape::updateVelocities<false, false>(0, n, xw.data(), xp.data(), x.data(), v.data(), S(1) / h);
    benchmark::ClobberMemory();
  }
  perItem(state, double(n));
}

template <class Shape> Shape shapeFor();
template <> drape::Plane shapeFor() { return {}; }
template <> drape::Sphere shapeFor() { return {0.3}; }
template <> drape::Box shapeFor() { return {Eigen::Vector3d(0.3, 0.2, 0.1)}; }
template <> drape::Capsule shapeFor() { return {0.05, 0.3}; }
/// A ball of radius 0.3 m as a 64-cell grid field of an icosphere (5 mm cells beside 2 cm faces).
template <> drape::MeshShape shapeFor() {
  static const auto grid = drape::buildDistanceGrid(drape::makeIcosphere(0.3, 4), {64});
  return {grid};
}

/// The deepest-point search on random 2 cm faces near the surface of each shape, or (cull) far from it.
template <class Shape, class S, bool kFar> void faceQuery(benchmark::State& state) {
  const drape::Pose pose;
  const auto sdf = drape::detail::compileSdf<S>(shapeFor<Shape>(), pose, Eigen::Vector3d::Zero());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  constexpr int kFaces = 1024;
  std::vector<std::array<drape::Vec3<S>, 3>> faces(kFaces);
  for (auto& f : faces) {
    Eigen::Vector3d c(u(rng), u(rng), u(rng));
    c = c.normalized() * (kFar ? 2.0 : 0.3) + Eigen::Vector3d(0, 0, 0.0);
    if constexpr (std::is_same_v<Shape, drape::Plane>) c.z() = kFar ? 2.0 : 0.002 * u(rng);
    for (auto& p : f) p = (c + 0.02 * Eigen::Vector3d(u(rng), u(rng), u(rng))).cast<S>();
  }
  drape::FaceQuery<S> q;
  long long evaluations = 0;
  for (auto _ : state)
    for (const auto& f : faces) {
      benchmark::DoNotOptimize(drape::queryFace<true>(sdf, f[0], f[1], f[2], S(0.005), 12, q));
      benchmark::DoNotOptimize(q);
      evaluations += q.evaluations;
    }
  perItem(state, kFaces);
  state.counters["evaluations"] = benchmark::Counter(double(evaluations) / double(kFaces * state.iterations()));
}

/// The projected gradient descent (descendOnFace) on the same faces of the meshed ball, uncertified, for
/// comparison with the branch and bound that queryFace runs on grid fields.
template <class S> void faceDescent(benchmark::State& state) {
  const auto sdf = drape::detail::compileSdf<S>(shapeFor<drape::MeshShape>(), drape::Pose{}, Eigen::Vector3d::Zero());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  constexpr int kFaces = 1024;
  std::vector<std::array<drape::Vec3<S>, 3>> faces(kFaces);
  for (auto& f : faces) {
    const Eigen::Vector3d c = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * 0.3;
    for (auto& p : f) p = (c + 0.02 * Eigen::Vector3d(u(rng), u(rng), u(rng))).cast<S>();
  }
  for (auto _ : state)
    for (const auto& f : faces) {
      const drape::FaceSphere<S> sphere = drape::faceSphere<S>(f[0], f[1], f[2]);
      drape::Vec3<S> g;
      const S phi = sdf(sphere.centre, g);
      benchmark::DoNotOptimize(drape::descendOnFace<S>(sdf, f[0], f[1], f[2], sphere.centre, phi, g, 12));
    }
  perItem(state, kFaces);
}

/// Contact response (split, no friction / with friction) and one ring of propagation on a 50x80 cloth whose
/// middle third rests on a floor.
template <class S, bool kFriction> void respondAndPropagate(benchmark::State& state) {
  const auto asset = grid<S>(50, 80);
  const Index n = asset->vertexCount();
  std::vector<drape::Vec3<S>> x(asset->restPositions), x0(x), v(n, drape::Vec3<S>(0.1, 0, -0.2));
  const std::vector<S> w(n, S(10));
  drape::ContactBuffer<S> contacts;
  contacts.resize(n);
  drape::PropagationBuffer<S> propagation;
  propagation.resize(n);
  drape::SolidMotion<S> motion{drape::Vec3<S>::Zero(), drape::Vec3<S>::Zero(), drape::Vec3<S>::Zero(),
                               S(kFriction ? 0.3 : 0), S(kFriction ? 0.3 : 0)};
  const bool propagate = state.range(0) == 1;
  Index live = 0;
  for (auto _ : state) {
    state.PauseTiming();
    contacts.begin();
    live = 0;
    for (Index i = n / 3; i < 2 * n / 3; ++i, ++live) {
      contacts.template record<false>(i, x[i], drape::Vec3<S>::UnitZ(), S(1e-4), motion, x[i],
                                       motion.velocityAt(x[i]));
      contacts.normalDv[i] = S(0.2);  // what the response would have removed: the source of propagation
    }
    for (auto& vi : v) vi = drape::Vec3<S>(0.1, 0, -0.2);
    state.ResumeTiming();
    if (propagate) {
      propagation.beginPass();
      drape::propagateRing(0, n, 1, contacts, propagation, asset->vertexNeighbours, v.data(), w.data(), S(0.5));
    } else {
      drape::respondContacts<kFriction>(0, n, contacts, x.data(), x0.data(), v.data(), S(1.0 / 300), S(1));
    }
    benchmark::ClobberMemory();
  }
  perItem(state, propagate ? double(n) : double(live));
}

/// The broad phase's rebuild (VertexBins::build) on a 256 x 256 sheet of 5 mm, rippled by 5 cm so that its faces
/// and cells vary: ns per vertex. On a 256 x 256 cloth settling over a ball it was 7 % of a step (docs/benchmarks.md).
void binsBuild(benchmark::State& state) {
  drape::SheetDesc g;
  g.nx = g.ny = 256;
  g.spacing = 0.005;
  const auto asset = drape::ClothAsset<float>::sheet(g);
  std::vector<drape::Vec3<float>> x(asset.restPositions);
  for (auto& p : x) p.z() += 0.05f * std::sin(40 * p.x()) * std::cos(30 * p.y());
  drape::VertexBins<float> bins;
  bins.setTopology(asset.triangles, asset.vertexCount(), 0.01f);
  for (auto _ : state) {
    bins.build(x.data(), asset.triangles);
    benchmark::ClobberMemory();
  }
  perItem(state, double(asset.vertexCount()));
}

BENCHMARK(distanceSet<float>)->ArgNames({"set", "simd"})->ArgsProduct({{0, 1, 2}, {0, 1, 2}});
BENCHMARK(distanceSet<double>)->ArgNames({"set", "simd"})->ArgsProduct({{0, 1, 2}, {0}});
BENCHMARK(integrate<float>)->ArgName("update")->DenseRange(0, 1);
BENCHMARK(faceQuery<drape::Plane, float, false>);
BENCHMARK(faceQuery<drape::Sphere, float, false>);
BENCHMARK(faceQuery<drape::Box, float, false>);
BENCHMARK(faceQuery<drape::Capsule, float, false>);
BENCHMARK(faceQuery<drape::Sphere, float, true>);  // culled
BENCHMARK(faceQuery<drape::Sphere, double, false>);
BENCHMARK(faceQuery<drape::MeshShape, float, false>);
BENCHMARK(faceQuery<drape::MeshShape, double, false>);
BENCHMARK(faceQuery<drape::MeshShape, float, true>);  // culled
BENCHMARK(faceDescent<float>);
BENCHMARK(respondAndPropagate<float, false>)->ArgName("propagate")->DenseRange(0, 1);
BENCHMARK(respondAndPropagate<float, true>)->ArgName("propagate")->Arg(0);
BENCHMARK(binsBuild);

}  // namespace

BENCHMARK_MAIN();
