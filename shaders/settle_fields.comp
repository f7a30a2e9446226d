// One solid's judgement of the settle's waiting exact points (the CPU twins: backedPlanes and clearFractions in
// include/drape/collision/response.hpp; docs/design.md §16, "Exact points tested"), compiled per shape: it ors in
// the planes its field backs at the point (the field within the thickness and the slack, its gradient within
// kBackedCos of the plane's normal), and, while no solid so far backs any plane, ands in the fractions of the
// segment from the vertex to the point where it reads at least the thickness less the slack. The fractions
// decide only where no solid backs a plane, so leaving them once one does changes no placement.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(std430, binding = DRAPE_B_SETTLE_POINTS) buffer Points { SettlePoint points[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_BOX_LOW) uniform vec3 boxLow;
layout(location = DRAPE_U_BOX_HIGH) uniform vec3 boxHigh;

bool inBox(vec3 q, float grow) {
  precise const vec3 low = boxLow - vec3(grow), high = boxHigh + vec3(grow);
  return all(greaterThanEqual(q, low)) && all(lessThanEqual(q, high));
}

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  uvec4 bits = points[i].bits;
  if ((bits.x & uint(DRAPE_SETTLE_WAITING)) == 0u) return;
  const vec4 p = points[i].point;
  precise const float reach = thickness + p.w;
  if (inBox(p.xyz, reach)) {
    vec3 g;
    const float phi = sdf(p.xyz, g);
    if (phi <= reach)
      for (int k = 0; k < DRAPE_CONTACT_SLOTS; ++k)
        if (((bits.x >> uint(k)) & 1u) != 0u && dot3(g, contacts[i].normal[k].xyz) >= DRAPE_BACKED_COS)
          bits.x |= 1u << uint(DRAPE_SETTLE_BACKED_SHIFT + k);
  }
  if (((bits.x >> uint(DRAPE_SETTLE_BACKED_SHIFT)) & 7u) == 0u) {
    const vec3 from = x[i].xyz;
    precise const float limit = thickness - p.w;
    for (int j = 0; j < DRAPE_SEGMENT_FRACTIONS; ++j) {
      precise const vec3 q = from + (float(j + 1) / float(DRAPE_SEGMENT_FRACTIONS)) * (p.xyz - from);
      if (!inBox(q, thickness)) continue;
      vec3 g;
      if (sdf(q, g) < limit) bits.y &= ~(1u << uint(j));
    }
  }
  points[i].bits = bits;
}
