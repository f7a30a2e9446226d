// Determinism: the same scene, built and run from scratch twice in one process, ends in bit-identical state.
#include "state_hash.hpp"

#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace {

using drape::test::hashState;

constexpr int kFrames = 40;           ///< steps of 1/60 s: 400 substeps at the default 10 substeps per step
constexpr drape::Index kNudged = 37;  ///< the vertex the perturbed scene moves

/// The scene of tests/test_stability.cpp's dropOnBall: a 30 x 30 cloth at 2 cm spacing dropped from 0.4 m onto
/// a ball of radius 0.15 resting on the floor, both with friction 0.5. The initial positions go through
/// setPositions, which puts the local origin on its 1/64 m lattice. With nudge, vertex kNudged's local x then
/// moves up by one ulp of S (exactly: the test checks it), so the scene differs from the plain one in one bit
/// pattern.
template <class S> std::unique_ptr<drape::Solver<S>> makeScene(const drape::Settings& settings, bool nudge = false) {
  drape::SheetDesc grid;
  grid.nx = grid.ny = 30;
  grid.spacing = 0.02;
  grid.placement.position = {0.03, 0.01, 0.4};
  auto asset = std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid));
  auto solver = std::make_unique<drape::Solver<S>>(asset, settings);
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = 0.15;
  ball.pose.position = {0, 0, 0.15};
  ball.staticFriction = ball.dynamicFriction = 0.5;
  solver->addSolid(ball);
  drape::Solid<drape::Plane> floor;
  floor.staticFriction = floor.dynamicFriction = 0.5;
  solver->addSolid(floor);

  std::vector<Eigen::Vector3d> world(std::size_t(solver->vertexCount()));
  for (drape::Index i = 0; i < solver->vertexCount(); ++i) world[std::size_t(i)] = solver->position(i);
  solver->setPositions(world);
  if (nudge) {
    const S moved = std::nextafter(solver->state().x[kNudged].x(), std::numeric_limits<S>::infinity());
    world[kNudged].x() = solver->state().origin.x() + double(moved);
    solver->setPositions(world);
  }
  return solver;
}

/// Builds the scene above from scratch with these settings, runs kFrames steps of 1/60 s and returns the hash
/// of the final state (origin, positions, velocities). Meant for reuse by other determinism checks (for
/// example the same scene on several threads, which must give the single-threaded hash).
template <class S> std::uint64_t runAndHash(const drape::Settings& settings, bool nudge = false) {
  const auto solver = makeScene<S>(settings, nudge);
  for (int f = 0; f < kFrames; ++f) solver->step(1.0 / 60.0);
  return hashState(solver->state());
}

}  // namespace

TEMPLATE_TEST_CASE("the same scene run twice from scratch ends in bit-identical state", "[determinism]", float,
                   double) {
  drape::Settings settings;  // 10 substeps, 1 iteration
  settings.collisionMethod =
      GENERATE(drape::CollisionMethod::Faces, drape::CollisionMethod::InSolve, drape::CollisionMethod::Vertices);
  INFO("method " << drape::toString(settings.collisionMethod));

  // The run does something worth hashing: by the end the cloth lies on the ball and its corners on the floor.
  {
    const auto solver = makeScene<TestType>(settings);
    const std::uint64_t initial = hashState(solver->state());
    for (int f = 0; f < kFrames; ++f) solver->step(1.0 / 60.0);
    CHECK(hashState(solver->state()) != initial);
    double lowest = 1e9, highest = -1e9;
    for (drape::Index i = 0; i < solver->vertexCount(); ++i) {
      REQUIRE(solver->position(i).allFinite());
      REQUIRE(solver->velocity(i).allFinite());
      lowest = std::min(lowest, solver->position(i).z());
      highest = std::max(highest, solver->position(i).z());
    }
    INFO("lowest vertex " << lowest << " m, highest " << highest << " m");
    CHECK(lowest < 0.02);    // on the floor
    CHECK(highest < 0.32);   // fallen onto the ball, whose top is at 0.3 m
    CHECK(highest > 0.29);   // and resting on it
  }

  const std::uint64_t first = runAndHash<TestType>(settings);
  const std::uint64_t second = runAndHash<TestType>(settings);
  CHECK(first == second);
}

TEMPLATE_TEST_CASE("moving one vertex by one ulp changes the final hash", "[determinism]", float, double) {
  const drape::Settings settings;
  // The perturbed start differs from the plain one in exactly one coordinate, by exactly one ulp.
  const auto plain = makeScene<TestType>(settings), nudged = makeScene<TestType>(settings, true);
  REQUIRE(plain->state().origin == nudged->state().origin);
  int differing = 0;
  for (drape::Index i = 0; i < plain->vertexCount(); ++i)
    for (int c = 0; c < 3; ++c) {
      const TestType a = plain->state().x[i][c], b = nudged->state().x[i][c];
      if (a == b) continue;
      ++differing;
      CHECK(i == kNudged);
      CHECK(c == 0);
      CHECK(b == std::nextafter(a, std::numeric_limits<TestType>::infinity()));
    }
  CHECK(differing == 1);
  CHECK(hashState(plain->state()) != hashState(nudged->state()));

  CHECK(runAndHash<TestType>(settings) != runAndHash<TestType>(settings, true));
}

TEMPLATE_TEST_CASE("two threads give the bit-identical state of one thread", "[determinism][threads]", float, double) {
  // Every work-shared loop writes only its own vertices (one colour of constraints, one contact vertex), so
  // the split between threads cannot change a single bit.
  if (!drape::threadsAvailable()) WARN("drape was built without OpenMP: threadCount 2 runs on one thread here");
  for (const auto method :
       {drape::CollisionMethod::Faces, drape::CollisionMethod::InSolve, drape::CollisionMethod::Vertices}) {
    drape::Settings one;
    one.collisionMethod = method;
    one.iterationCount = 2;  // the multipliers are live too
    drape::Settings two = one;
    two.threadCount = 2;
    INFO("method " << drape::toString(method));
    CHECK(runAndHash<TestType>(one) == runAndHash<TestType>(two));
  }
}

namespace {

/// Whether two faces share a corner.
bool shareCorner(const std::array<drape::Index, 3>& a, const std::array<drape::Index, 3>& b) {
  for (drape::Index u : a)
    for (drape::Index v : b)
      if (u == v) return true;
  return false;
}

/// A sheet's faces renumbered: its rows in the order 0, 2, 4, ..., 1, 3, 5, ... and each row's faces backwards, so
/// that rows sharing corners lie far apart in the numbering.
std::vector<std::array<drape::Index, 3>> renumberedRows(const std::vector<std::array<drape::Index, 3>>& faces,
                                                        drape::Index rowFaces) {
  const drape::Index rows = drape::Index(faces.size()) / rowFaces;
  std::vector<std::array<drape::Index, 3>> out;
  for (int parity = 0; parity < 2; ++parity)
    for (drape::Index r = parity; r < rows; r += 2)
      for (drape::Index k = rowFaces - 1; k >= 0; --k) out.push_back(faces[std::size_t(r * rowFaces + k)]);
  return out;
}

}  // namespace

TEST_CASE("a wave's plan waits for exactly the faces before it in other threads' segments that share a corner",
          "[determinism][threads]") {
  drape::SheetDesc grid;
  grid.nx = 40;
  grid.ny = 30;
  const auto sheet = drape::ClothAsset<float>::sheet(grid);
  const drape::Index rowFaces = 2 * (grid.nx - 1);
  const auto renumbered = renumberedRows(sheet.triangles, rowFaces);
  for (const auto* faces : {&sheet.triangles, &renumbered})
    for (int threads : {2, 3}) {
      INFO((faces == &sheet.triangles ? "rows in order" : "rows renumbered") << ", " << threads << " threads");
      drape::FaceWave wave;
      REQUIRE(wave.ready(drape::Index(faces->size()), *faces, grid.nx * grid.ny, threads));
      const std::vector<drape::Index>& bounds = wave.segments();
      // Each row of faces (a run whose neighbours share corners) is cut into one segment per thread.
      REQUIRE(bounds.size() == std::size_t(grid.ny - 1) * std::size_t(threads) + 1);
      for (std::size_t k = 0; k + 1 < bounds.size(); ++k) {
        CHECK(bounds[k + 1] - bounds[k] >= rowFaces / threads);
        CHECK(bounds[k + 1] - bounds[k] <= rowFaces / threads + 1);
      }
      std::vector<int> owner(faces->size());
      for (std::size_t k = 0; k + 1 < bounds.size(); ++k)
        for (drape::Index f = bounds[k]; f < bounds[k + 1]; ++f) owner[std::size_t(f)] = int(k) % threads;
      // Against a brute force over every pair of faces.
      std::vector<drape::Index> need(faces->size());
      int mismatches = 0, waiting = 0;
      for (std::size_t f = 0; f < faces->size(); ++f) {
        drape::Index last = -1;
        for (std::size_t g = 0; g < f; ++g)
          if (owner[g] != owner[f] && shareCorner((*faces)[g], (*faces)[f])) last = drape::Index(g);
        need[f] = last;
        waiting += last >= 0;
      }
      // Every thread visits its own segments of a list in order; together they visit the list once.
      std::vector<drape::Index> list;
      for (drape::Index f = 0; f < drape::Index(faces->size()); f += 1 + f % 3) list.push_back(f);
      std::vector<int> visits(faces->size(), 0);
      for (int t = 0; t < threads; ++t) {
        drape::WaveGate gate = wave.gate(t, list.data());
        const drape::Index count = drape::Index(list.size());
        drape::Index before = -1, visited = 0;
        for (drape::Index p = gate.first(count); p < count; p = gate.next(p, count)) {
          const drape::Index f = list[std::size_t(p)];
          CHECK(owner[std::size_t(f)] == t);
          CHECK(f > before);
          before = f;
          ++visits[std::size_t(f)];
          ++visited;
        }
        CHECK(gate.share(count) == visited);
      }
      for (drape::Index f : list) mismatches += visits[std::size_t(f)] != 1;
      CHECK(mismatches == 0);
      mismatches = 0;
      for (std::size_t f = 0; f < faces->size(); ++f) mismatches += wave.need(drape::Index(f)) != need[f];
      CHECK(mismatches == 0);
      CHECK(waiting >= int(bounds.size()) - 2);  // at least the first face of every segment but the first
    }
  // Faces numbered in no order: no runs to cut, so the pass stays on one thread.
  std::vector<std::array<drape::Index, 3>> shuffled = sheet.triangles;
  for (std::size_t k = 0; k < shuffled.size(); ++k) std::swap(shuffled[k], shuffled[(k * 7919) % shuffled.size()]);
  drape::FaceWave wave;
  CHECK_FALSE(wave.ready(drape::Index(shuffled.size()), shuffled, grid.nx * grid.ny, 2));
}

TEMPLATE_TEST_CASE("a face pass shared by two or three threads gives one thread's contacts bit for bit",
                   "[determinism][threads]", float, double) {
  using S = TestType;
  if (!drape::threadsAvailable()) WARN("drape was built without OpenMP: threadCount 2 runs on one thread here");
  struct Case {
    const char* name;
    drape::Index side;
    double spacing;
    bool broadPhase, renumber;
  };
  // A cloth the ball's box holds (every face, with kept clearances), the same without the bins, one the ball's box
  // holds a part of (the bins' list), and one whose rows are renumbered (rows sharing corners far apart).
  for (const Case c : {Case{"every face", 50, 0.015, true, false}, Case{"no bins", 50, 0.015, false, false},
                       Case{"the bins' list", 64, 0.02, true, false}, Case{"rows renumbered", 50, 0.015, true, true}}) {
    INFO(c.name);
    auto run = [&](int threads, std::int64_t& faceContacts, std::int64_t& keptClear) {
      drape::SheetDesc grid;
      grid.nx = grid.ny = c.side;
      grid.spacing = c.spacing;
      grid.placement.position = {0.01, -0.02, 0.65};
      auto sheet = drape::ClothAsset<S>::sheet(grid);
      if (c.renumber) {
        const auto faces = renumberedRows(sheet.triangles, 2 * (c.side - 1));
        std::vector<drape::Vec3<S>> points = sheet.restPositions;
        for (auto& p : points) p += sheet.origin.template cast<S>();
        sheet = drape::ClothAsset<S>::fromMesh(points, faces);
      }
      drape::Settings settings;
      settings.threadCount = threads;
      settings.broadPhase = c.broadPhase;
      drape::Solver<S> solver(std::make_shared<const drape::ClothAsset<S>>(sheet), settings);
      drape::Solid<drape::Sphere> ball;
      ball.shape.radius = 0.3;
      ball.pose.position = {0, 0, 0.3};
      ball.staticFriction = ball.dynamicFriction = 0.4;
      solver.addSolid(ball);
      solver.addSolid(drape::Solid<drape::Plane>{});
      faceContacts = keptClear = 0;
      for (int f = 0; f < 30; ++f)
        solver.step(1.0 / 60, [&](const drape::Solver<S>& s) noexcept {
          faceContacts += s.stats().faceContacts;
          keptClear += s.stats().facesKeptClear;
        });
      return hashState(solver.state());
    };
    std::int64_t contactsOne = 0, keptOne = 0;
    const std::uint64_t one = run(1, contactsOne, keptOne);
    CHECK(contactsOne > 100000);  // the cloth lies on the ball
    for (int threads : {2, 3}) {
      INFO(threads << " threads");
      std::int64_t contacts = 0, kept = 0;
      CHECK(run(threads, contacts, kept) == one);
      CHECK(contacts == contactsOne);
      CHECK(kept == keptOne);
    }
  }
}
