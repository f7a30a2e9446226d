#pragma once
// Metrics of docs/design.md §10, with one definition shared by tests, samples and benches.

#include <drape/collision/pgd.hpp>
#include <drape/front_end.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace drape {

struct StrainStats {
  double mean = 0;  ///< mean |l - l0| / l0 over stretch edges
  double max = 0;
};

template <Scalar S> StrainStats stretchStrain(const ClothAsset<S>& asset, const std::vector<Vec3<S>>& x) {
  StrainStats out;
  const auto& set = asset.stretch;
  for (Index k = 0; k < set.size(); ++k) {
    const auto [a, b] = set.pairs[k];
    const double e = std::abs(double((x[a] - x[b]).norm()) / double(set.restLength[k]) - 1.0);
    out.mean += e;
    out.max = std::max(out.max, e);
  }
  if (set.size() > 0) out.mean /= set.size();
  return out;
}

struct PenetrationStats {
  double depth = 0;      ///< deepest vertex or face point below a solid's surface (m), 0 if none
  double shortfall = 0;  ///< deepest vertex or face point inside the thickness shell (m), 0 if none
};

/// Vertices and the deepest point of every face (PGD with pgdIterations evaluations) against every solid.
template <ClothSolver Solver> PenetrationStats penetration(const Solver& solver, int pgdIterations = 64) {
  using S = typename Solver::scalar_type;
  const auto& x = solver.state().x;
  const double thickness = solver.settings().thickness;
  double minPhi = std::numeric_limits<double>::infinity();
  solver.forEachSolid([&](const auto& solid) {
    for (const auto& p : x) {
      Vec3<S> n;
      minPhi = std::min(minPhi, double(solid.sdf(p, n)));
    }
    for (const auto& t : solver.asset().triangles) {
      FaceQuery<S> q;  // culling is exact: phi is 1-Lipschitz
      if (queryFace<true>(solid.sdf, x[t[0]], x[t[1]], x[t[2]], S(thickness), pgdIterations, q))
        minPhi = std::min(minPhi, double(q.phi));
    }
  });
  return {std::max(0.0, -minPhi), std::max(0.0, thickness - minPhi)};
}

/// Trembling (docs/design.md §10): the normal component of (x_t - x_{t-1}) / dt_frame, accumulated over the
/// frames recorded, of every vertex that has been within thickness + margin of a solid in a recorded frame (or
/// the frame before the first), from that frame on however far it then moves: a vertex that bounces off a
/// surface counts while it is away, so no distance caps the reading. The normal is the nearest solid's where the
/// vertex is. Count::All counts every vertex from the first recorded frame (a cloth that should be at rest as a
/// whole). `rms`/`max` are as defined; `rmsCentred` removes each frame's mean normal velocity of the counted
/// vertices first, so a cloth that as a whole settles or lifts does not count as trembling.
class TrembleMeter {
 public:
  enum class Count { Touched, All };
  explicit TrembleMeter(double marginFraction = 0.2, Count count = Count::Touched)
      : marginFraction_(marginFraction), countAll_(count == Count::All) {}

  /// Records one frame of the solver's state, dtFrame after the last; `record` false only remembers it.
  template <ClothSolver Solver> void frame(const Solver& solver, double dtFrame, bool record);

  double rms() const { return samples_ ? std::sqrt(sumSq_ / double(samples_)) : 0.0; }
  double rmsCentred() const { return samples_ ? std::sqrt(sumSqCentred_ / double(samples_)) : 0.0; }
  double max() const { return max_; }
  double maxCentred() const { return maxCentred_; }
  std::size_t samples() const { return samples_; }
  /// Share of vertices within the margin of a solid in the last recorded frame and the one before.
  double contactFraction() const { return contactFraction_; }
  /// How many vertices the readings cover so far.
  std::size_t counted() const { return std::size_t(std::count(counted_.begin(), counted_.end(), char(1))); }

 private:
  double marginFraction_;
  bool countAll_;
  std::vector<Eigen::Vector3d> prevWorld_;
  std::vector<char> prevNear_;
  std::vector<char> counted_;  ///< 1 for a vertex counted from the recorded frames on (empty before the first)
  double sumSq_ = 0, sumSqCentred_ = 0, max_ = 0, maxCentred_ = 0, contactFraction_ = 0;
  std::size_t samples_ = 0;
};

template <ClothSolver Solver> void TrembleMeter::frame(const Solver& solver, double dtFrame, bool record) {
  using S = typename Solver::scalar_type;
  const Index n = solver.vertexCount();
  const double margin = solver.settings().thickness * (1.0 + marginFraction_);
  std::vector<double> phi(n, std::numeric_limits<double>::infinity());
  std::vector<Eigen::Vector3d> normal(n, Eigen::Vector3d::Zero());
  const auto& x = solver.state().x;
  solver.forEachSolid([&](const auto& solid) {
    for (Index i = 0; i < n; ++i) {
      Vec3<S> g;
      const double d = double(solid.sdf(x[i], g));
      if (d < phi[i]) {
        phi[i] = d;
        normal[i] = g.template cast<double>();
      }
    }
  });
  std::vector<Eigen::Vector3d> world(n);
  for (Index i = 0; i < n; ++i) world[i] = solver.position(i);
  std::vector<char> near(n);
  for (Index i = 0; i < n; ++i) near[i] = phi[i] < margin;
  if (record && !prevWorld_.empty()) {
    if (counted_.empty()) counted_.assign(std::size_t(n), countAll_ ? 1 : 0);
    std::vector<double> vn;
    Index nearBoth = 0;
    for (Index i = 0; i < n; ++i) {
      if (near[i] || prevNear_[i]) counted_[i] = 1;
      if (near[i] && prevNear_[i]) ++nearBoth;
      if (counted_[i]) vn.push_back(normal[i].dot(world[i] - prevWorld_[i]) / dtFrame);
    }
    if (!vn.empty()) {
      double mean = 0;
      for (double u : vn) mean += u;
      mean /= double(vn.size());
      for (double u : vn) {
        sumSq_ += u * u;
        sumSqCentred_ += (u - mean) * (u - mean);
        max_ = std::max(max_, std::abs(u));
        maxCentred_ = std::max(maxCentred_, std::abs(u - mean));
      }
      samples_ += vn.size();
    }
    contactFraction_ = double(nearBoth) / double(n);
  }
  prevWorld_ = std::move(world);
  prevNear_ = std::move(near);
}

}  // namespace drape

// A program that compiles the built-in solvers once (DRAPE_EXTERN_SOLVERS, drape/solver_instances.hpp) compiles
// the meters for them there too: with every shape's face search, they cost each test source about as much as
// the rest of its code.
#ifdef DRAPE_EXTERN_SOLVERS
#include <drape/solver.hpp>
extern template drape::PenetrationStats drape::penetration(const drape::Solver<float>&, int);
extern template drape::PenetrationStats drape::penetration(const drape::Solver<double>&, int);
extern template void drape::TrembleMeter::frame(const drape::Solver<float>&, double, bool);
extern template void drape::TrembleMeter::frame(const drape::Solver<double>&, double, bool);
#endif
