#pragma once
// Solids as signed distance fields: phi(x) < 0 inside, the gradient is the outward unit normal and phi is
// 1-Lipschitz (the face culling relies on it). Shapes are described in double in their own frame; the solver
// compiles each one, once per substep, into an Sdf of the cloth's scalar type, relative to the cloth's local
// origin, so float keeps its precision far from the world origin.

#include <drape/detail/parallel.hpp>
#include <drape/math.hpp>
#include <drape/shapes/shapes.hpp>

#include <algorithm>
#include <string>

namespace drape {

template <class Shape, Scalar S> struct Sdf;
/// A field with no edges (its Sdf declares kSmooth): the gradient turns smoothly along the surface and never flips.
template <class Shape, Scalar S> inline constexpr bool kSmoothField = requires { Sdf<Shape, S>::kSmooth; };
/// Whether the face pass holds deepest points for a field: not on a ball or a capsule, whose fields have no flat
/// stretch (a face is deepest where it is nearest the centre or the core, in closed form, or around a rod thinner
/// than the face by the cutting planes, where holding a point let the GPU's face order carry the rod through a
/// face), nor on a linear field, which has no face pass. The GLSL face pass reads it as
/// DRAPE_HOLDS_DEEPEST_POINTS (gpu/shapes.hpp).
template <class Field>
inline constexpr bool kHoldsDeepestPoints = !requires { Field::kPointCore; } && !requires { Field::kSegmentCore; };
/// Whether a field's face pass answers every vertex within the thickness, so that its vertex pass can be left out
/// where no path is swept: a ball's, whose closed form finds each face's nearest point exactly, so a vertex within
/// the thickness is a corner of faces whose nearest points are at least as deep (docs/design.md §3, "Speed"). Read
/// by the CPU's passes (ContactPasses::projectSolid) and, per solid, by the GPU's (SolidPass::facesAnswerVertices).
template <class Field> inline constexpr bool kFacesAnswerVertices = requires { Field::kPointCore; };


/// Whether a point at squared distance `squared` from a field's core (a ball's centre, a capsule's segment) lies
/// beyond `reach` from it for certain, the root's and the subtraction's roundings included: `squared` must be the
/// very value whose root the field takes. The margin, 1e-5 of reach squared, is about 80 float roundings; a point
/// within it is left to the field. NaN passes over nothing. CPU only: it changes no result, only the work.
template <Scalar S> DRAPE_ALWAYS_INLINE bool clearOfCore(S squared, S reach) {
  return reach > S(0) && squared > reach * reach * S(1 + 1e-5);
}

template <Scalar S> struct Sdf<Plane, S> {
  static constexpr bool kLinear = true;  ///< phi is linear: its minimum over a face is at a vertex
  static constexpr bool kConvex = true;  ///< phi is convex: the face search may use its tangent planes as bounds
  Vec3<S> normal;
  S offset;  ///< phi(x) = normal . x - offset

  S operator()(const Vec3<S>& x, Vec3<S>& gradient) const {
    gradient = normal;
    return normal.dot(x) - offset;
  }
};

template <Scalar S> struct Sdf<Sphere, S> {
  static constexpr bool kLinear = false;
  static constexpr bool kConvex = true;
  static constexpr bool kPointCore = true;  ///< phi is |x - centre| - radius: a face is deepest nearest the centre
  static constexpr bool kSmooth = true;     ///< no edges: the gradient turns smoothly along the surface
  Vec3<S> centre;
  S radius;

  // Inlined: the face pass on a ball evaluates it once per face contact; called, it was 3 % of the step.
  DRAPE_ALWAYS_INLINE S operator()(const Vec3<S>& x, Vec3<S>& gradient) const {
    const Vec3<S> d = x - centre;
    const S len = d.norm();
    gradient = len > S(0) ? Vec3<S>(d / len) : Vec3<S>::UnitZ();
    return len - radius;
  }
  /// Whether phi(x) >= level for certain, read off the squared distance without the root and the division: the
  /// vertex pass's cull (docs/design.md §3, "A vertex clear of a ball"). The squared distance is the one the
  /// field's root is taken of, so a point it passes over reads at least `level` there.
  DRAPE_ALWAYS_INLINE bool beyond(const Vec3<S>& x, S level) const {
    return clearOfCore((x - centre).squaredNorm(), radius + level);
  }
  /// What the level surface through x curves about: a point, about which it curves along every tangent (axis
  /// set to zero), or a line through the point along a unit axis, about which it curves around the axis only.
  Vec3<S> curvatureCentre(const Vec3<S>&, Vec3<S>& axis) const {
    axis.setZero();
    return centre;
  }
};

template <Scalar S> struct Sdf<Box, S> {
  static constexpr bool kLinear = false;
  static constexpr bool kConvex = true;
  Mat3<S> toLocal;  ///< rotation world -> box frame
  Vec3<S> centre;
  Vec3<S> halfExtents;

  S operator()(const Vec3<S>& x, Vec3<S>& gradient) const {
    const Vec3<S> q = toLocal * (x - centre);
    const Vec3<S> excess = q.cwiseAbs() - halfExtents;
    const Vec3<S> outside = excess.cwiseMax(S(0));
    const S outsideLen = outside.norm();
    Vec3<S> g;
    S phi;
    if (outsideLen > S(0)) {
      g = outside.cwiseProduct(q.cwiseSign()) / outsideLen;
      phi = outsideLen;
    } else {  // inside: the nearest face wins
      Index k = 0;
      phi = excess.maxCoeff(&k);
      g = Vec3<S>::Zero();
      g[k] = q[k] < S(0) ? S(-1) : S(1);
    }
    gradient = toLocal.transpose() * g;
    return phi;
  }
};

template <Scalar S> struct Sdf<Capsule, S> {
  static constexpr bool kLinear = false;
  static constexpr bool kConvex = true;
  /// phi is the distance from the core segment less the radius: a face is deepest nearest the segment
  static constexpr bool kSegmentCore = true;
  static constexpr bool kSmooth = true;  ///< no edges: the gradient turns smoothly along the surface
  Vec3<S> centre;
  Vec3<S> axis;  ///< unit, world
  S halfHeight;
  S radius;

  // Inlined, its root and division written out: called from the face pass, the field was 3 % of the capsule
  // scene's step, and inlined as Eigen expressions, its norm and division were calls.
  DRAPE_ALWAYS_INLINE S operator()(const Vec3<S>& x, Vec3<S>& gradient) const {
    const Vec3<S> d = fromCore(x);
    const S len = rootOf(d.squaredNorm());
    if (len > S(0)) {
      gradient = Vec3<S>(d.x() / len, d.y() / len, d.z() / len);
    } else {  // on the core segment: any direction perpendicular to the axis
      gradient = axis.unitOrthogonal();
    }
    return len - radius;
  }
  /// Whether phi(x) >= level for certain (Sdf<Sphere>::beyond), from the squared distance to the core segment.
  DRAPE_ALWAYS_INLINE bool beyond(const Vec3<S>& x, S level) const {
    return clearOfCore(fromCore(x).squaredNorm(), radius + level);
  }
  /// x less its nearest point of the core segment (the sums in Eigen's order, which differs between float and
  /// double).
  DRAPE_ALWAYS_INLINE Vec3<S> fromCore(const Vec3<S>& x) const {
    const Vec3<S> r = detail::minus3(x, centre);
    return movedAlong(r, -std::clamp(r.dot(axis), -halfHeight, halfHeight), axis);
  }
  /// What the level surface through x curves about (Sdf<Sphere>::curvatureCentre): the axis along the side, a
  /// cap's centre beyond the ends.
  Vec3<S> curvatureCentre(const Vec3<S>& x, Vec3<S>& around) const {
    const S t = (x - centre).dot(axis);
    if (std::abs(t) < halfHeight) {
      around = axis;
      return centre + t * axis;
    }
    around.setZero();
    return centre + std::clamp(t, -halfHeight, halfHeight) * axis;
  }
};

namespace detail {

/// Builds the Sdf of a shape placed by `pose`, relative to `origin`.
template <Scalar S> Sdf<Plane, S> compileSdf(const Plane&, const Pose& pose, const Eigen::Vector3d& origin) {
  const Eigen::Vector3d n = pose.rotation * Eigen::Vector3d::UnitZ();
  return {n.template cast<S>(), S(n.dot(pose.position - origin))};
}
template <Scalar S> Sdf<Sphere, S> compileSdf(const Sphere& s, const Pose& pose, const Eigen::Vector3d& origin) {
  return {(pose.position - origin).template cast<S>(), S(s.radius)};
}
template <Scalar S> Sdf<Box, S> compileSdf(const Box& b, const Pose& pose, const Eigen::Vector3d& origin) {
  return {pose.rotation.toRotationMatrix().transpose().template cast<S>(), (pose.position - origin).template cast<S>(),
          b.halfExtents.template cast<S>()};
}
template <Scalar S> Sdf<Capsule, S> compileSdf(const Capsule& c, const Pose& pose, const Eigen::Vector3d& origin) {
  return {(pose.position - origin).template cast<S>(), (pose.rotation * Eigen::Vector3d::UnitZ()).template cast<S>(),
          S(c.halfHeight), S(c.radius)};
}

}  // namespace detail
}  // namespace drape
