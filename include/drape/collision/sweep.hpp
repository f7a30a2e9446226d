#pragma once
// Continuous contact (docs/design.md §18): the paths a vertex and a face take in a substep, relative to a solid,
// searched by conservative advancement for the first place they come within the thickness, so that a substep's
// travel cannot carry the cloth through a solid thinner than it. The discrete passes see only where the cloth
// ends; these see the whole path.

#include <drape/collision/pgd.hpp>
#include <drape/detail/parallel.hpp>
#include <drape/kernel_constants.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace drape {

/// How far a path first came within the thickness: the point, the field's value and outward gradient there.
template <Scalar S> struct SweepHit {
  Vec3<S> point;
  Vec3<S> normal;
  S phi;
  bool hit;
  int evaluations;
};

/// The first point of the segment a -> b where it comes within `thickness` of the solid, by conservative
/// advancement: from a point at distance phi, no point of the segment within (phi - thickness / 2) / L of it (L
/// the field's Lipschitz constant) is closer than half the thickness, so the search jumps that far. It never
/// steps over the solid, and stops within the thickness on the side the path came from. A path that starts
/// inside the solid came from no side and is left to the discrete pass. No hit within kSweepSteps evaluations
/// counts as none.
template <Scalar S, class Field>
SweepHit<S> sweepPoint(const Field& sdf, const Vec3<S>& a, const Vec3<S>& b, S thickness) {
  const Vec3<S> d = b - a;
  const S stride = S(lipschitzOf<Field>()) * d.norm();  // how much phi can change per unit of t
  SweepHit<S> out{a, Vec3<S>::Zero(), S(0), false, 0};
  S t = 0;
  while (out.evaluations < constants::kSweepSteps) {
    const Vec3<S> q = a + t * d;
    Vec3<S> n;
    const S phi = sdf(q, n);
    ++out.evaluations;
    if (phi < thickness) return {q, n, phi, t > S(0) || phi >= S(0), out.evaluations};
    t += (phi - S(0.5) * thickness) / stride;
    if (!(t < S(1))) break;  // past the end (or a NaN): the discrete pass judges the end point
  }
  return out;
}

/// The face moving from corners a[0..2] to b[0..2] (each corner along its own segment, every point of the face
/// along the segment of its barycentric mix): the first time `when` it comes within `thickness` of the solid,
/// and its deepest point then (q, on the face a + when (b - a)). Conservative advancement as in sweepPoint, with
/// a lower bound on the face in place of a point's distance: its bounding sphere's, phi(centre) - L radius,
/// where that clears the thickness, else the face search's (queryFace, which certifies the face beyond the
/// thickness or finds the point within it). No point of the face moves further than its farthest corner.
/// Returns false for a face that starts inside the solid, or no hit within kFaceSweepSteps positions, or none
/// before the end (the discrete face pass judges the end).
template <Scalar S, class Field>
DRAPE_NOINLINE bool sweepFace(const Field& sdf, const Vec3<S> (&a)[3], const Vec3<S> (&b)[3], S thickness,
                              int maxIterations, bool exactSearch, FaceQuery<S>& q, int& evaluations, S& when) {
  const S lipschitz = S(lipschitzOf<Field>());
  const Vec3<S> d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const S travel = std::sqrt(std::max({d[0].squaredNorm(), d[1].squaredNorm(), d[2].squaredNorm()}));
  const S stride = lipschitz * travel;
  const S half = S(0.5) * thickness;
  S t = 0;
  for (int step = 0; step < constants::kFaceSweepSteps; ++step) {
    const Vec3<S> y0 = a[0] + t * d[0], y1 = a[1] + t * d[1], y2 = a[2] + t * d[2];
    const FaceSphere<S> sphere = faceSphere<S>(y0, y1, y2);
    Vec3<S> gradient;
    const S lower = sdf(sphere.centre, gradient) - lipschitz * sphere.radius;
    ++evaluations;
    if (lower >= thickness) {
      t += (lower - half) / stride;
    } else {
      FaceQuery<S> found;
      const bool near = queryFace<true>(sdf, y0, y1, y2, thickness, maxIterations, found, exactSearch);
      evaluations += near ? found.evaluations : 1;
      if (near && found.phi < thickness) {
        q = found;
        when = t;
        return t > S(0) || found.phi >= S(0);
      }
      t += half / stride;  // certified beyond the thickness
    }
    if (!(t < S(1))) break;
  }
  return false;
}

/// The faces the friction guard judges (docs/design.md §18): those with a corner position friction moved further
/// than `reach`, in index order, each with the box of its path. Gathered once a substep, then met by each solid's
/// box, so that a scene of many bodies pays for the faces friction moved far, not for every face once per body.
template <Scalar S> struct FrictionPaths {
  std::vector<Index> faces;
  std::vector<Vec3<S>> low, high;  ///< each path's box: the face where friction found it and where it left it

  /// Room for every face, so that gathering never allocates.
  void reserve(std::size_t faceCount) {
    faces.reserve(faceCount);
    low.reserve(faceCount);
    high.reserve(faceCount);
  }
  void gather(const std::vector<std::array<Index, 3>>& triangles, const Vec3<S>* before, const Vec3<S>* x,
              S reach) {
    faces.clear();
    low.clear();
    high.clear();
    for (std::size_t f = 0; f < triangles.size(); ++f) {
      const auto& t = triangles[f];
      const Vec3<S> a[3] = {before[t[0]], before[t[1]], before[t[2]]};
      const Vec3<S> b[3] = {x[t[0]], x[t[1]], x[t[2]]};
      if (!(std::max({(b[0] - a[0]).squaredNorm(), (b[1] - a[1]).squaredNorm(), (b[2] - a[2]).squaredNorm()}) >
            reach * reach))
        continue;
      faces.push_back(Index(f));
      low.push_back(a[0].cwiseMin(a[1]).cwiseMin(a[2]).cwiseMin(b[0]).cwiseMin(b[1]).cwiseMin(b[2]));
      high.push_back(a[0].cwiseMax(a[1]).cwiseMax(a[2]).cwiseMax(b[0]).cwiseMax(b[1]).cwiseMax(b[2]));
    }
  }
};

/// The friction guard (docs/design.md §18). Position friction moved contact vertices from `before` to `x`, each
/// along its own contact plane; on a solid thinner than a face that can carry a face across it. Every face of
/// `paths` (a corner moved further than `reach`) whose path from `before` to `x` came within `reach` of the solid
/// after its start (sweepFace), and which the solid then pierces where friction left it, marks its three corners. A
/// face whose corners all moved less cannot have crossed a solid it started at least `reach` from. Marks only, on
/// positions nothing changes meanwhile: the result does not depend on the order of the faces. `boxLow`, `boxHigh`:
/// the solid's box; a path whose box misses it grown by `reach` is passed over. Returns how many faces marked.
template <Scalar S, class Field>
Index markFrictionCrossings(const Field& sdf, const Vec3<S>& boxLow, const Vec3<S>& boxHigh,
                            const std::vector<std::array<Index, 3>>& triangles, const FrictionPaths<S>& paths,
                            const Vec3<S>* before, const Vec3<S>* x, S reach, int maxIterations, bool exactSearch,
                            std::uint8_t* marks) {
  const Vec3<S> low = boxLow.array() - reach, high = boxHigh.array() + reach;
  Index marked = 0;
  for (std::size_t k = 0; k < paths.faces.size(); ++k) {
    if (!((paths.high[k].array() >= low.array()).all() && (paths.low[k].array() <= high.array()).all())) continue;
    const auto& t = triangles[std::size_t(paths.faces[k])];
    const Vec3<S> a[3] = {before[t[0]], before[t[1]], before[t[2]]};
    const Vec3<S> b[3] = {x[t[0]], x[t[1]], x[t[2]]};
    FaceQuery<S> hit;
    int evaluations = 0;
    S when = 0;
    // A face already within reach where friction found it is the contact passes' to judge: only a path that
    // comes close on the way is friction's doing. And only a face the solid ends up piercing goes back: one
    // friction merely carried near the solid is the next substep's contact to answer, and putting its corners
    // back while their neighbours stay strains the cloth (a cloth thrown at a ball, docs/design.md §18).
    if (!(sweepFace(sdf, a, b, reach, maxIterations, exactSearch, hit, evaluations, when) && when > S(0))) continue;
    FaceQuery<S> end;
    if (queryFace<true>(sdf, b[0], b[1], b[2], reach, maxIterations, end, exactSearch) && end.phi < S(0)) {
      marks[t[0]] = marks[t[1]] = marks[t[2]] = 1;
      ++marked;
    }
  }
  return marked;
}
/// The same over every face (the paths gathered here).
template <Scalar S, class Field>
Index markFrictionCrossings(const Field& sdf, const Vec3<S>& boxLow, const Vec3<S>& boxHigh,
                            const std::vector<std::array<Index, 3>>& triangles, const Vec3<S>* before,
                            const Vec3<S>* x, S reach, int maxIterations, bool exactSearch, std::uint8_t* marks) {
  FrictionPaths<S> paths;
  paths.gather(triangles, before, x, reach);
  return markFrictionCrossings(sdf, boxLow, boxHigh, triangles, paths, before, x, reach, maxIterations, exactSearch,
                               marks);
}

}  // namespace drape
