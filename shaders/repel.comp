// Phase 1 of paper 001 (DESIGN 5; the CPU twin: repelVertices in include/drape/collision/response.hpp): every
// free vertex whose distance beyond the thickness, d = phi - thickness, lies in [0, R) has its velocity blended
// toward the solid's there, v' = a v + (1 - a) v_solid with a = falloff(d / R): linear (a = t), or smooth
// (a = 3t^2 - 2t^3). Runs at the start of each substep, before the prediction.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_SOLID_CENTRE) uniform vec3 centre;
layout(location = DRAPE_U_SOLID_LINEAR) uniform vec3 linearVelocity;
layout(location = DRAPE_U_SOLID_ANGULAR) uniform vec3 angularVelocity;
layout(location = DRAPE_U_REPULSION) uniform vec2 repulsion;  // 1 / R, and 1 for the smooth falloff (else 0)

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  const vec4 xi = x[i];
  if (xi.w == 0.0) return;
  vec3 n;
  precise const float t = (sdf(xi.xyz, n) - thickness) * repulsion.x;
  if (!(t >= 0.0 && t < 1.0)) return;
  precise const float a = repulsion.y != 0.0 ? t * t * (3.0 - 2.0 * t) : t;
  const vec3 vc = solidVelocityAt(xi.xyz, centre, linearVelocity, angularVelocity);
  precise const vec3 blended = a * v[i].xyz + (1.0 - a) * vc;
  v[i] = vec4(blended, 0.0);
}
