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

using drape::test::hex;
using drape::test::requireFinite;

const drape::test::PinnedHashes kPinned = {
#include "state_hashes_gpu.inc"
};

void checkPinned(const std::string& name, std::uint64_t hash) {
  const std::string& renderer = drape::test::gpuContext().renderer();
  const bool llvmpipe = renderer.find("llvmpipe") != std::string::npos;
  drape::test::checkPinned(kPinned, name, hash, llvmpipe ? "" : "renderer " + renderer + ", not llvmpipe");
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
  drape::RigidWorld world(drape::test::noGround());
  drape::test::dropIntoHammock(cloth, world, 40);
  checkPinned("gpu/hammock", drape::test::hashClothAndBodies(cloth, world));
}
