// Where surfaces meet (the CPU twin: projectOntoContactPlanes in include/drape/collision/response.hpp): a vertex
// with contacts in two or three slots goes outside all their half-spaces at once. A record that overflowed is left
// to the passes on the true fields. In a settle pass (pass >= 0) it is dispatched only if that pass's vertex passes
// found a contact (their dispatch command). Two stages, around the fields' judgement (settle_fields.comp, one
// dispatch per solid; docs/design.md §16, "Exact points tested"):
// - the first (DRAPE_SETTLE_PLACE 0) places a pinched vertex at the least-squares compromise from where the solve
//   left it (the packed positions, which the velocity update left as the solved ones), and writes a vertex whose
//   planes have an exact point near it as a SettlePoint that waits for the fields;
// - the second (DRAPE_SETTLE_PLACE 1) places each waiting vertex by the fields' answers (placeSettlePoint).
#ifndef DRAPE_SETTLE_PLACE
#define DRAPE_SETTLE_PLACE 0
#endif
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_PACKED) readonly buffer Packed { vec4 xw[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(std430, binding = DRAPE_B_SETTLE_POINTS) buffer Points { SettlePoint points[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
#if DRAPE_SETTLE_PLACE
  const uvec4 bits = points[i].bits;
  if ((bits.x & uint(DRAPE_SETTLE_WAITING)) == 0u) return;
#else
  points[i].bits.x = 0u;
#endif
  const uvec4 slots = contacts[i].slots;
  if (slots.x < 2u || slots.y != 0u) return;
  vec3 normals[DRAPE_CONTACT_SLOTS];
  float offsets[DRAPE_CONTACT_SLOTS];
  for (int k = 0; k < DRAPE_CONTACT_SLOTS; ++k) {
    normals[k] = contacts[i].normal[k].xyz;
    offsets[k] = contacts[i].velocity[k].w;
  }
  const int n = int(slots.x);
  const vec4 xi = x[i];
#if DRAPE_SETTLE_PLACE
  const uint planes = bits.x & 7u, backed = (bits.x >> uint(DRAPE_SETTLE_BACKED_SHIFT)) & 7u;
  const vec3 to = points[i].point.xyz;
  x[i] = vec4(placeSettlePoint(xi.xyz, to, planes, backed, bits.y, normals, offsets, n, xw[i].xyz), xi.w);
#else
  if (feasibleIn(normals, offsets, n, xi.xyz)) return;
  precise const float violation = halfSpaceViolation(normals, offsets, n, xi.xyz);
  vec3 to;
  if (nearestOnPlanes(normals, offsets, n, xi.xyz, kReach * violation, to)) {
    precise const float slack = DRAPE_EXACT_POINT_SLACK * violation;
    uint planes = 0u;
    for (int k = 0; k < n; ++k) {
      precise const float above = dot3(normals[k], to) - offsets[k];
      if (above <= slack) planes |= 1u << uint(k);
    }
    points[i].point = vec4(to, slack);
    points[i].bits = uvec4(planes | uint(DRAPE_SETTLE_WAITING), 0xffffffffu, 0u, 0u);
  } else {
    x[i] = vec4(leastSquaresCompromise(normals, offsets, n, xw[i].xyz, DRAPE_REACH), xi.w);
  }
#endif
}
