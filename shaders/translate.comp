// Moves every position by -shift, when the local origin moves by +shift (the CPU twin: BasicSolver::rebase).
// The shift lies on a 1/64 m lattice, so the move is exact in float.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_SHIFT) uniform vec3 shift;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  precise const vec3 p = x[i].xyz - shift;
  x[i] = vec4(p, x[i].w);
}
