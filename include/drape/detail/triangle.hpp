#pragma once
// The point of a triangle nearest to a point, by the Voronoi regions of its corners, edges and interior (the
// classification of Ericson, "Real-Time Collision Detection", 2005, §5.1.5): shared by the distance-field builder
// (in double, on meshes) and the face search on a ball (in the cloth's scalar type).

#include <drape/detail/parallel.hpp>

#include <cstdint>

namespace drape::detail {

/// Where on a triangle the closest point lies: a vertex, an edge (named by its two corners) or the face.
enum class TriangleFeature : std::uint8_t { VertexA, VertexB, VertexC, EdgeAB, EdgeBC, EdgeCA, Face };

/// The region of triangle abc nearest to p, with its weights: on an edge, `s` is the way from its first corner
/// to its second (EdgeAB: a + s (b - a); EdgeBC: b + s (c - b); EdgeCA: a + s (c - a)); on the face,
/// a + s (b - a) + t (c - a). `flat`: the face's weights came out of rounding with one of them negative or
/// their sum (the squared length of the normal) not positive, as on a triangle with no area.
template <class S> struct TriangleRegion {
  TriangleFeature feature;
  S s = 0, t = 0;
  bool flat = false;
};

/// Inlined: called from the face pass on a ball, its result went back through memory.
template <class S, class Vec>
DRAPE_ALWAYS_INLINE TriangleRegion<S> nearestRegion(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  using F = TriangleFeature;
  const Vec ab = b - a, ac = c - a, ap = p - a;
  const S d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= S(0) && d2 <= S(0)) return {F::VertexA};
  const Vec bp = p - b;
  const S d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= S(0) && d4 <= d3) return {F::VertexB};
  const S vc = d1 * d4 - d3 * d2;
  if (vc <= S(0) && d1 >= S(0) && d3 <= S(0)) return {F::EdgeAB, d1 / (d1 - d3)};
  const Vec cp = p - c;
  const S d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= S(0) && d5 <= d6) return {F::VertexC};
  const S vb = d5 * d2 - d1 * d6;
  if (vb <= S(0) && d2 >= S(0) && d6 <= S(0)) return {F::EdgeCA, d2 / (d2 - d6)};
  const S va = d3 * d6 - d5 * d4;
  if (va <= S(0) && d4 - d3 >= S(0) && d5 - d6 >= S(0)) return {F::EdgeBC, (d4 - d3) / ((d4 - d3) + (d5 - d6))};
  const S sum = va + vb + vc;
  const S inverse = S(1) / sum;
  return {F::Face, vb * inverse, vc * inverse, !(va >= S(0) && vb >= S(0) && vc >= S(0) && sum > S(0))};
}

}  // namespace drape::detail
