// docs/design.md §1, step 2 (the CPU twin: solveDistance in include/drape/constraints/distance.hpp): one colour
// of distance constraints, one invocation each. A colour's constraints share no vertex, so they run in parallel
// and give what the CPU's sequential pass over the colour gives; a dispatch per colour orders the colours.
// With useLambda the XPBD multiplier is accumulated (several passes over a compliant set); without it the
// correction is (rest - len) / ((wa + wb + alphaTilde) len), exact for one pass or a rigid set.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_PACKED) buffer Packed { vec4 xw[]; };
layout(std430, binding = DRAPE_B_CONSTRAINTS) readonly buffer Constraints { Constraint constraints[]; };
layout(std430, binding = DRAPE_B_LAMBDAS) buffer Lambdas { float lambdas[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_FIRST) uniform uint first;
layout(location = DRAPE_U_ALPHA_TILDE) uniform float alphaTilde;
layout(location = DRAPE_U_USE_LAMBDA) uniform uint useLambda;

void main() {
  if (gl_GlobalInvocationID.x >= count) return;
  const uint k = first + gl_GlobalInvocationID.x;
  const Constraint c = constraints[k];
  const vec4 a = xw[c.a], b = xw[c.b];
  precise const vec3 d = a.xyz - b.xyz;
  precise const float len = sqrt((d.x * d.x + d.y * d.y) + d.z * d.z);
  precise const float denom = (a.w + b.w) + alphaTilde;
  if (!(denom > 0.0 && len > 0.0)) return;  // both fixed and rigid, or coincident: no direction
  precise float s;
  if (useLambda != 0u) {
    precise const float dLambda = ((c.rest - len) - alphaTilde * lambdas[k]) / denom;
    lambdas[k] = lambdas[k] + dLambda;
    s = dLambda / len;
  } else {
    s = (c.rest - len) / (denom * len);
  }
  precise const float sa = a.w * s, sb = b.w * s;
  xw[c.a] = vec4(a.xyz + sa * d, a.w);
  xw[c.b] = vec4(b.xyz - sb * d, b.w);
}
