#pragma once
// The inclined-plane scene of the SDF collision paper (Figs 5 and 8): a horizontal cloth above a slope falls, lands and
// slides; or, started partly inside the slope, is pushed out of it; or, with a ridge in place of the slope, falls
// onto a box's top edge and hangs over it. Shared by the sample, the tests and the benches, so all three measure
// the same thing.

#include <drape/drape.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

namespace drape::scenes {

struct SlopeConfig {
  double angleDeg = 30;  ///< slope angle; 0 is a flat floor
  double friction = 0;   ///< static and dynamic Coulomb coefficient of the slope
  int subSteps = 10;
  int iterations = 1;
  int frames = 300;
  double dt = 1.0 / 60.0;  ///< s per frame
  int nx = 50, ny = 80;
  double spacing = 0.02;  ///< m
  CollisionMethod method = CollisionMethod::Faces;
  /// m, vertical gap between the cloth's uphill edge and the slope at the start; a large one drops the cloth flat
  /// from a height, a negative one starts its uphill part inside the slope (that edge -gap below the surface)
  double gap = 0.05;
  /// In place of the slope, a ridge: a long box (0.5 m square section) turned 45 degrees about x, so that one edge
  /// runs along x on top (at height 0) with faces falling 45 degrees to each side; `angleDeg` is then unused and
  /// the friction is the ridge's. The cloth starts `gap` above the edge and should come to rest hanging over it.
  bool ridge = false;
  /// m, the cloth's start moved across the slope (x) and up or down it (y)
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();
  double areaDensity = 0.1;    ///< kg/m^2
  double windowStart = 0.5;    ///< metrics use frames from this fraction of the run to its end
  bool penetrationEverySubstep = false;  ///< measure penetration after every substep (slow), else every frame
  std::string traceFile;       ///< CSV per frame, empty for none
  std::string objDir;          ///< an OBJ per frame, empty for none
  Settings base{};             ///< everything not set above
};

struct SlopeResult {
  int vertices = 0, faces = 0;
  double msPerFrame = 0;          ///< median wall time of step() (single thread)
  double nsPerVertexSubstep = 0;
  double meanMsPerFrame = 0;      ///< mean wall time of step() over the whole run, the landing included
  double meanNsPerVertexSubstep = 0;
  double tremblingRms = 0, tremblingMax = 0;  ///< as defined in docs/design.md §10
  double tremblingRmsCentred = 0, tremblingMaxCentred = 0;  ///< with each frame's mean normal velocity removed
  double acceleration = 0;         ///< fitted downhill acceleration of the centre of mass (m/s^2)
  int fittedFrames = 0;            ///< frames the acceleration was fitted over (fitted only from kMinFitFrames)
  double analyticAcceleration = 0; ///< g (sin - mu cos) when tan > mu, else 0
  double creep = 0;                ///< mean downhill speed over the window (m/s)
  double maxPenetration = 0;       ///< below the surface (m)
  double maxShortfall = 0;         ///< inside the thickness shell (m)
  double meanStrain = 0, maxStrain = 0;
  double contactFraction = 0;
  bool finite = true;
  /// Fewest frames in the window that fit an acceleration: two points always lie on a line.
  static constexpr int kMinFitFrames = 3;
  /// A cloth whose edges end more than twice their rest length apart no longer holds together: the run diverged.
  static constexpr double kDivergedStrain = 1.0;
  /// A vertex further than this inside the solid (ten of the default thicknesses) went through it.
  static constexpr double kThroughDepth = 0.05;  ///< m
  bool fitted() const { return fittedFrames >= kMinFitFrames; }
  bool fellThrough() const { return maxPenetration > kThroughDepth; }
  bool diverged() const { return !finite || maxStrain > kDivergedStrain || fellThrough(); }
};

inline Eigen::Quaterniond slopeRotation(double angleDeg) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angleDeg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitX()));
}

/// Down the slope, in world coordinates.
inline Eigen::Vector3d downhill(double angleDeg) { return slopeRotation(angleDeg) * Eigen::Vector3d(0, -1, 0); }

/// What a slope scene is made of, for any solver: the cloth, its settings and the slope (or the ridge).
template <Scalar S> struct SlopeParts {
  std::shared_ptr<const ClothAsset<S>> asset;
  Settings settings;
  Solid<Plane> slope;
  bool hasRidge = false;
  Solid<Box> ridge;

  /// Adds the scene's solid to a solver (CPU or GPU).
  template <class SolverT> void addSolidsTo(SolverT& solver) const {
    if (hasRidge)
      solver.addSolid(ridge);
    else
      solver.addSolid(slope);
  }
};

/// The ridge's half side (m): the box's square section is twice this.
inline constexpr double kRidgeHalfSide = 0.25;

template <Scalar S> SlopeParts<S> slopeParts(const SlopeConfig& c) {
  detail::requireRange(c.angleDeg, 0, 80, "angle");
  detail::require(c.frames >= 1, "frames must be >= 1");
  detail::require(c.nx >= 2 && c.ny >= 2, "nx and ny must be >= 2");
  detail::requireRange(c.friction, 0, 100, "friction");
  detail::requireRange(c.gap, -1, 100, "gap");
  const double theta = c.angleDeg * std::numbers::pi / 180.0;
  SheetDesc grid;
  grid.nx = c.nx;
  grid.ny = c.ny;
  grid.spacing = c.spacing;
  const double halfY = 0.5 * (c.ny - 1) * c.spacing;
  grid.placement.position = Eigen::Vector3d(c.shift.x(), c.shift.y(), c.ridge ? c.gap : halfY * std::tan(theta) + c.gap);
  SlopeParts<S> parts;
  parts.asset = std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid));
  parts.settings = c.base;
  parts.settings.subStepCount = c.subSteps;
  parts.settings.iterationCount = c.iterations;
  parts.settings.collisionMethod = c.method;
  parts.slope.pose.rotation = slopeRotation(c.angleDeg);
  parts.slope.staticFriction = parts.slope.dynamicFriction = c.friction;
  if (c.ridge) {
    parts.hasRidge = true;
    parts.ridge.shape.halfExtents = {0.5 * (c.nx - 1) * c.spacing + 0.2, kRidgeHalfSide, kRidgeHalfSide};
    parts.ridge.pose.rotation = Eigen::AngleAxisd(std::numbers::pi / 4, Eigen::Vector3d::UnitX());
    parts.ridge.pose.position = {0, 0, -kRidgeHalfSide * std::numbers::sqrt2};  // the top edge at height 0
    parts.ridge.staticFriction = parts.ridge.dynamicFriction = c.friction;
  }
  return parts;
}

template <Scalar S> Solver<S> makeSlope(const SlopeConfig& c) {
  const SlopeParts<S> parts = slopeParts<S>(c);
  Solver<S> solver(parts.asset, parts.settings, c.areaDensity);
  parts.addSolidsTo(solver);
  return solver;
}

inline void writeObj(const std::string& path, const std::vector<Eigen::Vector3d>& x,
                     const std::vector<std::array<Index, 3>>& triangles) {
  std::ofstream out(path);
  if (!out) throw Error("cannot write " + path);
  char line[128];
  for (const auto& p : x) {
    std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", p.x(), p.y(), p.z());
    out << line;
  }
  for (const auto& t : triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
}

/// Runs the scene on `solver` (made from slopeParts(c), on the CPU or the GPU) and measures it; onFrame(f), if
/// given, is called after frame f's metrics (for pictures).
template <class SolverT>
SlopeResult runSlopeOn(SolverT& solver, const SlopeConfig& c, const std::function<void(int)>& onFrame = {}) {
  const Index n = solver.vertexCount();
  const double theta = c.angleDeg * std::numbers::pi / 180.0;
  const double g = c.base.gravity.norm();
  // On the ridge, "down" and the tracked height are vertical: the cloth hangs still, so its fitted acceleration
  // and creep should be 0.
  const Eigen::Vector3d down = c.ridge ? Eigen::Vector3d(0, 0, -1) : downhill(c.angleDeg);
  const Eigen::Vector3d normal = c.ridge ? Eigen::Vector3d::UnitZ() : slopeRotation(c.angleDeg) * Eigen::Vector3d::UnitZ();
  const Index tracked = (c.ny / 2) * c.nx + c.nx / 2;  // the centre vertex (the SDF collision paper's Fig 5)
  const int windowFrame = std::clamp(int(c.windowStart * c.frames), 1, c.frames);

  SlopeResult r;
  r.vertices = n;
  r.faces = solver.asset().faceCount();
  TrembleMeter meter;
  std::vector<double> frameMs;
  std::vector<double> times, speeds;  // downhill speed of the centre of mass per frame, over the window
  auto centreOfMass = [&] {
    Eigen::Vector3d c0 = Eigen::Vector3d::Zero();
    for (Index i = 0; i < n; ++i) c0 += solver.position(i);
    return Eigen::Vector3d(c0 / double(n));
  };
  Eigen::Vector3d com = centreOfMass(), comWindow = com;
  std::ofstream trace;
  if (!c.traceFile.empty()) {
    trace.open(c.traceFile);
    if (!trace) throw Error("cannot write " + c.traceFile);
    trace << "time,tracked_height,com_downhill_speed,trembling_rms_so_far,contact_fraction\n";
  }
  meter.frame(solver, c.dt, false);
  double observerMs = 0;  // penetration measured inside step() is not the solver's time
  auto onSubStep = [&](const SolverT& s) {
    const auto t0 = std::chrono::steady_clock::now();
    if (c.penetrationEverySubstep) {
      const auto p = penetration(s);
      r.maxPenetration = std::max(r.maxPenetration, p.depth);
      r.maxShortfall = std::max(r.maxShortfall, p.shortfall);
    }
    observerMs += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  };
  for (int f = 1; f <= c.frames; ++f) {
    observerMs = 0;
    const auto t0 = std::chrono::steady_clock::now();
    if (c.penetrationEverySubstep)
      solver.step(c.dt, onSubStep);
    else
      solver.step(c.dt);
    if constexpr (requires { solver.finish(); }) solver.finish();  // a GPU's step is timed to its end
    frameMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() -
                      observerMs);
    if (!c.penetrationEverySubstep) {
      const auto p = penetration(solver);
      r.maxPenetration = std::max(r.maxPenetration, p.depth);
      r.maxShortfall = std::max(r.maxShortfall, p.shortfall);
    }
    const bool inWindow = f > windowFrame;
    meter.frame(solver, c.dt, inWindow);
    const Eigen::Vector3d comNow = centreOfMass();
    const double speed = down.dot(comNow - com) / c.dt;
    com = comNow;
    if (f == windowFrame) comWindow = comNow;
    if (inWindow) {
      times.push_back(f * c.dt);
      speeds.push_back(speed);
    }
    for (Index i = 0; i < n; ++i) r.finite = r.finite && solver.position(i).allFinite();
    if (trace.is_open())
      trace << f * c.dt << ',' << normal.dot(solver.position(tracked)) << ',' << speed << ',' << meter.rms() << ','
            << meter.contactFraction() << '\n';
    if (!c.objDir.empty()) {
      std::vector<Eigen::Vector3d> x(n);
      for (Index i = 0; i < n; ++i) x[i] = solver.position(i);
      char name[32];
      std::snprintf(name, sizeof name, "/frame_%04d.obj", f);
      writeObj(c.objDir + name, x, solver.asset().triangles);
    }
    if (onFrame) onFrame(f);
  }
  std::vector<double> sorted = frameMs;
  std::sort(sorted.begin(), sorted.end());
  r.msPerFrame = sorted[sorted.size() / 2];
  r.nsPerVertexSubstep = r.msPerFrame * 1e6 / (double(n) * c.subSteps);
  r.meanMsPerFrame = std::accumulate(frameMs.begin(), frameMs.end(), 0.0) / double(frameMs.size());
  r.meanNsPerVertexSubstep = r.meanMsPerFrame * 1e6 / (double(n) * c.subSteps);
  r.tremblingRms = meter.rms();
  r.tremblingMax = meter.max();
  r.tremblingRmsCentred = meter.rmsCentred();
  r.tremblingMaxCentred = meter.maxCentred();
  r.contactFraction = meter.contactFraction();
  r.fittedFrames = int(times.size());
  if (r.fitted()) {  // least-squares slope of speed over time
    double mt = 0, ms = 0;
    for (std::size_t k = 0; k < times.size(); ++k) mt += times[k], ms += speeds[k];
    mt /= times.size();
    ms /= times.size();
    double num = 0, den = 0;
    for (std::size_t k = 0; k < times.size(); ++k) num += (times[k] - mt) * (speeds[k] - ms), den += (times[k] - mt) * (times[k] - mt);
    r.acceleration = num / den;
  }
  const double windowTime = (c.frames - windowFrame) * c.dt;
  r.creep = windowTime > 0 ? down.dot(com - comWindow) / windowTime : 0;
  r.analyticAcceleration =
      !c.ridge && std::tan(theta) > c.friction ? g * (std::sin(theta) - c.friction * std::cos(theta)) : 0;
  const StrainStats strain = stretchStrain(solver.asset(), solver.state().x);
  r.meanStrain = strain.mean;
  r.maxStrain = strain.max;
  return r;
}

template <Scalar S> SlopeResult runSlope(const SlopeConfig& c) {
  Solver<S> solver = makeSlope<S>(c);
  return runSlopeOn(solver, c);
}

}  // namespace drape::scenes
