// docs/design.md §3 and §4, the face pass (the CPU twins: queryFace and deepestPointOnFace in
// include/drape/collision/pgd.hpp, branchAndBoundOnFace in include/drape/sdf/grid_search.hpp,
// projectFaceContactsAs in include/drape/collision/response.hpp), for one colour of faces: faces of a colour
// share no vertex, so each invocation moves its own three vertices. Per face: the bounding-sphere cull (phi at the
// centroid beyond the radius, times a grid field's Lipschitz constant, plus the thickness), then the search for
// the deepest point: on a convex solid Kelley's cutting planes (each tangent plane bounds the field from below
// along the face, so the search stops once the best value is certified), on a grid field branch and bound with
// bounds from the cells' trilinear polynomials. Where that point is closer than the thickness, the face's
// vertices move along the normal, weighted by barycentric weight (spread toward an even lift on fields with edges)
// and inverse mass, to carry it to the thickness.
// The moves are recorded in the vertices' contacts (recordContact, as the CPU records them). With continuous contact
// (docs/design.md §18), a face that travelled far is first searched along its path (sweepFace); that code is
// compiled only into the kernels of a scene with continuous contact (DRAPE_SWEEP), as a uniform branch around it
// still costs where the driver runs both sides of a branch.
//
// The CPU visits every face in index order; here the colours go in turn and the faces of one colour at once,
// which is another order of the same Gauss-Seidel pass: a colour's faces on their own give the CPU's bits.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_CONTACTS) buffer Contacts { Contact contacts[]; };
layout(std430, binding = DRAPE_B_FACES) readonly buffer Faces { uvec4 faces[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_FIRST) uniform uint first;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_SOLID_CENTRE) uniform vec3 centre;
layout(location = DRAPE_U_SOLID_LINEAR) uniform vec3 linearVelocity;
layout(location = DRAPE_U_SOLID_ANGULAR) uniform vec3 angularVelocity;
layout(location = DRAPE_U_PGD_ITERATIONS) uniform int maxIterations;
layout(location = DRAPE_U_FRICTION) uniform vec2 friction;  // static, dynamic
layout(location = DRAPE_U_BOX_LOW) uniform vec3 boxLow;
layout(location = DRAPE_U_BOX_HIGH) uniform vec3 boxHigh;
#if DRAPE_SWEEP
layout(std430, binding = DRAPE_B_START) readonly buffer Start { vec4 starts[]; };
layout(location = DRAPE_U_SWEEP) uniform vec2 sweep;  // the substep h and the gate squared; 0 (unset): no sweeps
#endif
#if DRAPE_BODY
layout(std430, binding = DRAPE_B_LINES) buffer LinesBuffer { Lines lines[]; };
layout(location = DRAPE_U_BODY) uniform int body;  // the coupled body this solid pushes
#else
const int body = -1;
#endif
#if !DRAPE_GUARD && DRAPE_HOLDS_DEEPEST_POINTS
layout(std430, binding = DRAPE_B_HELD) buffer Held { vec4 held[]; };
layout(location = DRAPE_U_HELD_PLACE) uniform uint heldPlace;  // the solid's place + 1; 0: nothing held
#endif

const int kMaxCuts = DRAPE_MAX_CUTS;
const int kMaxVertices = 2 * kMaxCuts + 6;
const float kGap = DRAPE_FACE_SEARCH_GAP;

vec3 cuts[kMaxCuts];
vec3 poly[kMaxVertices];
vec3 clipped[kMaxVertices];

// A cut: the tangent plane phi + n . (x - p) at barycentric b, as its values at the three corners.
vec3 cutAt(vec3 b, float phi, vec3 n, vec3 e1, vec3 e2) {
  precise const vec3 q = b.y * e1 + b.z * e2;
  precise const float nd = dot3(n, q);
  precise const vec3 c = vec3(phi - nd, phi + dot3(n, e1) - nd, phi + dot3(n, e2) - nd);
  return c;
}

#if !DRAPE_CONVEX
// The face search on a grid field (the CPU twins in include/drape/sdf/grid_search.hpp): branch and bound over
// the face's triangle, bounded by each cell's trilinear polynomial over the triangle's part in the cell.
const int kGridDepth = DRAPE_GRID_SEARCH_DEPTH;
const int kGridStack = 3 * kGridDepth + 4;
const int kPolyMost = 9;  // Polygon::kMost
vec3 partCuts[6];         // half-planes h0 + ha alpha + hb beta >= 0, as (h0, ha, hb)
vec4 gridStack[kGridStack];  // sub-triangles (o1, o2, s, lower)

float infinity() { return uintBitsToFloat(0x7F800000u); }

// A triangle's part in (alpha, beta) coordinates (Polygon).
struct Polygon {
  float a[kPolyMost + 1], b[kPolyMost + 1];
  int corners;
};

Polygon wholeTriangle() {
  Polygon p;
  p.a[0] = 0.0, p.b[0] = 0.0, p.a[1] = 1.0, p.b[1] = 0.0, p.a[2] = 0.0, p.b[2] = 1.0;
  p.corners = 3;
  return p;
}

// Polygon::split: keeps in `keep` the part where h >= 0, and returns the part where h <= 0.
Polygon splitPolygon(inout Polygon keep, vec3 h) {
  Polygon rest;
  rest.corners = 0;
  float ka[kPolyMost + 1], kb[kPolyMost + 1];
  int kept = 0;
  for (int i = 0; i < keep.corners; ++i) {
    const int j = i + 1 == keep.corners ? 0 : i + 1;
    precise const float si = (h.x + h.y * keep.a[i]) + h.z * keep.b[i];
    precise const float sj = (h.x + h.y * keep.a[j]) + h.z * keep.b[j];
    if (si >= 0.0 && kept <= kPolyMost) ka[kept] = keep.a[i], kb[kept] = keep.b[i], ++kept;
    if (si <= 0.0 && rest.corners <= kPolyMost)
      rest.a[rest.corners] = keep.a[i], rest.b[rest.corners] = keep.b[i], ++rest.corners;
    if ((si > 0.0 && sj < 0.0) || (si < 0.0 && sj > 0.0)) {
      precise const float t = si / (si - sj);
      precise const float ta = keep.a[i] + t * (keep.a[j] - keep.a[i]);
      precise const float tb = keep.b[i] + t * (keep.b[j] - keep.b[i]);
      if (kept <= kPolyMost) ka[kept] = ta, kb[kept] = tb, ++kept;
      if (rest.corners <= kPolyMost) rest.a[rest.corners] = ta, rest.b[rest.corners] = tb, ++rest.corners;
    }
  }
  keep.corners = kept;
  for (int i = 0; i < kept; ++i) keep.a[i] = ka[i], keep.b[i] = kb[i];
  return rest;
}

vec3 hessianTimes(CellPolynomial p, vec3 v) {
  precise const vec3 r = vec3(p.xy * v.y + p.xz * v.z, p.xy * v.x + p.yz * v.z, p.xz * v.x + p.yz * v.y);
  return r;
}

// lowestOfQuadratic over the polygon `part` (bounded by partCuts[0, cutCount) within the triangle).
float lowestOfQuadratic(CellPolynomial p, vec3 d0, vec3 d1, vec3 d2, Polygon part, int cutCount, out float alpha,
                        out float beta) {
  precise const vec3 e1 = d1 - d0, e2 = d2 - d0;
  const vec3 h0 = hessianTimes(p, d0), h1 = hessianTimes(p, e1), h2 = hessianTimes(p, e2);
  precise const float f0 = (p.value + dot3(p.slope, d0)) + 0.5 * dot3(d0, h0);
  precise const vec3 g0 = p.slope + h0;
  const float gp = dot3(g0, e1), gq = dot3(g0, e2);
  const float a = dot3(e1, h1), b = dot3(e1, h2), c = dot3(e2, h2);
  float best = infinity();
  alpha = 0.0, beta = 0.0;
  for (int i = 0; i < part.corners; ++i) {
    const float al = part.a[i], be = part.b[i];
    precise const float v = ((f0 + gp * al) + gq * be) + 0.5 * ((a * al * al + 2.0 * b * al * be) + c * be * be);
    if (v < best) best = v, alpha = al, beta = be;
    const int j = i + 1 == part.corners ? 0 : i + 1;
    precise const float da = part.a[j] - al, db = part.b[j] - be;
    precise const float slope = (gp + a * al + b * be) * da + (gq + b * al + c * be) * db;
    precise const float curve = (a * da * da + 2.0 * b * da * db) + c * db * db;
    if (curve > 0.0 && -slope > 0.0 && -slope < curve) {
      precise const float t = -slope / curve;
      precise const float ta = al + t * da, tb = be + t * db;
      precise const float tv = ((f0 + gp * ta) + gq * tb) + 0.5 * ((a * ta * ta + 2.0 * b * ta * tb) + c * tb * tb);
      if (tv < best) best = tv, alpha = ta, beta = tb;
    }
  }
  precise const float det = a * c - b * b;
  if (a > 0.0 && det > 0.0) {
    precise const float al = (b * gq - c * gp) / det, be = (b * gp - a * gq) / det;
    bool inside = al > 0.0 && be > 0.0 && al + be < 1.0;
    for (int k = 0; k < cutCount && inside; ++k) {
      precise const float side = (partCuts[k].x + partCuts[k].y * al) + partCuts[k].z * be;
      inside = side >= 0.0;
    }
    precise const float v = f0 + 0.5 * (gp * al + gq * be);
    if (inside && v < best) best = v, alpha = al, beta = be;
  }
  return best;
}

// boundOnTriangle: a lower bound of the field over the triangle u0, u1, u2 (in cells), the place to try next as
// corner weights, and the centroid's value when it comes free (infinity otherwise).
float boundOnTriangle(vec3 u0, vec3 u1, vec3 u2, out vec3 at, out float middleValue, inout int evaluations,
                      float cutoff) {
  const ivec3 count = gridCount();
  const float cellSize = gridCellSize();
  precise const vec3 c = ((u0 + u1) + u2) / 3.0;
  precise const vec3 d0 = u0 - c, d1 = u1 - c, d2 = u2 - c;
  const vec3 lo = min(min(u0, u1), u2), hi = max(max(u0, u1), u2);
  const int kSlabs = 4;
  ivec2 slabs[3][kSlabs];  // (cell, side)
  float splits[3][kSlabs];
  int slabCount[3] = int[3](0, 0, 0);
  bool local = true, outside = false;
  for (int a = 0; a < 3 && local; ++a) {
    const int topCell = count[a] - 2;
    const float top = float(count[a] - 1);
    int n = 0;
    if (lo[a] < 0.0) slabs[a][n] = ivec2(0, -1), splits[a][n] = 0.0, ++n;
    if (hi[a] >= 0.0 && lo[a] <= top) {
      const int first = min(int(max(lo[a], 0.0)), topCell), last = min(int(min(hi[a], top)), topCell);
      local = last - first + 1 + n <= kSlabs;
      for (int k = first; k <= last && local; ++k) slabs[a][n] = ivec2(k, 0), splits[a][n] = float(k + 1), ++n;
    }
    if (hi[a] > top && local) {
      local = n < kSlabs;
      if (local) slabs[a][n] = ivec2(topCell, 1), ++n;
    }
    slabCount[a] = n;
    if (local) outside = outside || slabs[a][0].y != 0 || slabs[a][n - 1].y != 0;
  }
  at = vec3(1.0 / 3.0);
  middleValue = infinity();
  if (!local) {
    middleValue = gridDistanceAt(c);
    ++evaluations;
    const float reach = sqrt(max(max(dot3(d0, d0), dot3(d1, d1)), dot3(d2, d2))) * cellSize;
    precise const float bound = middleValue - DRAPE_GRID_LIPSCHITZ * reach;
    return bound;
  }
  if (outside) {
    middleValue = gridDistanceAt(c);
    ++evaluations;
  }
  ivec3 home;
  for (int a = 0; a < 3; ++a) home[a] = min(int(max(c[a], 0.0)), count[a] - 2);
  const vec3 extent = max(max(abs(d0), abs(d1)), abs(d2));
  precise const float cube = extent.x * extent.y * extent.z;
  precise const vec3 e1 = u1 - u0, e2 = u2 - u0;
  float lowest = infinity();
  // Split into slabs along x, each of those along y, then z (boundOnTriangle).
  Polygon restX = wholeTriangle();
  for (int i0 = 0; i0 < slabCount[0]; ++i0) {
    Polygon inX = restX;
    if (i0 + 1 < slabCount[0]) restX = splitPolygon(inX, vec3(splits[0][i0] - u0.x, -e1.x, -e2.x));
    if (inX.corners == 0) continue;
    Polygon restY = inX;
    for (int i1 = 0; i1 < slabCount[1]; ++i1) {
      Polygon inY = restY;
      if (i1 + 1 < slabCount[1]) restY = splitPolygon(inY, vec3(splits[1][i1] - u0.y, -e1.y, -e2.y));
      if (inY.corners == 0) continue;
      Polygon restZ = inY;
      for (int i2 = 0; i2 < slabCount[2]; ++i2) {
        Polygon part = restZ;
        if (i2 + 1 < slabCount[2]) restZ = splitPolygon(part, vec3(splits[2][i2] - u0.z, -e1.z, -e2.z));
        if (part.corners == 0) continue;
        const ivec2 piece[3] = ivec2[3](slabs[0][i0], slabs[1][i1], slabs[2][i2]);
        const int index[3] = int[3](i0, i1, i2);
        const ivec3 cell = ivec3(piece[0].x, piece[1].x, piece[2].x);
        vec3 t, w = vec3(0.0);
        bool clamped = false;
        for (int a = 0; a < 3; ++a) {
          const int side = piece[a].y;
          t[a] = side == 0 ? c[a] - float(cell[a]) : (side < 0 ? 0.0 : 1.0);
          if (side != 0) w[a] = side < 0 ? c[a] : c[a] - float(count[a] - 1), clamped = true;
        }
        CellPolynomial p = gridExpand(cell, t);
        ++evaluations;
        if (!clamped && p.lowestNode >= cutoff) continue;
        int cutCount = 0;
        for (int a = 0; a < 3; ++a) {
          if (index[a] > 0) partCuts[cutCount++] = vec3(u0[a] - splits[a][index[a] - 1], e1[a], e2[a]);
          if (index[a] + 1 < slabCount[a]) partCuts[cutCount++] = vec3(splits[a][index[a]] - u0[a], -e1[a], -e2[a]);
        }
        if (clamped) {
          for (int k = 0; k < 8; ++k) {
            bool onFace = true;
            for (int a = 0; a < 3; ++a)
              if (piece[a].y != 0) onFace = onFace && (((k >> a) & 1) == (piece[a].y > 0 ? 1 : 0));
            if (onFace && !(p.node[k] >= 0.0)) {  // the box cuts the solid: the Lipschitz bound
              if (!outside) middleValue = gridDistanceAt(c), ++evaluations;
              const float reach = sqrt(max(max(dot3(d0, d0), dot3(d1, d1)), dot3(d2, d2))) * cellSize;
              precise const float bound = middleValue - DRAPE_GRID_LIPSCHITZ * reach;
              at = vec3(1.0 / 3.0);
              return bound;
            }
          }
          const float reach = length3(w);
          precise const float away = reach * cellSize;
          const float norm = sqrt(away * away + p.value * p.value);
          const float al = away / norm, be = p.value / norm;
          p.value = norm;
          for (int a = 0; a < 3; ++a) {
            precise const float clampedSlope = reach > 0.0 ? al * cellSize * w[a] / reach : 0.0;
            precise const float freeSlope = be * p.slope[a];
            p.slope[a] = piece[a].y != 0 ? clampedSlope : freeSlope;
          }
          p.xy = piece[0].y != 0 || piece[1].y != 0 ? 0.0 : be * p.xy;
          p.xz = piece[0].y != 0 || piece[2].y != 0 ? 0.0 : be * p.xz;
          p.yz = piece[1].y != 0 || piece[2].y != 0 ? 0.0 : be * p.yz;
          p.xyz = 0.0;
          p.lowestNode = -infinity();
        } else if (!outside && cell == home) {
          middleValue = p.value;
        }
        float al, be;
        const float quadratic = lowestOfQuadratic(p, d0, d1, d2, part, cutCount, al, be);
        precise const float bound = max(quadratic - abs(p.xyz) * cube, p.lowestNode);
        if (bound < lowest) lowest = bound, at = vec3((1.0 - al) - be, al, be);
      }
    }
  }
  return lowest;
}
#endif

#if DRAPE_SHAPE == DRAPE_SHAPE_SPHERE || DRAPE_SHAPE == DRAPE_SHAPE_CAPSULE
// The point of the triangle (a, b, c) nearest to p as barycentric weights w (nearestOnTriangle in
// include/drape/collision/pgd.hpp and nearestRegion in include/drape/detail/triangle.hpp, step for step); false for
// a triangle too flat for the interior's weights.
bool nearestOnTriangle(vec3 p, vec3 a, vec3 b, vec3 c, out vec3 w) {
  precise const vec3 ab = b - a, ac = c - a, ap = p - a;
  w = vec3(1.0 / 3.0);
  precise const vec3 normal =
      vec3(ab.y * ac.z - ab.z * ac.y, ab.z * ac.x - ab.x * ac.z, ab.x * ac.y - ab.y * ac.x);  // Eigen's cross
  if (!(dot3(normal, normal) > DRAPE_FLAT_SINE2 * dot3(ab, ab) * dot3(ac, ac))) return false;
  precise const float d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  w = vec3(1.0, 0.0, 0.0);
  if (d1 <= 0.0 && d2 <= 0.0) return true;
  precise const vec3 bp = p - b;
  precise const float d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  w = vec3(0.0, 1.0, 0.0);
  if (d3 >= 0.0 && d4 <= d3) return true;
  precise const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    precise const float s = d1 / (d1 - d3);
    w = vec3(1.0 - s, s, 0.0);
    return true;
  }
  precise const vec3 cp = p - c;
  precise const float d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  w = vec3(0.0, 0.0, 1.0);
  if (d6 >= 0.0 && d5 <= d6) return true;
  precise const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    precise const float s = d2 / (d2 - d6);
    w = vec3(1.0 - s, 0.0, s);
    return true;
  }
  precise const float va = d3 * d6 - d5 * d4;
  precise const float d43 = d4 - d3, d56 = d5 - d6;
  if (va <= 0.0 && d43 >= 0.0 && d56 >= 0.0) {
    precise const float s = d43 / (d43 + d56);
    w = vec3(0.0, 1.0 - s, s);
    return true;
  }
  precise const float sum = (va + vb) + vc;
  precise const float inverse = 1.0 / sum;
  precise const float s = vb * inverse, t = vc * inverse;
  w = vec3((1.0 - s) - t, s, t);
  return va >= 0.0 && vb >= 0.0 && vc >= 0.0 && sum > 0.0;
}
#endif

#if DRAPE_SHAPE == DRAPE_SHAPE_CAPSULE
// Whether the point of the triangle (a, b, c) nearest to p lies inside it: nearestRegion's Face
// (include/drape/detail/triangle.hpp), step for step.
bool nearestIsInside(vec3 p, vec3 a, vec3 b, vec3 c) {
  precise const vec3 ab = b - a, ac = c - a, ap = p - a;
  precise const float d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return false;
  precise const vec3 bp = p - b;
  precise const float d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return false;
  precise const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return false;
  precise const vec3 cp = p - c;
  precise const float d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return false;
  precise const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return false;
  precise const float va = d3 * d6 - d5 * d4;
  return !(va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0);
}

// The squared distance from x to the segment a + s d, s in [0, 1], of squared length length2 (squaredToSegment in
// include/drape/collision/pgd.hpp).
float squaredToSegment(vec3 x, vec3 a, vec3 d, float length2) {
  precise const vec3 r = x - a;
  precise const float s = length2 > 0.0 ? clamp(dot3(d, r) / length2, 0.0, 1.0) : 0.0;
  precise const vec3 off = r + (-s) * d;
  return dot3(off, off);
}

// The point of the triangle (x0, x1, x2) nearest to the segment [a, b] as barycentric weights w (nearestToSegment
// in include/drape/collision/pgd.hpp, step for step): the least of the segment's ends against the triangle, the
// corners against the segment and the edges' lines against the segment's where both nearest points are inside;
// false for a flat triangle and where the segment crosses it or lies in its plane.
bool nearestToSegment(vec3 a, vec3 b, vec3 x0, vec3 x1, vec3 x2, out vec3 w) {
  precise const vec3 e1 = x1 - x0, e2 = x2 - x0;
  precise const vec3 normal =
      vec3(e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x);  // Eigen's cross
  w = vec3(1.0 / 3.0);
  if (!(dot3(normal, normal) > DRAPE_FLAT_SINE2 * dot3(e1, e1) * dot3(e2, e2))) return false;
  precise const vec3 d = b - a;
  precise const float da = dot3(normal, a - x0), db = dot3(normal, b - x0);
  if (!(da > 0.0 && db > 0.0) && !(da < 0.0 && db < 0.0)) {  // the segment meets the triangle's plane
    if (!(da != db)) return false;
    precise const float f = da / (da - db);
    if (nearestIsInside(a + f * d, x0, x1, x2)) return false;
  }
  float best = uintBitsToFloat(0x7F800000u);  // infinity
  vec3 u;
  if (!nearestOnTriangle(a, x0, x1, x2, u)) return false;
  precise vec3 off = ((x0 + u.y * e1) + u.z * e2) - a;
  float dist = dot3(off, off);
  if (dist < best) best = dist, w = u;
  if (!nearestOnTriangle(b, x0, x1, x2, u)) return false;
  off = ((x0 + u.y * e1) + u.z * e2) - b;
  dist = dot3(off, off);
  if (dist < best) best = dist, w = u;
  precise const float length2 = dot3(d, d);
  for (int k = 0; k < 3; ++k) {
    const vec3 c = k == 0 ? x0 : (k == 1 ? x1 : x2);
    const vec3 next = k == 0 ? x1 : (k == 1 ? x2 : x0);
    dist = squaredToSegment(c, a, d, length2);
    if (dist < best) best = dist, w = vec3(k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0);
    precise const vec3 e = next - c, r = a - c;
    precise const float ee = dot3(e, e), de = dot3(d, e), dr = dot3(d, r), er = dot3(e, r);
    precise const float det = length2 * ee - de * de;
    if (!(det > DRAPE_PARALLEL_SINE2 * length2 * ee)) continue;
    precise const float s = (de * er - dr * ee) / det, t = (length2 * er - de * dr) / det;
    if (!(s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0)) continue;
    precise const vec3 between = (r + s * d) + (-t) * e;
    dist = dot3(between, between);
    if (dist < best) {
      best = dist;
      w = vec3(0.0);
      w[k] = 1.0 - t;
      w[(k + 1) % 3] = t;
    }
  }
  return true;
}
#endif

// One face against the field (queryFace): the bounding-sphere cull and, if the face may come within `margin`, its
// deepest point (barycentric qb, point qp, normal qn, distance qphi). False when culled.
bool searchFace(vec3 x0, vec3 x1, vec3 x2, float margin, out vec3 qb, out vec3 qn, out vec3 qp, out float qphi) {
#if DRAPE_SHAPE == DRAPE_SHAPE_SPHERE
  // A ball is deepest where the face is nearest its centre: the closed form of nearestOnTriangle
  // (include/drape/collision/pgd.hpp), culled first by the corners (a third of the longest edge's square below
  // the nearest corner's squared distance bounds the face's), then by the squared distance.
  {
    precise const float reach = shape[0].w + margin;
    precise const vec3 d0 = x0 - shape[0].xyz, d1 = x1 - shape[0].xyz, d2 = x2 - shape[0].xyz;
    precise const float corner = min(min(dot3(d0, d0), dot3(d1, d1)), dot3(d2, d2));
    precise const float edge = max(max(dot3(x1 - x0, x1 - x0), dot3(x2 - x1, x2 - x1)), dot3(x0 - x2, x0 - x2));
    precise const float clear = reach * (1.0 + DRAPE_CORNER_CULL_SLACK);
    if (3.0 * (corner - clear * clear) > edge) return false;
    vec3 nb;
    if (nearestOnTriangle(shape[0].xyz, x0, x1, x2, nb)) {
      precise const vec3 p = (x0 + nb.y * (x1 - x0)) + nb.z * (x2 - x0);
      precise const vec3 d = p - shape[0].xyz;
      if (dot3(d, d) > reach * reach) return false;
      qb = nb, qp = p;
      qphi = sdf(p, qn);
      return true;
    }
  }
#elif DRAPE_SHAPE == DRAPE_SHAPE_CAPSULE
  // A capsule is deepest where the face is nearest its core segment: the closed form of nearestToSegment
  // (include/drape/collision/pgd.hpp), culled first by the corners as on a ball, then by the squared distance. A
  // face the core crosses, or wider than the capsule, goes to the cutting planes.
  {
    precise const float reach = shape[1].w + margin;
    const vec3 axis = shape[1].xyz;
    precise const vec3 a = shape[0].xyz + (-shape[0].w) * axis, b = shape[0].xyz + shape[0].w * axis;
    precise const vec3 d = b - a;
    precise const float length2 = dot3(d, d);
    precise const float corner = min(min(squaredToSegment(x0, a, d, length2), squaredToSegment(x1, a, d, length2)),
                                     squaredToSegment(x2, a, d, length2));
    precise const float edge = max(max(dot3(x1 - x0, x1 - x0), dot3(x2 - x1, x2 - x1)), dot3(x0 - x2, x0 - x2));
    precise const float clear = reach * (1.0 + DRAPE_CORNER_CULL_SLACK);
    if (3.0 * (corner - clear * clear) > edge) return false;
    vec3 nb;
    if (4.0 * reach * reach >= edge && nearestToSegment(a, b, x0, x1, x2, nb)) {
      precise const vec3 p = (x0 + nb.y * (x1 - x0)) + nb.z * (x2 - x0);
      if (squaredToSegment(p, a, d, length2) > reach * reach) return false;
      qb = nb, qp = p;
      qphi = sdf(p, qn);
      return true;
    }
  }
#endif
  // Bounding sphere and cull (faceSphere, queryFace).
  precise const vec3 middle = ((x0 + x1) + x2) / 3.0;
  precise const float r2 = max(max(dot3(x0 - middle, x0 - middle), dot3(x1 - middle, x1 - middle)),
                               dot3(x2 - middle, x2 - middle));
  const float radius = sqrt(r2);
  vec3 gradC;
  const float phiC = sdf(middle, gradC);
#if DRAPE_CONVEX
  if (phiC > radius + margin) return false;
#else
  if (phiC > DRAPE_GRID_LIPSCHITZ * radius + margin) return false;  // a grid field is steeper than a distance
#endif

  qb = vec3(1.0 / 3.0), qn = gradC, qp = middle;
  qphi = phiC;
  int evaluations = 1;
  precise const vec3 e1 = x1 - x0, e2 = x2 - x0;
#if DRAPE_CONVEX
  // The cutting-plane search (deepestPointOnFace) with floor = margin.
  precise const vec3 e3 = x2 - x1;
  const float extent = max(max(length3(e1), length3(e2)), length3(e3));
  precise const float tolerance = kGap * extent;
  int cutCount = 1;
  cuts[0] = cutAt(qb, phiC, gradC, e1, e2);
  int corner = 0;
  float model = cuts[0].x;
  if (cuts[0].y < model) model = cuts[0].y, corner = 1;
  if (cuts[0].z < model) model = cuts[0].z, corner = 2;
  vec3 nextB = vec3(corner == 0 ? 1.0 : 0.0, corner == 1 ? 1.0 : 0.0, corner == 2 ? 1.0 : 0.0);
  float lower = model;
  bool exact = true;
  precise const float stopAt = margin + tolerance;
  while (evaluations < maxIterations && qphi - lower > tolerance && lower < stopAt) {
    precise const vec3 bb = nextB / (nextB.x + (nextB.y + nextB.z));  // Eigen sums the last two first
    precise const vec3 p = (x0 + bb.y * e1) + bb.z * e2;
    vec3 n;
    const float phi = sdf(p, n);
    ++evaluations;
    if (phi < qphi) qb = bb, qn = n, qphi = phi, qp = p;
    if (qphi - lower <= tolerance) break;
    const vec3 cut = cutAt(bb, phi, n, e1, e2);
    if (cutCount == kMaxCuts) {  // keep the cuts active at the model's minimum
      int kept = 0;
      precise const float slack = DRAPE_CUT_SLACK * tolerance;
      for (int k = 0; k < cutCount; ++k)
        if (dot3(cuts[k], bb) >= model - slack && kept < kMaxCuts - 1) cuts[kept++] = cuts[k];
      if (kept == kMaxCuts - 1) exact = false;
      cutCount = kept;
    }
    // Clip the triangle to where the new cut is highest; the model's minimum is the lowest vertex left.
    int vertices = 3;
    poly[0] = vec3(1.0, 0.0, 0.0);
    poly[1] = vec3(0.0, 1.0, 0.0);
    poly[2] = vec3(0.0, 0.0, 1.0);
    for (int k = 0; k < cutCount && vertices > 0; ++k) {
      precise const vec3 hk = cut - cuts[k];
      int outCount = 0;
      bool full = false;
      for (int i = 0; i < vertices; ++i) {
        const vec3 u = poly[i];
        const vec3 v = poly[i + 1 == vertices ? 0 : i + 1];
        precise const float su = dot3(hk, u), sv = dot3(hk, v);
        if (outCount + 2 > kMaxVertices) {
          full = true;
          break;
        }
        if (su >= 0.0) clipped[outCount++] = u;
        if ((su >= 0.0) != (sv >= 0.0)) {
          precise const vec3 w = u + (su / (su - sv)) * (v - u);
          clipped[outCount++] = w;
        }
      }
      vertices = (full || outCount + 2 > kMaxVertices) ? 0 : outCount;
      for (int i = 0; i < outCount; ++i) poly[i] = clipped[i];
    }
    if (vertices == 0) break;
    cuts[cutCount++] = cut;
    int arg = 0;
    model = dot3(cut, poly[0]);
    for (int i = 1; i < vertices; ++i) {
      const float m = dot3(cut, poly[i]);
      if (m < model) model = m, arg = i;
    }
    nextB = max(poly[arg], vec3(0.0));
    if (exact) lower = max(lower, model);
  }
#else
  // Branch and bound over the face (branchAndBoundOnFace and Sdf<MeshShape>::deepestPointOnFace) with
  // floor = margin: sub-triangles split in four, depth first, lowest bound first.
  const vec3 u0 = gridCells(x0), u1 = gridCells(x1), u2 = gridCells(x2);
  const float extent = max(max(length3(x1 - x0), length3(x2 - x0)), length3(x2 - x1));
  precise const float tolerance = DRAPE_FACE_SEARCH_GAP * extent;
  precise const float stopAt = margin + tolerance;
  precise const vec3 ue1 = u1 - u0, ue2 = u2 - u0;
  float value = phiC;
  vec3 best = vec3(1.0 / 3.0);
  int top = 0;
  const float smallest = ldexp(1.0, -kGridDepth);
  // visit(o1, o2, s): bound one sub-triangle and try its points; the root first.
  for (int pass = 0; ; ++pass) {
    vec4 children[4];
    int childCount;
    if (pass == 0) {
      children[0] = vec4(0.0, 0.0, 1.0, 0.0);
      childCount = 1;
    } else {
      if (top == 0 || evaluations >= DRAPE_GRID_SEARCH_BUDGET) break;
      const vec4 n = gridStack[--top];
      precise const float keepBelow = min(value - tolerance, stopAt);
      if (n.w >= keepBelow || abs(n.z) <= smallest) continue;
      precise const float h = n.z / 2.0;
      precise const float o1h = n.x + h, o2h = n.y + h;
      children[0] = vec4(n.x, n.y, h, 0.0);
      children[1] = vec4(o1h, n.y, h, 0.0);
      children[2] = vec4(n.x, o2h, h, 0.0);
      children[3] = vec4(o1h, o2h, -h, 0.0);
      childCount = 4;
    }
    for (int k = 0; k < childCount; ++k) {
      const float o1 = children[k].x, o2 = children[k].y, sz = children[k].z;
      precise const vec3 c0 = (u0 + o1 * ue1) + o2 * ue2;
      precise const vec3 c1 = (u0 + (o1 + sz) * ue1) + o2 * ue2;
      precise const vec3 c2 = (u0 + o1 * ue1) + (o2 + sz) * ue2;
      vec3 at;
      float middleValue;
      const float lower = boundOnTriangle(c0, c1, c2, at, middleValue, evaluations, min(value - tolerance, stopAt));
      if (middleValue < value) {
        precise const vec3 cb = vec3((1.0 - o1 - o2) - 2.0 * sz / 3.0, o1 + sz / 3.0, o2 + sz / 3.0);
        value = middleValue, best = cb;
      }
      if (lower < min(value - tolerance, stopAt)) {
        precise const float b1 = o1 + sz * at.y, b2 = o2 + sz * at.z;
        precise const vec3 tryAt = (u0 + b1 * ue1) + b2 * ue2;
        const float phi = gridDistanceAt(tryAt);
        ++evaluations;
        if (phi < value) value = phi, best = vec3((1.0 - b1) - b2, b1, b2);
      }
      children[k].w = lower;
    }
    // Stable insertion sort, highest bound first, so the lowest is taken next.
    for (int i = 1; i < childCount; ++i) {
      const vec4 key = children[i];
      int j = i - 1;
      while (j >= 0 && key.w > children[j].w) children[j + 1] = children[j], --j;
      children[j + 1] = key;
    }
    precise const float keep = min(value - tolerance, stopAt);
    for (int k = 0; k < childCount; ++k)
      if (children[k].w < keep && top < kGridStack) gridStack[top++] = children[k];
  }
  if (value < phiC) {
    const vec3 clampedB = max(best, vec3(0.0));
    precise const vec3 nb = clampedB / (clampedB.x + (clampedB.y + clampedB.z));
    precise const vec3 p = (nb.x * x0 + nb.y * x1) + nb.z * x2;
    vec3 n;
    qphi = sdf(p, n);
    qb = nb, qn = n, qp = p;
    ++evaluations;
  }
#endif
  return true;
}

// The face moving from corners (a0, a1, a2) to (b0, b1, b2) (sweepFace in include/drape/collision/sweep.hpp): the
// first time `when` it comes within the thickness of the solid, and its deepest point then. Conservative advancement
// with the bounding sphere's lower bound where it clears the thickness, else the face search's.
bool sweepFace(vec3 a0, vec3 a1, vec3 a2, vec3 b0, vec3 b1, vec3 b2, out vec3 qb, out vec3 qn, out vec3 qp,
               out float qphi, out float when) {
  precise const vec3 d0 = b0 - a0, d1 = b1 - a1, d2 = b2 - a2;
  const float travel = sqrt(max(max(dot3(d0, d0), dot3(d1, d1)), dot3(d2, d2)));
  precise const float stride = DRAPE_LIPSCHITZ * travel;
  precise const float halfThickness = 0.5 * thickness;
  float t = 0.0;
  when = 0.0;
  for (int step = 0; step < DRAPE_FACE_SWEEP_STEPS; ++step) {
    precise const vec3 y0 = a0 + t * d0, y1 = a1 + t * d1, y2 = a2 + t * d2;
    precise const vec3 middle = ((y0 + y1) + y2) / 3.0;
    precise const float r2 = max(max(dot3(y0 - middle, y0 - middle), dot3(y1 - middle, y1 - middle)),
                                 dot3(y2 - middle, y2 - middle));
    const float radius = sqrt(r2);
    vec3 gradient;
    precise const float lower = sdf(middle, gradient) - DRAPE_LIPSCHITZ * radius;
    if (lower >= thickness) {
      precise const float advance = (lower - halfThickness) / stride;
      t = t + advance;
    } else {
      vec3 fb, fn, fp;
      float fphi;
      if (searchFace(y0, y1, y2, thickness, fb, fn, fp, fphi) && fphi < thickness) {
        qb = fb, qn = fn, qp = fp, qphi = fphi, when = t;
        return t > 0.0 || fphi >= 0.0;
      }
      precise const float advance = halfThickness / stride;
      t = t + advance;
    }
    if (!(t < 1.0)) break;
  }
  return false;
}

// The direction a face contact pushes along, and how far (featureAlignedPush in
// include/drape/collision/response.hpp): at a sharp feature, a deepest point inside the face goes along the face's
// normal, one on an edge across that edge and, on a field with edges, across the solid's edge too (the gradients to
// either side of the point, mixed to have no part along the face's edge); a gradient already within the bounds is
// kept.
float featureAlignedPush(vec3 x0, vec3 x1, vec3 x2, float depth, vec3 qb, vec3 qp, inout vec3 qn) {
  int onEdge = 0, zero = -1;
  for (int k = 0; k < 3; ++k)
    if (qb[k] <= DRAPE_FEATURE_BARYCENTRIC) ++onEdge, zero = k;
  vec3 u;
  if (onEdge == 0) {
    precise vec3 m = cross(x1 - x0, x2 - x0);
    const float len = length3(m);
    if (!(len > 0.0)) return depth;
    u = m / len;
    if (dot3(u, qn) < 0.0) u = -u;
    if (dot3(u, qn) >= DRAPE_FEATURE_INTERIOR_COS) return depth;
  } else if (onEdge == 1) {
    const vec3 corners[3] = vec3[3](x0, x1, x2);
    precise vec3 e = corners[(zero + 2) % 3] - corners[(zero + 1) % 3];
    const float len = length3(e);
    if (!(len > 0.0)) return depth;
    e /= len;
    const float along = dot3(qn, e);
    if (abs(along) <= DRAPE_FEATURE_EDGE_SINE) return depth;
    precise vec3 w = qn - along * e;
#if !DRAPE_SMOOTH_FIELD
    precise const float probe = DRAPE_FEATURE_EDGE_PROBE * len;
    precise const vec3 behind = qp - probe * e, ahead = qp + probe * e;
    vec3 before, after;
    sdf(behind, before);
    sdf(ahead, after);
    const float down = dot3(before, e), up = dot3(after, e);
    if (down < 0.0 && up > 0.0) {
      const float a = up / (up - down);
      w = a * before + (1.0 - a) * after;
      w -= dot3(w, e) * e;
    }
#endif
    const float across = length3(w);
    if (!(across > DRAPE_FEATURE_MIN_RATE)) return depth;
    u = w / across;
  } else {
    return depth;
  }
  const float rate = dot3(u, qn);
  if (!(rate > DRAPE_FEATURE_MIN_RATE)) return depth;
  precise float s = depth / rate;
  for (int it = 0; it < DRAPE_FEATURE_NEWTON_STEPS; ++it) {
    vec3 g;
    const float phi = sdf(qp + s * u, g);
    const float grows = dot3(g, u);
    if (!(grows > DRAPE_FEATURE_MIN_RATE)) break;
    s += (thickness - phi) / grows;
  }
  qn = u;
  return max(s, 0.0);
}

#if DRAPE_GUARD
// Continuous contact's friction guard (markFrictionCrossings in include/drape/collision/sweep.hpp), over every face
// in any order: a face with a corner position friction moved further than the thickness uniform (the guard's
// reach), whose path from before friction came within the reach of the solid after its start, and which the solid
// then pierces where friction left it, marks its corners. Every mark is the same 1, so faces that share a corner
// need no order; restore_marked puts the marked corners back.
layout(std430, binding = DRAPE_B_GUARD_FROM) readonly buffer GuardFrom { vec4 before[]; };
layout(std430, binding = DRAPE_B_GUARD_MARKS) buffer GuardMarks { uint marks[]; };

void main() {
  if (gl_GlobalInvocationID.x >= count) return;
  const uvec4 t = faces[first + gl_GlobalInvocationID.x];
  const vec3 a0 = before[t.x].xyz, a1 = before[t.y].xyz, a2 = before[t.z].xyz;
  const vec3 b0 = x[t.x].xyz, b1 = x[t.y].xyz, b2 = x[t.z].xyz;
  precise const vec3 d0 = b0 - a0, d1 = b1 - a1, d2 = b2 - a2;
  if (!(max(max(dot3(d0, d0), dot3(d1, d1)), dot3(d2, d2)) > thickness * thickness)) return;
  precise const vec3 low = boxLow - vec3(thickness), high = boxHigh + vec3(thickness);
  const vec3 pathLow = min(min(min(a0, a1), min(a2, b0)), min(b1, b2));
  const vec3 pathHigh = max(max(max(a0, a1), max(a2, b0)), max(b1, b2));
  if (!(all(greaterThanEqual(pathHigh, low)) && all(lessThanEqual(pathLow, high)))) return;
  vec3 hb, hn, hp;
  float hphi, when;
  if (!(sweepFace(a0, a1, a2, b0, b1, b2, hb, hn, hp, hphi, when) && when > 0.0)) return;
  vec3 eb, en, ep;
  float ephi;
  if (searchFace(b0, b1, b2, thickness, eb, en, ep, ephi) && ephi < 0.0) {
    marks[t.x] = 1u;
    marks[t.y] = 1u;
    marks[t.z] = 1u;
  }
}
#else
void main() {
  if (gl_GlobalInvocationID.x >= count) return;
  const uvec4 t = faces[first + gl_GlobalInvocationID.x];
  vec4 a = x[t.x], b = x[t.y], c = x[t.z];
  precise const vec3 low = boxLow - vec3(thickness), high = boxHigh + vec3(thickness);
#if DRAPE_SWEEP
  if (sweep.y > 0.0) {
    // Continuous contact: a face whose corners travelled further than the gate relative to the solid is searched
    // along its path first; from its first contact on, no corner goes further against the contact normal than it
    // was then, and a corner that already holds a contact of another direction goes back along its own path.
    vec3 from[3], to[3];
    for (int k = 0; k < 3; ++k) {
      const vec3 s0 = starts[t[k]].xyz;
      precise const vec3 f = s0 + sweep.x * solidVelocityAt(s0, centre, linearVelocity, angularVelocity);
      from[k] = f;
    }
    to[0] = a.xyz, to[1] = b.xyz, to[2] = c.xyz;
    precise const vec3 d0 = to[0] - from[0], d1 = to[1] - from[1], d2 = to[2] - from[2];
    const bool far = max(max(dot3(d0, d0), dot3(d1, d1)), dot3(d2, d2)) > sweep.y;
    const vec3 pathLow = min(min(min(from[0], from[1]), min(from[2], to[0])), min(to[1], to[2]));
    const vec3 pathHigh = max(max(max(from[0], from[1]), max(from[2], to[0])), max(to[1], to[2]));
    vec3 hb, hn, hp;
    float hphi, when;
    if (far && all(greaterThanEqual(pathHigh, low)) && all(lessThanEqual(pathLow, high)) &&
        sweepFace(from[0], from[1], from[2], to[0], to[1], to[2], hb, hn, hp, hphi, when)) {
      const float w[3] = float[3](a.w, b.w, c.w);
      for (int k = 0; k < 3; ++k) {
        if (w[k] == 0.0) continue;
        precise const vec3 then = from[k] + when * (to[k] - from[k]);
        precise const float dn = dot3(hn, then - to[k]);
        if (!(dn > 0.0)) continue;
        const uint vi = t[k];
        Contact ct = contacts[vi];
        bool other = false;
        for (uint s = 0u; s < ct.slots.x; ++s) other = other || dot3(ct.normal[s].xyz, hn) < kMergeCos;
        precise const vec3 moved = other ? then : to[k] + dn * hn;
        x[vi] = vec4(moved, w[k]);
        const vec3 vc = solidContactVelocity(moved, hn, hp, centre, linearVelocity, angularVelocity);
#if DRAPE_BODY
        lineRecord = lines[vi];
        recordContact(ct, moved, hn, dn, vc, friction, body, momentAbout(hp, centre, hn));
        lines[vi] = lineRecord;
#else
        recordContact(ct, moved, hn, dn, vc, friction, body, vec3(0.0));
#endif
        contacts[vi] = ct;
      }
      a = x[t.x], b = x[t.y], c = x[t.z];
    }
  }
#endif
  const vec3 x0 = a.xyz, x1 = b.xyz, x2 = c.xyz;
  // A face whose box misses the solid's box grown by the thickness has no point within the thickness of it
  // (projectFaceContactsAs with kBoxed): culled before any field evaluation.
  if (!(all(greaterThanEqual(max(max(x0, x1), x2), low)) && all(lessThanEqual(min(min(x0, x1), x2), high)))) return;
  vec3 qb, qn, qp;
  float qphi;
  if (!searchFace(x0, x1, x2, thickness, qb, qn, qp, qphi)) return;
  // faceContactSlack in include/drape/collision/response.hpp: a share of the thickness and a few roundings.
  const vec3 qa = abs(qp);
  if (qphi >= thickness - (thickness * DRAPE_FACE_CONTACT_SLACK +
                           DRAPE_FACE_CONTACT_ROUNDING * max(max(qa.x, qa.y), qa.z)))
    return;
#if DRAPE_HOLDS_DEEPEST_POINTS
  // The face's held point, where it is as deep as the search's within the search's tolerance (HeldPoints in
  // include/drape/collision/response.hpp): a face parallel to a side or an edge of the solid is deepest along a
  // segment, and the search's end on it follows the rounding.
  if (heldPlace != 0u) {
    const uint fi = first + gl_GlobalInvocationID.x;
    const vec4 h = held[fi];
    if (h.w == float(heldPlace)) {
      precise const vec3 hp = x0 + h.y * (x1 - x0) + h.z * (x2 - x0);
      vec3 hn;
      const float hphi = sdf(hp, hn);
      precise const vec3 e01 = x1 - x0, e12 = x2 - x1, e20 = x0 - x2;
      const float extent = sqrt(max(max(dot3(e01, e01), dot3(e12, e12)), dot3(e20, e20)));
      if (hphi < thickness && hphi <= qphi + DRAPE_HELD_POINT_SLACK * DRAPE_FACE_SEARCH_GAP * extent)
        qb = h.xyz, qp = hp, qn = hn, qphi = hphi;
    }
    held[fi] = vec4(qb, float(heldPlace));
  }
#endif

  // Move the face's vertices (projectFaceContactsAs), the shares spread where deepest points are held.
#if DRAPE_HOLDS_DEEPEST_POINTS
  const float spread = DRAPE_FACE_SPREAD;
#else
  const float spread = 0.0;
#endif
  precise const vec3 wb = vec3(a.w * (qb.x + spread), b.w * (qb.y + spread), c.w * (qb.z + spread));
  precise const float denom = dot3(wb, qb);
  if (denom <= 0.0) return;
#if DRAPE_SHAPE == DRAPE_SHAPE_SPHERE
  // A ball's nearest point already has its gradient along the face's normal or across its edge.
  precise float depth = thickness - qphi;
#else
  precise float depth = featureAlignedPush(x0, x1, x2, thickness - qphi, qb, qp, qn);
#endif
  // No corner moves more than kFaceMoveCap times the depth (projectFaceContactsAs).
  precise const float most = max(max(wb.x, wb.y), wb.z) / denom;
  if (most > DRAPE_FACE_MOVE_CAP) depth *= DRAPE_FACE_MOVE_CAP / most;
  precise const vec3 placed = qp + depth * qn;  // where the moves carry the deepest point (a body's push acts there)
  for (int k = 0; k < 3; ++k) {
    if (wb[k] <= 0.0) continue;
    const uint vi = t[k];
    precise const float dn = wb[k] / denom * depth;
    const vec4 xv = x[vi];
    precise const vec3 moved = xv.xyz + dn * qn;
    x[vi] = vec4(moved, xv.w);
    Contact ct = contacts[vi];
    const vec3 vc = solidContactVelocity(moved, qn, placed, centre, linearVelocity, angularVelocity);
#if DRAPE_BODY
    lineRecord = lines[vi];
    recordContact(ct, moved, qn, dn, vc, friction, body, momentAbout(placed, centre, qn));
    lines[vi] = lineRecord;
#else
    recordContact(ct, moved, qn, dn, vc, friction, body, vec3(0.0));
#endif
    contacts[vi] = ct;
  }
}
#endif
