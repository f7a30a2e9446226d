// Keeps friction's moves out of one plane solid after the response (the CPU twin: holdOutOfPlane in
// include/drape/collision/response.hpp; docs/design.md §4, "Friction and the planes"). Position friction moves a
// vertex in its slots' tangent planes, toward where their solids carry it, which can take it into a plane it does
// not touch (a vertex pinched under a body falling onto the floor). A contact vertex friction took deeper into the
// plane than the thickness and than the contact passes left it (`before`) goes back to the shallower of the two,
// and none stays below the plane's surface; one within `slack` of where it goes stays. Compiled for the plane's
// field.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_GUARD_FROM) readonly buffer Before { vec4 before[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_SLACK) uniform float slack;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count || contacts[i].slots.x == 0u) return;
  const vec4 xw = x[i];
  vec3 n;
  const float reach = min(thickness, max(sdf(before[i].xyz, n), 0.0));
  precise const float gap = reach - sdf(xw.xyz, n);
  if (gap > slack) {
    precise const vec3 moved = xw.xyz + gap * n;
    x[i] = vec4(moved, xw.w);
  }
}
