#pragma once
// A cloth pinned at two corners: a horizontal sheet, held by the two corners of one short edge, swings down
// and comes to rest hanging under them. There are no solids, so it measures the constraint solve alone: how far
// a cloth with rigid (compliance 0) distance constraints stretches under its own weight, and how far it sags.
//
// The solver has no air damping, so the driver removes a fixed share of every vertex's velocity at the end of
// each frame (HangingConfig::damping, the same for every setting, independent of the substep count): the
// swing dies out within the run and the result is the settled shape. The damping changes how the cloth gets
// there, not where it rests.

#include <drape/drape.hpp>

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

namespace drape::scenes {

struct HangingConfig {
  int nx = 21, ny = 31;   ///< vertices across the pinned edge and along the hanging direction
  double spacing = 0.02;  ///< m
  int subSteps = 10;
  int iterations = 1;
  int frames = 150;
  double dt = 1.0 / 60.0;    ///< s per frame
  double height = 1.0;       ///< m, height of the horizontal sheet (and of the pins)
  double areaDensity = 0.1;  ///< kg/m^2
  double damping = 0.1;      ///< share of every velocity the driver removes after each frame, in [0, 1)
  bool bending = true;       ///< build bending constraints (AssetOptions::bending)
  Settings base{};           ///< everything not set above
};

struct HangingResult {
  int vertices = 0;
  std::vector<Eigen::Vector3d> x;  ///< world positions at the end
  double meanStrain = 0, maxStrain = 0;
  double lowestDrop = 0;  ///< m from the pins' height down to the lowest vertex
  double centreDrop = 0;  ///< m from the pins' height down to the middle vertex of the pinned edge
  double maxSpeed = 0;    ///< m/s, fastest vertex at the end (how settled it is)
  double msPerFrame = 0;  ///< median wall time of step() over the run (single thread)
  bool finite = true;
};

/// The two pinned vertices: the corners of the edge j = ny - 1.
inline std::array<Index, 2> hangingPins(const HangingConfig& c) {
  return {Index(c.ny - 1) * c.nx, Index(c.ny - 1) * c.nx + c.nx - 1};
}

template <Scalar S, class SolverT = Solver<S>> SolverT makeHanging(const HangingConfig& c) {
  detail::require(c.nx >= 2 && c.ny >= 2, "nx and ny must be >= 2");
  detail::require(c.frames >= 1, "frames must be >= 1");
  detail::require(c.damping >= 0 && c.damping < 1, "damping must be in [0, 1)");
  SheetDesc grid;
  grid.nx = c.nx;
  grid.ny = c.ny;
  grid.spacing = c.spacing;
  grid.placement.position = Eigen::Vector3d(0, 0, c.height);
  AssetOptions options;
  options.bending = c.bending;
  auto asset = std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid, options));
  Settings s = c.base;
  s.subStepCount = c.subSteps;
  s.iterationCount = c.iterations;
  SolverT solver(asset, s, c.areaDensity);
  for (Index p : hangingPins(c)) solver.pin(p);
  return solver;
}

/// The driver's damping: removes `share` of every vertex's velocity.
template <class SolverT> void dampVelocities(SolverT& solver, double share) {
  if (share <= 0) return;
  std::vector<Eigen::Vector3d> v(solver.vertexCount());
  for (Index i = 0; i < solver.vertexCount(); ++i) v[i] = (1.0 - share) * solver.velocity(i);
  solver.setVelocities(v);
}

template <class SolverT> HangingResult measureHanging(const SolverT& solver, const HangingConfig& c) {
  HangingResult r;
  const Index n = solver.vertexCount();
  r.vertices = n;
  r.x.resize(n);
  double lowest = c.height;
  for (Index i = 0; i < n; ++i) {
    r.x[i] = solver.position(i);
    r.finite = r.finite && r.x[i].allFinite();
    lowest = std::min(lowest, r.x[i].z());
    r.maxSpeed = std::max(r.maxSpeed, solver.velocity(i).norm());
  }
  r.lowestDrop = c.height - lowest;
  r.centreDrop = c.height - r.x[Index(c.ny - 1) * c.nx + c.nx / 2].z();
  const StrainStats strain = stretchStrain(solver.asset(), solver.state().x);
  r.meanStrain = strain.mean;
  r.maxStrain = strain.max;
  return r;
}

/// Runs the scene and measures the settled cloth; then calls atEnd(solver) (for example to time more steps).
template <Scalar S, class AtEnd> HangingResult runHanging(const HangingConfig& c, AtEnd&& atEnd) {
  Solver<S> solver = makeHanging<S>(c);
  std::vector<double> frameMs;
  frameMs.reserve(c.frames);
  for (int f = 1; f <= c.frames; ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    solver.step(c.dt);
    frameMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    dampVelocities(solver, c.damping);
  }
  HangingResult r = measureHanging(solver, c);
  std::sort(frameMs.begin(), frameMs.end());
  r.msPerFrame = frameMs[frameMs.size() / 2];
  atEnd(solver);
  return r;
}

template <Scalar S> HangingResult runHanging(const HangingConfig& c) {
  return runHanging<S>(c, [](Solver<S>&) {});
}

}  // namespace drape::scenes
