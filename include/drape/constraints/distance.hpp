#pragma once
// XPBD distance constraints C = |x_a - x_b| - l0, solved Gauss-Seidel colour by colour. Stretch, shear and
// bending all use this kernel: bending is a distance between the far vertices of two adjacent faces, which
// stays stable at compliance 0 (a dihedral-angle bend does not at 2 cm spacing).

#include <drape/cloth/asset.hpp>
#include <drape/detail/parallel.hpp>

namespace drape {
namespace detail {

/// One constraint (written per component: Eigen's 3-vector expressions cost more instructions here).
template <bool kLambda, Scalar S>
inline void solveDistance(Index a, Index b, S rest, S alphaTilde, S* lambda, Vec3<S>* x, const S* invMass) {
  const S wa = invMass[a], wb = invMass[b];
  S* pa = x[a].data();
  S* pb = x[b].data();
  // Every coordinate is read before any is written: a and b differ, but the compiler cannot know it and would
  // reload b after storing a.
  const S ax = pa[0], ay = pa[1], az = pa[2], bx = pb[0], by = pb[1], bz = pb[2];
  const S dx = ax - bx, dy = ay - by, dz = az - bz;
  const S len = std::sqrt(dx * dx + dy * dy + dz * dz);
  const S denom = wa + wb + alphaTilde;
  if (!(denom > S(0) && len > S(0))) return;  // both fixed and rigid, or coincident: no direction
  S s;                                         // the correction along d per unit inverse mass
  if constexpr (kLambda) {
    const S dLambda = (rest - len - alphaTilde * *lambda) / denom;
    *lambda += dLambda;
    s = dLambda / len;
  } else {
    s = (rest - len) / (denom * len);
  }
  const S sa = wa * s, sb = wb * s;
  pa[0] = ax + sa * dx, pa[1] = ay + sa * dy, pa[2] = az + sa * dz;
  pb[0] = bx - sb * dx, pb[1] = by - sb * dy, pb[2] = bz - sb * dz;
}

}  // namespace detail

/// One pass over `set`. alphaTilde = compliance / h^2; lambda holds the accumulated multipliers of this
/// substep (zeroed at its start), one per constraint; it may be null when kLambda is false. kLambda false drops
/// the multipliers: exact when they cannot matter, i.e. for rigid constraints (alphaTilde 0) or a single pass
/// per substep (lambda is 0 on entry and never read again), and it saves a load, a store and a multiply per
/// constraint.
/// Constraints of one colour share no vertex, so each colour is a work-shared loop when called inside a
/// parallel region; the implicit barrier after it orders the colours. (Four-lane SIMD blocks with gathered
/// and scattered positions measured no faster than this scalar loop: the gathers cost what the packets save.)
template <bool kLambda, Scalar S>
void solveDistanceSet(const DistanceSet<S>& set, S alphaTilde, S* lambda, Vec3<S>* x, const S* invMass) {
  const Index colours = set.colourCount();
  const auto* pairs = set.pairs.data();
  const S* rest = set.restLength.data();
  for (Index c = 0; c < colours; ++c) {
    const Index begin = set.colourOffsets[c], end = set.colourOffsets[c + 1];
    DRAPE_OMP(for schedule(static))
    for (Index k = begin; k < end; ++k)
      detail::solveDistance<kLambda>(pairs[k][0], pairs[k][1], rest[k], alphaTilde, kLambda ? lambda + k : nullptr,
                                     x, invMass);
  }
}

/// A vertex attached to a target point (in the cloth's local frame).
template <Scalar S> struct PinTarget {
  Index vertex;
  Vec3<S> target;
};

/// Pins: a vertex of inverse mass 0 is placed on its target (kinematic); any other is pulled toward it by a
/// zero-length XPBD distance constraint. Serial: two pins may hold the same vertex.
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
