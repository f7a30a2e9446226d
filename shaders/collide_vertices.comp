// DESIGN 4, the vertex pass (the CPU twin: projectVertexContactsAs in include/drape/collision/response.hpp): a
// free vertex closer to the solid than the thickness moves out along the field's gradient to the thickness, and
// its contact is recorded for the response: normal and correction, and the solid's velocity at the placed
// point. Every vertex writes its own record each substep (live or not), so nothing is cleared.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_CONTACTS) writeonly buffer Contacts { Contact contacts[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_SOLID_CENTRE) uniform vec3 centre;
layout(location = DRAPE_U_SOLID_LINEAR) uniform vec3 linearVelocity;
layout(location = DRAPE_U_SOLID_ANGULAR) uniform vec3 angularVelocity;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  const vec4 xi = x[i];
  Contact c;
  c.normal = vec4(0.0);
  c.solidVelocity = vec4(0.0);  // w = 0: no contact
  c.normalDv = vec4(0.0);
  if (xi.w != 0.0) {
    vec3 n;
    const float phi = sdf(xi.xyz, n);
    if (phi < thickness) {
      precise const float dn = thickness - phi;
      precise const vec3 p = xi.xyz + dn * n;
      x[i] = vec4(p, xi.w);
      c.normal = vec4(n, dn);
      c.solidVelocity = vec4(solidVelocityAt(p, centre, linearVelocity, angularVelocity), 1.0);
    }
  }
  contacts[i] = c;
}
