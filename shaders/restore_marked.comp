// The friction guard's second half (the CPU twin: BasicSolver::guardFriction in include/drape/solver.hpp): each
// vertex a caught face marked (collide_faces.comp with DRAPE_GUARD) goes back to where the contact passes left it,
// and its mark is cleared for the next substep. Its velocity keeps what the response gave it.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_GUARD_FROM) readonly buffer GuardFrom { vec4 before[]; };
layout(std430, binding = DRAPE_B_GUARD_MARKS) buffer GuardMarks { uint marks[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count || marks[i] == 0u) return;
  x[i] = before[i];
  marks[i] = 0u;
}
