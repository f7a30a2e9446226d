// docs/design.md §4, the vertex pass (the CPU twin: projectVertexContactsAs in include/drape/collision/response.hpp)
// for one solid: a free vertex closer to the solid than the thickness (by more than the slack) moves out along the
// field's gradient to the thickness, and its contact is recorded for the response (recordContact): normal and
// correction, the solid's velocity at the placed point, its friction (and for a coupled body, the line its push acts
// on: the placed point). The substep's first pass (fresh) starts every vertex's record, so nothing is cleared. In a
// settle pass (pass >= 0) the dispatch does nothing unless the pass before found a contact, and a contact found marks
// this pass's flag: the CPU's loop that stops once a pass finds none, without reading anything back.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_CONTACTS) buffer Contacts { Contact contacts[]; };
layout(std430, binding = DRAPE_B_FLAGS) buffer Flags { uint flags[]; };
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

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  if (pass > 0 && flags[pass - 1] == 0u) return;
  const vec4 xi = x[i];
  bool found = false;
  // Outside the solid's box grown by the thickness, phi is beyond the thickness: no field evaluation (what the
  // CPU's broad phase leaves out).
  precise const vec3 low = boxLow - vec3(thickness), high = boxHigh + vec3(thickness);
  const bool near = all(greaterThanEqual(xi.xyz, low)) && all(lessThanEqual(xi.xyz, high));
  if (xi.w != 0.0 && near) {
    vec3 n;
    const float phi = sdf(xi.xyz, n);
    precise const float limit = thickness - slack;
    if (phi < limit) {
      precise const float dn = thickness - phi;
      precise const vec3 p = xi.xyz + dn * n;
      x[i] = vec4(p, xi.w);
      Contact c = fresh != 0u ? emptyContact() : contacts[i];
      const vec3 vc = solidVelocityAt(p, centre, linearVelocity, angularVelocity);
#if DRAPE_BODY
      lineRecord = lines[i];
      recordContact(c, p, n, dn, vc, friction, body, momentAbout(p, centre, n));
      lines[i] = lineRecord;
#else
      recordContact(c, p, n, dn, vc, friction, body, vec3(0.0));
#endif
      contacts[i] = c;
      found = true;
    }
  }
  if (!found && fresh != 0u) contacts[i].slots = uvec4(0u);
  if (found && pass >= 0) flags[pass] = 1u;
}
