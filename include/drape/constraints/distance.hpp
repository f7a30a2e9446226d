#pragma once
// XPBD distance constraints C = |x_a - x_b| - l0, solved Gauss-Seidel colour by colour. Stretch, shear and
// bending all use this kernel: bending is a distance between the far vertices of two adjacent faces, which
// stays stable at compliance 0 (a dihedral-angle bend does not at 2 cm spacing).

#include <drape/cloth/asset.hpp>

namespace drape {

/// One pass over `set`. alphaTilde = compliance / h^2; lambda holds the accumulated multipliers of this
/// substep (zeroed at its start), one per constraint.
template <Scalar S>
void solveDistanceSet(const DistanceSet<S>& set, S alphaTilde, S* lambda, Vec3<S>* x, const S* invMass) {
  const Index colours = set.colourCount();
  for (Index c = 0; c < colours; ++c) {
    const Index end = set.colourOffsets[c + 1];
    for (Index k = set.colourOffsets[c]; k < end; ++k) {
      const auto [a, b] = set.pairs[k];
      const S wa = invMass[a], wb = invMass[b];
      const S denom = wa + wb + alphaTilde;
      const Vec3<S> d = x[a] - x[b];
      const S len = d.norm();
      if (denom <= S(0) || len <= S(0)) continue;  // both fixed and rigid, or coincident: no direction
      const S dLambda = (set.restLength[k] - len - alphaTilde * lambda[k]) / denom;
      lambda[k] += dLambda;
      const Vec3<S> step = (dLambda / len) * d;
      x[a] += wa * step;
      x[b] -= wb * step;
    }
  }
}

/// A vertex attached to a target point (in the cloth's local frame).
template <Scalar S> struct PinTarget {
  Index vertex;
  Vec3<S> target;
};

/// Pins: a vertex of inverse mass 0 is placed on its target (kinematic); any other is pulled toward it by a
/// zero-length XPBD distance constraint.
template <Scalar S>
void solvePins(const PinTarget<S>* pins, Index count, S alphaTilde, S* lambda, Vec3<S>* x, const S* invMass) {
  for (Index k = 0; k < count; ++k) {
    const Index i = pins[k].vertex;
    const S w = invMass[i];
    if (w == S(0)) {
      x[i] = pins[k].target;
      continue;
    }
    const Vec3<S> d = x[i] - pins[k].target;
    const S len = d.norm();
    if (len <= S(0)) continue;
    const S dLambda = (-len - alphaTilde * lambda[k]) / (w + alphaTilde);
    lambda[k] += dLambda;
    x[i] += (w * dLambda / len) * d;
  }
}

}  // namespace drape
