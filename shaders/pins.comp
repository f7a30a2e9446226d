// Pins (the CPU twin: solvePins in include/drape/constraints/distance.hpp), in one invocation, in order, since two
// pins may hold the same vertex: a vertex of inverse mass 0 is placed on its target (kinematic); any other is
// pulled toward it by a zero-length XPBD distance constraint, its multiplier accumulated over the iterations.
layout(local_size_x = 1) in;
layout(std430, binding = DRAPE_B_PACKED) buffer Packed { vec4 xw[]; };
layout(std430, binding = DRAPE_B_PINS) readonly buffer Pins { PinSlot pins[]; };
layout(std430, binding = DRAPE_B_PIN_LAMBDAS) buffer PinLambdas { float lambdas[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_ALPHA_TILDE) uniform float alphaTilde;

void main() {
  for (uint k = 0u; k < count; ++k) {
    const uint i = pins[k].vertex;
    const vec4 p = xw[i];
    if (p.w == 0.0) {
      xw[i] = vec4(pins[k].target, 0.0);
      continue;
    }
    precise const vec3 d = p.xyz - pins[k].target;
    precise const float len = length3(d);
    if (len <= 0.0) continue;
    precise const float dLambda = (-len - alphaTilde * lambdas[k]) / (p.w + alphaTilde);
    lambdas[k] = lambdas[k] + dLambda;
    precise const vec3 moved = p.xyz + (p.w * dLambda / len) * d;
    xw[i] = vec4(moved, p.w);
  }
}
