#pragma once
// What the coupling tests share, on the CPU (test_coupling.cpp) and the GPU (gpu/test_coupling.cpp): a square
// cloth, the cloth's momentum, and a rigid world in empty space.

#include <drape/drape.hpp>
#include <drape/rigid/world.hpp>

#include <memory>

namespace drape::test {

/// An n x n grid cloth, `spacing` apart, at height z.
template <class S> std::shared_ptr<const ClothAsset<S>> squareCloth(int n, double spacing, double z) {
  SheetDesc grid;
  grid.nx = grid.ny = n;
  grid.spacing = spacing;
  grid.placement.position = {0, 0, z};
  return std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid));
}

/// The cloth's linear momentum (kg m/s): its free vertices' masses times their velocities.
template <class Cloth> Eigen::Vector3d clothMomentum(const Cloth& cloth) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  const auto& state = cloth.state();
  for (Index i = 0; i < cloth.vertexCount(); ++i)
    if (state.invMass[std::size_t(i)] > 0)
      p += state.v[std::size_t(i)].template cast<double>() / double(state.invMass[std::size_t(i)]);
  return p;
}

/// A rigid world in empty space: no gravity, no ground.
inline RigidSettings emptySpace() {
  RigidSettings rigid;
  rigid.gravity.setZero();
  rigid.ground = false;
  return rigid;
}

}  // namespace drape::test
