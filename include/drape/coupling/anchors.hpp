#pragma once
// Vertices of inverse mass 0 (anchors) as supports of the coupled bodies (docs/design.md §6, "Anchors hold
// bodies"). An anchor cannot move, so no contact is recorded for it and the estimators, which pass a body the
// momentum its contacts gave the cloth, pass it nothing: a body fell through a cloth's pinned corner. Computed on
// the host for both solvers from the compiled fields, the bodies and the anchors' positions, which the host holds.

#include <drape/coupling/body.hpp>
#include <drape/coupling/body_sums.hpp>
#include <drape/kernel_constants.hpp>
#include <drape/sdf/solid.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace drape::coupling {

/// An anchor: a vertex of inverse mass 0 and where it is (world, m).
struct Anchor {
  Index vertex;
  Eigen::Vector3d world;
};

/// What anchorSupport reads of a coupled body where the cloth met it in this substep.
struct AnchoredBody {
  const CoupledBody& body;
  Eigen::Vector3d centre;  ///< its centre of mass where its field was compiled (world)
  double staticFriction, dynamicFriction;
  std::int32_t index;  ///< the solver's index of the body
};

/// Anchor `vertex` at x (the cloth's local frame, `origin` its world position) lies inside a body's contact shell,
/// phi < thickness, with the field's outward normal n there. It holds the body as a fixed solid holds a body
/// through a pinched vertex (pinchSupport): the impulse that stops the body's approach at its surface point beside
/// the anchor, along n, with the body's effective mass there, plus kPinchRate of the overlap per substep, and
/// Coulomb friction against the body's sliding over the anchor. Recorded in `sums` as one of the body's pinches
/// (addPinches shares them out), and listed in `spacers` (the cloth's local frame) against the fixed world, so that
/// a rigid world's solve keeps the body's surface kSpacerGap - 1 thicknesses off the anchor.
template <Scalar S>
void anchorSupport(Index vertex, const Vec3<S>& x, S phi, const Vec3<S>& n, const AnchoredBody& b,
                   const Eigen::Vector3d& origin, double h, double thickness, bool normalOnly, BodySums& sums,
                   std::vector<Spacer>& spacers) {
  const Eigen::Vector3d nd = n.template cast<double>().normalized();
  const Eigen::Vector3d surface = x.template cast<double>() - double(phi) * nd;  // local
  Spacer p;
  p.vertex = std::int32_t(vertex);
  p.body = b.index;
  p.other = -1;
  p.onBody = surface;
  p.onOther = x.template cast<double>() - (constants::kSpacerGap - 1) * thickness * nd;
  p.normal = -nd;
  spacers.push_back(p);
  ++sums.pinches;
  const Eigen::Vector3d r = surface + origin - b.centre;
  const Eigen::Vector3d at = b.centre + r;
  auto inverseMassAlong = [&](const Eigen::Vector3d& d) {
    const Eigen::Vector3d rd = r.cross(d);
    return b.body.inverseMass() + rd.dot(b.body.inverseInertiaWorld() * rd);
  };
  const Eigen::Vector3d v = b.body.velocityAt(at);
  const double approach = v.dot(nd) + constants::kPinchRate * (thickness - double(phi)) / h;
  const double kn = inverseMassAlong(nd);
  if (!(approach > 0) || !(kn > 0)) return;
  const double push = approach / (kn * h);  // N, on the body along -n
  Eigen::Vector3d force = -push * nd;
  Eigen::Vector3d slide = v - v.dot(nd) * nd;
  const double speed = slide.norm();
  if (speed > 0 && !normalOnly && (b.staticFriction > 0 || b.dynamicFriction > 0)) {
    slide /= speed;
    const double stop = speed / (inverseMassAlong(slide) * h);
    force -= (stop <= b.staticFriction * push ? stop : std::min(stop, b.dynamicFriction * push)) * slide;
  }
  sums.pinchForce += force;
  sums.pinchTorque += r.cross(force);
}

/// Every anchor's support of every coupled solid in `compiled` (one shape type's list) whose contact shell holds
/// it: added to `sums` (one per body) and `spacers`. `bodies` and `centres` are the solver's coupled bodies.
template <class Shape, Scalar S>
void supportAnchors(const std::vector<CompiledSolid<Shape, S>>& compiled, const std::vector<Anchor>& anchors,
                    const std::vector<CoupledBody*>& bodies, const std::vector<Eigen::Vector3d>& centres,
                    const Eigen::Vector3d& origin, double h, double thickness, bool normalOnly,
                    std::vector<BodySums>& sums, std::vector<Spacer>& spacers) {
  const S t = S(thickness);
  for (const CompiledSolid<Shape, S>& solid : compiled) {
    const std::int32_t index = solid.motion.body;
    if (index < 0) continue;
    const AnchoredBody b{*bodies[std::size_t(index)], centres[std::size_t(index)],
                         double(solid.motion.staticFriction), double(solid.motion.dynamicFriction), index};
    for (const Anchor& a : anchors) {
      const Vec3<S> x = (a.world - origin).template cast<S>();
      // Outside its box grown by the thickness a body's field is at least the thickness.
      const bool outside =
          (x.array() < solid.boxLow.array() - t).any() || (x.array() > solid.boxHigh.array() + t).any();
      if (solid.bounded && outside) continue;
      Vec3<S> n;
      const S phi = solid.sdf(x, n);
      if (!(phi < t)) continue;
      anchorSupport(a.vertex, x, phi, n, b, origin, h, thickness, normalOnly, sums[std::size_t(index)], spacers);
    }
  }
}

}  // namespace drape::coupling
