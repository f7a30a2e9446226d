#pragma once
// Solver settings: plain fields with defaults and units. validate() names the first bad field.

#include <drape/math.hpp>

#include <string>

namespace drape {

/// How contacts are resolved each substep (docs/design.md §1, §4, §14).
enum class CollisionMethod {
  /// Vertex and face contacts, projected after the velocity update (a face's deepest point found by PGD); each
  /// contact vertex's velocity relative to the solid is split (normal part attenuated, tangential part kept,
  /// Coulomb friction), and the normal corrections are propagated to neighbouring vertices. The SDF collision
  /// paper's method, and the default.
  Faces,
  /// Vertex contacts only, with the split: cheaper, but misses solid features smaller than the cloth's spacing.
  Vertices,
  /// Vertex and face contacts projected inside the constraint solve, with position-level friction; velocities
  /// come from the positions: no split, no propagation. The "previous method" that paper improves on, kept to
  /// compare against.
  InSolve,
};

inline const char* toString(CollisionMethod m) {
  switch (m) {
    case CollisionMethod::Faces: return "faces";
    case CollisionMethod::Vertices: return "vertices";
    case CollisionMethod::InSolve: return "in-solve";
  }
  return "?";
}

/// The method named "faces", "vertices" or "in-solve" (toString's names); throws drape::Error for another.
inline CollisionMethod collisionMethodFromString(const std::string& name) {
  for (CollisionMethod m : {CollisionMethod::Faces, CollisionMethod::Vertices, CollisionMethod::InSolve})
    if (name == toString(m)) return m;
  throw Error("drape: unknown collision method '" + name + "' (faces, vertices, in-solve)");
}

/// How the cloth's push on a dynamic solid is estimated (the cloth-rigid coupling thesis, 5.2; docs/design.md §6).
/// Each is explicit: per contact, the force on the particle is reversed onto the body at the contact point, summed
/// into one force and torque per body and applied in the same substep. The velocity the repulsion region (phase 1)
/// takes from a particle near a dynamic solid is passed on as an impulse whatever the estimator (the thesis's
/// combination: the energy estimate has no displacement to work with before contact).
enum class ContactForce {
  /// (F . n) n of the net force on the particle other than the contact (constraints, gravity) where it presses
  /// into the body: right for a resting load, blind to the particle's own momentum.
  SubForce,
  /// The work that changed the particle's kinetic energy over its displacement: (dE - F_other . d) / |d|^2 d.
  /// Underestimates where the particle and the body move oppositely; no force without a displacement.
  Energy,
  /// The momentum the contact gave the particle, m dv / h: the larger of the velocity change and the position
  /// correction over h along the normal (they agree where the particle can move; where it cannot, pinched
  /// against another surface, the correction carries the load), plus the tangential (friction) change.
  Impulse,
};

inline const char* toString(ContactForce f) {
  switch (f) {
    case ContactForce::SubForce: return "sub-force";
    case ContactForce::Energy: return "energy";
    case ContactForce::Impulse: return "impulse";
  }
  return "?";
}

/// The estimator named "sub-force", "energy" or "impulse" (toString's names); throws drape::Error for another.
inline ContactForce contactForceFromString(const std::string& name) {
  for (ContactForce f : {ContactForce::SubForce, ContactForce::Energy, ContactForce::Impulse})
    if (name == toString(f)) return f;
  throw Error("drape: unknown contact force estimator '" + name + "' (sub-force, energy, impulse)");
}

struct Settings {
  int subStepCount = 10;   ///< substeps per step(dt); h = dt / subStepCount
  int iterationCount = 1;  ///< constraint-solve passes per substep

  Eigen::Vector3d gravity{0, 0, -9.81};  ///< m/s^2

  // XPBD compliances (inverse stiffness). 0 is rigid. Distance constraints: m/N.
  double stretchCompliance = 0;   ///< structural edges
  double shearCompliance = 0;     ///< grid diagonals
  double bendingCompliance = 1e-3;  ///< far-vertex pairs across interior edges: small values keep the cloth flat
  double pinCompliance = 0;       ///< attachments of pinned vertices to their targets

  CollisionMethod collisionMethod = CollisionMethod::Faces;
  double thickness = 0.005;    ///< m: contacts hold the cloth this far outside each solid
  double normalDamping = 1;    ///< fraction of the separating normal velocity a contact removes, in [0, 1]
  /// 1/s: each free vertex's velocity decays as exp(-airDamping t), the loss to still air (and to the cloth's own
  /// internal friction) that the constraints do not model. 0 keeps every motion: a skirt hanging from a ball at 2
  /// substeps then still swings at 2.6e-4 m/s after 20 s, losing only what the solver dissipates (docs/design.md
  /// §1). It damps sliding too: on a frictionless slope the cloth's speed tends to g sin(angle) / airDamping.
  double airDamping = 0;
  int pgdIterations = 12;      ///< most SDF evaluations per face in the deepest-point search (>= 1); it
                               ///< stops earlier once certified, so this only caps curved faces
  bool culling = true;         ///< bounding-sphere culling of faces (exact: it never drops a contact)
  /// On grid fields (MeshShape) the face search is the exact branch and bound (docs/design.md §3). False trades it
  /// for the projected gradient descent, 4-9 times cheaper on meshed scenes but able to miss a face's deepest
  /// point by a sizeable share of its edge. The GPU runs only the exact search.
  bool exactGridSearch = true;
  /// Continuous contact (docs/design.md §18): where a vertex or a face travelled further than half the thickness
  /// relative to a bounded solid (any but the plane) in a substep, its path is searched for the first place it
  /// came within the thickness, so a fast cloth or few substeps cannot carry it through a thin solid. Costs
  /// nothing where nothing moves that fast. Applies to the faces and vertices methods, not to the in-solve
  /// baseline.
  bool continuousContact = false;
  /// Contacts with bounded solids (every shape but the plane) go through a uniform grid of the cloth's vertices,
  /// rebuilt once they have moved half a cell from where it binned them, so each such solid costs in proportion to the cloth near it rather than to the whole
  /// cloth (many rigid bodies at linear cost). The contacts are the same either way, bit for bit; off, every
  /// solid visits every vertex and face (cheaper only for a solid that covers the whole cloth).
  bool broadPhase = true;
  /// Restores, after each substep's constraint solve, the angular momentum its corrections added from nothing
  /// (docs/design.md §4): without it a cloth draped on a frictionless sphere turns about the sphere's axis at
  /// 0.2-0.65 rad/s after 10 s at 10 substeps, with it under 2e-3. On balls and capsules each face contact's
  /// corner then also answers along its own normal, and propagation follows the surface's curvature. Costs two
  /// passes over the vertices per substep, about 30 % of a step. CPU only, for now.
  bool keepAngularMomentum = false;
  /// Tethers (docs/design.md §1, "Tethers"): each free vertex is kept within its rest distance along the cloth of
  /// the four kinematic vertices (inverse mass 0) nearest it, after every pass of the constraint solve. One pass
  /// carries a pin's pull only a few edges a substep, so a cloth hanging from a few pinned vertices stretches beside
  /// them (a 1 x 1.6 m sheet hung by its corners: a largest strain of 1.24 at the default 10 substeps, 11.8 at 2);
  /// tethered, 0.10 and 0.36. Costs nothing without kinematic vertices. CPU only, for now.
  bool tethers = false;
  double propagationWeight = 0.5;  ///< share of a contact's normal velocity correction given to neighbours
  int propagationRings = 1;        ///< how many rings of neighbours receive it (0: none)

  ContactForce contactForce = ContactForce::Impulse;  ///< how the push on dynamic solids is estimated
  bool normalForceOnly = false;  ///< pass only the normal part of each contact force (the thesis's cure for
                                 ///< noisy torque from the energy and impulse estimates)

  /// Threads a step uses (OpenMP): 1 runs on the calling thread, 0 uses OpenMP's default team size. The
  /// result is bit-identical for every count. Without OpenMP at compile time every count runs on one thread.
  int threadCount = 1;

  /// The share of its velocity a free vertex keeps over a substep of h seconds, exp(-airDamping h): the one
  /// factor both solvers' predictions apply.
  double velocityKept(double h) const { return std::exp(-airDamping * h); }

  /// Throws drape::Error naming the first out-of-range field.
  void validate() const {
    using detail::require;
    using detail::requireRange;
    require(subStepCount >= 1 && subStepCount <= 10000,
            "subStepCount must be in [1, 10000] (got " + std::to_string(subStepCount) + ")");
    require(iterationCount >= 1 && iterationCount <= 1000,
            "iterationCount must be in [1, 1000] (got " + std::to_string(iterationCount) + ")");
    require(detail::allFinite(gravity) && gravity.cwiseAbs().maxCoeff() <= limits::kMaxAcceleration, [&] {
      return "gravity must be finite with components within +-1e6 m/s^2 (got (" + detail::formatNumber(gravity.x()) +
             ", " + detail::formatNumber(gravity.y()) + ", " + detail::formatNumber(gravity.z()) + "))";
    });
    requireRange(stretchCompliance, 0, 1e6, "stretchCompliance");
    requireRange(shearCompliance, 0, 1e6, "shearCompliance");
    requireRange(bendingCompliance, 0, 1e6, "bendingCompliance");
    requireRange(pinCompliance, 0, 1e6, "pinCompliance");
    require(collisionMethod == CollisionMethod::Faces || collisionMethod == CollisionMethod::InSolve ||
                collisionMethod == CollisionMethod::Vertices,
            "collisionMethod is not one of faces, vertices, in-solve");
    require(std::isfinite(thickness) && thickness > 0 && thickness <= 1,
            "thickness must be in (0, 1] m (got " + detail::formatNumber(thickness) + ")");
    requireRange(normalDamping, 0, 1, "normalDamping");
    requireRange(airDamping, 0, 1e4, "airDamping");
    require(pgdIterations >= 1 && pgdIterations <= 1000,
            "pgdIterations must be in [1, 1000] (got " + std::to_string(pgdIterations) + ")");
    requireRange(propagationWeight, 0, 1, "propagationWeight");
    require(propagationRings >= 0 && propagationRings <= 8,
            "propagationRings must be in [0, 8] (got " + std::to_string(propagationRings) + ")");
    require(contactForce == ContactForce::SubForce || contactForce == ContactForce::Energy ||
                contactForce == ContactForce::Impulse,
            "contactForce is not one of sub-force, energy, impulse");
    require(threadCount >= 0 && threadCount <= 1024,
            "threadCount must be in [0, 1024] (got " + std::to_string(threadCount) + ")");
  }
};

}  // namespace drape
