// The consumer's GPU program (drape::gpu through the install): a cloth dropped on a floor on the GPU comes to rest
// at the thickness above it, as the CPU consumer's does. Exits 77 (skipped) when no GL context can be made.
#include <drape/drape.hpp>
#include <drape/gpu/context.hpp>
#include <drape/gpu/solver.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

int main() {
  std::optional<drape::gpu::Context> context;
  try {
    context.emplace();
  } catch (const drape::Error& e) {
    std::printf("consumer_gpu: skipped: no GL context (%s)\n", e.what());
    return 77;
  }
  drape::SheetDesc grid;
  grid.nx = grid.ny = 8;
  grid.spacing = 0.05;
  grid.placement.position = {0, 0, 0.1};
  auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(grid));
  drape::gpu::Solver solver(*context, asset);
  solver.addSolid(drape::Solid<drape::Plane>{});
  for (int frame = 0; frame < 60; ++frame) solver.step(1.0 / 60.0);
  const double z = solver.position(0).z();
  std::printf("consumer_gpu (%s): corner height %.6f m\n", context->renderer().c_str(), z);
  return std::abs(z - solver.settings().thickness) < 1e-4 ? 0 : 1;
}
