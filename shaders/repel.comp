// Phase 1 of the cloth-rigid coupling thesis (docs/design.md §5; the CPU twin: repelVertices in
// include/drape/collision/response.hpp): every free vertex whose distance beyond the thickness, d = phi - thickness,
// lies in [0, R) has its velocity blended toward the solid's there, v' = a v + (1 - a) v_solid with a = falloff(d / R):
// linear (a = t), or smooth (a = 3t^2 - 2t^3). Runs at the start of each substep, before the prediction. For a coupled
// body's solid (DRAPE_BODY; the CPU twin: gatherRepulsionForces in include/drape/solver.hpp) each vertex also writes
// the velocity it lost or gained as a push on the body, m dv / h reversed, at its closest point on the body (its first
// BodyPush; body_sums.comp adds them up).
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_THICKNESS) uniform float thickness;
layout(location = DRAPE_U_SOLID_CENTRE) uniform vec3 centre;
layout(location = DRAPE_U_SOLID_LINEAR) uniform vec3 linearVelocity;
layout(location = DRAPE_U_SOLID_ANGULAR) uniform vec3 angularVelocity;
layout(location = DRAPE_U_REPULSION) uniform vec2 repulsion;  // 1 / R, and 1 for the smooth falloff (else 0)
#if DRAPE_BODY
layout(std430, binding = DRAPE_B_PUSHES) writeonly buffer Pushes { BodyPush pushes[]; };
layout(location = DRAPE_U_BODY) uniform int body;
layout(location = DRAPE_U_STEP) uniform float h;
layout(location = DRAPE_U_NORMAL_ONLY) uniform uint normalOnly;
#endif

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
#if DRAPE_BODY
  for (uint e = 0u; e < uint(DRAPE_CONTACT_SLOTS); ++e)
    pushes[uint(DRAPE_CONTACT_SLOTS) * i + e] = BodyPush(vec4(0.0), vec4(0.0), -1, 0, 0, 0);
#endif
  const vec4 xi = x[i];
  if (xi.w == 0.0) return;
  vec3 n;
  const float phi = sdf(xi.xyz, n);
  precise const float t = (phi - thickness) * repulsion.x;
  if (!(t >= 0.0 && t < 1.0)) return;
  precise const float a = repulsion.y != 0.0 ? t * t * (3.0 - 2.0 * t) : t;
  const vec3 vc = solidVelocityAt(xi.xyz, centre, linearVelocity, angularVelocity);
  const vec3 before = v[i].xyz;
  precise const vec3 blended = a * before + (1.0 - a) * vc;
  v[i] = vec4(blended, 0.0);
#if DRAPE_BODY
  precise const vec3 dv = blended - before;
  if (dv == vec3(0.0)) return;
  precise vec3 force = -(dv / (xi.w * h));
  if (normalOnly != 0u) force = dot3(force, n) * n;
  precise const vec3 point = xi.xyz - phi * n;
  pushes[uint(DRAPE_CONTACT_SLOTS) * i] =
      BodyPush(vec4(force, 0.0), vec4(momentAbout(point, centre, force), 0.0), body, 0, 0, 0);
#endif
}
