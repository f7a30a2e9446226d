#pragma once
// Energy and speed helpers shared by the [stability] tests (test_stability.cpp explains the energy bound).
#include <drape/drape.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <type_traits>

namespace stability {

using V3 = Eigen::Vector3d;
constexpr double kG = 9.81;

/// Kinetic plus gravitational potential energy (J) of the free vertices, heights measured from `ref`.
template <class Solver> double mechanicalEnergy(const Solver& s, const V3& ref = V3::Zero()) {
  const auto& st = s.state();
  const V3 g = s.settings().gravity;
  const V3 shift = st.origin - ref;
  double e = 0;
  for (std::size_t i = 0; i < st.x.size(); ++i) {
    if (st.invMass[i] == 0) continue;  // pinned: does not move, infinite mass
    const double m = 1.0 / double(st.invMass[i]);
    const V3 v = st.v[i].template cast<double>();
    e += m * (0.5 * v.squaredNorm() - g.dot(shift + st.x[i].template cast<double>()));
  }
  return e;
}

/// A square n x n sheet of the given spacing (m), centred at `at`.
template <class S> std::shared_ptr<const drape::ClothAsset<S>> gridAsset(int n, double spacing, const V3& at) {
  drape::SheetDesc grid;
  grid.nx = grid.ny = n;
  grid.spacing = spacing;
  grid.placement.position = at;
  return std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid));
}

/// Total mass of the free vertices (kg).
template <class Solver> double freeMass(const Solver& s) {
  double m = 0;
  for (auto w : s.state().invMass)
    if (w != 0) m += 1.0 / double(w);
  return m;
}

template <class Solver> double meanSpeedNow(const Solver& s) {
  double v = 0;
  for (const auto& u : s.state().v) v += double(u.norm());
  return v / double(s.vertexCount());
}

template <class S> const char* name() { return std::is_same_v<S, float> ? "float" : "double"; }

/// Rounding of E: positions within 1 m of the local origin carry a relative error eps, and the velocity
/// update turns it into a velocity error of eps * 1 m / h, so E is known to M (v_max eps / h + g eps) (1 m).
/// In float at 200 substeps (h = 83 us) that is 3e-5 J for a 9 g cloth.
template <class S> double energyTolerance(double mass, double maxSpeed, double h) {
  const double eps = std::numeric_limits<S>::epsilon();
  return mass * (maxSpeed * eps / h + kG * eps);
}

}  // namespace stability
