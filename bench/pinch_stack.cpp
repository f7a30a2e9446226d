// A body pressed into the floor's cloth by another body on it (scenes/pinch_stack.hpp; docs/benchmarks.md): a
// 128 g box dropped onto a 19 g box resting on a cloth on the floor, which should hold it two thicknesses up.
// For each drop height, float and double, over 1 s at 100 Hz and 10 substeps: the lowest gap between the light
// box's bottom and the floor while the box is wholly over the cloth (at rest: two thicknesses, 10 mm), the gap at
// the end, the deepest cloth vertex inside either box, read at the boxes' poses after each step, and how far the
// light box was knocked across the floor.
// Beside each run, the same drop without the cloth (the light box on the world's ground): what the rigid world's own
// contacts leave, with RigidSettings::iterationCount passes (--rigid-iterations, default 1, as RigidWorld's).
// Run: build/bench/pinch_stack [--rigid-iterations N] [drop heights in m, default 0.02 0.1 0.3]
#include <pinch_stack.hpp>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

using drape::scenes::PinchStack;

template <class S> PinchStack::Reading run(double dropHeight, int rigidIterations) {
  drape::Solver<S> cloth(PinchStack::asset<S>(), PinchStack::settings(), 0.1);
  return PinchStack::run(&cloth, dropHeight, rigidIterations);
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
              PinchStack::kThickness * 1e3, 2 * PinchStack::kThickness * 1e3, rigidIterations);
  std::printf("| drop (m) | scalar | top box's fastest (m/s) | light box's lowest gap (mm) | at the end (mm) | "
              "deepest cloth vertex in a box (mm) | light box moved (mm) | without cloth: lowest (mm) |\n"
              "|---:|---|---:|---:|---:|---:|---:|---:|\n");
  for (const double h : heights)
    for (const bool dbl : {false, true}) {
      const PinchStack::Reading r = dbl ? run<double>(h, rigidIterations) : run<float>(h, rigidIterations);
      // the world alone: no cloth, no scalar
      const PinchStack::Reading bare = PinchStack::run<drape::Solver<float>>(nullptr, h, rigidIterations);
      std::printf("| %.2f | %s | %.2f | %.2f | %.2f | %.2f | %.0f | %.2f |\n", h, dbl ? "double" : "float",
                  r.topSpeed, r.lowestGap * 1e3, r.finalGap * 1e3, r.deepest * 1e3, r.shift * 1e3,
                  bare.lowestGap * 1e3);
    }
  return 0;
}
