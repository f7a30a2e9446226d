#pragma once
// What the cloth passes to each coupled body in a substep, summed by kind (docs/design.md §6): the CPU twin of
// shaders/body_sums.comp and of gpu::layout::BodySum. Direct pushes go straight into the body's force and
// torque; an exchange (the vertices whose contacts are all with this body) is summed apart, to be shared
// (coupling/share.hpp); so is a pinch's support, shared among the body's pinches.

#include <drape/math.hpp>

#include <cstddef>
#include <vector>

namespace drape::coupling {

struct BodySums {
  Eigen::Vector3d exchangeForce = Eigen::Vector3d::Zero();   ///< N: the exchange's estimated push, on the body
  Eigen::Vector3d exchangeTorque = Eigen::Vector3d::Zero();  ///< N m, about the body's centre
  double vertexSide = 0;  ///< sum of |f|^2 / m over the exchange's pushes f
  double share = 1;       ///< of the exchange both sides take (shareExchanges)
  Eigen::Vector3d pinchForce = Eigen::Vector3d::Zero();   ///< N: the pinches' supports, summed
  Eigen::Vector3d pinchTorque = Eigen::Vector3d::Zero();  ///< N m
  int pinches = 0;
};

/// Each pinch's support was sized to hold the body alone; a body on several shares it among them.
inline void addPinches(const std::vector<BodySums>& sums, std::vector<Eigen::Vector3d>& force,
                       std::vector<Eigen::Vector3d>& torque) {
  for (std::size_t b = 0; b < sums.size(); ++b) {
    if (sums[b].pinches == 0) continue;
    force[b] += sums[b].pinchForce / sums[b].pinches;
    torque[b] += sums[b].pinchTorque / sums[b].pinches;
  }
}

}  // namespace drape::coupling
