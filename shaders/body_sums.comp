// docs/design.md §6, phase 2, per body (the CPU twin: the sums in gatherContactForces, include/drape/solver.hpp): one
// workgroup per coupled body (or per body of a range: a repelling body's pushes alone) adds up, in double, the pushes
// every vertex passed to it (contact_forces.comp), by kind: direct, exchange (with the sum of |f|^2 / m that
// shareExchanges weighs) and pinch (with their count). Each invocation sums a fixed stride of vertices and the
// workgroup then adds the partial sums in a fixed tree, so the result has one order however the GPU schedules it:
// no atomics.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_PUSHES) readonly buffer Pushes { BodyPush pushes[]; };
layout(std430, binding = DRAPE_B_BODY_SUMS) writeonly buffer BodySums { BodySum sums[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;  // vertices
layout(location = DRAPE_U_BODY) uniform int firstBody;  // workgroup k sums body firstBody + k

shared dvec4 partial[6][DRAPE_WORKGROUP];

void main() {
  const int b = firstBody + int(gl_WorkGroupID.x);
  const uint t = gl_LocalInvocationID.x;
  dvec4 acc[6] = dvec4[6](dvec4(0.0), dvec4(0.0), dvec4(0.0), dvec4(0.0), dvec4(0.0), dvec4(0.0));
  for (uint i = t; i < count; i += uint(DRAPE_WORKGROUP))
    for (uint e = 0u; e < uint(DRAPE_CONTACT_SLOTS); ++e) {
      const BodyPush p = pushes[uint(DRAPE_CONTACT_SLOTS) * i + e];
      if (p.body != b) continue;
      const int at = 2 * p.kind;  // DRAPE_PUSH_*: direct 0-1, exchange 2-3, pinch 4-5
      acc[at] += dvec4(dvec3(p.force.xyz), p.kind == DRAPE_PUSH_PINCH ? 1.0lf : double(p.force.w));
      acc[at + 1] += dvec4(dvec3(p.torque.xyz), 0.0lf);
    }
  for (int k = 0; k < 6; ++k) partial[k][t] = acc[k];
  barrier();
  for (uint stride = uint(DRAPE_WORKGROUP) / 2u; stride > 0u; stride /= 2u) {
    if (t < stride)
      for (int k = 0; k < 6; ++k) partial[k][t] += partial[k][t + stride];
    barrier();
  }
  if (t == 0u)
    sums[b] = BodySum(partial[0][0], partial[1][0], partial[2][0], partial[3][0], partial[4][0], partial[5][0]);
}
