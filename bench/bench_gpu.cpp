// The GPU against the CPU (issue 5, item 7), in one run: per kernel (ns per item, the kernel dispatched and
// waited for) and per step of the inclined-plane scene (50x80, 10 substeps, friction 0.3, in contact: 60 frames
// are run first). The GPU is the one Backend::Auto finds: an EGL hardware device where the machine has one, else
// Mesa's llvmpipe through OSMesa (DRAPE_GPU_BACKEND=egl|osmesa picks one). On llvmpipe the figures measure a
// CPU emulating a GPU, not a GPU.
//
//   build/bench/bench_gpu --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "slope.hpp"

#include <drape/gpu/solver.hpp>

#include <benchmark/benchmark.h>

#include <memory>
#include <optional>
#include <string>

namespace {

using drape::Index;
namespace gpu = drape::gpu;
namespace layout = drape::gpu::layout;

/// The context for the whole run, or why there is none.
gpu::Context* context(std::string& why) {
  static std::optional<gpu::Context> ctx;
  static std::string error;
  static bool tried = false;
  if (!tried) {
    tried = true;
    try {
      ctx.emplace();
    } catch (const drape::Error& e) {
      error = e.what();
    }
  }
  why = error;
  return ctx ? &*ctx : nullptr;
}

void perItem(benchmark::State& state, double items) {
  state.counters["ns_per_item"] =
      benchmark::Counter(items, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

drape::scenes::SlopeConfig slope() {
  drape::scenes::SlopeConfig c;
  c.friction = 0.3;
  return c;
}

/// One step (10 substeps) of the sliding cloth on the CPU, one thread.
void BM_SlopeStepCpu(benchmark::State& state) {
  const auto c = slope();
  drape::Solver<float> solver = drape::scenes::makeSlope<float>(c);
  for (int f = 0; f < 60; ++f) solver.step(c.dt);
  for (auto _ : state) solver.step(c.dt);
  perItem(state, double(solver.vertexCount()) * c.subSteps);  // per vertex-substep
}
BENCHMARK(BM_SlopeStepCpu)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The same step on the GPU, waited for.
void BM_SlopeStepGpu(benchmark::State& state) {
  std::string why;
  gpu::Context* ctx = context(why);
  if (!ctx) return state.SkipWithError(why.c_str());
  const auto c = slope();
  const auto parts = drape::scenes::slopeParts<float>(c);
  gpu::Solver solver(*ctx, parts.asset, parts.settings, c.areaDensity);
  solver.addSolid(parts.slope);
  for (int f = 0; f < 60; ++f) solver.step(c.dt);
  solver.finish();
  for (auto _ : state) {
    solver.step(c.dt);
    solver.finish();
  }
  state.SetLabel(ctx->renderer());
  perItem(state, double(solver.vertexCount()) * c.subSteps);
}
BENCHMARK(BM_SlopeStepGpu)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The 50x80 cloth's vertices and constraints on the GPU, as the solver lays them out.
struct GpuCloth {
  std::shared_ptr<const drape::ClothAsset<float>> asset;
  gpu::Buffer<layout::Vertex> x, v, xp, xw, x0;
  gpu::Buffer<layout::Constraint> constraints;
  gpu::Buffer<float> lambdas;
  explicit GpuCloth(const std::shared_ptr<const drape::ClothAsset<float>>& a) : asset(a) {
    const auto state = drape::ClothState<float>::fromAsset(*asset, 0.1);
    std::vector<layout::Vertex> pos(state.x.size()), zero(state.x.size(), layout::Vertex{0, 0, 0, 0});
    for (std::size_t i = 0; i < pos.size(); ++i)
      pos[i] = {1.01f * state.x[i].x(), 1.01f * state.x[i].y(), state.x[i].z(), state.invMass[i]};
    x.assign(pos);
    xw.assign(pos);
    v.assign(zero);
    xp.assign(pos);
    x0.assign(zero);
    std::vector<layout::Constraint> list;
    for (Index k = 0; k < asset->stretch.size(); ++k)
      list.push_back({std::uint32_t(asset->stretch.pairs[std::size_t(k)][0]),
                      std::uint32_t(asset->stretch.pairs[std::size_t(k)][1]), asset->stretch.restLength[std::size_t(k)], 0u});
    constraints.assign(list);
    lambdas.assign(std::vector<float>(list.size(), 0.0f));
    x.bind(layout::kPositions);
    v.bind(layout::kVelocities);
    xp.bind(layout::kPredicted);
    xw.bind(layout::kPacked);
    x0.bind(layout::kStart);
    constraints.bind(layout::kConstraints);
    lambdas.bind(layout::kLambdas);
  }
};

std::shared_ptr<const drape::ClothAsset<float>> cloth() {
  const auto parts = drape::scenes::slopeParts<float>(slope());
  return parts.asset;
}

/// A per-vertex kernel over the 4000 vertices: 0 predict, 1 update velocity.
void BM_VertexKernelGpu(benchmark::State& state) {
  std::string why;
  gpu::Context* ctx = context(why);
  if (!ctx) return state.SkipWithError(why.c_str());
  ctx->makeCurrent();
  GpuCloth c(cloth());
  const auto n = unsigned(c.asset->vertexCount());
  const bool predict = state.range(0) == 0;
  gpu::Program k(predict ? "predict" : "update_velocity",
                 predict ? gpu::shaders::predict : gpu::shaders::update_velocity);
  k.set(layout::kCount, n);
  k.set(layout::kStep, 1.0f / 600);
  k.set(layout::kInverseStep, 600.0f);
  k.set(layout::kGravityStep, 0.0f, 0.0f, -9.81f / 600);
  k.set(layout::kKeepStart, 1u);
  for (auto _ : state) {
    k.dispatch(n);
    glFinish();
  }
  state.SetLabel(predict ? "predict" : "update velocity");
  perItem(state, n);
}
BENCHMARK(BM_VertexKernelGpu)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_VertexKernelCpu(benchmark::State& state) {
  const auto asset = cloth();
  auto s = drape::ClothState<float>::fromAsset(*asset, 0.1);
  const Index n = asset->vertexCount();
  std::vector<drape::Vec3<float>> x0(static_cast<std::size_t>(n)), xp(static_cast<std::size_t>(n));
  std::vector<drape::Vec4<float>> xw(static_cast<std::size_t>(n));
  const bool predict = state.range(0) == 0;
  const drape::Vec3<float> gh(0, 0, -9.81f / 600);
  drape::predictPositions<true>(n, s.x.data(), s.v.data(), s.invMass.data(), gh, 1.0f / 600, x0.data(), xp.data(), xw.data());
  for (auto _ : state) {
    if (predict)
      drape::predictPositions<true>(n, s.x.data(), s.v.data(), s.invMass.data(), gh, 1.0f / 600, x0.data(), xp.data(),
                                    xw.data());
    else
      drape::updateVelocities<false, false>(n, xw.data(), xp.data(), s.x.data(), s.v.data(), 600.0f);
    benchmark::ClobberMemory();
  }
  state.SetLabel(predict ? "predict" : "update velocity");
  perItem(state, n);
}
BENCHMARK(BM_VertexKernelCpu)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// One pass over the stretch set, colour by colour: a dispatch per colour on the GPU.
void BM_StretchSolveGpu(benchmark::State& state) {
  std::string why;
  gpu::Context* ctx = context(why);
  if (!ctx) return state.SkipWithError(why.c_str());
  ctx->makeCurrent();
  GpuCloth c(cloth());
  gpu::Program k("solve_distance", gpu::shaders::solve_distance);
  k.set(layout::kAlphaTilde, 0.0f);
  k.set(layout::kUseLambda, 0u);
  const auto& offsets = c.asset->stretch.colourOffsets;
  for (auto _ : state) {
    for (std::size_t col = 0; col + 1 < offsets.size(); ++col) {
      k.set(layout::kFirst, unsigned(offsets[col]));
      k.set(layout::kCount, unsigned(offsets[col + 1] - offsets[col]));
      k.dispatch(std::size_t(offsets[col + 1] - offsets[col]));
    }
    glFinish();
  }
  state.counters["colours"] = double(offsets.size() - 1);
  perItem(state, double(c.asset->stretch.size()));
}
BENCHMARK(BM_StretchSolveGpu)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_StretchSolveCpu(benchmark::State& state) {
  const auto asset = cloth();
  const auto s = drape::ClothState<float>::fromAsset(*asset, 0.1);
  std::vector<drape::Vec4<float>> xw(s.x.size());
  for (std::size_t i = 0; i < xw.size(); ++i) xw[i] = {1.01f * s.x[i].x(), 1.01f * s.x[i].y(), s.x[i].z(), 0.0f};
  drape::LaneMasses<float> lanes;
  lanes.gather(asset->stretch, s.invMass.data());
  for (auto _ : state) {
    drape::solveDistanceSet<false, float>(asset->stretch, lanes, 0.0f, nullptr, xw.data(), s.invMass.data());
    benchmark::ClobberMemory();
  }
  perItem(state, double(asset->stretch.size()));
}
BENCHMARK(BM_StretchSolveCpu)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
