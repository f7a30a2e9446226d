#pragma once
// The numbers a CPU kernel and its GLSL twin must agree on, in one place (docs/design.md §9). The C++ kernels
// read them here; the shaders get them from gpu::layout::preamble() as #defines of the same value rounded to
// float, so no number is typed twice and a change here changes both.

namespace drape::constants {

/// Differently facing surfaces a vertex records per substep (a crease, a box corner, a pinch).
inline constexpr int kContactSlots = 3;
/// A contact whose normal is within this cosine of a recorded slot's is the same surface seen again.
inline constexpr double kMergeCos = 0.95;

// The nearest point in up to three half-spaces (nearestInHalfSpaces).
/// A point is inside a half-space n . y >= b up to this much times max(1, |b|).
inline constexpr double kFeasibleSlack = 1e-6;
/// Two planes with 1 - (n_j . n_k)^2 below this are parallel: the single-plane candidates cover them.
inline constexpr double kParallelPlanes = 1e-6;
/// Three planes whose normals' determinant is below this have no corner worth trying.
inline constexpr double kCornerDeterminant = 1e-4;
/// Farthest accepted move to the planes, in total violations (tangent planes say nothing far away).
inline constexpr double kReach = 4;
/// Passes of the least-squares compromise for a point pinched between surfaces (leastSquaresCompromise).
inline constexpr int kLeastSquaresPasses = 2;
/// The settle's exact point y is tested against the true fields (docs/design.md §16, "Exact points tested"): a
/// plane is one y lies on within this share of the vertex's total violation, and a field reads y as on its
/// surface within the thickness and that share.
inline constexpr double kExactPointSlack = 0.25;
/// A solid backs a plane at y where its gradient there is within this cosine of the plane's normal (5.7 degrees).
inline constexpr double kBackedCos = 0.995;
/// A refused exact point with some plane backed takes the least-squares compromise cut at 1/this^2.
inline constexpr double kRefusedReach = 2.5;
/// One with none backed takes the first of this many fractions of the segment from the vertex to y that every
/// solid leaves clear (one bit each in a 32-bit word: at most 32).
inline constexpr int kSegmentFractions = 32;
/// Sweeps of Jacobi rotations in the eigen-decomposition of its 3x3 normal matrix (symmetricEigen3).
inline constexpr int kEigenSweeps = 5;
/// An off-diagonal entry at most this times the sum of its two diagonal entries is left alone by the rotations.
inline constexpr double kEigenNegligible = 1e-12;

// The search for a face's deepest point (docs/design.md §3).
/// Most cutting planes the convex search keeps.
inline constexpr int kMaxCuts = 16;
/// The search stops within this many longest-edge lengths of the certified minimum.
inline constexpr double kFaceSearchGap = 3e-4;
/// A cut is kept while it is within this share of the tolerance of the model's minimum.
inline constexpr double kCutSlack = 0.01;
/// A face whose deepest point is within this share of the thickness of the contact shell, and this many roundings
/// of its coordinates besides, is left alone. A face lying on a flat side, its corners just placed at the
/// thickness by their own contacts, reads up to about one rounding of its point's largest coordinate inside it
/// (docs/design.md §3, "Faces at the thickness"). On a 5 mm thickness the share is 0.1 micrometre.
inline constexpr double kFaceContactSlack = 2e-5;
inline constexpr double kFaceContactRoundings = 4;
/// A face's held deepest point is kept while it is within this share of the search's tolerance of the search's
/// answer (HeldPoints): wide enough for float's rounding of equally deep points, narrow enough to bias no push.
inline constexpr double kHeldPointSlack = 0.01;
/// A face whose sine of the angle between its edges from the first corner is below the root of this is flat for
/// the closed-form nearest point: rounding (a fused multiply-add) can put it in the wrong Voronoi region.
inline constexpr double kFlatSine2 = 1e-6;
/// A capsule's core and a face's edge whose sine of the angle between them is below the root of this are
/// parallel for the closed-form nearest point (nearestToSegment): their lines' nearest points are then not sought.
inline constexpr double kParallelSine2 = 1e-5;
/// A face is culled from a ball by its corners (queryFace) only where they clear the ball's reach grown by this
/// share of it, so that rounding cannot cull a face that the nearest point would keep.
inline constexpr double kCornerCullSlack = 1e-4;
/// Projected gradient descent stops when a step moves every barycentric coordinate less than this.
inline constexpr double kMinDescentStep = 1e-3;
/// The face search on grid fields splits a face at most this many times (sub-triangles 1/4096 of its size)...
inline constexpr int kGridSearchDepth = 12;
/// ... and reads at most about this many cells (eight nodes each) per face.
inline constexpr int kGridSearchBudget = 512;
/// A Lipschitz constant of a grid field everywhere: inside the grid each partial derivative is an average of
/// node differences, at most 1 in size (sqrt(3) in all), and outside it sqrt(e^2 + g^2) or g + e adds the
/// box distance's 1; rounded up past the nodes' float rounding.
inline constexpr double kGridLipschitz = 2.75;

// A face on a sharp feature of a solid (docs/design.md §3, "Feature normals").
/// A face's deepest point with every barycentric coordinate above this is inside the face; with one at or below
/// it, on the opposite edge.
inline constexpr double kFeatureBarycentric = 1e-3;
/// Inside the face, a field gradient within this cosine of the face's normal is kept.
inline constexpr double kFeatureInteriorCos = 0.99;
/// On an edge, a field gradient whose component along the edge is below this is kept.
inline constexpr double kFeatureEdgeSine = 0.05;
/// On an edge of a face, on a field with edges, the gradient is also read this far (a fraction of the edge's
/// length) to either side of the deepest point along the edge.
inline constexpr double kFeatureEdgeProbe = 0.05;
/// Newton steps that carry the deepest point to the thickness along the new direction.
inline constexpr int kFeatureNewtonSteps = 2;
/// The new direction is used, and a Newton step taken, only where the field grows at least this fast along it.
inline constexpr double kFeatureMinRate = 0.05;

// A face contact's moves (projectFaceContactsAs, docs/design.md §4).
/// No corner of a face moves more than this many times the depth its deepest point is pushed: where the face's
/// free corners carry little of that point (its other corners pinned, or far heavier), the exact move, depth /
/// b, grows without bound as their weight b goes to 0. A uniform sheet's faces never reach it (at most 1.37
/// with equal masses, 1.82 where one corner has a third of the others' mass; with kFaceSpread 1.11 and 2.02).
inline constexpr double kFaceMoveCap = 3;
/// On a field with edges and sides, corner k of a face contact takes a share w_k (b_k + kFaceSpread) of the push,
/// not the least-norm w_k b_k: a face lying along an edge or a side is about as deep along a segment of itself,
/// and pushed from one end of it alone it tilts until the other end is deepest, a two-substep cycle.
inline constexpr double kFaceSpread = 1;

// Continuous contact (docs/design.md §18).
/// A vertex whose path in a substep, relative to a solid, is shorter than this share of the thickness is left to
/// the discrete passes: starting outside the thickness it cannot reach the solid's far side.
inline constexpr double kSweepGate = 0.5;
/// Most field evaluations along one vertex's path (conservative advancement).
inline constexpr int kSweepSteps = 64;
/// Most face searches along one face's sweep.
inline constexpr int kFaceSweepSteps = 32;
/// Position friction may carry a face along a solid but not within this share of the thickness of it: a face
/// whose corners friction moved and whose path came that close goes back (the friction guard).
inline constexpr double kFrictionGuard = 0.5;

// Several solids meeting (docs/design.md §16).
/// Extra vertex passes on the true fields where solids meet.
inline constexpr int kSettlePasses = 4;
/// Those passes leave a vertex alone within this share of the thickness of the contact shell.
inline constexpr double kSettleSlack = 1e-4;

// Two-way coupling (docs/design.md §6).
/// Share of a pinch's overlap its support undoes per substep.
inline constexpr double kPinchRate = 0.2;
/// A fixed solid pinches a vertex against a body when their normals' cosine is below this.
inline constexpr double kPinchOpposingCos = -0.5;
/// A pinch's spacer keeps the body this many thicknesses off the surface behind the cloth: a quarter short of
/// the cloth's two, so that a body resting on the cloth is held by the pinch's support alone and the spacer
/// acts only where another body presses it further (RigidWorld::addSpacer).
inline constexpr double kSpacerGap = 1.75;
/// A vertex touching several solids has its velocity change split among their normals where the normals' Gram
/// determinant (the squared volume they span) is above this; below it (surfaces facing each other), each slot
/// takes its whole normal part.
inline constexpr double kSplitGramMin = 1e-2;
/// A slot's contacts share a line of action only where its summed push is at least this along its normal.
inline constexpr double kLineMinAlong = 0.5;
/// The energy estimate needs a displacement of squared length above this (m^2).
inline constexpr double kEnergyMinDisplacement2 = 1e-24;

}  // namespace drape::constants
