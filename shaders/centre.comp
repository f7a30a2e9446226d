// The mean of the positions (the CPU twin: the centre BasicSolver::rebase takes, in double there), for moving
// the local origin after the cloth: one workgroup; each invocation sums every DRAPE_WORKGROUP-th vertex in
// order, then the partial sums are added pairwise in a fixed tree, so the result does not vary between runs.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_REDUCTION) writeonly buffer Reduction { vec4 result[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
shared vec3 partial[DRAPE_WORKGROUP];

void main() {
  const uint lane = gl_LocalInvocationID.x;
  precise vec3 sum = vec3(0.0);
  for (uint i = lane; i < count; i += DRAPE_WORKGROUP) sum = sum + x[i].xyz;
  partial[lane] = sum;
  barrier();
  for (uint width = DRAPE_WORKGROUP / 2u; width > 0u; width /= 2u) {
    if (lane < width) {
      precise const vec3 s = partial[lane] + partial[lane + width];
      partial[lane] = s;
    }
    barrier();
  }
  if (lane == 0u) result[0] = vec4(partial[0] / float(count), 0.0);
}
