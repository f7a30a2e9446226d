#pragma once
// The deepest point of a face in a grid distance field (docs/design.md §3): branch and bound over the face's
// barycentric triangle, with lower bounds taken from the trilinear field's own polynomials. The GLSL twin is the
// DRAPE_SHAPE_GRID branch of shaders/collide_faces.comp.
//
// Why not a descent: a field built from a non-convex mesh has several minima along a face (a concave crease, a
// box's edge seen from inside), and a descent from the centroid stops in whichever basin it starts in. Why these
// bounds: inside one cell the field is a trilinear polynomial, and a trilinear polynomial's expansion about any
// point c is exact and short,
//     P(c + d) = P + g . d + Pxy dx dy + Pxz dx dz + Pyz dy dz + Pxyz dx dy dz,
// so over a sub-triangle its minimum is at least the minimum of the quadratic part (found exactly: vertices,
// edges, interior) less |Pxyz| Dx Dy Dz, with D the sub-triangle's extents about c. The gap shrinks as the cube of
// the sub-triangle's size, so a few levels of subdivision settle a face; a plane's field (trilinear and linear
// alike) is settled at once. A sub-triangle spanning cells is cut along the cells' faces and each part bounded
// with its own cell's polynomial: the field has a kink there, and a bound that ignored it would shrink only as
// fast as the sub-triangle, which along a valley of the field (a box's edge seen from inside) costs thousands of
// sub-triangles. Each cell's bound is also at least the cell's lowest node. A sub-triangle that spans more than
// four slabs along an axis (cells, and the space beyond the grid's box) falls back on the field's Lipschitz
// bound; beyond the box the field has bounds of the same kind (boundOnTriangle).

#include <drape/collision/pgd.hpp>  // FaceQuery
#include <drape/kernel_constants.hpp>
#include <drape/math.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace drape::detail {

/// A cell's trilinear polynomial expanded about a point: P(c + d) = value + slope . d + xy dx dy + xz dx dz +
/// yz dy dz + xyz dx dy dz, exactly, with d in cells; lowestNode bounds it from below inside the cell.
template <Scalar S> struct CellPolynomial {
  S value;
  Vec3<S> slope;
  S xy, xz, yz, xyz;
  S lowestNode;
  S node[8];  ///< the cell's node values, node (i, j, k) at i + 2j + 4k

  /// From the cell's node values v[i + 2j + 4k] and the expansion point t (in cells from node (0, 0, 0)).
  static CellPolynomial expand(const S v[8], const Vec3<S>& t) {
    CellPolynomial p;
    // Along x, per (j, k): value and difference.
    S ax[4], dx[4];
    for (int jk = 0; jk < 4; ++jk) {
      dx[jk] = v[2 * jk + 1] - v[2 * jk];
      ax[jk] = v[2 * jk] + t[0] * dx[jk];
    }
    // Along y, per k (jk = j + 2k).
    S by[2], dyk[2], dxb[2], dxy[2];
    for (int k = 0; k < 2; ++k) {
      dyk[k] = ax[2 * k + 1] - ax[2 * k];
      by[k] = ax[2 * k] + t[1] * dyk[k];
      dxy[k] = dx[2 * k + 1] - dx[2 * k];
      dxb[k] = dx[2 * k] + t[1] * dxy[k];
    }
    p.value = by[0] + t[2] * (by[1] - by[0]);
    p.slope = Vec3<S>(dxb[0] + t[2] * (dxb[1] - dxb[0]), dyk[0] + t[2] * (dyk[1] - dyk[0]), by[1] - by[0]);
    p.xy = dxy[0] + t[2] * (dxy[1] - dxy[0]);
    p.xz = dxb[1] - dxb[0];
    p.yz = dyk[1] - dyk[0];
    p.xyz = dxy[1] - dxy[0];
    p.lowestNode = *std::min_element(v, v + 8);
    std::copy(v, v + 8, p.node);
    return p;
  }
};

/// A half-plane h0 + ha alpha + hb beta >= 0 of a triangle's coordinates (alpha, beta): the side of a cell's
/// face that holds the cell.
template <Scalar S> struct HalfPlane {
  S h0, ha, hb;
};

/// A triangle's part in (alpha, beta) coordinates, split off by half-planes: a convex polygon of up to kMost
/// corners.
template <Scalar S> struct Polygon {
  static constexpr int kMost = 3 + 6;  // a triangle cut twice along each axis
  S a[kMost + 1], b[kMost + 1];
  int corners = 3;

  /// The whole triangle.
  Polygon() { a[0] = S(0), b[0] = S(0), a[1] = S(1), b[1] = S(0), a[2] = S(0), b[2] = S(1); }

  /// Keeps the part where h >= 0 and puts the part where h <= 0 in `rest` (a corner on the line goes to both).
  void split(const HalfPlane<S>& h, Polygon& rest) {
    S ka[kMost + 1], kb[kMost + 1];
    int keep = 0;
    rest.corners = 0;
    for (int i = 0; i < corners; ++i) {
      const int j = i + 1 == corners ? 0 : i + 1;
      const S si = h.h0 + h.ha * a[i] + h.hb * b[i], sj = h.h0 + h.ha * a[j] + h.hb * b[j];
      if (si >= S(0) && keep <= kMost) ka[keep] = a[i], kb[keep++] = b[i];
      if (si <= S(0) && rest.corners <= kMost) rest.a[rest.corners] = a[i], rest.b[rest.corners++] = b[i];
      if ((si > S(0) && sj < S(0)) || (si < S(0) && sj > S(0))) {
        const S t = si / (si - sj);
        const S ta = a[i] + t * (a[j] - a[i]), tb = b[i] + t * (b[j] - b[i]);
        if (keep <= kMost) ka[keep] = ta, kb[keep++] = tb;
        if (rest.corners <= kMost) rest.a[rest.corners] = ta, rest.b[rest.corners++] = tb;
      }
    }
    corners = keep;
    std::copy(ka, ka + keep, a);
    std::copy(kb, kb + keep, b);
  }
};

/// The minimum of the quadratic part of p (everything but the xyz term) over the triangle c + d[0], c + d[1],
/// c + d[2], or over its part `part` cut out by `cuts` (the part in one cell), exactly: the lowest of the
/// corners, the edges' stationary points and the interior's. Returns it with its place as d[0] + alpha
/// (d[1] - d[0]) + beta (d[2] - d[0]); infinity when the part is empty.
template <Scalar S>
S lowestOfQuadratic(const CellPolynomial<S>& p, const Vec3<S> d[3], S& alpha, S& beta,
                    const Polygon<S>& part = Polygon<S>(), const HalfPlane<S>* cuts = nullptr, int cutCount = 0) {
  auto hessianTimes = [&](const Vec3<S>& v) {
    return Vec3<S>(p.xy * v.y() + p.xz * v.z(), p.xy * v.x() + p.yz * v.z(), p.xz * v.x() + p.yz * v.y());
  };
  const Vec3<S> e1 = d[1] - d[0], e2 = d[2] - d[0];
  const Vec3<S> h0 = hessianTimes(d[0]), h1 = hessianTimes(e1), h2 = hessianTimes(e2);
  const S f0 = p.value + p.slope.dot(d[0]) + S(0.5) * d[0].dot(h0);
  const Vec3<S> g0 = p.slope + h0;  // the quadratic's gradient at d[0]
  const S gp = g0.dot(e1), gq = g0.dot(e2);
  const S a = e1.dot(h1), b = e1.dot(h2), c = e2.dot(h2);
  // F(alpha, beta) = f0 + gp alpha + gq beta + (a alpha^2 + 2 b alpha beta + c beta^2) / 2
  auto value = [&](S al, S be) { return f0 + gp * al + gq * be + S(0.5) * (a * al * al + S(2) * b * al * be + c * be * be); };
  const int corners = part.corners;
  const S* pa = part.a;
  const S* pb = part.b;
  alpha = beta = S(0);
  if (corners == 0) return std::numeric_limits<S>::infinity();
  S best = std::numeric_limits<S>::infinity();
  auto consider = [&](S v, S al, S be) {
    if (v < best) best = v, alpha = al, beta = be;
  };
  for (int i = 0; i < corners; ++i) {
    consider(value(pa[i], pb[i]), pa[i], pb[i]);
    // Along the edge to the next corner: F(t) = F_i + slope t + curve t^2 / 2.
    const int j = i + 1 == corners ? 0 : i + 1;
    const S da = pa[j] - pa[i], db = pb[j] - pb[i];
    const S slope = (gp + a * pa[i] + b * pb[i]) * da + (gq + b * pa[i] + c * pb[i]) * db;
    const S curve = a * da * da + S(2) * b * da * db + c * db * db;
    if (curve > S(0) && -slope > S(0) && -slope < curve) {
      const S t = -slope / curve;
      consider(value(pa[i] + t * da, pb[i] + t * db), pa[i] + t * da, pb[i] + t * db);
    }
  }
  const S det = a * c - b * b;
  if (a > S(0) && det > S(0)) {  // a convex quadratic: its stationary point, if inside
    const S al = (b * gq - c * gp) / det, be = (b * gp - a * gq) / det;
    bool inside = al > S(0) && be > S(0) && al + be < S(1);
    for (int k = 0; k < cutCount && inside; ++k) inside = cuts[k].h0 + cuts[k].ha * al + cuts[k].hb * be >= S(0);
    if (inside) consider(f0 + S(0.5) * (gp * al + gq * be), al, be);
  }
  return best;
}

/// A lower bound of the sampled field over the triangle with corners u[0..2] (in cells), with a point of it to
/// try next as weights of the corners (`at`) and, when it is free, the field at the centroid (`centroid`,
/// infinity when not known). Adds the cells it expanded (each a read of eight nodes) to `evaluations`. A cell
/// whose nodes are all at or above `cutoff` is passed over: the bound is then exact only below the cutoff, which
/// is all the search asks of it.
///
/// Beyond the grid's box, where the triangle lies wholly below or above the box along an axis (clamped there),
/// the field is |(e, G)|: e the distance to the box, G the trilinear field at the box's nearest point, which does
/// not depend on the clamped coordinates. For any unit (alpha, beta) >= 0, |(e, G)| >= alpha e + beta G; taken
/// along (e, G) at the centroid it is tight to second order. e is convex, so its tangent plane at the centroid
/// bounds it, and the sum is again a quadratic whose minimum over the triangle is found exactly.
template <Scalar S, class Sampler>
S boundOnTriangle(const Sampler& g, const Vec3<S> u[3], Vec3<S>& at, S& centroid, int& evaluations,
                  S cutoff = std::numeric_limits<S>::infinity()) {
  const Vec3<S> c = (u[0] + u[1] + u[2]) / S(3);
  const Vec3<S> d[3] = {u[0] - c, u[1] - c, u[2] - c};
  const Vec3<S> lo = u[0].cwiseMin(u[1]).cwiseMin(u[2]), hi = u[0].cwiseMax(u[1]).cwiseMax(u[2]);
  // Along each axis the triangle meets a run of slabs: cells, and the space below (side -1) or above (+1) the box,
  // whose field comes from the box's first or last cell. Slab i and i + 1 meet at split[i].
  struct Slab {
    Index cell;
    int side;
  };
  constexpr int kSlabs = 4;  // more cells than this along an axis: split the triangle first
  Slab slabs[3][kSlabs];
  S split[3][kSlabs];
  int slabCount[3] = {0, 0, 0};
  bool local = true, outside = false;
  for (int a = 0; a < 3 && local; ++a) {
    const Index topCell = g.count[a] - 2;
    const S top = S(g.count[a] - 1);
    int& n = slabCount[a];
    if (lo[a] < S(0)) slabs[a][n] = {0, -1}, split[a][n++] = S(0);
    if (hi[a] >= S(0) && lo[a] <= top) {
      const Index first = std::min(Index(std::max(lo[a], S(0))), topCell);
      const Index last = std::min(Index(std::min(hi[a], top)), topCell);
      local = last - first + 1 + n <= kSlabs;
      for (Index k = first; k <= last && local; ++k) slabs[a][n] = {k, 0}, split[a][n++] = S(k + 1);
    }
    if (hi[a] > top && local) {
      local = n < kSlabs;
      if (local) slabs[a][n++] = {topCell, 1};
    }
    if (local) outside = outside || slabs[a][0].side != 0 || slabs[a][n - 1].side != 0;
  }
  at = Vec3<S>::Constant(S(1) / S(3));
  centroid = std::numeric_limits<S>::infinity();
  auto lipschitz = [&] {
    if (centroid == std::numeric_limits<S>::infinity()) {  // not yet known
      centroid = g.distanceAt(c);
      ++evaluations;
    }
    at = Vec3<S>::Constant(S(1) / S(3));
    const S reach = std::sqrt(std::max({d[0].squaredNorm(), d[1].squaredNorm(), d[2].squaredNorm()})) * g.cellSize;
    return centroid - S(constants::kGridLipschitz) * reach;
  };
  if (!local) return lipschitz();
  if (outside) {  // the centroid's value is not one of the expansions' below
    centroid = g.distanceAt(c);
    ++evaluations;
  }
  std::array<Index, 3> home;  // inside the box, the cell whose polynomial is the field at c
  for (int a = 0; a < 3; ++a) home[a] = std::min(Index(std::max(c[a], S(0))), g.count[a] - 2);
  const Vec3<S> extent = d[0].cwiseAbs().cwiseMax(d[1].cwiseAbs()).cwiseMax(d[2].cwiseAbs());
  const S cube = extent.x() * extent.y() * extent.z();
  const Vec3<S> e1 = u[1] - u[0], e2 = u[2] - u[0];
  S lowest = std::numeric_limits<S>::infinity();
  // The triangle is split into slabs along x, each of those along y, then z: every split is shared by the
  // pieces beyond it, and an empty slab ends its branch.
  auto below = [&](int a, S level) { return HalfPlane<S>{level - u[0][a], -e1[a], -e2[a]}; };  // u_a <= level
  Polygon<S> restX;
  for (int i0 = 0; i0 < slabCount[0]; ++i0) {
    Polygon<S> inX = restX;
    if (i0 + 1 < slabCount[0]) inX.split(below(0, split[0][i0]), restX);
    if (inX.corners == 0) continue;
    Polygon<S> restY = inX;
    for (int i1 = 0; i1 < slabCount[1]; ++i1) {
      Polygon<S> inY = restY;
      if (i1 + 1 < slabCount[1]) inY.split(below(1, split[1][i1]), restY);
      if (inY.corners == 0) continue;
      Polygon<S> restZ = inY;
      for (int i2 = 0; i2 < slabCount[2]; ++i2) {
        Polygon<S> part = restZ;
        if (i2 + 1 < slabCount[2]) part.split(below(2, split[2][i2]), restZ);
        if (part.corners == 0) continue;  // the triangle misses this piece
        const Slab piece[3] = {slabs[0][i0], slabs[1][i1], slabs[2][i2]};
        const int index[3] = {i0, i1, i2};
        const std::array<Index, 3> cell{piece[0].cell, piece[1].cell, piece[2].cell};
        Vec3<S> t, w = Vec3<S>::Zero();  // w: past the box along the piece's clamped axes (cells), about c
        bool clamped = false;
        for (int a = 0; a < 3; ++a) {
          const int side = piece[a].side;
          t[a] = side == 0 ? c[a] - S(cell[a]) : (side < 0 ? S(0) : S(1));
          if (side != 0) w[a] = side < 0 ? c[a] : c[a] - S(g.count[a] - 1), clamped = true;
        }
        CellPolynomial<S> p = g.expand(cell, t);
        ++evaluations;
        if (!clamped && p.lowestNode >= cutoff) continue;  // nothing in this cell is low enough to matter
        // The piece's sides, for the test of an interior minimum.
        HalfPlane<S> cuts[6];
        int cutCount = 0;
        for (int a = 0; a < 3; ++a) {
          if (index[a] > 0) cuts[cutCount++] = {u[0][a] - split[a][index[a] - 1], e1[a], e2[a]};
          if (index[a] + 1 < slabCount[a]) cuts[cutCount++] = below(a, split[a][index[a]]);
        }
        if (clamped) {
          // |(e, G)| is the field where G >= 0 on the box's face: at the face's nodes, which bound it.
          for (int k = 0; k < 8; ++k) {
            bool onFace = true;
            for (int a = 0; a < 3; ++a)
              if (piece[a].side != 0) onFace = onFace && (((k >> a) & 1) == (piece[a].side > 0 ? 1 : 0));
            if (onFace && !(p.node[k] >= S(0))) return lipschitz();  // the box cuts the solid
          }
          // alpha e + beta G, along (e, G) at c, with e's tangent plane (0 where e has no gradient at c); G drops
          // the clamped coordinates.
          const S reach = w.norm(), away = reach * g.cellSize;
          const S norm = std::sqrt(away * away + p.value * p.value);
          const S alpha = away / norm, beta = p.value / norm;
          p.value = norm;
          for (int a = 0; a < 3; ++a)
            p.slope[a] = piece[a].side != 0 ? (reach > S(0) ? alpha * g.cellSize * w[a] / reach : S(0))
                                            : beta * p.slope[a];
          p.xy = piece[0].side != 0 || piece[1].side != 0 ? S(0) : beta * p.xy;
          p.xz = piece[0].side != 0 || piece[2].side != 0 ? S(0) : beta * p.xz;
          p.yz = piece[1].side != 0 || piece[2].side != 0 ? S(0) : beta * p.yz;
          p.xyz = S(0);
          p.lowestNode = -std::numeric_limits<S>::infinity();
        } else if (!outside && cell == home) {
          centroid = p.value;
        }
        S alpha, beta;
        const S quadratic = lowestOfQuadratic(p, d, alpha, beta, part, cuts, cutCount);
        const S bound = std::max(quadratic - std::abs(p.xyz) * cube, p.lowestNode);
        if (bound < lowest) lowest = bound, at = Vec3<S>(S(1) - alpha - beta, alpha, beta);
      }
    }
  }
  return lowest;
}

/// Branch and bound for the lowest field value over a face whose corners in cells are u[0..2] (docs/design.md
/// §3). Sub-triangles come from splitting in four at the edge midpoints, depth first, lowest bound first; one is
/// dropped once its bound is within `tolerance` of the best value found or clears `floor` by it. Each bounded
/// sub-triangle also tries its centroid and the point where its bound is lowest. Starts from the centroid's value
/// `phiC`; returns the best barycentric point and its value in `value`, and spends at most about `budget` cell
/// reads (the count goes to `evaluations`, which starts at the caller's count).
template <Scalar S, class Sampler>
Vec3<S> branchAndBoundOnFace(const Sampler& g, const Vec3<S> u[3], S phiC, S tolerance, S floor, int budget,
                             S& value, int& evaluations) {
  // A sub-triangle: corners (o1, o2), (o1 + s, o2), (o1, o2 + s) in the face's coordinates (b1, b2); s < 0 for
  // the middle ones, which are turned over.
  struct Node {
    S o1, o2, s, lower;
  };
  constexpr int kDepth = constants::kGridSearchDepth;
  constexpr int kStack = 3 * kDepth + 4;  // each level leaves at most three siblings waiting
  Node stack[kStack];
  int top = 0;
  Vec3<S> best = Vec3<S>::Constant(S(1) / S(3));
  value = phiC;
  const Vec3<S> e1 = u[1] - u[0], e2 = u[2] - u[0];
  const S stop = floor + tolerance;
  auto threshold = [&] { return std::min(value - tolerance, stop); };
  // Bounds one sub-triangle, tries its points, and returns its node.
  auto visit = [&](S o1, S o2, S s) {
    const Vec3<S> corner[3] = {u[0] + o1 * e1 + o2 * e2, u[0] + (o1 + s) * e1 + o2 * e2,
                               u[0] + o1 * e1 + (o2 + s) * e2};
    Vec3<S> at;
    S centroid;
    const S lower = boundOnTriangle(g, corner, at, centroid, evaluations, threshold());
    if (centroid < value) value = centroid, best = Vec3<S>(S(1) - o1 - o2 - S(2) * s / S(3), o1 + s / S(3), o2 + s / S(3));
    if (lower < threshold()) {  // worth a look at the bound's lowest point
      const S b1 = o1 + s * at[1], b2 = o2 + s * at[2];
      const S phi = g.distanceAt(u[0] + b1 * e1 + b2 * e2);
      ++evaluations;
      if (phi < value) value = phi, best = Vec3<S>(S(1) - b1 - b2, b1, b2);
    }
    return Node{o1, o2, s, lower};
  };
  const Node root = visit(S(0), S(0), S(1));
  if (root.lower < threshold()) stack[top++] = root;
  const S smallest = std::ldexp(S(1), -kDepth);
  while (top > 0 && evaluations < budget) {
    const Node n = stack[--top];
    if (n.lower >= threshold() || std::abs(n.s) <= smallest) continue;
    const S h = n.s / S(2);
    Node child[4] = {visit(n.o1, n.o2, h), visit(n.o1 + h, n.o2, h), visit(n.o1, n.o2 + h, h),
                     visit(n.o1 + h, n.o2 + h, -h)};
    // Highest bound pushed first, so the lowest is taken next.
    std::sort(child, child + 4, [](const Node& a, const Node& b) { return a.lower > b.lower; });
    const S keep = threshold();
    for (const Node& k : child)
      if (k.lower < keep && top < kStack) stack[top++] = k;
  }
  return best;
}

}  // namespace drape::detail
