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

/// A shape's size: finite, above zero (or at zero where `zeroOk`) and at most limits::kMaxShapeSize.
inline void requireSize(double value, bool zeroOk, const char* what) {
  require(std::isfinite(value) && (value > 0 || (zeroOk && value == 0)) && value <= limits::kMaxShapeSize, [&] {
    return std::string(what) + (zeroOk ? " must be in [0, " : " must be in (0, ") +
           formatNumber(limits::kMaxShapeSize) + "] m (got " + formatNumber(value) + ")";
  });
}

inline void validateShape(const Plane&) {}
inline void validateShape(const Sphere& s) { requireSize(s.radius, false, "sphere radius"); }
inline void validateShape(const Box& b) {
  requireSize(b.halfExtents.x(), false, "box half extents: x");
  requireSize(b.halfExtents.y(), false, "box half extents: y");
  requireSize(b.halfExtents.z(), false, "box half extents: z");
}
inline void validateShape(const Capsule& c) {
  requireSize(c.radius, false, "capsule radius");
  requireSize(c.halfHeight, true, "capsule halfHeight");
}
inline void validateShape(const Cylinder& c) {
  requireSize(c.radius, false, "cylinder radius");
  requireSize(c.halfHeight, false, "cylinder halfHeight");
}

}  // namespace detail
}  // namespace drape
