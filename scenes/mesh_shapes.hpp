#pragma once
// The closed test meshes of the grid distance fields (icosphere, box, torus, L block), each with the analytic
// signed distance of the shape it approximates, and brute-force references that share no code with
// drape/sdf/grid.hpp: the exact distance to a mesh by projecting onto each triangle's plane and else onto its
// edges, and the inside test by the generalised winding number (a sum of solid angles). Shared by the tests
// ([meshsdf]) and the accuracy report (bench/mesh_sdf_accuracy), so both measure the same thing.

#include <drape/sdf/mesh.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace drape::scenes {

/// Distance from p to the segment ab.
inline double segmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

/// Distance from p to the triangle abc: to its plane when the foot of the perpendicular falls inside (all three
/// edge tests agree with the normal), else to the nearest edge.
inline double triangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  const double height = (p - a).dot(n);
  const Eigen::Vector3d foot = p - height * n;
  const bool inside =
      (b - a).cross(foot - a).dot(n) >= 0 && (c - b).cross(foot - b).dot(n) >= 0 && (a - c).cross(foot - c).dot(n) >= 0;
  if (inside) return std::abs(height);
  return std::min({segmentDistance(p, a, b), segmentDistance(p, b, c), segmentDistance(p, c, a)});
}

/// Unsigned distance from p to the mesh, by brute force over every triangle.
inline double meshDistance(const TriangleMesh& m, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : m.triangles)
    best = std::min(best, triangleDistance(p, m.vertices[f[0]], m.vertices[f[1]], m.vertices[f[2]]));
  return best;
}

/// Generalised winding number of the mesh about p (Jacobson et al. 2013): the solid angles of the triangles seen
/// from p (Van Oosterom and Strackee's formula) over 4 pi. 1 inside a closed outward mesh, 0 outside.
inline double windingNumber(const TriangleMesh& m, const Eigen::Vector3d& p) {
  double total = 0;
  for (const auto& f : m.triangles) {
    const Eigen::Vector3d a = m.vertices[f[0]] - p, b = m.vertices[f[1]] - p, c = m.vertices[f[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    total += 2 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la);
  }
  return total / (4 * std::numbers::pi);
}

/// Signed distance to the mesh: brute-force distance, negative where the winding number says inside.
inline double meshSignedDistance(const TriangleMesh& m, const Eigen::Vector3d& p) {
  const double d = meshDistance(m, p);
  return windingNumber(m, p) > 0.5 ? -d : d;
}

inline double sphereSdf(double radius, const Eigen::Vector3d& p) { return p.norm() - radius; }

inline double boxSdf(const Eigen::Vector3d& half, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = p.cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

inline double torusSdf(double R, double r, const Eigen::Vector3d& p) {
  return std::hypot(std::hypot(p.x(), p.y()) - R, p.z()) - r;
}

/// The L block of makeLBlock: the exact distance of an extruded polygon, from the polygon's exact 2D distance.
inline double lBlockSdf(double size, double armWidth, double halfHeight, const Eigen::Vector3d& p) {
  const double a = size / 2, b = -a + armWidth;
  const std::array<Eigen::Vector2d, 6> poly{Eigen::Vector2d(-a, -a), Eigen::Vector2d(a, -a), Eigen::Vector2d(a, b),
                                            Eigen::Vector2d(b, b),   Eigen::Vector2d(b, a),  Eigen::Vector2d(-a, a)};
  const Eigen::Vector2d q = p.head<2>();
  double d2 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector2d e = poly[(k + 1) % 6] - poly[k];
    const double t = std::clamp((q - poly[k]).dot(e) / e.squaredNorm(), 0.0, 1.0);
    d2 = std::min(d2, (q - (poly[k] + t * e)).norm());
  }
  const bool inside2 = q.x() > -a && q.x() < a && q.y() > -a && q.y() < a && (q.x() < b || q.y() < b);
  const Eigen::Vector2d w(inside2 ? -d2 : d2, std::abs(p.z()) - halfHeight);
  return std::min(w.maxCoeff(), 0.0) + w.cwiseMax(0.0).norm();
}

/// A test mesh and the analytic signed distance of the shape it approximates. `tessellation` bounds how far
/// the mesh's surface lies from the analytic one (0 where the mesh is the shape).
struct MeshShapeCase {
  std::string name;
  TriangleMesh mesh;
  std::function<double(const Eigen::Vector3d&)> analytic;
  double tessellation = 0;  ///< m
};

/// The four shapes: a sphere of radius 0.5 (1280 triangles), a 0.8 x 0.6 x 0.4 box, a torus R = 0.4,
/// r = 0.15 (48 x 24 x 2 triangles) and an L block 1 m wide, arms 0.4 m, 0.5 m thick.
inline std::vector<MeshShapeCase> meshShapeCases() {
  std::vector<MeshShapeCase> cases;
  {
    const double R = 0.5;
    TriangleMesh m = makeIcosphere(R, 3);
    // Vertices lie on the sphere; a face dips inside it by R minus its plane's distance from the centre.
    double dip = 0;
    for (const auto& f : m.triangles) {
      const Eigen::Vector3d n =
          (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]).normalized();
      dip = std::max(dip, R - n.dot(m.vertices[f[0]]));
    }
    cases.push_back({"icosphere", std::move(m), [R](const Eigen::Vector3d& p) { return sphereSdf(R, p); }, dip});
  }
  {
    const Eigen::Vector3d half(0.4, 0.3, 0.2);
    cases.push_back({"box", makeBoxMesh(half), [half](const Eigen::Vector3d& p) { return boxSdf(half, p); }, 0});
  }
  {
    const double R = 0.4, r = 0.15;
    const int segments = 48, sides = 24;
    // Every vertex is on the torus; a triangle's chords cut inside the tube by at most the sagittas of the two
    // sweeps (around z on the outer equator, radius R + r; around the tube, radius r).
    const double sag =
        (R + r) * (1 - std::cos(std::numbers::pi / segments)) + r * (1 - std::cos(std::numbers::pi / sides));
    cases.push_back({"torus", makeTorus(R, r, segments, sides),
                     [R, r](const Eigen::Vector3d& p) { return torusSdf(R, r, p); }, 2 * sag});
  }
  {
    const double size = 1.0, arm = 0.4, halfHeight = 0.25;
    cases.push_back({"L block", makeLBlock(size, arm, halfHeight),
                     [=](const Eigen::Vector3d& p) { return lBlockSdf(size, arm, halfHeight, p); }, 0});
  }
  return cases;
}

/// The mesh's bounding box.
inline std::pair<Eigen::Vector3d, Eigen::Vector3d> meshBounds(const TriangleMesh& m) {
  Eigen::Vector3d lo = m.vertices[0], hi = lo;
  for (const auto& v : m.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return {lo, hi};
}

}  // namespace drape::scenes
