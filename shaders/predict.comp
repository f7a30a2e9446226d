// docs/design.md §1, step 1 (the CPU twin: predictPositions in include/drape/cloth/integrate.hpp): a free vertex
// (inverse mass w != 0) gains h g of velocity, keeps the share keepVelocity = exp(-airDamping h) of it (1 without
// air damping, which leaves every bit as it was) and moves h v; a pinned one stays, its velocity set to zero (the
// update then gives it its pin's move). The prediction goes to the predicted positions (for the velocity update)
// and, with the inverse mass in w, to the packed positions the solve works on; with keepStart (a scene with
// friction) the start positions are kept too. `precise` keeps every product and sum rounded on its own, as the CPU
// kernel rounds them.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(std430, binding = DRAPE_B_PREDICTED) writeonly buffer Predicted { vec4 xp[]; };
layout(std430, binding = DRAPE_B_PACKED) writeonly buffer Packed { vec4 xw[]; };
layout(std430, binding = DRAPE_B_START) writeonly buffer Start { vec4 x0[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_STEP) uniform float h;
layout(location = DRAPE_U_GRAVITY_STEP) uniform vec3 gh;
layout(location = DRAPE_U_KEEP_START) uniform uint keepStart;
layout(location = DRAPE_U_KEEP_VELOCITY) uniform float keepVelocity;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  const vec4 xi = x[i];
  if (keepStart != 0u) x0[i] = xi;
  precise vec3 p = xi.xyz;
  if (xi.w != 0.0) {
    precise const vec3 vi = keepVelocity * (v[i].xyz + gh);
    v[i] = vec4(vi, 0.0);
    p = p + h * vi;
  } else {
    v[i] = vec4(0.0);  // a pinned vertex moves only where its pin takes it: the update measures that
  }
  xp[i] = vec4(p, 0.0);
  xw[i] = vec4(p, xi.w);
}
