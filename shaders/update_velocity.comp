// docs/design.md §1, step 3 (the CPU twin: updateVelocities in include/drape/cloth/integrate.hpp):
// v += (p - p_predicted) / h, which is (p - x_start) / h without the prediction's rounding in it, and x = p.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(std430, binding = DRAPE_B_PREDICTED) readonly buffer Predicted { vec4 xp[]; };
layout(std430, binding = DRAPE_B_PACKED) readonly buffer Packed { vec4 xw[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_INVERSE_STEP) uniform float invH;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  const vec4 p = xw[i];
  precise const vec3 vi = v[i].xyz + (p.xyz - xp[i].xyz) * invH;
  v[i] = vec4(vi, 0.0);
  x[i] = vec4(p.xyz, x[i].w);
}
