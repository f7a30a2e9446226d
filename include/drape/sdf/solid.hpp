#pragma once
// A solid: a shape, a pose, how it moves, and its friction with the cloth.

#include <drape/detail/parallel.hpp>  // DRAPE_ALWAYS_INLINE
#include <drape/coupling/body.hpp>
#include <drape/sdf/convex.hpp>  // every shape's compileSdf must be declared before compileSolid
#include <drape/sdf/grid.hpp>
#include <drape/sdf/shapes.hpp>

#include <cstdint>
#include <limits>

namespace drape {

enum class Motion {
  Static,     ///< never moves; its velocity must be zero
  Kinematic,  ///< moved by its given velocities every substep, unaffected by the cloth
  /// A rigid body the cloth pushes back (docs/design.md §6, §7): its pose and velocities are read from `body`
  /// every substep (the solid's own are ignored), and the contact forces are applied to it.
  Dynamic,
};

/// How the blend weight of the repulsion region falls off with distance (the cloth-rigid coupling thesis, eq. 5.5
/// and the polynomial it mentions): a(t) with t = d / R, 0 at contact and 1 at the region's edge.
enum class Falloff {
  Linear,  ///< a = t
  Smooth,  ///< a = 3t^2 - 2t^3: no kink at either end, so the blend starts and ends gently
};

/// Phase 1 of the cloth-rigid coupling thesis (docs/design.md §5): a cloth vertex within `radius` of the solid's
/// contact shell (0 <= phi - thickness < radius) has its velocity blended toward the solid's velocity at that
/// point before each substep's prediction, v' = a v + (1 - a) v_c. Off (radius 0) by default; a scene with no
/// repulsive solid runs no repulsion loop. The whole velocity is blended, as in the thesis: near a solid it also slows
/// sliding, like a cushion of air.
struct Repulsion {
  double radius = 0;  ///< m beyond the thickness; 0 turns it off
  Falloff falloff = Falloff::Linear;
};

template <class Shape> struct Solid {
  Shape shape{};
  Pose pose{};
  Eigen::Vector3d linearVelocity = Eigen::Vector3d::Zero();   ///< m/s, of the frame origin
  Eigen::Vector3d angularVelocity = Eigen::Vector3d::Zero();  ///< rad/s, world axes, about the frame origin
  Motion motion = Motion::Static;
  double staticFriction = 0;   ///< Coulomb coefficient for sticking
  double dynamicFriction = 0;  ///< Coulomb coefficient while sliding (applied to position and velocity alike)
  Repulsion repulsion{};
  /// The body a Motion::Dynamic solid follows and pushes (not owned; it must outlive its use by the solver).
  /// The shape is in the body's frame, whose origin is its centre of mass.
  CoupledBody* body = nullptr;
};

/// The part of a compiled solid that contact response needs: its velocity field and friction.
template <Scalar S> struct SolidMotion {
  Vec3<S> centre;  ///< frame origin relative to the cloth's local origin (m)
  Vec3<S> linearVelocity;
  Vec3<S> angularVelocity;
  S staticFriction;
  S dynamicFriction;
  std::int32_t body = -1;  ///< index of the solver's coupled body this solid pushes; -1 for none

  /// v_c(x) = v_r + w x (x - x_r): the velocity of the solid's material point at x (the thesis, eq. 5.4).
  DRAPE_ALWAYS_INLINE Vec3<S> velocityAt(const Vec3<S>& x) const { return linearVelocity + spin(x - centre); }
  /// The solid's velocity a contact at x answers to, where the contact's surface point is `anchor` and its normal
  /// n: the material velocity at x (friction holds x to it), with the normal part of the surface's velocity at the
  /// anchor. A face contact moves corners that lie off the surface; at a corner, a spinning solid's material
  /// velocity has a normal part its surface does not have, and removing it would turn a frictionless cloth with
  /// the solid (docs/design.md §4). A vertex contact's anchor is the vertex, where this is velocityAt(x).
  DRAPE_ALWAYS_INLINE Vec3<S> contactVelocityAt(const Vec3<S>& x, const Vec3<S>& n, const Vec3<S>& anchor) const {
    return movedAlong(velocityAt(x), n.dot(spin(anchor - x)), n);
  }
  /// w x d: how much faster the solid's material moves at a point d further on.
  DRAPE_ALWAYS_INLINE Vec3<S> spin(const Vec3<S>& d) const {
    // Written out: in every contact record, where GCC would otherwise call Eigen's cross product out of line.
    const Vec3<S>& w = angularVelocity;
    return Vec3<S>(w.y() * d.z() - w.z() * d.y(), w.z() * d.x() - w.x() * d.z(), w.x() * d.y() - w.y() * d.x());
  }
};

/// A solid ready for one substep: its distance field and motion in the cloth's scalar and local frame.
template <class Shape, Scalar S> struct CompiledSolid {
  Sdf<Shape, S> sdf;
  SolidMotion<S> motion;
  S repulsionRadius = 0;  ///< m beyond the thickness; 0: none
  Falloff falloff = Falloff::Linear;
  /// An axis-aligned box in the cloth's local frame outside which phi is at least the distance to the box
  /// (the broad phase's test); false for an unbounded solid (a plane), which every vertex and face meets.
  bool bounded = false;
  Vec3<S> boxLow = Vec3<S>::Zero(), boxHigh = Vec3<S>::Zero();
};

namespace detail {

template <class Shape> void validateSolid(const Solid<Shape>& s, const std::string& name) {
  require(detail::allFinite(s.pose.position) && detail::allFinite(s.pose.rotation.coeffs()) &&
              std::abs(s.pose.rotation.norm() - 1.0) < 1e-6,
          name + ": pose must be finite with a unit quaternion");
  require(detail::allFinite(s.linearVelocity) && detail::allFinite(s.angularVelocity), name + ": velocities must be finite");
  require(s.motion != Motion::Static || (s.linearVelocity.isZero(0) && s.angularVelocity.isZero(0)),
          name + ": a static solid must have zero velocity (make it Motion::Kinematic to move it)");
  require(s.motion == Motion::Static || s.motion == Motion::Kinematic || s.motion == Motion::Dynamic,
          name + ": motion is not a Motion value");
  require((s.motion == Motion::Dynamic) == (s.body != nullptr),
          name + (s.body ? ": a body is given but the motion is not Motion::Dynamic"
                         : ": a Motion::Dynamic solid needs the body it follows"));
  require(std::isfinite(s.staticFriction) && s.staticFriction >= 0,
          name + ": staticFriction must be >= 0 (got " + detail::formatNumber(s.staticFriction) + ")");
  require(std::isfinite(s.dynamicFriction) && s.dynamicFriction >= 0,
          name + ": dynamicFriction must be >= 0 (got " + detail::formatNumber(s.dynamicFriction) + ")");
  require(std::isfinite(s.repulsion.radius) && s.repulsion.radius >= 0 && s.repulsion.radius <= 10,
          name + ": repulsion radius must be in [0, 10] m (got " + detail::formatNumber(s.repulsion.radius) + ")");
  require(s.repulsion.falloff == Falloff::Linear || s.repulsion.falloff == Falloff::Smooth,
          name + ": repulsion falloff is not a Falloff value");
  validateShape(s.shape);
}

/// The shape's bounding box in its own frame, as centre and half extents; false for an unbounded shape. For a
/// grid distance field it is the grid's box: beyond it the field is at least the distance to the box.
inline bool shapeBox(const Plane&, Eigen::Vector3d&, Eigen::Vector3d&) { return false; }
inline bool shapeBox(const Sphere& s, Eigen::Vector3d& c, Eigen::Vector3d& e) {
  c.setZero();
  e.setConstant(s.radius);
  return true;
}
inline bool shapeBox(const Box& b, Eigen::Vector3d& c, Eigen::Vector3d& e) {
  c.setZero();
  e = b.halfExtents;
  return true;
}
inline bool shapeBox(const Capsule& s, Eigen::Vector3d& c, Eigen::Vector3d& e) {
  c.setZero();
  e = {s.radius, s.radius, s.halfHeight + s.radius};
  return true;
}
inline bool shapeBox(const Cylinder& s, Eigen::Vector3d& c, Eigen::Vector3d& e) {
  c.setZero();
  e = {s.radius, s.radius, s.halfHeight};
  return true;
}
inline bool shapeBox(const ConvexHull& h, Eigen::Vector3d& c, Eigen::Vector3d& e) {
  c.setZero();
  e.setConstant(h.boundingRadius());
  return true;
}
inline bool shapeBox(const MeshShape& m, Eigen::Vector3d& c, Eigen::Vector3d& e) {
  c = 0.5 * (m.grid->lower + m.grid->upper());
  e = 0.5 * (m.grid->upper() - m.grid->lower);
  return true;
}

/// Places the solid's bounding box in the cloth's local frame, grown by a margin that covers rounding to S (a
/// field evaluated in float is off by some ulps of the coordinates).
template <class Shape, Scalar S> void placeBounds(CompiledSolid<Shape, S>& out, const Solid<Shape>& s,
                                                  const Eigen::Vector3d& origin) {
  Eigen::Vector3d c, e;
  out.bounded = shapeBox(s.shape, c, e);
  if (!out.bounded) return;
  const Eigen::Matrix3d r = s.pose.rotation.toRotationMatrix();
  const Eigen::Vector3d mid = s.pose.position - origin + r * c;
  const Eigen::Vector3d half = r.cwiseAbs() * e;
  const double pad = 1e-6 + 64 * double(std::numeric_limits<S>::epsilon()) * (mid.cwiseAbs() + half).maxCoeff();
  out.boxLow = (mid - half).array().cast<S>() - S(pad);
  out.boxHigh = (mid + half).array().cast<S>() + S(pad);
}

template <class Shape, Scalar S>
CompiledSolid<Shape, S> compileSolid(const Solid<Shape>& s, const Eigen::Vector3d& origin) {
  CompiledSolid<Shape, S> out{compileSdf<S>(s.shape, s.pose, origin),
          {(s.pose.position - origin).template cast<S>(), s.linearVelocity.template cast<S>(), s.angularVelocity.template cast<S>(),
           S(s.staticFriction), S(s.dynamicFriction)},
          S(s.repulsion.radius),
          s.repulsion.falloff};
  placeBounds(out, s, origin);
  return out;
}

/// Recompiles `sdf` for a new pose. Every field is rebuilt, except that a hull keeps the query data it was
/// built with (its overload is in convex.hpp): the caller resets `sdf` to a default one when the shape itself changes.
template <Scalar S, class Shape>
void refreshSdf(Sdf<Shape, S>& sdf, const Shape& shape, const Pose& pose, const Eigen::Vector3d& origin) {
  sdf = compileSdf<S>(shape, pose, origin);
}

/// Compiles a solid for a new substep into `out`, which holds its compilation of the last substep (or a
/// default one): a field whose data depends on the shape alone (a hull's planes and edges) keeps it and only
/// takes the new pose (refreshSdf), so stepping a hull allocates nothing.
template <class Shape, Scalar S>
void recompileSolid(CompiledSolid<Shape, S>& out, const Solid<Shape>& s, const Eigen::Vector3d& origin) {
  refreshSdf<S>(out.sdf, s.shape, s.pose, origin);
  out.motion = {(s.pose.position - origin).template cast<S>(), s.linearVelocity.template cast<S>(),
                s.angularVelocity.template cast<S>(), S(s.staticFriction), S(s.dynamicFriction)};
  out.repulsionRadius = S(s.repulsion.radius);
  out.falloff = s.repulsion.falloff;
  placeBounds(out, s, origin);
}

/// Advances a kinematic solid's pose by its velocities over h seconds (exact for constant velocities). A
/// dynamic solid first takes its body's pose and velocities, then is carried the same way to where the body
/// will be at the end of the substep if no force acts, which is where the cloth's prediction meets it.
template <class Shape> void advancePose(Solid<Shape>& s, double h) {
  if (s.motion == Motion::Dynamic) {
    s.pose = s.body->pose();
    s.linearVelocity = s.body->linearVelocity();
    s.angularVelocity = s.body->angularVelocity();
    require(detail::allFinite(s.pose.position) && detail::allFinite(s.linearVelocity) &&
                detail::allFinite(s.angularVelocity),
            "a coupled body's pose or velocity is not finite");
  } else if (s.motion != Motion::Kinematic) {
    return;
  }
  s.pose.position += h * s.linearVelocity;
  const double angle = s.angularVelocity.norm() * h;
  if (angle > 0)
    s.pose.rotation = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, s.angularVelocity.normalized())) *
                       s.pose.rotation)
                          .normalized();
}

}  // namespace detail
}  // namespace drape
