#pragma once
// The state a step mutates: positions relative to a local origin that follows the cloth (so float stays
// precise far from the world origin), velocities and inverse masses.

#include <drape/cloth/asset.hpp>

#include <limits>

namespace drape {

template <Scalar S> struct ClothState {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< world position of the local frame (m), double
  std::vector<Vec3<S>> x;                            ///< #V positions relative to origin (m)
  std::vector<Vec3<S>> v;                            ///< #V velocities (m/s)
  std::vector<S> invMass;                            ///< #V inverse masses (1/kg); 0 is pinned

  /// The asset's rest positions, at rest, with masses from an area density: each vertex carries a third of
  /// the area of its faces.
  static ClothState fromAsset(const ClothAsset<S>& asset, double areaDensity) {
    detail::require(std::isfinite(areaDensity) && areaDensity > 0,
                    "areaDensity must be positive and finite (got " + detail::formatNumber(areaDensity) + " kg/m^2)");
    ClothState s;
    const Index n = asset.vertexCount();
    // Keep the local frame near the cloth from the start (offsets computed in double, then rounded once).
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : asset.restPositions) centre += p.template cast<double>();
    centre /= double(n);
    s.origin = asset.origin + centre;
    s.x.resize(n);
    for (Index i = 0; i < n; ++i) s.x[i] = (asset.restPositions[i].template cast<double>() - centre).template cast<S>();
    s.v.assign(n, Vec3<S>::Zero());
    std::vector<double> mass(n, 0.0);
    for (Index f = 0; f < asset.faceCount(); ++f)
      for (Index k : asset.triangles[f]) mass[k] += areaDensity * double(asset.faceRestArea[f]) / 3.0;
    s.invMass.resize(n);
    for (Index i = 0; i < n; ++i) {
      detail::require(mass[i] > 0, "vertex " + std::to_string(i) + " belongs to no face and has no mass");
      const double w = 1.0 / mass[i];
      detail::require(w >= double(std::numeric_limits<S>::min()) && w <= double(std::numeric_limits<S>::max()),
                      "the mass of vertex " + std::to_string(i) + " (" + std::to_string(mass[i]) +
                          " kg) is outside the range of the solver's scalar; check areaDensity");
      s.invMass[i] = S(w);
    }
    return s;
  }
};

}  // namespace drape
