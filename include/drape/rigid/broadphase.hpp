#pragma once
// Broad phase: which bounding boxes overlap. Sweep and prune on one axis, the one along which the box centres
// spread most (recomputed every call, so a pile on the ground sweeps along x or y and a column of falling
// bodies along z). The order of the previous call is kept and re-sorted by insertion sort, which is linear
// when bodies move little between substeps; the sweep costs O(n + pairs overlapping on the axis).

#include <drape/rigid/shapes.hpp>

#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

namespace drape {

class SweepAndPrune {
 public:
  /// The pairs (i, j), i < j, of boxes that overlap (closed intervals on every axis), sorted.
  /// `skip(i, j)`, if given, drops a pair before it is stored (e.g. two kinematic bodies).
  template <class Skip = std::nullptr_t>
  void findPairs(const std::vector<Aabb>& boxes, std::vector<std::pair<int, int>>& pairs, Skip skip = nullptr) {
    pairs.clear();
    const int n = static_cast<int>(boxes.size());
    if (static_cast<int>(order_.size()) != n) {
      order_.resize(n);
      for (int i = 0; i < n; ++i) order_[i] = i;
    }
    if (n < 2) return;

    Eigen::Vector3d mean = Eigen::Vector3d::Zero(), meanSq = Eigen::Vector3d::Zero();
    for (const auto& b : boxes) {
      const Eigen::Vector3d c = 0.5 * (b.min + b.max);
      mean += c, meanSq += c.cwiseAbs2();
    }
    mean /= n, meanSq /= n;
    (meanSq - mean.cwiseAbs2()).maxCoeff(&axis_);
    const int a = static_cast<int>(axis_);

    // Insertion sort by the lower bound on the axis: linear on an almost sorted order.
    for (int i = 1; i < n; ++i) {
      const int id = order_[i];
      const double key = boxes[id].min[a];
      int j = i - 1;
      while (j >= 0 && boxes[order_[j]].min[a] > key) {
        order_[j + 1] = order_[j];
        --j;
      }
      order_[j + 1] = id;
    }

    for (int i = 0; i < n; ++i) {
      const Aabb& bi = boxes[order_[i]];
      for (int j = i + 1; j < n; ++j) {
        const Aabb& bj = boxes[order_[j]];
        if (bj.min[a] > bi.max[a]) break;
        if (!bi.overlaps(bj)) continue;
        const int p = std::min(order_[i], order_[j]), q = std::max(order_[i], order_[j]);
        if constexpr (!std::is_same_v<Skip, std::nullptr_t>) {
          if (skip(p, q)) continue;
        }
        pairs.emplace_back(p, q);
      }
    }
    std::sort(pairs.begin(), pairs.end());
  }

  /// The axis the last call swept along (0 x, 1 y, 2 z).
  int axis() const { return static_cast<int>(axis_); }

 private:
  std::vector<int> order_;
  Eigen::Index axis_ = 0;
};

/// The same pairs as SweepAndPrune::findPairs, by testing every pair (O(n^2)); for tests.
inline std::vector<std::pair<int, int>> bruteForcePairs(const std::vector<Aabb>& boxes) {
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < static_cast<int>(boxes.size()); ++i)
    for (int j = i + 1; j < static_cast<int>(boxes.size()); ++j)
      if (boxes[i].overlaps(boxes[j])) pairs.emplace_back(i, j);
  return pairs;
}

}  // namespace drape
