#pragma once
// A solid: a shape, a pose, how it moves, and its friction with the cloth.

#include <drape/sdf/grid.hpp>  // every shape's compileSdf must be declared before compileSolid
#include <drape/sdf/shapes.hpp>

namespace drape {

enum class Motion {
  Static,     ///< never moves; its velocity must be zero
  Kinematic,  ///< moved by its given velocities every substep, unaffected by the cloth
};

template <class Shape> struct Solid {
  Shape shape{};
  Pose pose{};
  Eigen::Vector3d linearVelocity = Eigen::Vector3d::Zero();   ///< m/s, of the frame origin
  Eigen::Vector3d angularVelocity = Eigen::Vector3d::Zero();  ///< rad/s, world axes, about the frame origin
  Motion motion = Motion::Static;
  double staticFriction = 0;   ///< Coulomb coefficient for sticking
  double dynamicFriction = 0;  ///< Coulomb coefficient while sliding (applied to position and velocity alike)
};

/// The part of a compiled solid that contact response needs: its velocity field and friction.
template <Scalar S> struct SolidMotion {
  Vec3<S> centre;  ///< frame origin relative to the cloth's local origin (m)
  Vec3<S> linearVelocity;
  Vec3<S> angularVelocity;
  S staticFriction;
  S dynamicFriction;

  /// v_c(x) = v_r + w x (x - x_r): the velocity of the solid's material point at x (thesis eq. 5.4).
  Vec3<S> velocityAt(const Vec3<S>& x) const { return linearVelocity + angularVelocity.cross(x - centre); }
};

/// A solid ready for one substep: its distance field and motion in the cloth's scalar and local frame.
template <class Shape, Scalar S> struct CompiledSolid {
  Sdf<Shape, S> sdf;
  SolidMotion<S> motion;
};

namespace detail {

template <class Shape> void validateSolid(const Solid<Shape>& s, const std::string& name) {
  require(detail::allFinite(s.pose.position) && detail::allFinite(s.pose.rotation.coeffs()) &&
              std::abs(s.pose.rotation.norm() - 1.0) < 1e-6,
          name + ": pose must be finite with a unit quaternion");
  require(detail::allFinite(s.linearVelocity) && detail::allFinite(s.angularVelocity), name + ": velocities must be finite");
  require(s.motion != Motion::Static || (s.linearVelocity.isZero(0) && s.angularVelocity.isZero(0)),
          name + ": a static solid must have zero velocity (make it Motion::Kinematic to move it)");
  require(std::isfinite(s.staticFriction) && s.staticFriction >= 0,
          name + ": staticFriction must be >= 0 (got " + std::to_string(s.staticFriction) + ")");
  require(std::isfinite(s.dynamicFriction) && s.dynamicFriction >= 0,
          name + ": dynamicFriction must be >= 0 (got " + std::to_string(s.dynamicFriction) + ")");
  validateShape(s.shape);
}

template <class Shape, Scalar S>
CompiledSolid<Shape, S> compileSolid(const Solid<Shape>& s, const Eigen::Vector3d& origin) {
  return {compileSdf<S>(s.shape, s.pose, origin),
          {(s.pose.position - origin).template cast<S>(), s.linearVelocity.template cast<S>(), s.angularVelocity.template cast<S>(),
           S(s.staticFriction), S(s.dynamicFriction)}};
}

/// Advances a kinematic solid's pose by its velocities over h seconds (exact for constant velocities).
template <class Shape> void advancePose(Solid<Shape>& s, double h) {
  if (s.motion != Motion::Kinematic) return;
  s.pose.position += h * s.linearVelocity;
  const double angle = s.angularVelocity.norm() * h;
  if (angle > 0)
    s.pose.rotation = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, s.angularVelocity.normalized())) *
                       s.pose.rotation)
                          .normalized();
}

}  // namespace detail
}  // namespace drape
