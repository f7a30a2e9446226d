#pragma once
// Convex shapes of rigid bodies, their mass properties, support functions, bounding boxes and supporting
// features (the face, edge or point that touches). No libccd here: the narrow phase is in narrowphase.hpp.
//
// Every shape is described in its body frame, whose origin is the centre of mass: sphere, box, capsule and
// cylinder are centred on it by symmetry; a convex hull is shifted there when it is built.

#include <drape/math.hpp>
#include <drape/shapes/convex_hull.hpp>
#include <drape/shapes/shapes.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace drape {

using RigidShape = std::variant<Sphere, Box, Capsule, Cylinder, ConvexHull>;

/// Mass and inertia of a body about its centre of mass.
struct MassProperties {
  double mass = 1;                                           ///< kg
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Identity();     ///< kg m^2, body axes, about the centre of mass
};

/// An axis-aligned bounding box in world coordinates (m).
struct Aabb {
  Eigen::Vector3d min;
  Eigen::Vector3d max;
  bool overlaps(const Aabb& o) const {
    return (min.array() <= o.max.array()).all() && (o.min.array() <= max.array()).all();
  }
};

namespace detail {

// --- Validation ----------------------------------------------------------------------------------------------

inline void validateRigidShape(const RigidShape& s) {
  std::visit([](const auto& shape) { validateShape(shape); }, s);
}

/// Mass positive and finite; inertia finite, symmetric, positive definite, and its principal moments obey
/// the triangle inequality (I1 <= I2 + I3) that every real mass distribution satisfies.
inline void validateMassProperties(const MassProperties& m, const std::string& name) {
  require(std::isfinite(m.mass) && m.mass > 0, name + ": mass must be positive and finite (got " +
                                                   std::to_string(m.mass) + ")");
  require(allFinite(m.inertia), name + ": inertia must be finite");
  const double scale = m.inertia.cwiseAbs().maxCoeff();
  require(scale > 0, name + ": inertia must be positive definite (got zero)");
  require((m.inertia - m.inertia.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale,
          name + ": inertia must be symmetric");
  const Eigen::Vector3d p = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m.inertia, Eigen::EigenvaluesOnly).eigenvalues();
  require(p.minCoeff() > 1e-12 * scale, name + ": inertia must be positive definite (principal moments " +
                                            std::to_string(p[0]) + ", " + std::to_string(p[1]) + ", " +
                                            std::to_string(p[2]) + ")");
  require(p[2] <= (p[0] + p[1]) * (1 + 1e-9),
          name + ": inertia principal moments break the triangle inequality (" + std::to_string(p[0]) + " + " +
              std::to_string(p[1]) + " < " + std::to_string(p[2]) + ")");
}

}  // namespace detail

// --- Mass properties -----------------------------------------------------------------------------------------

namespace detail {

inline double volumeOf(const Sphere& s) { return 4.0 / 3.0 * std::numbers::pi * s.radius * s.radius * s.radius; }
inline double volumeOf(const Box& b) { return 8 * b.halfExtents.prod(); }
inline double volumeOf(const Cylinder& c) { return std::numbers::pi * c.radius * c.radius * 2 * c.halfHeight; }
inline double volumeOf(const Capsule& c) {
  return std::numbers::pi * c.radius * c.radius * (2 * c.halfHeight + 4.0 / 3.0 * c.radius);
}
inline double volumeOf(const ConvexHull& h) { return h.volume(); }

/// Inertia per unit mass (m^2) about the centre of mass.
inline Eigen::Matrix3d unitMassInertia(const Sphere& s) {
  return Eigen::Matrix3d::Identity() * (0.4 * s.radius * s.radius);
}
inline Eigen::Matrix3d unitMassInertia(const Box& b) {
  const Eigen::Vector3d e2 = b.halfExtents.cwiseAbs2();
  return Eigen::Vector3d(e2.y() + e2.z(), e2.x() + e2.z(), e2.x() + e2.y()).asDiagonal() * (1.0 / 3.0);
}
inline Eigen::Matrix3d unitMassInertia(const Cylinder& c) {
  const double r2 = c.radius * c.radius, h2 = c.halfHeight * c.halfHeight;
  const double side = (3 * r2 + 4 * h2) / 12;  // (3 r^2 + H^2) / 12 with H = 2 halfHeight
  return Eigen::Vector3d(side, side, 0.5 * r2).asDiagonal();
}
/// A cylinder of length H = 2 halfHeight plus two hemispheres; a hemisphere's own centre of mass is 3r/8 from
/// its flat face, which gives the parallel-axis term m_h (2r^2/5 + H^2/4 + 3Hr/8) for each cap.
inline Eigen::Matrix3d unitMassInertia(const Capsule& c) {
  const double r = c.radius, H = 2 * c.halfHeight;
  const double vc = std::numbers::pi * r * r * H, vh = 2.0 / 3.0 * std::numbers::pi * r * r * r;
  const double total = vc + 2 * vh;
  const double axial = vc * r * r / 2 + 2 * vh * 0.4 * r * r;
  const double side = vc * (3 * r * r + H * H) / 12 + 2 * vh * (0.4 * r * r + H * H / 4 + 3 * H * r / 8);
  return Eigen::Vector3d(side, side, axial).asDiagonal() * (1 / total);
}
inline Eigen::Matrix3d unitMassInertia(const ConvexHull& h) { return h.unitInertia() / h.volume(); }

}  // namespace detail

/// Volume of a shape (m^3).
inline double volume(const RigidShape& shape) {
  detail::validateRigidShape(shape);
  return std::visit([](const auto& s) { return detail::volumeOf(s); }, shape);
}

/// Mass properties of a shape of uniform density (kg/m^3).
inline MassProperties massFromDensity(const RigidShape& shape, double density) {
  detail::require(std::isfinite(density) && density > 0,
                  "density must be positive and finite (got " + std::to_string(density) + ")");
  detail::validateRigidShape(shape);
  return std::visit(
      [&](const auto& s) {
        const double m = density * detail::volumeOf(s);
        return MassProperties{m, m * detail::unitMassInertia(s)};
      },
      shape);
}

/// Mass properties of a shape of uniform density with the given mass (kg).
inline MassProperties massFromMass(const RigidShape& shape, double mass) {
  detail::require(std::isfinite(mass) && mass > 0, "mass must be positive and finite (got " + std::to_string(mass) + ")");
  detail::validateRigidShape(shape);
  return std::visit([&](const auto& s) { return MassProperties{mass, mass * detail::unitMassInertia(s)}; }, shape);
}

// --- Geometry queries ----------------------------------------------------------------------------------------

namespace detail {

inline double signOf(double x) { return x < 0 ? -1.0 : 1.0; }

/// The point of the shape farthest along `d` (body frame; d need not be unit, may be zero).
inline Eigen::Vector3d supportLocal(const Sphere& s, const Eigen::Vector3d& d) {
  const double len = d.norm();
  return len > 0 ? Eigen::Vector3d(d * (s.radius / len)) : Eigen::Vector3d(0, 0, s.radius);
}
inline Eigen::Vector3d supportLocal(const Box& b, const Eigen::Vector3d& d) {
  return {signOf(d.x()) * b.halfExtents.x(), signOf(d.y()) * b.halfExtents.y(), signOf(d.z()) * b.halfExtents.z()};
}
inline Eigen::Vector3d supportLocal(const Capsule& c, const Eigen::Vector3d& d) {
  return Eigen::Vector3d(0, 0, signOf(d.z()) * c.halfHeight) + supportLocal(Sphere{c.radius}, d);
}
inline Eigen::Vector3d supportLocal(const Cylinder& c, const Eigen::Vector3d& d) {
  const double radial = std::hypot(d.x(), d.y());
  Eigen::Vector3d p(0, 0, signOf(d.z()) * c.halfHeight);
  if (radial > 0) p.head<2>() = d.head<2>() * (c.radius / radial);
  return p;
}
inline Eigen::Vector3d supportLocal(const ConvexHull& h, const Eigen::Vector3d& d) {
  const auto& v = h.vertices();
  std::size_t best = 0;
  double bestDot = v[0].dot(d);
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double x = v[i].dot(d);
    if (x > bestDot) best = i, bestDot = x;
  }
  return v[best];
}
inline Eigen::Vector3d supportLocal(const RigidShape& shape, const Eigen::Vector3d& d) {
  return std::visit([&](const auto& s) { return supportLocal(s, d); }, shape);
}

/// Radius of a ball about the body origin that holds the shape (m).
inline double boundingRadius(const RigidShape& shape) {
  struct {
    double operator()(const Sphere& s) const { return s.radius; }
    double operator()(const Box& b) const { return b.halfExtents.norm(); }
    double operator()(const Capsule& c) const { return c.radius + c.halfHeight; }
    double operator()(const Cylinder& c) const { return std::hypot(c.radius, c.halfHeight); }
    double operator()(const ConvexHull& h) const { return h.boundingRadius(); }
  } visitor;
  return std::visit(visitor, shape);
}

/// World bounding box of the shape placed by `pose` (rotation matrix R, position x), exact for every shape.
inline Aabb worldAabb(const RigidShape& shape, const Eigen::Matrix3d& R, const Eigen::Vector3d& x) {
  struct {
    const Eigen::Matrix3d& R;
    Eigen::Vector3d operator()(const Sphere& s) const { return Eigen::Vector3d::Constant(s.radius); }
    Eigen::Vector3d operator()(const Box& b) const { return R.cwiseAbs() * b.halfExtents; }
    Eigen::Vector3d operator()(const Capsule& c) const {
      return R.col(2).cwiseAbs() * c.halfHeight + Eigen::Vector3d::Constant(c.radius);
    }
    Eigen::Vector3d operator()(const Cylinder& c) const {
      const Eigen::Vector3d a = R.col(2);
      const Eigen::Vector3d radial = (Eigen::Vector3d::Ones() - a.cwiseAbs2()).cwiseMax(0).cwiseSqrt();
      return a.cwiseAbs() * c.halfHeight + radial * c.radius;
    }
    Eigen::Vector3d operator()(const ConvexHull&) const { return Eigen::Vector3d::Zero(); }
  } extent{R};
  if (const auto* h = std::get_if<ConvexHull>(&shape)) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (const auto& v : h->vertices()) {
      const Eigen::Vector3d w = R * v;
      lo = lo.cwiseMin(w), hi = hi.cwiseMax(w);
    }
    return {lo + x, hi + x};
  }
  const Eigen::Vector3d e = std::visit(extent, shape);
  return {x - e, x + e};
}

/// Most points a supporting feature has (a hull face with more is reduced to its best triangle).
inline constexpr int kMaxFeaturePoints = 32;

/// The part of a shape's surface that faces a direction: a polygon (count >= 3, counter-clockwise about its
/// outward `normal`), a segment (count 2) or a point (count 1). World coordinates.
struct Feature {
  int count = 0;
  std::array<Eigen::Vector3d, kMaxFeaturePoints> points;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

/// Sine of the largest tilt between a capsule or cylinder side (or a cylinder cap) and the contact plane
/// for which it is offered as a segment (or disc) rather than a point. Points of it that are farther than
/// the contact margin from the other body are dropped afterwards, so a generous angle costs nothing.
inline constexpr double kFlatFeatureSin = 0.2;
/// Points of a cylinder cap's polygon (one of them is always the cap's support point).
inline constexpr int kCapPoints = 8;

/// The supporting feature of `shape`, placed by (R, x), in the world direction `n` (unit).
inline Feature supportingFeature(const RigidShape& shape, const Eigen::Matrix3d& R, const Eigen::Vector3d& x,
                                 const Eigen::Vector3d& n) {
  Feature f;
  const Eigen::Vector3d d = R.transpose() * n;
  auto point = [&](const Eigen::Vector3d& local) { f.points[f.count++] = R * local + x; };
  if (const auto* b = std::get_if<Box>(&shape)) {
    int k = 0;
    d.cwiseAbs().maxCoeff(&k);
    const double s = signOf(d[k]);
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    const Eigen::Vector3d h = b->halfExtents;
    // Counter-clockwise about s * e_k: (i, j) is right-handed with k.
    const double us[4] = {1, -1, -1, 1}, vs[4] = {1, 1, -1, -1};
    for (int c = 0; c < 4; ++c) {
      Eigen::Vector3d p;
      p[k] = s * h[k];
      p[i] = us[c] * h[i];
      p[j] = s * vs[c] * h[j];
      point(p);
    }
    f.normal = R.col(k) * s;
  } else if (const auto* c = std::get_if<Capsule>(&shape)) {
    if (std::abs(d.z()) < kFlatFeatureSin) {
      const Eigen::Vector3d radial = Eigen::Vector3d(d.x(), d.y(), 0).normalized() * c->radius;
      point(radial + Eigen::Vector3d(0, 0, c->halfHeight));
      point(radial - Eigen::Vector3d(0, 0, c->halfHeight));
    } else {
      point(supportLocal(*c, d));
    }
  } else if (const auto* y = std::get_if<Cylinder>(&shape)) {
    const double radial = std::hypot(d.x(), d.y());
    if (std::abs(d.z()) > std::sqrt(1 - kFlatFeatureSin * kFlatFeatureSin)) {
      const double s = signOf(d.z());
      const double start = radial > 0 ? std::atan2(d.y(), d.x()) : 0.0;
      for (int k = 0; k < kCapPoints; ++k) {
        // Counter-clockwise about s * z.
        const double a = start + s * 2 * std::numbers::pi * k / kCapPoints;
        point({y->radius * std::cos(a), y->radius * std::sin(a), s * y->halfHeight});
      }
      f.normal = R.col(2) * s;
    } else if (std::abs(d.z()) < kFlatFeatureSin) {
      const Eigen::Vector3d r = Eigen::Vector3d(d.x(), d.y(), 0) * (y->radius / radial);
      point(r + Eigen::Vector3d(0, 0, y->halfHeight));
      point(r - Eigen::Vector3d(0, 0, y->halfHeight));
    } else {
      point(supportLocal(*y, d));
    }
  } else if (const auto* h = std::get_if<ConvexHull>(&shape)) {
    const auto& faces = h->faces();
    std::size_t best = 0;
    for (std::size_t i = 1; i < faces.size(); ++i)
      if (faces[i].normal.dot(d) > faces[best].normal.dot(d)) best = i;
    const auto& face = faces[best];
    if (static_cast<int>(face.vertices.size()) <= kMaxFeaturePoints) {
      for (int v : face.vertices) point(h->vertices()[v]);
    } else {
      point(supportLocal(*h, d));
    }
    if (f.count >= 3) f.normal = R * face.normal;
  } else {
    point(supportLocal(shape, d));  // sphere
  }
  if (f.count < 3) f.normal = n;
  return f;
}

}  // namespace detail
}  // namespace drape
