// Determinism: the same scene, built and run from scratch twice in one process, ends in bit-identical state.
#include "state_hash.hpp"

#include <drape/drape.hpp>

#include <catch2/catch.hpp>

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
