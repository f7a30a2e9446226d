// docs/design.md §4, the velocity split (the CPU twin: respondContacts and applyPositionFriction in
// include/drape/collision/response.hpp), per contact vertex and each surface it touches, relative to that solid:
// an approaching normal velocity is removed, a separating one damped by normalDamping, the tangential one kept
// minus Coulomb friction with the slot's coefficients. Friction acts on the position (the tangential
// displacement of the substep within mu_s times the correction is undone: stick) and takes as much from the
// velocity as from the position (slip). A vertex touching several surfaces then gets the nearest velocity that
// approaches none of them (nearestInHalfSpaces). Compiled with DRAPE_FRICTION 0 for a scene without friction,
// which then pays nothing for it.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(std430, binding = DRAPE_B_START) readonly buffer Start { vec4 x0[]; };
layout(std430, binding = DRAPE_B_CONTACTS) buffer Contacts { Contact contacts[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_STEP) uniform float h;
layout(location = DRAPE_U_INVERSE_STEP) uniform float invH;
layout(location = DRAPE_U_NORMAL_DAMPING) uniform float normalDamping;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  const int slots = int(contacts[i].slots.x);  // most vertices touch nothing: read the count alone first
  if (slots == 0) return;
  const Contact c = contacts[i];
  vec3 vi = v[i].xyz;
#if DRAPE_FRICTION
  const vec4 xw = x[i];
  vec3 xi = xw.xyz;
  const vec3 start = x0[i].xyz;
#endif
  precise float dvnSum = 0.0;
  for (int k = 0; k < slots; ++k) {
    const vec3 n = c.normal[k].xyz, vc = c.velocity[k].xyz;
    precise const vec3 vRel = vi - vc;
    precise const float vn = dot3(n, vRel);
    precise vec3 vt = vRel - vn * n;
    precise const float vnNew = vn < 0.0 ? 0.0 : vn * (1.0 - normalDamping);
#if DRAPE_FRICTION
    const float correction = c.normal[k].w;
    const vec2 mu = c.friction[k].xy;  // static, dynamic
    if (applyPositionFriction(n, vc, correction, mu, xi, start, h)) {
      vt = vec3(0.0);
    } else {
      precise const float speed = length3(vt);
      precise const float slow = mu.y * correction * invH;
      vt = vt * (speed > slow ? (speed - slow) / speed : 0.0);
    }
#endif
    precise const vec3 vNew = (vc + vnNew * n) + vt;
    vi = vNew;
    dvnSum = dvnSum + max(vnNew - vn, 0.0);
  }
  if (slots > 1) {
    vec3 normals[DRAPE_CONTACT_SLOTS];
    float bounds[DRAPE_CONTACT_SLOTS];
    for (int k = 0; k < DRAPE_CONTACT_SLOTS; ++k) {
      normals[k] = c.normal[k].xyz;
      bounds[k] = dot3(c.normal[k].xyz, c.velocity[k].xyz);
    }
    vi = nearestInHalfSpaces(normals, bounds, slots, vi, vi, length3(vi));
  }
#if DRAPE_FRICTION
  x[i] = vec4(xi, xw.w);
#endif
  v[i] = vec4(vi, 0.0);
  contacts[i].normalDv = vec4(dvnSum, 0.0, 0.0, 0.0);
}
