// The solid's field at a list of points (the CPU twin: Sdf<Shape, S>::operator()), for the tests that hold each
// shape's GLSL field to its C++ one: reads the points from the position buffer, writes (gradient, phi) into the
// velocity buffer.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_VELOCITIES) writeonly buffer Out { vec4 result[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  vec3 g;
  const float phi = sdf(x[i].xyz, g);
  result[i] = vec4(g, phi);
}
