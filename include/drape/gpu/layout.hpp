#pragma once
// What the C++ side and the compute shaders must agree on (DESIGN 9), in one place: the workgroup size, the
// binding of every storage buffer, the location of every uniform, and the layout of every struct a shader
// reads. The shaders never spell a number of their own: each is compiled after preamble(), which turns the
// constants below into #defines and declares the structs in GLSL, and the static_asserts pin the C++ twins to
// std430's layout.

#include <cstddef>
#include <cstdint>
#include <string>

namespace drape::gpu::layout {

/// Invocations per workgroup of every per-vertex and per-constraint kernel.
inline constexpr unsigned kWorkgroup = 64;

/// Storage-buffer bindings. Per vertex, every array holds vec4s (std430 gives a vec3 array a 16-byte stride
/// anyway): positions with the inverse mass in w, so the solve reads a vertex and its mass in one load.
enum Binding : unsigned {
  kPositions = 0,    ///< vec4 per vertex: x (m, in the cloth's local frame), w = inverse mass (1/kg)
  kVelocities = 1,   ///< vec4 per vertex: v (m/s), w unused (0)
  kPredicted = 2,    ///< vec4 per vertex: the prediction p = x + h v, which the velocity update starts from
  kPacked = 3,       ///< vec4 per vertex: the positions the solve works on, w = inverse mass
  kConstraints = 4,  ///< Constraint per distance constraint, colour by colour
  kLambdas = 5,      ///< float per distance constraint: the XPBD multipliers of the current substep
};

/// Uniform locations (set per dispatch with glProgramUniform*).
enum Uniform : int {
  kCount = 0,         ///< uint: how many items this dispatch covers
  kFirst = 1,         ///< uint: the first item (a colour's first constraint)
  kStep = 2,          ///< float: the substep h (s)
  kGravityStep = 3,   ///< vec3: h g (m/s), the velocity gravity adds in one substep
  kAlphaTilde = 4,    ///< float: compliance / h^2
  kUseLambda = 5,     ///< uint: 1 to accumulate multipliers (several passes of a compliant set), else 0
  kInverseStep = 6,   ///< float: 1 / h
};

/// One distance constraint: |x_a - x_b| = rest.
struct Constraint {
  std::uint32_t a, b;
  float rest;
  std::uint32_t pad;
};
static_assert(sizeof(Constraint) == 16 && alignof(Constraint) == 4);
static_assert(offsetof(Constraint, a) == 0 && offsetof(Constraint, b) == 4 && offsetof(Constraint, rest) == 8);

/// The per-vertex element: four floats, 16 bytes, as std430 lays out a vec4 array.
struct Vertex {
  float x, y, z, w;
};
static_assert(sizeof(Vertex) == 16 && offsetof(Vertex, w) == 12);

/// The text every kernel is compiled after: the GLSL version, the constants above as #defines, and the structs.
inline std::string preamble() {
  auto define = [](const char* name, long value) { return "#define " + std::string(name) + " " + std::to_string(value) + "\n"; };
  std::string s = "#version 430 core\n";
  s += define("DRAPE_WORKGROUP", kWorkgroup);
  s += define("DRAPE_B_POSITIONS", kPositions);
  s += define("DRAPE_B_VELOCITIES", kVelocities);
  s += define("DRAPE_B_PREDICTED", kPredicted);
  s += define("DRAPE_B_PACKED", kPacked);
  s += define("DRAPE_B_CONSTRAINTS", kConstraints);
  s += define("DRAPE_B_LAMBDAS", kLambdas);
  s += define("DRAPE_U_COUNT", kCount);
  s += define("DRAPE_U_FIRST", kFirst);
  s += define("DRAPE_U_STEP", kStep);
  s += define("DRAPE_U_GRAVITY_STEP", kGravityStep);
  s += define("DRAPE_U_ALPHA_TILDE", kAlphaTilde);
  s += define("DRAPE_U_USE_LAMBDA", kUseLambda);
  s += define("DRAPE_U_INVERSE_STEP", kInverseStep);
  s += "struct Constraint { uint a; uint b; float rest; uint pad; };\n";
  s += "#line 1\n";
  return s;
}

}  // namespace drape::gpu::layout
