// DESIGN 4, the velocity split (the CPU twin: respondContacts and applyPositionFriction in
// include/drape/collision/response.hpp), per contact vertex, relative to the solid: an approaching normal
// velocity is removed, a separating one damped by normalDamping, the tangential one kept minus Coulomb
// friction. Friction acts on the position (the tangential displacement of the substep within mu_s times the
// correction is undone: stick) and takes as much from the velocity as from the position (slip). Compiled with
// DRAPE_FRICTION 0 for a scene without friction, which then pays nothing for it.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(std430, binding = DRAPE_B_START) readonly buffer Start { vec4 x0[]; };
layout(std430, binding = DRAPE_B_CONTACTS) buffer Contacts { Contact contacts[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_STEP) uniform float h;
layout(location = DRAPE_U_INVERSE_STEP) uniform float invH;
layout(location = DRAPE_U_NORMAL_DAMPING) uniform float normalDamping;
layout(location = DRAPE_U_FRICTION) uniform vec2 friction;  // static, dynamic

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  const Contact c = contacts[i];
  if (c.solidVelocity.w == 0.0) return;
  const vec3 n = c.normal.xyz, vc = c.solidVelocity.xyz;
  const float correction = c.normal.w;
  precise const vec3 vRel = v[i].xyz - vc;
  precise const float vn = dot3(n, vRel);
  precise vec3 vt = vRel - vn * n;
  precise const float vnNew = vn < 0.0 ? 0.0 : vn * (1.0 - normalDamping);
#if DRAPE_FRICTION
  const vec4 xi = x[i];
  precise const vec3 disp = (xi.xyz - x0[i].xyz) - h * vc;
  precise const vec3 dispT = disp - dot3(n, disp) * n;
  precise const float slip = length3(dispT);
  if (slip <= friction.x * correction) {
    x[i] = vec4(xi.xyz - dispT, xi.w);
    vt = vec3(0.0);
  } else {
    precise const float undo = min(1.0, friction.y * correction / slip);
    x[i] = vec4(xi.xyz - undo * dispT, xi.w);
    precise const float speed = length3(vt);
    precise const float slow = friction.y * correction * invH;
    vt = vt * (speed > slow ? (speed - slow) / speed : 0.0);
  }
#endif
  precise const vec3 vNew = vc + vnNew * n + vt;
  v[i] = vec4(vNew, 0.0);
  contacts[i].normalDv = vec4(max(vnNew - vn, 0.0), 0.0, 0.0, 0.0);
}
