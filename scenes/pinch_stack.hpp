#pragma once
// A body pressed into the floor's cloth by another body on it (docs/design.md §6). A light box (4 x 4 x 2 cm,
// 19 g) rests on a 30 x 30 cloth (1 cm) lying on the floor; a heavier box of the same footprint (4 cm tall, 128 g)
// is dropped onto it from a height. The cloth under the light box is pinched between it and the floor and should
// hold it two thicknesses up (10 mm) whatever lands on it: the pinch's support stops the light box's own approach
// before the rigid world's substep, the push of the box on top comes in the world's solve after it, and the
// pinch's spacer (RigidWorld::addSpacer) holds it there. Shared by bench/pinch_stack and the tests.

#include <drape/drape.hpp>
#include <drape/coupling/rigid_world.hpp>

#include <rigid_rain.hpp>  // bodyPenetrationAtBodies

#include <algorithm>
#include <cmath>
#include <memory>

namespace drape::scenes {

struct PinchStack {
  static constexpr double kThickness = 0.005;  ///< m
  static constexpr double kHalf = 0.02;        ///< m, half the boxes' width
  static constexpr double kLowHalfHeight = 0.01, kTopHalfHeight = 0.02;
  static constexpr int kSide = 30;              ///< the cloth's vertices along each side
  static constexpr double kSpacing = 0.01;      ///< m
  static constexpr double kClothHalf = 0.5 * (kSide - 1) * kSpacing;  ///< m, half the cloth's width

  struct Reading {
    double lowestGap = 1e9;  ///< m, the light box's lowest corner above the floor while wholly over the cloth
    double finalGap = 0;     ///< m, at the end
    double deepest = 0;      ///< m, the deepest cloth vertex inside a box, read at the boxes' poses after each step
    double topSpeed = 0;     ///< m/s, the top box's speed when it lands (the largest over the run)
    double shift = 0;        ///< m, how far the light box ended from where it started, across the floor
    int stepsOff = 0;        ///< steps at whose end the light box was not wholly over the cloth
  };

  static Settings settings() {
    Settings s;
    s.thickness = kThickness;
    s.threadCount = 1;
    return s;
  }
  template <Scalar S> static std::shared_ptr<const ClothAsset<S>> asset() {
    SheetDesc sheet;
    sheet.nx = sheet.ny = kSide;
    sheet.spacing = kSpacing;
    sheet.placement.position = {0, 0, kThickness};
    return std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(sheet));
  }

  /// The lowest of a box's corners.
  static double lowestCorner(const RigidBody& body, const Eigen::Vector3d& half) {
    double low = 1e9;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d c((k & 1) ? half.x() : -half.x(), (k & 2) ? half.y() : -half.y(),
                              (k & 4) ? half.z() : -half.z());
      low = std::min(low, (body.pose().position + body.pose().rotation * c).z());
    }
    return low;
  }

  /// Drops the top box from `dropHeight` over `steps` steps of 0.01 s at the cloth's substeps, with `cloth` (made
  /// with settings() and asset()) on the floor; without a cloth (`cloth` null) the boxes alone on the world's
  /// ground, what the rigid world's own contacts leave. RigidSettings::iterationCount is `rigidIterations`.
  template <class Cloth> static Reading run(Cloth* cloth, double dropHeight, int rigidIterations, int steps = 100) {
    if (cloth) {
      Solid<Plane> floor;
      floor.staticFriction = floor.dynamicFriction = 0.5;
      cloth->addSolid(floor);
    }
    RigidSettings rigid;
    rigid.iterationCount = rigidIterations;
    RigidWorld world(rigid);  // its ground is the same floor
    const Eigen::Vector3d lowHalf(kHalf, kHalf, kLowHalfHeight), topHalf(kHalf, kHalf, kTopHalfHeight);
    BodyDesc low;
    low.shape = Box{lowHalf};
    low.density = 600;  // 19 g
    low.pose.position = {0.003, -0.002, (cloth ? 2 * kThickness : 0.0) + kLowHalfHeight + 0.001};
    const int a = world.add(low);
    BodyDesc top;
    top.shape = Box{topHalf};
    top.density = 2000;  // 128 g
    top.pose.position = low.pose.position + Eigen::Vector3d(0, 0, kLowHalfHeight + kTopHalfHeight + dropHeight);
    const int b = world.add(top);
    CouplingDesc coupling;
    coupling.staticFriction = coupling.dynamicFriction = 0.3;
    if (cloth) {
      addCoupledBody(*cloth, world, a, coupling);
      addCoupledBody(*cloth, world, b, coupling);
    }
    Reading r;
    for (int s = 0; s < steps; ++s) {
      if (cloth)
        stepCoupled(*cloth, world, 0.01);
      else
        world.step(0.01);
      // Only while the light box is wholly over the cloth: a box knocked to the cloth's edge tips off it.
      const Eigen::Vector3d at = world.body(a).pose().position;
      if (std::max(std::abs(at.x()), std::abs(at.y())) <= kClothHalf - kHalf * std::sqrt(2.0))
        r.lowestGap = std::min(r.lowestGap, lowestCorner(world.body(a), lowHalf));
      else
        ++r.stepsOff;
      if (cloth) r.deepest = std::max(r.deepest, bodyPenetrationAtBodies(*cloth, world));
      r.topSpeed = std::max(r.topSpeed, world.body(b).linearVelocity().norm());
    }
    r.finalGap = lowestCorner(world.body(a), lowHalf);
    r.shift = (world.body(a).pose().position - low.pose.position).head<2>().norm();
    return r;
  }
};

}  // namespace drape::scenes
