#pragma once
// The cloth asset: topology, rest data and constraint colouring, built once and shared by any number of
// cloth states. Rest positions are relative to the asset's origin (double), so rest lengths stay exact in
// float wherever the cloth is placed.

#include <drape/math.hpp>

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <utility>
#include <vector>

namespace drape {

/// Compressed adjacency lists: the neighbours of item `i` are `items[offsets[i] .. offsets[i+1])`.
struct Adjacency {
  std::vector<Index> offsets{0};
  std::vector<Index> items;

  Index size() const { return Index(offsets.size()) - 1; }
  const Index* begin(Index i) const { return items.data() + offsets[i]; }
  const Index* end(Index i) const { return items.data() + offsets[i + 1]; }
};

/// A set of distance constraints between vertex pairs, reordered so that each colour holds constraints that
/// share no vertex (Gauss-Seidel within a colour is then order-independent and parallel-safe).
template <Scalar S> struct DistanceSet {
  std::vector<std::array<Index, 2>> pairs;  ///< #C vertex pairs
  std::vector<S> restLength;                ///< #C rest lengths (m)
  std::vector<Index> colourOffsets{0};      ///< colour c holds constraints [colourOffsets[c], colourOffsets[c+1])

  Index size() const { return Index(pairs.size()); }
  Index colourCount() const { return Index(colourOffsets.size()) - 1; }
};

/// A rectangular sheet: a regular lattice of nx by ny vertices in the local XY plane, centred on the pose's
/// position.
struct SheetDesc {
  Index nx = 50;          ///< vertices along local x
  Index ny = 80;          ///< vertices along local y
  double spacing = 0.02;  ///< distance between neighbouring vertices (m)
  Pose placement;         ///< where the sheet's centre sits and how it is turned
};

/// What to build besides stretch edges.
struct AssetOptions {
  bool bending = true;  ///< distance constraints between the far vertices of each pair of adjacent faces
};

template <Scalar S> struct ClothAsset {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< world position the rest positions are relative to (m)
  std::vector<Vec3<S>> restPositions;            ///< #V rest positions relative to origin (m)
  std::vector<std::array<Index, 3>> triangles;   ///< #F counter-clockwise faces
  std::vector<std::array<Index, 2>> edges;       ///< #E unique edges, each with its smaller index first
  std::vector<std::array<Index, 2>> bendPairs;   ///< the two far vertices of each interior edge
  std::vector<S> faceRestArea;                   ///< #F rest areas (m^2)
  DistanceSet<S> stretch;                        ///< structural edges
  DistanceSet<S> shear;                          ///< the sheet's diagonals (empty for meshes)
  DistanceSet<S> bending;                        ///< bend pairs
  Adjacency vertexNeighbours;                    ///< vertices sharing an edge with each vertex

  Index vertexCount() const { return Index(restPositions.size()); }
  Index faceCount() const { return Index(triangles.size()); }

  /// A sheet of nx by ny vertices, quads split along alternating diagonals so the cloth has no preferred
  /// direction. Axis edges are stretch constraints, diagonals are shear.
  static ClothAsset sheet(const SheetDesc& desc, const AssetOptions& options = {});

  /// Any triangle mesh. positions: #V by 3 (m); triangles: #F by 3 vertex indices. Every edge is a stretch
  /// constraint. Rejects non-finite positions, out-of-range indices, repeated indices in a face, faces of
  /// zero area, and edges shared by more than two faces.
  static ClothAsset fromMesh(const std::vector<Vec3<S>>& positions,
                             const std::vector<std::array<Index, 3>>& triangles,
                             const AssetOptions& options = {});
};

namespace detail {

inline Adjacency buildAdjacency(Index count, const std::vector<std::pair<Index, Index>>& incidence) {
  Adjacency adj;
  adj.offsets.assign(count + 1, 0);
  for (auto [owner, item] : incidence) ++adj.offsets[owner + 1];
  for (Index i = 0; i < count; ++i) adj.offsets[i + 1] += adj.offsets[i];
  adj.items.resize(incidence.size());
  std::vector<Index> fill(adj.offsets.begin(), adj.offsets.end() - 1);
  for (auto [owner, item] : incidence) adj.items[fill[owner]++] = item;
  return adj;
}

/// Greedy colouring: each constraint takes the lowest colour that neither of its vertices has yet, then the
/// set is reordered colour by colour (stable within a colour, so the order is deterministic).
template <Scalar S>
DistanceSet<S> colourDistanceSet(Index vertexCount, const std::vector<std::array<Index, 2>>& pairs,
                                 const std::vector<Vec3<S>>& rest) {
  std::vector<std::vector<char>> used;  // used[c][v]: vertex v already has a constraint of colour c
  std::vector<Index> colour(pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    auto [a, b] = pairs[k];
    Index c = 0;
    for (;; ++c) {
      if (c == Index(used.size())) used.emplace_back(vertexCount, 0);
      if (!used[c][a] && !used[c][b]) break;
    }
    used[c][a] = used[c][b] = 1;
    colour[k] = c;
  }
  DistanceSet<S> set;
  const Index colours = Index(used.size());
  set.colourOffsets.assign(colours + 1, 0);
  for (Index c : colour) ++set.colourOffsets[c + 1];
  for (Index c = 0; c < colours; ++c) set.colourOffsets[c + 1] += set.colourOffsets[c];
  set.pairs.resize(pairs.size());
  set.restLength.resize(pairs.size());
  std::vector<Index> fill(set.colourOffsets.begin(), set.colourOffsets.end() - 1);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const Index slot = fill[colour[k]]++;
    set.pairs[slot] = pairs[k];
    set.restLength[slot] = (rest[pairs[k][0]] - rest[pairs[k][1]]).norm();
  }
  return set;
}

/// Fills edges, bend pairs, adjacency and areas from positions and triangles (already validated).
/// stretchPairs null: every edge is a stretch constraint (meshes).
template <Scalar S>
void finishAsset(ClothAsset<S>& asset, const std::vector<std::array<Index, 2>>* stretchPairs,
                 const std::vector<std::array<Index, 2>>& shearPairs, const AssetOptions& options) {
  const Index nv = asset.vertexCount();
  const Index nf = asset.faceCount();
  // Each undirected edge with the far vertices of the faces that share it.
  std::map<std::pair<Index, Index>, std::vector<Index>> edgeFaces;
  asset.faceRestArea.resize(nf);
  for (Index f = 0; f < nf; ++f) {
    const auto& t = asset.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const Index a = t[k], b = t[(k + 1) % 3], far = t[(k + 2) % 3];
      edgeFaces[{std::min(a, b), std::max(a, b)}].push_back(far);
    }
    const auto& x = asset.restPositions;
    asset.faceRestArea[f] = S(0.5) * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm();
  }
  std::vector<std::pair<Index, Index>> vv;
  for (const auto& [edge, fars] : edgeFaces) {
    require(fars.size() <= 2, "edge (" + std::to_string(edge.first) + ", " + std::to_string(edge.second) +
                                  ") is shared by " + std::to_string(fars.size()) +
                                  " faces; the cloth mesh must be manifold (at most 2)");
    asset.edges.push_back({edge.first, edge.second});
    vv.emplace_back(edge.first, edge.second);
    vv.emplace_back(edge.second, edge.first);
    if (fars.size() == 2 && fars[0] != fars[1]) asset.bendPairs.push_back({fars[0], fars[1]});
  }
  asset.vertexNeighbours = buildAdjacency(nv, vv);
  asset.stretch = colourDistanceSet<S>(nv, stretchPairs ? *stretchPairs : asset.edges, asset.restPositions);
  asset.shear = colourDistanceSet<S>(nv, shearPairs, asset.restPositions);
  if (options.bending) asset.bending = colourDistanceSet<S>(nv, asset.bendPairs, asset.restPositions);
}

}  // namespace detail

template <Scalar S> ClothAsset<S> ClothAsset<S>::sheet(const SheetDesc& desc, const AssetOptions& options) {
  detail::require(desc.nx >= 2 && desc.ny >= 2, "sheet needs nx >= 2 and ny >= 2 (got " +
                                                    std::to_string(desc.nx) + " x " + std::to_string(desc.ny) + ")");
  detail::require(std::int64_t(desc.nx) * desc.ny <= (std::int64_t(1) << 26), "sheet of " +
                      std::to_string(desc.nx) + " x " + std::to_string(desc.ny) + " vertices is too large");
  detail::require(std::isfinite(desc.spacing) && desc.spacing > 0 &&
                      desc.spacing * std::max(desc.nx, desc.ny) <= 1e5,
                  "sheet spacing must be positive, finite and the sheet at most 1e5 m across (got spacing " +
                      detail::formatNumber(desc.spacing) + ")");
  detail::require(detail::allFinite(desc.placement.position) && desc.placement.position.cwiseAbs().maxCoeff() <= 1e7 &&
                      detail::allFinite(desc.placement.rotation.coeffs()) &&
                      std::abs(desc.placement.rotation.norm() - 1.0) < 1e-6,
                  "sheet placement must be finite, within 1e7 m of the world origin, with a unit quaternion");
  ClothAsset asset;
  const Index nx = desc.nx, ny = desc.ny;
  auto id = [nx](Index i, Index j) { return j * nx + i; };
  const double x0 = -0.5 * (nx - 1) * desc.spacing, y0 = -0.5 * (ny - 1) * desc.spacing;
  asset.origin = desc.placement.position;
  asset.restPositions.reserve(std::size_t(nx) * ny);
  for (Index j = 0; j < ny; ++j)
    for (Index i = 0; i < nx; ++i)
      asset.restPositions.push_back(
          (desc.placement.rotation * Eigen::Vector3d(x0 + i * desc.spacing, y0 + j * desc.spacing, 0)).template cast<S>());
  std::vector<std::array<Index, 2>> stretchPairs, shearPairs;
  for (Index j = 0; j < ny; ++j)
    for (Index i = 0; i < nx; ++i) {
      if (i + 1 < nx) stretchPairs.push_back({id(i, j), id(i + 1, j)});
      if (j + 1 < ny) stretchPairs.push_back({id(i, j), id(i, j + 1)});
    }
  for (Index j = 0; j + 1 < ny; ++j)
    for (Index i = 0; i + 1 < nx; ++i) {
      const Index a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        asset.triangles.push_back({a, b, c});
        asset.triangles.push_back({a, c, d});
        shearPairs.push_back({a, c});
      } else {
        asset.triangles.push_back({a, b, d});
        asset.triangles.push_back({b, c, d});
        shearPairs.push_back({std::min(b, d), std::max(b, d)});
      }
    }
  detail::finishAsset(asset, &stretchPairs, shearPairs, options);
  return asset;
}

template <Scalar S>
ClothAsset<S> ClothAsset<S>::fromMesh(const std::vector<Vec3<S>>& positions,
                                      const std::vector<std::array<Index, 3>>& triangles,
                                      const AssetOptions& options) {
  using detail::require;
  require(positions.size() <= (std::size_t(1) << 26),
          "a cloth mesh of " + std::to_string(positions.size()) + " vertices is too large (at most 2^26)");
  const Index nv = Index(positions.size());
  require(nv >= 3 && !triangles.empty(), "a cloth mesh needs at least 3 vertices and 1 triangle");
  for (Index i = 0; i < nv; ++i)
    require(detail::allFinite(positions[i]) && positions[i].cwiseAbs().maxCoeff() <= S(1e6),
            "vertex " + std::to_string(i) + " has a non-finite position or one beyond 1e6 m");
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const auto& t = triangles[f];
    for (int k = 0; k < 3; ++k)
      require(t[k] >= 0 && t[k] < nv, "triangle " + std::to_string(f) + " has vertex index " +
                                          std::to_string(t[k]) + " out of range [0, " + std::to_string(nv) + ")");
    require(t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "triangle " + std::to_string(f) + " repeats a vertex index (degenerate)");
    const Vec3<S> e1 = positions[t[1]] - positions[t[0]], e2 = positions[t[2]] - positions[t[0]];
    const S area2 = e1.cross(e2).norm();
    const S lmax = std::max({e1.norm(), e2.norm(), (positions[t[2]] - positions[t[1]]).norm()});
    // Zero area, or so thin that its height is below 1e-6 of its longest edge: no stable normal, no mass.
    require(lmax > 0 && area2 > S(1e-6) * lmax * lmax,
            "triangle " + std::to_string(f) + " is degenerate (zero or near-zero area)");
  }
  // The same three vertices twice, in either winding, would count the face's mass twice.
  std::vector<std::pair<std::array<Index, 3>, std::size_t>> corners(triangles.size());
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    corners[f] = {triangles[f], f};
    std::sort(corners[f].first.begin(), corners[f].first.end());
  }
  std::sort(corners.begin(), corners.end());
  for (std::size_t k = 1; k < corners.size(); ++k)
    require(corners[k].first != corners[k - 1].first, [&] {
      return "triangle " + std::to_string(corners[k].second) + " repeats triangle " +
             std::to_string(corners[k - 1].second) + " (the same three vertices)";
    });
  ClothAsset asset;
  asset.restPositions = positions;
  asset.triangles = triangles;
  // Edges are collected by finishAsset; every edge is structural.
  detail::finishAsset(asset, nullptr, {}, options);
  return asset;
}

}  // namespace drape
