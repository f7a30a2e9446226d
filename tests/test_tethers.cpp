// Tethers (Settings::tethers, docs/design.md §1): free vertices kept within their rest distance along the cloth of
// the kinematic vertices they hang from.
#include <drape/drape.hpp>

#include "sanitizer.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace {

/// A sheet of nx x ny vertices (2 cm) in the horizontal plane at z = 0.5 m, pinned at its four corners.
template <class S> drape::Solver<S> hungByCorners(int nx, int ny, int substeps, bool tethers, int threads = 1) {
  drape::Settings settings;
  settings.subStepCount = substeps;
  settings.tethers = tethers;
  settings.threadCount = threads;
  drape::SheetDesc grid;
  grid.nx = nx;
  grid.ny = ny;
  grid.spacing = 0.02;
  grid.placement.position = {0, 0, 0.5};
  drape::Solver<S> cloth(std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid)), settings,
                         0.1);
  for (const drape::Index i : {0, nx - 1, (ny - 1) * nx, ny * nx - 1}) cloth.pin(i);
  return cloth;
}

/// The largest strain of the cloth's edges.
template <class S> double largestStrain(const drape::Solver<S>& cloth) {
  const auto& asset = cloth.asset();
  double most = 0;
  for (const auto& e : asset.edges) {
    const double rest = (asset.restPositions[e[0]] - asset.restPositions[e[1]]).template cast<double>().norm();
    most = std::max(most, (cloth.position(e[0]) - cloth.position(e[1])).norm() / rest - 1);
  }
  return most;
}

}  // namespace

TEMPLATE_TEST_CASE("a cloth hung by its corners stretches beside them, and not with tethers", "[tethers]", float,
                   double) {
  // A 1 x 1.6 m sheet (50 x 80) falls into a hammock from its four pinned corners. One pass over the edges per
  // substep carries the corners' pull only a few edges, so the edges beside the corners take the cloth's weight
  // stretched: read after each of 3 s, the largest strain reaches 1.24 at 10 substeps and 11.8 at 2. Tethered, it
  // is 0.10-0.11 and 0.36. (A vertex's tethers are met one after another, so one pulling against another can leave
  // a vertex a little beyond the first: up to 6 mm at 10 substeps and 2.5 cm at 2 on this sheet, whose border
  // between two corners is exactly as long as the straight line between them.)
  using S = TestType;
  struct Case {
    int substeps;
    double bound;
  };
  for (const Case c : {Case{10, 0.15}, Case{2, 0.5}}) {
    if (drape::test::kSanitized && c.substeps == 10) continue;
    double without = 0, with = 0;
    for (const bool tethers : {false, true}) {
      drape::Solver<S> cloth = hungByCorners<S>(50, 80, c.substeps, tethers);
      for (int f = 1; f <= 300; ++f) {
        cloth.step(0.01);
        if (f % 100 == 0) (tethers ? with : without) = std::max(tethers ? with : without, largestStrain(cloth));
      }
    }
    INFO(c.substeps << " substeps: largest strain " << without << " without tethers, " << with << " with them");
    CHECK(without > 1);  // the meter sees the stretch
    CHECK(with <= c.bound);
  }
}

TEMPLATE_TEST_CASE("tethers leave a flat pinned cloth where it lies", "[tethers]", float, double) {
  // Without gravity a flat sheet pinned at its corners has nothing to move it; its tethers' lengths are the paths
  // along its edges, never shorter than the straight lines in its plane, so none may pull a vertex either.
  using S = TestType;
  drape::Solver<S> cloth = hungByCorners<S>(21, 13, 10, true);
  drape::Settings settings = cloth.settings();
  settings.gravity = Eigen::Vector3d::Zero();
  cloth.setSettings(settings);
  std::vector<Eigen::Vector3d> start;
  for (drape::Index i = 0; i < cloth.vertexCount(); ++i) start.push_back(cloth.position(i));
  for (int f = 0; f < 100; ++f) cloth.step(0.01);
  double moved = 0;
  for (drape::Index i = 0; i < cloth.vertexCount(); ++i)
    moved = std::max(moved, (cloth.position(i) - start[std::size_t(i)]).norm());
  INFO("largest move " << moved << " m");
  CHECK(moved <= 1e-6);
}

TEST_CASE("tethers follow the pins: let go, a cloth is tethered no more, the same bits on one thread and two",
          "[tethers][threads]") {
  // The tethers are built again whenever an inverse mass changes. Let go at 0.5 s, the corners fall with the rest:
  // the cloth's centre of mass then falls at g, which a tether still pulling toward a freed corner would change (it
  // moves one end only). Until then, and after, two threads give the same bits as one.
  auto run = [](int threads, double& acceleration) {
    drape::Solver<float> cloth = hungByCorners<float>(20, 20, 10, true, threads);
    auto centreVelocity = [&] {
      double mass = 0, vz = 0;
      for (drape::Index i = 0; i < cloth.vertexCount(); ++i) {
        const double m = 1 / double(cloth.state().invMass[std::size_t(i)]);
        mass += m, vz += m * cloth.velocity(i).z();
      }
      return vz / mass;
    };
    std::vector<Eigen::Vector3d> at;
    double v0 = 0;
    for (int f = 1; f <= 100; ++f) {
      if (f == 51)
        for (const drape::Index i : {0, 19, 380, 399}) cloth.setInverseMass(i, 1.0 / (0.1 * 0.02 * 0.02));
      cloth.step(0.01);
      if (f == 60) v0 = centreVelocity();
    }
    acceleration = (centreVelocity() - v0) / 0.4;
    for (drape::Index i = 0; i < cloth.vertexCount(); ++i) at.push_back(cloth.position(i));
    return at;
  };
  double a1 = 0, a2 = 0;
  const auto one = run(1, a1), two = run(2, a2);
  double apart = 0;
  for (std::size_t i = 0; i < one.size(); ++i) apart = std::max(apart, (one[i] - two[i]).norm());
  INFO("the centre of mass's acceleration after the release " << a1 << " m/s^2; one thread and two apart by "
                                                               << apart << " m");
  CHECK(std::abs(a1 + 9.81) <= 1e-3 * 9.81);
  CHECK(apart == 0);
}
