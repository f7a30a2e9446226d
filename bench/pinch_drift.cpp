// A cloth pinched between the floor and a box lower than twice the thickness (scenes/low_pinch.hpp), from several
// places of the box: whether it holds still (docs/design.md, Known limits). The test
// "a cloth pinched between the floor and a box lower than twice the thickness holds still" runs the first place
// only. Each run is the test's: 1 s at 100 Hz, 10 substeps. Two readings over its last half second:
// - the fastest vertex's speed, as the test reads it (at most 1e-3 m/s with friction, 5e-3 without);
// - the fastest vertex's move from one frame to the next over the frame's time. A contact's push is not turned
//   into velocity (docs/design.md §4), so a vertex that the contacts move back and forth every frame may read a
//   speed of 0; this reading sees it.
// For each method, friction (0 and 0.5), gap (1.9, 1.8 and 1.6 thicknesses), float and double: how many places
// pass each reading, its median and worst, and the lowest and highest vertex over all runs.
// Run: build/bench/pinch_drift [places, default 16]
#include <drape/drape.hpp>

#include <low_pinch.hpp>
#include <rest_scenes.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

using namespace drape;

struct Reading {
  double fastest = 0;  ///< m/s, the largest vertex speed over the last half second
  double moving = 0;   ///< m/s, the largest vertex move between frames over the last half second, over the frame
  double lowest = 1e9, highest = -1e9;  ///< m, over the whole run
};

template <class S> Reading run(double gap, double friction, int place, CollisionMethod method) {
  Solver<S> cloth = scenes::makeLowPinch<S>(gap, friction, scenes::shiftOf(place), method);
  constexpr double dt = 0.01;
  Reading r;
  std::vector<Eigen::Vector3d> last(std::size_t(cloth.vertexCount()));
  for (int s = 0; s < 100; ++s) {
    cloth.step(dt);
    for (Index i = 0; i < cloth.vertexCount(); ++i) {
      const Eigen::Vector3d p = cloth.position(i);
      if (s >= 50) {
        r.fastest = std::max(r.fastest, cloth.velocity(i).norm());
        r.moving = std::max(r.moving, (p - last[std::size_t(i)]).norm() / dt);
      }
      last[std::size_t(i)] = p;
      r.lowest = std::min(r.lowest, p.z());
      r.highest = std::max(r.highest, p.z());
    }
  }
  return r;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  const int places = argc > 1 ? std::atoi(argv[1]) : 16;
  if (places < 1) {
    std::fprintf(stderr, "pinch_drift: the number of places must be at least 1 (got %s)\n", argv[1]);
    return 2;
  }
  std::printf("%d places of the box (the first the test's, the others within 1 cm of it in x and y)\n", places);
  std::printf("%-9s %-4s %-4s %-6s | %-8s %-9s %-9s | %-8s %-9s %-9s | %s\n", "method", "mu", "gap", "type", "still",
              "median", "worst", "no move", "median", "worst", "z (mm)");
  for (CollisionMethod method : {CollisionMethod::Faces, CollisionMethod::Vertices, CollisionMethod::InSolve})
    for (double friction : {0.0, 0.5})
      for (double gap : {1.9, 1.8, 1.6})
        for (int precision = 0; precision < 2; ++precision) {
          const double limit = friction > 0 ? 1e-3 : 5e-3;  // the test's
          std::vector<double> fastest, moving;
          int still = 0, unmoved = 0;
          double lowest = 1e9, highest = -1e9;
          for (int k = 0; k < places; ++k) {
            const Reading r =
                precision == 0 ? run<float>(gap, friction, k, method) : run<double>(gap, friction, k, method);
            fastest.push_back(r.fastest), moving.push_back(r.moving);
            still += r.fastest <= limit;
            unmoved += r.moving <= limit;
            lowest = std::min(lowest, r.lowest), highest = std::max(highest, r.highest);
          }
          std::printf("%-9s %-4.1f %-4.1f %-6s | %2d / %-3d %-9.2g %-9.2g | %2d / %-3d %-9.2g %-9.2g | %.2f to %.2f\n",
                      toString(method), friction, gap, precision == 0 ? "float" : "double", still, places,
                      median(fastest), *std::max_element(fastest.begin(), fastest.end()), unmoved, places,
                      median(moving), *std::max_element(moving.begin(), moving.end()), 1e3 * lowest, 1e3 * highest);
        }
  return 0;
}
