#pragma once
// What the coupling tests share, on the CPU (test_coupling.cpp) and the GPU (gpu/test_coupling.cpp): a square
// cloth, the cloth's momentum, and a rigid world in empty space.

#include <drape/drape.hpp>
#include <drape/coupling/rigid_world.hpp>
#include <drape/rigid/world.hpp>

#include "rigid_rain.hpp"  // bodyPenetrationAtBodies

#include <algorithm>
#include <array>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace drape::test {

/// An n x n grid cloth, `spacing` apart, at height z.
template <class S> std::shared_ptr<const ClothAsset<S>> squareCloth(int n, double spacing, double z) {
  SheetDesc grid;
  grid.nx = grid.ny = n;
  grid.spacing = spacing;
  grid.placement.position = {0, 0, z};
  return std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid));
}

/// The cloth's linear momentum (kg m/s): its free vertices' masses times their velocities.
template <class Cloth> Eigen::Vector3d clothMomentum(const Cloth& cloth) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  const auto& state = cloth.state();
  for (Index i = 0; i < cloth.vertexCount(); ++i)
    if (state.invMass[std::size_t(i)] > 0)
      p += state.v[std::size_t(i)].template cast<double>() / double(state.invMass[std::size_t(i)]);
  return p;
}

/// A rigid world in empty space: no gravity, no ground.
/// Drops a ball (radius 5 cm, density 300, at 1 m/s) into `cloth`, a 21 x 21 square of 2 cm pinned at its
/// corners, coupled with friction 0.3 to a body of `world` (which should have gravity and no ground), and runs
/// `steps` coupled steps of 0.01 s: the pinned state hashes' hammock.
template <class Cloth> void dropIntoHammock(Cloth& cloth, RigidWorld& world, int steps) {
  for (Index corner : {0, 20, 420, 440}) cloth.pin(corner);
  BodyDesc ball;
  ball.shape = Sphere{0.05};
  ball.pose.position = {0.02, -0.01, 0.12};
  ball.linearVelocity = {0, 0, -1};
  ball.density = 300;
  const int b = world.add(ball);
  CouplingDesc coupling;
  coupling.staticFriction = coupling.dynamicFriction = 0.3;
  addCoupledBody(cloth, world, b, coupling);
  for (int s = 0; s < steps; ++s) stepCoupled(cloth, world, 0.01);
}

/// The kinetic energy of the cloth's free vertices and the world's dynamic bodies (J).
template <class Cloth> double kineticEnergy(const Cloth& cloth, const RigidWorld& world) {
  double e = world.kineticEnergy();
  const auto& state = cloth.state();
  for (Index i = 0; i < cloth.vertexCount(); ++i)
    if (state.invMass[std::size_t(i)] > 0)
      e += 0.5 * state.v[std::size_t(i)].template cast<double>().squaredNorm() / double(state.invMass[std::size_t(i)]);
  return e;
}

/// Two 0.064 g boxes side by side, 2 mm apart, their tops tilted 20 degrees into a V, rising at 2 m/s into
/// `cloth` (a cloth at z = 0 in empty space), coupled to it: the vertices over the gap touch both. Returns the
/// cloth's index of each box's body (a slot's ContactSlot::body), which is the world's here.
template <class Cloth> std::array<int, 2> pressTwoBoxes(Cloth& cloth, RigidWorld& world) {
  std::array<int, 2> boxes{};
  for (std::size_t k = 0; k < 2; ++k) {
    const double x = k == 0 ? -0.021 : 0.021;
    BodyDesc box;
    box.shape = Box{Eigen::Vector3d(0.02, 0.04, 0.01)};
    box.pose.position = {x + 0.004, -0.003, -0.05};
    box.pose.rotation = Eigen::AngleAxisd(x > 0 ? 0.35 : -0.35, Eigen::Vector3d::UnitY());
    box.linearVelocity = {0, 0, 2};
    box.density = 1;
    boxes[k] = world.add(box);
    addCoupledBody(cloth, world, boxes[k]);
  }
  return boxes;
}

/// A ball pressing a cloth onto a box, both rigid bodies: the cloth (`sheet()`, with `thickness` 5 mm) lies on a
/// 30 x 30 x 10 cm box resting on the world's ground, and a 3 cm ball lands on it at 0.5 m/s. The vertices under
/// the ball are pinched between the two bodies.
struct BallOnBox {
  static constexpr double r = 0.03, thickness = 0.005, half = 0.05;  ///< the ball's radius, the box's half height
  int box = -1, ball = -1;
  /// The cloth: 21 x 21 vertices 1 cm apart, lying on the box's top.
  static SheetDesc sheet() {
    SheetDesc grid;
    grid.nx = grid.ny = 21;
    grid.spacing = 0.01;
    grid.placement.position = {0, 0, 2 * half + thickness};
    return grid;
  }
  template <class Cloth> BallOnBox(Cloth& cloth, RigidWorld& world) {
    BodyDesc under;
    under.shape = Box{{0.15, 0.15, half}};
    under.pose.position = {0, 0, half};
    under.density = 500;
    box = world.add(under);
    BodyDesc falling;
    falling.shape = Sphere{r};
    falling.pose.position = {0.002, -0.001, 2 * half + 2 * thickness + r + 0.002};
    falling.linearVelocity = {0, 0, -0.5};
    falling.density = 500;
    ball = world.add(falling);
    CouplingDesc coupling;
    coupling.staticFriction = coupling.dynamicFriction = 0.3;
    addCoupledBody(cloth, world, box, coupling);
    addCoupledBody(cloth, world, ball, coupling);
  }
  /// The ball's centre over the box's top, less r: 2 thicknesses where the cloth holds them apart.
  double gap(const RigidWorld& world) const {
    return world.body(ball).pose().position.z() - world.body(box).pose().position.z() - half - r;
  }
};

/// A body dropped onto a cloth whose every vertex is pinned (a 21 x 21 sheet of 2 cm at z = 0, `thickness`
/// 5 mm): no vertex can move, so nothing but the anchors' supports holds the body up (coupling/anchors.hpp). The
/// body lands off centre at 1 m/s, 2 cm above its contact shell, coupled with friction 0.3 to `world` (gravity, no
/// ground). `box` drops a 6 x 4 x 2 cm box turned 0.3 rad about z; else a ball of radius 5 cm.
struct OnAnchors {
  static constexpr double thickness = 0.005;
  int body = -1;
  double bottomBelowCentre = 0;  ///< the body's lowest point under its centre while level
  static SheetDesc sheet() {
    SheetDesc grid;
    grid.nx = grid.ny = 21;
    grid.spacing = 0.02;
    return grid;
  }
  template <class S> static std::shared_ptr<const ClothAsset<S>> asset() {
    return std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(sheet()));
  }
  static Settings settings() {
    Settings s;
    s.thickness = thickness;
    return s;
  }
  template <class Cloth> OnAnchors(Cloth& cloth, RigidWorld& world, bool box) {
    for (Index i = 0; i < cloth.vertexCount(); ++i) cloth.pin(i);
    BodyDesc d;
    if (box) {
      d.shape = Box{Eigen::Vector3d(0.03, 0.02, 0.01)};
      d.pose.rotation = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
      bottomBelowCentre = 0.01;
    } else {
      d.shape = Sphere{0.05};
      bottomBelowCentre = 0.05;
    }
    d.pose.position = {0.013, -0.007, bottomBelowCentre + thickness + 0.02};
    d.linearVelocity = {0, 0, -1};
    d.density = 300;
    body = world.add(d);
    CouplingDesc coupling;
    coupling.staticFriction = coupling.dynamicFriction = 0.3;
    addCoupledBody(cloth, world, body, coupling);
  }
  /// The body's lowest point over the sheet (the anchors' plane), taken as if level.
  double gap(const RigidWorld& world) const { return world.body(body).pose().position.z() - bottomBelowCentre; }
  /// What 2 s of coupled steps (0.01 s) did: the lowest gap at any substep's end, the deepest anchor inside the
  /// body at any step's end, and the body's gap, speed and spin at the end.
  struct Landing {
    double lowest = 1, deepest = 0, finalGap = 0, speed = 0, spin = 0;
    std::string describe() const {
      using detail::formatNumber;
      return "lowest gap " + formatNumber(lowest) + " m, final " + formatNumber(finalGap) +
             " m, deepest anchor in it " + formatNumber(deepest) + " m, at the end " + formatNumber(speed) + " m/s, " +
             formatNumber(spin) + " rad/s";
    }
  };
  template <class Cloth> Landing land(Cloth& cloth, RigidWorld& world, int steps = 200, double plane = 0) const {
    Landing r;
    const auto watch = [&](const Cloth&) { r.lowest = std::min(r.lowest, gap(world) - plane); };
    for (int s = 0; s < steps; ++s) {
      stepCoupled(cloth, world, 0.01, watch);
      r.deepest = std::max(r.deepest, scenes::bodyPenetrationAtBodies(cloth, world));
    }
    r.finalGap = gap(world) - plane;
    r.speed = world.body(body).linearVelocity().norm();
    r.spin = world.body(body).angularVelocity().norm();
    return r;
  }
  /// Lets the body come to rest (1 s), then moves the whole sheet `drop` metres down, by new positions or, with
  /// `attached` (every vertex attached to where it is, at inverse mass 0), by its pins' targets, and lets the body
  /// land on it there: the landing, its gaps taken over the sheet's new plane.
  template <class Cloth> Landing moveSheetDown(Cloth& cloth, RigidWorld& world, bool attached, double drop) const {
    if (attached)
      for (Index i = 0; i < cloth.vertexCount(); ++i) cloth.attach(i, cloth.position(i));
    for (int s = 0; s < 100; ++s) stepCoupled(cloth, world, 0.01);
    const Eigen::Vector3d down(0, 0, -drop);
    std::vector<Eigen::Vector3d> moved(std::size_t(cloth.vertexCount()));
    for (Index i = 0; i < cloth.vertexCount(); ++i) moved[std::size_t(i)] = cloth.position(i) + down;
    if (attached)
      for (Index i = 0; i < cloth.vertexCount(); ++i) cloth.setPinTarget(i, moved[std::size_t(i)]);
    else
      cloth.setPositions(moved);
    return land(cloth, world, 150, -drop);
  }
};

/// Gravity and no ground: the cloth alone holds what falls on it.
inline RigidSettings noGround() {
  RigidSettings rigid;
  rigid.ground = false;
  return rigid;
}

inline RigidSettings emptySpace() {
  RigidSettings rigid;
  rigid.gravity.setZero();
  rigid.ground = false;
  return rigid;
}

/// A body held by an application's engine, as a coupled body sees it: a ball at rest at `at` until `broken`,
/// then with a pose that is not finite (what an engine that diverged reports).
struct BreakingBody : CoupledBody {
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  bool broken = false;  ///< its pose turns non-finite
  bool refuses = false;  ///< it throws where the cloth pushes it, as an application's engine might
  Pose pose() const override {
    Pose p;
    p.position = broken ? Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()) : at;
    return p;
  }
  Eigen::Vector3d linearVelocity() const override { return Eigen::Vector3d::Zero(); }
  Eigen::Vector3d angularVelocity() const override { return Eigen::Vector3d::Zero(); }
  double inverseMass() const override { return 1; }
  Eigen::Matrix3d inverseInertiaWorld() const override { return Eigen::Matrix3d::Identity(); }
  void applyForceAtPoint(const Eigen::Vector3d&, const Eigen::Vector3d&) override {
    if (refuses) throw std::runtime_error("the engine refused the force");
  }
};

/// A 20 x 20 cloth (1 cm) lying on a 4 cm ball held by `body` (friction 0.3), for the undone-step tests.
template <class Solver> void layOnBreakingBall(Solver& cloth, BreakingBody& body) {
  body.at = {0, 0, -0.04};
  Solid<Sphere> ball;
  ball.shape.radius = 0.04;
  ball.motion = Motion::Dynamic;
  ball.body = &body;
  ball.pose.position = body.at;
  ball.staticFriction = ball.dynamicFriction = 0.3;
  cloth.addSolid(ball);
}

/// Whether two cloths have the same positions and velocities, bit for bit.
template <class A, class B> bool sameClothState(const A& a, const B& b) {
  if (a.vertexCount() != b.vertexCount()) return false;
  for (Index i = 0; i < a.vertexCount(); ++i)
    if (a.position(i) != b.position(i) || a.velocity(i) != b.velocity(i)) return false;
  return true;
}

/// Twin cloths on breaking balls stepped 10 frames; then the first one's body breaks (or, with `refuse`,
/// refuses the cloth's push) after the 5th substep of a step, which must throw and leave it as its twin; then,
/// the body mended, both step 3 more frames.
struct UndoneStep {
  bool sameBefore = false, sameAfterFailure = false, sameOrigin = false, sameLater = false;
  int substeps = 0;      ///< substeps the failed step observed
  std::string message;   ///< what it threw (empty: nothing)
};
template <class Solver> UndoneStep breakMidStep(Solver& cloth, Solver& reference, bool refuse = false) {
  BreakingBody body, twin;
  layOnBreakingBall(cloth, body);
  layOnBreakingBall(reference, twin);
  UndoneStep out;
  for (int f = 0; f < 10; ++f) {
    cloth.step(1.0 / 60);
    reference.step(1.0 / 60);
  }
  out.sameBefore = sameClothState(cloth, reference);
  try {
    cloth.step(1.0 / 60, [&](const Solver&) { (refuse ? body.refuses : body.broken) = ++out.substeps == 5; });
  } catch (const std::exception& e) {
    out.message = e.what();
  }
  out.sameAfterFailure = sameClothState(cloth, reference);
  out.sameOrigin = cloth.state().origin == reference.state().origin;
  body.broken = body.refuses = false;  // the engine recovered
  for (int f = 0; f < 3; ++f) {
    cloth.step(1.0 / 60);
    reference.step(1.0 / 60);
  }
  out.sameLater = sameClothState(cloth, reference);
  return out;
}

}  // namespace drape::test
