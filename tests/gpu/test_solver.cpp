// The GPU solver against the CPU solver: the same hanging cloth, stepped on both, compared vertex by
// vertex over 1 to 10 substeps and on its invariants over seconds; and two GPU runs, bit for bit.
#include "gpu_helpers.hpp"
#include "slope.hpp"
#include "sphere_drape.hpp"

#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <memory>
#include <tuple>
#include <vector>

namespace {

using drape::Index;

/// A 30 x 20 cloth, 2 cm spacing, hanging in the vertical xz plane from its two top corners, pulled sideways by
/// a slanted gravity so it swings (not just sags).
struct Hanging {
  std::shared_ptr<const drape::ClothAsset<float>> asset;
  drape::Settings settings;
  std::vector<Index> pinned;

  explicit Hanging(int iterations = 1, double stretchCompliance = 0) {
    drape::SheetDesc g;
    g.nx = 30;
    g.ny = 20;
    g.spacing = 0.02;
    g.placement.position = {0, 0, 1};
    g.placement.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(EIGEN_PI / 2, Eigen::Vector3d::UnitX()));  // the grid's y is up
    asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(g));
    settings.iterationCount = iterations;
    settings.stretchCompliance = stretchCompliance;
    settings.gravity = {2.0, 0, -9.81};
    Index top = 0;  // the two corners of the highest row
    for (Index i = 0; i < asset->vertexCount(); ++i)
      if (asset->restPositions[std::size_t(i)].z() > asset->restPositions[std::size_t(top)].z() + 1e-4f) top = i;
    const float zTop = asset->restPositions[std::size_t(top)].z();
    Index lo = -1, hi = -1;
    for (Index i = 0; i < asset->vertexCount(); ++i) {
      const auto& p = asset->restPositions[std::size_t(i)];
      if (std::abs(p.z() - zTop) > 1e-4f) continue;
      if (lo < 0 || p.x() < asset->restPositions[std::size_t(lo)].x()) lo = i;
      if (hi < 0 || p.x() > asset->restPositions[std::size_t(hi)].x()) hi = i;
    }
    pinned = {lo, hi};
  }
  template <class Solver> void pin(Solver& s) const {
    for (Index i : pinned) s.pin(i);
  }
};

double largestGap(const drape::Solver<float>& cpu, const drape::gpu::Solver& gpu) {
  double worst = 0;
  for (Index i = 0; i < cpu.vertexCount(); ++i) worst = std::max(worst, (cpu.position(i) - gpu.position(i)).norm());
  return worst;
}

}  // namespace

TEST_CASE("the GPU solver follows the CPU solver over 1 to 10 substeps", "[gpu]") {
  auto& context = drape::test::gpuContext();
  const int iterations = GENERATE(1, 4);
  const double compliance = iterations == 1 ? 0.0 : 1e-7;  // four passes on a compliant set: the multipliers
  INFO(iterations << " iterations, stretch compliance " << compliance);
  const Hanging scene(iterations, compliance);
  for (int substeps : {1, 5, 10}) {
    INFO(substeps << " substeps of 1/600 s");
    drape::Settings s = scene.settings;
    s.subStepCount = substeps;
    drape::Solver<float> cpu(scene.asset, s);
    drape::gpu::Solver gpu(context, scene.asset, s);
    scene.pin(cpu);
    scene.pin(gpu);
    const double dt = substeps / 600.0;
    cpu.step(dt);
    gpu.step(dt);
    // The cloth has moved (gravity alone: 1/2 g t^2, 0.14 mm after 1/60 s), and the two agree far below that.
    double moved = 0;
    for (Index i = 0; i < cpu.vertexCount(); ++i)
      moved = std::max(moved, (cpu.position(i) - scene.asset->restPositions[std::size_t(i)].cast<double>() -
                               scene.asset->origin).norm());
    REQUIRE(moved > 1e-6);
    CHECK(largestGap(cpu, gpu) <= 1e-5);
    double speedGap = 0;
    for (Index i = 0; i < cpu.vertexCount(); ++i) speedGap = std::max(speedGap, (cpu.velocity(i) - gpu.velocity(i)).norm());
    CHECK(speedGap <= 1e-5 * 600);  // a position's 1e-5 m over one substep
    for (Index i : scene.pinned) CHECK(gpu.position(i) == cpu.position(i));
  }
}

TEST_CASE("with air damping the GPU solver's falling cloth slows as v0 exp(-c t) + g (1 - exp(-c t)) / c", "[gpu]") {
  // The hanging scene's cloth let go (no pins), thrown sideways at 3 m/s, air damping 2/s, 10 substeps a frame:
  // the constraints move no mass centre, so the mean velocity follows the damped fall on either solver, within
  // c h of the terminal speed (the substep's lag, about c h / 2), and the two solvers agree far closer. Without
  // damping the mean is 5 m/s faster after 1 s.
  auto& context = drape::test::gpuContext();
  const Hanging scene;
  drape::Settings s = scene.settings;
  s.airDamping = 2;
  s.subStepCount = 10;
  drape::Solver<float> cpu(scene.asset, s);
  drape::gpu::Solver gpu(context, scene.asset, s);
  const Eigen::Vector3d v0(0, 3, 0);
  const std::vector<Eigen::Vector3d> start(std::size_t(cpu.vertexCount()), v0);
  cpu.setVelocities(start);
  gpu.setVelocities(start);
  const double dt = 1.0 / 60, h = dt / s.subStepCount, c = s.airDamping;
  const Eigen::Vector3d g = s.gravity;
  auto mean = [](const auto& solver) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (Index i = 0; i < solver.vertexCount(); ++i) sum += solver.velocity(i);
    return Eigen::Vector3d(sum / double(solver.vertexCount()));
  };
  for (int f = 1; f <= 60; ++f) {
    cpu.step(dt);
    gpu.step(dt);
    const double t = f * dt, decay = std::exp(-c * t);
    const Eigen::Vector3d expected = v0 * decay + g * (1 - decay) / c;
    const Eigen::Vector3d onGpu = mean(gpu), onCpu = mean(cpu);
    INFO("t = " << t << " s: mean velocity on the GPU " << onGpu.transpose() << ", on the CPU " << onCpu.transpose()
                << ", expected " << expected.transpose());
    REQUIRE((onGpu - expected).norm() <= c * h * (v0.norm() + g.norm() / c));
    REQUIRE((onGpu - onCpu).norm() <= 1e-4);
  }
}

TEST_CASE("over two seconds the GPU and CPU solvers' swinging cloth agree on its invariants", "[gpu]") {
  const Hanging scene;
  drape::Solver<float> cpu(scene.asset, scene.settings);
  drape::gpu::Solver gpu(drape::test::gpuContext(), scene.asset, scene.settings);
  scene.pin(cpu);
  scene.pin(gpu);
  // Invariants of a hanging cloth: the height of its centre of mass (it swings, so it moves by centimetres),
  // and its longest edge's stretch (inextensible edges with one pass: a few per cent).
  auto centreHeight = [](const auto& s) {
    double z = 0;
    for (Index i = 0; i < s.vertexCount(); ++i) z += s.position(i).z();
    return z / double(s.vertexCount());
  };
  auto stretch = [&](const auto& s) {
    double worst = 0;
    for (Index k = 0; k < scene.asset->stretch.size(); ++k) {
      const auto& p = scene.asset->stretch.pairs[std::size_t(k)];
      worst = std::max(worst, (s.position(p[0]) - s.position(p[1])).norm() / double(scene.asset->stretch.restLength[std::size_t(k)]) - 1);
    }
    return worst;
  };
  double heightGap = 0, stretchGap = 0, lowest = 1e9, highest = -1e9;
  for (int step = 0; step < 120; ++step) {
    cpu.step(1.0 / 60);
    gpu.step(1.0 / 60);
    const double zc = centreHeight(cpu), zg = centreHeight(gpu);
    heightGap = std::max(heightGap, std::abs(zc - zg));
    stretchGap = std::max(stretchGap, std::abs(stretch(cpu) - stretch(gpu)));
    lowest = std::min(lowest, zc);
    highest = std::max(highest, zc);
    REQUIRE(std::isfinite(zg));
  }
  INFO("centre height gap " << heightGap << " m, stretch gap " << stretchGap << ", centre swung over "
                            << highest - lowest << " m");
  REQUIRE(highest - lowest > 0.01);  // the cloth did swing (1.7 cm)
  CHECK(heightGap <= 1e-4);
  CHECK(stretchGap <= 1e-3);
}

TEST_CASE("two GPU runs of the same scene are bit-identical", "[gpu]") {
  const Hanging scene(4, 1e-7);
  auto run = [&] {
    drape::gpu::Solver gpu(drape::test::gpuContext(), scene.asset, scene.settings);
    scene.pin(gpu);
    for (int step = 0; step < 30; ++step) gpu.step(1.0 / 60);
    const auto& s = gpu.state();
    return std::make_pair(s.x, s.v);
  };
  const auto a = run(), b = run();
  REQUIRE(a.first.size() == b.first.size());
  CHECK(std::memcmp(a.first.data(), b.first.data(), a.first.size() * sizeof(a.first[0])) == 0);
  CHECK(std::memcmp(a.second.data(), b.second.data(), a.second.size() * sizeof(a.second[0])) == 0);
}

TEST_CASE("the GPU solver rejects bad input before changing anything", "[gpu]") {
  const Hanging scene;
  drape::gpu::Solver gpu(drape::test::gpuContext(), scene.asset, scene.settings);
  const Eigen::Vector3d before = gpu.position(7);
  CHECK_THROWS_WITH(gpu.step(-1), Catch::Contains("dt"));
  CHECK_THROWS_WITH(gpu.setInverseMass(gpu.vertexCount(), 1), Catch::Contains("out of range"));
  CHECK_THROWS_WITH(gpu.setInverseMass(3, -1), Catch::Contains("inverse mass of vertex 3"));
  std::vector<Eigen::Vector3d> v(std::size_t(gpu.vertexCount()), Eigen::Vector3d::Zero());
  v[5].x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(gpu.setVelocities(v), Catch::Contains("vertex 5"));
  CHECK(gpu.velocity(4) == Eigen::Vector3d::Zero());
  drape::Settings bad = scene.settings;
  bad.iterationCount = 0;
  CHECK_THROWS_WITH(gpu.setSettings(bad), Catch::Contains("iterationCount"));
  CHECK(gpu.settings().iterationCount == 1);
  CHECK(gpu.position(7) == before);
}

TEST_CASE("EGL and OSMesa contexts give the same bits", "[gpu]") {
  // Both are Mesa's llvmpipe on a machine without a GPU; with a GPU, EGL takes it and the two may round apart.
  std::unique_ptr<drape::gpu::Context> egl, os;
  try {
    egl = std::make_unique<drape::gpu::Context>(drape::gpu::Backend::Egl);
    os = std::make_unique<drape::gpu::Context>(drape::gpu::Backend::OSMesa);
  } catch (const drape::Error& e) {
    WARN("not compared, one of the two cannot be made here: " << e.what());
    return;
  }
  if (!egl->software()) {
    WARN("not compared: EGL gives a hardware device (" << egl->renderer() << ")");
    return;
  }
  const Hanging scene(4, 1e-7);
  auto run = [&](drape::gpu::Context& context) {
    drape::gpu::Solver gpu(context, scene.asset, scene.settings);
    scene.pin(gpu);
    for (int step = 0; step < 10; ++step) gpu.step(1.0 / 60);
    return gpu.state().x;
  };
  const auto a = run(*egl), b = run(*os);
  CHECK(std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
  // Releasing a context unbinds it; then the shared one is made current again, for the tests after this one.
  egl.reset();
  os.reset();
  drape::test::gpuContext().makeCurrent();
}

// --- against a plane: the inclined-plane scene of the SDF collision paper (scenes/slope.hpp) --------------------

namespace {

drape::gpu::Solver makeGpuSlope(const drape::scenes::SlopeConfig& c) {
  const auto parts = drape::scenes::slopeParts<float>(c);
  drape::gpu::Solver gpu(drape::test::gpuContext(), parts.asset, parts.settings, c.areaDensity);
  gpu.addSolid(parts.slope);
  return gpu;
}

}  // namespace

TEST_CASE("on the slope the GPU solver follows the CPU solver over 1 to 10 substeps", "[gpu]") {
  drape::scenes::SlopeConfig c;
  c.nx = 24;
  c.ny = 30;
  c.gap = 0.001;  // the uphill rows start inside the thickness: contacts from the first substep
  c.friction = GENERATE(0.0, 0.3, 1.0);  // sliding, slowed, stuck (tan 30 deg = 0.58)
  c.method = GENERATE(drape::CollisionMethod::Faces, drape::CollisionMethod::Vertices,
                      drape::CollisionMethod::InSolve);
  INFO("friction " << c.friction << ", " << drape::toString(c.method));
  for (int substeps : {1, 3, 10}) {
    INFO(substeps << " substeps");
    c.subSteps = substeps;
    drape::Solver<float> cpu = drape::scenes::makeSlope<float>(c);
    drape::gpu::Solver gpu = makeGpuSlope(c);
    // Two steps, with contacts (the faces and vertices methods' in every substep of both; the in-solve method's in the first: it
    // turns the uphill rows' push out of the thickness into velocity, and they leave the slope for a while).
    std::size_t touching = 0;
    for (int step = 0; step < 2; ++step) {
      cpu.step(c.dt, [&](const drape::Solver<float>& s) {
        touching = std::max(touching, s.contacts().liveVertices().size());
      });
      gpu.step(c.dt);
    }
    REQUIRE(touching >= 10);  // part of the uphill row touches
    CHECK(largestGap(cpu, gpu) <= 1e-5);
    double speedGap = 0;
    for (Index i = 0; i < cpu.vertexCount(); ++i)
      speedGap = std::max(speedGap, (cpu.velocity(i) - gpu.velocity(i)).norm());
    CHECK(speedGap <= 1e-5 / (c.dt / substeps));
  }
}

TEST_CASE("sliding down the slope, the GPU solver's cloth has the CPU's trembling, acceleration and penetration",
          "[gpu]") {
  drape::scenes::SlopeConfig c;  // the sample's scene: 50 x 80, 30 degrees, 10 substeps
  c.frames = 150;                // 2.5 s: it lands at about 0.3 s and slides for the rest
  c.friction = GENERATE(0.0, 0.3);
  INFO("friction " << c.friction);
  drape::Solver<float> cpu = drape::scenes::makeSlope<float>(c);
  drape::gpu::Solver gpu = makeGpuSlope(c);
  const auto a = drape::scenes::runSlopeOn(cpu, c), b = drape::scenes::runSlopeOn(gpu, c);
  INFO("CPU: acceleration " << a.acceleration << " m/s^2 (analytic " << a.analyticAcceleration << "), trembling rms "
                            << a.tremblingRms << " m/s, penetration " << a.maxPenetration << " m");
  INFO("GPU: acceleration " << b.acceleration << " m/s^2, trembling rms " << b.tremblingRms << " m/s, penetration "
                            << b.maxPenetration << " m");
  REQUIRE(b.finite);
  REQUIRE(a.acceleration > 0.5 * a.analyticAcceleration);  // it does slide
  CHECK(std::abs(b.acceleration - a.acceleration) <= 0.01 * a.analyticAcceleration);
  CHECK(b.tremblingRms <= 1.1 * a.tremblingRms + 1e-4);
  CHECK(b.maxPenetration <= a.maxPenetration + 1e-4);
  CHECK(b.maxStrain <= a.maxStrain + 1e-3);
}

TEST_CASE("the GPU solver rejects bad settings and solids before changing anything", "[gpu]") {
  const auto parts = drape::scenes::slopeParts<float>(drape::scenes::SlopeConfig{});
  drape::Settings badSettings = parts.settings;
  badSettings.iterationCount = 0;
  CHECK_THROWS_WITH(drape::gpu::Solver(drape::test::gpuContext(), parts.asset, badSettings),
                    Catch::Contains("iterationCount"));
  drape::gpu::Solver gpu(drape::test::gpuContext(), parts.asset, parts.settings);
  gpu.addSolid(parts.slope);
  drape::Solid<drape::Sphere> badBall;
  badBall.shape.radius = -1;
  CHECK_THROWS_WITH(gpu.addSolid(badBall), Catch::Contains("radius"));
  CHECK_THROWS_WITH(gpu.solid<drape::Sphere>(0), Catch::Contains("out of range"));  // nothing was added
  CHECK_THROWS_WITH(gpu.setSettings(badSettings), Catch::Contains("iterationCount"));
  CHECK(gpu.settings().iterationCount == parts.settings.iterationCount);
  // Valid settings the GPU does not run are refused, by name, rather than ignored.
  drape::Settings noCulling = parts.settings, noBroadPhase = parts.settings, threads = parts.settings;
  noCulling.culling = false;
  noBroadPhase.broadPhase = false;
  threads.threadCount = 2;
  CHECK_THROWS_WITH(gpu.setSettings(noCulling), Catch::Contains("culling"));
  CHECK_THROWS_WITH(gpu.setSettings(noBroadPhase), Catch::Contains("broadPhase"));
  CHECK_THROWS_WITH(gpu.setSettings(threads), Catch::Contains("threadCount"));
  drape::Settings descent = parts.settings;
  descent.exactGridSearch = false;
  CHECK_THROWS_WITH(gpu.setSettings(descent), Catch::Contains("exactGridSearch"));
  drape::Settings keep = parts.settings;
  keep.keepAngularMomentum = true;
  CHECK_THROWS_WITH(gpu.setSettings(keep), Catch::Contains("keepAngularMomentum"));
  CHECK_FALSE(gpu.settings().keepAngularMomentum);
  drape::Settings tethered = parts.settings;
  tethered.tethers = true;
  CHECK_THROWS_WITH(gpu.setSettings(tethered), Catch::Contains("tethers"));
  CHECK_FALSE(gpu.settings().tethers);
  CHECK_THROWS_WITH(drape::gpu::Solver(drape::test::gpuContext(), parts.asset, noCulling),
                    Catch::Contains("culling"));
  CHECK(gpu.settings().culling);
  CHECK(gpu.settings().broadPhase);
  CHECK(gpu.settings().threadCount == 1);
}

TEST_CASE("repulsion: a plane rising toward a cloth slows it alike on the GPU and the CPU", "[gpu]") {
  // A horizontal cloth falls toward a floor that rises at 1 m/s into it, with a 5 cm repulsion region: the region
  // blends the vertices' velocities toward the floor's before contact (docs/design.md §5).
  const drape::Falloff falloff = GENERATE(drape::Falloff::Linear, drape::Falloff::Smooth);
  drape::SheetDesc grid;
  grid.nx = 25;
  grid.ny = 20;
  grid.spacing = 0.02;
  grid.placement.position = {0, 0, 0.1};
  auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(grid));
  drape::Solid<drape::Plane> floor;
  floor.motion = drape::Motion::Kinematic;
  floor.linearVelocity = {0, 0, 1};
  floor.pose.position = {0, 0, 0.02};
  floor.repulsion.radius = 0.05;
  floor.repulsion.falloff = falloff;
  drape::Solver<float> cpu(asset);
  drape::gpu::Solver gpu(drape::test::gpuContext(), asset);
  cpu.addSolid(floor);
  gpu.addSolid(floor);
  drape::Solver<float> bare(asset);  // the same without the region, to see that it acts
  floor.repulsion.radius = 0;
  bare.addSolid(floor);
  for (int step = 0; step < 3; ++step) {  // 3 frames of 1/60 s: the floor closes 5 cm, into the region
    cpu.step(1.0 / 60);
    gpu.step(1.0 / 60);
    bare.step(1.0 / 60);
  }
  double blended = 0, gap = 0;
  for (Index i = 0; i < cpu.vertexCount(); ++i) {
    blended = std::max(blended, (cpu.velocity(i) - bare.velocity(i)).norm());
    gap = std::max(gap, (cpu.velocity(i) - gpu.velocity(i)).norm());
  }
  INFO("largest velocity change by the region " << blended << " m/s, GPU against CPU " << gap << " m/s");
  REQUIRE(blended > 0.1);  // the region did slow the cloth toward the floor's velocity
  CHECK(gap <= 1e-5 * 600);
  CHECK(largestGap(cpu, gpu) <= 1e-5);
}

TEST_CASE("pins with moving targets: the GPU solver follows the CPU solver", "[gpu]") {
  // Two corners fixed (inverse mass 0) on targets that move in a circle, and a third vertex of the top row
  // attached by a compliant pin, four iterations (the pins' multipliers accumulate).
  const Hanging scene(4, 0);
  drape::Settings s = scene.settings;
  s.pinCompliance = 1e-4;
  drape::Solver<float> cpu(scene.asset, s);
  drape::gpu::Solver gpu(drape::test::gpuContext(), scene.asset, s);
  const Index middle = (scene.pinned[0] + scene.pinned[1]) / 2;
  std::vector<Eigen::Vector3d> start;
  for (Index i : scene.pinned) {
    start.push_back(cpu.position(i));
    cpu.pin(i);
    gpu.pin(i);
    cpu.attach(i, cpu.position(i));
    gpu.attach(i, gpu.position(i));
  }
  cpu.attach(middle, cpu.position(middle) + Eigen::Vector3d(0, 0.05, 0));
  gpu.attach(middle, gpu.position(middle) + Eigen::Vector3d(0, 0.05, 0));
  double moved = 0, cornerSpeedGap = 0;
  for (int step = 0; step < 30; ++step) {
    const double a = 0.2 * step;
    for (Index k = 0; k < 2; ++k) {
      const Eigen::Vector3d target = start[std::size_t(k)] + 0.1 * Eigen::Vector3d(std::cos(a) - 1, std::sin(a), 0);
      cpu.setPinTarget(k, target);
      gpu.setPinTarget(k, target);
    }
    cpu.step(1.0 / 60);
    gpu.step(1.0 / 60);
    moved = std::max(moved, (cpu.position(scene.pinned[0]) - start[0]).norm());
    // A fixed corner moves only in a step's first substep, where its target jumps: at the step's end it is still.
    for (Index i : scene.pinned) {
      CHECK(cpu.velocity(i).norm() == 0);
      cornerSpeedGap = std::max(cornerSpeedGap, (cpu.velocity(i) - gpu.velocity(i)).norm());
    }
  }
  REQUIRE(moved > 0.05);  // the corners followed their targets
  CHECK(cornerSpeedGap == 0);
  CHECK((cpu.position(scene.pinned[0]) - cpu.pins()[0].target).norm() < 1e-6);
  CHECK(largestGap(cpu, gpu) <= 1e-5);
  CHECK_THROWS_WITH(gpu.setPinTarget(3, Eigen::Vector3d::Zero()), Catch::Contains("pin index 3"));
  CHECK_THROWS_WITH(gpu.attach(0, Eigen::Vector3d(std::nan(""), 0, 0)), Catch::Contains("not finite"));
  CHECK(gpu.pins().size() == 3);
}

TEST_CASE("continuous contact on the GPU: thin rods stop the cloth as on the CPU", "[gpu]") {
  // The CPU's [continuous] scenes, on the GPU solver. Without continuous contact the cloth passes both rods.
  drape::Solid<drape::Capsule> rod;
  rod.shape.radius = 0.003;
  rod.pose.rotation = Eigen::AngleAxisd(0.5 * EIGEN_PI, Eigen::Vector3d::UnitX());  // along y
  rod.staticFriction = rod.dynamicFriction = 0.5;
  auto run = [&](int n, double z, int substeps, int frames, bool continuous, double shift = 0) {
    drape::SheetDesc g;
    g.nx = g.ny = n;
    g.spacing = 0.02;
    g.placement.position = {shift, 0, z};
    const auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(g));
    drape::Settings settings;
    settings.subStepCount = substeps;
    settings.continuousContact = continuous;
    drape::gpu::Solver gpu(drape::test::gpuContext(), asset, settings);
    gpu.addSolid(rod);
    double lowestMean = 1e9, depth = 0, mean = 0;
    for (int f = 0; f < frames; ++f) {
      gpu.step(1.0 / 60.0);
      mean = 0;
      for (Index i = 0; i < gpu.vertexCount(); ++i) mean += gpu.position(i).z() / double(gpu.vertexCount());
      lowestMean = std::min(lowestMean, mean);
      depth = std::max(depth, drape::penetration(gpu).depth);
    }
    return std::tuple{lowestMean, depth, mean};
  };
  SECTION("dropped from 10 cm on a 3 mm rod at 2 substeps") {
    rod.shape.halfHeight = 0.5;
    const auto [on, depth, end] = run(40, 0.1, 2, 60, true);
    const double off = std::get<0>(run(40, 0.1, 2, 60, false));
    std::printf("[gpu continuous] rod drop: lowest mean height %.4g m, deepest point in the rod %.3g m; without %.4g m\n",
                on, depth, off);
    CHECK(on > -0.3);
    CHECK(depth == 0);
    CHECK(off < -1);
  }
  SECTION("the same drop from starts moved 1 and 3 mm across the rod") {
    // From these starts, before the friction guard (docs/design.md §18), friction carried a face across the rod.
    rod.shape.halfHeight = 0.5;
    for (const double shift : {0.001, 0.003}) {
      const auto [on, depth, end] = run(40, 0.1, 2, 60, true, shift);
      std::printf("[gpu continuous] rod drop, start moved %.0f mm: lowest mean height %.4g m, deepest point in the "
                  "rod %.3g m\n",
                  shift * 1e3, on, depth);
      CHECK(on > -0.3);
      CHECK(depth == 0);
    }
  }
  SECTION("a kinematic 3 mm rod rising at 10 m/s into the cloth") {
    rod.shape.halfHeight = 0.3;
    rod.motion = drape::Motion::Kinematic;
    rod.pose.position = {0, 0, -0.05};
    rod.linearVelocity = {0, 0, 10};
    const double rodZ = -0.05 + 10 * 3 / 60.0;
    const auto [lowest, depth, on] = run(16, 0.0, 10, 3, true);
    const double off = std::get<2>(run(16, 0.0, 10, 3, false));
    std::printf("[gpu continuous] rising rod: mean height at the end %.4g m (the rod's axis at %.3g m), deepest "
                "point in the rod %.3g m; without %.4g m\n",
                on, rodZ, depth, off);
    CHECK(on > rodZ - 0.15);  // carried, hanging from the rod
    CHECK(depth == 0);
    CHECK(off < rodZ - 0.3);  // left behind
  }
}

TEST_CASE("a frictionless spinning sphere answers the cloth as the same sphere at rest, on the GPU too", "[gpu]") {
  // The CPU test of the same name ([spin]): a face contact takes the normal part of the solid's velocity from
  // its contact point (collide_faces.comp), and propagation the solids' speed along its normal (propagate.comp).
  // The cloth is draped on the CPU for 1/3 s; then one GPU substep from that state with the sphere at rest, one
  // with it spinning at 2 rad/s about the vertical. (The GPU's face pass goes colour by colour, the CPU's face by
  // face, so the two solvers' substeps are not compared here; tests/gpu/test_faces.cpp compares the passes.)
  // With the corners' own material velocity in collide_faces.comp, the two were 3.4e-2 m/s apart.
  auto& context = drape::test::gpuContext();
  using drape::scenes::SphereDrape;
  const auto asset = SphereDrape::asset<float>();
  drape::Solver<float> drape(asset);
  drape.addSolid(SphereDrape::sphere());
  drape.pin(SphereDrape::kCentre);
  for (int f = 0; f < 20; ++f) drape.step(1.0 / 60.0);
  std::vector<Eigen::Vector3d> x, v;
  for (Index i = 0; i < drape.vertexCount(); ++i) x.push_back(drape.position(i)), v.push_back(drape.velocity(i));

  drape::Settings one;
  one.subStepCount = 1;
  auto substep = [&](auto& solver, double spin) {
    solver.addSolid(SphereDrape::sphere(spin));
    solver.pin(SphereDrape::kCentre);
    solver.setPositions(x);
    solver.setVelocities(v);
    solver.step(1.0 / 600.0);
    std::vector<Eigen::Vector3d> out;
    for (Index i = 0; i < solver.vertexCount(); ++i) out.push_back(solver.velocity(i));
    return out;
  };
  drape::gpu::Solver gpuStill(context, asset, one), gpuSpinning(context, asset, one);
  const auto still = substep(gpuStill, 0), spinning = substep(gpuSpinning, 2);
  double apart = 0, fastest = 0;
  for (std::size_t i = 0; i < still.size(); ++i) {
    apart = std::max(apart, (spinning[i] - still[i]).norm());
    fastest = std::max(fastest, still[i].norm());
  }
  std::printf("[gpu spin] fastest vertex %.3g m/s; spinning against still %.3g m/s\n", fastest, apart);
  CHECK(apart <= 1e-6);  // the CPU's float bound: a few ulps of the sphere's 0.6 m/s surface speed
}
