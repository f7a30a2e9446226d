// Helpers every kernel is compiled with (after layout.hpp's preamble). Each sums in the order the CPU code
// does, `precise` so no product is fused into a sum: Eigen's dot product of two 3-vectors, which the CPU
// kernels use, adds the last two products first.

float dot3(vec3 a, vec3 b) {
  precise float s = a.x * b.x + (a.y * b.y + a.z * b.z);
  return s;
}
float length3(vec3 a) { return sqrt(dot3(a, a)); }

// w x d: how much faster a solid spinning at w moves at a point d further on (SolidMotion::spin).
vec3 spinOver(vec3 angular, vec3 d) {
  precise vec3 r = vec3(angular.y * d.z - angular.z * d.y, angular.z * d.x - angular.x * d.z,
                        angular.x * d.y - angular.y * d.x);
  return r;
}

// The velocity of a solid's material point at x: v + w x (x - centre) (SolidMotion::velocityAt).
vec3 solidVelocityAt(vec3 x, vec3 centre, vec3 linear, vec3 angular) {
  precise vec3 v = linear + spinOver(angular, x - centre);
  return v;
}

// The solid's velocity a contact at x answers to, its surface point being anchor and its normal n: the material
// velocity at x with the normal part of the surface's velocity at the anchor (SolidMotion::contactVelocityAt).
vec3 solidContactVelocity(vec3 x, vec3 n, vec3 anchor, vec3 centre, vec3 linear, vec3 angular) {
  precise const float s = dot3(n, spinOver(angular, anchor - x));
  precise vec3 v = solidVelocityAt(x, centre, linear, angular) + s * n;
  return v;
}

// Rows r0, r1, r2 of a rotation times v, and its transpose times v, as Eigen sums them.
vec3 rotate(vec3 r0, vec3 r1, vec3 r2, vec3 v) { return vec3(dot3(r0, v), dot3(r1, v), dot3(r2, v)); }
vec3 rotateBack(vec3 r0, vec3 r1, vec3 r2, vec3 v) {
  return vec3(dot3(vec3(r0.x, r1.x, r2.x), v), dot3(vec3(r0.y, r1.y, r2.y), v), dot3(vec3(r0.z, r1.z, r2.z), v));
}

// --- contact records (the CPU twin: ContactBuffer in include/drape/collision/response.hpp) ---------------------

// Contacts whose normals agree within this cosine share a slot (constants::kMergeCos).
const float kMergeCos = DRAPE_MERGE_COS;

// An empty record: no slot taken.
Contact emptyContact() {
  Contact c;
  for (int k = 0; k < DRAPE_CONTACT_SLOTS; ++k) c.normal[k] = c.velocity[k] = c.friction[k] = vec4(0.0);
  c.body = ivec4(-1);
  c.slots = uvec4(0u);
  c.normalDv = vec4(0.0);
  return c;
}

#if DRAPE_BODY
// A coupled body's kernels keep where each slot's push acts (ContactLine): the caller loads the vertex's lines
// here before recordContact and stores them after.
Lines lineRecord;
#endif

// (a - centre) x n, written out as the CPU's Eigen cross product computes it: a contact's moment about a body.
vec3 momentAbout(vec3 a, vec3 centre, vec3 n) {
  precise const vec3 r = a - centre;
  precise const vec3 m = vec3(r.y * n.z - r.z * n.y, r.z * n.x - r.x * n.z, r.x * n.y - r.y * n.x);
  return m;
}

// Records that the vertex was placed at x, dn along n, out of a solid whose velocity there is vc
// (ContactBuffer::record and recordMore): a new direction takes a free slot; the same surface seen again (the
// normals within kMergeCos) takes the latest normal and placement; a direction that finds every slot taken joins
// the closest, whose normal stays, unless it faces away from every one or two of them are one body's faces and it
// is another solid's (the two closest such then share a slot and it takes the other), and marks the record
// overflowed. The corrections add up. In a coupled body's kernels (DRAPE_BODY) the slot's line takes this
// contact's share of its push and moment (`moment` about the body's centre); other solids' kernels write no line.
void recordContact(inout Contact c, vec3 x, vec3 n, float dn, vec3 vc, vec2 friction, int body, vec3 moment) {
  const uint count = c.slots.x;
  if (count == 0u) {
    c.slots = uvec4(1u, 0u, 0u, 0u);
    c.normal[0] = vec4(n, dn);
    c.velocity[0] = vec4(vc, dot3(n, x));
    c.friction[0] = vec4(friction, 0.0, 0.0);
    c.body[0] = body;
#if DRAPE_BODY
    lineRecord.push[0] = vec4(n, 0.0);
    lineRecord.moment[0] = vec4(moment, 0.0);
#endif
    return;
  }
  int best = -1;
  float bestCos = kMergeCos;
  for (int k = 0; k < int(count); ++k) {
    const float cs = dot3(c.normal[k].xyz, n);
    if (cs >= bestCos) best = k, bestCos = cs;
  }
  if (best < 0 && count < uint(DRAPE_CONTACT_SLOTS)) {
    c.normal[count] = vec4(n, dn);
    c.velocity[count] = vec4(vc, dot3(n, x));
    c.friction[count] = vec4(friction, 0.0, 0.0);
    c.body[count] = body;
#if DRAPE_BODY
    lineRecord.push[count] = vec4(n, 0.0);
    lineRecord.moment[count] = vec4(moment, 0.0);
#endif
    c.slots.x = count + 1u;
    return;
  }
  if (best < 0) {
    c.slots.y = 1u;
    bestCos = -2.0;
    for (int k = 0; k < DRAPE_CONTACT_SLOTS; ++k) {
      const float cs = dot3(c.normal[k].xyz, n);
      if (cs > bestCos) best = k, bestCos = cs;
    }
    // A direction facing away from every recorded one, or two recorded faces of one body while this contact is
    // another solid's: the two closest recorded ones share a slot (mergeSlot), and this one takes the other.
    int keep = -1, give = -1;
    float pairCos = bestCos;
    for (int j = 0; j < DRAPE_CONTACT_SLOTS; ++j)
      for (int k = j + 1; k < DRAPE_CONTACT_SLOTS; ++k) {
        const bool oneBody = c.body[j] >= 0 && c.body[j] == c.body[k] && c.body[j] != body;
        const float cs = dot3(c.normal[j].xyz, c.normal[k].xyz);
        if ((bestCos < 0.0 || oneBody) && cs > pairCos) keep = j, give = k, pairCos = cs;
      }
    if (keep >= 0) {
      precise const float merged = c.normal[keep].w + c.normal[give].w;
#if DRAPE_BODY
      if (c.body[keep] == c.body[give] && merged > 0.0) {
        precise const float share = c.normal[give].w / merged;
        precise const vec3 push =
            lineRecord.push[keep].xyz + share * (lineRecord.push[give].xyz - lineRecord.push[keep].xyz);
        precise const vec3 mom =
            lineRecord.moment[keep].xyz + share * (lineRecord.moment[give].xyz - lineRecord.moment[keep].xyz);
        lineRecord.push[keep] = vec4(push, 0.0);
        lineRecord.moment[keep] = vec4(mom, 0.0);
      }
      lineRecord.push[give] = vec4(n, 0.0);
      lineRecord.moment[give] = vec4(moment, 0.0);
#endif
      c.velocity[keep].w = max(c.velocity[keep].w, dot3(c.normal[keep].xyz, x));
      c.normal[keep].w = merged;
      c.normal[give] = vec4(n, dn);
      c.velocity[give] = vec4(vc, dot3(n, x));
      c.friction[give] = vec4(friction, 0.0, 0.0);
      c.body[give] = body;
      return;
    }
  }
  precise const float total = c.normal[best].w + dn;
#if DRAPE_BODY
  if (c.body[best] != body) {
    if (bestCos >= kMergeCos) lineRecord.push[best] = vec4(n, 0.0), lineRecord.moment[best] = vec4(moment, 0.0);
  } else if (total > 0.0) {  // this contact's share of the slot's push and moment
    precise const float share = dn / total;
    precise const vec3 push = lineRecord.push[best].xyz + share * (n - lineRecord.push[best].xyz);
    precise const vec3 mom = lineRecord.moment[best].xyz + share * (moment - lineRecord.moment[best].xyz);
    lineRecord.push[best] = vec4(push, 0.0);
    lineRecord.moment[best] = vec4(mom, 0.0);
  }
#endif
  if (bestCos >= kMergeCos) {
    c.normal[best] = vec4(n, total);
    c.velocity[best] = vec4(vc, dot3(n, x));
    c.body[best] = body;
  } else {
    c.normal[best].w = total;
    c.velocity[best] = vec4(vc, max(c.velocity[best].w, dot3(c.normal[best].xyz, x)));
  }
}

// Coulomb friction on positions for one contact surface (the CPU twin: applyPositionFriction in
// include/drape/collision/response.hpp): the substep's tangential displacement relative to the solid, if within
// mu_s times the correction, is undone (stick: returns true); beyond it, mu_d times the correction of it is.
bool applyPositionFriction(vec3 n, vec3 vc, float correction, vec2 mu, inout vec3 x, vec3 start, float h) {
  precise const vec3 disp = (x - start) - h * vc;
  precise const vec3 dispT = disp - dot3(n, disp) * n;
  precise const float slip = length3(dispT);
  if (slip <= mu.x * correction) {
    precise const vec3 stuck = x - dispT;
    x = stuck;
    return true;
  }
  precise const float undo = min(1.0, mu.y * correction / slip);
  precise const vec3 slid = x - undo * dispT;
  x = slid;
  return false;
}

// The point nearest to y0 in {y : n_k . y >= b_k} for up to three half-spaces (the CPU twin: nearestInHalfSpaces
// in include/drape/collision/response.hpp): the nearest feasible point among the projections onto every subset of
// the planes, within kReach times the total violation (or minReach); else the least-squares compromise from
// `fallback` along the directions the planes determine well (leastSquaresCompromise).
const float kReach = DRAPE_REACH;

// symmetricEigen3's twin: cyclic Jacobi rotations, a[row][column]; a ends diagonal, v's columns its eigenvectors.
void symmetricEigen3(inout float a[3][3], out float v[3][3]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) v[i][j] = i == j ? 1.0 : 0.0;
  for (int sweep = 0; sweep < DRAPE_EIGEN_SWEEPS; ++sweep)
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        const float apq = a[p][q];
        precise const float negligible = DRAPE_EIGEN_NEGLIGIBLE * (abs(a[p][p]) + abs(a[q][q]));
        if (abs(apq) <= negligible) continue;
        precise const float theta = (a[q][q] - a[p][p]) / (2.0 * apq);
        precise const float t = (theta >= 0.0 ? 1.0 : -1.0) / (abs(theta) + sqrt(theta * theta + 1.0));
        precise const float c = 1.0 / sqrt(t * t + 1.0);
        precise const float sn = t * c;
        for (int k = 0; k < 3; ++k) {
          const float akp = a[k][p], akq = a[k][q];
          precise const float np = c * akp - sn * akq, nq = sn * akp + c * akq;
          a[k][p] = np;
          a[k][q] = nq;
        }
        for (int k = 0; k < 3; ++k) {
          const float apk = a[p][k], aqk = a[q][k];
          precise const float np = c * apk - sn * aqk, nq = sn * apk + c * aqk;
          a[p][k] = np;
          a[q][k] = nq;
        }
        for (int k = 0; k < 3; ++k) {
          const float vkp = v[k][p], vkq = v[k][q];
          precise const float np = c * vkp - sn * vkq, nq = sn * vkp + c * vkq;
          v[k][p] = np;
          v[k][q] = nq;
        }
      }
}

// leastSquaresMove's twin: one pass of the compromise from y, over the planes y violates; one or two planes in
// closed form (p + q and p - q, eigenvalues |p + q|^2 / 2 and |p - q|^2 / 2), three by Jacobi rotations.
vec3 leastSquaresMove(vec3 n[DRAPE_CONTACT_SLOTS], float b[DRAPE_CONTACT_SLOTS], int count, vec3 y, float weakest) {
  int violated = 0;
  int which[DRAPE_CONTACT_SLOTS];
  float r[DRAPE_CONTACT_SLOTS];
  for (int k = 0; k < count; ++k) {
    precise const float rk = b[k] - dot3(n[k], y);
    if (rk > 0.0) {
      which[violated] = k;
      r[violated] = rk;
      ++violated;
    }
  }
  if (violated == 0) return vec3(0.0);
  if (violated == 1) {
    const vec3 p = n[which[0]];
    precise const float length2 = dot3(p, p);
    precise const vec3 along = (r[0] / length2) * p;
    return length2 >= weakest ? along : vec3(0.0);
  }
  precise vec3 move = vec3(0.0);
  if (violated == 2) {
    const vec3 p = n[which[0]], q = n[which[1]];
    precise const vec3 sum = p + q, difference = p - q;
    precise const float sum2 = dot3(sum, sum), difference2 = dot3(difference, difference);
    if (sum2 >= 2.0 * weakest) move = move + ((r[0] + r[1]) / sum2) * sum;
    if (difference2 >= 2.0 * weakest) move = move + ((r[0] - r[1]) / difference2) * difference;
    return move;
  }
  float a[3][3] = float[3][3](float[3](0.0, 0.0, 0.0), float[3](0.0, 0.0, 0.0), float[3](0.0, 0.0, 0.0));
  float v[3][3];
  precise vec3 g = vec3(0.0);
  for (int m = 0; m < violated; ++m) {
    const vec3 nk = n[which[m]];
    g = g + r[m] * nk;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        precise const float aij = a[i][j] + nk[i] * nk[j];
        a[i][j] = aij;
      }
  }
  symmetricEigen3(a, v);
  for (int i = 0; i < 3; ++i) {
    if (!(a[i][i] >= weakest)) continue;
    const vec3 e = vec3(v[0][i], v[1][i], v[2][i]);
    precise const float along = dot3(e, g) / a[i][i];
    move = move + along * e;
  }
  return move;
}

// leastSquaresCompromise's twin: DRAPE_LEAST_SQUARES_PASSES passes of leastSquaresMove, the cut at 1 / reach^2.
vec3 leastSquaresCompromise(vec3 n[DRAPE_CONTACT_SLOTS], float b[DRAPE_CONTACT_SLOTS], int count, vec3 from,
                            float reach) {
  precise const float weakest = 1.0 / (reach * reach);
  vec3 y = from;
  for (int pass = 0; pass < DRAPE_LEAST_SQUARES_PASSES; ++pass) {
    precise const vec3 next = y + leastSquaresMove(n, b, count, y, weakest);
    y = next;
  }
  return y;
}

bool feasibleIn(vec3 n[DRAPE_CONTACT_SLOTS], float b[DRAPE_CONTACT_SLOTS], int count, vec3 y) {
  for (int k = 0; k < count; ++k) {
    precise const float bound = b[k] - DRAPE_FEASIBLE_SLACK * max(1.0, abs(b[k]));
    if (dot3(n[k], y) < bound) return false;
  }
  return true;
}

// halfSpaceViolation's twin: how far y0 is outside the half-spaces, summed.
float halfSpaceViolation(vec3 n[DRAPE_CONTACT_SLOTS], float b[DRAPE_CONTACT_SLOTS], int count, vec3 y0) {
  precise float violation = 0.0;
  for (int k = 0; k < count; ++k) violation = violation + max(b[k] - dot3(n[k], y0), 0.0);
  return violation;
}

// nearestOnPlanes's twin: the nearest feasible point to y0 among the projections onto every subset of the planes,
// within `reach`; false where there is none.
bool nearestOnPlanes(vec3 n[DRAPE_CONTACT_SLOTS], float b[DRAPE_CONTACT_SLOTS], int count, vec3 y0, float reach,
                     out vec3 best) {
  precise const float reach2 = reach * reach;
  best = y0;
  bool found = false;
  float bestDist = 0.0;
  vec3 candidate[7];
  int candidates = 0;
  for (int k = 0; k < count; ++k) {
    precise const vec3 y = y0 + (b[k] - dot3(n[k], y0)) * n[k];
    candidate[candidates++] = y;
  }
  for (int j = 0; j < count; ++j)
    for (int k = j + 1; k < count; ++k) {  // the line where planes j and k meet
      precise const float ab = dot3(n[j], n[k]);
      precise const float det = 1.0 - ab * ab;
      if (det < DRAPE_PARALLEL_PLANES) continue;
      precise const float ra = b[j] - dot3(n[j], y0), rb = b[k] - dot3(n[k], y0);
      precise const vec3 y = (y0 + ((ra - ab * rb) / det) * n[j]) + ((rb - ab * ra) / det) * n[k];
      candidate[candidates++] = y;
    }
  if (count == 3) {  // the corner where all three meet: Gaussian elimination with partial pivoting
    precise const float d = n[0].x * (n[1].y * n[2].z - n[1].z * n[2].y) -
                            n[1].x * (n[0].y * n[2].z - n[0].z * n[2].y) +
                            n[2].x * (n[0].y * n[1].z - n[0].z * n[1].y);
    if (abs(d) > DRAPE_CORNER_DETERMINANT) {
      vec4 m[3] = vec4[3](vec4(n[0], b[0]), vec4(n[1], b[1]), vec4(n[2], b[2]));
      for (int col = 0; col < 3; ++col) {
        int pivot = col;
        for (int r = col + 1; r < 3; ++r)
          if (abs(m[r][col]) > abs(m[pivot][col])) pivot = r;
        const vec4 t = m[col];
        m[col] = m[pivot];
        m[pivot] = t;
        for (int r = col + 1; r < 3; ++r) {
          precise const float f = m[r][col] / m[col][col];
          precise const vec4 row = m[r] - f * m[col];
          m[r] = row;
        }
      }
      precise const float z = m[2].w / m[2].z;
      precise const float yv = (m[1].w - m[1].z * z) / m[1].y;
      precise const float xv = (m[0].w - (m[0].y * yv + m[0].z * z)) / m[0].x;
      candidate[candidates++] = vec3(xv, yv, z);
    }
  }
  for (int c = 0; c < candidates; ++c) {
    precise const vec3 d = candidate[c] - y0;
    const float dist = dot3(d, d);
    if ((!found || dist < bestDist) && dist <= reach2 && feasibleIn(n, b, count, candidate[c]))
      best = candidate[c], bestDist = dist, found = true;
  }
  return found;
}

vec3 nearestInHalfSpaces(vec3 n[DRAPE_CONTACT_SLOTS], float b[DRAPE_CONTACT_SLOTS], int count, vec3 y0,
                         vec3 fallback, float minReach) {
  if (feasibleIn(n, b, count, y0)) return y0;
  precise const float reach = max(kReach * halfSpaceViolation(n, b, count, y0), minReach);
  vec3 best;
  if (nearestOnPlanes(n, b, count, y0, reach, best)) return best;
  return leastSquaresCompromise(n, b, count, fallback, DRAPE_REACH);
}

// placeSettlePoint's twin: where a vertex whose exact point `to` the fields judged goes (docs/design.md §16,
// "Exact points tested"): `to` where every plane it lies on is backed, the compromise cut at 1/kRefusedReach^2
// where some is, else the first fraction of the segment from `from` that every field leaves clear (`to` where
// not even it is).
vec3 placeSettlePoint(vec3 from, vec3 to, uint planes, uint backed, uint clear, vec3 n[DRAPE_CONTACT_SLOTS],
                      float b[DRAPE_CONTACT_SLOTS], int count, vec3 fallback) {
  if ((backed & planes) == planes) return to;
  if (backed != 0u) return leastSquaresCompromise(n, b, count, fallback, DRAPE_REFUSED_REACH);
  if (((clear >> uint(DRAPE_SEGMENT_FRACTIONS - 1)) & 1u) == 0u) return to;
  precise const float f = float(findLSB(clear) + 1) / float(DRAPE_SEGMENT_FRACTIONS);
  precise const vec3 q = from + f * (to - from);
  return q;
}


// The solid's field, packed by drape::gpu::packShape (include/drape/gpu/shapes.hpp).
layout(location = DRAPE_U_SHAPE) uniform vec4 shape[5];

// The signed distance of the solid's field at x and its gradient, for the shape the kernel is compiled for
// (DRAPE_SHAPE). Each is the twin of Sdf<Shape, S>::operator() in include/drape/sdf/shapes.hpp or convex.hpp,
// step for step.
#if DRAPE_SHAPE == DRAPE_SHAPE_PLANE
// shape[0] = (outward normal, offset): phi = n . x - offset.
float sdf(vec3 x, out vec3 gradient) {
  gradient = shape[0].xyz;
  precise float phi = dot3(shape[0].xyz, x) - shape[0].w;
  return phi;
}
#elif DRAPE_SHAPE == DRAPE_SHAPE_SPHERE
// shape[0] = (centre, radius): phi = |x - centre| - radius, gradient +z at the centre itself.
float sdf(vec3 x, out vec3 gradient) {
  precise const vec3 d = x - shape[0].xyz;
  precise const float len = length3(d);
  gradient = len > 0.0 ? d / len : vec3(0.0, 0.0, 1.0);
  precise float phi = len - shape[0].w;
  return phi;
}
#elif DRAPE_SHAPE == DRAPE_SHAPE_BOX
// shape[0].xyz = centre; shape[1..3] = the rows of the world-to-box rotation, with the half extents in w.
float sdf(vec3 x, out vec3 gradient) {
  const vec3 r0 = shape[1].xyz, r1 = shape[2].xyz, r2 = shape[3].xyz;
  const vec3 half_ = vec3(shape[1].w, shape[2].w, shape[3].w);
  precise const vec3 q = rotate(r0, r1, r2, x - shape[0].xyz);
  precise const vec3 excess = abs(q) - half_;
  const vec3 outside = max(excess, vec3(0.0));
  precise const float outsideLen = length3(outside);
  vec3 g;
  float phi;
  if (outsideLen > 0.0) {
    precise const vec3 gg = (outside * sign(q)) / outsideLen;
    g = gg;
    phi = outsideLen;
  } else {  // inside: the nearest face wins (the first on a tie, as Eigen's maxCoeff)
    int k = 0;
    if (excess.y > excess[k]) k = 1;
    if (excess.z > excess[k]) k = 2;
    phi = excess[k];
    g = vec3(0.0);
    g[k] = q[k] < 0.0 ? -1.0 : 1.0;
  }
  gradient = rotateBack(r0, r1, r2, g);
  return phi;
}
#elif DRAPE_SHAPE == DRAPE_SHAPE_CAPSULE
// shape[0] = (centre, half height), shape[1] = (unit axis, radius), shape[2].xyz = a unit vector orthogonal to
// the axis (Eigen's unitOrthogonal, computed once on the CPU): the gradient on the core segment itself.
float sdf(vec3 x, out vec3 gradient) {
  const vec3 axis = shape[1].xyz;
  const float halfHeight = shape[0].w;
  precise const vec3 r = x - shape[0].xyz;
  const float t = clamp(dot3(r, axis), -halfHeight, halfHeight);
  precise const vec3 d = r - t * axis;
  precise const float len = length3(d);
  gradient = len > 0.0 ? d / len : shape[2].xyz;
  precise float phi = len - shape[1].w;
  return phi;
}
#elif DRAPE_SHAPE == DRAPE_SHAPE_CYLINDER
// shape[0] = (centre, radius), shape[1..3] = the rows of the world-to-cylinder rotation, half height in
// shape[1].w. The 2D field of the (radial, axial) half-plane: outside the rim's quadrant |(dr, dz)|, else the
// larger of dr and dz.
float sdf(vec3 x, out vec3 gradient) {
  const vec3 r0 = shape[1].xyz, r1 = shape[2].xyz, r2 = shape[3].xyz;
  const float radius = shape[0].w, halfHeight = shape[1].w;
  precise const vec3 q = rotate(r0, r1, r2, x - shape[0].xyz);
  precise const float r2sum = q.x * q.x + q.y * q.y;
  precise const float rr = sqrt(r2sum);
  float ux = 1.0, uy = 0.0;
  if (r2sum >= 1.17549435e-38) {  // FLT_MIN: on (or subnormally near) the axis every radial direction will do
    precise const float a = q.x / rr, b = q.y / rr;
    ux = a;
    uy = b;
  }
  const float sz = q.z < 0.0 ? -1.0 : 1.0;
  precise const float dr = rr - radius;
  precise const float dz = abs(q.z) - halfHeight;
  vec3 g;
  float phi;
  if (dr > 0.0 && dz > 0.0) {
    precise const float p = sqrt(dr * dr + dz * dz);
    precise const vec3 gg = vec3(dr * ux / p, dr * uy / p, dz * sz / p);
    phi = p;
    g = gg;
  } else if (dr == 0.0 && dz == 0.0) {
    phi = 0.0;
    const float c = sqrt(0.5);
    g = vec3(c * ux, c * uy, c * sz);
  } else if (dr >= dz) {
    phi = dr;
    g = vec3(ux, uy, 0.0);
  } else {
    phi = dz;
    g = vec3(0.0, 0.0, sz);
  }
  gradient = rotateBack(r0, r1, r2, g);
  return phi;
}
#elif DRAPE_SHAPE == DRAPE_SHAPE_GRID
// A distance grid built from a mesh (the CPU twins: Sdf<MeshShape, S> and GridSampler in
// include/drape/sdf/grid.hpp): shape[0] = (centre, cell size), shape[1..3] = the rows of the world-to-mesh
// rotation with the grid's lower corner in w, shape[4] = (1 / cell size, node counts along x, y, z); the nodes
// (normal, distance), x fastest, in their own buffer. Trilinear inside the grid; outside, the distance to the
// grid's box combined with the distance at the nearest point of the box.
layout(std430, binding = DRAPE_B_SHAPE_DATA) readonly buffer GridNodes { vec4 nodes[]; };

float sdf(vec3 x, out vec3 gradient) {
  const vec3 r0 = shape[1].xyz, r1 = shape[2].xyz, r2 = shape[3].xyz;
  const vec3 lower = vec3(shape[1].w, shape[2].w, shape[3].w);
  const float cellSize = shape[0].w, invCellSize = shape[4].x;
  const ivec3 count = ivec3(shape[4].yzw);
  precise const vec3 q = rotate(r0, r1, r2, x - shape[0].xyz);
  precise const vec3 u = (q - lower) * invCellSize;  // in cells from node (0, 0, 0)
  ivec3 cell;
  vec3 t, excess;  // excess: how far q lies beyond the grid's box along each axis (m), 0 inside
  for (int a = 0; a < 3; ++a) {
    const float c = clamp(u[a], 0.0, float(count[a] - 1));
    precise const float beyond = (u[a] - c) * cellSize;
    excess[a] = beyond;
    cell[a] = min(int(c), count[a] - 2);
    t[a] = c - float(cell[a]);
  }
  const int sy = count.x, sz = count.x * count.y;
  const int n0 = cell.z * sz + cell.y * sy + cell.x;
  // x, then y, then z: seven lerps of (normal, distance).
  precise const vec4 c00 = nodes[n0] + t.x * (nodes[n0 + 1] - nodes[n0]);
  precise const vec4 c10 = nodes[n0 + sy] + t.x * (nodes[n0 + sy + 1] - nodes[n0 + sy]);
  precise const vec4 c01 = nodes[n0 + sz] + t.x * (nodes[n0 + sz + 1] - nodes[n0 + sz]);
  precise const vec4 c11 = nodes[n0 + sz + sy] + t.x * (nodes[n0 + sz + sy + 1] - nodes[n0 + sz + sy]);
  precise const vec4 c0 = c00 + t.y * (c10 - c00);
  precise const vec4 c1 = c01 + t.y * (c11 - c01);
  precise const vec4 v = c0 + t.z * (c1 - c0);
  const float g = v.w;
  vec3 n = v.xyz;
  const float len = length3(n);
  n = len > 0.0 ? n / len : vec3(0.0, 0.0, 1.0);  // node normals that cancel exactly: any unit vector
  const float e = length3(excess);
  if (e == 0.0) {
    gradient = rotateBack(r0, r1, r2, n);
    return g;
  }
  // Outside: the gradient of sqrt(e^2 + g^2), with g's gradient along the box face (the clamped axes drop out).
  for (int a = 0; a < 3; ++a)
    if (excess[a] != 0.0) n[a] = 0.0;
  precise const float phi = g > 0.0 ? sqrt(e * e + g * g) : g + e;
  precise const vec3 grad = excess + max(g, 0.0) * n;
  const float glen = length3(grad);
  gradient = rotateBack(r0, r1, r2, glen > 0.0 ? grad / glen : excess / e);
  return phi;
}

// The face search's view of the grid (the CPU twins: Sdf<MeshShape>::toCells, GridSampler::distanceAt and
// GridSampler::expand with CellPolynomial::expand in include/drape/sdf/grid_search.hpp).
ivec3 gridCount() { return ivec3(shape[4].yzw); }
float gridCellSize() { return shape[0].w; }

// Where x lies in the grid, in cells from node (0, 0, 0).
vec3 gridCells(vec3 x) {
  const vec3 lower = vec3(shape[1].w, shape[2].w, shape[3].w);
  precise const vec3 q = rotate(shape[1].xyz, shape[2].xyz, shape[3].xyz, x - shape[0].xyz);
  precise const vec3 u = (q - lower) * shape[4].x;
  return u;
}

// The distance alone at u (in cells): sdf()'s value without the gradient.
float gridDistanceAt(vec3 u) {
  const ivec3 count = gridCount();
  const float cellSize = gridCellSize();
  ivec3 cell;
  vec3 t;
  precise float excess2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const float c = clamp(u[a], 0.0, float(count[a] - 1));
    precise const float beyond = (u[a] - c) * cellSize;
    excess2 = excess2 + beyond * beyond;
    cell[a] = min(int(c), count[a] - 2);
    t[a] = c - float(cell[a]);
  }
  const int sy = count.x, sz = count.x * count.y;
  const int n0 = cell.z * sz + cell.y * sy + cell.x;
  precise const float c00 = nodes[n0].w + t.x * (nodes[n0 + 1].w - nodes[n0].w);
  precise const float c10 = nodes[n0 + sy].w + t.x * (nodes[n0 + sy + 1].w - nodes[n0 + sy].w);
  precise const float c01 = nodes[n0 + sz].w + t.x * (nodes[n0 + sz + 1].w - nodes[n0 + sz].w);
  precise const float c11 = nodes[n0 + sz + sy].w + t.x * (nodes[n0 + sz + sy + 1].w - nodes[n0 + sz + sy].w);
  precise const float c0 = c00 + t.y * (c10 - c00);
  precise const float c1 = c01 + t.y * (c11 - c01);
  precise const float g = c0 + t.z * (c1 - c0);
  if (excess2 == 0.0) return g;
  const float e = sqrt(excess2);
  precise const float outside = g > 0.0 ? sqrt(e * e + g * g) : g + e;
  return outside;
}

// A cell's trilinear polynomial expanded about t (in cells from its lowest node): value + slope . d + xy dx dy +
// xz dx dz + yz dy dz + xyz dx dy dz, exactly; its nodes v[i + 2j + 4k].
struct CellPolynomial {
  float value;
  vec3 slope;
  float xy, xz, yz, xyz;
  float lowestNode;
  float node[8];
};

CellPolynomial gridExpand(ivec3 cell, vec3 t) {
  const ivec3 count = gridCount();
  const int sy = count.x, sz = count.x * count.y;
  const int n0 = cell.z * sz + cell.y * sy + cell.x;
  CellPolynomial p;
  for (int k = 0; k < 8; ++k) p.node[k] = nodes[n0 + ((k & 1) != 0 ? 1 : 0) + ((k & 2) != 0 ? sy : 0) + ((k & 4) != 0 ? sz : 0)].w;
  float ax[4], dx[4];
  for (int jk = 0; jk < 4; ++jk) {
    precise const float dd = p.node[2 * jk + 1] - p.node[2 * jk];
    precise const float aa = p.node[2 * jk] + t.x * dd;
    dx[jk] = dd, ax[jk] = aa;
  }
  float by[2], dyk[2], dxb[2], dxy[2];
  for (int k = 0; k < 2; ++k) {
    precise const float dy = ax[2 * k + 1] - ax[2 * k];
    precise const float b = ax[2 * k] + t.y * dy;
    precise const float dxyk = dx[2 * k + 1] - dx[2 * k];
    precise const float dxbk = dx[2 * k] + t.y * dxyk;
    dyk[k] = dy, by[k] = b, dxy[k] = dxyk, dxb[k] = dxbk;
  }
  precise const float value = by[0] + t.z * (by[1] - by[0]);
  precise const vec3 slope = vec3(dxb[0] + t.z * (dxb[1] - dxb[0]), dyk[0] + t.z * (dyk[1] - dyk[0]), by[1] - by[0]);
  precise const float xy = dxy[0] + t.z * (dxy[1] - dxy[0]);
  precise const float xz = dxb[1] - dxb[0], yz = dyk[1] - dyk[0], xyz = dxy[1] - dxy[0];
  p.value = value, p.slope = slope, p.xy = xy, p.xz = xz, p.yz = yz, p.xyz = xyz;
  float lowest = p.node[0];
  for (int k = 1; k < 8; ++k) lowest = min(lowest, p.node[k]);
  p.lowestNode = lowest;
  return p;
}
#elif DRAPE_SHAPE == DRAPE_SHAPE_HULL
// A convex hull (the twin of Sdf<ConvexHull, S>): shape[0] = (centre, nearSurface), shape[1..3] = the rows of the
// world-to-hull rotation, with the face count in shape[1].w; the faces and edges in the shape-data buffer
// (packHull in gpu/shapes.hpp): per face two vec4s, (normal, offset) and (first edge, edge count); then per edge
// three, (start, 1 / |delta|^2), (delta, twin edge or -1), (inward, 0). Inside, the largest signed distance to a
// face plane; outside, the distance to the closest point, found in the face, edge or vertex region that holds q.
layout(std430, binding = DRAPE_B_SHAPE_DATA) readonly buffer HullData { vec4 hullData[]; };

vec3 hullOutside(vec3 r0, vec3 r1, vec3 r2, vec3 delta, float distance, vec3 frontNormal) {
  precise const vec3 g = distance > shape[0].w ? delta / distance : frontNormal;
  return rotateBack(r0, r1, r2, g);
}

float sdf(vec3 x, out vec3 gradient) {
  const vec3 r0 = shape[1].xyz, r1 = shape[2].xyz, r2 = shape[3].xyz;
  const int faces = int(shape[1].w);
  const int edgeBase = 2 * faces;
  const float slack = shape[0].w;
  precise const vec3 q = rotate(r0, r1, r2, x - shape[0].xyz);
  int front = 0;
  precise float frontDistance = dot3(hullData[0].xyz, q) - hullData[0].w;
  for (int f = 1; f < faces; ++f) {
    const vec4 plane = hullData[2 * f];
    precise const float s = dot3(plane.xyz, q) - plane.w;
    if (s > frontDistance) front = f, frontDistance = s;
  }
  const vec3 frontNormal = hullData[2 * front].xyz;
  if (frontDistance <= 0.0) {
    gradient = rotateBack(r0, r1, r2, frontNormal);
    return frontDistance;
  }
  float bestSq = uintBitsToFloat(0x7F800000u);  // infinity
  vec3 bestDelta = vec3(0.0);
  for (int f = 0; f < faces; ++f) {
    const vec4 plane = hullData[2 * f];
    precise const float s = dot3(plane.xyz, q) - plane.w;
    precise const float beyond = s - slack;
    if (!(s > 0.0) || (s > slack && beyond * beyond >= bestSq)) continue;
    const int first = int(hullData[2 * f + 1].x), edgeCount = int(hullData[2 * f + 1].y);
    bool inPolygon = true;
    for (int k = 0; k < edgeCount; ++k) {
      const int e = edgeBase + 3 * (first + k);
      const vec4 start = hullData[e], delta = hullData[e + 1], inward = hullData[e + 2];
      precise const vec3 r = q - start.xyz;
      if (dot3(r, inward.xyz) >= 0.0) continue;
      inPolygon = false;
      precise const float along = dot3(r, delta.xyz) * start.w;
      precise const vec3 d = r - clamp(along, 0.0, 1.0) * delta.xyz;
      const float dSq = dot3(d, d);
      const int twin = int(delta.w);
      if (along > 0.0 && along < 1.0 && twin >= 0) {
        const int t = edgeBase + 3 * twin;
        precise const vec3 rt = q - hullData[t].xyz;
        if (dot3(rt, hullData[t + 2].xyz) <= 0.0) {
          const float distance = sqrt(dSq);
          gradient = hullOutside(r0, r1, r2, d, distance, frontNormal);
          return distance;
        }
      }
      if (dSq < bestSq) bestSq = dSq, bestDelta = d;
    }
    if (inPolygon) {
      gradient = rotateBack(r0, r1, r2, plane.xyz);
      return s;
    }
  }
  const float distance = sqrt(bestSq);
  gradient = hullOutside(r0, r1, r2, bestDelta, distance, frontNormal);
  return distance;
}
#endif

// Whether the field is convex (every built-in solid; not a grid built from a mesh, which may be non-convex):
// the face search then bounds the field by its tangent planes (Kelley), else it descends (projected gradient).
#if DRAPE_SHAPE == DRAPE_SHAPE_GRID
#define DRAPE_CONVEX 0
#else
#define DRAPE_CONVEX 1
#endif
// The field's Lipschitz constant (lipschitzOf): a grid's is stated, every other field is a distance.
#if DRAPE_CONVEX
#define DRAPE_LIPSCHITZ 1.0
#else
#define DRAPE_LIPSCHITZ DRAPE_GRID_LIPSCHITZ
#endif
