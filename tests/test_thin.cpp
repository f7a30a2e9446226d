// Faces catch solid features thinner than the vertex spacing (DESIGN 3): a rod or a thin box pushed up into
// a falling cloth, between two rows of vertices. Vertex contacts never see it; face contacts do.
#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <memory>

namespace {

constexpr double kSpacing = 0.02;
constexpr double kRodZ0 = -0.05;  // m, where the rod starts, below the cloth
constexpr double kRodSpeed = 1.0;  // m/s upward

/// Runs 0.3 s and returns how many vertices of the two rows beside the rod (y = +-1 cm) ended below its axis.
/// A cloth that caught the rod hangs over it, with those rows on top; one it passed through lies under it.
template <class S, class Shape>
int verticesBelowRod(const Shape& shape, drape::CollisionMethod method) {
  drape::GridDesc grid;
  grid.nx = 16;
  grid.ny = 16;
  grid.spacing = kSpacing;
  grid.placement.position = {0, 0, 0};
  auto asset = std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::grid(grid));
  drape::Settings settings;
  settings.collisionMethod = method;
  drape::Solver<S> solver(asset, settings);
  drape::Solid<Shape> rod;
  rod.shape = shape;
  rod.motion = drape::Motion::Kinematic;
  // Along x, midway between the two vertex rows at y = -0.01 and y = +0.01.
  rod.pose.rotation = Eigen::AngleAxisd(0.5 * 3.14159265358979, Eigen::Vector3d::UnitY());
  rod.pose.position = {0, 0, kRodZ0};
  if constexpr (std::is_same_v<Shape, drape::Box>) rod.pose.rotation.setIdentity();
  rod.linearVelocity = {0, 0, kRodSpeed};
  solver.addSolid(rod);
  const int frames = 18;
  for (int f = 0; f < frames; ++f) solver.step(1.0 / 60.0);
  const double rodZ = kRodZ0 + kRodSpeed * frames / 60.0;
  int below = 0, straddling = 0;
  for (drape::Index j : {grid.ny / 2 - 1, grid.ny / 2})  // the rows at y = -1 cm and +1 cm at rest
    for (drape::Index i = 3; i < grid.nx - 3; ++i) {
      const Eigen::Vector3d p = solver.position(j * grid.nx + i);
      REQUIRE(p.allFinite());
      ++straddling;
      below += p.z() < rodZ;
    }
  REQUIRE(straddling > 0);
  return below;
}

}  // namespace

TEMPLATE_TEST_CASE("a thin capsule between vertex rows: faces catch it, vertices let it through", "[thin]", float,
                   double) {
  drape::Capsule rod;
  rod.radius = 0.003;  // diameter 6 mm < half the 2 cm spacing; the 5 mm thickness leaves a gap at vertices
  rod.halfHeight = 0.3;
  CHECK(verticesBelowRod<TestType>(rod, drape::CollisionMethod::Improved) == 0);
  CHECK(verticesBelowRod<TestType>(rod, drape::CollisionMethod::Vertex) > 0);
}

TEMPLATE_TEST_CASE("a thin box between vertex rows: faces catch it, vertices let it through", "[thin]", float,
                   double) {
  drape::Box plate;
  plate.halfExtents = {0.3, 0.002, 0.002};  // 4 mm wide, along x
  CHECK(verticesBelowRod<TestType>(plate, drape::CollisionMethod::Improved) == 0);
  CHECK(verticesBelowRod<TestType>(plate, drape::CollisionMethod::Vertex) > 0);
}
