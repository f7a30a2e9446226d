#pragma once
// A convex hull of a point set: a rigid body's shape and a solid's distance field (sdf/convex.hpp).

#include <drape/math.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace drape {

/// The convex hull of a point set. Built once from the points (an incremental hull, O(n^2) in the point
/// count: meant for tens to a few hundred points); its mass properties are exact for the hull (a tetrahedron
/// per hull triangle, from an interior point). The vertices are shifted so that the hull's centre of mass
/// (uniform density) is the origin; `shift()` is where that centre was in the input points' frame.
class ConvexHull {
 public:
  /// A hull face: its outward unit normal and its vertices (indices into vertices()), counter-clockwise
  /// about the normal. Coplanar triangles are merged into one polygon.
  struct Face {
    Eigen::Vector3d normal;
    std::vector<int> vertices;
  };

  /// Throws drape::Error if there are fewer than 4 points, a point is not finite, or the points do not span
  /// a volume.
  explicit ConvexHull(const std::vector<Eigen::Vector3d>& points) { build(points); }

  const std::vector<Eigen::Vector3d>& vertices() const { return vertices_; }  ///< m, body frame
  const std::vector<Face>& faces() const { return faces_; }
  double volume() const { return volume_; }                                      ///< m^3
  const Eigen::Vector3d& shift() const { return shift_; }                        ///< m, input frame
  /// Inertia about the centre of mass per unit density (m^5; multiply by kg/m^3).
  const Eigen::Matrix3d& unitInertia() const { return unitInertia_; }
  double boundingRadius() const { return boundingRadius_; }  ///< m, largest vertex distance from the origin

 private:
  void build(const std::vector<Eigen::Vector3d>& points);

  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Face> faces_;
  double volume_ = 0;
  Eigen::Vector3d shift_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d unitInertia_ = Eigen::Matrix3d::Zero();
  double boundingRadius_ = 0;
};

namespace detail {

inline void validateShape(const ConvexHull&) {}  // checked when built

struct HullTriangle {
  std::array<int, 3> v;
  Eigen::Vector3d normal;  // unit, outward
  double offset;           // normal . x for x on the plane
};

inline HullTriangle makeHullTriangle(const std::vector<Eigen::Vector3d>& p, int a, int b, int c) {
  Eigen::Vector3d n = (p[b] - p[a]).cross(p[c] - p[a]);
  const double len = n.norm();
  n = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::UnitZ();
  return {{a, b, c}, n, n.dot(p[a])};
}

}  // namespace detail

inline void ConvexHull::build(const std::vector<Eigen::Vector3d>& points) {
  using detail::require;
  require(points.size() >= 4, "convex hull needs at least 4 points (got " + std::to_string(points.size()) + ")");
  for (const auto& p : points)
    require(detail::allFinite(p) && p.cwiseAbs().maxCoeff() <= limits::kMaxShapeSize,
            "convex hull points must be finite and within 1e5 m of the hull's frame");
  const int n = static_cast<int>(points.size());

  Eigen::Vector3d lo = points[0], hi = points[0];
  for (const auto& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double scale = (hi - lo).norm();
  require(scale > 0, "convex hull points must span a volume (they are all equal)");
  const double eps = 1e-10 * scale;

  // Initial tetrahedron: extreme in x, farthest from it, farthest from that line, farthest from that plane.
  int i0 = 0;
  for (int i = 1; i < n; ++i)
    if (points[i].x() < points[i0].x()) i0 = i;
  auto farthest = [&](auto dist) {
    int best = -1;
    double bestD = -1;
    for (int i = 0; i < n; ++i) {
      const double d = dist(points[i]);
      if (d > bestD) best = i, bestD = d;
    }
    return std::pair{best, bestD};
  };
  const auto [i1, d1] = farthest([&](const Eigen::Vector3d& p) { return (p - points[i0]).norm(); });
  const Eigen::Vector3d e1 = (points[i1] - points[i0]).normalized();
  const auto [i2, d2] = farthest([&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d r = p - points[i0];
    return (r - r.dot(e1) * e1).norm();
  });
  require(d2 > 1e-7 * scale, "convex hull points must span a volume (they are collinear)");
  const Eigen::Vector3d planeN = (points[i1] - points[i0]).cross(points[i2] - points[i0]).normalized();
  const auto [i3, d3] = farthest([&](const Eigen::Vector3d& p) { return std::abs((p - points[i0]).dot(planeN)); });
  require(d3 > 1e-7 * scale, "convex hull points must span a volume (they are coplanar)");
  (void)d1;

  const Eigen::Vector3d inside = (points[i0] + points[i1] + points[i2] + points[i3]) / 4;
  std::vector<detail::HullTriangle> tris;
  auto addOriented = [&](int a, int b, int c) {
    auto t = detail::makeHullTriangle(points, a, b, c);
    if (t.normal.dot(inside) - t.offset > 0) t = detail::makeHullTriangle(points, a, c, b);
    tris.push_back(t);
  };
  addOriented(i0, i1, i2);
  addOriented(i0, i1, i3);
  addOriented(i0, i2, i3);
  addOriented(i1, i2, i3);

  std::vector<std::pair<int, int>> edges;
  std::vector<char> visible;
  for (int p = 0; p < n; ++p) {
    if (p == i0 || p == i1 || p == i2 || p == i3) continue;
    visible.assign(tris.size(), 0);
    bool any = false;
    for (std::size_t t = 0; t < tris.size(); ++t)
      if (tris[t].normal.dot(points[p]) - tris[t].offset > eps) visible[t] = 1, any = true;
    if (!any) continue;
    edges.clear();
    for (std::size_t t = 0; t < tris.size(); ++t)
      if (visible[t])
        for (int k = 0; k < 3; ++k) edges.emplace_back(tris[t].v[k], tris[t].v[(k + 1) % 3]);
    std::vector<detail::HullTriangle> kept;
    kept.reserve(tris.size() + edges.size());
    for (std::size_t t = 0; t < tris.size(); ++t)
      if (!visible[t]) kept.push_back(tris[t]);
    for (const auto& [a, b] : edges) {  // horizon: an edge of a visible face whose twin is not visible
      const bool twin = std::find(edges.begin(), edges.end(), std::pair{b, a}) != edges.end();
      if (!twin) kept.push_back(detail::makeHullTriangle(points, a, b, p));
    }
    tris = std::move(kept);
  }

  // Volume, centre of mass and inertia: one tetrahedron (inside, a, b, c) per triangle. The covariance of a
  // tetrahedron with one vertex at the origin is V/20 (sum_i a_i a_i^T + s s^T), s = a + b + c; the inertia
  // is trace(C) 1 - C (Blow and Binstock, "How to find the inertia tensor (or other mass properties) of a 3D
  // solid body represented by a triangle mesh").
  double volume = 0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& t : tris) {
    const Eigen::Vector3d a = points[t.v[0]] - inside, b = points[t.v[1]] - inside, c = points[t.v[2]] - inside;
    const double v = a.dot(b.cross(c)) / 6;
    const Eigen::Vector3d s = a + b + c;
    volume += v;
    moment += v * s / 4;
    cov += v / 20 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  require(volume > 1e-12 * scale * scale * scale, "convex hull points must span a volume");
  const Eigen::Vector3d com = moment / volume;  // relative to `inside`
  cov -= volume * com * com.transpose();
  unitInertia_ = cov.trace() * Eigen::Matrix3d::Identity() - cov;
  volume_ = volume;
  shift_ = inside + com;

  // Vertices used by the hull, re-indexed and shifted to the centre of mass.
  std::vector<int> index(n, -1);
  for (const auto& t : tris)
    for (int k : t.v)
      if (index[k] < 0) {
        index[k] = static_cast<int>(vertices_.size());
        vertices_.push_back(points[k] - shift_);
        boundingRadius_ = std::max(boundingRadius_, vertices_.back().norm());
      }

  // Faces: coplanar triangles merged, vertices ordered by angle about the face's centroid.
  std::vector<char> used(tris.size(), 0);
  for (std::size_t t = 0; t < tris.size(); ++t) {
    if (used[t]) continue;
    Face face{tris[t].normal, {}};
    for (std::size_t u = t; u < tris.size(); ++u) {
      if (used[u] || tris[u].normal.dot(tris[t].normal) < 1 - 1e-9 || std::abs(tris[u].offset - tris[t].offset) > 1e-9 * scale)
        continue;
      used[u] = 1;
      for (int k : tris[u].v)
        if (std::find(face.vertices.begin(), face.vertices.end(), index[k]) == face.vertices.end())
          face.vertices.push_back(index[k]);
    }
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int v : face.vertices) centre += vertices_[v];
    centre /= static_cast<double>(face.vertices.size());
    const Eigen::Vector3d u = (vertices_[face.vertices[0]] - centre).normalized();
    const Eigen::Vector3d w = face.normal.cross(u);
    std::sort(face.vertices.begin(), face.vertices.end(), [&](int a, int b) {
      const Eigen::Vector3d ra = vertices_[a] - centre, rb = vertices_[b] - centre;
      return std::atan2(ra.dot(w), ra.dot(u)) < std::atan2(rb.dot(w), rb.dot(u));
    });
    faces_.push_back(std::move(face));
  }
}

}  // namespace drape
