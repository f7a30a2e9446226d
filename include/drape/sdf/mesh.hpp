#pragma once
// Closed triangle meshes for grid distance fields: the mesh type, its validation, and generators for the
// shapes the tests and benches use (icosphere, box, torus, an L-shaped block). Everything is in double and in
// the mesh's own frame; a mesh becomes a solid through buildDistanceGrid (drape/sdf/grid.hpp).

#include <drape/math.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace drape {

/// A triangle mesh. A mesh that becomes a distance field must be closed, edge-manifold, vertex-manifold and
/// wound counter-clockwise seen from outside (validateClosedMesh).
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;        ///< #V positions (m)
  std::vector<std::array<Index, 3>> triangles;  ///< #F vertex indices, counter-clockwise seen from outside

  Index vertexCount() const { return Index(vertices.size()); }
  Index triangleCount() const { return Index(triangles.size()); }
};

namespace detail {

inline std::uint64_t directedEdgeKey(Index a, Index b) {
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint64_t(std::uint32_t(b));
}

inline std::string edgeName(Index a, Index b) { return "edge (" + std::to_string(a) + ", " + std::to_string(b) + ")"; }

/// Maps each directed edge (a, b) of a validated closed mesh to the triangle that holds it.
inline std::unordered_map<std::uint64_t, Index> directedEdges(const TriangleMesh& mesh) {
  std::unordered_map<std::uint64_t, Index> owner;
  owner.reserve(mesh.triangles.size() * 3);
  for (Index t = 0; t < mesh.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) owner.emplace(directedEdgeKey(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]), t);
  return owner;
}

}  // namespace detail

/// Throws drape::Error naming the first problem that keeps `mesh` from bounding a solid: no triangles,
/// non-finite vertices, indices out of range, a repeated index or zero area in a triangle, an edge with one
/// face (a hole) or more than two (non-manifold), an edge used twice in the same direction (inconsistent
/// winding), a vertex where two fans of faces touch (non-manifold vertex), or a negative enclosed volume
/// (faces wound inside out). Self-intersections are not detected.
inline void validateClosedMesh(const TriangleMesh& mesh) {
  using detail::require;
  const Index nv = mesh.vertexCount();
  const Index nf = mesh.triangleCount();
  require(nf >= 4, "a closed mesh needs at least 4 triangles (got " + std::to_string(nf) + ")");
  for (Index v = 0; v < nv; ++v)
    require(detail::allFinite(mesh.vertices[v]) && mesh.vertices[v].cwiseAbs().maxCoeff() <= limits::kMaxShapeSize,
            [&] { return "mesh vertex " + std::to_string(v) + " is not finite or lies beyond 1e5 m"; });

  for (Index t = 0; t < nf; ++t) {
    const auto& f = mesh.triangles[t];
    const std::string name = "mesh triangle " + std::to_string(t);
    for (int k = 0; k < 3; ++k)
      require(f[k] >= 0 && f[k] < nv,
              name + " has vertex index " + std::to_string(f[k]) + " outside [0, " + std::to_string(nv) + ")");
    require(f[0] != f[1] && f[1] != f[2] && f[0] != f[2], name + " repeats a vertex index");
    const Eigen::Vector3d e0 = mesh.vertices[f[1]] - mesh.vertices[f[0]];
    const Eigen::Vector3d e1 = mesh.vertices[f[2]] - mesh.vertices[f[0]];
    const Eigen::Vector3d e2 = mesh.vertices[f[2]] - mesh.vertices[f[1]];
    const double longest2 = std::max({e0.squaredNorm(), e1.squaredNorm(), e2.squaredNorm()});
    // Twice the area against the longest edge squared: scale-free, and zero for slivers whose normal (and so
    // the sign of the distance) is meaningless.
    require(e0.cross(e1).norm() > 1e-10 * longest2, name + " is degenerate (zero area)");
  }

  // Each directed edge once, and its reverse once: closed, edge-manifold and consistently wound at once.
  std::unordered_map<std::uint64_t, Index> owner;
  owner.reserve(std::size_t(nf) * 3);
  for (Index t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) {
      const Index a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      const auto [it, fresh] = owner.emplace(detail::directedEdgeKey(a, b), t);
      if (!fresh) {
        // Twice in one direction: either a third face on the edge or two neighbours wound oppositely.
        const bool reverseSeen = owner.count(detail::directedEdgeKey(b, a)) != 0;
        require(false, "mesh " + detail::edgeName(a, b) + " of triangle " + std::to_string(t) +
                           (reverseSeen ? " has more than two faces (non-manifold)"
                                        : " is wound the same way by triangles " + std::to_string(it->second) +
                                              " and " + std::to_string(t) + " (inconsistent orientation)"));
      }
    }
  for (Index t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) {
      const Index a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      require(owner.count(detail::directedEdgeKey(b, a)) != 0, "mesh is not closed: " + detail::edgeName(a, b) +
                                                                   " of triangle " + std::to_string(t) +
                                                                   " has no neighbour (a hole)");
    }

  // Vertex-manifold: walking across edges around a vertex must visit all of its faces (one fan, not two cones
  // touching at a point, where the angle-weighted pseudonormal does not give the sign).
  std::vector<Index> incident(std::size_t(nv), 0), firstFace(std::size_t(nv), -1);
  for (Index t = 0; t < nf; ++t)
    for (Index v : mesh.triangles[t]) {
      ++incident[v];
      if (firstFace[v] < 0) firstFace[v] = t;
    }
  for (Index v = 0; v < nv; ++v) {
    if (firstFace[v] < 0) continue;  // unused vertices are ignored
    Index t = firstFace[v], steps = 0;
    do {
      const auto& f = mesh.triangles[t];
      const int k = f[0] == v ? 0 : f[1] == v ? 1 : 2;
      const Index prev = f[(k + 2) % 3];  // the edge (prev, v) is held by the next face as (v, prev)
      t = owner.at(detail::directedEdgeKey(v, prev));
      ++steps;
    } while (t != firstFace[v] && steps <= incident[v]);
    require(steps == incident[v],
            "mesh vertex " + std::to_string(v) + " is non-manifold: its faces form more than one fan");
  }

  // Signed volume (divergence theorem): negative when every face is wound clockwise seen from outside.
  double volume6 = 0;
  for (const auto& f : mesh.triangles)
    volume6 += mesh.vertices[f[0]].dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]]));
  require(volume6 > 0,
          "mesh encloses a negative volume: its faces are wound inside out (clockwise seen from "
          "outside)");
}

/// A sphere of `radius` (m) about the origin: an icosahedron whose faces are split into four `subdivisions`
/// times, every vertex on the sphere. 20 * 4^subdivisions triangles; the faces lie inside the sphere by at most
/// about radius * (0.65 / 2^subdivisions)^2 / 2.
inline TriangleMesh makeIcosphere(double radius, int subdivisions) {
  detail::require(std::isfinite(radius) && radius > 0, "icosphere radius must be positive and finite");
  detail::require(subdivisions >= 0 && subdivisions <= 8,
                  "icosphere subdivisions must be in [0, 8] (got " + std::to_string(subdivisions) + ")");
  const double p = (1 + std::sqrt(5.0)) / 2;
  TriangleMesh m;
  m.vertices = {{-1, p, 0},  {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
                {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  for (auto& v : m.vertices) v.normalize();
  m.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<Index, Index>, Index> midpoints;  // each edge is split once, shared by both faces
    auto midpoint = [&](Index a, Index b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized());
      return midpoints[key] = Index(m.vertices.size()) - 1;
    };
    std::vector<std::array<Index, 3>> finer;
    finer.reserve(m.triangles.size() * 4);
    for (const auto& f : m.triangles) {
      const Index a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      finer.push_back({f[0], a, c});
      finer.push_back({f[1], b, a});
      finer.push_back({f[2], c, b});
      finer.push_back({a, b, c});
    }
    m.triangles = std::move(finer);
  }
  for (auto& v : m.vertices) v *= radius;
  return m;
}

/// The box [-halfExtents, halfExtents] (m): 8 vertices, 12 triangles.
inline TriangleMesh makeBoxMesh(const Eigen::Vector3d& halfExtents) {
  detail::require(detail::allFinite(halfExtents) && (halfExtents.array() > 0).all(),
                  "box mesh half extents must be positive and finite");
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)  // vertex i has coordinate k at +halfExtents[k] when bit k of i is set
    m.vertices.push_back(
        Eigen::Vector3d((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1).cwiseProduct(halfExtents));
  m.triangles = {{0, 2, 3}, {0, 3, 1},   // -z
                 {4, 5, 7}, {4, 7, 6},   // +z
                 {0, 1, 5}, {0, 5, 4},   // -y
                 {2, 6, 7}, {2, 7, 3},   // +y
                 {0, 4, 6}, {0, 6, 2},   // -x
                 {1, 3, 7}, {1, 7, 5}};  // +x
  return m;
}

/// A torus about the z axis: the circle of radius r (m) swept around the circle of radius R (m) in the xy
/// plane, with `segments` steps around z and `sides` steps around the tube; every vertex on the torus.
inline TriangleMesh makeTorus(double R, double r, int segments, int sides) {
  detail::require(
      std::isfinite(R) && std::isfinite(r) && r > 0 && R > r,
      "torus radii must be finite with R > r > 0 (got R = " + detail::formatNumber(R) + ", r = " + detail::formatNumber(r) + ")");
  detail::require(segments >= 3 && sides >= 3, "torus needs at least 3 segments and 3 sides");
  TriangleMesh m;
  const double twoPi = 2 * std::numbers::pi;
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < sides; ++j) {
      const double u = twoPi * i / segments, v = twoPi * j / sides;
      const double rho = R + r * std::cos(v);
      m.vertices.emplace_back(rho * std::cos(u), rho * std::sin(u), r * std::sin(v));
    }
  auto id = [&](int i, int j) { return Index((i % segments) * sides + (j % sides)); };
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < sides; ++j) {
      // (u, v) increasing is counter-clockwise seen from outside: d/du x d/dv points away from the tube's core.
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

/// A non-convex solid: the L-shaped footprint {[-a, a] x [-a, -a + 2w]} u {[-a, -a + 2w] x [-a, a]} in the xy
/// plane (a = size / 2, w = armWidth / 2) extruded over z in [-halfHeight, halfHeight]. Its exact signed
/// distance is that of an extruded polygon, so tests have an analytic reference with a concave edge.
inline TriangleMesh makeLBlock(double size, double armWidth, double halfHeight) {
  detail::require(std::isfinite(size) && std::isfinite(armWidth) && std::isfinite(halfHeight) && halfHeight > 0 &&
                      armWidth > 0 && armWidth < size,
                  "L block needs size > armWidth > 0 and halfHeight > 0, all finite");
  const double a = size / 2, b = -a + armWidth;
  // The footprint, counter-clockwise seen from +z; vertex 3 is the reflex corner, which sees every other one,
  // so the caps are fans from it.
  const std::array<Eigen::Vector2d, 6> footprint{Eigen::Vector2d(-a, -a), Eigen::Vector2d(a, -a),
                                                 Eigen::Vector2d(a, b),   Eigen::Vector2d(b, b),
                                                 Eigen::Vector2d(b, a),   Eigen::Vector2d(-a, a)};
  TriangleMesh m;
  for (double z : {-halfHeight, halfHeight})
    for (const auto& p : footprint) m.vertices.emplace_back(p.x(), p.y(), z);
  for (Index k : {4, 5, 0, 1}) {
    const Index next = (k + 1) % 6;
    m.triangles.push_back({3, next, k});                        // bottom, seen from -z
    m.triangles.push_back({9, Index(6 + k), Index(6 + next)});  // top, seen from +z
  }
  for (Index k = 0; k < 6; ++k) {  // one quad per footprint edge
    const Index next = (k + 1) % 6;
    m.triangles.push_back({k, next, Index(6 + next)});
    m.triangles.push_back({k, Index(6 + next), Index(6 + k)});
  }
  return m;
}

}  // namespace drape
