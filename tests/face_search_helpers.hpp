#pragma once
// Random faces and a brute-force minimum over a face, for the tests of the face searches (test_pgd.cpp,
// test_grid_search.cpp).

#include <drape/math.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace drape::test::faces {

inline double uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

inline Eigen::Vector3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  for (;;) {
    const Eigen::Vector3d v(n(rng), n(rng), n(rng));
    const double len = v.norm();
    if (len > 1e-6) return v / len;
  }
}

/// A roughly equilateral triangle of edge about `edge`, centred on `centre`, randomly turned and skewed.
inline std::array<Eigen::Vector3d, 3> randomTriangle(std::mt19937& rng, const Eigen::Vector3d& centre, double edge) {
  const Eigen::Vector3d n = randomUnit(rng);
  const Eigen::Vector3d u = n.unitOrthogonal();
  const Eigen::Vector3d v = n.cross(u);
  const double r = edge / std::sqrt(3.0);
  const double a0 = uniform(rng, 0, 2 * std::numbers::pi);
  std::array<Eigen::Vector3d, 3> t;
  for (std::size_t k = 0; k < 3; ++k) {
    const double a = a0 + double(k) * 2 * std::numbers::pi / 3 + uniform(rng, -0.35, 0.35);
    const double rk = r * uniform(rng, 0.8, 1.2);
    t[k] = centre + rk * (std::cos(a) * u + std::sin(a) * v);
  }
  return t;
}

/// The smallest phi over a barycentric lattice of the face, `n` subdivisions per side, corners included.
template <class S, class Field> S bruteMinimum(const Field& sdf, const std::array<Vec3<S>, 3>& x, int n) {
  S best = std::numeric_limits<S>::infinity();
  Vec3<S> g;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n - i; ++j) {
      const S b0 = S(i) / S(n), b1 = S(j) / S(n), b2 = S(n - i - j) / S(n);
      best = std::min(best, sdf(Vec3<S>(b0 * x[0] + b1 * x[1] + b2 * x[2]), g));
    }
  return best;
}

}  // namespace drape::test::faces
