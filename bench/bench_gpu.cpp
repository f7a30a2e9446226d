// The GPU against the CPU, in one run: per kernel (ns per item, the kernel dispatched and
// waited for) and per step of the inclined-plane scene (50x80, 10 substeps, friction 0.3, in contact: 60 frames
// are run first). The GPU is the one Backend::Auto finds: an EGL hardware device where the machine has one, else
// Mesa's llvmpipe through OSMesa (DRAPE_GPU_BACKEND=egl|osmesa picks one). On llvmpipe the figures measure a
// CPU emulating a GPU, not a GPU.
//
// The collision kernels are measured on the same cloth, flat, with a ball of 20 cm radius poking 2 cm through its
// middle (the vertex pass, and the face pass over every colour, positions restored before each pass); the coupled
// scene is the rigid rain's first second (5 bodies falling onto the pinned cloth, stepped from 0.6 s, when they
// are on it).
//
//   build/bench/bench_gpu --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "rigid_rain.hpp"
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
  k.set(layout::kKeepVelocity, 1.0f);
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
  drape::predictPositions<true, false>(0, n, s.x.data(), s.v.data(), s.invMass.data(), gh, 1.0f / 600, x0.data(),
                                       xp.data(), xw.data());
  for (auto _ : state) {
    if (predict)
      drape::predictPositions<true, false>(0, n, s.x.data(), s.v.data(), s.invMass.data(), gh, 1.0f / 600, x0.data(),
                                           xp.data(), xw.data());
    else
      drape::updateVelocities<false, false>(0, n, xw.data(), xp.data(), s.x.data(), s.v.data(), 600.0f);
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
  drape::DistanceBlocks<float> lanes(asset->stretch);
  lanes.gatherMasses(s.invMass.data());
  for (auto _ : state) {
    drape::solveDistanceSet<false, float>(asset->stretch, lanes, 0.0f, nullptr, xw.data(), s.invMass.data());
    benchmark::ClobberMemory();
  }
  perItem(state, double(asset->stretch.size()));
}
BENCHMARK(BM_StretchSolveCpu)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// The flat cloth and the ball poking through it, compiled at the cloth's origin.
drape::CompiledSolid<drape::Sphere, float> pokingBall(const drape::ClothAsset<float>& asset) {
  const auto state = drape::ClothState<float>::fromAsset(asset, 0.1);
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = 0.2;
  ball.pose.position = state.origin + Eigen::Vector3d(0.003, -0.004, 0.02 - 0.2);
  ball.staticFriction = 0.3;
  return drape::detail::compileSolid<drape::Sphere, float>(ball, state.origin);
}

/// The collision passes against the ball: 0 the vertex pass, 1 the face pass (a dispatch per colour). The
/// positions are restored from a copy before each pass, and for the face pass the records cleared (included: a
/// buffer copy, and a clear).
void BM_CollideGpu(benchmark::State& state) {
  std::string why;
  gpu::Context* ctx = context(why);
  if (!ctx) return state.SkipWithError(why.c_str());
  ctx->makeCurrent();
  const auto asset = cloth();
  auto s = drape::ClothState<float>::fromAsset(*asset, 0.1);
  std::vector<layout::Vertex> pos(s.x.size());
  for (std::size_t i = 0; i < pos.size(); ++i) pos[i] = {s.x[i].x(), s.x[i].y(), s.x[i].z(), s.invMass[i]};
  gpu::Buffer<layout::Vertex> x(pos), pristine(pos);
  gpu::Buffer<layout::Contact> contacts(std::vector<layout::Contact>(pos.size(), layout::Contact{}));
  const auto coloured = gpu::colourFaces(asset->triangles, asset->vertexCount());
  gpu::Buffer<std::array<std::uint32_t, 4>> faces(coloured.faces);
  gpu::Buffer<std::uint32_t> flags(std::vector<std::uint32_t>(4, 0u));
  x.bind(layout::kPositions);
  contacts.bind(layout::kContacts);
  faces.bind(layout::kFaces);
  flags.bind(layout::kFlags);
  const auto ball = pokingBall(*asset);
  const bool facePass = state.range(0) == 1;
  gpu::Program k(facePass ? "collide_faces" : "collide_vertices",
                 facePass ? gpu::shaders::collide_faces : gpu::shaders::collide_vertices, gpu::shapeDefine<drape::Sphere>());
  gpu::setShape(k.id(), gpu::packShape(ball.sdf));
  k.set(layout::kThickness, 0.005f);
  k.set(layout::kSolidCentre, ball.motion.centre.x(), ball.motion.centre.y(), ball.motion.centre.z());
  k.set(layout::kSolidLinear, 0.0f, 0.0f, 0.0f);
  k.set(layout::kSolidAngular, 0.0f, 0.0f, 0.0f);
  k.set(layout::kBoxLow, ball.boxLow.x(), ball.boxLow.y(), ball.boxLow.z());
  k.set(layout::kBoxHigh, ball.boxHigh.x(), ball.boxHigh.y(), ball.boxHigh.z());
  glProgramUniform1i(k.id(), layout::kPgdIterations, 12);
  if (!facePass) {  // the vertex pass starts every record (fresh); the face pass's records are cleared below
    glProgramUniform1i(k.id(), layout::kPass, -1);
    k.set(layout::kFresh, 1u);
  }
  const auto bytes = GLsizeiptr(pos.size() * sizeof(layout::Vertex));
  for (auto _ : state) {
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glCopyNamedBufferSubData(pristine.id(), x.id(), 0, 0, bytes);
    if (facePass) {
      glClearNamedBufferData(contacts.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);  // no record yet
      for (std::size_t c = 0; c + 1 < coloured.offsets.size(); ++c) {
        k.set(layout::kFirst, unsigned(coloured.offsets[c]));
        k.set(layout::kCount, unsigned(coloured.offsets[c + 1] - coloured.offsets[c]));
        k.dispatch(coloured.offsets[c + 1] - coloured.offsets[c]);
      }
    } else {
      k.set(layout::kCount, unsigned(pos.size()));
      k.dispatch(pos.size());
    }
    glFinish();
  }
  state.SetLabel(facePass ? "face pass" : "vertex pass");
  perItem(state, facePass ? double(asset->faceCount()) : double(pos.size()));
}
BENCHMARK(BM_CollideGpu)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_CollideCpu(benchmark::State& state) {
  const auto asset = cloth();
  const auto s = drape::ClothState<float>::fromAsset(*asset, 0.1);
  const auto ball = pokingBall(*asset);
  const bool facePass = state.range(0) == 1;
  drape::ContactBuffer<float> contacts;
  contacts.resize(asset->vertexCount());
  drape::CollisionStats stats;
  std::vector<drape::Vec3<float>> x;
  for (auto _ : state) {
    x = s.x;
    contacts.begin();
    if (facePass)
      drape::projectFaceContacts<true>(ball, 0.005f, 12, asset->triangles, drape::AllItems{}, asset->faceCount(),
                                       x.data(), s.invMass.data(), contacts, stats, x.data());
    else
      drape::projectVertexContacts(0, asset->vertexCount(), ball, 0.005f, x.data(), s.invMass.data(),
                                   drape::AllItems{}, contacts, x.data());
    benchmark::ClobberMemory();
  }
  state.SetLabel(facePass ? "face pass" : "vertex pass");
  perItem(state, facePass ? double(asset->faceCount()) : double(asset->vertexCount()));
}
BENCHMARK(BM_CollideCpu)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// One step of the rigid rain with 5 bodies (two-way coupling), from 0.6 s: 0 on the CPU, 1 on the GPU.
void BM_RainStep(benchmark::State& state) {
  drape::scenes::RainConfig config;
  config.bodies = 5;
  auto measure = [&](auto& scene) {
    for (int s = 0; s < 60; ++s) scene.step();
    for (auto _ : state) scene.step();
  };
  if (state.range(0) == 0) {
    drape::scenes::RigidRain<float> scene(config);
    measure(scene);
    state.SetLabel("cpu");
  } else {
    std::string why;
    gpu::Context* ctx = context(why);
    if (!ctx) return state.SkipWithError(why.c_str());
    drape::scenes::RigidRain<float, gpu::Solver> scene(config, *ctx);
    measure(scene);  // each step waits: the bodies' forces are read back every substep
    state.SetLabel(ctx->renderer());
  }
}
BENCHMARK(BM_RainStep)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(20);

}  // namespace

BENCHMARK_MAIN();
