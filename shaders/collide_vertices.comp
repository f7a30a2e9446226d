// docs/design.md §4, the vertex pass (the CPU twin: projectVertexContactsAs in include/drape/collision/response.hpp)
// for one solid: a free vertex closer to the solid than the thickness (by more than the slack) moves out along the
// field's gradient to the thickness, and its contact is recorded for the response (recordContact): normal and
// correction, the solid's velocity at the placed point, its friction (and for a coupled body, the line its push acts
// on: the placed point). The substep's first pass (fresh) starts every vertex's record, so nothing is cleared. In a
// settle pass (pass >= 0) a contact found writes this pass's dispatch command, which runs the next pass and this
// pass's settle (dispatchIndirect; the commands are cleared to no work): the CPU's loop that stops once a pass
// finds none, without reading anything back, and a pass with nothing to do costs no invocation.
// With continuous contact (docs/design.md §18; sweep.y > 0, the substep's first pass only), a vertex whose path
// relative to the solid is longer than the gate is first searched along it (sweepPoint in
// include/drape/collision/sweep.hpp); where it came within the thickness, the vertex goes to the thickness beyond
// the field's tangent plane there. That code is compiled only into the kernels of a scene with continuous contact
// (DRAPE_SWEEP): a uniform branch around it still costs where the driver runs both sides of a branch.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_CONTACTS) buffer Contacts { Contact contacts[]; };
layout(std430, binding = DRAPE_B_FLAGS) writeonly buffer Flags { uint commands[]; };  // x, y, z per settle pass
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_SOLID_CENTRE) uniform vec3 centre;
layout(location = DRAPE_U_SOLID_LINEAR) uniform vec3 linearVelocity;
layout(location = DRAPE_U_SOLID_ANGULAR) uniform vec3 angularVelocity;
layout(location = DRAPE_U_FRICTION) uniform vec2 friction;  // static, dynamic
#if DRAPE_BODY
layout(std430, binding = DRAPE_B_LINES) buffer LinesBuffer { Lines lines[]; };
layout(location = DRAPE_U_BODY) uniform int body;  // the coupled body this solid pushes
#else
const int body = -1;
#endif
layout(location = DRAPE_U_SLACK) uniform float slack;
layout(location = DRAPE_U_PASS) uniform int pass;
layout(location = DRAPE_U_FRESH) uniform uint fresh;
layout(location = DRAPE_U_BOX_LOW) uniform vec3 boxLow;
layout(location = DRAPE_U_BOX_HIGH) uniform vec3 boxHigh;
#if DRAPE_SWEEP
layout(std430, binding = DRAPE_B_START) readonly buffer Start { vec4 x0[]; };
layout(location = DRAPE_U_SWEEP) uniform vec2 sweep;  // the substep h and the gate squared; 0 (unset): no sweeps

// Conservative advancement along a -> b (sweepPoint): the first point within the thickness, false for none.
bool sweepPoint(vec3 a, vec3 b, out vec3 q, out vec3 n, out float phiHit) {
  precise const vec3 d = b - a;
  precise const float stride = DRAPE_LIPSCHITZ * length3(d);
  float t = 0.0;
  for (int k = 0; k < DRAPE_SWEEP_STEPS; ++k) {
    precise const vec3 at = a + t * d;
    vec3 g;
    const float phi = sdf(at, g);
    if (phi < thickness) {
      q = at, n = g, phiHit = phi;
      return t > 0.0 || phi >= 0.0;
    }
    precise const float advance = (phi - 0.5 * thickness) / stride;
    t = t + advance;
    if (!(t < 1.0)) break;
  }
  return false;
}
#endif

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  vec4 xi = x[i];
  bool found = false;
  Contact c;
  // Outside the solid's box grown by the thickness, phi is beyond the thickness: no field evaluation (what the
  // CPU's broad phase leaves out). A swept path is tested by its own box.
  precise const vec3 low = boxLow - vec3(thickness), high = boxHigh + vec3(thickness);
#if DRAPE_SWEEP
  if (sweep.y > 0.0 && xi.w != 0.0) {
    const vec3 s0 = x0[i].xyz;
    precise const vec3 from = s0 + sweep.x * solidVelocityAt(s0, centre, linearVelocity, angularVelocity);
    precise const vec3 path = xi.xyz - from;
    const bool pathNear = all(greaterThanEqual(max(from, xi.xyz), low)) && all(lessThanEqual(min(from, xi.xyz), high));
    if (dot3(path, path) > sweep.y && pathNear) {
      vec3 q, n;
      float phiHit;
      if (sweepPoint(from, xi.xyz, q, n, phiHit)) {
        precise const float beyond = phiHit + dot3(n, xi.xyz - q);  // the end against the tangent plane
        if (beyond < thickness) {
          precise const float dn = thickness - beyond;
          precise const vec3 p = xi.xyz + dn * n;
          xi.xyz = p;
          x[i] = xi;
          c = fresh != 0u ? emptyContact() : contacts[i];
#if DRAPE_BODY
          lineRecord = lines[i];  // read only for a vertex that records a contact
#endif
          const vec3 vc = solidContactVelocity(p, n, q, centre, linearVelocity, angularVelocity);
          // A coupled body's push acts on the line through the point where the path met the solid.
          recordContact(c, p, n, dn, vc, friction, body, momentAbout(q, centre, n));
          found = true;
        }
      }
    }
  }
#endif
  const bool near = all(greaterThanEqual(xi.xyz, low)) && all(lessThanEqual(xi.xyz, high));
  if (xi.w != 0.0 && near) {
    vec3 n;
    const float phi = sdf(xi.xyz, n);
    precise const float limit = thickness - slack;
    if (phi < limit) {
      precise const float dn = thickness - phi;
      precise const vec3 p = xi.xyz + dn * n;
      x[i] = vec4(p, xi.w);
      if (!found) {
        c = fresh != 0u ? emptyContact() : contacts[i];
#if DRAPE_BODY
        lineRecord = lines[i];
#endif
      }
      const vec3 vc = solidVelocityAt(p, centre, linearVelocity, angularVelocity);
      recordContact(c, p, n, dn, vc, friction, body, momentAbout(p, centre, n));
      found = true;
    }
  }
  if (found) {
    contacts[i] = c;
#if DRAPE_BODY
    lines[i] = lineRecord;
#endif
  }
  if (!found && fresh != 0u) contacts[i].slots = uvec4(0u);
  if (found && pass >= 0) {  // every writer writes the same command: this dispatch's size
    commands[3 * pass] = gl_NumWorkGroups.x;
    commands[3 * pass + 1] = 1u;
    commands[3 * pass + 2] = 1u;
  }
}
