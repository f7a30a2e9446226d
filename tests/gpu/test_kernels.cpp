// The compute kernels against their CPU twins (docs/design.md §9), each on the same inputs, and the GPU solver
// against the CPU solver over 1 to 10 substeps and over seconds.
//
// Tolerances. Every kernel keeps its arithmetic `precise` and in the CPU kernel's order, so on llvmpipe the two
// round alike; a GPU may still differ in the last bit of a division or square root (GLSL allows 2.5 ulp for a
// division and treats sqrt as 1 / inversesqrt). So a kernel run once is held to 4 ulp of the largest
// magnitude involved, and a solver run over a step to 1e-5 m, 40 ulp at the cloth's 0.5 m: a wrong index, a
// missed colour or a dropped term moves vertices by millimetres.
#include "gpu_helpers.hpp"

#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <cstring>
#include <random>
#include <vector>

namespace {

using drape::Index;
using drape::Vec3;
using drape::Vec4;
using drape::gpu::layout::Vertex;
namespace layout = drape::gpu::layout;

constexpr double kUlp = 1.1920928955078125e-07;  // float epsilon

std::vector<Vertex> toVertices(const std::vector<Vec3<float>>& x, const std::vector<float>& w) {
  std::vector<Vertex> out(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) out[i] = {x[i].x(), x[i].y(), x[i].z(), w.empty() ? 0.0f : w[i]};
  return out;
}
std::vector<Vec3<float>> xyz(const std::vector<Vertex>& v) {
  std::vector<Vec3<float>> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = {v[i].x, v[i].y, v[i].z};
  return out;
}
std::vector<Vec3<float>> xyz(const std::vector<Vec4<float>>& v) {
  std::vector<Vec3<float>> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = v[i].head<3>();
  return out;
}

/// Random vertices: positions in a 4 m cube, velocities up to 3 m/s, inverse masses in [0.5, 50] with every
/// fifth vertex fixed (0).
struct RandomVertices {
  std::vector<Vec3<float>> x, v;
  std::vector<float> w;
  explicit RandomVertices(Index n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> pos(-2.0f, 2.0f), vel(-3.0f, 3.0f), mass(0.5f, 50.0f);
    for (Index i = 0; i < n; ++i) {
      x.emplace_back(pos(rng), pos(rng), pos(rng));
      v.emplace_back(vel(rng), vel(rng), vel(rng));
      w.push_back(i % 5 == 2 ? 0.0f : mass(rng));
    }
  }
};

/// A jittered 23 x 17 grid cloth stretched by 5 % (odd sizes: colours of uneven length, partial workgroups).
std::shared_ptr<const drape::ClothAsset<float>> jitteredGrid() {
  drape::SheetDesc g;
  g.nx = 23;
  g.ny = 17;
  g.spacing = 0.02;
  return std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(g));
}

}  // namespace

TEST_CASE("every kernel compiles and links on the context", "[gpu]") {
  drape::test::gpuContext().makeCurrent();
  REQUIRE(std::size(drape::gpu::shaders::kAll) >= 3);
  for (const auto& k : drape::gpu::shaders::kAll) {
    INFO(k.name);
    CHECK_NOTHROW(drape::gpu::Program(k.name, k.source));
  }
}

TEST_CASE("a kernel that does not compile is reported with its name and the compiler's log", "[gpu]") {
  drape::test::gpuContext().makeCurrent();
  try {
    drape::gpu::Program("broken", "layout(local_size_x = 1) in; void main() { undeclared = 1; }");
    FAIL("no error");
  } catch (const drape::Error& e) {
    const std::string what = e.what();
    CHECK(what.find("'broken'") != std::string::npos);
    CHECK(what.find("undeclared") != std::string::npos);
  }
}

TEST_CASE("an unknown backend name is rejected with the names that exist", "[gpu]") {
  CHECK_THROWS_WITH(drape::gpu::backendFromString("vulkan"), Catch::Contains("'vulkan'") && Catch::Contains("osmesa"));
  CHECK(drape::gpu::backendFromString("egl") == drape::gpu::Backend::Egl);
}

TEST_CASE("predict: the GPU kernel against predictPositions, without and with air damping", "[gpu]") {
  drape::test::gpuContext().makeCurrent();
  const Index n = 1000;  // not a multiple of the workgroup
  const RandomVertices r(n, 7);
  const float h = 1.0f / 600.0f;
  const Vec3<float> gh = Vec3<float>(0.3f, -0.2f, -9.81f) * h;
  const bool damped = GENERATE(false, true);
  drape::Settings air;
  air.airDamping = 2;
  const float keep = damped ? float(air.velocityKept(double(h))) : 1.0f;  // as the solvers set it
  INFO("keep " << keep);

  std::vector<Vec3<float>> v = r.v, xp(n);
  std::vector<Vec4<float>> xw(n);
  if (damped)
    drape::predictPositions<false, true, float>(0, n, r.x.data(), v.data(), r.w.data(), gh, h, nullptr, xp.data(),
                                                xw.data(), keep);
  else
    drape::predictPositions<false, false, float>(0, n, r.x.data(), v.data(), r.w.data(), gh, h, nullptr, xp.data(),
                                                 xw.data());
  // Damping changes every free velocity by more than the tolerance below, so the comparison sees it.
  if (damped) CHECK(drape::test::largestDifference(v, r.v) > 1e-4);

  drape::gpu::Buffer<Vertex> gx(toVertices(r.x, r.w)), gv(toVertices(r.v, {})), gp{std::vector<Vertex>(std::size_t(n))},
      gw{std::vector<Vertex>(std::size_t(n))};
  gx.bind(layout::kPositions);
  gv.bind(layout::kVelocities);
  gp.bind(layout::kPredicted);
  gw.bind(layout::kPacked);
  drape::gpu::Program predict("predict", drape::gpu::shaders::predict);
  predict.set(layout::kCount, unsigned(n));
  predict.set(layout::kStep, h);
  predict.set(layout::kGravityStep, gh.x(), gh.y(), gh.z());
  predict.set(layout::kKeepVelocity, keep);
  predict.dispatch(std::size_t(n));

  const auto packed = gw.read();
  CHECK(drape::test::largestDifference(xyz(gv.read()), v) <= 4 * kUlp * 3.1);
  CHECK(drape::test::largestDifference(xyz(gp.read()), xp) <= 4 * kUlp * 2.1);
  CHECK(drape::test::largestDifference(xyz(packed), xyz(xw)) <= 4 * kUlp * 2.1);
  for (Index i = 0; i < n; ++i) {
    INFO("vertex " << i);
    REQUIRE(packed[std::size_t(i)].w == r.w[std::size_t(i)]);  // the inverse mass rides along for the solve
  }
  // A fixed vertex does not move, and its velocity is set to zero (the update then gives it its pin's move).
  REQUIRE(r.w[2] == 0.0f);
  CHECK(r.v[2].norm() > 0);
  CHECK(v[2] == Vec3<float>::Zero());
  CHECK(gv.read()[2].z == 0.0f);
  CHECK(gp.read()[2].x == r.x[2].x());
}

TEST_CASE("update velocity: the GPU kernel against updateVelocities", "[gpu]") {
  drape::test::gpuContext().makeCurrent();
  const Index n = 777;
  const RandomVertices start(n, 9), solved(n, 10);
  const float invH = 600.0f;
  // The predictions, and solved positions a few millimetres from them.
  std::vector<Vec3<float>> xp = start.x, x(n), v = start.v;
  std::vector<Vec4<float>> xw(n);
  for (Index i = 0; i < n; ++i) {
    const Vec3<float> p = start.x[std::size_t(i)] + 0.001f * solved.v[std::size_t(i)];
    xw[std::size_t(i)] = Vec4<float>(p.x(), p.y(), p.z(), start.w[std::size_t(i)]);
  }
  std::vector<Vertex> packed(n);
  for (Index i = 0; i < n; ++i) packed[std::size_t(i)] = {xw[std::size_t(i)].x(), xw[std::size_t(i)].y(), xw[std::size_t(i)].z(), xw[std::size_t(i)].w()};
  drape::updateVelocities<false, false>(0, n, xw.data(), xp.data(), x.data(), v.data(), invH);

  drape::gpu::Buffer<Vertex> gx(toVertices(start.x, start.w)), gv(toVertices(start.v, {})), gp(toVertices(xp, {})),
      gw(packed);
  gx.bind(layout::kPositions);
  gv.bind(layout::kVelocities);
  gp.bind(layout::kPredicted);
  gw.bind(layout::kPacked);
  drape::gpu::Program update("update_velocity", drape::gpu::shaders::update_velocity);
  update.set(layout::kCount, unsigned(n));
  update.set(layout::kInverseStep, invH);
  update.dispatch(std::size_t(n));

  const auto positions = gx.read();
  CHECK(drape::test::largestDifference(xyz(positions), x) == 0);  // a copy
  // v + (p - xp) / h: the difference is exact (Sterbenz), the product one rounding, the sum another.
  CHECK(drape::test::largestDifference(xyz(gv.read()), v) <= 4 * kUlp * 10);
  for (Index i = 0; i < n; ++i) {
    INFO("vertex " << i);
    REQUIRE(positions[std::size_t(i)].w == start.w[std::size_t(i)]);  // the inverse mass is kept
  }
}

TEST_CASE("solve: the GPU kernel, one dispatch per colour, against solveDistanceSet", "[gpu]") {
  drape::test::gpuContext().makeCurrent();
  const auto asset = jitteredGrid();
  const Index n = asset->vertexCount();
  // Deformed positions (stretched 5 %, jittered 4 mm), inverse masses with every seventh vertex fixed.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> jitter(-0.004f, 0.004f), mass(0.5f, 20.0f);
  std::vector<Vec4<float>> xw(n);
  std::vector<float> w(n);
  for (Index i = 0; i < n; ++i) {
    const Vec3<float> p = 1.05f * asset->restPositions[std::size_t(i)] + Vec3<float>(jitter(rng), jitter(rng), jitter(rng));
    xw[std::size_t(i)] = Vec4<float>(p.x(), p.y(), p.z(), 0.0f);
    w[std::size_t(i)] = i % 7 == 3 ? 0.0f : mass(rng);
  }
  const bool withLambda = GENERATE(false, true);
  const float alphaTilde = withLambda ? 0.04f : 0.0f;  // compliance 1e-8 m/N at h = 1/2000 s when with multipliers
  const int passes = withLambda ? 3 : 1;
  INFO((withLambda ? "three passes with multipliers" : "one pass, rigid"));

  // The CPU: each set in turn, as the solver orders them, through the scalar kernel (the SIMD ones give its bits).
  std::vector<Vec4<float>> cpu = xw;
  const drape::DistanceSet<float>* sets[3] = {&asset->stretch, &asset->shear, &asset->bending};
  std::vector<std::vector<float>> lambdas(3);
  const drape::DistanceBlocks<float> blocks[3] = {drape::DistanceBlocks<float>(*sets[0]),
                                                  drape::DistanceBlocks<float>(*sets[1]),
                                                  drape::DistanceBlocks<float>(*sets[2])};
  for (int s = 0; s < 3; ++s) lambdas[std::size_t(s)].assign(std::size_t(sets[s]->size()), 0.0f);
  for (int p = 0; p < passes; ++p)
    for (int s = 0; s < 3; ++s) {
      if (withLambda)
        drape::solveDistanceSet<true, float>(*sets[s], blocks[s], alphaTilde, lambdas[std::size_t(s)].data(),
                                             cpu.data(), w.data(), drape::SimdLevel::Scalar);
      else
        drape::solveDistanceSet<false, float>(*sets[s], blocks[s], alphaTilde, nullptr, cpu.data(), w.data(),
                                              drape::SimdLevel::Scalar);
    }

  // The GPU: all three sets in one buffer, a dispatch per colour.
  std::vector<layout::Constraint> constraints;
  std::size_t start[3];
  for (int s = 0; s < 3; ++s) {
    start[s] = constraints.size();
    for (Index k = 0; k < sets[s]->size(); ++k)
      constraints.push_back({std::uint32_t(sets[s]->pairs[std::size_t(k)][0]), std::uint32_t(sets[s]->pairs[std::size_t(k)][1]),
                             sets[s]->restLength[std::size_t(k)], 0u});
  }
  std::vector<Vertex> packed(n);
  for (Index i = 0; i < n; ++i) packed[std::size_t(i)] = {xw[std::size_t(i)].x(), xw[std::size_t(i)].y(), xw[std::size_t(i)].z(), w[std::size_t(i)]};
  drape::gpu::Buffer<Vertex> gw(packed);
  drape::gpu::Buffer<layout::Constraint> gc(constraints);
  drape::gpu::Buffer<float> gl(std::vector<float>(constraints.size(), 0.0f));
  gw.bind(layout::kPacked);
  gc.bind(layout::kConstraints);
  gl.bind(layout::kLambdas);
  drape::gpu::Program solve("solve_distance", drape::gpu::shaders::solve_distance);
  solve.set(layout::kAlphaTilde, alphaTilde);
  solve.set(layout::kUseLambda, unsigned(withLambda));
  for (int p = 0; p < passes; ++p)
    for (int s = 0; s < 3; ++s)
      for (Index c = 0; c < sets[s]->colourCount(); ++c) {
        const Index first = sets[s]->colourOffsets[std::size_t(c)], count = sets[s]->colourOffsets[std::size_t(c) + 1] - first;
        solve.set(layout::kFirst, unsigned(start[s] + std::size_t(first)));
        solve.set(layout::kCount, unsigned(count));
        solve.dispatch(std::size_t(count));
      }

  const auto gpu = gw.read();
  const double moved = drape::test::largestDifference(xyz(cpu), xyz(xw));
  REQUIRE(moved > 1e-3);  // the solve did move the vertices by millimetres: the comparison below means something
  CHECK(drape::test::largestDifference(xyz(gpu), xyz(cpu)) <= 4 * kUlp * 0.3);  // the cloth spans 0.46 x 0.34 m
  if (withLambda) {
    // The multipliers too (the CPU's scalar kernel keeps one per constraint, in the same order).
    const auto gpuLambda = gl.read();
    double worst = 0, largest = 0;
    for (int s = 0; s < 3; ++s)
      for (Index k = 0; k < sets[s]->size(); ++k) {
        const double l = lambdas[std::size_t(s)][std::size_t(k)];
        worst = std::max(worst, std::abs(double(gpuLambda[start[s] + std::size_t(k)]) - l));
        largest = std::max(largest, std::abs(l));
      }
    REQUIRE(largest > 0);
    CHECK(worst <= 16 * kUlp * largest);
  }
}
