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
  /// about the normal. Coplanar triangles are merged into one polygon (within 1e-9 of the hull's size).
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

// --- Exact orientation --------------------------------------------------------------------------------------
// The hull's decisions (is a point in front of a triangle, behind it, or on its plane) are signs of a 3x3
// determinant of coordinate differences. Rounded, they change with how a compiler orders and fuses the
// arithmetic (-march=native fuses some multiply-adds and not others), and a builder that decides differently
// about the same point in two places builds a wrong hull. Here each sign is exact: a rounded determinant with a
// generous error bound decides when it can, and an exact sum of floating-point terms (an expansion, after
// Shewchuk, "Adaptive precision floating-point arithmetic and fast robust geometric predicates", 1997) decides
// the rest. Products are split with std::fma, sums with the two-sum identity: both exact under any
// contraction setting (not under -ffast-math, which reassociates). Exact while no product of three coordinate
// differences underflows (differences above about 1e-100 m).

inline void twoSum(double a, double b, double& sum, double& error) {
  sum = a + b;
  const double bPart = sum - a;
  error = (a - (sum - bPart)) + (b - bPart);
}

/// h = e * b for an expansion e (components nonoverlapping, increasing in magnitude, no zeros); returns h's
/// length, at most 2 * elen.
inline int scaleExpansion(int elen, const double* e, double b, double* h) {
  if (elen == 0) return 0;
  int n = 0;
  double q = e[0] * b, error = std::fma(e[0], b, -q);
  if (error != 0) h[n++] = error;
  for (int i = 1; i < elen; ++i) {
    const double product = e[i] * b, productError = std::fma(e[i], b, -product);
    double sum;
    twoSum(q, productError, sum, error);
    if (error != 0) h[n++] = error;
    twoSum(product, sum, q, error);
    if (error != 0) h[n++] = error;
  }
  if (q != 0) h[n++] = q;
  return n;
}

/// h = e + f, each component of f grown into e in turn; h (room for elen + flen) may be e itself.
inline int sumExpansions(int elen, const double* e, int flen, const double* f, double* h) {
  if (h != e) std::copy(e, e + elen, h);
  int n = elen;
  for (int j = 0; j < flen; ++j) {
    double q = f[j];
    int kept = 0;
    for (int i = 0; i < n; ++i) {
      double error;
      twoSum(q, h[i], q, error);
      if (error != 0) h[kept++] = error;
    }
    if (q != 0) h[kept++] = q;
    n = kept;
  }
  return n;
}

/// h = e * f; returns h's length, at most 2 * elen * flen.
inline int multiplyExpansions(int elen, const double* e, int flen, const double* f, double* h) {
  int n = 0;
  double scaled[64];
  for (int j = 0; j < flen; ++j) {
    const int m = scaleExpansion(elen, e, f[j], scaled);
    n = sumExpansions(n, h, m, scaled, h);
  }
  return n;
}

/// b - a exactly, as an expansion of at most two components.
inline int difference(double b, double a, double* h) {
  double d, error;
  twoSum(b, -a, d, error);
  int n = 0;
  if (error != 0) h[n++] = error;
  if (d != 0) h[n++] = d;
  return n;
}

/// The sign of ((b - a) x (c - a)) . (p - a): +1 if p is in front of the triangle abc (on the side its
/// counter-clockwise normal points to), -1 behind it, 0 exactly on its plane.
inline int orientation(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& p) {
  const Eigen::Vector3d u = b - a, v = c - a, w = p - a;
  const double det = u.x() * (v.y() * w.z() - v.z() * w.y()) + u.y() * (v.z() * w.x() - v.x() * w.z()) +
                     u.z() * (v.x() * w.y() - v.y() * w.x());
  const Eigen::Vector3d au = u.cwiseAbs(), av = v.cwiseAbs(), aw = w.cwiseAbs();
  const double permanent = au.x() * (av.y() * aw.z() + av.z() * aw.y()) +
                           au.y() * (av.z() * aw.x() + av.x() * aw.z()) + au.z() * (av.x() * aw.y() + av.y() * aw.x());
  // The rounded determinant errs by at most about 8 epsilon times the permanent, fused or not (Shewchuk's
  // bound for this form); 1e-13 leaves a margin of over 100.
  if (det > 1e-13 * permanent) return 1;
  if (det < -1e-13 * permanent) return -1;
  double du[3][2], dv[3][2], dw[3][2];
  int nu[3], nv[3], nw[3];
  for (int k = 0; k < 3; ++k) {
    nu[k] = difference(b[k], a[k], du[k]);
    nv[k] = difference(c[k], a[k], dv[k]);
    nw[k] = difference(p[k], a[k], dw[k]);
  }
  double total[192];
  int n = 0;
  for (int k = 0; k < 3; ++k) {  // u_k (v_{k+1} w_{k+2} - v_{k+2} w_{k+1})
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    double plus[8], minus[8], cofactor[16], term[64];
    const int np = multiplyExpansions(nv[k1], dv[k1], nw[k2], dw[k2], plus);
    int nm = multiplyExpansions(nv[k2], dv[k2], nw[k1], dw[k1], minus);
    for (int i = 0; i < nm; ++i) minus[i] = -minus[i];
    const int nc = sumExpansions(np, plus, nm, minus, cofactor);
    const int nt = multiplyExpansions(nc, cofactor, nu[k], du[k], term);
    n = sumExpansions(n, total, nt, term, total);
  }
  return n == 0 ? 0 : (total[n - 1] > 0 ? 1 : -1);  // the largest component decides
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

  // Initial tetrahedron: extreme in x, farthest from it, farthest from that line, farthest from that plane.
  // Rounded distances choose it; the thresholds keep it far from flat, so its orientation is certain.
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

  // Incremental hull over triangles, counter-clockwise seen from outside. A point strictly in front of some
  // triangle is outside: the triangles it sees go, and the horizon (their edges whose twin stays) is joined
  // to it. A point on a plane sees nothing there, so no triangle is ever flat.
  using Tri = std::array<int, 3>;
  std::vector<Tri> tris;
  auto addOutward = [&](int a, int b, int c, int behind) {
    if (detail::orientation(points[a], points[b], points[c], points[behind]) > 0) std::swap(b, c);
    tris.push_back({a, b, c});
  };
  addOutward(i0, i1, i2, i3);
  addOutward(i0, i1, i3, i2);
  addOutward(i0, i2, i3, i1);
  addOutward(i1, i2, i3, i0);

  std::vector<std::pair<int, int>> edges, sortedEdges;
  std::vector<char> visible;
  for (int p = 0; p < n; ++p) {
    if (p == i0 || p == i1 || p == i2 || p == i3) continue;
    visible.assign(tris.size(), 0);
    bool any = false;
    for (std::size_t t = 0; t < tris.size(); ++t)
      if (detail::orientation(points[tris[t][0]], points[tris[t][1]], points[tris[t][2]], points[p]) > 0)
        visible[t] = 1, any = true;
    if (!any) continue;
    edges.clear();
    for (std::size_t t = 0; t < tris.size(); ++t)
      if (visible[t])
        for (int k = 0; k < 3; ++k) edges.emplace_back(tris[t][k], tris[t][(k + 1) % 3]);
    sortedEdges = edges;
    std::sort(sortedEdges.begin(), sortedEdges.end());
    std::vector<Tri> kept;
    kept.reserve(tris.size() + edges.size());
    for (std::size_t t = 0; t < tris.size(); ++t)
      if (!visible[t]) kept.push_back(tris[t]);
    for (const auto& [a, b] : edges)  // horizon: an edge of a visible triangle whose twin is not visible
      if (!std::binary_search(sortedEdges.begin(), sortedEdges.end(), std::pair{b, a})) kept.push_back({a, b, p});
    tris = std::move(kept);
  }

  // Volume, centre of mass and inertia: one tetrahedron (inside, a, b, c) per triangle. The covariance of a
  // tetrahedron with one vertex at the origin is V/20 (sum_i a_i a_i^T + s s^T), s = a + b + c; the inertia
  // is trace(C) 1 - C (Blow and Binstock, "How to find the inertia tensor (or other mass properties) of a 3D
  // solid body represented by a triangle mesh").
  const Eigen::Vector3d inside = (points[i0] + points[i1] + points[i2] + points[i3]) / 4;
  double volume = 0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& t : tris) {
    const Eigen::Vector3d a = points[t[0]] - inside, b = points[t[1]] - inside, c = points[t[2]] - inside;
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

  // Faces: neighbouring triangles merged where they lie within 1e-9 of the hull's size of one plane, grown
  // from the largest triangle not yet taken (whose rounded normal is the most accurate). A sliver along an
  // edge (points a rounding error off its line) has a rounded normal that may point anywhere; it joins a
  // face by its vertices alone, rather than tilting a plane of its own.
  const double flat = 1e-9 * scale;
  const std::size_t count = tris.size();
  std::vector<Eigen::Vector3d> areaNormal(count);  // (b - a) x (c - a): twice the area, outward
  std::vector<std::pair<std::pair<int, int>, int>> byEdge;  // (start, end) -> triangle
  for (std::size_t t = 0; t < count; ++t) {
    const auto& [a, b, c] = tris[t];
    areaNormal[t] = (points[b] - points[a]).cross(points[c] - points[a]);
    for (int k = 0; k < 3; ++k) byEdge.push_back({{tris[t][k], tris[t][(k + 1) % 3]}, static_cast<int>(t)});
  }
  std::sort(byEdge.begin(), byEdge.end());
  auto across = [&](int a, int b) {  // the triangle on the other side of edge a -> b
    const auto it = std::lower_bound(byEdge.begin(), byEdge.end(), std::pair{std::pair{b, a}, -1});
    return it != byEdge.end() && it->first == std::pair{b, a} ? it->second : -1;
  };
  std::vector<int> bySize(count);
  for (std::size_t t = 0; t < count; ++t) bySize[t] = static_cast<int>(t);
  std::stable_sort(bySize.begin(), bySize.end(),
                   [&](int s, int t) { return areaNormal[s].squaredNorm() > areaNormal[t].squaredNorm(); });
  std::vector<int> faceOf(count, -1);
  std::vector<std::vector<int>> members;  // the triangles of each face
  for (int seed : bySize) {
    if (faceOf[seed] >= 0) continue;
    const int face = static_cast<int>(members.size());
    const Eigen::Vector3d normal = areaNormal[seed].normalized();
    const Eigen::Vector3d& origin = points[tris[seed][0]];
    members.push_back({seed});
    faceOf[seed] = face;
    for (std::size_t m = 0; m < members[face].size(); ++m) {
      const Tri t = tris[members[face][m]];
      for (int k = 0; k < 3; ++k) {
        const int u = across(t[k], t[(k + 1) % 3]);
        if (u < 0 || faceOf[u] >= 0) continue;
        bool onPlane = true;
        for (int i : tris[u]) onPlane = onPlane && std::abs(normal.dot(points[i] - origin)) <= flat;
        if (onPlane) faceOf[u] = face, members[face].push_back(u);
      }
    }
  }

  // Each face's polygon is its triangles' boundary, already counter-clockwise. Should a merged set not bound
  // one simple loop (a rounding at the flatness threshold could pinch it), its triangles stay faces of their
  // own, with the set's normal (a sliver's own may point anywhere). Faces come in the order of their first
  // triangle, vertices in the order the triangles first use them.
  std::vector<std::size_t> faceOrder(members.size());
  for (std::size_t f = 0; f < members.size(); ++f) {
    faceOrder[f] = f;
    std::sort(members[f].begin(), members[f].end());
  }
  std::sort(faceOrder.begin(), faceOrder.end(),
            [&](std::size_t f, std::size_t g) { return members[f][0] < members[g][0]; });
  std::vector<std::vector<int>> loops;  // input point indices, one loop per face
  std::vector<Eigen::Vector3d> loopNormals;
  std::vector<std::pair<int, int>> boundary;
  for (std::size_t face : faceOrder) {
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // Newell's: the sum of the triangles' area normals
    boundary.clear();
    for (int t : members[face]) {
      normal += areaNormal[t];
      for (int k = 0; k < 3; ++k) {
        const int a = tris[t][k], b = tris[t][(k + 1) % 3];
        const int u = across(a, b);
        if (u < 0 || faceOf[u] != static_cast<int>(face)) boundary.emplace_back(a, b);
      }
    }
    std::sort(boundary.begin(), boundary.end());
    std::vector<int> loop;
    bool simple = true;
    for (std::size_t e = 1; e < boundary.size(); ++e) simple = simple && boundary[e].first != boundary[e - 1].first;
    auto leaving = [&](int v) { return std::lower_bound(boundary.begin(), boundary.end(), std::pair{v, -1}); };
    int start = tris[members[face][0]][0];  // the first triangle's first vertex, if it is on the boundary
    if (leaving(start) == boundary.end() || leaving(start)->first != start) start = boundary[0].first;
    for (int v = start; simple;) {
      loop.push_back(v);
      const auto next = leaving(v);
      if (next == boundary.end() || next->first != v) simple = false;
      else v = next->second;
      if (v == start || loop.size() > boundary.size()) break;
    }
    if (simple && loop.size() == boundary.size()) {
      // Starting one vertex before the first triangle's first: the order the pinned state hashes of scenes
      // with hulls were recorded with.
      std::rotate(loop.begin(), loop.end() - 1, loop.end());
      loops.push_back(std::move(loop));
      loopNormals.push_back(normal);
    } else {
      for (int t : members[face]) loops.push_back({tris[t][0], tris[t][1], tris[t][2]}), loopNormals.push_back(normal);
    }
  }
  std::vector<char> onFace(n, 0);
  for (const auto& loop : loops)
    for (int k : loop) onFace[k] = 1;
  std::vector<int> index(n, -1);
  for (const auto& t : tris)
    for (int k : t)
      if (onFace[k] && index[k] < 0) {
        index[k] = static_cast<int>(vertices_.size());
        vertices_.push_back(points[k] - shift_);
        boundingRadius_ = std::max(boundingRadius_, vertices_.back().norm());
      }
  for (std::size_t f = 0; f < loops.size(); ++f) {
    Face face{loopNormals[f].normalized(), {}};
    for (int k : loops[f]) face.vertices.push_back(index[k]);
    faces_.push_back(std::move(face));
  }
}

}  // namespace drape
