// docs/design.md §6 (the CPU twin: the end of shareExchanges in include/drape/solver.hpp): a body lighter than the
// vertices pushing it takes only a share s of their exchange, and so do they: each vertex in a body's exchange
// keeps s of the velocity change the contacts (or propagation) gave it, v = v_pre + s (v - v_pre).
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(std430, binding = DRAPE_B_V_PRE) readonly buffer VPre { vec4 vPre[]; };
layout(std430, binding = DRAPE_B_PUSHES) readonly buffer Pushes { BodyPush pushes[]; };
layout(std430, binding = DRAPE_B_SHARES) readonly buffer Shares { float shares[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  for (uint e = 0u; e < uint(DRAPE_CONTACT_SLOTS); ++e) {
    const BodyPush p = pushes[uint(DRAPE_CONTACT_SLOTS) * i + e];
    if (p.body < 0 || p.kind != 1) continue;
    const float s = shares[p.body];
    const vec3 pre = vPre[i].xyz;
    precise const vec3 kept = pre + s * (v[i].xyz - pre);
    v[i] = vec4(kept, 0.0);
    return;  // at most one exchange per vertex
  }
}
