#pragma once
// A cloth folded into a V gutter of two frictionless planes (walls at `wallDeg` from horizontal), laid in
// 1 mm above the thickness and left to settle. The fold line touches both walls at once: this is where the
// in-solve method keeps trembling and the faces method settles (the SDF collision
// paper's claim, docs/design.md §4).

#include <drape/drape.hpp>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

namespace drape::scenes {

struct GutterConfig {
  double wallDeg = 45;
  int nx = 21, ny = 40;  ///< vertices across the gutter and along it
  double spacing = 0.02;
  int frames = 300;
  double dt = 1.0 / 60.0;
  double windowStart = 0.5;  ///< trembling is measured from this fraction of the run
  double gap = 0.001;        ///< m above the thickness at the start
  Settings settings{};
};

struct GutterResult {
  double tremblingRms = 0, tremblingMax = 0, tremblingRmsCentred = 0;
  double contactFraction = 0;
  double maxPenetration = 0;  ///< below a wall's surface (m), at substep ends
  double maxShortfall = 0;    ///< inside the thickness (m), at substep ends
  double maxSpeed = 0;  ///< m/s over the window
};

/// The solver with the two walls and the cloth folded into the V.
template <Scalar S> Solver<S> makeGutter(const GutterConfig& c) {
  SheetDesc grid;
  grid.nx = c.nx;
  grid.ny = c.ny;
  grid.spacing = c.spacing;
  auto asset = std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid));
  Solver<S> solver(asset, c.settings);
  const double wall = c.wallDeg * std::numbers::pi / 180.0;
  for (int side : {1, -1}) {
    Solid<Plane> p;
    p.pose.rotation = Eigen::AngleAxisd(side * wall, Eigen::Vector3d::UnitY());
    solver.addSolid(p);
  }
  // Fold the sheet to the V: across-coordinate u runs up both walls.
  std::vector<Eigen::Vector3d> x(solver.vertexCount());
  const double lift = (c.settings.thickness + c.gap) / std::cos(wall);
  for (int j = 0; j < c.ny; ++j)
    for (int i = 0; i < c.nx; ++i) {
      const double u = (i - 0.5 * (c.nx - 1)) * c.spacing, y = (j - 0.5 * (c.ny - 1)) * c.spacing;
      x[j * c.nx + i] = {u * std::cos(wall), y, std::abs(u) * std::sin(wall) + lift};
    }
  solver.setPositions(x);
  return solver;
}

template <Scalar S> GutterResult runGutter(const GutterConfig& c) {
  Solver<S> solver = makeGutter<S>(c);
  GutterResult r;
  TrembleMeter meter;
  meter.frame(solver, c.dt, false);
  const int window = int(c.windowStart * c.frames);
  for (int f = 1; f <= c.frames; ++f) {
    solver.step(c.dt, [&](const Solver<S>& s) {
      const PenetrationStats p = penetration(s);
      r.maxPenetration = std::max(r.maxPenetration, p.depth);
      r.maxShortfall = std::max(r.maxShortfall, p.shortfall);
    });
    meter.frame(solver, c.dt, f > window);
    if (f > window)
      for (Index i = 0; i < solver.vertexCount(); ++i) r.maxSpeed = std::max(r.maxSpeed, solver.velocity(i).norm());
  }
  r.tremblingRms = meter.rms();
  r.tremblingMax = meter.max();
  r.tremblingRmsCentred = meter.rmsCentred();
  r.contactFraction = meter.contactFraction();
  return r;
}

}  // namespace drape::scenes
