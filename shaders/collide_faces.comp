// docs/design.md §3 and §4, the face pass (the CPU twins: queryFace and deepestPointOnFace in
// include/drape/collision/pgd.hpp, projectFaceContactsAs in include/drape/collision/response.hpp), for one colour
// of faces: faces of a colour share no vertex, so each invocation moves its own three vertices. Per face: the
// bounding-sphere cull (phi at the centroid beyond the radius plus the thickness), then Kelley's cutting-plane
// search for the deepest point (the field of a convex solid is convex along the face, so each tangent plane
// bounds it from below and the search stops once the best value is certified), and where that point is closer
// than the thickness, the face's vertices move along the normal, weighted by barycentric weight and inverse
// mass, to carry it to the thickness. The moves are recorded in the vertices' contacts (recordContact, as the
// CPU records them).
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
#if DRAPE_BODY
layout(std430, binding = DRAPE_B_LINES) buffer LinesBuffer { Lines lines[]; };
layout(location = DRAPE_U_BODY) uniform int body;  // the coupled body this solid pushes
#else
const int body = -1;
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

// The field's slope in barycentric coordinates, within the simplex's plane: g - mean(g), g = (n . x0, n . x1, n . x2).
vec3 slopeAt(vec3 n, vec3 x0, vec3 x1, vec3 x2) {
  const vec3 g = vec3(dot3(n, x0), dot3(n, x1), dot3(n, x2));
  precise const float mean = (g.x + (g.y + g.z)) / 3.0;
  precise const vec3 s = g - vec3(mean);
  return s;
}

// Euclidean projection onto {b : b >= 0, b0 + b1 + b2 = 1} (projectToSimplex): sorted descending, the largest
// threshold that keeps a coordinate positive.
vec3 projectToSimplex(vec3 y) {
  float u0 = y.x, u1 = y.y, u2 = y.z, tmp;
  if (u1 > u0) tmp = u0, u0 = u1, u1 = tmp;
  if (u2 > u1) tmp = u1, u1 = u2, u2 = tmp;
  if (u1 > u0) tmp = u0, u0 = u1, u1 = tmp;
  const float u[3] = float[3](u0, u1, u2);
  precise float sum = 0.0;
  float theta = 0.0;
  for (int j = 0; j < 3; ++j) {
    sum = sum + u[j];
    precise const float t = (sum - 1.0) / float(j + 1);
    if (u[j] - t > 0.0) theta = t;
  }
  return max(y - vec3(theta), vec3(0.0));
}

void main() {
  if (gl_GlobalInvocationID.x >= count) return;
  const uvec4 t = faces[first + gl_GlobalInvocationID.x];
  const vec4 a = x[t.x], b = x[t.y], c = x[t.z];
  const vec3 x0 = a.xyz, x1 = b.xyz, x2 = c.xyz;
  // A face whose box misses the solid's box grown by the thickness has no point within the thickness of it
  // (projectFaceContactsAs with kBoxed): culled before any field evaluation.
  precise const vec3 low = boxLow - vec3(thickness), high = boxHigh + vec3(thickness);
  if (!(all(greaterThanEqual(max(max(x0, x1), x2), low)) && all(lessThanEqual(min(min(x0, x1), x2), high)))) return;
  // Bounding sphere and cull (faceSphere, queryFace).
  precise const vec3 middle = ((x0 + x1) + x2) / 3.0;
  precise const float r2 = max(max(dot3(x0 - middle, x0 - middle), dot3(x1 - middle, x1 - middle)),
                               dot3(x2 - middle, x2 - middle));
  const float radius = sqrt(r2);
  vec3 gradC;
  const float phiC = sdf(middle, gradC);
  if (phiC > radius + thickness) return;

  vec3 qb = vec3(1.0 / 3.0), qn = gradC, qp = middle;
  float qphi = phiC;
  int evaluations = 1;
  precise const vec3 e1 = x1 - x0, e2 = x2 - x0;
#if DRAPE_CONVEX
  // The cutting-plane search (deepestPointOnFace) with floor = thickness.
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
  precise const float stopAt = thickness + tolerance;
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
        const vec3 v = poly[(i + 1) % vertices];
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
  // Projected gradient descent over the barycentric simplex (the CPU twin: descendOnFace), for a field that may
  // not be convex: Barzilai-Borwein step lengths, halved when a step does not lower phi. The CPU searches grid
  // fields by branch and bound (include/drape/sdf/grid_search.hpp), which is not yet ported here.
  const float kMinStep = DRAPE_MIN_DESCENT_STEP;
  vec3 slope = slopeAt(gradC, x0, x1, x2);
  const float slopeLen = length3(slope);
  float alpha = slopeLen > 0.0 ? 1.0 / slopeLen : 0.0;  // the first trial moves one unit
  while (evaluations < maxIterations && alpha > 0.0) {
    precise const vec3 bb = projectToSimplex(qb - alpha * slope);
    precise const vec3 stepB = bb - qb;
    if (max(max(abs(stepB.x), abs(stepB.y)), abs(stepB.z)) < kMinStep) break;
    precise const vec3 p = (x0 + bb.y * e1) + bb.z * e2;
    vec3 n;
    const float phi = sdf(p, n);
    ++evaluations;
    if (phi < qphi) {
      const vec3 next = slopeAt(n, x0, x1, x2);
      precise const float sy = dot3(stepB, next - slope);
      precise const float bbStep = dot3(stepB, stepB) / sy;
      alpha = sy > 0.0 ? bbStep : 2.0 * alpha;
      slope = next;
      qb = bb, qn = n, qphi = phi, qp = p;
    } else {
      alpha *= 0.5;
    }
  }
#endif
  if (qphi >= thickness) return;

  // Move the face's vertices (projectFaceContactsAs).
  precise const vec3 wb = vec3(a.w * qb.x, b.w * qb.y, c.w * qb.z);
  precise const float denom = dot3(wb, qb);
  if (denom <= 0.0) return;
  precise const float depth = thickness - qphi;
  precise const vec3 placed = qp + depth * qn;  // where the moves carry the deepest point (a body's push acts there)
  for (int k = 0; k < 3; ++k) {
    if (wb[k] <= 0.0) continue;
    const uint vi = t[k];
    precise const float dn = wb[k] / denom * depth;
    const vec4 xv = x[vi];
    precise const vec3 moved = xv.xyz + dn * qn;
    x[vi] = vec4(moved, xv.w);
    Contact ct = contacts[vi];
    const vec3 vc = solidVelocityAt(moved, centre, linearVelocity, angularVelocity);
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
