#pragma once
// The cloth solver on the GPU (docs/design.md §9): the CPU solver's substep loop, each kernel a compute
// dispatch on buffers that stay on the GPU. The state is uploaded once, stepped many times, and read back on
// demand (position(), velocity(), state()): nothing crosses the bus between steps unless asked.
//
// What it runs so far, for float: predict, the distance constraints (stretch, shear, bending; one dispatch per
// colour, all iterations, with the XPBD multipliers when several passes meet a compliant set), the velocity
// update, and against any number of solids (planes, spheres, boxes, capsules, cylinders, hulls and grid fields from
// meshes, static, kinematic or dynamic, visited in the CPU solver's order: by shape type, then as added) the repulsion
// region and the faces and vertices collision methods: per solid the vertex pass and the face pass
// (bounding-sphere cull and the search for the deepest point, cutting planes on convex fields and projected
// gradient descent on a grid's, one dispatch per colour of faces that share no vertex), each vertex recording up
// to three differently facing surfaces as the CPU does; where surfaces meet, the placement outside all of a
// vertex's contact planes and the settle passes; the velocity split with Coulomb friction, per surface, then
// reconciled; and propagation ring by ring; and the local origin following the cloth, as on the CPU; fixed
// vertices (inverse mass 0) and pins with targets. Convex hulls, the in-solve method and the two-way coupling with
// dynamic bodies run too (see the kernels' list in docs/design.md §9). The GPU always culls (boxes, bounding
// spheres), which drops no contact; settings that turn culling or the broad phase off are rejected.
//
// Against planes the GPU gives the CPU's bits on llvmpipe. Against a curved solid the face pass visits the
// faces colour by colour where the CPU goes in index order (another order of the same Gauss-Seidel pass); the
// two then agree on the scene's invariants, not bit for bit.
//
// Each kernel in shaders/ has its CPU twin named in its header comment; tests/gpu/ compares each pair.

#include <drape/cloth/asset.hpp>
#include <drape/cloth/state.hpp>
#include <drape/front_end.hpp>
#include <drape/gpu/coupling.hpp>
#include <drape/gpu/program.hpp>
#include <drape/gpu/shapes.hpp>
#include <drape/gpu/solid_kernels.hpp>
#include <drape/gpu/shader_sources.hpp>
#include <drape/settings.hpp>

#include <drape/sdf/solid.hpp>

#include <algorithm>
#include <array>
#include <limits>
#include <memory>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

namespace drape::gpu {

/// Faces in colours that share no vertex, for the face pass: colour c is faces[offsets[c], offsets[c + 1]), each
/// as (a, b, c, 0), in index order within the colour.
struct FaceColours {
  std::vector<std::array<std::uint32_t, 4>> faces;
  std::vector<std::size_t> offsets;
};

/// Greedy colouring in index order: a face takes the lowest colour none of its vertices has yet (at most 32; a
/// grid cloth takes 6 to 8). Throws drape::Error if a vertex is in so many faces that 32 do not do.
inline FaceColours colourFaces(const std::vector<std::array<Index, 3>>& triangles, Index vertexCount) {
  std::vector<std::uint32_t> taken(std::size_t(vertexCount), 0);  // bit c: colour c has the vertex
  std::vector<int> colour(triangles.size());
  int colours = 0;
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    std::uint32_t used = 0;
    for (Index v : triangles[f]) used |= taken[std::size_t(v)];
    int c = 0;
    while (c < 32 && (used >> c & 1u)) ++c;
    drape::detail::require(c < 32, "the GPU face pass needs at most 32 face colours (face " + std::to_string(f) +
                                       " has a vertex in too many faces)");
    colour[f] = c;
    for (Index v : triangles[f]) taken[std::size_t(v)] |= 1u << c;
    colours = std::max(colours, c + 1);
  }
  FaceColours out;
  out.offsets.assign(1, 0);
  for (int c = 0; c < colours; ++c) {
    for (std::size_t f = 0; f < triangles.size(); ++f)
      if (colour[f] == c)
        out.faces.push_back({std::uint32_t(triangles[f][0]), std::uint32_t(triangles[f][1]),
                             std::uint32_t(triangles[f][2]), 0u});
    out.offsets.push_back(out.faces.size());
  }
  return out;
}

class Solver : public SolverFront<Solver, float, DRAPE_BUILT_IN_SHAPES> {
  using Front = SolverFront<Solver, float, DRAPE_BUILT_IN_SHAPES>;
  friend Front;

 public:
  /// Uploads the asset's constraints and its rest state (masses from areaDensity, kg/m^2). `context` must be
  /// current and outlive the solver.
  Solver(Context& context, std::shared_ptr<const ClothAsset<float>> asset, const Settings& settings = {},
         double areaDensity = 0.1)
      : Front((context.makeCurrent(), std::move(asset)), settings, areaDensity),  // current before the kernels compile
        context_(&context),
        predict_("predict", shaders::predict),
        solve_("solve_distance", shaders::solve_distance),
        update_("update_velocity", shaders::update_velocity),
        respond_("respond", shaders::respond, "#define DRAPE_FRICTION 0\n"),
        respondFriction_("respond", shaders::respond, "#define DRAPE_FRICTION 1\n"),
        propagate_("propagate", shaders::propagate),
        centre_("centre", shaders::centre),
        translate_("translate", shaders::translate),
        pinKernel_("pins", shaders::pins),
        settle_("settle", shaders::settle),
        settlePlace_("settle", shaders::settle, "#define DRAPE_SETTLE_PLACE 1\n"),
        frictionKernel_("friction", shaders::friction),
        restore_("restore_marked", shaders::restore_marked),
        holdPlane_("hold_planes", shaders::hold_planes, shapeDefine<Plane>()) {
    // The three sets, colour by colour, in one buffer: set s's colour c starts at offset_[s] + colourOffsets[c].
    std::vector<layout::Constraint> constraints;
    const DistanceSet<float>* sets[3] = {&asset_->stretch, &asset_->shear, &asset_->bending};
    for (int s = 0; s < 3; ++s) {
      setStart_[s] = constraints.size();
      for (Index k = 0; k < sets[s]->size(); ++k) {
        const auto& p = sets[s]->pairs[std::size_t(k)];
        constraints.push_back({std::uint32_t(p[0]), std::uint32_t(p[1]), sets[s]->restLength[std::size_t(k)], 0u});
      }
    }
    constraints_.assign(constraints);
    lambdas_.assign(std::vector<float>(constraints.size(), 0.0f));
    const std::vector<layout::Vertex> zero(state_.x.size(), layout::Vertex{0, 0, 0, 0});
    positions_.assign(zero);
    velocities_.assign(zero);
    predicted_.assign(zero);
    packed_.assign(zero);
    start_.assign(zero);
    contacts_.assign(std::vector<layout::Contact>(zero.size(), layout::Contact{}));
    rings_.assign(std::vector<layout::Ring>(zero.size(), layout::Ring{}));
    reduction_.assign(std::vector<layout::Vertex>(1));
    settleCommands_.assign(std::vector<std::uint32_t>(3 * constants::kSettlePasses, 0u));
    const Adjacency& around = asset_->vertexNeighbours;
    neighbourOffsets_.assign(std::vector<std::uint32_t>(around.offsets.begin(), around.offsets.end()));
    neighbours_.assign(std::vector<std::uint32_t>(around.items.begin(), around.items.end()));
    uploadFaces();
    upload();
  }

  /// The GPU's position buffer (vec4: position relative to state().origin, inverse mass) and the faces, colour
  /// by colour, for drawing the cloth where it is (Renderer::drawTriangles) without reading it back.
  const Buffer<layout::Vertex>& positionBuffer() const { return positions_; }
  const Buffer<std::array<std::uint32_t, 4>>& faceBuffer() const { return faces_; }
  /// The last substep's contact records (layout::Contact per vertex), for tools and tests that read them back.
  const Buffer<layout::Contact>& contactBuffer() const { return contacts_; }
  /// The local origin the positions are relative to (world, m): the state's, without reading the state back.
  const Eigen::Vector3d& origin() const { return state_.origin; }

  /// Waits until the GPU has done every step asked of it (for timing: step() returns once it is queued).
  void finish() const {
    context_->makeCurrent();
    glFinish();
  }
 private:
  // The front end is not a dependent base here: its members are found without using-declarations.
  void uploadFaces() {
    const FaceColours coloured = gpu::colourFaces(asset_->triangles, vertexCount());
    faceColourOffsets_ = coloured.offsets;
    faces_.assign(coloured.faces);
    held_.assign(std::vector<layout::Vertex>(coloured.faces.size(), layout::Vertex{0, 0, 0, 0}));
  }

  // --- the front end's hooks (SolverFront) ------------------------------------------------------------------
  void loadState() const { download(); }
  void storeState(StateChange) { upload(); }
  /// An undoable step's start: copies on the device, so keeping it costs no read-back.
  void keepStart() {
    context_->makeCurrent();
    copyVertices(positions_, keptPositions_);
    copyVertices(velocities_, keptVelocities_);
    copyVertices(held_, keptHeld_, held_.size());
  }
  void restoreStart() {
    context_->makeCurrent();
    copyVertices(keptPositions_, positions_);
    copyVertices(keptVelocities_, velocities_);
    copyVertices(keptHeld_, held_, held_.size());
    fresh_ = false;
  }
  void copyVertices(const Buffer<layout::Vertex>& from, Buffer<layout::Vertex>& to, std::size_t count = 0) {
    const std::size_t n = count > 0 ? count : state_.x.size();
    if (to.size() != n) to.assign(std::vector<layout::Vertex>(n));
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glCopyNamedBufferSubData(from.id(), to.id(), 0, 0, GLsizeiptr(n * sizeof(layout::Vertex)));
  }
  /// The settings the GPU does not run: it always culls (bounding boxes and spheres, which drop no contact) and
  /// its parallelism is the device's, so turning culling or the broad phase off, or asking for CPU threads,
  /// is an error rather than a setting silently ignored.
  static void checkSettings(const Settings& s) {
    drape::detail::require(s.culling, "the GPU solver always culls faces: Settings::culling = false is not supported");
    drape::detail::require(s.exactGridSearch, "the GPU solver runs the exact face search on grid fields: "
                                              "Settings::exactGridSearch = false is not supported");
    drape::detail::require(!s.keepAngularMomentum, "the GPU solver does not yet restore the solve's angular "
                                                   "momentum: Settings::keepAngularMomentum = true is not supported");
    drape::detail::require(!s.tethers, "the GPU solver does not yet run tethers: Settings::tethers = true is not "
                                       "supported");
    drape::detail::require(s.broadPhase,
                           "the GPU solver always culls by bounding box: Settings::broadPhase = false is not supported");
    drape::detail::require(s.threadCount == 1, [&] {
      return "the GPU solver runs on the device: Settings::threadCount must be 1 (got " +
             std::to_string(s.threadCount) + ")";
    });
  }
  /// Compiles the solid's kernels before the front end takes it (a kernel that fails to compile changes nothing).
  template <class Shape> void checkSolid(const Solid<Shape>& solid) {
    context_->makeCurrent();
    kernels_.compileFor<Shape>(solid.motion == Motion::Dynamic);
  }
  /// Uploads the shape data of solid k (a mesh's grid, a hull's faces), and frees what no solid uses any more.
  template <class Shape> void solidSet(Index k) {
    kernels_.upload(std::get<std::vector<CompiledSolid<Shape, float>>>(compiled_)[std::size_t(k)]);
    kernels_.dropUnused();
    if (held_.size() > 0) {  // a place may now hold another solid: nothing held
      glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
      glClearNamedBufferData(held_.id(), GL_R32F, GL_RED, GL_FLOAT, nullptr);
    }
  }

  /// Moves the local origin after the cloth (SolverFront::moveOrigin). The centre is summed on the GPU.
  void beginStep() {
    context_->makeCurrent();
    const auto n = unsigned(vertexCount());
    positions_.bind(layout::kPositions);
    reduction_.bind(layout::kReduction);
    centre_.set(layout::kCount, n);
    glUseProgram(centre_.id());
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    const layout::Vertex c = reduction_.read()[0];
    const Eigen::Vector3d shift = moveOrigin(Eigen::Vector3d(c.x, c.y, c.z));
    if (shift.isZero(0)) return;
    const Vec3<float> shiftF = shift.cast<float>();
    translate_.set(layout::kCount, n);
    translate_.set(layout::kShift, shiftF.x(), shiftF.y(), shiftF.z());
    translate_.dispatch(n);
  }

  /// This substep's solids in the CPU solver's order (by shape type, then as added), each moved first if
  /// kinematic (prepareSolids) and its field packed for the kernels (packShape).
  void prepareSolids(double hd) {
    passes_.clear();
    const bool maySweep = settings_.continuousContact && settings_.collisionMethod != CollisionMethod::InSolve;
    const bool mayGuard = settings_.continuousContact && settings_.collisionMethod == CollisionMethod::Faces;
    const SolidFeatures has = Front::prepareSolids(hd, [&](const auto& compiled, const auto&) {
      passes_.push_back(kernels_.pass(compiled));
      if (maySweep && compiled.bounded)
        kernels_.compileSweepFor(compiled, compiled.motion.body >= 0);
      if (mayGuard && compiled.bounded) kernels_.compileGuardFor(compiled);
      // A scene that reconciles (several solids, or a curved one) judges the settle's exact points by every field.
      if (solidCount() > 1 || !std::decay_t<decltype(compiled.sdf)>::kLinear) kernels_.compileSettleFor(compiled);
    });
    friction_ = has.friction;
    repulsive_ = has.repulsion;
    reconcile_ = has.reconcile;
    coupled_ = has.coupled;
    if (reconcile_ && settlePoints_.size() != state_.x.size())
      settlePoints_.assign(std::vector<layout::SettlePoint>(state_.x.size(), layout::SettlePoint{}));
    sweep_ = settings_.continuousContact && settings_.collisionMethod != CollisionMethod::InSolve && has.bounded > 0;
    // Position friction must not carry a face across a solid: continuous contact with faces guards it.
    guard_ = sweep_ && friction_ && settings_.collisionMethod == CollisionMethod::Faces;
    // Friction and pushes of a moving solid beside a plane may carry a vertex into the plane (hold_planes.comp).
    const auto isPlane = [](const SolidPass& p) { return p.code == layout::kPlane; };
    holdPlanes_ = friction_ && has.moving && solidCount() > 1 &&
                  settings_.collisionMethod != CollisionMethod::InSolve &&
                  std::any_of(passes_.begin(), passes_.end(), isPlane);
    if ((guard_ || holdPlanes_) && guardFrom_.size() != state_.x.size())
      guardFrom_.assign(std::vector<layout::Vertex>(state_.x.size()));
    if (guard_ && guardMarks_.size() != state_.x.size())
      guardMarks_.assign(std::vector<std::uint32_t>(state_.x.size(), 0u));
    if (coupled_) coupling_.reserve(state_.x.size(), bodies_.size());  // the coupling's buffers, once it has a body
  }

  /// Vertices with several contact planes go outside all of them (projectOntoContactPlanes) in three stages
  /// (docs/design.md §16, "Exact points tested"): the placement, which writes the exact points it finds as waiting;
  /// each solid's judgement of them; the waiting vertices placed by it. In settle pass `pass` only if that pass
  /// found a contact (the command its vertex passes wrote).
  void settle(int pass) {
    const auto n = unsigned(vertexCount());
    const float thickness = float(settings_.thickness);
    const auto run = [&](const Program& k) {
      k.set(layout::kCount, n);
      if (pass < 0) k.dispatch(n);
      else k.dispatchIndirect(settleCommands_.id(), settleCommand(pass));
    };
    run(settle_);
    for (const SolidPass& p : passes_)
      if (pass < 0) kernels_.settlePass(p, thickness, n);
      else kernels_.settlePass(p, thickness, n, settleCommands_.id(), settleCommand(pass));
    run(settlePlace_);
  }
  /// Where settle pass `pass`'s dispatch command lies in settleCommands_, in bytes.
  static GLintptr settleCommand(int pass) { return GLintptr(3 * sizeof(std::uint32_t)) * pass; }

  /// What coupled body b's repulsion region took from or gave the vertices, reversed onto the body
  /// (gatherRepulsionForces): the pushes its repel kernel wrote (to b alone), summed, start the substep's force
  /// and torque. Only b's sum is made and read: a pass over the vertices per repelling body.
  void gatherRepulsionForces(int b) {
    const layout::BodySum s = coupling_.sumPushes(b, 1, unsigned(vertexCount()))[0];
    bodyForce_[std::size_t(b)] += Eigen::Vector3d(s.directForce[0], s.directForce[1], s.directForce[2]);
    bodyTorque_[std::size_t(b)] += Eigen::Vector3d(s.directTorque[0], s.directTorque[1], s.directTorque[2]);
  }

  /// All contacts of a substep (projectAll, as on the CPU): per solid the vertex pass, then (a curved solid, when
  /// `faces`) the face pass; where surfaces meet, the placement outside all of a vertex's contact planes and,
  /// with several solids, the settle passes. The faces' buffer is bound here.
  /// `h`: the substep, for continuous contact (0 for none: the in-solve method's contacts).
  void projectAll(bool faces, float h = 0.0f) {
    faces = faces && settings_.collisionMethod != CollisionMethod::Vertices;
    if (faces) faces_.bind(layout::kFaces), held_.bind(layout::kHeld);
    const float thickness = float(settings_.thickness);
    const auto n = unsigned(vertexCount());
    const float gate = float(constants::kSweepGate) * thickness;
    for (std::size_t k = 0; k < passes_.size(); ++k) {
      // Continuous contact sweeps bounded solids only (a half-space has no far side), as on the CPU.
      const Eigen::Vector2f sweep =
          sweep_ && h > 0.0f && passes_[k].curved ? Eigen::Vector2f(h, gate * gate) : Eigen::Vector2f::Zero();
      // Where the face pass answers every vertex within the thickness (a ball's; ContactPasses::projectSolid's
      // kVertexPass), the vertex pass, if it is the substep's first, only starts the records (a slack past any depth).
      if (!(faces && passes_[k].facesAnswerVertices && sweep.y() <= 0.0f))
        kernels_.vertexPass(passes_[k], thickness, n, k == 0, -1, 0.0f, sweep);
      else if (k == 0)
        kernels_.vertexPass(passes_[k], thickness, n, true, -1, std::numeric_limits<float>::infinity(), sweep);
      if (faces && passes_[k].curved)
        kernels_.facePass(passes_[k], thickness, settings_.pgdIterations, faceColourOffsets_, sweep,
                          unsigned(k + 1));
    }
    if (!reconcile_) return;
    settle(-1);
    if (passes_.size() < 2) return;
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);  // a clear after shader writes
    glClearNamedBufferData(settleCommands_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
    const float slack = float(constants::kSettleSlack) * thickness;
    for (int pass = 0; pass < constants::kSettlePasses; ++pass) {
      // The first settle pass always runs; each later one only if the one before it found a contact.
      const GLintptr command = pass == 0 ? -1 : settleCommand(pass - 1);
      for (const SolidPass& p : passes_)
        kernels_.vertexPass(p, thickness, n, false, pass, slack, Eigen::Vector2f::Zero(), settleCommands_.id(),
                            command);
      settle(pass);
    }
  }

  /// CollisionMethod::InSolve's collisions inside the solve (collideInSolve, as on the CPU), on the positions the solve has reached:
  /// those go to the positions' buffer, the contacts are projected there (pinched vertices start from the
  /// prediction) with position friction, and the result goes back to the solve's.
  void collideInSolve(float h) {
    const auto bytes = GLsizeiptr(std::size_t(vertexCount()) * sizeof(layout::Vertex));
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glCopyNamedBufferSubData(packed_.id(), positions_.id(), 0, 0, bytes);  // both hold the inverse mass in w
    predicted_.bind(layout::kPacked);  // the settle placement's reference: the prediction, as on the CPU
    projectAll(true);
    packed_.bind(layout::kPacked);
    if (friction_) {
      frictionKernel_.set(layout::kCount, unsigned(vertexCount()));
      frictionKernel_.set(layout::kStep, h);
      frictionKernel_.dispatch(std::size_t(vertexCount()));
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glCopyNamedBufferSubData(positions_.id(), packed_.id(), 0, 0, bytes);
  }

  /// One substep's stages (docs/design.md §1), each a dispatch or a few.
  void subStep(double hd) {
    context_->makeCurrent();  // an observer of the last substep may have made another context current
    const float h = float(hd);
    prepareSolids(hd);
    bindBuffers();
    if (repulsive_) repel(h);  // 0. repulsion (phase 1), for each solid that has a region
    if (coupled_) coupling_.keepStartVelocities(velocities_, state_.x.size());
    predict(h);
    const bool inSolve = settings_.collisionMethod == CollisionMethod::InSolve && !passes_.empty();
    solve(h, inSolve);
    update_.set(layout::kCount, unsigned(vertexCount()));  // 3. update velocity
    update_.set(layout::kInverseStep, 1.0f / h);
    update_.dispatch(std::size_t(vertexCount()));
    // 4. collide (docs/design.md §3, §4): per solid, project vertices, then faces; where surfaces meet, settle;
    //    split; propagate (as on the CPU). The in-solve method collided inside the solve instead.
    if (coupled_) coupling_.keepPreContactVelocities(velocities_, state_.x.size());
    if (!passes_.empty() && !inSolve) {
      projectAll(true, h);
      respondAndPropagate(h);
    }
    // 5. the cloth's push on the coupled bodies, applied before they move (docs/design.md §6)
    if (coupled_) {
      anchorSums_.assign(bodies_.size(), coupling::BodySums{});
      anchorSpacers_.clear();
      supportAnchors(double(h), anchorSums_, anchorSpacers_);
      coupling_.gather(bodies_, bodyCentre_, state_.origin, settings_, h, unsigned(vertexCount()), bodyForce_,
                       bodyTorque_, spacers_, anchorSums_);
      spacers_.insert(spacers_.end(), anchorSpacers_.begin(), anchorSpacers_.end());
      spacersToBodyFrames();
    }
    fresh_ = false;  // the CPU copy of the state is behind now
  }

  void bindBuffers() const {
    positions_.bind(layout::kPositions);
    velocities_.bind(layout::kVelocities);
    predicted_.bind(layout::kPredicted);
    packed_.bind(layout::kPacked);
    constraints_.bind(layout::kConstraints);
    lambdas_.bind(layout::kLambdas);
    start_.bind(layout::kStart);
    contacts_.bind(layout::kContacts);
    neighbourOffsets_.bind(layout::kNeighbourOffsets);
    neighbours_.bind(layout::kNeighbours);
    rings_.bind(layout::kPropagation);
    settleCommands_.bind(layout::kFlags);
    if (reconcile_) settlePoints_.bind(layout::kSettlePoints);
    if (coupled_) coupling_.bind();
  }

  void repel(float h) {
    const auto n = unsigned(vertexCount());
    for (const SolidPass& p : passes_) {
      if (!(p.repulsionRadius > 0)) continue;
      kernels_.repel(p, float(settings_.thickness), n, h, settings_.normalForceOnly);
      if (p.motion.body >= 0) gatherRepulsionForces(p.motion.body);
    }
  }

  /// 1. predict
  void predict(float h) {
    const auto n = unsigned(vertexCount());
    const Vec3<float> gh = (settings_.gravity * double(h)).cast<float>();
    predict_.set(layout::kCount, n);
    predict_.set(layout::kStep, h);
    predict_.set(layout::kGravityStep, gh.x(), gh.y(), gh.z());
    predict_.set(layout::kKeepStart, unsigned(friction_ || coupled_ || sweep_));
    predict_.set(layout::kKeepVelocity, float(settings_.velocityKept(double(h))));
    predict_.dispatch(n);
  }

  /// 2. solve, set by set and colour by colour, as the CPU solver orders them; then the pins, and the in-solve
  ///    method's contacts after each pass.
  void solve(float h, bool inSolve) {
    const float h2 = h * h;
    const float alphas[3] = {float(settings_.stretchCompliance) / h2, float(settings_.shearCompliance) / h2,
                             float(settings_.bendingCompliance) / h2};
    const int iterations = settings_.iterationCount;
    if (iterations > 1) {
      glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);  // the clear comes after the last substep's shader writes
      glClearNamedBufferData(lambdas_.id(), GL_R32F, GL_RED, GL_FLOAT, nullptr);
    }
    const DistanceSet<float>* sets[3] = {&asset_->stretch, &asset_->shear, &asset_->bending};
    if (!pins_.empty()) uploadPins(float(settings_.pinCompliance) / h2);
    for (int it = 0; it < iterations; ++it) {
      for (int s = 0; s < 3; ++s) {
        solve_.set(layout::kAlphaTilde, alphas[s]);
        solve_.set(layout::kUseLambda, unsigned(iterations > 1 && alphas[s] > 0));
        const auto& offsets = sets[s]->colourOffsets;
        for (std::size_t c = 0; c + 1 < offsets.size(); ++c) {
          const auto count = unsigned(offsets[c + 1] - offsets[c]);
          solve_.set(layout::kFirst, unsigned(setStart_[s] + std::size_t(offsets[c])));
          solve_.set(layout::kCount, count);
          solve_.dispatch(count);
        }
      }
      if (!pins_.empty()) {
        glUseProgram(pinKernel_.id());
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      }
      if (inSolve) collideInSolve(h);
    }
  }

  /// The pins' targets in this substep's local frame, and their multipliers zeroed.
  void uploadPins(float alphaTilde) {
    std::vector<layout::PinSlot> slots(pins_.size());
    for (std::size_t k = 0; k < pins_.size(); ++k) {
      const Vec3<float> t = (pins_[k].target - state_.origin).cast<float>();
      slots[k] = {{t.x(), t.y(), t.z()}, std::uint32_t(pins_[k].vertex)};
    }
    if (pinSlots_.size() != slots.size()) {
      pinSlots_.assign(slots);
      pinLambdas_.assign(std::vector<float>(slots.size(), 0.0f));
    } else {
      pinSlots_.write(slots);
    }
    glClearNamedBufferData(pinLambdas_.id(), GL_R32F, GL_RED, GL_FLOAT, nullptr);
    pinSlots_.bind(layout::kPins);
    pinLambdas_.bind(layout::kPinLambdas);
    pinKernel_.set(layout::kCount, unsigned(pins_.size()));
    pinKernel_.set(layout::kAlphaTilde, alphaTilde);
  }

  /// The velocity split, then propagation (collide's second half).
  void respondAndPropagate(float h) {
    const auto n = unsigned(vertexCount());
    if (guard_ || holdPlanes_) copyVertices(positions_, guardFrom_);  // where the contact passes left them
    const Program& respond = friction_ ? respondFriction_ : respond_;
    respond.set(layout::kCount, n);
    respond.set(layout::kStep, h);
    respond.set(layout::kInverseStep, 1.0f / h);
    respond.set(layout::kNormalDamping, float(settings_.normalDamping));
    respond.dispatch(n);
    if (holdPlanes_) {
      const float thickness = float(settings_.thickness);
      holdPlane_.set(layout::kCount, n);
      holdPlane_.set(layout::kThickness, thickness);
      holdPlane_.set(layout::kSlack, float(constants::kSettleSlack) * thickness);
      guardFrom_.bind(layout::kGuardFrom);
      for (const SolidPass& p : passes_)
        if (p.code == layout::kPlane) {
          setShape(holdPlane_.id(), p.field);
          holdPlane_.dispatch(n);
        }
    }
    if (guard_) guardFriction();  // after the hold, as on the CPU (respondContacts holds each vertex)
    if (settings_.collisionMethod != CollisionMethod::Faces || settings_.propagationRings <= 0 ||
        !(settings_.propagationWeight > 0))
      return;
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glClearNamedBufferData(rings_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
    propagate_.set(layout::kCount, n);
    propagate_.set(layout::kWeight, float(settings_.propagationWeight));
    for (int ring = 1; ring <= settings_.propagationRings; ++ring) {
      propagate_.set(layout::kRing, unsigned(ring));
      propagate_.dispatch(n);
    }
  }

  /// Continuous contact's friction guard (BasicSolver::guardFriction): against every bounded curved solid, the
  /// faces that position friction carried within kFrictionGuard of the thickness of it, and that it then pierces,
  /// mark their corners (collide_faces.comp with DRAPE_GUARD), which go back (restore_marked.comp).
  void guardFriction() {
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    guardFrom_.bind(layout::kGuardFrom);
    guardMarks_.bind(layout::kGuardMarks);
    faces_.bind(layout::kFaces);
    const float reach = float(constants::kFrictionGuard * settings_.thickness);
    bool any = false;
    for (const SolidPass& p : passes_) {
      if (!p.curved || !kernels_.guards(p)) continue;
      kernels_.guardPass(p, reach, settings_.pgdIterations, faces_.size());
      any = true;
    }
    if (!any) return;
    restore_.set(layout::kCount, unsigned(vertexCount()));
    restore_.dispatch(std::size_t(vertexCount()));
  }

  /// The CPU copy of the state into the GPU's buffers.
  void upload() {
    context_->makeCurrent();
    const std::size_t n = state_.x.size();
    std::vector<layout::Vertex> x(n), v(n);
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = {state_.x[i].x(), state_.x[i].y(), state_.x[i].z(), state_.invMass[i]};
      v[i] = {state_.v[i].x(), state_.v[i].y(), state_.v[i].z(), 0.0f};
    }
    positions_.write(x);
    velocities_.write(v);
    fresh_ = true;
  }
  /// The GPU's state into the CPU copy, if a step changed it since the last read.
  void download() const {
    if (fresh_) return;
    context_->makeCurrent();
    const std::vector<layout::Vertex> x = positions_.read(), v = velocities_.read();
    for (std::size_t i = 0; i < x.size(); ++i) {
      state_.x[i] = {x[i].x, x[i].y, x[i].z};
      state_.v[i] = {v[i].x, v[i].y, v[i].z};
    }
    fresh_ = true;
  }

  Context* context_;
  std::vector<coupling::BodySums> anchorSums_;  ///< the anchors' supports of each coupled body, this substep
  std::vector<Spacer> anchorSpacers_;
  mutable bool fresh_ = true;  ///< the CPU copy of the state (SolverFront::state_) is current
  std::vector<SolidPass> passes_;  ///< this substep's solids (prepareSolids)
  bool friction_ = false;    ///< some solid has friction this substep
  bool repulsive_ = false;   ///< some solid has a repulsion region this substep
  bool reconcile_ = false;   ///< a vertex may touch several surfaces this substep (a curved solid, or several)
  SolidKernels kernels_;  ///< each shape type's kernels, and the solids' shape data
  Buffer<std::uint32_t> settleCommands_;  ///< per settle pass, the dispatch command its vertex passes write
  Buffer<layout::SettlePoint> settlePoints_;  ///< the settle's exact points while the fields judge them
  bool coupled_ = false;          ///< some solid is a dynamic body this substep
  bool sweep_ = false;            ///< continuous contact this substep (the setting, and a bounded solid)
  bool guard_ = false;            ///< and friction's moves are guarded (guardFriction)
  bool holdPlanes_ = false;       ///< friction's moves are kept out of the planes (hold_planes.comp)
  Buffer<layout::Vertex> guardFrom_;  ///< the positions the contact passes left, for the guard and the hold
  Buffer<std::uint32_t> guardMarks_;  ///< the guard's marks, cleared as they are undone
  BodyCoupling coupling_;  ///< the coupling's kernels, and its buffers once a scene has a dynamic solid
  Program predict_, solve_, update_, respond_, respondFriction_, propagate_, centre_, translate_, pinKernel_, settle_,
      settlePlace_, frictionKernel_, restore_, holdPlane_;
  Buffer<layout::PinSlot> pinSlots_;
  Buffer<float> pinLambdas_;
  Buffer<std::array<std::uint32_t, 4>> faces_;  ///< the faces, colour by colour (colourFaces)
  Buffer<layout::Vertex> held_, keptHeld_;      ///< per face as faces_: its held deepest point (layout::kHeld)
  std::vector<std::size_t> faceColourOffsets_;   ///< colour c is faces [offsets[c], offsets[c + 1])
  Buffer<layout::Vertex> positions_, velocities_, predicted_, packed_, start_, reduction_;
  Buffer<layout::Vertex> keptPositions_, keptVelocities_;  ///< an undoable step's start (keepStart)
  Buffer<layout::Contact> contacts_;
  Buffer<layout::Ring> rings_;
  Buffer<std::uint32_t> neighbourOffsets_, neighbours_;
  Buffer<layout::Constraint> constraints_;
  Buffer<float> lambdas_;
  std::size_t setStart_[3] = {0, 0, 0};
};

}  // namespace drape::gpu
