// Several solids on the GPU: the records of up to three surfaces per vertex, the placement outside all of
// a vertex's contact planes (settle.comp), the per-surface velocity split then reconciled (respond.comp), each
// against its CPU twin on random records; and scenes where surfaces meet (a V gutter of two planes, a cloth
// pinched between a ball and the floor), GPU against CPU.
#include "gpu_helpers.hpp"
#include "edge_press.hpp"
#include "gutter.hpp"

#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <tuple>
#include <vector>

namespace {

using drape::Index;
using drape::Vec3;
namespace layout = drape::gpu::layout;

/// Slot k of a GPU record as the CPU's slot c holds it.
void putSlot(layout::Contact& g, int k, const drape::ContactSlot<float>& c) {
  for (int a = 0; a < 3; ++a) g.normal[k][a] = c.normal[a], g.velocity[k][a] = c.solidVelocity[a];
  g.normal[k][3] = c.correction;
  g.velocity[k][3] = c.offset;
  g.friction[k][0] = c.staticFriction;
  g.friction[k][1] = c.dynamicFriction;
  g.body[k] = c.body;
}

/// Random contact records for n vertices: each has 1 to 3 slots whose planes pass within 3 mm of its position,
/// facing anywhere (so some vertices lie outside all of them, some are pinched between facing planes, some sit
/// in a wedge or a corner), with random solid velocities, corrections and friction; the CPU's ContactBuffer and
/// the GPU's records hold the same.
struct RandomContacts {
  std::vector<Vec3<float>> x, reference, xStart, v;
  drape::ContactBuffer<float> cpu;
  std::vector<layout::Contact> gpu;

  explicit RandomContacts(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f), frac(0.0f, 1.0f);
    auto direction = [&] {
      Vec3<float> d;
      do d = Vec3<float>(unit(rng), unit(rng), unit(rng));
      while (d.squaredNorm() < 0.01f || d.squaredNorm() > 1.0f);
      return Vec3<float>(d.normalized());
    };
    cpu.resize(n);
    cpu.begin();
    gpu.assign(std::size_t(n), layout::Contact{});
    for (int i = 0; i < n; ++i) {
      const Vec3<float> at(0.1f * unit(rng), 0.1f * unit(rng), 0.1f * unit(rng));
      x.push_back(at);
      reference.push_back(at + 0.003f * direction());
      xStart.push_back(at + 0.004f * Vec3<float>(unit(rng), unit(rng), unit(rng)));
      v.push_back(Vec3<float>(unit(rng), unit(rng), unit(rng)));
      const int slots = 1 + i % 3;
      cpu.stamp[std::size_t(i)] = cpu.current;
      cpu.slotCount[std::size_t(i)] = std::uint8_t(slots);
      layout::Contact& g = gpu[std::size_t(i)];
      g.slots[0] = std::uint32_t(slots);
      g.slots[1] = i % 17 == 0 ? 1u : 0u;  // now and then an overflowed record, which settle leaves alone
      if (g.slots[1]) cpu.overflow[std::size_t(i)] = cpu.current;
      for (int k = 0; k < slots; ++k) {
        drape::ContactSlot<float> c;
        c.normal = direction();
        c.solidVelocity = 0.3f * Vec3<float>(unit(rng), unit(rng), unit(rng));
        c.correction = 0.002f * frac(rng);
        c.staticFriction = 0.5f * frac(rng);
        c.dynamicFriction = 0.5f * frac(rng);
        c.offset = c.normal.dot(at) + 0.003f * unit(rng);
        c.body = -1;
        cpu.slots[std::size_t(i)][std::size_t(k)] = c;
        putSlot(g, k, c);
      }
    }
  }
};

std::vector<layout::Vertex> packed(const std::vector<Vec3<float>>& p, float w) {
  std::vector<layout::Vertex> out(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) out[i] = {p[i].x(), p[i].y(), p[i].z(), w};
  return out;
}
std::vector<Vec3<float>> unpacked(const std::vector<layout::Vertex>& p) {
  std::vector<Vec3<float>> out(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) out[i] = {p[i].x, p[i].y, p[i].z};
  return out;
}

}  // namespace

TEST_CASE("settle: the GPU placement outside several contact planes against projectOntoContactPlanes", "[gpu]") {
  // The random records' planes are tangents of no solid but the floor's, whose plane slot 0 of every other vertex
  // takes: so the fields back some exact points (the floor's plane), refuse others with a plane backed (the
  // compromise) and refuse the rest outright (the segment, through a ball and a box).
  drape::test::gpuContext().makeCurrent();
  const int n = 3000;
  const float thickness = 0.005f;
  RandomContacts r(n, 7);
  drape::ContactSlot<float> floorSlot{};  // scalars zero; every field is copied, so none is left unset
  floorSlot.normal = Vec3<float>::UnitZ();
  floorSlot.solidVelocity.setZero();
  floorSlot.offset = thickness;
  floorSlot.body = -1;
  for (int i = 1; i < n; i += 2) {  // of the vertices with two or three slots, every other one
    r.cpu.slots[std::size_t(i)][0] = floorSlot;
    putSlot(r.gpu[std::size_t(i)], 0, floorSlot);
  }
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = 0.04;
  ball.pose.position = {0.02, 0.01, 0.0};
  drape::Solid<drape::Box> block;
  block.shape.halfExtents = {0.03, 0.02, 0.05};
  block.pose.position = {-0.04, -0.03, 0.01};
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  using drape::CompiledSolid;
  const std::tuple<std::vector<CompiledSolid<drape::Plane, float>>, std::vector<CompiledSolid<drape::Sphere, float>>,
                   std::vector<CompiledSolid<drape::Box, float>>>
      solids{{drape::detail::compileSolid<drape::Plane, float>(drape::Solid<drape::Plane>{}, origin)},
             {drape::detail::compileSolid<drape::Sphere, float>(ball, origin)},
             {drape::detail::compileSolid<drape::Box, float>(block, origin)}};
  const drape::SettleFields<float, decltype(solids)> fields{solids, thickness};
  std::vector<Vec3<float>> x = r.x;
  drape::projectOntoContactPlanes(0, n, r.cpu, x.data(), r.reference.data(), r.x.data(), fields);

  // What the fields decided, counted on the CPU's own steps.
  int taken = 0, compromised = 0, segment = 0;
  for (int i = 0; i < n; ++i) {
    const int count = r.cpu.slotCount[std::size_t(i)];
    if (count < 2 || r.cpu.overflow[std::size_t(i)] == r.cpu.current) continue;
    Vec3<float> nk[3];
    float bk[3];
    for (int k = 0; k < count; ++k) {
      const drape::ContactSlot<float>& c = r.cpu.slots[std::size_t(i)][std::size_t(k)];
      nk[k] = c.normal, bk[k] = c.offset;
    }
    const Vec3<float> y0 = r.x[std::size_t(i)];
    if (drape::insideHalfSpaces(nk, bk, count, y0)) continue;
    const float violation = drape::halfSpaceViolation(nk, bk, count, y0);
    drape::SettlePoint<float> p{y0, y0, float(drape::constants::kExactPointSlack) * violation, 0u};
    if (!drape::nearestOnPlanes(nk, bk, count, y0, float(drape::constants::kReach) * violation, p.to)) continue;
    for (int k = 0; k < count; ++k)
      if (nk[k].dot(p.to) - bk[k] <= p.slack) p.planes |= 1u << k;
    const unsigned backed = fields.backed(p, nk);
    ((backed & p.planes) == p.planes ? taken : backed != 0u ? compromised : segment) += 1;
  }
  INFO("exact points taken " << taken << ", refused to the compromise " << compromised << ", to the segment "
                             << segment);
  REQUIRE(taken > 50);
  REQUIRE(compromised > 50);
  REQUIRE(segment > 50);

  drape::gpu::Buffer<layout::Vertex> gx(packed(r.x, 1.0f)), gref(packed(r.reference, 1.0f));
  drape::gpu::Buffer<layout::Contact> gc(r.gpu);
  drape::gpu::Buffer<layout::SettlePoint> points{std::vector<layout::SettlePoint>(std::size_t(n))};
  gx.bind(layout::kPositions);
  gref.bind(layout::kPacked);
  gc.bind(layout::kContacts);
  points.bind(layout::kSettlePoints);
  drape::gpu::Program plan("settle", drape::gpu::shaders::settle);
  drape::gpu::Program place("settle", drape::gpu::shaders::settle, "#define DRAPE_SETTLE_PLACE 1\n");
  drape::gpu::SolidKernels kernels;
  std::vector<drape::gpu::SolidPass> passes;
  std::apply([&](const auto&... lists) {
    (..., [&](const auto& list) {
      kernels.compileSettleFor(list[0]);
      passes.push_back(kernels.pass(list[0]));
    }(lists));
  }, solids);
  const auto settle = [&](bool indirect, GLuint commands) {
    for (const drape::gpu::Program* k : {&plan, &place}) k->set(layout::kCount, unsigned(n));
    const auto run = [&](const drape::gpu::Program& k) {
      if (indirect) k.dispatchIndirect(commands, 0);
      else k.dispatch(n);
    };
    run(plan);
    for (const auto& p : passes)
      if (indirect) kernels.settlePass(p, thickness, unsigned(n), commands, 0);
      else kernels.settlePass(p, thickness, unsigned(n));
    run(place);
  };
  // A settle pass whose vertex passes found nothing runs from a command they left cleared: no move.
  drape::gpu::Buffer<std::uint32_t> noWork(std::vector<std::uint32_t>(3, 0u));
  settle(true, noWork.id());
  REQUIRE(drape::test::largestDifference(unpacked(gx.read()), r.x) == 0);
  settle(false, 0);
  const auto gpuX = unpacked(gx.read());

  int moved = 0;
  for (int i = 0; i < n; ++i) moved += (x[std::size_t(i)] - r.x[std::size_t(i)]).norm() > 1e-5f ? 1 : 0;
  INFO(moved << " of " << n << " vertices moved by the CPU");
  REQUIRE(moved > n / 4);
  // The candidates and the least-squares steps are the CPU's arithmetic in its order; the corner of three planes
  // is solved by elimination where the CPU uses Eigen's LU, so it may differ by a few roundings.
  CHECK(drape::test::largestDifference(gpuX, x) <= 1e-6);
}

TEST_CASE("respond: the GPU split of several surfaces against respondContacts", "[gpu]") {
  drape::test::gpuContext().makeCurrent();
  const int n = 3000;
  const bool friction = GENERATE(false, true);
  INFO((friction ? "with friction" : "without friction"));
  RandomContacts r(n, 11);
  const float h = 1.0f / 600, damping = 0.1f;
  std::vector<Vec3<float>> x = r.x, v = r.v;
  if (friction)
    drape::respondContacts<true>(0, n, r.cpu, x.data(), r.xStart.data(), v.data(), h, damping);
  else
    drape::respondContacts<false>(0, n, r.cpu, x.data(), r.xStart.data(), v.data(), h, damping);

  drape::gpu::Buffer<layout::Vertex> gx(packed(r.x, 1.0f)), gv(packed(r.v, 0.0f)), gs(packed(r.xStart, 1.0f));
  drape::gpu::Buffer<layout::Contact> gc(r.gpu);
  gx.bind(layout::kPositions);
  gv.bind(layout::kVelocities);
  gs.bind(layout::kStart);
  gc.bind(layout::kContacts);
  drape::gpu::Program k("respond", drape::gpu::shaders::respond,
                        friction ? "#define DRAPE_FRICTION 1\n" : "#define DRAPE_FRICTION 0\n");
  k.set(layout::kCount, unsigned(n));
  k.set(layout::kStep, h);
  k.set(layout::kInverseStep, 1.0f / h);
  k.set(layout::kNormalDamping, damping);
  k.dispatch(n);
  const auto gpuX = unpacked(gx.read()), gpuV = unpacked(gv.read());
  const auto gpuC = gc.read();

  REQUIRE(drape::test::largestDifference(v, r.v) > 0.1);  // the split changed velocities by m/s
  if (friction) REQUIRE(drape::test::largestDifference(x, r.x) > 1e-4);  // and friction moved vertices
  CHECK(drape::test::largestDifference(gpuX, x) <= 1e-7);
  CHECK(drape::test::largestDifference(gpuV, v) <= 1e-5);
  double worstDv = 0;
  for (int i = 0; i < n; ++i)
    worstDv = std::max(worstDv, std::abs(double(gpuC[std::size_t(i)].normalDv[0]) - r.cpu.normalDv[std::size_t(i)]));
  CHECK(worstDv <= 1e-5);
}

TEST_CASE("hold planes: the GPU keeps friction's moves out of a plane as holdOutOfPlane does", "[gpu]") {
  // Random records (every fifth vertex with none, which stays where it is) about a tilted plane whose thickness
  // holds about half of them, each with a position ahead of the response 3 mm from its own: some were shallower
  // and go back to it, to the thickness or to the surface, some deeper and stay.
  drape::test::gpuContext().makeCurrent();
  const int n = 3000;
  RandomContacts r(n, 13);
  for (int i = 0; i < n; i += 5) r.cpu.stamp[std::size_t(i)] = 0, r.gpu[std::size_t(i)].slots[0] = 0;
  drape::Sdf<drape::Plane, float> plane;
  plane.normal = Vec3<float>(0.2f, -0.3f, 0.9f).normalized();
  plane.offset = 0.03f;  // some records lie below the surface
  const float thickness = 0.05f, slack = 1e-4f;
  std::vector<Vec3<float>> x = r.x;
  drape::holdOutOfPlane(0, n, r.cpu, plane, thickness, slack, x.data(), r.reference.data());

  drape::gpu::Buffer<layout::Vertex> gx(packed(r.x, 0.5f)), gb(packed(r.reference, 1.0f));
  drape::gpu::Buffer<layout::Contact> gc(r.gpu);
  gx.bind(layout::kPositions);
  gb.bind(layout::kGuardFrom);
  gc.bind(layout::kContacts);
  drape::gpu::Program k("hold_planes", drape::gpu::shaders::hold_planes, drape::gpu::shapeDefine<drape::Plane>());
  drape::gpu::setShape(k.id(), drape::gpu::packShape(plane));
  k.set(layout::kCount, unsigned(n));
  k.set(layout::kThickness, thickness);
  k.set(layout::kSlack, slack);
  k.dispatch(n);
  const auto read = gx.read();
  const auto gpuX = unpacked(read);

  int moved = 0, left = 0;
  for (int i = 0; i < n; ++i) {
    const std::size_t u = std::size_t(i);
    Vec3<float> g;
    if (x[u] != r.x[u]) ++moved;
    else if (plane(r.x[u], g) < thickness) ++left;  // no records, or deeper before the response
  }
  INFO(moved << " moved, " << left << " inside the thickness left alone");
  REQUIRE(moved > 300);
  REQUIRE(left > 300);
  CHECK(drape::test::largestDifference(gpuX, x) <= 1e-7);  // fused multiply-adds may round one way on the CPU
  bool weightsKept = true;
  for (const layout::Vertex& p : read) weightsKept = weightsKept && p.w == 0.5f;
  CHECK(weightsKept);
}

TEST_CASE("a cloth folded into a V gutter of two planes: the GPU solver follows the CPU solver", "[gpu]") {
  // scenes/gutter.hpp's scene: the fold line touches both walls at once, so every substep reconciles two planes
  // (settle and its passes, the split of two surfaces). Planes have no face pass: the GPU does the CPU's
  // arithmetic in the CPU's order.
  drape::scenes::GutterConfig c;
  // At 45 degrees the walls meet square and the two projections commute; at 60 the fold vertices are pushed
  // back into one wall by the other, so the settle placement and the reconciled split act every substep.
  c.wallDeg = GENERATE(45.0, 60.0);
  c.settings.collisionMethod = GENERATE(drape::CollisionMethod::Faces, drape::CollisionMethod::InSolve);
  INFO("walls at " << c.wallDeg << " degrees, " << drape::toString(c.settings.collisionMethod));
  drape::SheetDesc grid;
  grid.nx = c.nx;
  grid.ny = c.ny;
  grid.spacing = c.spacing;
  auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(grid));
  drape::Solver<float> cpu(asset, c.settings);
  drape::gpu::Solver gpu(drape::test::gpuContext(), asset, c.settings);
  const double wall = c.wallDeg * std::numbers::pi / 180.0;
  for (int side : {1, -1}) {
    drape::Solid<drape::Plane> p;
    p.pose.rotation = Eigen::AngleAxisd(side * wall, Eigen::Vector3d::UnitY());
    cpu.addSolid(p);
    gpu.addSolid(p);
  }
  std::vector<Eigen::Vector3d> x(std::size_t(cpu.vertexCount()));
  const double lift = (c.settings.thickness + c.gap) / std::cos(wall);
  for (int j = 0; j < c.ny; ++j)
    for (int i = 0; i < c.nx; ++i) {
      const double u = (i - 0.5 * (c.nx - 1)) * c.spacing, y = (j - 0.5 * (c.ny - 1)) * c.spacing;
      x[std::size_t(j * c.nx + i)] = {u * std::cos(wall), y, std::abs(u) * std::sin(wall) + lift};
    }
  cpu.setPositions(x);
  gpu.setPositions(x);
  double worst = 0, gpuDepth = 0, cpuDepth = 0;
  drape::TrembleMeter cpuMeter, gpuMeter;
  for (int frame = 1; frame <= 120; ++frame) {
    cpu.step(c.dt);
    gpu.step(c.dt);
    std::vector<Eigen::Vector3d> a, b;
    for (Index i = 0; i < cpu.vertexCount(); ++i) a.push_back(cpu.position(i)), b.push_back(gpu.position(i));
    worst = std::max(worst, drape::test::largestDifference(a, b));
    cpuDepth = std::max(cpuDepth, drape::penetration(cpu).depth);
    gpuDepth = std::max(gpuDepth, drape::penetration(gpu).depth);
    cpuMeter.frame(cpu, c.dt, frame > 60);
    gpuMeter.frame(gpu, c.dt, frame > 60);
  }
  INFO("largest position difference " << worst << " m; deepest penetration CPU " << cpuDepth << ", GPU " << gpuDepth
                                      << " m; trembling rms CPU " << cpuMeter.rms() << ", GPU " << gpuMeter.rms()
                                      << " m/s; contact fraction " << gpuMeter.contactFraction());
  // The cloth lies on the walls (93 % of the vertices in contact at 45 degrees; 42 % at 60, where the sheet
  // folds more sharply than the walls and its edges stand off them).
  REQUIRE(gpuMeter.contactFraction() > 0.3);
  CHECK(worst == 0);
  CHECK(gpuDepth <= std::max(2 * cpuDepth, 1e-5));
}

TEST_CASE("a cloth pinched in a gap narrower than twice its thickness: the GPU's settle passes follow the CPU's",
          "[gpu]") {
  // The pinch of tests/test_thin.cpp with vertex contacts (no face pass, whose order differs on the GPU), so the
  // GPU does the CPU's arithmetic in the CPU's order. Under the box no position clears both surfaces, so every
  // settle pass finds the pinched vertices again: on the GPU each pass after the first runs from the command the
  // one before wrote (Program::dispatchIndirect). Run from a command never written, the passes after the first
  // did nothing and the GPU left the CPU's bits (by 1.7e-6 m within the 20 frames).
  drape::Settings settings;
  settings.collisionMethod = drape::CollisionMethod::Vertices;
  drape::SheetDesc grid;
  grid.nx = grid.ny = 21;
  grid.spacing = 0.02;
  grid.placement.position = {0, 0, settings.thickness};
  auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(grid));
  drape::Solver<float> cpu(asset, settings);
  drape::gpu::Solver gpu(drape::test::gpuContext(), asset, settings);
  cpu.addSolid(drape::Solid<drape::Plane>{});
  gpu.addSolid(drape::Solid<drape::Plane>{});
  drape::Solid<drape::Box> box;
  box.shape.halfExtents = {0.08, 0.08, 0.04};
  box.pose.position = {0.005, -0.003, 1.6 * settings.thickness + 0.04};
  cpu.addSolid(box);
  gpu.addSolid(box);
  double worst = 0;
  for (int frame = 1; frame <= 20; ++frame) {
    cpu.step(0.01);
    gpu.step(0.01);
    std::vector<Eigen::Vector3d> a, b;
    for (Index i = 0; i < cpu.vertexCount(); ++i) a.push_back(cpu.position(i)), b.push_back(gpu.position(i));
    worst = std::max(worst, drape::test::largestDifference(a, b));
  }
  INFO("largest position difference " << worst << " m");
  CHECK(worst == 0);
}

TEST_CASE("a cloth pinched between a ball and the floor, by a box's corner: GPU and CPU agree", "[gpu]") {
  // A cloth falls onto a ball and a tilted box that both rest on the floor and drapes down to it: vertices touch
  // two and three surfaces at once (ball and floor, box faces and floor), with friction.
  drape::SheetDesc grid;
  grid.nx = grid.ny = 24;
  grid.spacing = 0.04;
  grid.placement.position = {0, 0, 0.5};
  auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(grid));
  drape::Solver<float> cpu(asset, drape::Settings{}, 0.2);
  drape::gpu::Solver gpu(drape::test::gpuContext(), asset, drape::Settings{}, 0.2);
  drape::Solid<drape::Plane> floor;
  floor.staticFriction = floor.dynamicFriction = 0.4;
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = 0.15;
  ball.pose.position = {-0.2, 0.05, 0.15};
  ball.staticFriction = ball.dynamicFriction = 0.3;
  drape::Solid<drape::Box> box;
  box.shape.halfExtents = {0.12, 0.1, 0.1};
  box.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  box.pose.position = {0.2, -0.05, 0.1};
  box.staticFriction = box.dynamicFriction = 0.3;
  cpu.addSolid(floor);
  cpu.addSolid(ball);
  cpu.addSolid(box);
  gpu.addSolid(floor);
  gpu.addSolid(ball);
  gpu.addSolid(box);
  const auto r = drape::test::stepSideBySide(cpu, gpu, 90, 60);
  INFO("deepest penetration CPU " << r.cpuDepth << " m, GPU " << r.gpuDepth << " m; centre height gap "
                                  << r.heightGap << " m; CPU centre at " << r.cpuZ << " m; trembling rms CPU "
                                  << r.cpuMeter.rms() << ", GPU " << r.gpuMeter.rms() << " m/s");
  REQUIRE(r.cpuZ < 0.2);  // it fell onto the solids and the floor
  CHECK(r.gpuDepth <= std::max(2 * r.cpuDepth, 1e-4));
  CHECK(r.heightGap <= 0.01);
  CHECK(r.gpuMeter.rms() <= 2 * r.cpuMeter.rms() + 1e-3);
}

TEST_CASE("collide_vertices in a settle pass writes that pass's dispatch command only where it finds a contact",
          "[gpu]") {
  // The settle passes after the first, and each pass's settle, run from the command the pass before wrote
  // (Program::dispatchIndirect): a pass that finds nothing leaves it cleared, and what follows costs no invocation.
  drape::test::gpuContext().makeCurrent();
  drape::Solid<drape::Box> floor;
  floor.shape.halfExtents = {1.0, 1.0, 0.1};
  floor.pose.position = {0, 0, -0.1};
  const auto solid = drape::detail::compileSolid<drape::Box, float>(floor, Eigen::Vector3d::Zero());
  const float thickness = 0.005f;
  const int n = 300;  // more than one workgroup
  drape::gpu::Program k("collide_vertices", drape::gpu::shaders::collide_vertices,
                        drape::gpu::shapeDefine<drape::Box>());
  drape::gpu::SolidKernels::setUniforms(k, drape::gpu::SolidKernels{}.pass(solid), thickness);
  k.set(layout::kCount, unsigned(n));
  k.set(layout::kSlack, 0.0f);
  k.set(layout::kFresh, 0u);
  const auto run = [&](float height, int pass) {
    std::vector<layout::Vertex> x(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) x[std::size_t(i)] = {0.001f * float(i), 0.0f, height, 1.0f};
    drape::gpu::Buffer<layout::Vertex> gx(x);
    drape::gpu::Buffer<layout::Contact> gc(std::vector<layout::Contact>(std::size_t(n), layout::Contact{}));
    drape::gpu::Buffer<std::uint32_t> commands(std::vector<std::uint32_t>(3 * drape::constants::kSettlePasses, 0u));
    gx.bind(layout::kPositions);
    gc.bind(layout::kContacts);
    commands.bind(layout::kFlags);
    glProgramUniform1i(k.id(), layout::kPass, pass);
    k.dispatch(std::size_t(n));
    return commands.read();
  };
  const auto groups = std::uint32_t((n + layout::kWorkgroup - 1) / layout::kWorkgroup);
  for (int pass = 0; pass < drape::constants::kSettlePasses; ++pass) {
    INFO("settle pass " << pass);
    const auto inside = run(0.5f * thickness, pass);  // every vertex within the thickness: found
    const auto clear = run(2.0f * thickness, pass);   // none: nothing found
    for (int p = 0; p < drape::constants::kSettlePasses; ++p) {
      INFO("command " << p);
      const std::uint32_t* c = &inside[std::size_t(3 * p)];
      if (p == pass) {
        CHECK(c[0] == groups);
        CHECK(c[1] == 1u);
        CHECK(c[2] == 1u);
      } else {
        CHECK((c[0] | c[1] | c[2]) == 0u);
      }
      for (int a = 0; a < 3; ++a) CHECK(clear[std::size_t(3 * p + a)] == 0u);
    }
  }
  // The first pass (-1) writes no command.
  for (const std::uint32_t c : run(0.5f * thickness, -1)) CHECK(c == 0u);
}

TEST_CASE("collide_vertices: a surface that finds every slot taken, against the CPU vertex pass's records", "[gpu]") {
  // Every vertex already holds three differently facing surfaces when a floor (the top of a large box) catches it.
  // Where all three face away from the floor (the faces of a body's corner pressing down), or all three are one
  // coupled body's, the two closest share a slot and the floor takes the other; otherwise the floor joins its
  // closest (recordMore, recordContact).
  drape::test::gpuContext().makeCurrent();
  const int n = 600;
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), frac(0.0f, 1.0f);
  drape::Solid<drape::Box> floor;
  floor.shape.halfExtents = {1.0, 1.0, 0.1};
  floor.pose.position = {0, 0, -0.1};
  floor.staticFriction = 0.4;
  floor.dynamicFriction = 0.3;
  const auto solid = drape::detail::compileSolid<drape::Box, float>(floor, Eigen::Vector3d::Zero());
  const float thickness = 0.005f;
  std::vector<Vec3<float>> x(std::size_t(n), Vec3<float>::Zero());
  std::vector<float> w(std::size_t(n), 1.0f);
  drape::ContactBuffer<float> cpu;
  cpu.resize(n);
  cpu.begin();
  std::vector<layout::Contact> gpu(std::size_t(n), layout::Contact{});
  int facingAway = 0;
  for (int i = 0; i < n; ++i) {
    x[std::size_t(i)] = Vec3<float>(0.3f * unit(rng), 0.3f * unit(rng), 0.004f * frac(rng));
    const bool down = i % 2 == 0;  // all three facing down: the floor faces away from every one
    Vec3<float> normals[3];
    for (int k = 0; k < 3; ++k) {
      bool apart;
      do {
        normals[k] = Vec3<float>(unit(rng), unit(rng), down ? -0.3f - frac(rng) : unit(rng)).normalized();
        apart = normals[k].z() < 0.9f;  // never the floor's own direction (that would merge, not overflow)
        for (int j = 0; j < k; ++j) apart = apart && normals[j].dot(normals[k]) < 0.9f;
      } while (!apart);
    }
    facingAway += down;
    cpu.stamp[std::size_t(i)] = cpu.current;
    cpu.slotCount[std::size_t(i)] = 3;
    layout::Contact& g = gpu[std::size_t(i)];
    g.slots[0] = 3;
    for (int k = 0; k < 3; ++k) {
      drape::ContactSlot<float> c;
      c.normal = normals[k];
      c.solidVelocity = 0.3f * Vec3<float>(unit(rng), unit(rng), unit(rng));
      c.correction = 0.002f * frac(rng);
      c.staticFriction = 0.5f * frac(rng);
      c.dynamicFriction = 0.5f * frac(rng);
      c.offset = c.normal.dot(x[std::size_t(i)]) - 0.001f * frac(rng);
      c.body = i % 6 == 1 ? 5 : -1;  // now and then three faces of one coupled body: they make room too
      cpu.slots[std::size_t(i)][std::size_t(k)] = c;
      putSlot(g, k, c);
    }
  }
  std::vector<Vec3<float>> xc = x;
  const auto found = drape::projectVertexContacts(0, n, solid, thickness, xc.data(), w.data(), drape::AllItems{}, cpu,
                                                  xc.data(), 0.0f);
  REQUIRE(found.found == n);

  drape::gpu::Buffer<layout::Vertex> gx(packed(x, 1.0f));
  drape::gpu::Buffer<layout::Contact> gc(gpu);
  drape::gpu::Buffer<std::uint32_t> flags(std::vector<std::uint32_t>(4, 0u));
  gx.bind(layout::kPositions);
  gx.bind(layout::kStart);
  gc.bind(layout::kContacts);
  flags.bind(layout::kFlags);
  drape::gpu::Program k("collide_vertices", drape::gpu::shaders::collide_vertices,
                        drape::gpu::shapeDefine<drape::Box>());
  drape::gpu::SolidKernels::setUniforms(k, drape::gpu::SolidKernels{}.pass(solid), thickness);
  k.set(layout::kCount, unsigned(n));
  k.set(layout::kSlack, 0.0f);
  glProgramUniform1i(k.id(), layout::kPass, -1);
  k.set(layout::kFresh, 0u);  // the records above stand
  k.dispatch(std::size_t(n));
  const auto gpuC = gc.read();

  CHECK(drape::test::largestDifference(unpacked(gx.read()), xc) <= 1e-7);
  int merged = 0, joined = 0;
  for (int i = 0; i < n; ++i) {
    INFO("vertex " << i);
    const layout::Contact& g = gpuC[std::size_t(i)];
    REQUIRE(g.slots[0] == 3u);
    CHECK(g.slots[1] == 1u);
    REQUIRE(cpu.overflow[std::size_t(i)] == cpu.current);
    bool floorSlot = false;
    for (int s = 0; s < 3; ++s) {
      const drape::ContactSlot<float>& c = cpu.slots[std::size_t(i)][std::size_t(s)];
      INFO("slot " << s);
      for (int a = 0; a < 3; ++a) CHECK(g.normal[s][a] == c.normal[a]);
      CHECK(std::abs(g.normal[s][3] - c.correction) <= 1e-6f * c.correction + 1e-12f);
      CHECK(std::abs(g.velocity[s][3] - c.offset) <= 1e-6f);
      for (int a = 0; a < 3; ++a) CHECK(g.velocity[s][a] == c.solidVelocity[a]);
      CHECK(g.friction[s][0] == c.staticFriction);
      CHECK(g.friction[s][1] == c.dynamicFriction);
      CHECK(g.body[s] == c.body);
      floorSlot = floorSlot || c.normal == Vec3<float>::UnitZ();
    }
    merged += floorSlot, joined += !floorSlot;
  }
  INFO(merged << " records made room for the floor, " << joined << " joined it to a slot, " << facingAway
                << " had all three facing away from it");
  CHECK(merged > n / 4);  // both ways are compared
  CHECK(joined > n / 5);
}

TEST_CASE("a box pressed edge first onto a cloth on the floor: the GPU keeps friction's moves out of the floor too",
          "[gpu]") {
  // The CPU's "[contacts][friction]" scene on the GPU solver: a long box turned 30 degrees about its length comes
  // down edge first at 1 m/s onto a cloth on the floor and stops with its edge 2 mm above it. Its sloping sides'
  // position friction and pushes carried the cloth beside the edge below the floor's surface (hold_planes.comp keeps
  // it out); read at the frames' ends.
  const double thickness = drape::Settings{}.thickness;
  const drape::SheetDesc grid = drape::scenes::edgePressSheet(thickness);
  drape::gpu::Solver gpu(drape::test::gpuContext(),
                         std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(grid)));
  double lowest = thickness;
  drape::scenes::pressEdgeFirst(gpu, std::numbers::pi / 6, 0.002, [&](drape::gpu::Solver& g, double dt) {
    g.step(dt);
    for (drape::Index i = 0; i < g.vertexCount(); ++i) lowest = std::min(lowest, g.position(i).z());
  });
  INFO("lowest vertex at a frame's end " << lowest * 1e3 << " mm");
  CHECK(lowest >= -1e-4 * thickness);  // a vertex within kSettleSlack of where the hold puts it stays
}
