#pragma once
// The cloth side of the broad phase, for scenes with many bounded solids (many rigid bodies at linear cost per
// body). The cloth's vertices are binned into the cells of a uniform lattice (VertexBins, a counting sort), rebuilt when they have
// moved too far from where they were binned (below). A bounded solid's vertex pass then visits only the
// vertices in the cells its box meets, grown by the thickness, and its face pass only the faces owned by them
// (a face is owned by its first vertex, and every point of it lies within the face's reach of that vertex).
//
// Nothing is lost: outside a solid's box its field is at least the distance to the box (placeBounds), so a
// vertex further than the thickness from the box is no contact, and a face whose owner is further than the
// thickness plus the reach has no point within the thickness. So the contacts are those of the full passes,
// bit for bit (the faces are visited in ascending order, as the full pass does).
//
// Vertices move in every substep's prediction and solve and while contacts are resolved. The velocity update and
// every contact pass report how far the vertices they moved have got from where they were binned; the largest
// such distance since the bins were built (the drift) grows each query by as much, and past a quarter of a cell
// the bins are rebuilt (docs/design.md §13).

#include <drape/math.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace drape {

template <Scalar S> class VertexBins {
 public:
  /// Once per topology: the faces each vertex owns, and the cell size.
  void setTopology(const std::vector<std::array<Index, 3>>& triangles, Index vertexCount, S cellSize) {
    vertexCount_ = vertexCount;
    cell_ = cellSize;
    ownedStart_.assign(std::size_t(vertexCount) + 1, 0);
    for (const auto& t : triangles) ++ownedStart_[std::size_t(t[0]) + 1];
    for (Index i = 0; i < vertexCount; ++i) ownedStart_[i + 1] += ownedStart_[i];
    owned_.resize(triangles.size());
    std::vector<Index> fill(ownedStart_.begin(), ownedStart_.end() - 1);
    for (Index f = 0; f < Index(triangles.size()); ++f) owned_[std::size_t(fill[triangles[f][0]]++)] = f;
    cellOf_.resize(std::size_t(vertexCount));
    faceBits_.assign((triangles.size() + 63) / 64, 0);
    items_.resize(std::size_t(vertexCount));
    binned_.resize(std::size_t(vertexCount));
    reach_.resize(std::size_t(vertexCount));
  }

  S drift() const { return drift_; }
  /// A pass moved vertices at most d from where they were binned.
  void noteDrift(S d) { drift_ = std::max(drift_, d); }
  /// The positions the vertices were binned at.
  const Vec3<S>* binned() const { return binned_.data(); }
  /// The binned positions are so far from the current ones that queries would grow too much.
  bool stale() const { return !(drift_ <= S(kStaleDrift) * cellUsed_); }
  /// The drift, in cells, past which the bins are rebuilt: in the rain the queries grown by the drift cost more
  /// than building the bins more often, down to a quarter of a cell (docs/design.md §13).
  static constexpr double kStaleDrift = 0.25;

  /// Bins the vertices by their current positions and measures how far each vertex's faces reach from it.
  void build(const Vec3<S>* x, const std::vector<std::array<Index, 3>>& triangles) {
    drift_ = 0;
    Vec3<S> lo = Vec3<S>::Constant(std::numeric_limits<S>::max()), hi = -lo;
    for (Index i = 0; i < vertexCount_; ++i) {
      binned_[std::size_t(i)] = x[i];
      lo = lo.cwiseMin(x[i]);
      hi = hi.cwiseMax(x[i]);
      reach_[std::size_t(i)] = 0;
    }
    // Squares first and one root per vertex: a root is monotone, so these are the same reaches bit for bit as a
    // root per face. The largest is kept in a local: as a member, every store into reach_ might have changed it.
    for (const auto& t : triangles) {
      S& own = reach_[std::size_t(t[0])];
      own = std::max(own, std::max((x[t[1]] - x[t[0]]).squaredNorm(), (x[t[2]] - x[t[0]]).squaredNorm()));
    }
    S most = 0;
    for (Index i = 0; i < vertexCount_; ++i) {
      S& own = reach_[std::size_t(i)];
      own = rootOf(own);
      most = std::max(most, own);
    }
    maxReach_ = most;
    // At most about two cells per vertex: a cloth spread thin over a large box gets larger cells.
    const double maxCells = 2.0 * double(vertexCount_) + 64;
    double size = double(cell_);
    const Eigen::Vector3d extent = (hi - lo).template cast<double>();
    auto cellsAt = [&](double c) {
      double total = 1;
      for (int k = 0; k < 3; ++k) total *= std::floor(extent[k] / c) + 1;
      return total;
    };
    if (!(extent.allFinite())) size = std::numeric_limits<double>::infinity();  // an exploded cloth: one cell
    while (std::isfinite(size) && cellsAt(size) > maxCells) size *= 1.5;
    cellUsed_ = S(size);
    inv_ = std::isfinite(size) ? S(1.0 / size) : S(0);
    low_ = lo;
    for (int k = 0; k < 3; ++k) dims_[k] = std::isfinite(size) ? int(std::floor(extent[k] / size)) + 1 : 1;
    const std::size_t cells = std::size_t(dims_[0]) * std::size_t(dims_[1]) * std::size_t(dims_[2]);
    cellStart_.assign(cells + 1, 0);
    for (Index i = 0; i < vertexCount_; ++i) {
      const std::array<int, 3> c = cellAt(x[i]);
      cellOf_[std::size_t(i)] = std::int32_t(linear(c[0], c[1], c[2]));
      ++cellStart_[std::size_t(cellOf_[std::size_t(i)]) + 1];
    }
    for (std::size_t c = 0; c < cells; ++c) cellStart_[c + 1] += cellStart_[c];
    fill_.assign(cellStart_.begin(), cellStart_.end() - 1);
    for (Index i = 0; i < vertexCount_; ++i) items_[std::size_t(fill_[std::size_t(cellOf_[std::size_t(i)])]++)] = i;
  }

  /// The vertices whose current position lies in [low, high] grown by margin (each once, in cell order).
  void vertices(const Vec3<S>* x, const Vec3<S>& low, const Vec3<S>& high, S margin, std::vector<Index>& out) const {
    out.clear();
    const Vec3<S> lo = low.array() - margin, hi = high.array() + margin;
    visit(lo.array() - drift_, hi.array() + drift_, [&](Index i) {
      if ((x[i].array() >= lo.array()).all() && (x[i].array() <= hi.array()).all()) out.push_back(i);
    });
  }

  /// How many vertices vertices() would look at for the same box: those binned in the cells it meets.
  Index countNear(const Vec3<S>& low, const Vec3<S>& high, S margin) const {
    Index count = 0;
    const Vec3<S> lo = low.array() - margin - drift_, hi = high.array() + margin + drift_;
    std::array<int, 3> a{}, b{};
    if (!cellRange(lo, hi, a, b)) return 0;
    for (int k = a[2]; k <= b[2]; ++k)
      for (int j = a[1]; j <= b[1]; ++j) {
        const std::size_t row = linear(0, j, k);
        count += cellStart_[row + std::size_t(b[0]) + 1] - cellStart_[row + std::size_t(a[0])];
      }
    return count;
  }

  /// The faces that may have a point in [low, high] grown by margin, in ascending order. They are marked in a
  /// bit set as the cells give them, then read out word by word over the span of face indices marked (faces
  /// near one body are a few rows of the cloth: a few words), which costs less than sorting them.
  void faces(const Vec3<S>* x, const Vec3<S>& low, const Vec3<S>& high, S margin, std::vector<Index>& out) {
    out.clear();
    // Every point of a face is within its owner's reach + 2 drift of the owner now (each of the face's vertices
    // moved at most drift since the reach was measured).
    const S grow = margin + S(2) * drift_;
    const S most = grow + maxReach_;
    std::size_t first = faceBits_.size(), last = 0;
    visit(low.array() - most - drift_, high.array() + most + drift_, [&](Index i) {
      const S g = grow + reach_[std::size_t(i)];
      if (!((x[i].array() >= low.array() - g).all() && (x[i].array() <= high.array() + g).all())) return;
      for (Index k = ownedStart_[std::size_t(i)]; k < ownedStart_[std::size_t(i) + 1]; ++k) {
        const auto f = std::size_t(owned_[std::size_t(k)]);
        faceBits_[f / 64] |= std::uint64_t(1) << (f % 64);
        first = std::min(first, f / 64);
        last = std::max(last, f / 64);
      }
    });
    for (std::size_t w = first; w <= last && w < faceBits_.size(); ++w) {
      for (std::uint64_t bits = faceBits_[w]; bits != 0; bits &= bits - 1)
        out.push_back(Index(w * 64 + std::size_t(std::countr_zero(bits))));
      faceBits_[w] = 0;  // cleared for the next query
    }
  }

 private:
  /// The cell of a point, clamped to the lattice (a non-finite coordinate goes to cell 0).
  std::array<int, 3> cellAt(const Vec3<S>& p) const {
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k) {
      const S t = (p[k] - low_[k]) * inv_;
      c[k] = t >= S(0) ? int(std::min(t, S(dims_[k] - 1))) : 0;
    }
    return c;
  }
  std::size_t linear(int i, int j, int k) const {
    return (std::size_t(k) * std::size_t(dims_[1]) + std::size_t(j)) * std::size_t(dims_[0]) + std::size_t(i);
  }
  /// The cells [a, b] that meet [lo, hi]; false where none does (or a bound is NaN).
  bool cellRange(const Vec3<S>& lo, const Vec3<S>& hi, std::array<int, 3>& a, std::array<int, 3>& b) const {
    for (int k = 0; k < 3; ++k) {
      const S t0 = (lo[k] - low_[k]) * inv_, t1 = (hi[k] - low_[k]) * inv_;
      if (!(t1 >= S(0)) || !(t0 < S(dims_[k]))) return false;
      a[k] = t0 > S(0) ? int(t0) : 0;
      b[k] = int(std::min(t1, S(dims_[k] - 1)));
    }
    return true;
  }
  /// Calls f(vertex) for every vertex binned in a cell that meets [lo, hi].
  template <class F> void visit(const Vec3<S>& lo, const Vec3<S>& hi, F&& f) const {
    std::array<int, 3> a{}, b{};
    if (!cellRange(lo, hi, a, b)) return;
    for (int k = a[2]; k <= b[2]; ++k)
      for (int j = a[1]; j <= b[1]; ++j) {
        const std::size_t row = linear(0, j, k);
        for (std::size_t c = row + std::size_t(a[0]); c <= row + std::size_t(b[0]); ++c)
          for (Index s = cellStart_[c]; s < cellStart_[c + 1]; ++s) f(items_[std::size_t(s)]);
      }
  }

  Index vertexCount_ = 0;
  S cell_ = 1, cellUsed_ = 1, inv_ = 1, maxReach_ = 0, drift_ = 0;
  Vec3<S> low_ = Vec3<S>::Zero();
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<Vec3<S>> binned_;  ///< positions at the build
  std::vector<S> reach_;         ///< farthest vertex of the faces each vertex owns, at the build
  std::vector<Index> ownedStart_, owned_;  ///< faces owned by each vertex (CSR)
  std::vector<Index> cellStart_, fill_, items_;
  std::vector<std::int32_t> cellOf_;
  std::vector<std::uint64_t> faceBits_;  ///< scratch of faces(): a bit per face, all clear between queries
};

}  // namespace drape
