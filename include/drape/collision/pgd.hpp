#pragma once
// The deepest point of a face in a solid: bounding-sphere culling, and a cutting-plane search over the face's
// barycentric simplex (in place of the projected gradient descent of the SDF collision paper, Fig 1); on a ball
// and a capsule, the face's point nearest the centre or the core segment in closed form.

#include <drape/detail/parallel.hpp>
#include <drape/detail/triangle.hpp>
#include <drape/kernel_constants.hpp>
#include <drape/math.hpp>

#include <algorithm>
#include <limits>
#include <utility>

namespace drape {

/// A culled face's clearance (queryFace) is shortened by this share of the lengths it was computed from, so that
/// rounding cannot let a face skip a search that would have found it in contact. CPU only: the GPU's face pass
/// keeps nothing between substeps.
inline constexpr double kClearanceSlack = 1e-5;

/// Where a face is deepest in a solid.
template <Scalar S> struct FaceQuery {
  Vec3<S> barycentric;  ///< b, on the simplex
  Vec3<S> point;        ///< b0 x0 + b1 x1 + b2 x2
  Vec3<S> normal;       ///< SDF gradient at point (outward)
  S phi;                ///< signed distance at point (m)
  int evaluations;      ///< SDF evaluations spent, the centroid's included
};

/// Euclidean projection onto {b : b_i >= 0, sum b_i = 1} (sort-based, exact for three coordinates), for the
/// descent on non-convex fields.
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

/// The point of the triangle (x0, x1, x2) nearest to p, as barycentric weights (detail::nearestRegion). False
/// for a flat triangle, which the caller searches otherwise: on a triangle with no area the Voronoi regions
/// overlap, and rounding picked the wrong edge, a point 1 mm from the nearest, where the build fuses
/// multiply-adds. Inlined, with queryFace, into the face pass: called, its weights went back through memory and
/// were read back at once, wider than they were stored (a store-forwarding stall per face on a ball).
template <Scalar S>
DRAPE_ALWAYS_INLINE bool nearestOnTriangle(const Vec3<S>& p, const Vec3<S>& x0, const Vec3<S>& x1,
                                           const Vec3<S>& x2, Vec3<S>& b) {
  using F = detail::TriangleFeature;
  const Vec3<S> e1 = x1 - x0, e2 = x2 - x0;
  if (!(e1.cross(e2).squaredNorm() > S(constants::kFlatSine2) * e1.squaredNorm() * e2.squaredNorm())) return false;
  const detail::TriangleRegion<S> r = detail::nearestRegion<S>(p, x0, x1, x2);
  switch (r.feature) {
    case F::VertexA: b = Vec3<S>(1, 0, 0); return true;
    case F::VertexB: b = Vec3<S>(0, 1, 0); return true;
    case F::VertexC: b = Vec3<S>(0, 0, 1); return true;
    case F::EdgeAB: b = Vec3<S>(S(1) - r.s, r.s, 0); return true;
    case F::EdgeCA: b = Vec3<S>(S(1) - r.s, 0, r.s); return true;
    case F::EdgeBC: b = Vec3<S>(0, S(1) - r.s, r.s); return true;
    case F::Face: break;
  }
  b = Vec3<S>(S(1) - r.s - r.t, r.s, r.t);
  return !r.flat;
}

namespace detail {

/// x0 + b1 (x1 - x0) + b2 (x2 - x0), in Eigen's order, written out: in the face pass the Eigen expression became
/// a call.
template <Scalar S>
DRAPE_ALWAYS_INLINE Vec3<S> pointOnFace(const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2, S b1, S b2) {
  return Vec3<S>(x0.x() + b1 * (x1.x() - x0.x()) + b2 * (x2.x() - x0.x()),
                 x0.y() + b1 * (x1.y() - x0.y()) + b2 * (x2.y() - x0.y()),
                 x0.z() + b1 * (x1.z() - x0.z()) + b2 * (x2.z() - x0.z()));
}
/// The squared distance from x to the segment a + s d, s in [0, 1], of squared length `length2`.
template <Scalar S>
DRAPE_ALWAYS_INLINE S squaredToSegment(const Vec3<S>& x, const Vec3<S>& a, const Vec3<S>& d, S length2) {
  const Vec3<S> r = minus3(x, a);
  const S s = length2 > S(0) ? std::clamp(dot3(d, r) / length2, S(0), S(1)) : S(0);
  const Vec3<S> off = movedAlong(r, -s, d);
  return dot3(off, off);
}

}  // namespace detail

/// The point of the triangle (x0, x1, x2) nearest to the segment [a, b] (a capsule's core), as barycentric
/// weights. The nearest pair of points is one of: an end of the segment with its nearest point of the triangle, a
/// corner of the triangle with its nearest point of the segment, or an interior point of the segment with one of
/// an edge where the two lines' nearest points both fall inside; or the segment crosses the triangle. Each
/// candidate is a true pair of points, so the least of them never undercuts the distance: where a segment and an
/// edge are too nearly parallel for their lines' nearest points (kParallelSine2), an end of one of them is as
/// near to within the square of the angle. False for a flat triangle and where the segment crosses the triangle
/// or lies in its plane: the face then holds a point of the core, and which side to push it to is the search's.
/// Inlined into the face pass, as nearestOnTriangle is. The GLSL twin (shaders/collide_faces.comp) follows it
/// step for step.
template <Scalar S>
DRAPE_ALWAYS_INLINE bool nearestToSegment(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& x0, const Vec3<S>& x1,
                                          const Vec3<S>& x2, Vec3<S>& w) {
  using detail::dot3, detail::minus3;
  const Vec3<S> e1 = minus3(x1, x0), e2 = minus3(x2, x0);
  const Vec3<S> normal = e1.cross(e2);
  if (!(dot3(normal, normal) > S(constants::kFlatSine2) * dot3(e1, e1) * dot3(e2, e2))) return false;
  const Vec3<S> d = minus3(b, a);
  const S da = dot3(normal, minus3(a, x0)), db = dot3(normal, minus3(b, x0));
  if (!(da > S(0) && db > S(0)) && !(da < S(0) && db < S(0))) {  // the segment meets the triangle's plane
    if (!(da != db)) return false;                                // in it, or of no length on it
    const detail::TriangleRegion<S> r = detail::nearestRegion<S>(movedAlong(a, da / (da - db), d), x0, x1, x2);
    if (r.feature == detail::TriangleFeature::Face) return false;
  }
  S best = std::numeric_limits<S>::infinity();
  // The segment's ends.
  for (const Vec3<S>* end : {&a, &b}) {
    Vec3<S> u;
    if (!nearestOnTriangle<S>(*end, x0, x1, x2, u)) return false;
    const Vec3<S> off = minus3(movedAlong(movedAlong(x0, u[1], e1), u[2], e2), *end);
    const S dist = dot3(off, off);
    if (dist < best) best = dist, w = u;
  }
  const S length2 = dot3(d, d);
  const Vec3<S>* corners[3] = {&x0, &x1, &x2};
  for (int k = 0; k < 3; ++k) {
    // Corner k and its nearest point of the segment.
    const Vec3<S>& c = *corners[k];
    const S dist = detail::squaredToSegment(c, a, d, length2);
    if (dist < best) best = dist, w = Vec3<S>::Unit(k);
    // The edge from corner k to the next, against the segment: both lines' nearest points, where both are inside.
    const Vec3<S> e = minus3(*corners[(k + 1) % 3], c), r = minus3(a, c);
    const S ee = dot3(e, e), de = dot3(d, e), dr = dot3(d, r), er = dot3(e, r);
    const S det = length2 * ee - de * de;
    if (!(det > S(constants::kParallelSine2) * length2 * ee)) continue;
    const S s = (de * er - dr * ee) / det, t = (length2 * er - de * dr) / det;
    if (!(s >= S(0) && s <= S(1) && t >= S(0) && t <= S(1))) continue;
    const Vec3<S> off = movedAlong(movedAlong(r, s, d), -t, e);
    const S between = dot3(off, off);
    if (between < best) {
      best = between;
      w = Vec3<S>::Zero();
      w[k] = S(1) - t;
      w[(k + 1) % 3] = t;
    }
  }
  return true;
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

/// min phi(b0 x0 + b1 x1 + b2 x2) over the simplex, started from the centroid whose value phiC and gradient
/// gradC the caller already has from culling; at most maxIterations SDF evaluations, the centroid's included.
///
/// Why cutting planes rather than projected gradient descent: every built-in solid is convex, so phi along a
/// face is convex, but it is often not smooth there. Inside a box it is a max of planes (gradient steps
/// zigzag across the crease and stall), a thin capsule or a small ball crossing the face makes it a V-shaped
/// valley or a cone, and on a plane a gradient step that hits an edge crawls along it. Convexity gives every
/// evaluation a global lower bound instead: the tangent plane phi_k + n_k . (x - p_k) lies below phi on the
/// whole face. Kelley's method evaluates next where the max of those planes (the model) is lowest. On a max of
/// planes or a cone the model becomes exact after a few cuts and the answer is exact; on smooth curved faces
/// it closes in steadily. The first step goes to the corner the centroid's gradient points at, as the long
/// first step of projected gradient descent does; a plane is done after that (two evaluations).
///
/// The model's minimum is a certified lower bound on the true minimum, so the search stops as soon as the
/// best value found is within kGap face lengths of it, rather than after a fixed count: most faces take 2-5
/// evaluations, and the budget only caps the curved cases (a ball smaller than a face).
///
/// Why the model is cheap to minimise: in barycentric coordinates a cut is linear, c_k . b with c_k its values
/// at the three corners. The search only ever evaluates at the model's minimiser, and the new cut is above the
/// old model there (or the gap is closed and the search stops), so the new minimum lies on the new cut (Seidel's
/// incremental LP): clip the triangle to where the new cut is highest and take its lowest vertex. That is
/// O(cuts) per step, with no LP solver. The cuts are kept (up to kMaxCuts; beyond that, only those active at
/// the minimum, which keeps it the minimum); evaluating anywhere else, e.g. a damped or Newton step, would
/// break that invariant and with it the certificate.
///
/// The same bound culls: once the certified minimum is clearly above `floor` (the contact margin), no point of
/// the face is within it and the search stops, returning its best point so far (whose phi is then above the
/// floor too). The default, infinity, never stops early. Near a solid most faces that pass the bounding-sphere
/// cull are settled so by the centroid's own tangent plane, without another evaluation.
template <Scalar S, class Field>
FaceQuery<S> deepestPointOnFace(const Field& sdf, const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2,
                                const Vec3<S>& centroid, S phiC, const Vec3<S>& gradC, int maxIterations,
                                S floor = std::numeric_limits<S>::infinity()) {
  FaceQuery<S> q{Vec3<S>::Constant(S(1) / S(3)), centroid, gradC, phiC, 1};
  constexpr int kMaxCuts = constants::kMaxCuts;
  constexpr S kGap = S(constants::kFaceSearchGap);
  const Vec3<S> e1 = x1 - x0, e2 = x2 - x0;
  const S extent = std::max({e1.norm(), e2.norm(), (x2 - x1).norm()});
  const S tolerance = kGap * extent;
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
  // Clipping a convex polygon adds at most one vertex per cut; the slack covers rounding.
  constexpr int kMaxVertices = 2 * kMaxCuts + 6;
  Vec3<S> polyStore[kMaxVertices], clippedStore[kMaxVertices];
  // A face resting on the solid has its minimum at the floor itself (a vertex just placed at the thickness):
  // the certificate must clear the floor by more than rounding, or such a contact could be lost.
  const S stop = floor + tolerance;
  while (q.evaluations < maxIterations && q.phi - lower > tolerance && lower < stop) {
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
      const S slack = S(constants::kCutSlack) * tolerance;
      for (int k = 0; k < count; ++k)
        if (cuts[k].dot(b) >= model - slack && kept < kMaxCuts - 1) cuts[kept++] = cuts[k];
      if (kept == kMaxCuts - 1) exact = false;  // maybe some dropped: the model's minimum is then no bound
      count = kept;
    }
    // The model's new minimum lies on the new cut (the old minimum violates it): minimise the new cut over
    // the part of the triangle where it is the highest.
    // The polygon and its clipped copy trade places after each cut; each vertex's side of the cut is computed
    // once, and the next vertex's index without an integer division.
    Vec3<S>* poly = polyStore;
    Vec3<S>* clipped = clippedStore;
    int vertices = 3;
    for (int k = 0; k < 3; ++k) poly[k] = Vec3<S>::Unit(k);
    for (int k = 0; k < count && vertices > 0; ++k) {
      const Vec3<S> h = c - cuts[k];
      int out = 0;
      S su = h.dot(poly[0]);
      for (int i = 0; i < vertices; ++i) {
        const Vec3<S>& u = poly[i];
        const Vec3<S>& v = poly[i + 1 == vertices ? 0 : i + 1];
        const S sv = h.dot(v);
        if (out + 2 > kMaxVertices) break;
        if (su >= S(0)) clipped[out++] = u;
        if ((su >= S(0)) != (sv >= S(0))) clipped[out++] = u + (su / (su - sv)) * (v - u);
        su = sv;
      }
      vertices = out + 2 > kMaxVertices ? 0 : out;  // (rounding made a mess: give up, keep the best)
      std::swap(poly, clipped);
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
    if (exact) lower = std::max(lower, model);
  }
  return q;
}

/// The same search for a field that may not be convex (a grid SDF built from a non-convex mesh), where tangent planes
/// bound nothing: the projected gradient descent of the SDF collision paper over the barycentric simplex, started from
/// the centroid. The gradient in barycentric coordinates is g = (n . x0, n . x1, n . x2), taken within the simplex's
/// plane. The first trial moves one face extent down it, as the cutting-plane search's first step goes to a corner;
/// after an accepted step the next length is the Barzilai-Borwein one, s.s / s.y (s the step, y the change of
/// gradient), which is Newton's step on a quadratic; a step that does not lower phi is halved. It stops when a step
/// moves less than kMinStep in barycentric units (a thousandth of the face), or after maxIterations evaluations, the
/// centroid's included. It finds a local minimum: where a face crosses a concave crease, the deeper side can be missed
/// if the centroid's gradient points away from it; the vertex pass still catches the face's corners.
template <Scalar S, class Field>
FaceQuery<S> descendOnFace(const Field& sdf, const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2,
                           const Vec3<S>& centroid, S phiC, const Vec3<S>& gradC, int maxIterations) {
  FaceQuery<S> q{Vec3<S>::Constant(S(1) / S(3)), centroid, gradC, phiC, 1};
  constexpr S kMinStep = S(constants::kMinDescentStep);
  const Vec3<S> e1 = x1 - x0, e2 = x2 - x0;
  auto slopeAt = [&](const Vec3<S>& n) {
    const Vec3<S> g(n.dot(x0), n.dot(x1), n.dot(x2));
    return Vec3<S>(g - Vec3<S>::Constant(g.mean()));
  };
  Vec3<S> slope = slopeAt(gradC);
  S alpha = slope.norm() > S(0) ? S(1) / slope.norm() : S(0);  // the first trial moves one unit
  while (q.evaluations < maxIterations && alpha > S(0)) {
    const Vec3<S> b = projectToSimplex<S>(q.barycentric - alpha * slope);
    const Vec3<S> step = b - q.barycentric;
    if (step.cwiseAbs().maxCoeff() < kMinStep) break;  // converged, or pinned against an edge or corner
    const Vec3<S> p = x0 + b[1] * e1 + b[2] * e2;
    Vec3<S> n;
    const S phi = sdf(p, n);
    ++q.evaluations;
    if (phi < q.phi) {
      const Vec3<S> next = slopeAt(n);
      const S sy = step.dot(next - slope);
      // Barzilai-Borwein where the curvature along the step is positive; otherwise twice the last length.
      alpha = sy > S(0) ? step.squaredNorm() / sy : S(2) * alpha;
      slope = next;
      q = {b, p, n, phi, q.evaluations};
    } else {
      alpha *= S(0.5);
    }
  }
  return q;
}

/// The field's Lipschitz constant: 1 for a true distance, a grid's stated bound (Field::kLipschitz) otherwise.
template <class Field> constexpr double lipschitzOf() {
  if constexpr (requires { Field::kLipschitz; })
    return double(Field::kLipschitz);
  else
    return 1.0;
}

/// One face against one field: the bounding-sphere cull (when kCull) and, if the face may come within margin,
/// its deepest point: on a ball the nearest point to its centre (which culls by itself), cutting planes on another
/// convex field, a field's own search where it has one (a grid's branch and bound, which spends up to
/// kGridSearchBudget cell reads rather than maxIterations, unless exactSearch is false: Settings::exactGridSearch),
/// the descent otherwise.
/// Returns false when culled. Shared by the solver's face pass and the penetration metric.
///
/// With kClearance, a culled face also states by how much: `clearance` is a distance that every point of the face
/// may move by without coming within `margin` of the solid, less a rounding slack (kClearanceSlack of the
/// scales involved); 0 where the face was not culled. The face pass keeps it between substeps (KeptClearance).
///
/// With `boundsFirst` false the cheap bounds that only cull what the search would cull too (the corners' bound on a
/// ball or a capsule, a field's lower bound) are left out: a face that was in contact at its last test mostly
/// still is, and if not, its search finds it clear. Which faces are in contact is the same either way.
template <bool kCull, bool kClearance = false, Scalar S, class Field>
DRAPE_ALWAYS_INLINE bool queryFace(const Field& sdf, const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2,
                                   S margin, int maxIterations, FaceQuery<S>& q, bool exactSearch = true,
                                   [[maybe_unused]] S* clearance = nullptr, [[maybe_unused]] bool boundsFirst = true) {
  static_assert(kCull || !kClearance, "only a culled face has a clearance");
  if constexpr (kClearance) *clearance = S(0);
  if constexpr (requires { Field::kPointCore; }) {
    // The distance to a point less a radius (a ball) is deepest where the face is nearest that point: found in
    // closed form, exact to rounding, where cutting planes close in on a curved field one cut at a time. The
    // exact minimum culls by itself, so the bounding sphere is not needed.
    const S reach = sdf.radius + margin;
    if (kCull && boundsFirst) {
      // Most faces near a ball are clear of it, and their corners tell so without the nearest point's branches:
      // for p = sum b_k x_k, |p - c|^2 = sum b_k |x_k - c|^2 - sum_{j<k} b_j b_k |x_j - x_k|^2, so no point of
      // the face is nearer than the nearest corner's squared distance less a third of the longest edge's square.
      // Only faces that the nearest point would cull too are culled here (kCornerCullSlack).
      const S corner = std::min({(x0 - sdf.centre).squaredNorm(), (x1 - sdf.centre).squaredNorm(),
                                 (x2 - sdf.centre).squaredNorm()});
      const S edge = std::max({(x1 - x0).squaredNorm(), (x2 - x1).squaredNorm(), (x0 - x2).squaredNorm()});
      const S clear = reach * S(1 + constants::kCornerCullSlack);
      if (S(3) * (corner - clear * clear) > edge) {  // no division: its latency was the test's cost
        if constexpr (kClearance)
          *clearance = rootOf(corner - edge / S(3)) - reach -
                       S(kClearanceSlack) * (reach + largestAbs(sdf.centre));
        return false;
      }
    }
    Vec3<S> b;
    if (nearestOnTriangle<S>(sdf.centre, x0, x1, x2, b)) {
      const Vec3<S> p = detail::pointOnFace(x0, x1, x2, b[1], b[2]);
      // The rest are told by the squared distance, without a root or a division.
      if (kCull && (p - sdf.centre).squaredNorm() > reach * reach) {
        if constexpr (kClearance)
          *clearance = (p - sdf.centre).norm() - reach -
                       S(kClearanceSlack) * (reach + largestAbs(sdf.centre));
        return false;
      }
      Vec3<S> n;
      const S phi = sdf(p, n);
      q = {b, p, n, phi, 1};
      return true;
    }
  }
  if constexpr (requires { Field::kSegmentCore; }) {
    // The distance to a segment less a radius (a capsule) is deepest where the face is nearest the segment: the
    // ball's closed form and corner cull, with the segment for the centre. For any point c of the segment the
    // identity above bounds |p - c|, so the nearest corner's squared distance from the segment less a third of
    // the longest edge's square bounds the face's. A capsule narrower than the face (a rod the cloth folds
    // around) keeps the cutting planes after the cull (docs/design.md §3, "A capsule in closed form").
    const S reach = sdf.radius + margin;
    const Vec3<S> a = movedAlong(sdf.centre, -sdf.halfHeight, sdf.axis);
    const Vec3<S> b = movedAlong(sdf.centre, sdf.halfHeight, sdf.axis);
    const Vec3<S> d = detail::minus3(b, a);
    const S length2 = detail::dot3(d, d);
    const Vec3<S> e01 = detail::minus3(x1, x0), e12 = detail::minus3(x2, x1), e20 = detail::minus3(x0, x2);
    const S edge = std::max({detail::dot3(e01, e01), detail::dot3(e12, e12), detail::dot3(e20, e20)});
    if (kCull && boundsFirst) {
      const S corner = std::min({detail::squaredToSegment(x0, a, d, length2),
                                 detail::squaredToSegment(x1, a, d, length2),
                                 detail::squaredToSegment(x2, a, d, length2)});
      const S clear = reach * S(1 + constants::kCornerCullSlack);
      if (S(3) * (corner - clear * clear) > edge) {
        if constexpr (kClearance)
          *clearance = rootOf(corner - edge / S(3)) - reach -
                       S(kClearanceSlack) * (reach + sdf.halfHeight + largestAbs(sdf.centre));
        return false;
      }
    }
    Vec3<S> w;
    if (S(4) * reach * reach >= edge && nearestToSegment<S>(a, b, x0, x1, x2, w)) {
      const Vec3<S> p = detail::pointOnFace(x0, x1, x2, w[1], w[2]);
      const S core = detail::squaredToSegment(p, a, d, length2);
      if (kCull && core > reach * reach) {
        if constexpr (kClearance)
          *clearance = rootOf(core) - reach -
                       S(kClearanceSlack) * (reach + sdf.halfHeight + largestAbs(sdf.centre));
        return false;
      }
      Vec3<S> n;
      const S phi = sdf(p, n);
      q = {w, p, n, phi, 1};
      return true;
    }
  }
  const FaceSphere<S> sphere = faceSphere<S>(x0, x1, x2);
  if constexpr (kCull && requires { sdf.lowerBound(sphere.centre); }) {
    // A field with a cheap lower bound culls with it first: where the bound clears the sphere, phi does too.
    if (boundsFirst) {
      const S bound = sdf.lowerBound(sphere.centre);
      if (bound > sphere.radius + margin) {
        // The bound (a largest plane distance) is 1-Lipschitz, as the field is.
        if constexpr (kClearance)
          *clearance = bound - sphere.radius - margin -
                       S(kClearanceSlack) *
                           (largestAbs(sphere.centre) + sphere.radius + std::abs(bound) + margin);
        return false;
      }
    }
  }
  Vec3<S> gradC;
  const S phiC = sdf(sphere.centre, gradC);
  // A field steeper than a true distance (a grid's) states how much: the sphere test scales by it.
  constexpr S kLipschitz = S(lipschitzOf<Field>());
  if (kCull && phiC > kLipschitz * sphere.radius + margin) {
    // A move by d changes phi by at most the Lipschitz constant times d.
    if constexpr (kClearance)
      *clearance = (phiC - kLipschitz * sphere.radius - margin) / kLipschitz -
                   S(kClearanceSlack) *
                       (largestAbs(sphere.centre) + sphere.radius + std::abs(phiC) + margin);
    return false;
  }
  // With culling, the search's own bounds cull too.
  const S floor = kCull ? margin : std::numeric_limits<S>::infinity();
  if constexpr (Field::kConvex)
    q = deepestPointOnFace<S>(sdf, x0, x1, x2, sphere.centre, phiC, gradC, maxIterations, floor);
  else if constexpr (requires { sdf.deepestPointOnFace(x0, x1, x2, x0, phiC, gradC, maxIterations, floor); }) {
    if (exactSearch)
      q = sdf.deepestPointOnFace(x0, x1, x2, sphere.centre, phiC, gradC, constants::kGridSearchBudget, floor);
    else
      q = descendOnFace<S>(sdf, x0, x1, x2, sphere.centre, phiC, gradC, maxIterations);
  } else
    q = descendOnFace<S>(sdf, x0, x1, x2, sphere.centre, phiC, gradC, maxIterations);
  return true;
}

}  // namespace drape
