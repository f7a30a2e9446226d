// Keeps the contact vertices at least the thickness out of one plane solid after the response (the CPU twin:
// holdOutOfPlane in include/drape/collision/response.hpp; docs/design.md §4, "Friction and the planes"). Position
// friction moves a vertex in its slots' tangent planes, toward where their solids carry it, which can take it into
// a plane it does not touch (a vertex pinched under a body falling onto the floor). Vertices within `slack` of the
// thickness (the plane's own contacts, to rounding) are left where they are. Compiled for the plane's field.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_SLACK) uniform float slack;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count || contacts[i].slots.x == 0u) return;
  const vec4 xw = x[i];
  vec3 n;
  precise const float gap = thickness - sdf(xw.xyz, n);
  if (gap > slack) {
    precise const vec3 moved = xw.xyz + gap * n;
    x[i] = vec4(moved, xw.w);
  }
}
