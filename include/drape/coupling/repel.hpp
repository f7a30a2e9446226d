#pragma once
// Phase 1 of the coupling (docs/design.md §5): the repulsion region that slows the cloth before it reaches a
// solid, and the impulse it passes to a coupled body. The CPU twin of shaders/repel.comp.

#include <drape/cloth/state.hpp>
#include <drape/sdf/solid.hpp>

#include <vector>

namespace drape::coupling {

/// Every free vertex of [begin, end) whose distance beyond the thickness, d = phi - thickness, lies in [0, R)
/// has its velocity blended toward the solid's there: v' = a v + (1 - a) v_c, a = falloff(d / R) (the
/// cloth-rigid coupling thesis, eq. 5.4). Each vertex writes only its own velocity.
template <Falloff kFalloff, class Shape, Scalar S>
void repelVertices(Index begin, Index end, const CompiledSolid<Shape, S>& solid, S thickness, const Vec3<S>* x,
                   Vec3<S>* v, const S* invMass) {
  const S invR = S(1) / solid.repulsionRadius;
  for (Index i = begin; i < end; ++i) {
    if (invMass[i] == S(0)) continue;
    Vec3<S> n;
    const S t = (solid.sdf(x[i], n) - thickness) * invR;
    if (!(t >= S(0) && t < S(1))) continue;
    const S a = kFalloff == Falloff::Linear ? t : t * t * (S(3) - S(2) * t);
    v[i] = a * v[i] + (S(1) - a) * solid.motion.velocityAt(x[i]);
  }
}

/// The velocity the region took from each particle near a dynamic solid (from vBefore to the state's), m dv / h,
/// reversed onto the body at the particle's closest point on it and added to its force and torque about
/// `centre` (world).
template <class Shape, Scalar S>
void gatherRepulsionForces(const CompiledSolid<Shape, S>& solid, const ClothState<S>& state, const Vec3<S>* vBefore,
                           S h, bool normalOnly, const Eigen::Vector3d& centre, Eigen::Vector3d& force,
                           Eigen::Vector3d& torque) {
  const Index count = Index(state.x.size());
  for (Index i = 0; i < count; ++i) {
    const Vec3<S> dv = state.v[i] - vBefore[i];
    if (dv.isZero(0)) continue;
    Vec3<S> n;
    const S phi = solid.sdf(state.x[i], n);
    Eigen::Vector3d f = -(dv / (state.invMass[i] * h)).template cast<double>();
    if (normalOnly) f = f.dot(n.template cast<double>()) * n.template cast<double>();
    const Eigen::Vector3d point = state.origin + (state.x[i] - phi * n).template cast<double>();
    force += f;
    torque += (point - centre).cross(f);
  }
}

}  // namespace drape::coupling
