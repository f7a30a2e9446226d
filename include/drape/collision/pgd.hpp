#pragma once
// The deepest point of a face in a solid: bounding-sphere culling and projected gradient descent over the
// face's barycentric simplex (paper 002, Fig 1).

#include <drape/math.hpp>

#include <algorithm>
#include <limits>

namespace drape {

/// Where a face is deepest in a solid.
template <Scalar S> struct FaceQuery {
  Vec3<S> barycentric;  ///< b, on the simplex
  Vec3<S> point;        ///< b0 x0 + b1 x1 + b2 x2
  Vec3<S> normal;       ///< SDF gradient at point (outward)
  S phi;                ///< signed distance at point (m)
  int evaluations;      ///< SDF evaluations spent, the centroid's included
};

/// Euclidean projection onto {b : b_i >= 0, sum b_i = 1} (sort-based, exact for three coordinates).
template <Scalar S> Vec3<S> projectToSimplex(const Vec3<S>& y) {
  S u[3] = {y[0], y[1], y[2]};
  std::sort(u, u + 3, [](S a, S b) { return a > b; });
  S sum = 0, theta = 0;
  for (int j = 0; j < 3; ++j) {
    sum += u[j];
    const S t = (sum - S(1)) / S(j + 1);
    if (u[j] - t > S(0)) theta = t;
  }
  return (y.array() - theta).cwiseMax(S(0)).matrix();
}

/// Bounding sphere of a face: centre at the centroid, radius the largest centroid-to-vertex distance.
/// Because phi is 1-Lipschitz, phi(centroid) > radius + margin proves no point of the face is within margin.
template <Scalar S> struct FaceSphere {
  Vec3<S> centre;
  S radius;
};

template <Scalar S> FaceSphere<S> faceSphere(const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2) {
  const Vec3<S> c = (x0 + x1 + x2) / S(3);
  const S r2 = std::max({(x0 - c).squaredNorm(), (x1 - c).squaredNorm(), (x2 - c).squaredNorm()});
  return {c, std::sqrt(r2)};
}

/// Projected gradient descent for min phi(b0 x0 + b1 x1 + b2 x2) over the simplex, started from the centroid
/// (a corner start gets stuck on box ridges) whose value phiC and gradient gradC the caller already has from
/// culling. d phi / d b_i = grad phi . x_i. The first step is long enough to reach any corner; later steps
/// take the Barzilai-Borwein length, and a step that does not lower phi is halved and retried. Stops after
/// maxIterations SDF evaluations or when b moves less than 1e-5.
template <Scalar S, class Field>
FaceQuery<S> deepestPointOnFace(const Field& sdf, const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2,
                                const Vec3<S>& centroid, S phiC, const Vec3<S>& gradC, int maxIterations) {
  FaceQuery<S> q{Vec3<S>::Constant(S(1) / S(3)), centroid, gradC, phiC, 1};
  // Only the part of the gradient along the simplex matters; removing the mean keeps the numbers small.
  auto gradB = [&](const Vec3<S>& n) {
    const Vec3<S> g(n.dot(x0), n.dot(x1), n.dot(x2));
    return Vec3<S>(g.array() - g.mean());
  };
  Vec3<S> g = gradB(q.normal);
  const S range = g.maxCoeff() - g.minCoeff();
  const S extent = std::max({(x1 - x0).norm(), (x2 - x1).norm(), (x0 - x2).norm()});
  if (!(range > S(1e-7) * extent)) return q;  // phi is flat across the face to first order
  S eta = S(1) / range;
  const S etaMax = S(1e4) / std::max(extent, std::numeric_limits<S>::min());
  constexpr S kStepTolerance = S(1e-5);
  while (q.evaluations < maxIterations) {
    // A move longer than 2 in b crosses the whole simplex: clamp it, so the projection stays well-conditioned.
    Vec3<S> move = eta * g;
    const S longest = move.cwiseAbs().maxCoeff();
    if (longest > S(2)) move *= S(2) / longest;
    const Vec3<S> b = projectToSimplex<S>(q.barycentric - move);
    const Vec3<S> s = b - q.barycentric;
    if (s.cwiseAbs().maxCoeff() < kStepTolerance) break;
    const Vec3<S> p = b[0] * x0 + b[1] * x1 + b[2] * x2;
    Vec3<S> n;
    const S phi = sdf(p, n);
    ++q.evaluations;
    if (phi < q.phi) {
      const Vec3<S> gNew = gradB(n);
      const S sy = s.dot(gNew - g);
      eta = sy > S(0) ? std::min(s.squaredNorm() / sy, etaMax) : std::min(eta * S(2), etaMax);
      q = {b, p, n, phi, q.evaluations};
      g = gNew;
    } else {
      eta *= S(0.5);
    }
  }
  return q;
}

}  // namespace drape
