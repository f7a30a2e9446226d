#pragma once
// Exact signed distance fields of the two convex rigid-body shapes that shapes.hpp does not cover: Cylinder and
// ConvexHull (drape/rigid/shapes.hpp, which needs no libccd). Like the other fields: phi < 0 inside, the
// gradient is the outward unit normal, phi is 1-Lipschitz and convex. Where phi has no gradient (on the
// medial surface inside, on a rim or edge, on the axis) the normal returned is one of the shape's outward
// normals there, so that it is still a subgradient of phi: phi(y) >= phi(x) + normal . (y - x) for every y,
// which is what a face search may rely on for a kConvex field (for a hull, to within phi in a band of
// sqrt(epsilon) times its size outside its surface: see HullField::nearSurface).
//
// validateShape(const Cylinder&) (radius and halfHeight positive and finite) and validateShape(const
// ConvexHull&) (nothing: the hull is checked when it is built) are declared in drape/rigid/shapes.hpp.

#include <drape/math.hpp>
#include <drape/sdf/shapes.hpp>
#include <drape/shapes/convex_hull.hpp>
#include <drape/shapes/shapes.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

namespace drape {

template <Scalar S> struct Sdf<Cylinder, S> {
  static constexpr bool kLinear = false;
  static constexpr bool kConvex = true;
  Mat3<S> toLocal;  ///< rotation world -> cylinder frame
  Vec3<S> centre;
  S radius;
  S halfHeight;

  /// The 2D field of the (radial, axial) half-plane: dr = r - radius, dz = |z| - halfHeight; outside the rim's
  /// quadrant (both > 0) phi = |(dr, dz)|, else phi = max(dr, dz).
  S operator()(const Vec3<S>& x, Vec3<S>& gradient) const {
    const Vec3<S> q = toLocal * (x - centre);
    const S r2 = q.x() * q.x() + q.y() * q.y();
    // The radial direction; on the axis (or so near it that r^2 is subnormal) every radial direction is
    // equally near: the frame's x.
    S ux = S(1), uy = S(0), r = std::sqrt(r2);
    if (r2 >= std::numeric_limits<S>::min()) ux = q.x() / r, uy = q.y() / r;
    const S sz = q.z() < S(0) ? S(-1) : S(1);
    const S dr = r - radius;
    const S dz = std::abs(q.z()) - halfHeight;
    Vec3<S> g;
    S phi;
    if (dr > S(0) && dz > S(0)) {  // nearest the rim circle
      phi = std::sqrt(dr * dr + dz * dz);
      g = Vec3<S>(dr * ux / phi, dr * uy / phi, dz * sz / phi);
    } else if (dr == S(0) && dz == S(0)) {  // exactly on the rim: the bisector of its two faces' normals
      phi = S(0);
      const S c = std::sqrt(S(0.5));
      g = Vec3<S>(c * ux, c * uy, c * sz);
    } else if (dr >= dz) {  // the side is nearest (outside beside it, or inside nearer it than a cap)
      phi = dr;
      g = Vec3<S>(ux, uy, S(0));
    } else {  // a cap is nearest
      phi = dz;
      g = Vec3<S>(S(0), S(0), sz);
    }
    gradient = toLocal.transpose() * g;
    return phi;
  }
};

namespace detail {

/// A convex hull's faces prepared for distance queries, in its body frame, in the field's scalar type.
template <Scalar S> struct HullField {
  struct Face {
    Vec3<S> normal;  ///< outward, unit
    S offset;        ///< normal . x on the face's plane
    int firstEdge;
    int edgeCount;
  };
  struct Edge {
    Vec3<S> start;     ///< a polygon vertex
    Vec3<S> delta;     ///< to the next vertex counter-clockwise
    Vec3<S> inward;    ///< face normal x delta: points into the polygon, in its plane
    S invLengthSq;     ///< 1 / |delta|^2, 0 for a zero-length edge
    int twin;          ///< the same edge in the neighbouring face (index into edges), -1 if none was found
  };
  std::vector<Face> faces;
  std::vector<Edge> edges;  ///< each face's polygon edges, in order; every hull edge appears twice
  /// Outside by less than this, sqrt(epsilon) times the hull's size, the direction from the closest point
  /// is not the normal: rounding (epsilon times the size) would turn it by up to that over the distance. The
  /// normal is then that of the face q is farthest in front of, an outward normal at the closest point or
  /// next to it, and a subgradient of phi up to the distance. Beyond it the direction is good to sqrt(epsilon).
  S nearSurface;
};

/// Builds the hull's query data (O(vertices of all faces); no pose: it is shared by every pose).
template <Scalar S> std::shared_ptr<const HullField<S>> makeHullField(const ConvexHull& hull) {
  require(!hull.faces().empty() && hull.vertices().size() >= 4,
          "convex hull has no faces (a moved-from ConvexHull?)");
  auto field = std::make_shared<HullField<S>>();
  const auto& v = hull.vertices();
  double size = 0;
  for (const auto& p : v) size = std::max(size, p.cwiseAbs().maxCoeff());
  field->faces.reserve(hull.faces().size());
  std::vector<std::pair<std::pair<int, int>, int>> byVertices;  // (start, end) -> edge, to find the twins
  for (const auto& f : hull.faces()) {
    const int n = static_cast<int>(f.vertices.size());
    require(n >= 3, "convex hull face has fewer than 3 vertices");
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int i : f.vertices) mean += v[i];
    mean /= n;
    field->faces.push_back(
        {f.normal.template cast<S>(), S(f.normal.dot(mean)), static_cast<int>(field->edges.size()), n});
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d& a = v[f.vertices[k]];
      const Eigen::Vector3d d = v[f.vertices[(k + 1) % n]] - a;
      const double lengthSq = d.squaredNorm();
      byVertices.push_back({{f.vertices[k], f.vertices[(k + 1) % n]}, static_cast<int>(field->edges.size())});
      field->edges.push_back({a.template cast<S>(), d.template cast<S>(), f.normal.cross(d).template cast<S>(),
                              lengthSq > 0 ? S(1 / lengthSq) : S(0), -1});
    }
  }
  std::sort(byVertices.begin(), byVertices.end());
  for (const auto& [ends, edge] : byVertices) {
    const std::pair<int, int> reversed{ends.second, ends.first};
    const auto twin = std::lower_bound(byVertices.begin(), byVertices.end(), std::pair{reversed, -1});
    if (twin != byVertices.end() && twin->first == reversed) field->edges[edge].twin = twin->second;
  }
  field->nearSurface = std::sqrt(std::numeric_limits<S>::epsilon()) * S(size);
  return field;
}

}  // namespace detail

/// The exact signed distance to a convex hull. Inside, phi is the largest signed distance to a face plane
/// (exact for a convex polytope: the ball of that radius lies in every half-space and touches the nearest
/// plane on its face). Outside, phi is the distance to the closest point of the surface, which lies on a face
/// that the point is in front of: the projection onto that face's plane if it falls inside the polygon, else
/// the closest point of one of its edges (or a vertex); the normal is the direction from that point. Cost:
/// one dot product per face, then a few per edge of the faces the point is in front of.
///
/// The faces and edges are held through a shared_ptr to data built by compileSdf: copying the field (once per
/// substep per solid) copies a pointer, and the data is laid out for the query (planes with their offsets,
/// edges with their in-plane normals and inverse squared lengths) rather than recomputed from the hull's
/// index lists at every sample. A hull's face count varies, so fixed arrays in the field would bound it.
template <Scalar S> struct Sdf<ConvexHull, S> {
  static constexpr bool kLinear = false;
  static constexpr bool kConvex = true;
  Mat3<S> toLocal;  ///< rotation world -> hull body frame
  Vec3<S> centre;   ///< body frame origin (the hull's centre of mass)
  std::shared_ptr<const detail::HullField<S>> hull;
  /// Hulls of up to this many faces keep their plane distances between the two loops of a query.
  static constexpr int kKeptPlanes = 64;

  S operator()(const Vec3<S>& x, Vec3<S>& gradient) const {
    const Vec3<S> q = toLocal * (x - centre);
    const auto& faces = hull->faces;
    // The planes' distances, kept for the outside search below where the hull is small enough (most are). The
    // GLSL twin reads them again from its buffer: the same bits, without a private array on the GPU.
    S kept[kKeptPlanes];
    const bool keep = faces.size() <= std::size_t(kKeptPlanes);
    std::size_t front = 0;  // the face whose plane q is farthest in front of (least behind)
    S frontDistance = faces[0].normal.dot(q) - faces[0].offset;
    kept[0] = frontDistance;
    for (std::size_t f = 1; f < faces.size(); ++f) {
      const S s = faces[f].normal.dot(q) - faces[f].offset;
      if (keep) kept[f] = s;
      if (s > frontDistance) front = f, frontDistance = s;
    }
    if (frontDistance <= S(0)) {  // inside or on the surface: the nearest plane
      gradient = toLocal.transpose() * faces[front].normal;
      return frontDistance;
    }
    // Outside: the closest point is on a face that q is in front of. Each face, edge and vertex has a region
    // of points whose closest point is on it (the point plus the normal cone there); where q's region is
    // found exactly, it is taken without comparing distances, whose rounding would otherwise let a point a
    // little farther win (the distance to it grows only with the square of its offset, the normal linearly).
    S bestSq = std::numeric_limits<S>::infinity();
    Vec3<S> bestDelta = Vec3<S>::Zero();  // q - the nearest candidate so far
    const auto* edges = hull->edges.data();
    const S slack = hull->nearSurface;  // a face whose region holds q may seem a little farther than it is
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const auto& face = faces[f];
      const S s = keep ? kept[f] : face.normal.dot(q) - face.offset;
      if (!(s > S(0)) || (s > slack && (s - slack) * (s - slack) >= bestSq)) continue;
      const auto* e = edges + face.firstEdge;
      bool inPolygon = true;
      for (int k = 0; k < face.edgeCount; ++k) {
        const Vec3<S> r = q - e[k].start;
        if (r.dot(e[k].inward) >= S(0)) continue;
        inPolygon = false;  // beyond this edge, seen in the face's plane
        const S along = r.dot(e[k].delta) * e[k].invLengthSq;
        const Vec3<S> d = r - std::clamp(along, S(0), S(1)) * e[k].delta;
        const S dSq = d.squaredNorm();
        // The edge's region: beside its inside, beyond it seen from both of its faces.
        if (along > S(0) && along < S(1) && e[k].twin >= 0 &&
            (q - edges[e[k].twin].start).dot(edges[e[k].twin].inward) <= S(0))
          return outside(d, std::sqrt(dSq), faces[front].normal, gradient);
        if (dSq < bestSq) bestSq = dSq, bestDelta = d;
      }
      if (inPolygon) {  // the face's region: no point of the hull is nearer than its plane
        gradient = toLocal.transpose() * face.normal;
        return s;
      }
    }
    // A vertex's region (the nearest vertex wins by a margin there), or a boundary between regions that
    // rounding kept from being found, where the candidates on either side agree.
    return outside(bestDelta, std::sqrt(bestSq), faces[front].normal, gradient);
  }

  /// A lower bound on phi at x that costs one dot product per face: the largest signed distance to the faces'
  /// planes (phi itself inside; outside, the nearest point of the hull is at least that far), less the field's
  /// rounding scale nearSurface, since phi computed through an edge or a vertex may round a little below the
  /// plane's distance. The face search culls with it before it evaluates phi.
  S lowerBound(const Vec3<S>& x) const {
    const Vec3<S> q = toLocal * (x - centre);
    S most = -std::numeric_limits<S>::infinity();
    for (const auto& face : hull->faces) most = std::max(most, face.normal.dot(q) - face.offset);
    return most - hull->nearSurface;
  }

 private:
  S outside(const Vec3<S>& delta, S distance, const Vec3<S>& frontNormal, Vec3<S>& gradient) const {
    gradient = toLocal.transpose() * (distance > hull->nearSurface ? Vec3<S>(delta / distance) : frontNormal);
    return distance;
  }
};

namespace detail {

template <Scalar S> Sdf<Cylinder, S> compileSdf(const Cylinder& c, const Pose& pose, const Eigen::Vector3d& origin) {
  return {pose.rotation.toRotationMatrix().transpose().template cast<S>(), (pose.position - origin).template cast<S>(),
          S(c.radius), S(c.halfHeight)};
}
/// Builds the hull's query data each call (a few allocations and O(hull size) work); a caller that compiles
/// the same hull every substep uses refreshSdf, which builds it once.
template <Scalar S>
Sdf<ConvexHull, S> compileSdf(const ConvexHull& h, const Pose& pose, const Eigen::Vector3d& origin) {
  return {pose.rotation.toRotationMatrix().transpose().template cast<S>(), (pose.position - origin).template cast<S>(),
          makeHullField<S>(h)};
}

/// Recompiles a hull's field for a new pose, keeping the query data it was built with (see refreshSdf in
/// drape/sdf/solid.hpp); a default field (no data yet) is compiled from scratch.
template <Scalar S>
void refreshSdf(Sdf<ConvexHull, S>& sdf, const ConvexHull& hull, const Pose& pose, const Eigen::Vector3d& origin) {
  if (!sdf.hull) {
    sdf = compileSdf<S>(hull, pose, origin);
    return;
  }
  sdf.toLocal = pose.rotation.toRotationMatrix().transpose().template cast<S>();
  sdf.centre = (pose.position - origin).template cast<S>();
}

}  // namespace detail
}  // namespace drape
