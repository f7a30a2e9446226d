#pragma once
// A horizontal cloth dropped onto a ball: it falls, lands on the top of the ball, and drapes around it.
// The run records every vertex's position at fixed times (for a trajectory against a reference run) and the
// deepest penetration of a vertex or of a face's deepest point (PGD) into the ball at every frame's end.

#include <drape/drape.hpp>

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

namespace drape::scenes {

struct DropConfig {
  int nx = 21, ny = 31;
  double spacing = 0.02;  ///< m
  int subSteps = 10;
  int iterations = 1;
  int frames = 72;
  double dt = 1.0 / 60.0;  ///< s per frame
  double radius = 0.15;    ///< m, the ball's radius
  Eigen::Vector3d ballCentre = Eigen::Vector3d::Zero();  ///< m; the cloth's centre starts above the origin
  double height = 0.25;    ///< m, height of the horizontal cloth's centre above the world origin
  double friction = 0.3;   ///< static and dynamic Coulomb coefficient of the ball
  double areaDensity = 0.1;  ///< kg/m^2
  int sampleEvery = 6;       ///< frames between recorded positions (the first at frame sampleEvery)
  Settings base{};           ///< everything not set above
};

struct DropResult {
  int vertices = 0;
  std::vector<double> sampleTimes;                       ///< s
  std::vector<std::vector<Eigen::Vector3d>> samples;     ///< world positions at each sample time
  double maxPenetration = 0;  ///< m below the ball's surface, worst over frame ends
  double maxShortfall = 0;    ///< m inside the thickness shell, worst over frame ends
  double meanStrain = 0, maxStrain = 0;  ///< at the end
  double msPerFrame = 0;      ///< median wall time of step() over the run (single thread)
  bool finite = true;
};

template <Scalar S, class SolverT = Solver<S>> SolverT makeDrop(const DropConfig& c) {
  detail::require(c.nx >= 2 && c.ny >= 2, "nx and ny must be >= 2");
  detail::require(c.frames >= 1 && c.sampleEvery >= 1, "frames and sampleEvery must be >= 1");
  SheetDesc grid;
  grid.nx = c.nx;
  grid.ny = c.ny;
  grid.spacing = c.spacing;
  grid.placement.position = Eigen::Vector3d(0, 0, c.height);
  auto asset = std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid));
  Settings s = c.base;
  s.subStepCount = c.subSteps;
  s.iterationCount = c.iterations;
  SolverT solver(asset, s, c.areaDensity);
  Solid<Sphere> ball;
  ball.shape.radius = c.radius;
  ball.pose.position = c.ballCentre;
  ball.staticFriction = ball.dynamicFriction = c.friction;
  solver.addSolid(ball);
  return solver;
}

/// Runs the scene; then calls atEnd(solver) (for example to time more steps).
template <Scalar S, class AtEnd> DropResult runDrop(const DropConfig& c, AtEnd&& atEnd) {
  Solver<S> solver = makeDrop<S>(c);
  const Index n = solver.vertexCount();
  DropResult r;
  r.vertices = n;
  std::vector<double> frameMs;
  frameMs.reserve(c.frames);
  for (int f = 1; f <= c.frames; ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    solver.step(c.dt);
    frameMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    const PenetrationStats p = penetration(solver);
    r.maxPenetration = std::max(r.maxPenetration, p.depth);
    r.maxShortfall = std::max(r.maxShortfall, p.shortfall);
    if (f % c.sampleEvery == 0) {
      std::vector<Eigen::Vector3d> x(n);
      for (Index i = 0; i < n; ++i) {
        x[i] = solver.position(i);
        r.finite = r.finite && x[i].allFinite();
      }
      r.sampleTimes.push_back(f * c.dt);
      r.samples.push_back(std::move(x));
    }
  }
  const StrainStats strain = stretchStrain(solver.asset(), solver.state().x);
  r.meanStrain = strain.mean;
  r.maxStrain = strain.max;
  std::sort(frameMs.begin(), frameMs.end());
  r.msPerFrame = frameMs[frameMs.size() / 2];
  atEnd(solver);
  return r;
}

template <Scalar S> DropResult runDrop(const DropConfig& c) {
  return runDrop<S>(c, [](Solver<S>&) {});
}

}  // namespace drape::scenes
