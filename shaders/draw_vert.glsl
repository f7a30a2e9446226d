// The vertex shader of drape::gpu::Renderer: triangles read from a position buffer (vec4, relative to an origin)
// and a face buffer, three vertices a face (gl_VertexID), flat-shaded with the face's own normal.
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_FACES) readonly buffer Faces { uvec4 faces[]; };
layout(location = 0) uniform mat4 viewProjection;
layout(location = 1) uniform vec3 offset;       // position + offset: relative to the camera's target
layout(location = 5) uniform vec3 worldOrigin;  // position + worldOrigin: world (for the checker pattern)
out vec3 worldPosition;
flat out vec3 faceNormal;

void main() {
  const uint face = uint(gl_VertexID) / 3u, corner = uint(gl_VertexID) % 3u;
  const uvec4 t = faces[face];
  const vec3 a = x[t.x].xyz, b = x[t.y].xyz, c = x[t.z].xyz;
  const vec3 p = corner == 0u ? a : (corner == 1u ? b : c);
  const vec3 n = cross(b - a, c - a);
  faceNormal = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0, 0.0, 1.0);
  worldPosition = p + worldOrigin;
  gl_Position = viewProjection * vec4(p + offset, 1.0);
}
