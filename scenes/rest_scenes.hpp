#pragma once
// Scenes where a cloth should come to rest on a solid and drape's contacts find that hardest (docs/design.md,
// Known limits): a 40x40 cloth (2 cm) on a ridge (the slope sample's box turned 45 degrees, an edge on top), on a
// cube standing on a corner, on a 3 mm rod (a capsule, continuous contact on) and on a 0.2 m ball, all at mu 0.5.
// Each comes with the solid's distance field, to tell the vertices near it from the free skirt.

#include <drape/drape.hpp>

#include <slope.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>
#include <vector>

namespace drape::scenes {

enum class RestScene { Ridge, Corner, Rod, Ball };
inline const char* name(RestScene s) {
  switch (s) {
    case RestScene::Ridge: return "ridge";
    case RestScene::Corner: return "cube corner";
    case RestScene::Rod: return "3 mm rod";
    case RestScene::Ball: return "ball";
  }
  return "";
}

using Distance = std::function<double(const Eigen::Vector3d&)>;

/// Placement k's shift of a scene's start (m): none for the first, then the points of an additive recurrence
/// (the plastic number's, which spreads points evenly in the square) over a 2 cm cell centred on the start.
inline Eigen::Vector2d shiftOf(int k) {
  if (k == 0) return Eigen::Vector2d::Zero();
  const double a = 0.7548776662466927, b = 0.5698402909980532;
  auto frac = [](double v) { return v - std::floor(v); };
  return 0.02 * Eigen::Vector2d(frac(0.5 + k * a), frac(0.5 + k * b)) - Eigen::Vector2d(0.01, 0.01);
}

/// The RMS speed of the vertices within `reach` of the solid whose distance field is `distance` (0 if none is).
template <class S> double rmsSpeedNear(const Solver<S>& solver, const Distance& distance, double reach) {
  double sum = 0;
  int count = 0;
  for (Index i = 0; i < solver.vertexCount(); ++i)
    if (distance(solver.position(i)) <= reach) sum += solver.velocity(i).squaredNorm(), ++count;
  return count > 0 ? std::sqrt(sum / count) : 0.0;
}
/// The RMS speed of all vertices.
template <class S> double rmsSpeed(const Solver<S>& solver) {
  return rmsSpeedNear(solver, [](const Eigen::Vector3d&) { return 0.0; }, 0.0);
}

/// At most this span over a second at the frames' ends (m), a cloth is still where a viewer sees it: the rest
/// tests' speed bound, 1e-4 m/s, kept for a second by one vertex (FrameSpan).
inline constexpr double kStillSpan = 1e-4;

/// The largest distance a vertex spans at the frames' ends over a window of frames (the diagonal of the box its
/// positions fill): what a viewer sees move. A speed read at a frame's end reads a cycle of the substeps that
/// returns within the frame, and can catch a cycle that spans frames at a still moment; a span sees the second
/// and not the first.
class FrameSpan {
 public:
  /// Adds the positions at a frame's end; the first call (after clear) opens the window.
  template <class S> void add(const Solver<S>& solver) {
    const bool first = low_.empty();
    low_.resize(std::size_t(solver.vertexCount()));
    high_.resize(low_.size());
    for (Index i = 0; i < solver.vertexCount(); ++i) {
      const Eigen::Vector3d p = solver.position(i);
      const std::size_t k = std::size_t(i);
      low_[k] = first ? p : Eigen::Vector3d(low_[k].cwiseMin(p));
      high_[k] = first ? p : Eigen::Vector3d(high_[k].cwiseMax(p));
    }
  }
  void clear() {
    low_.clear();
    high_.clear();
  }
  /// The largest span over the window so far (m).
  double largest() const {
    double most = 0;
    for (std::size_t k = 0; k < low_.size(); ++k) most = std::max(most, (high_[k] - low_[k]).norm());
    return most;
  }

 private:
  std::vector<Eigen::Vector3d> low_, high_;
};

/// The solid's distance field, in double, at the world origin.
template <class Shape> Distance fieldOf(const Solid<Shape>& solid) {
  const Sdf<Shape, double> sdf = detail::compileSdf<double>(solid.shape, solid.pose, Eigen::Vector3d::Zero());
  return [sdf](const Eigen::Vector3d& x) {
    Eigen::Vector3d n;
    return sdf(x, n);
  };
}

/// The scene's cloth and solid in a solver with the given method and substeps (the rest of Settings at its
/// defaults), and in `distance` the solid's field. `shift` moves the cloth's start in x and y (m).
template <class S>
Solver<S> makeRestScene(RestScene scene, CollisionMethod method, int substeps, Distance& distance,
                        const Eigen::Vector2d& shift = Eigen::Vector2d::Zero()) {
  constexpr double kFriction = 0.5;
  if (scene == RestScene::Ridge) {  // the slope sample's ridge: inclined_plane --ridge --nx 40 --ny 40
    SlopeConfig c;
    c.ridge = true;
    c.friction = kFriction;
    c.nx = c.ny = 40;
    c.subSteps = substeps;
    c.method = method;
    c.shift = shift;
    distance = fieldOf(slopeParts<S>(c).ridge);
    return makeSlope<S>(c);
  }
  Settings settings;
  settings.collisionMethod = method;
  settings.subStepCount = substeps;
  settings.continuousContact = scene == RestScene::Rod;  // at 2 substeps the rod is tunnelled without it
  SheetDesc sheet;
  sheet.nx = sheet.ny = 40;
  sheet.spacing = 0.02;
  // Off-centre by part of a cell, so no vertex sits exactly on the top of the solid.
  sheet.placement.position = {0.01 + shift.x(), -0.02 + shift.y(),
                              scene == RestScene::Ball ? 0.21 : scene == RestScene::Rod ? 0.1 : 0.0};
  Solver<S> solver(std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(sheet)), settings);
  if (scene == RestScene::Corner) {  // a 0.4 m cube, the diagonal through one corner vertical, that corner 1 cm below
    Solid<Box> cube;
    cube.shape.halfExtents = {0.2, 0.2, 0.2};
    cube.pose.rotation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d::UnitZ());
    cube.pose.position = {0, 0, -0.2 * std::numbers::sqrt3 - 0.01};
    cube.staticFriction = cube.dynamicFriction = kFriction;
    solver.addSolid(cube);
    distance = fieldOf(cube);
  } else if (scene == RestScene::Rod) {  // along x at height 0
    Solid<Capsule> rod;
    rod.shape.radius = 0.003;
    rod.shape.halfHeight = 1.0;
    rod.pose.rotation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX());
    rod.staticFriction = rod.dynamicFriction = kFriction;
    solver.addSolid(rod);
    distance = fieldOf(rod);
  } else {
    Solid<Sphere> ball;
    ball.shape.radius = 0.2;
    ball.staticFriction = ball.dynamicFriction = kFriction;
    solver.addSolid(ball);
    distance = fieldOf(ball);
  }
  return solver;
}

}  // namespace drape::scenes
