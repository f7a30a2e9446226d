// Helpers every kernel is compiled with (after layout.hpp's preamble). Each sums in the order the CPU code
// does, `precise` so no product is fused into a sum: Eigen's dot product of two 3-vectors, which the CPU
// kernels use, adds the last two products first.

float dot3(vec3 a, vec3 b) {
  precise float s = a.x * b.x + (a.y * b.y + a.z * b.z);
  return s;
}
float length3(vec3 a) { return sqrt(dot3(a, a)); }

// The velocity of a solid's material point at x: v + w x (x - centre) (SolidMotion::velocityAt).
vec3 solidVelocityAt(vec3 x, vec3 centre, vec3 linear, vec3 angular) {
  precise vec3 d = x - centre;
  precise vec3 r = vec3(angular.y * d.z - angular.z * d.y, angular.z * d.x - angular.x * d.z,
                        angular.x * d.y - angular.y * d.x);
  precise vec3 v = linear + r;
  return v;
}

// The signed distance of a solid's field and its gradient, for the shape the kernel is compiled for
// (DRAPE_SHAPE; the CPU twins: Sdf<Shape, S> in include/drape/sdf/shapes.hpp):
// - a plane, shape = (outward normal, offset): phi = n . x - offset;
// - a sphere, shape = (centre, radius): phi = |x - centre| - radius, gradient +z at the centre itself.
#if DRAPE_SHAPE == DRAPE_SHAPE_PLANE
float sdf(vec3 x, vec4 shape, out vec3 gradient) {
  gradient = shape.xyz;
  precise float phi = dot3(shape.xyz, x) - shape.w;
  return phi;
}
#elif DRAPE_SHAPE == DRAPE_SHAPE_SPHERE
float sdf(vec3 x, vec4 shape, out vec3 gradient) {
  precise const vec3 d = x - shape.xyz;
  precise const float len = length3(d);
  gradient = len > 0.0 ? d / len : vec3(0.0, 0.0, 1.0);
  precise float phi = len - shape.w;
  return phi;
}
#endif
