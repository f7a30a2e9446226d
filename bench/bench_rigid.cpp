// Rigid bodies: wall time per step against the body count in a rain scene (the cloth-rigid coupling thesis's Fig 6.7):
// random seeded shapes (sphere, box, capsule, cylinder, convex hull) dropped into a region walled by four static
// (kinematic, zero velocity) boxes on the ground. The region's area grows with the count so that the pile's depth, and
// so the contacts per body, stay alike. Each timed step follows 1.5 s of settling; the time is the mean of the timed
// steps, which keep running the same scene.
//
//   build-rigid/bench/bench_rigid --benchmark_counters_tabular=true
//
// The BigO line is Google Benchmark's least-squares fit of time = k N: k is the cost per body per step.

#include <drape/rigid/world.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

namespace {

using drape::BodyDesc;
using Eigen::Vector3d;

drape::RigidWorld rain(int count, unsigned seed) {
  drape::RigidWorld world;  // 10 substeps, 1 iteration, ground at z = 0
  const double side = std::max(2.0, 0.9 * std::sqrt(double(count)));  // m, about 0.8 bodies per m^2 per layer
  const double wall = 0.1, height = 0.6;
  for (int k = 0; k < 4; ++k) {
    BodyDesc w;
    const bool alongX = k < 2;
    const double s = k % 2 ? 1 : -1;
    w.shape = drape::Box{alongX ? Vector3d(side / 2 + wall, wall, height) : Vector3d(wall, side / 2 + wall, height)};
    w.pose.position = alongX ? Vector3d(0, s * (side / 2 + wall), height) : Vector3d(s * (side / 2 + wall), 0, height);
    w.motion = drape::BodyMotion::Kinematic;
    world.add(w);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const int perLayer = std::max(1, int(side * side / 0.6));
  for (int i = 0; i < count; ++i) {
    BodyDesc b;
    const double a = 0.1 + 0.15 * u(rng), c = 0.1 + 0.15 * u(rng);
    switch (i % 5) {
      case 0: b.shape = drape::Sphere{a}; break;
      case 1: b.shape = drape::Box{Vector3d(a, c, 0.1 + 0.15 * u(rng))}; break;
      case 2: b.shape = drape::Capsule{0.6 * a, c}; break;
      case 3: b.shape = drape::Cylinder{a, c}; break;
      default: {
        std::vector<Vector3d> pts;
        for (int p = 0; p < 12; ++p) pts.emplace_back(a * (2 * u(rng) - 1), a * (2 * u(rng) - 1), c * (2 * u(rng) - 1));
        pts.emplace_back(a, 0, 0), pts.emplace_back(-a, 0, 0), pts.emplace_back(0, a, 0), pts.emplace_back(0, 0, c);
        b.shape = drape::ConvexHull(pts);
      }
    }
    const double r = 0.5 * side - 0.35;
    b.pose.position = Vector3d(r * (2 * u(rng) - 1), r * (2 * u(rng) - 1), 0.6 + 0.7 * (i / perLayer) + 0.3 * u(rng));
    b.pose.rotation = Eigen::Quaterniond::UnitRandom();
    b.linearVelocity = Vector3d(0, 0, -2 * u(rng));
    b.angularVelocity = Vector3d(u(rng), u(rng), u(rng));
    world.add(b);
  }
  return world;
}

void BM_RainStep(benchmark::State& state) {
  const int count = static_cast<int>(state.range(0));
  drape::RigidWorld world = rain(count, 42);
  const double dt = 1.0 / 60;
  for (int f = 0; f < 90; ++f) world.step(dt);
  std::size_t contacts = 0, steps = 0;
  for (auto _ : state) {
    world.step(dt);
    contacts += world.contacts().size();
    ++steps;
  }
  state.SetComplexityN(count);
  state.counters["bodies"] = count;
  state.counters["manifolds"] = double(contacts) / double(steps);
  state.counters["us_per_body"] = benchmark::Counter(double(count) * double(steps),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_RainStep)
    ->Arg(1)->Arg(2)->Arg(5)->Arg(10)->Arg(20)->Arg(40)->Arg(80)->Arg(160)->Arg(320)->Arg(640)->Arg(1280)
    ->Unit(benchmark::kMillisecond)
    ->Complexity(benchmark::oN);

}  // namespace

BENCHMARK_MAIN();
