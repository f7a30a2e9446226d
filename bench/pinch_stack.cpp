// A body pressed into the floor's cloth by another body on it (docs/design.md, Known limits: the rain's depths). A
// light box (4 x 4 x 2 cm, 19 g) rests on a cloth lying on the floor; a heavier box of the same footprint (4 cm
// tall) is dropped onto it from a height. The cloth under the light box is pinched between it and the floor and
// should hold it two thicknesses up, whatever lands on it. The pinch's support stops the light box's own approach
// to the floor before the rigid world's substep, and the push of the box on top comes in the rigid world's solve
// after it: this scene reads what that leaves.
// For each drop height, float and double, over 1 s at 100 Hz and 10 substeps: the lowest gap between the light
// box's bottom and the floor (at rest: two thicknesses, 10 mm), the gap at the end, and the deepest cloth vertex
// inside either box, read at the boxes' poses after each step.
// Beside each run, the same drop without the cloth (the light box on the world's ground): what the rigid world's own
// contacts leave, with RigidSettings::iterationCount passes (--rigid-iterations, default 1, as RigidWorld's).
// Run: build/bench/pinch_stack [--rigid-iterations N] [drop heights in m, default 0.02 0.1 0.3]
#include <drape/drape.hpp>
#include <drape/coupling/rigid_world.hpp>

#include <rigid_rain.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace drape;

constexpr double kThickness = 0.005;  ///< m
constexpr double kHalf = 0.02;        ///< m, half the boxes' width
constexpr double kLowHalfHeight = 0.01, kTopHalfHeight = 0.02;

struct Reading {
  double lowestGap = 1e9;  ///< m, the light box's lowest corner above the floor, over the run
  double finalGap = 0;     ///< m, at the end
  double deepest = 0;      ///< m, the deepest cloth vertex inside a box, over the run
  double topSpeed = 0;     ///< m/s, the top box's speed when it lands (the largest over the run)
};

/// The lowest of a box's corners.
double lowestCorner(const RigidBody& body, const Eigen::Vector3d& half) {
  double low = 1e9;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d c((k & 1) ? half.x() : -half.x(), (k & 2) ? half.y() : -half.y(),
                            (k & 4) ? half.z() : -half.z());
    low = std::min(low, (body.pose().position + body.pose().rotation * c).z());
  }
  return low;
}

/// With `withCloth` false, the boxes alone on the world's ground: what the rigid world's own contacts leave.
template <class S> Reading run(double dropHeight, int rigidIterations, bool withCloth = true) {
  Settings settings;
  settings.thickness = kThickness;
  settings.threadCount = 1;
  SheetDesc sheet;
  sheet.nx = sheet.ny = 30;
  sheet.spacing = 0.01;
  sheet.placement.position = {0, 0, kThickness};
  Solver<S> cloth(std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(sheet)), settings, 0.1);
  Solid<Plane> floor;
  floor.staticFriction = floor.dynamicFriction = 0.5;
  cloth.addSolid(floor);
  RigidSettings rigid;
  rigid.iterationCount = rigidIterations;
  RigidWorld world(rigid);  // its ground is the same floor
  const Eigen::Vector3d lowHalf(kHalf, kHalf, kLowHalfHeight), topHalf(kHalf, kHalf, kTopHalfHeight);
  BodyDesc low;
  low.shape = Box{lowHalf};
  low.density = 600;  // 19 g
  low.pose.position = {0.003, -0.002, (withCloth ? 2 * kThickness : 0.0) + kLowHalfHeight + 0.001};
  const int a = world.add(low);
  BodyDesc top;
  top.shape = Box{topHalf};
  top.density = 2000;  // 128 g
  top.pose.position = low.pose.position + Eigen::Vector3d(0, 0, kLowHalfHeight + kTopHalfHeight + dropHeight);
  const int b = world.add(top);
  CouplingDesc coupling;
  coupling.staticFriction = coupling.dynamicFriction = 0.3;
  if (withCloth) {
    addCoupledBody(cloth, world, a, coupling);
    addCoupledBody(cloth, world, b, coupling);
  }
  Reading r;
  for (int s = 0; s < 100; ++s) {
    if (withCloth)
      stepCoupled(cloth, world, 0.01);
    else
      world.step(0.01);
    r.lowestGap = std::min(r.lowestGap, lowestCorner(world.body(a), lowHalf));
    if (withCloth) r.deepest = std::max(r.deepest, scenes::bodyPenetrationAtBodies(cloth, world));
    r.topSpeed = std::max(r.topSpeed, world.body(b).linearVelocity().norm());
  }
  r.finalGap = lowestCorner(world.body(a), lowHalf);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> heights;
  int rigidIterations = 1;
  for (int k = 1; k < argc; ++k) {
    if (std::string(argv[k]) == "--rigid-iterations" && k + 1 < argc) {
      char* end = nullptr;
      const long n = std::strtol(argv[++k], &end, 10);
      if (*end != '\0' || n < 1 || n > 1000) {
        std::fprintf(stderr, "pinch_stack: --rigid-iterations must be a whole number in [1, 1000] (got '%s')\n",
                     argv[k]);
        return 2;
      }
      rigidIterations = int(n);
      continue;
    }
    char* end = nullptr;
    const double h = std::strtod(argv[k], &end);
    if (end == argv[k] || *end != '\0' || !(h >= 0 && h <= 2)) {
      std::fprintf(stderr, "pinch_stack: a drop height must be a number of metres in [0, 2] (got '%s')\n", argv[k]);
      return 2;
    }
    heights.push_back(h);
  }
  if (heights.empty()) heights = {0.02, 0.1, 0.3};
  std::printf("A 128 g box dropped onto a 19 g box that rests on a cloth on the floor (thickness %.0f mm: the light "
              "box rests %.0f mm up). Over 1 s at 100 Hz, 10 substeps, %d rigid pass(es) per substep:\n\n",
              kThickness * 1e3, 2 * kThickness * 1e3, rigidIterations);
  std::printf("| drop (m) | scalar | top box's fastest (m/s) | light box's lowest gap (mm) | at the end (mm) | "
              "deepest cloth vertex in a box (mm) | without cloth: lowest (mm) |\n"
              "|---:|---|---:|---:|---:|---:|---:|\n");
  for (const double h : heights)
    for (const bool dbl : {false, true}) {
      const Reading r = dbl ? run<double>(h, rigidIterations) : run<float>(h, rigidIterations);
      const Reading bare = run<float>(h, rigidIterations, false);  // the world alone: no cloth, no scalar
      std::printf("| %.2f | %s | %.2f | %.2f | %.2f | %.2f | %.2f |\n", h, dbl ? "double" : "float", r.topSpeed,
                  r.lowestGap * 1e3, r.finalGap * 1e3, r.deepest * 1e3, bare.lowestGap * 1e3);
    }
  return 0;
}
