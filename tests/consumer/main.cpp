// A cloth dropped on a floor comes to rest at the thickness above it. The solver declares the floor's shape
// alone (a scene pays for what it declares), which also compiles in less than half the time of drape::Solver's
// every shape: this program checks the packaging, and drape::Solver is compiled by the tests.
#include <drape/drape.hpp>

#include <cstdio>
#include <memory>

int main() {
  drape::SheetDesc grid;
  grid.nx = grid.ny = 8;
  grid.spacing = 0.05;
  grid.placement.position = {0, 0, 0.1};
  auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(grid));
  drape::BasicSolver<float, drape::Plane> solver(asset);
  solver.addSolid(drape::Solid<drape::Plane>{});
  for (int frame = 0; frame < 60; ++frame) solver.step(1.0 / 60.0);
  const double z = solver.position(0).z();
  std::printf("corner height %.6f m\n", z);
  return std::abs(z - solver.settings().thickness) < 1e-4 ? 0 : 1;
}
