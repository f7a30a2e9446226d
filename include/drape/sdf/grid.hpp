#pragma once
// Grid distance fields built from closed triangle meshes: the "distance field volume texture" of the cloth-rigid
// coupling thesis (step 1 of its algorithm). A regular grid is built once around the mesh, each node holding the exact
// signed distance to the mesh and the unit normal (the gradient of the exact field there); a query interpolates both
// trilinearly. Outside the grid's box the field continues as sqrt(box distance^2 + boundary value^2), a lower bound of
// the true distance that grows outward and keeps the field 1-Lipschitz across the box (a plain sum
// "box distance + boundary value" would be an upper bound and only sqrt(2)-Lipschitz).
//
// What holds for the sampled field (tests/test_mesh_sdf.cpp measures each):
//   - at a node it is the exact signed distance of the mesh, rounded to float;
//   - inside the box |sampled - exact| <= sum_i w_i |x - node_i| <= (sqrt(3) / 2) cellSize, because the exact
//     field is 1-Lipschitz and the trilinear weights w_i are a convex combination; the bound is reached only on
//     the medial axis (the centre of a sphere). Near a smooth surface the error is O(cellSize^2 / radius);
//     near a crease of the field (inside a box's edges, outside a concave edge) it is O(cellSize);
//   - each partial derivative of the trilinear field is an average of node differences, each at most 1 in
//     size, so the field is 1-Lipschitz along each axis and at most sqrt(3)-Lipschitz in any direction; where
//     the surface is smooth at the scale of a cell it is 1-Lipschitz up to O(cellSize / radius);
//   - the sign is right wherever the sampled distance is farther from zero than the interpolation error.
// The returned gradient is the trilinearly interpolated node normal, normalised (smooth and exact at the
// nodes, where the gradient of the trilinear field would be a piecewise-bilinear, non-unit approximation).

#include <drape/detail/triangle.hpp>
#include <drape/sdf/grid_search.hpp>
#include <drape/sdf/mesh.hpp>
#include <drape/sdf/shapes.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

namespace drape {

/// A signed distance grid in a mesh's frame, immutable once built (share it through
/// std::shared_ptr<const DistanceGrid>). Node (i, j, k) sits at lower + cellSize * (i, j, k).
struct DistanceGrid {
  Eigen::Vector3d lower = Eigen::Vector3d::Zero();  ///< position of node (0, 0, 0) in the mesh frame (m)
  double cellSize = 0;                              ///< m
  std::array<Index, 3> nodeCount{0, 0, 0};          ///< nodes along x, y, z (at least 2 each)
  /// (normal x, y, z, signed distance in m) per node, x fastest. Float: its rounding (1e-7 of the distances)
  /// is far below the interpolation error (1e-3 cell and up), it halves the memory (67^3 nodes: 4.8 MB), and a
  /// node is one aligned 16-byte load, the layout of an RGBA32F 3D texture.
  std::vector<Eigen::Vector4f> nodes;

  Eigen::Vector3d upper() const {
    return lower + cellSize * Eigen::Vector3d(nodeCount[0] - 1, nodeCount[1] - 1, nodeCount[2] - 1);
  }
  std::size_t nodeIndex(Index i, Index j, Index k) const {
    return (std::size_t(k) * std::size_t(nodeCount[1]) + std::size_t(j)) * std::size_t(nodeCount[0]) + std::size_t(i);
  }
  Eigen::Vector3d nodePosition(Index i, Index j, Index k) const { return lower + cellSize * Eigen::Vector3d(i, j, k); }
};

/// How finely and how far around the mesh the grid reaches.
struct DistanceGridOptions {
  Index resolution = 64;  ///< cells along the longest side of the mesh's box grown by margin (if cellSize is 0)
  double cellSize = 0;    ///< m; when positive it is used instead of resolution
  double margin = 0;      ///< m of exact field beyond the mesh's bounding box (one more cell is always added)
};

namespace detail {

struct ClosestOnTriangle {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  TriangleFeature feature = TriangleFeature::Face;
};

/// Closest point of the triangle abc to p (nearestRegion). The region tests are exact sign tests, so the reported
/// feature is the one whose pseudonormal gives the sign. The triangle must not be degenerate (every denominator is
/// then a positive squared length).
inline ClosestOnTriangle closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                           const Eigen::Vector3d& c) {
  using F = TriangleFeature;
  const TriangleRegion<double> r = nearestRegion<double>(p, a, b, c);
  switch (r.feature) {
    case F::VertexA: return {a, F::VertexA};
    case F::VertexB: return {b, F::VertexB};
    case F::VertexC: return {c, F::VertexC};
    case F::EdgeAB: return {a + r.s * (b - a), F::EdgeAB};
    case F::EdgeCA: return {a + r.s * (c - a), F::EdgeCA};
    case F::EdgeBC: return {b + r.s * (c - b), F::EdgeBC};
    case F::Face: break;
  }
  return {a + (b - a) * r.s + (c - a) * r.t, F::Face};
}

/// A bounding volume hierarchy over a mesh's triangles for closest-point queries: median splits along the
/// longest axis of the centroids, at most four triangles per leaf.
class TriangleBvh {
 public:
  struct Hit {
    double distance2 = std::numeric_limits<double>::infinity();
    Index triangle = -1;
    ClosestOnTriangle closest{};
  };

  explicit TriangleBvh(const TriangleMesh& mesh) : mesh_(mesh) {
    order_.resize(mesh.triangles.size());
    std::iota(order_.begin(), order_.end(), Index(0));
    centroids_.reserve(mesh.triangles.size());
    for (const auto& f : mesh.triangles)
      centroids_.push_back((mesh.vertices[f[0]] + mesh.vertices[f[1]] + mesh.vertices[f[2]]) / 3);
    nodes_.reserve(2 * mesh.triangles.size() / kLeafSize + 2);
    build(0, Index(order_.size()));
    corners_.reserve(order_.size());
    for (Index t : order_) {
      const auto& f = mesh.triangles[t];
      corners_.push_back({mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]]});
    }
  }

  /// Refines `hit` with the closest triangle to p; a hit that already holds a candidate (the previous query's
  /// triangle, say) bounds the search and prunes most of the tree.
  void closest(const Eigen::Vector3d& p, Hit& hit) const {
    std::array<Index, 64> stack;  // depth is log2(#F / 4): 64 is never reached
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Index id = stack[--top];
      const Node& node = nodes_[id];
      if (boxDistance2(node, p) >= hit.distance2) continue;
      if (node.count > 0) {
        for (Index s = node.first; s < node.first + node.count; ++s) {
          const auto& v = corners_[s];
          const ClosestOnTriangle c = closestOnTriangle(p, v[0], v[1], v[2]);
          const double d2 = (p - c.point).squaredNorm();
          if (d2 < hit.distance2) hit = {d2, order_[s], c};
        }
      } else {  // visit the nearer child first: its hits prune the other
        const Index left = id + 1, right = node.first;
        const bool leftFirst = boxDistance2(nodes_[left], p) <= boxDistance2(nodes_[right], p);
        stack[top++] = leftFirst ? right : left;
        stack[top++] = leftFirst ? left : right;
      }
    }
  }

  /// The distance from p to triangle t, as a starting bound for closest().
  void seed(const Eigen::Vector3d& p, Index t, Hit& hit) const {
    const auto& f = mesh_.triangles[t];
    const ClosestOnTriangle c = closestOnTriangle(p, mesh_.vertices[f[0]], mesh_.vertices[f[1]], mesh_.vertices[f[2]]);
    hit = {(p - c.point).squaredNorm(), t, c};
  }

 private:
  static constexpr Index kLeafSize = 4;
  struct Node {
    Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
    // A slab [slabLo, slabHi] along `axis` (the mean normal of the node's faces) that holds its triangles: for a
    // nearly flat patch it is far thinner than the box, which prunes the near-ties of points deep inside.
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
    double slabLo = 0, slabHi = 0;
    Index first = 0;  ///< leaf: first slot in order_; inner: index of the right child (the left one follows)
    Index count = 0;  ///< triangles in a leaf, 0 for an inner node
  };

  /// A lower bound of the squared distance from p to the node's triangles: the larger of the distances to its
  /// box and to its slab.
  static double boxDistance2(const Node& n, const Eigen::Vector3d& p) {
    const double box = (n.lo - p).cwiseMax(p - n.hi).cwiseMax(0.0).squaredNorm();
    const double h = n.axis.dot(p);
    const double slab = std::max({n.slabLo - h, h - n.slabHi, 0.0});
    return std::max(box, slab * slab);
  }

  Index build(Index begin, Index end) {
    const Index id = Index(nodes_.size());
    nodes_.push_back({});
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    Eigen::Vector3d clo = lo, chi = hi;
    for (Index s = begin; s < end; ++s) {
      for (Index v : mesh_.triangles[order_[s]]) {
        lo = lo.cwiseMin(mesh_.vertices[v]);
        hi = hi.cwiseMax(mesh_.vertices[v]);
      }
      clo = clo.cwiseMin(centroids_[order_[s]]);
      chi = chi.cwiseMax(centroids_[order_[s]]);
    }
    nodes_[id].lo = lo;
    nodes_[id].hi = hi;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (Index s = begin; s < end; ++s) {
      const auto& f = mesh_.triangles[order_[s]];
      normal +=
          (mesh_.vertices[f[1]] - mesh_.vertices[f[0]]).cross(mesh_.vertices[f[2]] - mesh_.vertices[f[0]]).normalized();
    }
    // Any unit axis gives a valid bound; the mean normal gives a thin one.
    normal = normal.norm() > 1e-12 ? Eigen::Vector3d(normal.normalized()) : Eigen::Vector3d::UnitZ();
    nodes_[id].axis = normal;
    nodes_[id].slabLo = std::numeric_limits<double>::infinity();
    nodes_[id].slabHi = -nodes_[id].slabLo;
    for (Index s = begin; s < end; ++s)
      for (Index v : mesh_.triangles[order_[s]]) {
        nodes_[id].slabLo = std::min(nodes_[id].slabLo, normal.dot(mesh_.vertices[v]));
        nodes_[id].slabHi = std::max(nodes_[id].slabHi, normal.dot(mesh_.vertices[v]));
      }
    if (end - begin <= kLeafSize) {
      nodes_[id].first = begin;
      nodes_[id].count = end - begin;
      return id;
    }
    int axis = 0;
    (chi - clo).maxCoeff(&axis);
    const Index mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](Index x, Index y) { return centroids_[x][axis] < centroids_[y][axis]; });
    build(begin, mid);  // lands at id + 1
    const Index right = build(mid, end);
    nodes_[id].first = right;
    nodes_[id].count = 0;
    return id;
  }

  const TriangleMesh& mesh_;
  std::vector<Index> order_;  ///< triangle indices, grouped by leaf
  std::vector<Eigen::Vector3d> centroids_;
  std::vector<std::array<Eigen::Vector3d, 3>> corners_;  ///< per slot of order_, for cache-friendly leaves
  std::vector<Node> nodes_;
};

/// Angle-weighted pseudonormals (Baerentzen and Aanaes 2005): for a point whose closest mesh point lies on a
/// feature (face, edge or vertex), the sign of (p - closest) . pseudonormal(feature) is the sign of the
/// distance. Faces use their normal, edges the sum of their two faces' normals, vertices the sum of their
/// faces' normals weighted by the face angle at the vertex. Needs a validated closed mesh.
class Pseudonormals {
 public:
  explicit Pseudonormals(const TriangleMesh& mesh)
      : face_(mesh.triangles.size()),
        edge_(mesh.triangles.size()),
        vertex_(mesh.vertices.size(), Eigen::Vector3d::Zero()) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& f = mesh.triangles[t];
      face_[t] =
          (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]).normalized();
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e1 = (mesh.vertices[f[(k + 1) % 3]] - mesh.vertices[f[k]]).normalized();
        const Eigen::Vector3d e2 = (mesh.vertices[f[(k + 2) % 3]] - mesh.vertices[f[k]]).normalized();
        vertex_[f[k]] += std::acos(std::clamp(e1.dot(e2), -1.0, 1.0)) * face_[t];
      }
    }
    const auto owner = directedEdges(mesh);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {  // edge k joins corners k and k + 1; its neighbour holds it reversed
        const auto& f = mesh.triangles[t];
        edge_[t][k] = face_[t] + face_[owner.at(directedEdgeKey(f[(k + 1) % 3], f[k]))];
      }
  }

  Eigen::Vector3d of(const TriangleMesh& mesh, Index t, TriangleFeature feature) const {
    using F = TriangleFeature;
    switch (feature) {
      case F::VertexA:
        return vertex_[mesh.triangles[t][0]];
      case F::VertexB:
        return vertex_[mesh.triangles[t][1]];
      case F::VertexC:
        return vertex_[mesh.triangles[t][2]];
      case F::EdgeAB:
        return edge_[t][0];
      case F::EdgeBC:
        return edge_[t][1];
      case F::EdgeCA:
        return edge_[t][2];
      default:
        return face_[t];
    }
  }

 private:
  std::vector<Eigen::Vector3d> face_;
  std::vector<std::array<Eigen::Vector3d, 3>> edge_;
  std::vector<Eigen::Vector3d> vertex_;
};

/// Trilinear sampling of a grid in its mesh frame, in scalar S. Outside the box the clamped boundary value g
/// and the distance e to the box combine as sqrt(e^2 + g^2) (see the top of this file).
///
/// Points and gradients travel as four-vectors with w = 0: every vector operation then fills whole SIMD registers.
/// With three-vectors GCC's SLP vectoriser may compute on a register's unused fourth lane, whose leftover
/// contents can raise FE_INVALID or FE_OVERFLOW under floating-point traps (as the tests run).
template <Scalar S>
struct GridSampler {
  using V4 = Eigen::Matrix<S, 4, 1>;
  const Eigen::Vector4f* nodes = nullptr;
  std::array<Index, 3> count{};
  V4 lower = V4::Zero();  ///< w = 0
  S cellSize = 0;
  S invCellSize = 0;

  GridSampler() = default;
  explicit GridSampler(const DistanceGrid& g)
      : nodes(g.nodes.data()),
        count(g.nodeCount),
        lower(S(g.lower.x()), S(g.lower.y()), S(g.lower.z()), S(0)),
        cellSize(S(g.cellSize)),
        invCellSize(S(1 / g.cellSize)) {}

  /// q: a point of the mesh frame with w = 0; the gradient comes back with w = 0.
  S operator()(const V4& q, V4& gradient) const {
    const V4 u = (q - lower) * invCellSize;  // in cells from node (0, 0, 0)
    std::array<Index, 3> cell;
    V4 t = V4::Zero(), excess = V4::Zero();  // excess: how far q lies beyond the box along each axis (m), 0 inside
    for (int a = 0; a < 3; ++a) {
      const S top = S(count[a] - 1);
      const S c = std::clamp(u[a], S(0), top);  // also keeps the int conversion below in range
      excess[a] = (u[a] - c) * cellSize;
      cell[a] = std::min(Index(c), count[a] - 2);
      t[a] = c - S(cell[a]);
    }
    const std::size_t sx = 1, sy = std::size_t(count[0]), sz = sy * std::size_t(count[1]);
    const Eigen::Vector4f* n0 = nodes + (std::size_t(cell[2]) * sz + std::size_t(cell[1]) * sy + std::size_t(cell[0]));
    auto at = [&](std::size_t offset) -> V4 { return n0[offset].template cast<S>(); };
    // x, then y, then z: 7 lerps of (normal, distance) four-vectors.
    const V4 c00 = at(0) + t[0] * (at(sx) - at(0));
    const V4 c10 = at(sy) + t[0] * (at(sy + sx) - at(sy));
    const V4 c01 = at(sz) + t[0] * (at(sz + sx) - at(sz));
    const V4 c11 = at(sz + sy) + t[0] * (at(sz + sy + sx) - at(sz + sy));
    const V4 c0 = c00 + t[1] * (c10 - c00);
    const V4 c1 = c01 + t[1] * (c11 - c01);
    const V4 v = c0 + t[2] * (c1 - c0);
    const S g = v[3];
    V4 n = v;
    n[3] = S(0);
    const S len = n.norm();
    if (len > S(0)) {
      n /= len;
    } else {  // node normals cancel exactly: any unit vector
      n = V4(S(0), S(0), S(1), S(0));
    }
    const S e = excess.norm();
    if (e == S(0)) {
      gradient = n;
      return g;
    }
    // Outside: the gradient of sqrt(e^2 + g^2), with g's gradient along the box face (the clamped axes drop out).
    for (int a = 0; a < 3; ++a)
      if (excess[a] != S(0)) n[a] = S(0);
    const S phi = g > S(0) ? std::sqrt(e * e + g * g) : g + e;  // g > 0 whenever the box pads the mesh
    const V4 grad = excess + std::max(g, S(0)) * n;
    const S glen = grad.norm();
    gradient = glen > S(0) ? V4(grad / glen) : V4(excess / e);
    return phi;
  }

  /// The same for a three-vector point and gradient.
  S operator()(const Vec3<S>& q, Vec3<S>& gradient) const {
    V4 g;
    const S phi = (*this)(V4(q.x(), q.y(), q.z(), S(0)), g);
    gradient = Vec3<S>(g[0], g[1], g[2]);
    return phi;
  }

  /// The distance alone at u, a point in cells from node (0, 0, 0): the value operator() gives, with the same
  /// arithmetic on the distances. For the face search (grid_search.hpp), which needs no gradient until the end.
  S distanceAt(const Vec3<S>& u) const {
    std::array<Index, 3> cell;
    S t[3], excess2 = 0;
    for (int a = 0; a < 3; ++a) {
      const S c = std::clamp(u[a], S(0), S(count[a] - 1));
      const S beyond = (u[a] - c) * cellSize;
      excess2 += beyond * beyond;
      cell[a] = std::min(Index(c), count[a] - 2);
      t[a] = c - S(cell[a]);
    }
    const std::size_t sx = 1, sy = std::size_t(count[0]), sz = sy * std::size_t(count[1]);
    const Eigen::Vector4f* n0 = nodes + (std::size_t(cell[2]) * sz + std::size_t(cell[1]) * sy + std::size_t(cell[0]));
    auto at = [&](std::size_t offset) { return S(n0[offset][3]); };
    const S c00 = at(0) + t[0] * (at(sx) - at(0));
    const S c10 = at(sy) + t[0] * (at(sy + sx) - at(sy));
    const S c01 = at(sz) + t[0] * (at(sz + sx) - at(sz));
    const S c11 = at(sz + sy) + t[0] * (at(sz + sy + sx) - at(sz + sy));
    const S c0 = c00 + t[1] * (c10 - c00);
    const S c1 = c01 + t[1] * (c11 - c01);
    const S g = c0 + t[2] * (c1 - c0);
    if (excess2 == S(0)) return g;
    const S e = std::sqrt(excess2);
    return g > S(0) ? std::sqrt(e * e + g * g) : g + e;
  }

  /// The trilinear polynomial of one cell (node `cell` its lowest corner), expanded about t (in cells from that
  /// node, anywhere: the polynomial extends beyond its cell). The expansion is exact (see CellPolynomial).
  CellPolynomial<S> expand(const std::array<Index, 3>& cell, const Vec3<S>& t) const {
    const std::size_t sx = 1, sy = std::size_t(count[0]), sz = sy * std::size_t(count[1]);
    const Eigen::Vector4f* n0 = nodes + (std::size_t(cell[2]) * sz + std::size_t(cell[1]) * sy + std::size_t(cell[0]));
    S v[8];  // v[i + 2j + 4k]: node (i, j, k) of the cell
    for (int k = 0; k < 8; ++k) v[k] = S(n0[(k & 1 ? sx : 0) + (k & 2 ? sy : 0) + (k & 4 ? sz : 0)][3]);
    return CellPolynomial<S>::expand(v, t);
  }
};

}  // namespace detail

/// Builds the signed distance grid of a closed mesh (validated first: see validateClosedMesh). Each node gets
/// the exact distance to the mesh (closest points through a BVH, each query seeded with its neighbour's
/// triangle) and its sign from angle-weighted pseudonormals.
inline std::shared_ptr<const DistanceGrid> buildDistanceGrid(const TriangleMesh& mesh,
                                                             const DistanceGridOptions& options = {}) {
  using detail::require;
  require(std::isfinite(options.margin) && options.margin >= 0,
          "distance grid margin must be finite and >= 0 (got " + detail::formatNumber(options.margin) + ")");
  require(std::isfinite(options.cellSize) && options.cellSize >= 0,
          "distance grid cellSize must be finite and >= 0 (got " + detail::formatNumber(options.cellSize) + ")");
  require(options.cellSize > 0 || (options.resolution >= 2 && options.resolution <= 1024),
          "distance grid resolution must be in [2, 1024] (got " + std::to_string(options.resolution) + ")");
  validateClosedMesh(mesh);

  Eigen::Vector3d lo = mesh.vertices[mesh.triangles[0][0]], hi = lo;
  for (const auto& f : mesh.triangles)
    for (Index v : f) {
      lo = lo.cwiseMin(mesh.vertices[v]);
      hi = hi.cwiseMax(mesh.vertices[v]);
    }
  const Eigen::Vector3d extent = (hi - lo).array() + 2 * options.margin;
  const double h = options.cellSize > 0 ? options.cellSize : extent.maxCoeff() / options.resolution;
  std::array<Index, 3> count{};
  double total = 1;
  for (int a = 0; a < 3; ++a) {
    // Cells to cover the extent (less a hair so an exact fit does not add one), plus one padding cell per side:
    // boundary nodes then lie strictly outside the mesh, so the continuation outside the box is well defined.
    const double cells = std::ceil(extent[a] / h * (1 - 1e-12)) + 2;
    require(cells <= 4096, "distance grid would need " + std::to_string(cells) +
                               " cells along one axis (at most 4096): raise cellSize or lower resolution");
    count[a] = Index(cells) + 1;
    total *= count[a];
  }
  require(total <= double(1 << 26), "distance grid would need " + detail::formatNumber(total) +
                                        " nodes (at most 2^26, 1 GiB): raise cellSize or lower resolution");

  auto grid = std::make_shared<DistanceGrid>();
  grid->cellSize = h;
  grid->nodeCount = count;
  grid->lower = (lo + hi) / 2 - h * Eigen::Vector3d(count[0] - 1, count[1] - 1, count[2] - 1) / 2;
  grid->nodes.resize(std::size_t(total));

  const detail::TriangleBvh bvh(mesh);
  const detail::Pseudonormals pseudonormals(mesh);
  for (Index k = 0; k < count[2]; ++k)
    for (Index j = 0; j < count[1]; ++j) {
      Index hint = -1;  // restarted per row, so a node's value never depends on the order rows are visited
      for (Index i = 0; i < count[0]; ++i) {
        const Eigen::Vector3d p = grid->nodePosition(i, j, k);
        detail::TriangleBvh::Hit hit;
        if (hint >= 0) bvh.seed(p, hint, hit);
        bvh.closest(p, hit);
        hint = hit.triangle;
        const Eigen::Vector3d pn = pseudonormals.of(mesh, hit.triangle, hit.closest.feature);
        const Eigen::Vector3d away = p - hit.closest.point;
        const double d = std::sqrt(hit.distance2);
        const double sign = away.dot(pn) < 0 ? -1.0 : 1.0;
        // The gradient of the exact field is the unit vector from the closest point, flipped inside; on the
        // surface (closer than rounding can resolve a direction) it is the pseudonormal.
        const Eigen::Vector3d normal = d > 1e-9 * h ? Eigen::Vector3d(sign * away / d) : pn.normalized();
        grid->nodes[grid->nodeIndex(i, j, k)] =
            Eigen::Vector4f(float(normal.x()), float(normal.y()), float(normal.z()), float(sign * d));
      }
    }
  return grid;
}

/// A solid whose shape is a grid distance field (built once by buildDistanceGrid, shared by any number of
/// solids). The grid's mesh frame is the solid's frame.
struct MeshShape {
  std::shared_ptr<const DistanceGrid> grid;
};

template <Scalar S>
struct Sdf<MeshShape, S> {
  static constexpr bool kLinear = false;
  static constexpr bool kConvex = false;  ///< the mesh may be non-convex: a face search cannot assume one minimum
  static constexpr double kLipschitz = constants::kGridLipschitz;  ///< for the face cull (queryFace)
  using V4 = Eigen::Matrix<S, 4, 1>;
  using M4 = Eigen::Matrix<S, 4, 4>;
  std::shared_ptr<const DistanceGrid> grid;  ///< keeps the nodes that `sample` reads alive
  M4 toLocal;                                ///< rotation world -> mesh frame, padded with zeros (see GridSampler)
  V4 centre;                                 ///< mesh frame origin relative to the cloth's local origin (m), w = 0
  detail::GridSampler<S> sample;

  S operator()(const Vec3<S>& x, Vec3<S>& gradient) const {
    const V4 d = V4(x.x(), x.y(), x.z(), S(0)) - centre;
    V4 g;
    const S phi = sample(V4(toLocal * d), g);
    const V4 world = toLocal.transpose() * g;
    gradient = Vec3<S>(world[0], world[1], world[2]);
    return phi;
  }

  /// Where x lies in the grid, in cells from node (0, 0, 0).
  Vec3<S> toCells(const Vec3<S>& x) const {
    const V4 u = (toLocal * (V4(x.x(), x.y(), x.z(), S(0)) - centre) - sample.lower) * sample.invCellSize;
    return Vec3<S>(u[0], u[1], u[2]);
  }

  /// The deepest point of a face (queryFace's search for this field): branch and bound over the face
  /// (detail::branchAndBoundOnFace), from the centroid's value phiC and gradient gradC, to within
  /// kFaceSearchGap face lengths of the field's minimum, at most about `budget` cell reads; the search drops
  /// what clears `floor`. The best point is evaluated once more for its gradient (counted).
  FaceQuery<S> deepestPointOnFace(const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2, const Vec3<S>& centroid,
                                  S phiC, const Vec3<S>& gradC, int budget, S floor) const {
    const S extent = std::max({(x1 - x0).norm(), (x2 - x0).norm(), (x2 - x1).norm()});
    const Vec3<S> u[3] = {toCells(x0), toCells(x1), toCells(x2)};
    FaceQuery<S> q{Vec3<S>::Constant(S(1) / S(3)), centroid, gradC, phiC, 1};
    S value;
    const Vec3<S> b = detail::branchAndBoundOnFace<S>(sample, u, phiC, S(constants::kFaceSearchGap) * extent, floor,
                                                      budget, value, q.evaluations);
    if (value < phiC) {
      q.barycentric = b.cwiseMax(S(0)) / b.cwiseMax(S(0)).sum();  // b0 = 1 - b1 - b2 may round below zero
      q.point = b[0] * x0 + b[1] * x1 + b[2] * x2;
      q.phi = (*this)(q.point, q.normal);
      ++q.evaluations;
    }
    return q;
  }
};

namespace detail {

inline void validateShape(const MeshShape& s) {
  require(s.grid != nullptr, "mesh shape has no grid (build one with buildDistanceGrid)");
  const DistanceGrid& g = *s.grid;
  require(std::isfinite(g.cellSize) && g.cellSize > 0, "mesh shape grid cellSize must be positive and finite");
  require(allFinite(g.lower), "mesh shape grid lower corner must be finite");
  require(g.nodeCount[0] >= 2 && g.nodeCount[1] >= 2 && g.nodeCount[2] >= 2,
          "mesh shape grid needs at least 2 nodes along each axis");
  require(g.nodes.size() == std::size_t(g.nodeCount[0]) * std::size_t(g.nodeCount[1]) * std::size_t(g.nodeCount[2]),
          "mesh shape grid holds " + std::to_string(g.nodes.size()) + " nodes, not nodeCount's product");
}

template <Scalar S>
Sdf<MeshShape, S> compileSdf(const MeshShape& m, const Pose& pose, const Eigen::Vector3d& origin) {
  Eigen::Matrix<S, 4, 4> toLocal = Eigen::Matrix<S, 4, 4>::Zero();
  toLocal.template topLeftCorner<3, 3>() = pose.rotation.toRotationMatrix().transpose().template cast<S>();
  const Eigen::Vector3d c = pose.position - origin;
  return {m.grid, toLocal, Eigen::Matrix<S, 4, 1>(S(c.x()), S(c.y()), S(c.z()), S(0)), GridSampler<S>(*m.grid)};
}

}  // namespace detail
}  // namespace drape
