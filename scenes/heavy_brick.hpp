#pragma once
// The heavy brick of the cloth-rigid coupling thesis's Fig 6.4: a cloth lies on the floor, a kinematic brick
// comes down on it and presses it to the floor (its bottom `squeeze` thicknesses above the floor, so the cloth under
// it is pinched), and then one edge of the cloth is pulled sideways at constant speed so the cloth is drawn out
// from under the brick against friction on both sides. Shared by samples/heavy_brick and its ctest.

#include <drape/drape.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <vector>

namespace drape::scenes {

struct BrickConfig {
  int nx = 30, ny = 20;          ///< cloth vertices along x (the pull) and y
  double spacing = 0.02;         ///< m
  Eigen::Vector3d brickHalf{0.1, 0.25, 0.05};  ///< m; wider than the cloth along y
  double brickX = -0.06;         ///< m, the brick's centre along x (the cloth is centred on the origin)
  double squeeze = 1.8;          ///< brick bottom above the floor when pressing, in thicknesses (< 2 pinches)
  double dropSpeed = 0.5;        ///< m/s the brick comes down at
  double pullSpeed = 0.3;        ///< m/s of the pulled edge (+x)
  double settle = 0.1;           ///< s before the brick moves
  double hold = 0.2;             ///< s the brick presses before the pull
  double pull = 1.2;             ///< s of pulling
  double friction = 0.3;         ///< static and dynamic, brick and floor alike
  double dt = 1.0 / 60;
  int subSteps = 10;
  int iterations = 1;
  Settings base{};  ///< cloth settings besides subStepCount and iterationCount
};

struct BrickResult {
  int vertices = 0, frames = 0;
  double underAtStart = 0, underAtEnd = 0;  ///< share of the cloth's vertices under the brick's footprint
  double pulled = 0;                        ///< m the edge moved
  double maxFloorPenetration = 0;           ///< m, deepest vertex below the floor (any substep)
  double maxBrickPenetration = 0;           ///< m, deepest vertex inside the brick (any substep)
  double maxSpeed = 0;                      ///< m/s of any free vertex (any substep)
  double tremblingRms = 0;                  ///< m/s, RMS vertical velocity of the pinched vertices while pulled
  double maxStrain = 0;                     ///< largest edge strain at the end of a frame
  double msPerFrame = 0;                    ///< median wall time of a frame
  bool finite = true;
};

template <Scalar S> BrickResult runHeavyBrick(const BrickConfig& c) {
  SheetDesc grid;
  grid.nx = c.nx;
  grid.ny = c.ny;
  grid.spacing = c.spacing;
  Settings settings = c.base;
  settings.subStepCount = c.subSteps;
  settings.iterationCount = c.iterations;
  const double thickness = settings.thickness;
  grid.placement.position = {0, 0, thickness};
  auto asset = std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid));
  Solver<S> cloth(asset, settings);
  Solid<Plane> floor;
  floor.staticFriction = floor.dynamicFriction = c.friction;
  cloth.addSolid(floor);
  Solid<Box> brick;
  brick.shape.halfExtents = c.brickHalf;
  const double startBottom = 2 * thickness + 0.05, pressBottom = c.squeeze * thickness;
  brick.pose.position = {c.brickX, 0, startBottom + c.brickHalf.z()};
  brick.motion = Motion::Kinematic;
  brick.staticFriction = brick.dynamicFriction = c.friction;
  const Index brickIndex = cloth.addSolid(brick);

  // The pulled edge: the column at the largest x, following its targets exactly.
  std::vector<Index> edge;
  std::vector<Index> pins;
  for (Index j = 0; j < c.ny; ++j) {
    const Index i = j * c.nx + (c.nx - 1);
    edge.push_back(i);
    cloth.pin(i);
    pins.push_back(cloth.attach(i, cloth.position(i)));
  }
  std::vector<Eigen::Vector3d> targets;
  for (Index i : edge) targets.push_back(cloth.position(i));

  auto underBrick = [&](const Eigen::Vector3d& p) {
    return std::abs(p.x() - c.brickX) <= c.brickHalf.x() && std::abs(p.y()) <= c.brickHalf.y();
  };
  auto shareUnder = [&]() {
    int n = 0;
    for (Index i = 0; i < cloth.vertexCount(); ++i) n += underBrick(cloth.position(i)) ? 1 : 0;
    return double(n) / double(cloth.vertexCount());
  };

  BrickResult r;
  r.vertices = cloth.vertexCount();
  const double dropTime = (startBottom - pressBottom) / c.dropSpeed;
  const double total = c.settle + dropTime + c.hold + c.pull;
  r.frames = int(std::ceil(total / c.dt));
  double sumV2 = 0;
  std::int64_t samples = 0;
  std::vector<double> ms;
  bool pulling = false;
  for (int f = 0; f < r.frames; ++f) {
    const double t = f * c.dt;
    // The brick: still, coming down, or pressing where it stopped.
    Solid<Box> b = cloth.template solid<Box>(brickIndex);
    const bool dropping = t >= c.settle && t < c.settle + dropTime;
    if (dropping) {
      b.pose.position.z() = startBottom - (t - c.settle) * c.dropSpeed + c.brickHalf.z();
      b.linearVelocity = {0, 0, -c.dropSpeed};
      // Stop exactly at the pressing height at the end of this frame.
      const double end = std::max(pressBottom + c.brickHalf.z(), b.pose.position.z() - c.dropSpeed * c.dt);
      b.linearVelocity.z() = (end - b.pose.position.z()) / c.dt;
    } else {
      if (t >= c.settle) b.pose.position.z() = pressBottom + c.brickHalf.z();
      b.linearVelocity.setZero();
    }
    b.motion = b.linearVelocity.isZero(0) ? Motion::Static : Motion::Kinematic;
    cloth.setSolid(brickIndex, b);
    if (t == 0) r.underAtStart = shareUnder();
    pulling = t >= c.settle + dropTime + c.hold;
    if (pulling) {
      for (std::size_t k = 0; k < edge.size(); ++k) {
        targets[k].x() += c.pullSpeed * c.dt;
        cloth.setPinTarget(pins[k], targets[k]);
      }
      r.pulled += c.pullSpeed * c.dt;
    }
    const auto start = std::chrono::steady_clock::now();
    cloth.step(c.dt, [&](const Solver<S>& s) {
      const Eigen::Vector3d brickCentre = s.template solid<Box>(brickIndex).pose.position;
      for (Index i = 0; i < s.vertexCount(); ++i) {
        const Eigen::Vector3d p = s.position(i), v = s.velocity(i);
        if (!p.allFinite() || !v.allFinite()) r.finite = false;
        r.maxFloorPenetration = std::max(r.maxFloorPenetration, -p.z());
        const Eigen::Vector3d q = (p - brickCentre).cwiseAbs() - c.brickHalf;
        if ((q.array() < 0).all()) r.maxBrickPenetration = std::max(r.maxBrickPenetration, -q.maxCoeff());
        if (s.state().invMass[i] > 0) r.maxSpeed = std::max(r.maxSpeed, v.norm());
        if (pulling && underBrick(p)) {
          sumV2 += v.z() * v.z();
          ++samples;
        }
      }
    });
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    for (const auto& e : asset->edges) {
      const double rest = double((asset->restPositions[e[1]] - asset->restPositions[e[0]]).norm());
      r.maxStrain = std::max(r.maxStrain, (cloth.position(e[1]) - cloth.position(e[0])).norm() / rest - 1);
    }
  }
  r.underAtEnd = shareUnder();
  r.tremblingRms = samples > 0 ? std::sqrt(sumV2 / double(samples)) : 0;
  std::nth_element(ms.begin(), ms.begin() + ms.size() / 2, ms.end());
  r.msPerFrame = ms[ms.size() / 2];
  return r;
}

}  // namespace drape::scenes
