#pragma once
// A long box pressed edge first onto a cloth lying on the floor (docs/design.md §4, "Friction and the planes"):
// a 20x20 cloth (2 cm) a thickness above the floor (friction 0.5), and a kinematic 0.6 x 0.1 x 0.1 m box (friction
// 0.3) turned about its length, coming down at 1 m/s from 10 cm and stopping with its lowest edge `gap` above the
// floor. Its sloping sides' friction and pushes press the cloth beside the edge toward the floor.

#include <drape/drape.hpp>

#include <cmath>

namespace drape::scenes {

/// The cloth's sheet, for a solver of the given thickness.
inline SheetDesc edgePressSheet(double thickness) {
  SheetDesc grid;
  grid.nx = grid.ny = 20;
  grid.spacing = 0.02;
  grid.placement.position = {0, 0, thickness};
  return grid;
}

/// Adds the floor and the box turned `tilt` radians to `cloth` (made from edgePressSheet), then runs 60 frames of
/// 1/60 s: `frame(cloth, dt)` steps the cloth, then the box is moved down, and held once its edge is `gap` up.
template <class Cloth, class Frame> void pressEdgeFirst(Cloth& cloth, double tilt, double gap, Frame&& frame) {
  Solid<Plane> floor;
  floor.staticFriction = floor.dynamicFriction = 0.5;
  cloth.addSolid(floor);
  Solid<Box> box;
  box.shape.halfExtents = {0.3, 0.05, 0.05};
  box.motion = Motion::Kinematic;
  box.staticFriction = box.dynamicFriction = 0.3;
  const double speed = 1, dt = 1.0 / 60;
  box.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()));
  const double low = 0.05 * (std::cos(tilt) + std::sin(tilt));  // from the box's centre down to its lowest edge
  box.pose.position = {0, 0, 0.1 + low};
  box.linearVelocity = {0, 0, -speed};
  const Index k = cloth.addSolid(box);
  for (int f = 0; f < 60; ++f) {
    frame(cloth, dt);
    box.pose.position.z() -= speed * dt;
    if (box.pose.position.z() - low <= gap) {
      box.pose.position.z() = gap + low;
      box.linearVelocity.setZero();
    }
    cloth.setSolid(k, box);
  }
}

}  // namespace drape::scenes
