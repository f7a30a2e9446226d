#pragma once
// A cloth pinched between the floor and a box lower than twice the thickness (docs/design.md §16, Known limits):
// a 21x21 cloth (2 cm) lying on the floor under a 0.16 m box whose bottom is 1.6-1.9 thicknesses up. Under the
// box no position satisfies both surfaces; the vertices just outside its bottom edges meet both the floor and the
// faces that touch the edge. The cloth starts at rest and nothing pulls it, so it should stay still.

#include <drape/drape.hpp>

#include <memory>

namespace drape::scenes {

/// The pinch with the box's bottom `gapInThicknesses` thicknesses up, both surfaces at `friction`, the box moved by
/// `shift` (m, in x and y) from the test's place, the collision method `method`.
template <class S>
Solver<S> makeLowPinch(double gapInThicknesses, double friction, const Eigen::Vector2d& shift = Eigen::Vector2d::Zero(),
                       CollisionMethod method = CollisionMethod::Faces) {
  Settings settings;
  settings.collisionMethod = method;
  SheetDesc grid;
  grid.nx = grid.ny = 21;
  grid.spacing = 0.02;
  grid.placement.position = {0, 0, settings.thickness};
  Solver<S> cloth(std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid)), settings);
  Solid<Plane> floor;
  floor.staticFriction = floor.dynamicFriction = friction;
  cloth.addSolid(floor);
  Solid<Box> box;
  box.shape.halfExtents = {0.08, 0.08, 0.04};
  box.pose.position = {0.005 + shift.x(), -0.003 + shift.y(), gapInThicknesses * settings.thickness + 0.04};
  box.staticFriction = box.dynamicFriction = friction;
  cloth.addSolid(box);
  return cloth;
}

}  // namespace drape::scenes
