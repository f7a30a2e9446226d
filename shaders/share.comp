// docs/design.md §6 (the CPU twin: the end of shareExchanges in include/drape/coupling/share.hpp): a body lighter
// than the vertices pushing it takes only a share s of their exchange, and so do they: a vertex whose contacts are
// all with the body keeps s of the velocity change the contacts (or propagation) gave it, v = v_pre + s (v - v_pre);
// a vertex touching several solids gives back (1 - s) of each body's part of its change.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(std430, binding = DRAPE_B_V_PRE) readonly buffer VPre { vec4 vPre[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(std430, binding = DRAPE_B_PUSHES) readonly buffer Pushes { BodyPush pushes[]; };
layout(std430, binding = DRAPE_B_SHARES) readonly buffer Shares { float shares[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  precise vec3 kept = v[i].xyz;
  bool changed = false;
  for (uint e = 0u; e < uint(DRAPE_CONTACT_SLOTS); ++e) {
    const BodyPush p = pushes[uint(DRAPE_CONTACT_SLOTS) * i + e];
    if (p.body < 0 || p.kind != DRAPE_PUSH_EXCHANGE) continue;
    const float s = shares[p.body];
    changed = true;
    if (p.slot < 0) {  // the vertex's whole change: its only exchange
      const vec3 pre = vPre[i].xyz;
      kept = pre + s * (kept - pre);
      break;
    }
    kept = kept - (1.0 - s) * p.torque.w * contacts[i].normal[p.slot].xyz;
  }
  if (changed) v[i] = vec4(kept, 0.0);
}
