// Pinned state hashes on the GPU (llvmpipe through OSMesa, as ctest runs it): the slope and a coupled drop
// must end in exactly the bits recorded in state_hashes_gpu.inc (see tests/test_state_hashes.cpp). They hold
// for one Mesa build; DRAPE_PRINT_HASHES=1 prints the table, and a renderer other than llvmpipe skips the check.
#include "gpu_helpers.hpp"

#include "../coupling_helpers.hpp"
#include "../state_hash.hpp"

#include <drape/drape.hpp>
#include <drape/coupling/rigid_world.hpp>

#include <slope.hpp>

#include <catch2/catch.hpp>

#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>

namespace {

using drape::test::Fnv1a;
using drape::test::hex;

const std::map<std::string, std::uint64_t>& pinned() {
  static const std::map<std::string, std::uint64_t> table = {
#include "state_hashes_gpu.inc"
  };
  return table;
}

void checkPinned(const std::string& name, std::uint64_t hash) {
  if (const char* print = std::getenv("DRAPE_PRINT_HASHES"); print && *print && *print != '0') {
    std::cout << "{\"" << name << "\", " << hex(hash) << "ull},\n";  // a line of state_hashes_gpu.inc
    return;
  }
  const std::string& renderer = drape::test::gpuContext().renderer();
  if (renderer.find("llvmpipe") == std::string::npos) {
    WARN("renderer " << renderer << ": " << name << " is not compared with its llvmpipe hash");
    return;
  }
  const auto it = pinned().find(name);
  INFO("run " << name << " ended in state hash " << hex(hash));
  REQUIRE(it != pinned().end());
  CHECK(hex(hash) == hex(it->second));
}

template <class Solver> void requireFinite(const Solver& solver) {
  for (drape::Index i = 0; i < solver.vertexCount(); ++i) {
    REQUIRE(solver.position(i).allFinite());
    REQUIRE(solver.velocity(i).allFinite());
  }
}

}  // namespace

TEST_CASE("pinned state hashes on the GPU: the slope at 2 and 10 substeps", "[gpu][hashes]") {
  for (const int subSteps : {2, 10}) {
    drape::scenes::SlopeConfig c;
    c.nx = 20;
    c.ny = 30;
    c.friction = 0.2;
    c.subSteps = subSteps;
    const auto parts = drape::scenes::slopeParts<float>(c);
    drape::gpu::Solver gpu(drape::test::gpuContext(), parts.asset, parts.settings, c.areaDensity);
    gpu.addSolid(parts.slope);
    for (int f = 0; f < 45; ++f) gpu.step(c.dt);
    requireFinite(gpu);
    checkPinned("gpu/slope/" + std::to_string(subSteps), drape::test::hashState(gpu.state()));
  }
}

TEST_CASE("pinned state hashes on the GPU: a ball dropped into a hammock (two-way coupling)", "[gpu][hashes]") {
  drape::gpu::Solver cloth(drape::test::gpuContext(), drape::test::squareCloth<float>(21, 0.02, 0.0));
  for (drape::Index corner : {0, 20, 420, 440}) cloth.pin(corner);
  drape::RigidSettings rigid;  // gravity, no ground: the cloth holds the ball
  rigid.ground = false;
  drape::RigidWorld world(rigid);
  drape::BodyDesc ball;
  ball.shape = drape::Sphere{0.05};
  ball.pose.position = {0.02, -0.01, 0.12};
  ball.linearVelocity = {0, 0, -1};
  ball.density = 300;
  const int b = world.add(ball);
  drape::CouplingDesc coupling;
  coupling.staticFriction = coupling.dynamicFriction = 0.3;
  drape::addCoupledBody(cloth, world, b, coupling);
  for (int s = 0; s < 40; ++s) drape::stepCoupled(cloth, world, 0.01);
  requireFinite(cloth);
  Fnv1a f;
  drape::test::addState(f, cloth.state());
  const drape::RigidBody& body = world.body(b);
  f.addVector(body.pose().position);
  f.addVector(body.pose().rotation.coeffs());
  f.addVector(body.linearVelocity());
  f.addVector(body.angularVelocity());
  checkPinned("gpu/hammock", f.value());
}
