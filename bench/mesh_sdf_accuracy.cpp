// Accuracy of grid distance fields against resolution, for each test mesh (scenes/mesh_shapes.hpp): the
// sampled field (double) against the exact signed distance of the mesh (brute force) at random points, as the
// maximum and RMS error in cells, over the whole grid and in a band near the surface; the largest difference to
// the analytic shape; how far from the surface a wrong sign was seen; and the build time.
// Run: build/bench/mesh_sdf_accuracy [points per shape, default 20000]
#include <drape/sdf/grid.hpp>

#include <mesh_shapes.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

int main(int argc, char** argv) {
  using namespace drape;
  const int count = argc > 1 ? std::atoi(argv[1]) : 20000;
  const double band = 0.05;  // m: "near the surface" is |exact| < band
  std::printf(
      "| shape | triangles | resolution | cell (mm) | max/cell | RMS/cell | max/cell near | RMS/cell near |"
      " max vs analytic (mm) | wrong sign within (cells) | build (ms) |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& shape : scenes::meshShapeCases()) {
    // Points in the mesh's box grown by 10 % of its longest side, which every grid below covers (margin).
    const auto [lo, hi] = scenes::meshBounds(shape.mesh);
    const double pad = 0.1 * (hi - lo).maxCoeff();
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<Eigen::Vector3d> points(count);
    std::vector<double> exact(count), analytic(count);
    for (int i = 0; i < count; ++i) {
      const Eigen::Vector3d t(unit(rng), unit(rng), unit(rng));
      points[i] = (lo.array() - pad + t.array() * ((hi - lo).array() + 2 * pad)).matrix();
      exact[i] = scenes::meshSignedDistance(shape.mesh, points[i]);
      analytic[i] = shape.analytic(points[i]);
    }
    for (int resolution : {16, 32, 64, 128}) {
      DistanceGridOptions options;
      options.resolution = resolution;
      options.margin = pad;
      const auto start = std::chrono::steady_clock::now();
      const auto grid = buildDistanceGrid(shape.mesh, options);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      const detail::GridSampler<double> sample(*grid);
      double maxAll = 0, sumAll = 0, maxNear = 0, sumNear = 0, maxAnalytic = 0;
      int near = 0;
      double wrongSignDepth = 0;  // the largest |exact| where the sampled sign is wrong
      for (int i = 0; i < count; ++i) {
        Eigen::Vector3d g;
        const double phi = sample(points[i], g);
        const double err = std::abs(phi - exact[i]);
        maxAll = std::max(maxAll, err);
        sumAll += err * err;
        if (std::abs(exact[i]) < band) {
          maxNear = std::max(maxNear, err);
          sumNear += err * err;
          ++near;
        }
        maxAnalytic = std::max(maxAnalytic, std::abs(phi - analytic[i]));
        if ((phi < 0) != (exact[i] < 0)) wrongSignDepth = std::max(wrongSignDepth, std::abs(exact[i]));
      }
      const double h = grid->cellSize;
      std::printf("| %s | %d | %d | %.2f | %.3f | %.4f | %.3f | %.4f | %.3f | %.3f | %.0f |\n", shape.name.c_str(),
                  shape.mesh.triangleCount(), resolution, 1e3 * h, maxAll / h, std::sqrt(sumAll / count) / h,
                  maxNear / h, std::sqrt(sumNear / std::max(near, 1)) / h, 1e3 * maxAnalytic, wrongSignDepth / h, ms);
    }
  }
  std::printf(
      "\n%d random points per shape in the mesh's box grown by 10 %% of its longest side (also the grid's "
      "margin); near: |exact| < %.2f m; resolution: cells along the longest side of the grown box.\n",
      count, band);
  return 0;
}
