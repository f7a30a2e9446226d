// Where surfaces meet (the CPU twin: projectOntoContactPlanes in include/drape/collision/response.hpp): a vertex
// with contacts in two or three slots goes to the nearest point outside all their half-spaces at once
// (nearestInHalfSpaces), a pinched one starting its least-squares placement from where the solve left it (the
// packed positions, which the velocity update left as the solved ones). A record that overflowed is left to the
// passes on the true fields. In a settle pass (pass >= 0) it is dispatched only if that pass's vertex passes found
// a contact (their dispatch command).
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_PACKED) readonly buffer Packed { vec4 xw[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  const uvec4 slots = contacts[i].slots;
  if (slots.x < 2u || slots.y != 0u) return;
  vec3 normals[DRAPE_CONTACT_SLOTS];
  float offsets[DRAPE_CONTACT_SLOTS];
  for (int k = 0; k < DRAPE_CONTACT_SLOTS; ++k) {
    normals[k] = contacts[i].normal[k].xyz;
    offsets[k] = contacts[i].velocity[k].w;
  }
  const vec4 xi = x[i];
  x[i] = vec4(nearestInHalfSpaces(normals, offsets, int(slots.x), xi.xyz, xw[i].xyz, 0.0), xi.w);
}
