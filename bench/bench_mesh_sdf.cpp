// Grid distance fields from meshes: the time to build a 64^3 grid (one thread) and the cost of one sample, in ns,
// in float and double, at random points near the surface (where cloth queries it) of a posed grid.
// Run: build/bench/bench_mesh_sdf --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// The accuracy table against resolution is printed by build/bench/mesh_sdf_accuracy.
#include <drape/sdf/grid.hpp>

#include <mesh_shapes.hpp>

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

namespace {

using namespace drape;

const scenes::MeshShapeCase& shape(int i) {
  static const auto cases = scenes::meshShapeCases();
  return cases[std::size_t(i)];
}

/// Builds the 64^3 grid of shape 0 (icosphere, 1280 triangles) or 2 (torus, 2304 triangles).
void build64(benchmark::State& state) {
  const auto& s = shape(int(state.range(0)));
  std::size_t nodes = 0;
  for (auto _ : state) {
    const auto grid = buildDistanceGrid(s.mesh, DistanceGridOptions{64, 0, 0});
    nodes = grid->nodes.size();
    benchmark::DoNotOptimize(grid.get());
  }
  state.SetLabel(s.name + ", " + std::to_string(s.mesh.triangleCount()) + " triangles, " + std::to_string(nodes) +
                 " nodes");
  state.counters["ns_per_node"] =
      benchmark::Counter(double(nodes), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// Times one field over 4096 points (value and gradient per sample), reported in ns per sample.
template <class S, class Field>
void timeSamples(benchmark::State& state, const Field& sdf, const std::vector<Vec3<S>>& points) {
  std::size_t i = 0;
  for (auto _ : state) {
    Vec3<S> g;
    const S phi = sdf(points[i++ & 4095], g);
    benchmark::DoNotOptimize(phi);
    benchmark::DoNotOptimize(g);
  }
  state.counters["ns_per_sample"] =
      benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// One query of a posed 64^3 torus grid (value and gradient) at points within 0.05 m of its surface, spread over
/// the whole torus (range 0: the grid's 1.5 MB do not stay in cache) or within a 0.1 m patch of it (range 1: as
/// the faces of one cloth touching one place query it).
template <class S>
void sample(benchmark::State& state) {
  const bool patch = state.range(0) == 1;
  const double spread = patch ? 0.1 / 1.2 : 1.0;
  const Eigen::Vector3d centre = patch ? Eigen::Vector3d(0.55, 0, 0) : Eigen::Vector3d::Zero();  // outer equator
  const auto& s = shape(2);
  const auto grid = buildDistanceGrid(s.mesh, DistanceGridOptions{64, 0, 0});
  Pose pose;
  pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 1, 0).normalized()));
  pose.position = Eigen::Vector3d(0.3, 0.1, 1.0);
  const Eigen::Vector3d origin(0, 0, 1);
  const auto sdf = detail::compileSdf<S>(MeshShape{grid}, pose, origin);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<Vec3<S>> points;
  while (points.size() < 4096) {
    const Eigen::Vector3d p = centre + spread * Eigen::Vector3d(0.6 * unit(rng), 0.6 * unit(rng), 0.2 * unit(rng));
    if (std::abs(s.analytic(p)) < 0.05) points.push_back((pose.apply(p) - origin).template cast<S>());
  }
  timeSamples(state, sdf, points);
}

/// The built-in analytic box, for scale.
template <class S>
void sampleBox(benchmark::State& state) {
  const auto sdf = detail::compileSdf<S>(Box{Eigen::Vector3d(0.4, 0.3, 0.2)}, Pose{}, Eigen::Vector3d::Zero());
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  std::vector<Vec3<S>> points(4096);
  for (auto& p : points) p = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).template cast<S>();
  timeSamples(state, sdf, points);
}

}  // namespace

BENCHMARK(build64)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(sample, float)->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(sample, double)->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(sampleBox, float);
BENCHMARK_TEMPLATE(sampleBox, double);
BENCHMARK_MAIN();
