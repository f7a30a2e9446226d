// Kinematic solids: the contact velocity v_c = v + w x (x - x_r) drives friction and the velocity split.
#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <memory>

namespace {

template <class S> drape::Solver<S> clothOnFloor(const drape::Solid<drape::Plane>& floor) {
  drape::SheetDesc grid;
  grid.nx = grid.ny = 10;
  grid.spacing = 0.02;
  grid.placement.position = {0, 0, 0.005};  // resting at the thickness
  auto asset = std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid));
  drape::Solver<S> solver(asset);
  solver.addSolid(floor);
  return solver;
}

}  // namespace

TEMPLATE_TEST_CASE("a sliding floor carries a cloth by friction and not without it", "[kinematic]", float, double) {
  drape::Solid<drape::Plane> floor;
  floor.motion = drape::Motion::Kinematic;
  floor.linearVelocity = {0.5, 0, 0};  // sliding in its own plane: the surface stays at z = 0
  SECTION("sticky floor: the cloth moves with it") {
    floor.staticFriction = floor.dynamicFriction = 1.0;
    auto solver = clothOnFloor<TestType>(floor);
    for (int f = 0; f < 60; ++f) solver.step(1.0 / 60.0);
    for (drape::Index i = 0; i < solver.vertexCount(); ++i) {
      CHECK(solver.velocity(i).x() == Approx(0.5).margin(1e-4));
      CHECK(solver.position(i).z() == Approx(0.005).margin(1e-5));
    }
  }
  SECTION("frictionless floor: the cloth stays where it is") {
    auto solver = clothOnFloor<TestType>(floor);
    const Eigen::Vector3d before = solver.position(0);
    for (int f = 0; f < 60; ++f) solver.step(1.0 / 60.0);
    CHECK((solver.position(0) - before).norm() < 1e-5);
  }
}

TEMPLATE_TEST_CASE("a turntable spins a sticky cloth at w x r", "[kinematic]", float, double) {
  drape::Solid<drape::Plane> table;
  table.motion = drape::Motion::Kinematic;
  table.angularVelocity = {0, 0, 2.0};  // rad/s about the world z axis through the frame origin
  table.staticFriction = table.dynamicFriction = 1.0;
  auto solver = clothOnFloor<TestType>(table);
  for (int f = 0; f < 60; ++f) solver.step(1.0 / 60.0);
  for (drape::Index i = 0; i < solver.vertexCount(); ++i) {
    const Eigen::Vector3d p = solver.position(i);
    const Eigen::Vector3d expected = Eigen::Vector3d(0, 0, 2.0).cross(Eigen::Vector3d(p.x(), p.y(), 0));
    CHECK((solver.velocity(i) - expected).norm() < 1e-3);
  }
}
