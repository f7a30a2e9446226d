#pragma once
// Tethers (Settings::tethers; docs/design.md §1, "Tethers"): each free vertex is kept within its rest distance,
// measured along the cloth, of the kinematic vertices it hangs from (Kim, Chentanez and Müller-Fischer, "Long range
// attachments: a method to simulate inextensible clothing in computer games", 2012). A few passes over the edges
// carry a pin's pull only a few edges a substep, so a cloth hanging from a few pinned vertices stretches most beside
// them; a tether reaches the whole way at once.

#include <drape/cloth/asset.hpp>
#include <drape/math.hpp>

#include <cmath>
#include <functional>
#include <queue>
#include <tuple>
#include <vector>

namespace drape {

/// Each free vertex's tethers, to the kTethersPerVertex kinematic vertices nearest it along the cloth's edges.
template <Scalar S> struct Tethers {
  /// Anchors per vertex: with four, a sheet pinned at its corners is tethered to all of them; along a pinned row,
  /// to the nearest stretch of it.
  static constexpr int kTethersPerVertex = 4;

  std::vector<Index> start{0};  ///< vertex i's tethers are [start[i], start[i + 1])
  std::vector<Index> anchor;    ///< the kinematic vertex of each tether
  std::vector<S> length;        ///< the longest each may be (m): the shortest path to its anchor along rest edges

  bool empty() const { return anchor.empty(); }

  /// Builds the tethers of `asset`'s vertices for the inverse masses `invMass` (0: kinematic). The lengths are
  /// shortest paths along the rest mesh's edges (Dijkstra from every anchor at once, keeping each vertex's nearest
  /// kTethersPerVertex anchors), never shorter than the distance along the surface, so a tether never holds a
  /// vertex nearer than the cloth itself would let it be. Anchors that no edge path reaches give no tether.
  void build(const ClothAsset<S>& asset, const S* invMass) {
    const Index n = Index(asset.restPositions.size());
    // Each vertex's nearest anchors, settled in order of distance: (distance, vertex, anchor).
    using Entry = std::tuple<double, Index, Index>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
    for (Index i = 0; i < n; ++i)
      if (invMass[i] == S(0)) open.emplace(0.0, i, i);
    std::vector<std::vector<std::pair<Index, double>>> nearest(static_cast<std::size_t>(n));
    auto holds = [&](Index v, Index a) {
      for (const auto& [b, d] : nearest[std::size_t(v)])
        if (b == a) return true;
      return false;
    };
    while (!open.empty()) {
      const auto [d, v, a] = open.top();
      open.pop();
      auto& mine = nearest[std::size_t(v)];
      if (int(mine.size()) >= kTethersPerVertex || holds(v, a)) continue;
      mine.emplace_back(a, d);
      for (const Index* u = asset.vertexNeighbours.begin(v); u != asset.vertexNeighbours.end(v); ++u) {
        if (int(nearest[std::size_t(*u)].size()) >= kTethersPerVertex || holds(*u, a)) continue;
        const double l = (asset.restPositions[*u] - asset.restPositions[v]).template cast<double>().norm();
        open.emplace(d + l, *u, a);
      }
    }
    start.assign(1, 0);
    anchor.clear();
    length.clear();
    for (Index i = 0; i < n; ++i) {
      if (invMass[i] > S(0))
        for (const auto& [a, d] : nearest[std::size_t(i)]) anchor.push_back(a), length.push_back(S(d));
      start.push_back(Index(anchor.size()));
    }
  }
};

/// Pulls each vertex of [begin, end) that is further from an anchor than its tether allows back onto the tether's
/// sphere, toward the anchor, in the positions the constraint solve works on. Anchors are kinematic and never
/// moved here, so any split of the vertices among threads gives the same result.
template <Scalar S> void applyTethers(Index begin, Index end, const Tethers<S>& tethers, Vec4<S>* xw) {
  for (Index i = begin; i < end; ++i) {
    const Index first = tethers.start[std::size_t(i)], last = tethers.start[std::size_t(i) + 1];
    if (first == last) continue;
    Vec3<S> x = xw[i].template head<3>();
    for (Index k = first; k < last; ++k) {
      const Vec3<S> p = xw[tethers.anchor[std::size_t(k)]].template head<3>();
      const Vec3<S> d = x - p;
      const S limit = tethers.length[std::size_t(k)];
      const S squared = d.squaredNorm();
      if (squared > limit * limit) x = p + d * (limit / std::sqrt(squared));
    }
    xw[i].template head<3>() = x;
  }
}

}  // namespace drape
