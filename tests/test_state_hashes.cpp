// Pinned state hashes: a fixed set of runs must end in exactly the bits recorded below. A change of code that
// is meant to leave the physics alone (a restructure, a rename, moving a loop) keeps every hash; a change that
// alters one on purpose updates it here and says why in its commit. DRAPE_PRINT_HASHES=1 prints the table.
//
// The hashes hold for one compiler and flag set (the CMake build, g++ at -O2 or -O3 without -march): the
// float kernels give the same bits with or without AVX2 (docs/design.md §8), and the step's result does not
// depend on the thread count. A build that lets the compiler fuse multiply-adds (-march=native on a processor
// with FMA, or -ffp-contract=fast with FMA available) rounds differently, and there the check is skipped.
#include "coupling_helpers.hpp"
#include "state_hash.hpp"

#include <drape/drape.hpp>
#include <drape/coupling/rigid_world.hpp>

#include <gutter.hpp>
#include <rigid_rain.hpp>
#include <slope.hpp>

#include <catch2/catch.hpp>

#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <type_traits>

namespace {

using drape::test::hex;
using drape::test::requireFinite;

/// The recorded hashes, by run name (scene / variant / scalar).
const drape::test::PinnedHashes kPinned = {
#include "state_hashes.inc"
};

void checkPinned(const std::string& name, std::uint64_t hash) {
  drape::test::checkPinned(kPinned, name, hash, drape::test::kMayFuse ? "built with fused multiply-adds" : "");
}

template <class S> const char* scalarName() { return std::is_same_v<S, float> ? "float" : "double"; }

/// A 20 x 30 cloth lands on the 30-degree slope (friction 0.2) and slides, 45 frames of 1/60 s.
template <class S> std::uint64_t slopeRun(drape::CollisionMethod method, int subSteps) {
  drape::scenes::SlopeConfig c;
  c.nx = 20;
  c.ny = 30;
  c.friction = 0.2;
  c.subSteps = subSteps;
  c.method = method;
  auto solver = drape::scenes::makeSlope<S>(c);
  for (int f = 0; f < 45; ++f) solver.step(c.dt);
  requireFinite(solver);
  return drape::test::hashState(solver.state());
}

/// A 15 x 20 cloth folded into a V of two frictionless planes at 45 and 60 degrees, 60 frames.
template <class S> std::uint64_t gutterRun() {
  drape::scenes::GutterConfig c;
  c.nx = 15;
  c.ny = 20;
  auto solver = drape::scenes::makeGutter<S>(c);
  for (int f = 0; f < 60; ++f) solver.step(c.dt);
  requireFinite(solver);
  return drape::test::hashState(solver.state());
}

/// A 21 x 21 cloth (2 cm) dropped from 0.25 m onto a solid centred at the origin (friction 0.3) and the floor
/// 0.2 m below it, 60 frames.
template <class S, class Shape> std::uint64_t dropRun(const drape::Solid<Shape>& solid) {
  drape::Solver<S> solver(drape::test::squareCloth<S>(21, 0.02, 0.25), drape::Settings{});
  solver.addSolid(solid);
  drape::Solid<drape::Plane> floor;
  floor.pose.position = {0, 0, -0.2};
  floor.staticFriction = floor.dynamicFriction = 0.5;
  solver.addSolid(floor);
  for (int f = 0; f < 60; ++f) solver.step(1.0 / 60);
  requireFinite(solver);
  return drape::test::hashState(solver.state());
}

template <class Shape> drape::Solid<Shape> frictional(const Shape& shape, const drape::Pose& pose = {}) {
  drape::Solid<Shape> s;
  s.shape = shape;
  s.pose = pose;
  s.staticFriction = s.dynamicFriction = 0.3;
  return s;
}

/// Five bodies rain onto a 21 x 21 cloth pinned at its corners, which are let go at 0.3 s; 60 steps of 0.01 s.
template <class S> std::uint64_t rainRun() {
  drape::scenes::RainConfig c;
  c.bodies = 5;
  c.seed = 7;
  c.nx = c.ny = 21;
  c.minDrop = 0.55;
  c.maxDrop = 0.9;
  c.release = 0.3;
  drape::scenes::RigidRain<S> rain(c);
  for (int k = 0; k < 60; ++k) rain.step();
  return drape::test::hashClothAndBodies(rain.cloth(), rain.world());
}

/// A ball dropped into a 21 x 21 hammock pinned at its corners, two-way coupled; 40 steps.
template <class S> std::uint64_t hammockRun(drape::ContactForce estimator) {
  drape::Settings settings;
  settings.contactForce = estimator;
  drape::Solver<S> cloth(drape::test::squareCloth<S>(21, 0.02, 0.0), settings);
  drape::RigidWorld world(drape::test::noGround());
  drape::test::dropIntoHammock(cloth, world, 40);
  return drape::test::hashClothAndBodies(cloth, world);
}

const char* methodName(drape::CollisionMethod m) { return drape::toString(m); }

}  // namespace

TEMPLATE_TEST_CASE("pinned state hashes: the slope at 1, 5 and 10 substeps, each collision method", "[hashes]", float,
                   double) {
  for (const auto method :
       {drape::CollisionMethod::Faces, drape::CollisionMethod::InSolve, drape::CollisionMethod::Vertices})
    for (const int subSteps : {1, 5, 10})
      checkPinned(std::string("slope/") + methodName(method) + "/" + std::to_string(subSteps) + "/" +
                      scalarName<TestType>(),
                  slopeRun<TestType>(method, subSteps));
}

TEMPLATE_TEST_CASE("pinned state hashes: the V gutter", "[hashes]", float, double) {
  checkPinned(std::string("gutter/") + scalarName<TestType>(), gutterRun<TestType>());
}

TEMPLATE_TEST_CASE("pinned state hashes: drops on a ball, a box, a capsule and a meshed torus", "[hashes]", float,
                   double) {
  using S = TestType;
  const std::string scalar = scalarName<S>();
  checkPinned("drop/ball/" + scalar, dropRun<S>(frictional(drape::Sphere{0.15})));
  drape::Pose turned;
  turned.rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 0).normalized());
  checkPinned("drop/box/" + scalar, dropRun<S>(frictional(drape::Box{{0.12, 0.1, 0.08}}, turned)));
  drape::Pose across;
  across.rotation = Eigen::AngleAxisd(1.5707963267948966, Eigen::Vector3d::UnitX());
  checkPinned("drop/capsule/" + scalar, dropRun<S>(frictional(drape::Capsule{0.05, 0.12}, across)));
  static const auto torus = drape::buildDistanceGrid(drape::makeTorus(0.15, 0.05, 48, 24), {});
  checkPinned("drop/torus/" + scalar, dropRun<S>(frictional(drape::MeshShape{torus})));
}

TEMPLATE_TEST_CASE("pinned state hashes: the rigid rain and the hammock (two-way coupling)", "[hashes]", float,
                   double) {
  using S = TestType;
  const std::string scalar = scalarName<S>();
  checkPinned("rain/" + scalar, rainRun<S>());
  for (const auto estimator : {drape::ContactForce::Impulse, drape::ContactForce::Energy, drape::ContactForce::SubForce})
    checkPinned(std::string("hammock/") + drape::toString(estimator) + "/" + scalar, hammockRun<S>(estimator));
}
