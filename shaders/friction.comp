// The in-solve method's friction (the CPU twin: applyContactFriction in include/drape/collision/response.hpp):
// inside the solve, after each pass's contacts, Coulomb friction on the positions of every contact vertex for
// each surface it touches (applyPositionFriction), relative to where the vertex started the substep.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_START) readonly buffer Start { vec4 x0[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_STEP) uniform float h;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  const int slots = int(contacts[i].slots.x);
  if (slots == 0) return;
  const vec4 xw = x[i];
  vec3 xi = xw.xyz;
  const vec3 start = x0[i].xyz;
  for (int k = 0; k < slots; ++k) {
    const Contact c = contacts[i];
    applyPositionFriction(c.normal[k].xyz, c.velocity[k].xyz, c.normal[k].w, c.friction[k].xy, xi, start, h);
  }
  x[i] = vec4(xi, xw.w);
}
