// Rest at few substeps (docs/design.md, Known limits): a 40x40 cloth (2 cm) that should come to rest on a solid,
// stepped at 60 Hz for a while, and the RMS speed of all its vertices read at a quarter, half and all of the run,
// and at the end that of the vertices within 2 cm of the solid, with the time per frame (one thread, the whole run:
// landing included), so that a setting's rest and its price are read side by side.
// The scenes are the ones where drape's contacts are hardest to bring to rest: a ridge (the slope sample's box
// turned 45 degrees, an edge on top, mu 0.5), a cube standing on a corner (mu 0.5), a 3 mm rod (a capsule,
// mu 0.5, continuous contact on) and a 0.2 m ball (mu 0.5), each for every collision method, float and double.
// Without air damping (Settings::airDamping, default 0) a cloth loses no motion of its own: where it hangs free (the
// skirt over the ball, the halves over the rod) it swings down only through the solver's dissipation, so that
// part of a reading is not trembling.
// With --placements P, each run is repeated with the cloth's start moved P - 1 more times, by up to half a cell
// (1 cm) each way in x and y: whether a cloth comes to rest can hang on where its vertices meet the solid's edges.
// The largest strain of the cloth's stretch edges at the end is read beside the speeds: at few substeps the
// constraint passes leave a hanging cloth stretched, most where it hangs from the solid.
// The speeds are read at a frame's end, which a cycle of the substeps can hide or inflate: a vertex that moves
// and comes back within a frame reads a speed where an application sees it still, and one whose cycle spans
// frames may read little at the moment it is read. So the positions are read too, at every frame's end over the
// run's last second: the largest distance any vertex spans there (scenes::FrameSpan) is what a viewer sees move,
// and a cloth at rest spans nothing.
// Run: build/bench/rest_drift [--iterations N, default 1] [--air-damping C in 1/s, default 0] [--placements P,
//      default 1] [--rings R, Settings::propagationRings, default 1] [--weight W, Settings::propagationWeight,
//      default 0.5] [--scenes ridge,corner,rod,ball]
//      [--methods faces,in-solve,vertices] [seconds, default 20] [substep counts..., default 2]
#include <drape/drape.hpp>

#include <rest_scenes.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <string>
#include <vector>

namespace {

using namespace drape;
using scenes::RestScene;
using scenes::shiftOf;

/// The RMS speed of all vertices at a quarter, half and all of the run; at the end, that of the vertices within
/// kNear of the solid (the contacts and their neighbours, not the free skirt), and the lowest vertex (a cloth that
/// fell through is far below the solid).
constexpr double kNear = 0.02;  ///< m
struct Reading {
  double rms[3] = {0, 0, 0};
  double nearRms = 0;
  double lowest = 0;
  double strain = 0;      ///< the largest strain of the stretch edges at the end
  double span = 0;        ///< the largest distance a vertex spans at the frames' ends over the last second (m)
  double msPerFrame = 0;  ///< the whole run's stepping time over its frames, landing included
};

/// At most this RMS speed of all vertices (m/s), a cloth is at rest (the target of the rest tests).
constexpr double kAtRest = 1e-4;
using scenes::kStillSpan;  // and still where a viewer sees it: the rest tests' second bound

template <class S>
Reading run(RestScene scene, CollisionMethod method, int substeps, int iterations, double airDamping, int rings,
            double weight, double seconds, int placement = 0) {
  scenes::Distance distance;
  Solver<S> solver = scenes::makeRestScene<S>(scene, method, substeps, distance, shiftOf(placement));
  Settings settings = solver.settings();
  settings.iterationCount = iterations;
  settings.airDamping = airDamping;
  settings.propagationRings = rings;
  settings.propagationWeight = weight;
  solver.setSettings(settings);
  const int frames = int(seconds * 60 + 0.5);
  const int marks[3] = {frames / 4, frames / 2, frames};
  const int watched = std::min(frames, 60);  // the last second's frames
  scenes::FrameSpan span;
  Reading r;
  double stepping = 0;
  for (int f = 1; f <= frames; ++f) {
    const auto start = std::chrono::steady_clock::now();
    solver.step(1.0 / 60.0);
    stepping += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    for (int k = 0; k < 3; ++k)
      if (f == marks[k]) r.rms[k] = scenes::rmsSpeed(solver);
    if (f > frames - watched) span.add(solver);
  }
  r.span = span.largest();
  r.msPerFrame = stepping / frames;
  r.nearRms = scenes::rmsSpeedNear(solver, distance, kNear);
  r.strain = stretchStrain(solver.asset(), solver.state().x).max;
  r.lowest = 1e300;
  for (Index i = 0; i < solver.vertexCount(); ++i) r.lowest = std::min(r.lowest, solver.position(i).z());
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  int iterations = 1, placements = 1, rings = Settings{}.propagationRings, first = 1;
  double airDamping = 0, weight = Settings{}.propagationWeight;
  std::vector<RestScene> scenesRun = {RestScene::Ridge, RestScene::Corner, RestScene::Rod, RestScene::Ball};
  std::vector<CollisionMethod> methods = {CollisionMethod::Faces, CollisionMethod::InSolve, CollisionMethod::Vertices};
  // A comma-separated list's items.
  auto itemsOf = [](const std::string& list) {
    std::vector<std::string> items;
    for (std::size_t at = 0; at <= list.size();) {
      const std::size_t comma = std::min(list.find(',', at), list.size());
      items.push_back(list.substr(at, comma - at));
      at = comma + 1;
    }
    return items;
  };
  for (; first + 1 < argc && std::string(argv[first]).starts_with("--"); first += 2) {
    const std::string option = argv[first];
    if (option == "--iterations") {
      iterations = std::atoi(argv[first + 1]);
    } else if (option == "--air-damping") {
      airDamping = std::atof(argv[first + 1]);
    } else if (option == "--placements") {
      placements = std::atoi(argv[first + 1]);
    } else if (option == "--rings") {
      rings = std::atoi(argv[first + 1]);
    } else if (option == "--weight") {
      weight = std::atof(argv[first + 1]);
    } else if (option == "--scenes") {
      scenesRun.clear();
      for (const std::string& item : itemsOf(argv[first + 1])) {
        const RestScene named[] = {RestScene::Ridge, RestScene::Corner, RestScene::Rod, RestScene::Ball};
        const char* keys[] = {"ridge", "corner", "rod", "ball"};
        const auto k = std::find(std::begin(keys), std::end(keys), item) - std::begin(keys);
        if (k == 4) {
          std::fprintf(stderr, "rest_drift: unknown scene '%s' (ridge, corner, rod, ball)\n", item.c_str());
          return 2;
        }
        scenesRun.push_back(named[k]);
      }
    } else if (option == "--methods") {
      methods.clear();
      try {
        for (const std::string& item : itemsOf(argv[first + 1])) methods.push_back(collisionMethodFromString(item));
      } catch (const Error& e) {
        std::fprintf(stderr, "rest_drift: %s\n", e.what());
        return 2;
      }
    } else {
      std::fprintf(stderr,
                   "rest_drift: unknown option %s (--iterations, --air-damping, --placements, --rings, --weight, "
                   "--scenes, --methods)\n",
                   option.c_str());
      return 2;
    }
  }
  // The solver's settings check their own ranges (Settings::validate), before any run starts.
  try {
    Settings chosen;
    chosen.iterationCount = iterations;
    chosen.airDamping = airDamping;
    chosen.propagationRings = rings;
    chosen.propagationWeight = weight;
    chosen.validate();
  } catch (const Error& e) {
    std::fprintf(stderr, "rest_drift: %s\n", e.what());
    return 2;
  }
  if (placements < 1 || placements > 1000) {
    std::fprintf(stderr, "rest_drift: --placements must be in [1, 1000]\n");
    return 2;
  }
  const double seconds = argc > first ? std::atof(argv[first]) : 20.0;
  std::vector<int> substeps;
  for (int a = first + 1; a < argc; ++a) substeps.push_back(std::atoi(argv[a]));
  if (substeps.empty()) substeps = {2};
  if (!(seconds >= 0.1) || seconds > 600) {
    std::fprintf(stderr, "rest_drift: seconds must be in [0.1, 600]\n");
    return 2;
  }
  for (int n : substeps)
    if (n < 1 || n > 1000) {
      std::fprintf(stderr, "rest_drift: substep counts must be in [1, 1000]\n");
      return 2;
    }
  if (placements > 1) {
    std::printf(
        "%d solver iteration(s) per substep, air damping %g/s, %d propagation ring(s) of weight %g, %d placements of "
        "the cloth. After %g s: how "
        "many are at rest (RMS speed of all vertices at most %g m/s) and how many of those are also still (no "
        "vertex spanning more than %g mm at the frames' ends over the last second), the median and the worst RMS "
        "speed (m/s), the median within 2 cm of the solid, the median and the worst largest strain, the median and "
        "the worst largest distance a vertex spans at the frames' ends over the last second (mm), and the median "
        "time per frame (ms, landing included).\n\n",
        iterations, airDamping, rings, weight, placements, seconds, kAtRest, kStillSpan * 1e3);
    std::printf(
        "| scene | substeps | method | scalar | at rest | still | median | worst | median within 2 cm | strain | "
        "span (mm) | ms per frame |\n");
    std::printf("|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  } else {
    std::printf(
        "%d solver iteration(s) per substep, air damping %g/s, %d propagation ring(s) of weight %g. RMS speed of all "
        "vertices (m/s) after %g, %g "
        "and %g s; at the end the lowest vertex (m) and the largest strain; the largest distance a vertex spans at "
        "the frames' ends over the last second (mm); the time per frame (ms, landing included).\n\n",
        iterations, airDamping, rings, weight, seconds / 4, seconds / 2, seconds);
    std::printf(
        "| scene | substeps | method | scalar | RMS at %g s | at %g s | at %g s | within 2 cm at %g s | lowest | "
        "strain | span (mm) | ms per frame |\n",
        seconds / 4, seconds / 2, seconds, seconds);
    std::printf("|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  for (RestScene scene : scenesRun)
    for (int n : substeps)
      for (CollisionMethod m : methods)
        for (bool isFloat : {true, false}) {
          std::vector<Reading> readings;
          for (int k = 0; k < placements; ++k)
            readings.push_back(isFloat ? run<float>(scene, m, n, iterations, airDamping, rings, weight, seconds, k)
                                       : run<double>(scene, m, n, iterations, airDamping, rings, weight, seconds, k));
          std::printf("| %s | %d | %s | %s |", scenes::name(scene), n, toString(m), isFloat ? "float" : "double");
          if (placements > 1) {
            std::vector<double> all, near, strains, spans, times;
            for (const Reading& r : readings)
              all.push_back(r.rms[2]), near.push_back(r.nearRms), strains.push_back(r.strain),
                  spans.push_back(r.span * 1e3), times.push_back(r.msPerFrame);
            const auto resting = std::count_if(all.begin(), all.end(), [](double v) { return v <= kAtRest; });
            const auto still = std::count_if(readings.begin(), readings.end(), [](const Reading& r) {
              return r.rms[2] <= kAtRest && r.span <= kStillSpan;
            });
            std::printf(" %d of %d | %d | %.1e | %.1e | %.1e | %.2f, %.2f | %.1e, %.1e | %.2f |\n", int(resting),
                        placements, int(still), median(all), *std::max_element(all.begin(), all.end()), median(near),
                        median(strains), *std::max_element(strains.begin(), strains.end()), median(spans),
                        *std::max_element(spans.begin(), spans.end()), median(times));
          } else {
            const Reading& r = readings[0];
            std::printf(" %.1e | %.1e | %.1e | %.1e | %.3f | %.2f | %.1e | %.2f |\n", r.rms[0], r.rms[1], r.rms[2],
                        r.nearRms, r.lowest, r.strain, r.span * 1e3, r.msPerFrame);
          }
          std::fflush(stdout);
        }
  return 0;
}
