// docs/design.md §6, phase 2, per vertex (the CPU twin: gatherContactForces with pinchSupport, pinchingSlot, spacerOf,
// unresolvedOverlap, contactPoint, addWrench, addExchange, ownShare, addSplitExchange and gatherPropagatedImpulse in
// include/drape/coupling/contact_forces.hpp): what each contact vertex passes to the coupled bodies it touches, by
// the chosen estimator (sub-force, energy-based, impulse-based), reversed onto the body at the contact's line;
// each entry is written to the vertex's own BodyPush slots (one per contact slot at most), so nothing is summed
// here and no atomics are needed. body_sums.comp then sums them per body in a fixed order.
//
// A vertex whose slots all belong to one body passes that body its whole velocity change along the slot that
// corrected it most (an exchange, which shareExchanges may scale); a vertex between two bodies, or a body and a
// fixed solid, passes each body the part of its change that body's slot made (ownShare), as an exchange of that
// part, unless it is pinched against a fixed solid or another body facing the body, which then holds the body
// through it (a pinch), and is listed as a spacer for the rigid world (appended: the solver sorts them). With the
// impulse estimator and propagation, a vertex not in contact passes what propagation gave it to the body of its
// first neighbour in contact with one.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_VELOCITIES) readonly buffer Velocities { vec4 v[]; };
layout(std430, binding = DRAPE_B_START) readonly buffer Start { vec4 x0[]; };
layout(std430, binding = DRAPE_B_V_START) readonly buffer VStart { vec4 vStart[]; };
layout(std430, binding = DRAPE_B_V_PRE) readonly buffer VPre { vec4 vPre[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(std430, binding = DRAPE_B_LINES) readonly buffer LinesBuffer { Lines lines[]; };
layout(std430, binding = DRAPE_B_NEIGHBOUR_OFFSETS) readonly buffer NeighbourOffsets { uint neighbourOffsets[]; };
layout(std430, binding = DRAPE_B_NEIGHBOURS) readonly buffer Neighbours { uint neighbours[]; };
layout(std430, binding = DRAPE_B_BODIES) readonly buffer Bodies { Body bodies[]; };
layout(std430, binding = DRAPE_B_PUSHES) writeonly buffer Pushes { BodyPush pushes[]; };
// spacers[0] is the header: vertex counts the records after it, body is their room.
layout(std430, binding = DRAPE_B_SPACERS) buffer Spacers { SpacerRecord spacers[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_STEP) uniform float h;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_ESTIMATOR) uniform int estimator;  // DRAPE_ESTIMATOR_*
layout(location = DRAPE_U_NORMAL_ONLY) uniform uint normalOnly;
layout(location = DRAPE_U_PROPAGATED) uniform uint propagated;

const int kDirect = DRAPE_PUSH_DIRECT, kExchange = DRAPE_PUSH_EXCHANGE, kPinch = DRAPE_PUSH_PINCH;
const float kPinchRate = DRAPE_PINCH_RATE;  // share of a pinch's overlap its support undoes per substep

BodyPush entries[DRAPE_CONTACT_SLOTS];
int entryCount = 0;

vec3 crossOf(vec3 a, vec3 b) {
  precise const vec3 c = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
  return c;
}

// Where slot k of vertex `at` pushes its body, from the body's centre (contactPoint).
vec3 contactPoint(uint at, int k, Body body) {
  const vec3 n = contacts[at].normal[k].xyz;
  precise const vec3 touch = (x[at].xyz - thickness * n) - body.centre.xyz;
  const vec3 push = lines[at].push[k].xyz, moment = lines[at].moment[k].xyz;
  precise const float along = dot3(push, n);
  if (!(along > DRAPE_LINE_MIN_ALONG)) return touch;
  precise const vec3 r = crossOf(n, moment / along) + dot3(touch, n) * n;
  return r;
}

// A push f on slot k's body from vertex `at` (addWrench), as entry of the given kind; vertexSide for an exchange.
void addEntry(uint at, int k, vec3 f, int kind, float vertexSide) {
  const Contact c = contacts[at];
  const int b = c.body[k];
  const vec3 n = c.normal[k].xyz;
  // Without friction a contact can only push along its normal.
  if (normalOnly != 0u || (c.friction[k].x == 0.0 && c.friction[k].y == 0.0)) f = dot3(f, n) * n;
  const vec3 r = contactPoint(at, k, bodies[b]);
  entries[entryCount].force = vec4(f, vertexSide);
  entries[entryCount].torque = vec4(crossOf(r, f), 0.0);
  entries[entryCount].body = b;
  entries[entryCount].kind = kind;
  ++entryCount;
}

// The overlap the projections could not resolve for slot k of vertex i (unresolvedOverlap).
float unresolvedOverlap(uint i, int k) {
  const Contact c = contacts[i];
  const vec3 xi = x[i].xyz, n = c.normal[k].xyz;
  precise float overlap = max(c.velocity[k].w - dot3(n, xi), 0.0);
  for (int j = 0; j < int(c.slots.x); ++j)
    if (j != k)
      overlap = overlap + max(c.velocity[j].w - dot3(c.normal[j].xyz, xi), 0.0) * max(-dot3(c.normal[j].xyz, n), 0.0);
  return overlap;
}

// What share of the normal part of vertex i's change dv along slot k's normal was slot k's (ownShare): a_k over
// n_k . dv, with the a_j solving the slots' Gram system G a = (n_j . dv), padded to 3 x 3 (Cramer's rule); 1 where
// the normals nearly span less than their count.
float ownShare(uint i, int k, vec3 dv) {
  const Contact c = contacts[i];
  precise const float along = dot3(c.normal[k].xyz, dv);
  if (!(along > 0.0)) return 0.0;
  mat3 g = mat3(1.0);
  vec3 b = vec3(0.0);
  const int count = int(c.slots.x);
  for (int j = 0; j < count; ++j) {
    b[j] = dot3(c.normal[j].xyz, dv);
    for (int l = 0; l < count; ++l) g[l][j] = dot3(c.normal[j].xyz, c.normal[l].xyz);
  }
  const float det = determinant(g);
  if (!(det > DRAPE_SPLIT_GRAM_MIN)) return 1.0;
  g[k] = b;
  return max(determinant(g) / det, 0.0) / along;
}

// The slot of vertex i that pinches it against slot k's body: a fixed solid's facing it before another body's;
// -1 where there is none (pinchingSlot).
int pinchingSlot(uint i, int k) {
  const Contact c = contacts[i];
  const vec3 n = c.normal[k].xyz;
  int fixedSlot = -1, bodySlot = -1;  // (`fixed` is reserved in GLSL)
  for (int j = 0; j < int(c.slots.x); ++j) {
    if (j == k || !(dot3(c.normal[j].xyz, n) < DRAPE_PINCH_OPPOSING_COS)) continue;
    if (c.body[j] < 0) fixedSlot = j;
    else if (c.body[j] != c.body[k]) bodySlot = j;
  }
  return fixedSlot >= 0 ? fixedSlot : bodySlot;
}

// Vertex i pinched between slot k's body and slot o's surface, as a spacer (spacerOf): each slot's plane lies a
// thickness out of its surface (velocity.w: where the vertex was placed along the normal).
void addSpacer(uint i, int k, int o) {
  const int at = atomicAdd(spacers[0].vertex, 1);
  if (at >= spacers[0].body) return;  // no room: the room is one record per contact slot of every vertex
  const Contact c = contacts[i];
  const vec3 xi = x[i].xyz, nk = c.normal[k].xyz, no = c.normal[o].xyz;
  precise const vec3 onBody = xi - (dot3(nk, xi) - c.velocity[k].w + thickness) * nk;
  precise const vec3 onOther = xi + ((DRAPE_SPACER_GAP - 1.0) * thickness - (dot3(no, xi) - c.velocity[o].w)) * no;
  spacers[1 + at] = SpacerRecord(vec4(onBody, 0.0), vec4(onOther, 0.0), vec4(no, 0.0), int(i), c.body[k], c.body[o], k);
}

mat3 inverseInertiaOf(Body body) {
  return transpose(mat3(body.inverseInertia[0].xyz, body.inverseInertia[1].xyz, body.inverseInertia[2].xyz));
}

// A vertex pinched between slot k's body and a surface facing it, a fixed solid or another body: the surface
// holds the body through it, with the pair's effective mass against another body (pinchSupport). Returns false
// when the vertex is not pinched.
bool pinchSupport(uint i, int k) {
  const Contact c = contacts[i];
  const vec3 n = c.normal[k].xyz;
  const int against = pinchingSlot(i, k);
  if (against < 0) return false;
  if (c.body[against] < c.body[k]) addSpacer(i, k, against);
  const Body body = bodies[c.body[k]];
  const vec3 r = contactPoint(i, k, body);
  const mat3 inverseInertia = inverseInertiaOf(body);
  vec3 wall = c.velocity[against].xyz, ro = vec3(0.0);
  float otherInverseMass = 0.0;
  mat3 otherInverseInertia = mat3(0.0);
  if (c.body[against] >= 0) {
    const Body other = bodies[c.body[against]];
    ro = contactPoint(i, against, other);
    precise const vec3 otherAt = other.linear.xyz + crossOf(other.angular.xyz, ro);
    wall = otherAt;
    otherInverseMass = other.centre.w;
    otherInverseInertia = inverseInertiaOf(other);
  }
  precise const vec3 bodyAt = body.linear.xyz + crossOf(body.angular.xyz, r);
  precise const float approach = dot3(bodyAt - wall, n) + kPinchRate * unresolvedOverlap(i, k) / h;
  const vec3 rn = crossOf(r, n), on = crossOf(ro, n);
  precise float kn = body.centre.w + dot3(rn, inverseInertia * rn);
  if (c.body[against] >= 0) kn = kn + (otherInverseMass + dot3(on, otherInverseInertia * on));
  if (!(approach > 0.0) || !(kn > 0.0)) {
    entries[entryCount].force = vec4(0.0);
    entries[entryCount].torque = vec4(0.0);
    entries[entryCount].body = c.body[k];
    entries[entryCount].kind = kPinch;
    ++entryCount;
    return true;
  }
  precise const float push = approach / (kn * h);  // N, on the body along -n
  precise vec3 force = -push * n;
  precise vec3 slide = bodyAt - v[i].xyz;
  slide = slide - dot3(slide, n) * n;
  const float speed = length3(slide);
  if (speed > 0.0 && normalOnly == 0u) {
    slide = slide / speed;
    const vec3 rt = crossOf(r, slide), ot = crossOf(ro, slide);
    precise float kt = body.centre.w + dot3(rt, inverseInertia * rt);
    if (c.body[against] >= 0) kt = kt + (otherInverseMass + dot3(ot, otherInverseInertia * ot));
    precise const float stop = speed / (kt * h);
    const vec2 mu = c.friction[k].xy;
    force = force - (stop <= mu.x * push ? stop : min(stop, mu.y * push)) * slide;
  }
  addEntry(i, k, force, kPinch, 0.0);
  return true;
}

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  for (int e = 0; e < DRAPE_CONTACT_SLOTS; ++e) {
    entries[e].force = vec4(0.0);
    entries[e].torque = vec4(0.0);
    entries[e].body = -1;
    entries[e].kind = kDirect;
    entries[e].slot = -1;
  }
  const Contact c = contacts[i];
  const int slots = int(c.slots.x);
  const float w = x[i].w;
  if (slots == 0) {
    // gatherPropagatedImpulse: the first neighbour in contact with a body takes what propagation gave i.
    precise const vec3 dv = v[i].xyz - vPre[i].xyz;
    if (propagated != 0u && w != 0.0 && dv != vec3(0.0)) {
      bool done = false;
      for (uint q = neighbourOffsets[i]; q < neighbourOffsets[i + 1u] && !done; ++q) {
        const uint j = neighbours[q];
        const Contact cj = contacts[j];
        for (int k = 0; k < int(cj.slots.x) && !done; ++k) {
          if (cj.body[k] < 0) continue;
          precise const float m = 1.0 / w;
          precise const vec3 f = -(m / h) * dv;
          addEntry(j, k, f, kExchange, dot3(f, f) / m);
          done = true;
        }
      }
    }
  } else {
    bool oneBody = true;
    int top = 0;  // the slot that corrected the vertex most
    for (int k = 1; k < slots; ++k) {
      oneBody = oneBody && c.body[k] == c.body[0];
      if (c.normal[k].w > c.normal[top].w) top = k;
    }
    precise const float m = 1.0 / w;
    const vec3 vi = v[i].xyz, pre = vPre[i].xyz, start = vStart[i].xyz;
    precise const vec3 dv = vi - pre;                       // what the contacts did
    precise const vec3 otherForce = m * (pre - start) / h;  // constraints and gravity this substep
    precise vec3 energyForce = vec3(0.0);
    if (estimator == DRAPE_ESTIMATOR_ENERGY) {
      precise const vec3 d = x[i].xyz - x0[i].xyz;
      precise const float d2 = dot3(d, d);
      precise const float work = 0.5 * m * (dot3(vi, vi) - dot3(start, start)) - dot3(otherForce, d);
      if (d2 > DRAPE_ENERGY_MIN_DISPLACEMENT2) energyForce = (work / d2) * d;
      precise const vec3 balance = m * (vi - start) / h - otherForce;
      const float cap = length3(balance);
      const float size = length3(energyForce);
      if (size > cap) energyForce = energyForce * (cap / size);
    }
    for (int k = 0; k < slots; ++k) {
      if (c.body[k] < 0) continue;
      if (slots > 1 && !oneBody && pinchSupport(i, k)) continue;
      if (oneBody && k != top) continue;
      const vec3 n = c.normal[k].xyz;
      precise vec3 onBody = vec3(0.0);
      if (estimator == DRAPE_ESTIMATOR_SUB_FORCE) {
        precise const float fn = dot3(otherForce, n);
        if (fn < 0.0) onBody = fn * n;
      } else if (estimator == DRAPE_ESTIMATOR_ENERGY) {
        onBody = oneBody ? -energyForce : -dot3(energyForce, n) * n;
      } else {
        precise const float dvn = dot3(dv, n);
        precise vec3 impulse = (dvn + unresolvedOverlap(i, k) / h) * n;
        if (oneBody) impulse = impulse + (dv - dvn * n);  // the tangential (friction) change
        onBody = -(m / h) * impulse;
      }
      if (oneBody) {
        addEntry(i, k, onBody, kExchange, dot3(onBody, onBody) / m);
        continue;
      }
      // One of several solids' (addSplitExchange): the slot's own share, as a vertex of that share of the mass.
      const float weight = ownShare(i, k, dv);
      if (!(weight > 0.0)) continue;
      precise const vec3 f = weight * onBody;
      addEntry(i, k, f, kExchange, dot3(f, f) / (weight * m));
      entries[entryCount - 1].torque.w = weight * dot3(dv, n);
      entries[entryCount - 1].slot = k;
    }
  }
  for (int e = 0; e < DRAPE_CONTACT_SLOTS; ++e) pushes[DRAPE_CONTACT_SLOTS * i + uint(e)] = entries[e];
}
