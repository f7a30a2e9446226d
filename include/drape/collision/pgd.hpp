#pragma once
// The deepest point of a face in a solid: bounding-sphere culling and projected gradient descent over the
// face's barycentric simplex (paper 002, Fig 1).

#include <drape/math.hpp>

#include <algorithm>
#include <limits>

#ifndef PGD_LAMBDA
#define PGD_LAMBDA 0
#endif
#ifndef PGD_GAP
#define PGD_GAP 2e-4
#endif

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

/// Kelley cutting planes for min phi(b0 x0 + b1 x1 + b2 x2) over the simplex, started from the centroid
/// whose value phiC and gradient gradC the caller already has from culling.
template <Scalar S, class Field>
FaceQuery<S> deepestPointOnFace(const Field& sdf, const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2,
                                const Vec3<S>& centroid, S phiC, const Vec3<S>& gradC, int maxIterations) {
  FaceQuery<S> q{Vec3<S>::Constant(S(1) / S(3)), centroid, gradC, phiC, 1};
  constexpr int kMaxCuts = 16;
  const Vec3<S> e1 = x1 - x0, e2 = x2 - x0;
  const S extent = std::max({e1.norm(), e2.norm(), (x2 - x1).norm()});
  const S tolerance = S(PGD_GAP) * extent;
  // A cut is the tangent plane phi_k + n_k . (x - p_k), stored as its values at the three corners.
  auto cutAt = [&](const Vec3<S>& b, S phi, const Vec3<S>& n) {
    const S nd = n.dot(b[1] * e1 + b[2] * e2);
    return Vec3<S>(phi - nd, phi + n.dot(e1) - nd, phi + n.dot(e2) - nd);
  };
  Vec3<S> cuts[kMaxCuts];
  int count = 1;
  cuts[0] = cutAt(q.barycentric, phiC, gradC);
  Index corner = 0;
  S model = cuts[0].minCoeff(&corner);
  Vec3<S> next = Vec3<S>::Unit(corner);
  S lower = model;
  bool exact = true;
  Vec3<S> poly[kMaxCuts + 3], clipped[kMaxCuts + 3];
  while (q.evaluations < maxIterations && q.phi - lower > tolerance) {
    const Vec3<S> b = next / next.sum();
    const Vec3<S> p = x0 + b[1] * e1 + b[2] * e2;
    Vec3<S> n;
    const S phi = sdf(p, n);
    ++q.evaluations;
    if (phi < q.phi) q = {b, p, n, phi, q.evaluations};
    if (q.phi - lower <= tolerance) break;
    const Vec3<S> c = cutAt(b, phi, n);
    if (count == kMaxCuts) {  // keep the cuts active at the model's minimum: it stays the minimum
      int kept = 0;
      const S slack = S(1e-4) * tolerance;
      for (int k = 0; k < count; ++k)
        if (cuts[k].dot(b) >= model - slack && kept < kMaxCuts - 1) cuts[kept++] = cuts[k];
      if (kept == kMaxCuts - 1) exact = false;
      count = kept;
    }
    // The model's new minimum lies on the new cut (the old minimum violates it): minimise the new cut over
    // the part of the triangle where it is the highest.
    int vertices = 3;
    for (int k = 0; k < 3; ++k) poly[k] = Vec3<S>::Unit(k);
    for (int k = 0; k < count && vertices > 0; ++k) {
      const Vec3<S> h = c - cuts[k];
      int out = 0;
      for (int i = 0; i < vertices; ++i) {
        const Vec3<S>& u = poly[i];
        const Vec3<S>& v = poly[(i + 1) % vertices];
        const S su = h.dot(u), sv = h.dot(v);
        if (su >= S(0)) clipped[out++] = u;
        if ((su >= S(0)) != (sv >= S(0))) clipped[out++] = u + (su / (su - sv)) * (v - u);
      }
      vertices = out;
      std::copy(clipped, clipped + out, poly);
    }
    if (vertices == 0) break;
    cuts[count++] = c;
    int arg = 0;
    model = c.dot(poly[0]);
    for (int i = 1; i < vertices; ++i) {
      const S m = c.dot(poly[i]);
      if (m < model) model = m, arg = i;
    }
    next = poly[arg].cwiseMax(S(0));
    if (PGD_LAMBDA > 0) next += S(PGD_LAMBDA) * (q.barycentric - next / next.sum());
    if (exact) lower = std::max(lower, model);
  }
  return q;
}

}  // namespace drape
