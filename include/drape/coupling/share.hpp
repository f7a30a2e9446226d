#pragma once
// A body's exchange with the vertices that touch only it, shared as an inelastic collision of the two
// (docs/design.md §6): the CPU twin of shaders/share.comp, and the formula the GPU solver applies to the sums
// it reads back.

#include <drape/cloth/asset.hpp>
#include <drape/coupling/body.hpp>
#include <drape/coupling/body_sums.hpp>
#include <drape/coupling/contact_forces.hpp>

#include <cstdint>
#include <utility>
#include <vector>

namespace drape::coupling {

/// The estimates take each vertex's push as if the body could not move. Where the vertices pushing a light
/// body together outweigh it, the body got all of their momentum change and left faster than they came, with
/// energy from nowhere: a 1.3 g hull met by a dozen vertices spun up to 870 rad/s in one substep. So each
/// body's exchange with the vertices that touch only it is an inelastic collision of the two: each push f_i is
/// an impulse h f_i between the vertex's mass m_i and the body, and both sides take the share
/// s = Q / (Q + J^T M^-1 J) of it, with Q = sum h^2 |f_i|^2 / m_i, J = (F h, T h) the body's summed impulse and M
/// its mass matrix. For vertices of total mass M_c pushing alike along n at r, s = 1 / (1 + M_c k) with
/// k = 1/m + (r x n)^T I^-1 (r x n): the impulse of two masses meeting, m_eff M_c / (m_eff + M_c) against the
/// immovable body's M_c. A heavy body (k M_c -> 0) keeps all of it. The vertices keep the rest of their change
/// undone, so they meet the body again the next substep: with the impulse estimate, momentum is still
/// exchanged exactly, only later. A vertex touching several solids takes part in each body's exchange with the
/// part of its change that was that body's (ownShare in coupling/contact_forces.hpp). Pinches are not scaled.
inline double exchangeShare(const CoupledBody& body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque,
                            double vertexSide) {
  // Both sides of Q / (Q + J^T M^-1 J) without their common factor h^2.
  const double bodySide = body.inverseMass() * force.squaredNorm() + torque.dot(body.inverseInertiaWorld() * torque);
  return bodySide > 0 ? vertexSide / (vertexSide + bodySide) : 1.0;
}

/// Adds each body's share of its exchange to its force and torque, and scales the exchanged vertices' velocity
/// changes (from vPre) to their side's share. `exchanged` lists each such vertex with its body.
template <Scalar S>
void shareExchanges(const std::vector<CoupledBody*>& bodies, std::vector<BodySums>& sums,
                    const std::vector<Exchanged>& exchanged, std::vector<Eigen::Vector3d>& force,
                    std::vector<Eigen::Vector3d>& torque, Vec3<S>* v, const Vec3<S>* vPre) {
  bool partial = false;
  for (std::size_t b = 0; b < sums.size(); ++b) {
    BodySums& e = sums[b];
    e.share = exchangeShare(*bodies[b], e.exchangeForce, e.exchangeTorque, e.vertexSide);
    force[b] += e.share * e.exchangeForce;
    torque[b] += e.share * e.exchangeTorque;
    partial = partial || e.share < 1;
  }
  if (!partial) return;
  for (const Exchanged& e : exchanged) {
    const S share = S(sums[std::size_t(e.body)].share);
    if (e.slot < 0)
      v[e.vertex] = vPre[e.vertex] + share * (v[e.vertex] - vPre[e.vertex]);
    else  // the part of the change that slot's body made, scaled alone
      v[e.vertex] -= (S(1) - share) * e.part.template cast<S>();
  }
}

}  // namespace drape::coupling
