// Faces catch solid features thinner than the vertex spacing (docs/design.md §3): a rod or a thin box pushed up
// into a falling cloth, between two rows of vertices. Vertex contacts never see it; face contacts do.
#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <low_pinch.hpp>
#include <rest_scenes.hpp>

#include <memory>
#include <vector>

namespace {

constexpr double kSpacing = 0.02;
constexpr double kRodZ0 = -0.05;  // m, where the rod starts, below the cloth
constexpr double kRodSpeed = 1.0;  // m/s upward

/// Runs 0.3 s and returns how many vertices of the two rows beside the rod (y = +-1 cm) ended below its axis.
/// A cloth that caught the rod hangs over it, with those rows on top; one it passed through lies under it.
template <class S, class Shape>
int verticesBelowRod(const Shape& shape, drape::CollisionMethod method) {
  drape::SheetDesc grid;
  grid.nx = 16;
  grid.ny = 16;
  grid.spacing = kSpacing;
  grid.placement.position = {0, 0, 0};
  auto asset = std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid));
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
  CHECK(verticesBelowRod<TestType>(rod, drape::CollisionMethod::Faces) == 0);
  CHECK(verticesBelowRod<TestType>(rod, drape::CollisionMethod::Vertices) > 0);
}

TEMPLATE_TEST_CASE("a thin box between vertex rows: faces catch it, vertices let it through", "[thin]", float,
                   double) {
  drape::Box plate;
  plate.halfExtents = {0.3, 0.002, 0.002};  // 4 mm wide, along x
  CHECK(verticesBelowRod<TestType>(plate, drape::CollisionMethod::Faces) == 0);
  CHECK(verticesBelowRod<TestType>(plate, drape::CollisionMethod::Vertices) > 0);
}

TEMPLATE_TEST_CASE("a cloth pinched between the floor and a box lower than twice the thickness holds still",
                   "[thin][pinch]", float, double) {
  using S = TestType;
  // A 0.4 m cloth on the floor under a 0.16 m box whose bottom is 1.6-1.9 thicknesses up: under the box no
  // position satisfies both surfaces, so the pinched vertices take the least-squares compromise. The rim
  // vertices' faces touch the box's bottom edges and record slightly tilted normals there, nearly facing the
  // floor's. When that compromise was found by gradient steps toward where the two planes meet (far off to the
  // side), each substep moved the rim sideways by the tilt times the violations, and the constraint solve turned
  // it into velocity: the fastest vertex over the last half second was at 0.18-0.32 m/s (double) and
  // 0.36-1.21 m/s (float). Along the well-determined directions only, frictionless, it is at 0.8-2.1 mm/s: the
  // whole cloth still slides, smoothly, on what the first squeeze gave it (nothing frictionless takes that
  // away). With friction the pinched cloth is at rest (at most 4e-6 m/s measured; 1e-3 is asserted). The test
  // below asserts it from 16 places of the box within 1 cm of this one.
  const double friction = GENERATE(0.0, 0.5);
  const double thickness = drape::Settings{}.thickness;
  for (const double gapInThicknesses : {1.9, 1.8, 1.6}) {
    drape::Solver<S> cloth = drape::scenes::makeLowPinch<S>(gapInThicknesses, friction);
    double fastest = 0, lowest = 1e9, highest = -1e9;
    for (int s = 0; s < 100; ++s) {
      cloth.step(0.01);
      for (drape::Index i = 0; i < cloth.vertexCount(); ++i) {
        REQUIRE(std::isfinite(cloth.position(i).z()));
        if (s >= 50) fastest = std::max(fastest, cloth.velocity(i).norm());
        lowest = std::min(lowest, cloth.position(i).z());
        highest = std::max(highest, cloth.position(i).z());
      }
    }
    INFO("friction " << friction << ", gap " << gapInThicknesses << " thicknesses: fastest vertex " << fastest
                     << " m/s over the last 0.5 s, z in [" << lowest << ", " << highest << "] m");
    CHECK(fastest <= (friction > 0 ? 1e-3 : 5e-3));
    CHECK(lowest >= 0);                // never through the floor
    CHECK(highest <= 3 * thickness);  // nor thrown up
  }
}

TEMPLATE_TEST_CASE("a cloth pinched under a low box with friction holds still from every place of the box",
                   "[thin][pinch]", float, double) {
  using S = TestType;
  // The same pinch with the box moved within 1 cm in x and y (bench/pinch_drift.cpp). A rim face lying level
  // along the box's bottom edge is equally deep along a segment of that edge, and the face search ended at either
  // end of it as the substep's rounding fell: pushed from one end the face moved its outer corner down into the
  // floor's thickness, from the other it did not, so the corner went down and up every other substep and kept
  // the solve's pull as velocity (0.08 m/s in float at 1.9 thicknesses, 0.025 m/s at 1.8, from one place each).
  // A face in contact now keeps the point it was pushed from while that point is as deep as the search's
  // (docs/design.md §3, "Ties between deepest points"). Both readings are asserted: the speed at the frames'
  // ends, and each vertex's move from one frame to the next, which sees a cycle the speed at a frame's end misses.
  // At 1.6 thicknesses one place of 16 kept a fold of free cloth beside the box swinging (8e-3 to 1.1e-2 m/s) until
  // the settle's exact points were judged by the fields (docs/design.md §16, "Exact points tested").
  for (const double gapInThicknesses : {1.9, 1.8, 1.6}) {
    for (int place = 0; place < 16; ++place) {
      drape::Solver<S> cloth = drape::scenes::makeLowPinch<S>(gapInThicknesses, 0.5, drape::scenes::shiftOf(place));
      constexpr double dt = 0.01;
      double fastest = 0, moving = 0;
      std::vector<Eigen::Vector3d> last(std::size_t(cloth.vertexCount()));
      for (int s = 0; s < 100; ++s) {
        cloth.step(dt);
        for (drape::Index i = 0; i < cloth.vertexCount(); ++i) {
          const Eigen::Vector3d p = cloth.position(i);
          if (s >= 50) {
            fastest = std::max(fastest, cloth.velocity(i).norm());
            moving = std::max(moving, (p - last[std::size_t(i)]).norm() / dt);
          }
          last[std::size_t(i)] = p;
        }
      }
      INFO("gap " << gapInThicknesses << " thicknesses, place " << place << ": fastest vertex " << fastest
                  << " m/s, fastest move between frames " << moving << " m/s over the last 0.5 s");
      CHECK(fastest <= 1e-3);
      CHECK(moving <= 1e-3);
    }
  }
}
