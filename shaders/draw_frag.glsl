// The fragment shader of drape::gpu::Renderer: a base colour lit from one direction on both sides (a cloth has
// two), with an optional 25 cm checker pattern in world space so that sliding shows.
in vec3 worldPosition;
flat in vec3 faceNormal;
layout(location = 2) uniform vec3 colour;
layout(location = 3) uniform vec3 light;
layout(location = 4) uniform uint checker;
out vec4 fragColour;

void main() {
  vec3 base = colour;
  if (checker != 0u) {
    const ivec3 cell = ivec3(floor(worldPosition * 4.0));
    if (((cell.x + cell.y + cell.z) & 1) != 0) base *= 0.82;
  }
  fragColour = vec4(base * (0.35 + 0.65 * abs(dot(faceNormal, light))), 1.0);
}
