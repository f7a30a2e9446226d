#pragma once
// The shapes of solids and rigid bodies, each described in double in its own frame (docs/design.md §2): what
// a distance field (sdf/) and a rigid body (rigid/) are made from. Neither of those folders includes the other.

#include <drape/math.hpp>

#include <cmath>
#include <string>

namespace drape {

/// The half-space below the solid frame's z = 0 plane; the outward normal is the frame's +z.
struct Plane {};
/// A ball centred on the solid frame's origin.
struct Sphere {
  double radius = 0.5;  ///< m
};
/// A box centred on the solid frame's origin, aligned with its axes.
struct Box {
  Eigen::Vector3d halfExtents{0.5, 0.5, 0.5};  ///< m
};
/// Points within `radius` of the segment from -halfHeight to +halfHeight along the solid frame's z axis.
struct Capsule {
  double radius = 0.1;      ///< m
  double halfHeight = 0.5;  ///< m, half the length of the core segment
};

/// A solid cylinder centred on the body frame's origin, its axis along the frame's z (like Capsule).
struct Cylinder {
  double radius = 0.5;      ///< m
  double halfHeight = 0.5;  ///< m, half the length along z
};

namespace detail {

inline void validateShape(const Plane&) {}
inline void validateShape(const Sphere& s) {
  require(std::isfinite(s.radius) && s.radius > 0, "sphere radius must be positive and finite (got " +
                                                       std::to_string(s.radius) + ")");
}
inline void validateShape(const Box& b) {
  require(detail::allFinite(b.halfExtents) && (b.halfExtents.array() > 0).all(),
          "box half extents must be positive and finite");
}
inline void validateShape(const Capsule& c) {
  require(std::isfinite(c.radius) && c.radius > 0, "capsule radius must be positive and finite (got " +
                                                       std::to_string(c.radius) + ")");
  require(std::isfinite(c.halfHeight) && c.halfHeight >= 0,
          "capsule halfHeight must be non-negative and finite (got " + std::to_string(c.halfHeight) + ")");
}

inline void validateShape(const Cylinder& c) {
  require(std::isfinite(c.radius) && c.radius > 0, "cylinder radius must be positive and finite (got " +
                                                       std::to_string(c.radius) + ")");
  require(std::isfinite(c.halfHeight) && c.halfHeight > 0,
          "cylinder halfHeight must be positive and finite (got " + std::to_string(c.halfHeight) + ")");
}

}  // namespace detail
}  // namespace drape
