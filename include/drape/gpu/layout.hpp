#pragma once
// What the C++ side and the compute shaders must agree on (docs/design.md §9), in one place: the workgroup
// size, the binding of every storage buffer, the location of every uniform, and the layout of every struct a shader
// reads. The shaders never spell a number of their own: each is compiled after preamble(), which turns the
// constants below into #defines and declares the structs in GLSL, and the static_asserts pin the C++ twins to
// std430's layout.

#include <drape/kernel_constants.hpp>

#include <cstddef>
#include <cstdio>
#include <cstdint>
#include <limits>
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
  kStart = 6,        ///< vec4 per vertex: the position at the start of the substep (friction reads it)
  kContacts = 7,     ///< Contact per vertex: this substep's contacts with the solids (up to three surfaces)
  kNeighbourOffsets = 8,  ///< uint per vertex + 1: where each vertex's neighbours start in kNeighbours
  kNeighbours = 9,        ///< uint: the neighbours of every vertex (the asset's vertexNeighbours, in order)
  kPropagation = 10,      ///< Ring per vertex: what a propagation ring passed to the vertex
  kReduction = 11,        ///< vec4: a reduction's result (the centre of the positions)
  kFaces = 12,            ///< uvec4 per face: its three vertices (and 0), colour by colour
  kPins = 13,             ///< PinSlot per pin
  kPinLambdas = 14,       ///< float per pin: its XPBD multiplier in the current substep
  kShapeData = 15,        ///< vec4s: a grid field's nodes ((normal, distance), x fastest) or a hull's faces and edges
  kFlags = 16,            ///< per settle pass, the dispatch command (3 uints) its vertex passes write on a contact
  // The coupling with dynamic bodies (only in a scene that has them):
  kVStart = 17,           ///< vec4 per vertex: the velocity at the start of the substep
  kVPre = 18,             ///< vec4 per vertex: the velocity before the contacts acted
  kLines = 19,            ///< Lines per vertex: where each body slot's push acts (ContactLine)
  kPushes = 20,           ///< BodyPush[kContactSlots] per vertex: what the vertex passes to bodies this substep
  kBodies = 21,           ///< Body per coupled body
  kBodySums = 22,         ///< BodySum per coupled body: the pushes summed by kind
  kShares = 23,           ///< float per coupled body: the share of its exchange both sides take
  // Continuous contact's friction guard (only with continuous contact, friction and faces):
  kGuardFrom = 24,        ///< vec4 per vertex: the position the contact passes left, before friction
  kGuardMarks = 25,       ///< uint per vertex: 1 where a face the guard caught goes back to kGuardFrom
  kHeld = 26,             ///< vec4 per face, colour by colour: where it was last deepest in a solid (barycentric),
                          ///<   w = that solid's place + 1, 0 for none (HeldPoints)
  kSpacers = 27,          ///< SpacerRecord: a header (vertex: how many follow; body: room) and this substep's pinches
  kSettlePoints = 28,     ///< SettlePoint per vertex: the settle's exact point while the fields judge it
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
  kThickness = 7,     ///< float: the cloth's thickness (m)
  kSolidCentre = 9,   ///< vec3: the solid's frame origin (m, the cloth's local frame)
  kSolidLinear = 10,  ///< vec3: its linear velocity (m/s)
  kSolidAngular = 11, ///< vec3: its angular velocity (rad/s)
  kNormalDamping = 12,  ///< float: Settings::normalDamping
  kFriction = 13,     ///< vec2: the solid's static and dynamic Coulomb coefficients
  kRing = 14,         ///< uint: the propagation ring of this dispatch, from 1
  kWeight = 15,       ///< float: Settings::propagationWeight
  kKeepStart = 16,    ///< uint: 1 to keep the start positions (a scene with friction), else 0
  kShift = 17,        ///< vec3: how far the local origin moves (m)
  kPgdIterations = 18,  ///< int: Settings::pgdIterations, the face search's most field evaluations
  kRepulsion = 19,      ///< vec2: 1 / the repulsion radius (1/m), and 1 for the smooth falloff (else 0)
  kSlack = 20,          ///< float: a vertex pass leaves vertices within this of the thickness where they are (m)
  kPass = 21,           ///< int: the settle pass a dispatch belongs to (0-3), -1 for the substep's first pass
  kFresh = 22,          ///< uint: 1 for the substep's first vertex pass, which starts every vertex's record
  kBody = 23,           ///< int: the coupled body a solid's contacts push (its index this substep)
  kEstimator = 24,      ///< int: the contact-force estimator (0 sub-force, 1 energy, 2 impulse)
  kNormalOnly = 25,     ///< uint: 1 to pass bodies only the normal part of each push
  kPropagated = 26,     ///< uint: 1 to pass on the impulse propagation gave vertices not in contact
  kSweep = 27,          ///< vec2: continuous contact's substep h (s) and gate squared (m^2); 0 is off
  kBoxLow = 28,         ///< vec3: the solid's bounding box (the cloth's local frame), outside which phi is at least
  kBoxHigh = 29,        ///<   the distance to the box (placeBounds); +-FLT_MAX for an unbounded solid
  kKeepVelocity = 30,   ///< float: the share of its velocity a free vertex keeps in a substep, exp(-airDamping h)
  kHeldPlace = 31,      ///< uint: the face pass's solid's place + 1, 0 where the pass holds no deepest points
  kShape = 32,  ///< vec4[5] (locations 32-36): the solid's field, packed by packShape (gpu/shapes.hpp)
};

/// The contact-force estimator a dispatch of contact_forces.comp uses (kEstimator).
enum EstimatorCode : int { kSubForce = 0, kEnergy = 1, kImpulse = 2 };
/// What a vertex's push to a body is (BodyPush::kind): the body's sums keep the kinds apart.
enum PushKind : int { kDirect = 0, kExchange = 1, kPinch = 2 };

/// Shape codes for DRAPE_SHAPE, the shape a collision kernel is compiled for.
enum ShapeCode : int { kPlane = 1, kSphere = 2, kBox = 3, kCapsule = 4, kCylinder = 5, kGridShape = 6, kHull = 7 };

/// One distance constraint: |x_a - x_b| = rest.
struct Constraint {
  std::uint32_t a, b;
  float rest;
  std::uint32_t pad;
};
static_assert(sizeof(Constraint) == 16 && alignof(Constraint) == 4);
static_assert(offsetof(Constraint, a) == 0 && offsetof(Constraint, b) == 4 && offsetof(Constraint, rest) == 8);

/// Up to this many differently facing surfaces per vertex and substep (ContactBuffer::kSlots).
inline constexpr unsigned kContactSlots = constants::kContactSlots;

/// A vertex's contacts of the substep (the CPU's ContactBuffer record, ContactSlot per slot): per slot, the
/// outward normal with the correction (m) in w, the solid's velocity at the contact with the slot's half-space
/// offset n . x in w, and the static and dynamic friction coefficients; the coupled body per slot (-1: none);
/// in `slots` the count (0: no contact) and 1 in y where a surface found every slot taken (the overflow); and in
/// `normalDv.x` the normal velocity change the response made (m/s), which propagation spreads.
struct Contact {
  float normal[kContactSlots][4];
  float velocity[kContactSlots][4];
  float friction[kContactSlots][4];
  std::int32_t body[4];
  std::uint32_t slots[4];
  float normalDv[4];
};
static_assert(sizeof(Contact) == 192 && alignof(Contact) == 4);
static_assert(offsetof(Contact, velocity) == 48 && offsetof(Contact, friction) == 96 && offsetof(Contact, body) == 144 &&
              offsetof(Contact, slots) == 160 && offsetof(Contact, normalDv) == 176);

/// Where each body slot's push acts (the CPU's ContactLine per slot): the mean normal of its contacts, and
/// their mean moment about the body's centre, weighted by their corrections.
struct Lines {
  float push[kContactSlots][4];
  float moment[kContactSlots][4];
};
static_assert(sizeof(Lines) == 96 && offsetof(Lines, moment) == 48);

/// What a vertex passes to one body this substep: the force (N, w: |f|^2 / m for an exchange) and the torque
/// about the body's centre (N m); the body (-1: none) and the kind (0 direct, 1 exchange, 2 pinch). An exchange of
/// a vertex touching several solids names its contact slot (-1: the vertex's whole change), and torque[3] holds
/// the slot's part of the vertex's velocity change along the slot's normal (m/s; coupling::Exchanged).
struct BodyPush {
  float force[4];
  float torque[4];
  std::int32_t body, kind, slot, pad;
};
static_assert(sizeof(BodyPush) == 48 && offsetof(BodyPush, torque) == 16 && offsetof(BodyPush, body) == 32);

/// A pinch as a rigid world's spacer (drape::Spacer, coupling::spacerOf): the points on the body's surface and
/// kSpacerGap thicknesses out of the other surface (m, the cloth's local frame), the other surface's normal, the
/// vertex, the two bodies (other -1 for a fixed solid) and the body's slot. Appended in any order; the solver
/// sorts them.
struct SpacerRecord {
  float onBody[4];
  float onOther[4];
  float normal[4];
  std::int32_t vertex, body, other, slot;
};
static_assert(sizeof(SpacerRecord) == 64 && offsetof(SpacerRecord, normal) == 32 &&
              offsetof(SpacerRecord, vertex) == 48);

/// A coupled body as the force kernel reads it: its centre (m, the cloth's local frame) with its inverse mass in
/// w, its velocities, and the rows of its inverse inertia tensor in world axes.
struct Body {
  float centre[4];
  float linear[4];
  float angular[4];
  float inverseInertia[3][4];
};
static_assert(sizeof(Body) == 96 && offsetof(Body, inverseInertia) == 48);

/// A body's pushes summed (in double) by kind: force and torque each, with the exchange's sum of |f|^2 / m in
/// exchangeForce[3] and the pinch count in pinchForce[3].
struct BodySum {
  double directForce[4], directTorque[4];
  double exchangeForce[4], exchangeTorque[4];
  double pinchForce[4], pinchTorque[4];
};
static_assert(sizeof(BodySum) == 192 && offsetof(BodySum, exchangeForce) == 64 && offsetof(BodySum, pinchForce) == 128);

/// What propagation ring `reached` passed to a vertex: the share it offers the next ring (amount, m/s), along
/// the mean normal of its sources (normal[0..2]), relative to the solids' speed along it (normal[3]). reached is
/// 0 before any ring.
struct Ring {
  float normal[4];
  float amount;
  std::uint32_t reached;
  std::uint32_t pad[2];
};
static_assert(sizeof(Ring) == 32 && offsetof(Ring, amount) == 16 && offsetof(Ring, reached) == 20);

/// A pin: its vertex and its target (m, the cloth's local frame).
struct PinSlot {
  float target[3];
  std::uint32_t vertex;
};
static_assert(sizeof(PinSlot) == 16 && offsetof(PinSlot, vertex) == 12);

/// The settle's exact point for one vertex while the solids' fields judge it (the CPU's SettlePoint, with the
/// fields' answers): the point (m) with the slack in w; in bits[0] the planes it lies on (bit k: slot k), the
/// planes some field backs (bit 4 + k) and kSettleWaiting while it waits, in bits[1] the segment's fractions every
/// field so far leaves clear (bit j: fraction j + 1 of kSegmentFractions).
struct SettlePoint {
  float point[4];
  std::uint32_t bits[4];
};
static_assert(sizeof(SettlePoint) == 32 && offsetof(SettlePoint, bits) == 16);
/// SettlePoint::bits[0]: the point waits for the fields' answers.
inline constexpr unsigned kSettleWaiting = 1u << 8;
/// SettlePoint::bits[0]: the first bit of the backed planes.
inline constexpr unsigned kSettleBackedShift = 4;

/// The per-vertex element: four floats, 16 bytes, as std430 lays out a vec4 array.
struct Vertex {
  float x, y, z, w;
};
static_assert(sizeof(Vertex) == 16 && offsetof(Vertex, w) == 12);

/// A constant as GLSL reads it: an integer as it is, a real rounded to float with enough digits to give that
/// float back (and a point, so GLSL reads a float).
inline std::string glslLiteral(long value) { return std::to_string(value); }
inline std::string glslLiteral(unsigned value) { return std::to_string(value); }
inline std::string glslLiteral(int value) { return std::to_string(value); }
inline std::string glslLiteral(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", double(float(value)));
  std::string s = text;
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return value < 0 ? "(" + s + ")" : s;
}

/// The text every kernel is compiled after: the GLSL version, the constants above as #defines, and the structs.
/// `defines` (e.g. "#define DRAPE_FRICTION 0\\n") go after the version line, before the defaults.
inline std::string preamble(const std::string& defines = {}) {
  const auto define = [](const char* name, auto value) { return "#define " + std::string(name) + " " + glslLiteral(value) + "\n"; };
  std::string s = "#version 430 core\n" + defines;
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
  s += define("DRAPE_B_START", kStart);
  s += define("DRAPE_B_CONTACTS", kContacts);
  s += define("DRAPE_B_NEIGHBOUR_OFFSETS", kNeighbourOffsets);
  s += define("DRAPE_B_NEIGHBOURS", kNeighbours);
  s += define("DRAPE_B_PROPAGATION", kPropagation);
  s += define("DRAPE_U_THICKNESS", kThickness);
  s += define("DRAPE_U_SHAPE", kShape);
  s += define("DRAPE_U_SOLID_CENTRE", kSolidCentre);
  s += define("DRAPE_U_SOLID_LINEAR", kSolidLinear);
  s += define("DRAPE_U_SOLID_ANGULAR", kSolidAngular);
  s += define("DRAPE_U_NORMAL_DAMPING", kNormalDamping);
  s += define("DRAPE_U_FRICTION", kFriction);
  s += define("DRAPE_U_RING", kRing);
  s += define("DRAPE_U_WEIGHT", kWeight);
  s += define("DRAPE_U_KEEP_START", kKeepStart);
  s += define("DRAPE_U_KEEP_VELOCITY", kKeepVelocity);
  s += define("DRAPE_B_REDUCTION", kReduction);
  s += define("DRAPE_U_SHIFT", kShift);
  s += define("DRAPE_B_FACES", kFaces);
  s += define("DRAPE_U_PGD_ITERATIONS", kPgdIterations);
  s += define("DRAPE_U_REPULSION", kRepulsion);
  s += define("DRAPE_B_PINS", kPins);
  s += define("DRAPE_B_PIN_LAMBDAS", kPinLambdas);
  s += define("DRAPE_SHAPE_PLANE", kPlane);
  s += define("DRAPE_SHAPE_SPHERE", kSphere);
  s += define("DRAPE_SHAPE_BOX", kBox);
  s += define("DRAPE_SHAPE_CAPSULE", kCapsule);
  s += define("DRAPE_SHAPE_CYLINDER", kCylinder);
  s += define("DRAPE_SHAPE_GRID", kGridShape);
  s += define("DRAPE_SHAPE_HULL", kHull);
  s += define("DRAPE_ESTIMATOR_SUB_FORCE", kSubForce);
  s += define("DRAPE_ESTIMATOR_ENERGY", kEnergy);
  s += define("DRAPE_ESTIMATOR_IMPULSE", kImpulse);
  s += define("DRAPE_PUSH_DIRECT", kDirect);
  s += define("DRAPE_PUSH_EXCHANGE", kExchange);
  s += define("DRAPE_PUSH_PINCH", kPinch);
  s += define("DRAPE_B_SHAPE_DATA", kShapeData);
  s += define("DRAPE_B_FLAGS", kFlags);
  s += define("DRAPE_B_GUARD_FROM", kGuardFrom);
  s += define("DRAPE_B_GUARD_MARKS", kGuardMarks);
  s += define("DRAPE_B_HELD", kHeld);
  s += define("DRAPE_U_HELD_PLACE", kHeldPlace);
  s += define("DRAPE_U_SLACK", kSlack);
  s += define("DRAPE_U_PASS", kPass);
  s += define("DRAPE_U_FRESH", kFresh);
  s += define("DRAPE_U_SWEEP", kSweep);
  s += define("DRAPE_CONTACT_SLOTS", kContactSlots);
  s += define("DRAPE_B_SETTLE_POINTS", kSettlePoints);
  s += define("DRAPE_SETTLE_WAITING", kSettleWaiting);
  s += define("DRAPE_SETTLE_BACKED_SHIFT", kSettleBackedShift);
  // drape/kernel_constants.hpp, rounded to float as the kernels use them.
  s += define("DRAPE_MERGE_COS", constants::kMergeCos);
  s += define("DRAPE_FEASIBLE_SLACK", constants::kFeasibleSlack);
  s += define("DRAPE_PARALLEL_PLANES", constants::kParallelPlanes);
  s += define("DRAPE_CORNER_DETERMINANT", constants::kCornerDeterminant);
  s += define("DRAPE_REACH", constants::kReach);
  s += define("DRAPE_FACE_MOVE_CAP", constants::kFaceMoveCap);
  s += define("DRAPE_FACE_SPREAD", constants::kFaceSpread);
  s += define("DRAPE_LEAST_SQUARES_PASSES", constants::kLeastSquaresPasses);
  s += define("DRAPE_EXACT_POINT_SLACK", constants::kExactPointSlack);
  s += define("DRAPE_BACKED_COS", constants::kBackedCos);
  s += define("DRAPE_REFUSED_REACH", constants::kRefusedReach);
  s += define("DRAPE_SEGMENT_FRACTIONS", constants::kSegmentFractions);
  s += define("DRAPE_EIGEN_SWEEPS", constants::kEigenSweeps);
  s += define("DRAPE_EIGEN_NEGLIGIBLE", constants::kEigenNegligible);
  s += define("DRAPE_MAX_CUTS", constants::kMaxCuts);
  s += define("DRAPE_FACE_SEARCH_GAP", constants::kFaceSearchGap);
  s += define("DRAPE_HELD_POINT_SLACK", constants::kHeldPointSlack);
  s += define("DRAPE_FACE_CONTACT_SLACK", constants::kFaceContactSlack);
  // The shaders work in float: the roundings' share of a coordinate, in float's epsilon.
  s += define("DRAPE_FACE_CONTACT_ROUNDING",
              constants::kFaceContactRoundings * double(std::numeric_limits<float>::epsilon()));
  s += define("DRAPE_CUT_SLACK", constants::kCutSlack);
  s += define("DRAPE_FLAT_SINE2", constants::kFlatSine2);
  s += define("DRAPE_CORNER_CULL_SLACK", constants::kCornerCullSlack);
  s += define("DRAPE_PARALLEL_SINE2", constants::kParallelSine2);
  s += define("DRAPE_MIN_DESCENT_STEP", constants::kMinDescentStep);
  s += define("DRAPE_GRID_SEARCH_DEPTH", constants::kGridSearchDepth);
  s += define("DRAPE_GRID_SEARCH_BUDGET", constants::kGridSearchBudget);
  s += define("DRAPE_GRID_LIPSCHITZ", constants::kGridLipschitz);
  s += define("DRAPE_SWEEP_STEPS", constants::kSweepSteps);
  s += define("DRAPE_FACE_SWEEP_STEPS", constants::kFaceSweepSteps);
  s += define("DRAPE_FEATURE_BARYCENTRIC", constants::kFeatureBarycentric);
  s += define("DRAPE_FEATURE_INTERIOR_COS", constants::kFeatureInteriorCos);
  s += define("DRAPE_FEATURE_EDGE_SINE", constants::kFeatureEdgeSine);
  s += define("DRAPE_FEATURE_EDGE_PROBE", constants::kFeatureEdgeProbe);
  s += define("DRAPE_FEATURE_NEWTON_STEPS", constants::kFeatureNewtonSteps);
  s += define("DRAPE_FEATURE_MIN_RATE", constants::kFeatureMinRate);
  s += define("DRAPE_PINCH_RATE", constants::kPinchRate);
  s += define("DRAPE_PINCH_OPPOSING_COS", constants::kPinchOpposingCos);
  s += define("DRAPE_SPACER_GAP", constants::kSpacerGap);
  s += define("DRAPE_SPLIT_GRAM_MIN", constants::kSplitGramMin);
  s += define("DRAPE_LINE_MIN_ALONG", constants::kLineMinAlong);
  s += define("DRAPE_ENERGY_MIN_DISPLACEMENT2", constants::kEnergyMinDisplacement2);
  s += define("DRAPE_B_V_START", kVStart);
  s += define("DRAPE_B_V_PRE", kVPre);
  s += define("DRAPE_B_LINES", kLines);
  s += define("DRAPE_B_PUSHES", kPushes);
  s += define("DRAPE_B_SPACERS", kSpacers);
  s += define("DRAPE_B_BODIES", kBodies);
  s += define("DRAPE_B_BODY_SUMS", kBodySums);
  s += define("DRAPE_B_SHARES", kShares);
  s += define("DRAPE_U_BODY", kBody);
  s += define("DRAPE_U_ESTIMATOR", kEstimator);
  s += define("DRAPE_U_NORMAL_ONLY", kNormalOnly);
  s += define("DRAPE_U_PROPAGATED", kPropagated);
  s += define("DRAPE_U_BOX_LOW", kBoxLow);
  s += define("DRAPE_U_BOX_HIGH", kBoxHigh);
  // A kernel compiled without a choice gets the plane and friction (so every kernel compiles on its own).
  s += "#ifndef DRAPE_SHAPE\n#define DRAPE_SHAPE DRAPE_SHAPE_PLANE\n#endif\n";
  s += "#ifndef DRAPE_FRICTION\n#define DRAPE_FRICTION 1\n#endif\n";
  s += "#ifndef DRAPE_BODY\n#define DRAPE_BODY 0\n#endif\n";
  s += "#ifndef DRAPE_GUARD\n#define DRAPE_GUARD 0\n#endif\n";
  s += "#ifndef DRAPE_SWEEP\n#define DRAPE_SWEEP 0\n#endif\n";
  s += "struct Constraint { uint a; uint b; float rest; uint pad; };\n";
  s += "struct Contact { vec4 normal[DRAPE_CONTACT_SLOTS]; vec4 velocity[DRAPE_CONTACT_SLOTS]; "
       "vec4 friction[DRAPE_CONTACT_SLOTS]; ivec4 body; uvec4 slots; vec4 normalDv; };\n";
  s += "struct SettlePoint { vec4 point; uvec4 bits; };\n";
  s += "struct Ring { vec4 normal; float amount; uint reached; uint pad0; uint pad1; };\n";
  s += "struct PinSlot { vec3 target; uint vertex; };\n";
  s += "struct Lines { vec4 push[DRAPE_CONTACT_SLOTS]; vec4 moment[DRAPE_CONTACT_SLOTS]; };\n";
  s += "struct BodyPush { vec4 force; vec4 torque; int body; int kind; int slot; int pad; };\n";
  s += "struct SpacerRecord { vec4 onBody; vec4 onOther; vec4 normal; int vertex; int body; int other; int slot; };\n";
  s += "struct Body { vec4 centre; vec4 linear; vec4 angular; vec4 inverseInertia[3]; };\n";
  s += "struct BodySum { dvec4 directForce; dvec4 directTorque; dvec4 exchangeForce; dvec4 exchangeTorque; "
       "dvec4 pinchForce; dvec4 pinchTorque; };\n";
  return s;
}

}  // namespace drape::gpu::layout
