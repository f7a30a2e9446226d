#pragma once
// The substep loop (docs/design.md §1; Algorithm 1 of the SDF-based PBD collision paper for cloth-solid interaction):
//   for each substep: predict, iterationCount constraint passes, velocity update, collide.
// Solid types are template parameters: a type the scene does not use is an empty array that no loop visits.

#include <drape/cloth/asset.hpp>
#include <drape/cloth/integrate.hpp>
#include <drape/cloth/spin.hpp>
#include <drape/cloth/state.hpp>
#include <drape/cloth/tethers.hpp>
#include <drape/collision/broadphase.hpp>
#include <drape/collision/passes.hpp>
#include <drape/collision/pgd.hpp>
#include <drape/collision/response.hpp>
#include <drape/constraints/distance.hpp>
#include <drape/coupling/contact_forces.hpp>
#include <drape/coupling/repel.hpp>
#include <drape/coupling/share.hpp>
#include <drape/detail/parallel.hpp>
#include <drape/front_end.hpp>
#include <drape/kernel_constants.hpp>
#include <drape/sdf/grid.hpp>
#include <drape/sdf/solid.hpp>
#include <drape/settings.hpp>

#include <algorithm>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace drape {

template <Scalar S, class... Shapes> class BasicSolver : public SolverFront<BasicSolver<S, Shapes...>, S, Shapes...> {
  using Front = SolverFront<BasicSolver<S, Shapes...>, S, Shapes...>;
  friend Front;

 public:
  using Front::solidCount;
  using Front::vertexCount;

  /// asset: shared topology; areaDensity: kg/m^2, giving each vertex a third of its faces' mass.
  explicit BasicSolver(std::shared_ptr<const ClothAsset<S>> asset, const Settings& settings = {},
                       double areaDensity = 0.1)
      : Front(std::move(asset), settings, areaDensity) {
    const Index n = asset_->vertexCount();
    xPrev_.resize(n);
    xPredicted_.resize(n);
    packed_.resize(n);
    blocks_[0] = DistanceBlocks<S>(asset_->stretch);
    blocks_[1] = DistanceBlocks<S>(asset_->shear);
    blocks_[2] = DistanceBlocks<S>(asset_->bending);
    gatherLaneMasses();
    spinChunks_.resize(std::size_t((n + kSpinChunk - 1) / kSpinChunk));
    lambdaStretch_.resize(blocks_[0].lambdaCount(asset_->stretch));
    lambdaShear_.resize(blocks_[1].lambdaCount(asset_->shear));
    lambdaBending_.resize(blocks_[2].lambdaCount(asset_->bending));
    propagation_.resize(n);
    // Bins of two mean edge lengths: a cell holds a few vertices of a flat cloth.
    double edgeSum = 0;
    for (const auto& e : asset_->edges)
      edgeSum += double((asset_->restPositions[e[1]] - asset_->restPositions[e[0]]).norm());
    const double meanEdge = asset_->edges.empty() ? 1.0 : edgeSum / double(asset_->edges.size());
    passes_.setTopology(asset_->triangles, n, S(2 * std::max(meanEdge, 1e-6)));
  }

  /// Collision work of the last substep.
  const CollisionStats& stats() const { return passes_.stats(); }
  /// Contact records of the last substep (the faces and vertices methods).
  const ContactBuffer<S>& contacts() const { return passes_.contacts(); }

 private:
  using Front::asset_;
  using Front::bodies_;
  using Front::bodyCentre_;
  using Front::bodyForce_;
  using Front::bodyTorque_;
  using Front::compiled_;
  using Front::pins_;
  using Front::settings_;
  using Front::state_;

  // --- the front end's hooks (SolverFront) ------------------------------------------------------------------
  void loadState() const {}
  void storeState(StateChange change) {
    if (change == StateChange::Positions) passes_.positionsReplaced();
    if (change == StateChange::Masses) massesChanged_ = tethersStale_ = true;  // the lane copies, the tethers
  }
  void keepStart() {
    startX_ = state_.x;
    startV_ = state_.v;
    startHeld_ = passes_.heldPoints();
  }
  void restoreStart() {
    state_.x = startX_;
    state_.v = startV_;
    passes_.restoreHeldPoints(startHeld_);
    passes_.positionsReplaced();
  }
  static void checkSettings(const Settings&) {}  // the CPU runs every valid setting
  template <class Shape> static void checkSolid(const Solid<Shape>&) {}
  template <class Shape> void solidSet(Index) { passes_.solidsChanged(); }

  /// Moves the local origin to follow the cloth, in steps of 1/64 m so the shift is exact in float.
  void beginStep() {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : state_.x) centre += p.template cast<double>();
    centre /= double(state_.x.size());
    const Eigen::Vector3d shift = this->moveOrigin(centre);
    if (shift.isZero(0)) return;
    const Vec3<S> shiftS = shift.cast<S>();
    for (auto& p : state_.x) p -= shiftS;
    passes_.positionsReplaced();
  }

  template <class F> void forEachCompiled(F&& f) {
    std::apply([&](auto&... lists) { (f(lists), ...); }, compiled_);
  }

  void prepareSolids(double h) {
    const SolidFeatures has = Front::prepareSolids(h, [](const auto&, const auto&) {});
    hasFriction_ = has.friction;
    repulsive_ = has.repulsion;
    reconcile_ = has.reconcile;
    coupled_ = has.coupled;
    keepSpin_ = settings_.keepAngularMomentum;
    pinLocal_.resize(pins_.size());
    lambdaPins_.resize(pins_.size());
    for (std::size_t k = 0; k < pins_.size(); ++k)
      pinLocal_[k] = {pins_[k].vertex, (pins_[k].target - state_.origin).template cast<S>()};
    passes_.prepare(settings_.broadPhase && has.bounded > 0, coupled_);
    // Continuous contact needs the start positions, and only a bounded solid (not a half-space) can be crossed.
    sweep_ = settings_.continuousContact && settings_.collisionMethod != CollisionMethod::InSolve && has.bounded > 0;
    // Position friction must not carry a face across a solid: continuous contact with faces guards it.
    guard_ = sweep_ && hasFriction_ && settings_.collisionMethod == CollisionMethod::Faces;
    // Friction and pushes of a moving solid beside a plane may carry a vertex into the plane (holdOutOfPlane).
    holdPlanes_ = false;
    if constexpr (Front::template kHasShape<Plane>)
      holdPlanes_ = hasFriction_ && has.moving && !std::get<std::vector<CompiledSolid<Plane, S>>>(compiled_).empty() &&
                    solidCount() > 1 && settings_.collisionMethod != CollisionMethod::InSolve;
    if (guard_ && guardMarks_.size() != state_.x.size()) {
      xBeforeFriction_.resize(state_.x.size());
      guardMarks_.assign(state_.x.size(), 0);
    }
    if (guard_) guardPaths_.reserve(asset_->triangles.size());
    if (coupled_ && vStart_.size() != state_.v.size()) {
      vStart_.resize(state_.v.size());
      vPre_.resize(state_.v.size());
      exchanged_.reserve(state_.v.size() * std::size_t(constants::kContactSlots));
      this->spacers_.reserve(state_.v.size());
    }
  }

  // Defined below the class, not inline: where the built-in solvers are compiled once (DRAPE_EXTERN_SOLVERS),
  // the other files then do not compile the substep and every kernel it reaches.
  void subStep(double hd);

  /// One substep's stages (docs/design.md §1), run by every thread of the team.
  void subStepBody(const S h) {
    // 0. repulsion (phase 1), only in a scene that declares it
    if (repulsive_) repel(S(settings_.thickness), h);
    if (coupled_) copyVelocities(vStart_);  // the estimators' velocity at the start of the substep
    predict(h);
    solve(h);
    if (keepSpin_) restoreSpin(h);
    update(h);
    // 4. collide
    if (coupled_) copyVelocities(vPre_);  // before any contact acts
    if (settings_.collisionMethod != CollisionMethod::InSolve) {
      projectAll(S(settings_.thickness), settings_.collisionMethod == CollisionMethod::Faces, h);
      respondAndPropagate(h);
    }
    // 5. the cloth's push on the coupled bodies, applied before they move (docs/design.md §6)
    if (coupled_) {
      DRAPE_OMP(single)
      {
        try {  // an application's body may refuse the push
          gatherContactForces(h, S(this->settings_.thickness));
          for (std::size_t b = 0; b < this->bodies_.size(); ++b)
            this->bodies_[b]->applyForceAndTorque(this->bodyForce_[b], this->bodyTorque_[b]);
        } catch (...) {
          teamError_ = std::current_exception();
        }
      }
    }
  }

  /// 1. predict, into the packed positions the solve works on (the start positions are kept aside only for
  ///    friction and the energy estimate, their readers after the velocity update)
  void predict(const S h) {
    const Vec3<S> gh = (settings_.gravity * double(h)).template cast<S>();
    Vec3<S>* x = state_.x.data();
    Vec3<S>* v = state_.v.data();
    Vec3<S>* x0 = xPrev_.data();
    Vec3<S>* xp = xPredicted_.data();
    Vec4<S>* xw = packed_.data();
    const S* w = state_.invMass.data();
    const Index n = vertexCount();
    const S keep = S(settings_.velocityKept(double(h)));
    // Shares of whole fours, which float takes in SIMD lanes: the same vertices on any number of threads.
    const SimdLevel level = simdLevelFor<S>(bestSimdLevel());
    withFlags([&](auto keepStart, auto damp) {
      teamFor((n + 3) / 4, [&](Index b, Index e) {
        predictPositions<keepStart(), damp()>(4 * b, std::min(4 * e, n), x, v, w, gh, h, x0, xp, xw, keep, level);
      });
    }, hasFriction_ || coupled_ || sweep_ || keepSpin_, settings_.airDamping > 0);
  }

  /// 2. iterationCount passes over the constraints, set by set, then the pins; the in-solve method's contacts
  ///    after each pass.
  void solve(const S h) {
    const S h2 = h * h;
    const S stretchAlpha = S(settings_.stretchCompliance) / h2, shearAlpha = S(settings_.shearCompliance) / h2,
            bendingAlpha = S(settings_.bendingCompliance) / h2, pinAlpha = S(settings_.pinCompliance) / h2;
    const bool inSolve = settings_.collisionMethod == CollisionMethod::InSolve;
    const int iterations = settings_.iterationCount;
    const ClothAsset<S>& a = *asset_;
    Vec3<S>* x = state_.x.data();
    Vec4<S>* xw = packed_.data();
    if (iterations > 1) {  // one pass needs no multipliers (see solveDistanceSet)
      DRAPE_OMP(single)
      {
        std::fill(lambdaStretch_.begin(), lambdaStretch_.end(), S(0));
        std::fill(lambdaShear_.begin(), lambdaShear_.end(), S(0));
        std::fill(lambdaBending_.begin(), lambdaBending_.end(), S(0));
      }
    }
    for (int it = 0; it < iterations; ++it) {
      solveSet(a.stretch, blocks_[0], stretchAlpha, lambdaStretch_.data(), iterations);
      solveSet(a.shear, blocks_[1], shearAlpha, lambdaShear_.data(), iterations);
      solveSet(a.bending, blocks_[2], bendingAlpha, lambdaBending_.data(), iterations);
      if (!pinLocal_.empty()) {
        DRAPE_OMP(single)
        {
          if (it == 0) std::fill(lambdaPins_.begin(), lambdaPins_.end(), S(0));
          withFlags([&](auto record) {
            solvePins<record()>(pinLocal_.data(), Index(pinLocal_.size()), pinAlpha, lambdaPins_.data(), xw,
                                this->state_.invMass.data(), &spinExternal_, xPrev_.data());
          }, keepSpin_);
        }
      }
      if (tethering_)
        teamFor(vertexCount(), [&](Index b, Index e) { applyTethers(b, e, tethers_, xw); });
      if (inSolve) {  // contacts inside the solve, on the unpacked positions
        unpack(x, xw);
        collideInSolve(h, S(settings_.thickness));
        if (keepSpin_) {  // the contacts' pushes are the solids', not the solve's
          const S* w = this->state_.invMass.data();
          forEachSpinChunk([&](Index b, Index e) {
            SpinSums pushed;
            for (Index i = b; i < e; ++i) {
              if (w[i] > S(0)) pushed.addExternal(x[i], Vec3<S>(x[i] - xw[i].template head<3>()), w[i]);
              xw[i].template head<3>() = x[i];
            }
            return pushed;
          });
          DRAPE_OMP(single)
          for (const SpinSums& c : spinChunks_) spinExternal_.add(c);
        } else {
          teamFor(vertexCount(), [&](Index b, Index e) {
            for (Index i = b; i < e; ++i) xw[i].template head<3>() = x[i];
          });
        }
      }
    }
  }

  /// The farthest a free vertex travelled in the substep (h |v| after the update, which is (x - x_start) / h),
  /// for continuous contact: the largest over the threads, so the same on any number of them.
  S measureTravel(const S h) {
    DRAPE_OMP(single)
    travel_ = 0;
    const Vec3<S>* v = state_.v.data();
    S fastest = 0;
    teamForNoWait(vertexCount(), [&](Index b, Index e) {
      for (Index i = b; i < e; ++i) fastest = std::max(fastest, v[i].squaredNorm());
    });
    teamMax(travel_, h * std::sqrt(fastest));
    DRAPE_OMP(barrier)
    return travel_;
  }

  /// Chunks of kSpinChunk vertices shared by the team, each chunk's sums into spinChunks_: added in chunk order,
  /// they do not depend on the thread count.
  template <class F> void forEachSpinChunk(F&& sums) {
    const Index n = vertexCount();
    teamFor(Index(spinChunks_.size()), [&](Index b, Index e) {
      for (Index c = b; c < e; ++c) spinChunks_[std::size_t(c)] = sums(c * kSpinChunk, std::min(n, (c + 1) * kSpinChunk));
    });
  }

  /// 2b. With Settings::keepAngularMomentum: the moment the solve's pushes added, less the external pushes inside
  ///     it, taken out again by a rotation of the free vertices (cloth/spin.hpp).
  void restoreSpin(const S h) {
    const Vec4<S>* xw = packed_.data();
    const Vec3<S>* xp = xPredicted_.data();
    const Vec3<S>* xs = xPrev_.data();
    const S* w = state_.invMass.data();
    forEachSpinChunk([&](Index b, Index e) { return sumSolvePushes(b, e, xw, xp, xs, w); });
    DRAPE_OMP(single)
    {
      SpinSums total;
      for (const SpinSums& c : spinChunks_) total.add(c);
      total.moment -= spinExternal_.moment;
      total.push -= spinExternal_.push;
      const FreeAxes axes = freeAxes(fixed_, xw, kFixedPointTolerance);
      spinOn_ = restoringSpin(total, axes, double(h), spinOmega_, spinCentre_);
    }
    if (!spinOn_) return;
    Vec3<S>* v = state_.v.data();
    teamFor(vertexCount(), [&](Index b, Index e) { applySpin(b, e, xw, w, v, spinOmega_, spinCentre_); });
  }

  /// 3. update velocity (updateVelocities). Where a vertex may touch several surfaces, the positions the
  ///    contacts start from are kept (in the prediction's buffer, free from here on) for the pinched vertices'
  ///    least-squares placement. With the broad phase, the update also measures how far the vertices got from
  ///    where the bins took them, so the bins are rebuilt only when queries would have to grow too much.
  void update(const S h) {
    const Index n = vertexCount();
    Vec3<S>* x = state_.x.data();
    Vec3<S>* v = state_.v.data();
    Vec3<S>* xp = xPredicted_.data();
    Vec4<S>* xw = packed_.data();
    const S invH = S(1) / h;
    if (passes_.measuresDrift()) {
      S far = 0;
      withFlags([&](auto keep) {
        teamForNoWait(n, [&](Index b, Index e) {
          far = updateVelocities<keep(), true>(b, e, xw, xp, x, v, invH, passes_.binned());
        });
      }, reconcile_);
      passes_.addUpdateDrift(far);
      DRAPE_OMP(barrier)
    } else {
      const SimdLevel level = simdLevelFor<S>(bestSimdLevel());  // in whole fours, as the prediction
      withFlags([&](auto keep) {
        teamFor((n + 3) / 4, [&](Index b, Index e) {
          updateVelocities<keep(), false>(4 * b, std::min(4 * e, n), xw, xp, x, v, invH, {}, level);
        });
      }, reconcile_);
    }
  }

  /// After any change of a mass: the kinematic vertices' list (restoreSpin), and the constraint blocks' copies of
  /// the inverse masses, which only the float SIMD kernels read (double runs the scalar kernel on the masses).
  void gatherLaneMasses() {
    fixed_.clear();
    for (Index i = 0; i < vertexCount(); ++i)
      if (!(state_.invMass[std::size_t(i)] > S(0))) fixed_.push_back(i);
    if constexpr (!std::is_same_v<S, float>) return;
    for (DistanceBlocks<S>& b : blocks_) b.gatherMasses(state_.invMass.data());
  }

  /// The packed positions back into the state.
  void unpack(Vec3<S>* x, const Vec4<S>* xw) {
    teamFor(vertexCount(), [&](Index b, Index e) {
      for (Index i = b; i < e; ++i) x[i] = xw[i].template head<3>();
    });
  }

  void copyVelocities(std::vector<Vec3<S>>& to) {
    const Vec3<S>* v = state_.v.data();
    Vec3<S>* out = to.data();
    teamFor(vertexCount(), [&](Index b, Index e) { std::copy(v + b, v + e, out + b); });
  }

  void repel(S thickness, S h) {
    Vec3<S>* v = state_.v.data();
    forEachCompiled([&](auto& list) {
      for (const auto& solid : list) {
        if (!(solid.repulsionRadius > S(0))) continue;
        if (solid.motion.body >= 0) copyVelocities(vPre_);  // scratch: what the region changes is an impulse
        teamFor(vertexCount(), [&](Index b, Index e) {
          if (solid.falloff == Falloff::Linear)
            coupling::repelVertices<Falloff::Linear>(b, e, solid, thickness, this->state_.x.data(), v,
                                                     this->state_.invMass.data());
          else
            coupling::repelVertices<Falloff::Smooth>(b, e, solid, thickness, this->state_.x.data(), v,
                                                     this->state_.invMass.data());
        });
        if (solid.motion.body >= 0) {
          const std::size_t b = std::size_t(solid.motion.body);
          DRAPE_OMP(single)
          coupling::gatherRepulsionForces(solid, this->state_, vPre_.data(), h, this->settings_.normalForceOnly,
                                          this->bodyCentre_[b], this->bodyForce_[b], this->bodyTorque_[b]);
        }
      }
    });
  }

  /// Phase 2 (docs/design.md §6): the cloth's pushes on the coupled bodies (coupling/contact_forces.hpp), each
  /// body's exchange shared with the vertices that made it (coupling/share.hpp), then the pinches' and the
  /// anchors' supports (coupling/anchors.hpp).
  void gatherContactForces(S h, S thickness) {
    const coupling::SubstepView<S> view{passes_.contacts(),
                                        state_,
                                        xPrev_.data(),
                                        vStart_.data(),
                                        vPre_.data(),
                                        asset_->vertexNeighbours,
                                        bodies_,
                                        bodyCentre_,
                                        h,
                                        thickness,
                                        settings_.contactForce,
                                        settings_.normalForceOnly,
                                        coupling::passesPropagatedImpulse(settings_)};
    coupling::Gathered out{bodyForce_, bodyTorque_, bodySums_, exchanged_, this->spacers_};
    coupling::gatherContactForces(view, out);
    this->supportAnchors(double(h), bodySums_, this->spacers_);
    this->spacersToBodyFrames();
    coupling::shareExchanges(bodies_, bodySums_, exchanged_, bodyForce_, bodyTorque_, state_.v.data(), vPre_.data());
    coupling::addPinches(bodySums_, bodyForce_, bodyTorque_);
  }

  /// One pass over a constraint set, colour after colour, each colour's items shared by the team.
  void solveSet(const DistanceSet<S>& set, const DistanceBlocks<S>& blocks, S alpha, S* lambda, int iterations) {
    const SimdLevel level = simdLevelFor<S>(bestSimdLevel());
    Vec4<S>* xw = packed_.data();
    const S* w = state_.invMass.data();
    withFlags([&](auto useLambda) {
      for (Index c = 0; c < set.colourCount(); ++c)
        teamFor(colourItems(set, blocks, c, level), [&](Index b, Index e) {
          solveDistanceColour<useLambda()>(b, e, c, set, blocks, alpha, lambda, xw, w, level);
        });
    }, iterations > 1 && alpha > S(0));
  }

  /// All contacts of a substep (ContactPasses::projectAll).
  void projectAll(S thickness, bool faces, S h = S(0)) {
    PassInputs<S> in{state_.x.data(),       state_.invMass.data(),        xPredicted_.data(),
                     asset_->triangles,      thickness,                    settings_.pgdIterations,
                     settings_.culling,      settings_.exactGridSearch,    keepSpin_};
    if (keepSpin_ && settings_.collisionMethod != CollisionMethod::InSolve) in.keepTurn = state_.v.data();
    if (sweep_ && h > S(0)) {
      const S gate = S(constants::kSweepGate) * thickness;
      in.sweep = {xPrev_.data(), h, gate * gate};
      in.travel = measureTravel(h);
    }
    passes_.projectAll(compiled_, in, faces, reconcile_, solidCount(),
                       settings_.collisionMethod == CollisionMethod::InSolve);
  }

  /// CollisionMethod::InSolve: the same vertex and face contacts, projected inside the solve pass, with
  /// position-level friction; the velocity update then turns every projection into velocity.
  void collideInSolve(S h, S thickness) {
    projectAll(thickness, true);
    if (hasFriction_)
      teamFor(vertexCount(), [&](Index b, Index e) {
        applyContactFriction(b, e, passes_.contacts(), this->state_.x.data(), xPrev_.data(), h);
      });
  }

  /// The velocity split with friction, then (with faces) propagation, after the contacts were projected.
  void respondAndPropagate(S h) {
    Vec3<S>* x = state_.x.data();
    Vec3<S>* v = state_.v.data();
    const S* w = state_.invMass.data();
    const bool faces = settings_.collisionMethod == CollisionMethod::Faces;
    const S damping = S(settings_.normalDamping);
    // Shares of whole eights: the SIMD response takes aligned eights and fours (respondContacts), the same ones
    // on any number of threads.
    const SimdLevel level = simdLevelFor<S>(bestSimdLevel());
    const Index n = vertexCount();
    if (guard_) teamFor(n, [&](Index b, Index e) { std::copy(x + b, x + e, xBeforeFriction_.data() + b); });
    PlaneHold<S> hold;
    if constexpr (Front::template kHasShape<Plane>)
      if (holdPlanes_) {
        const auto& planes = std::get<std::vector<CompiledSolid<Plane, S>>>(compiled_);
        hold = {planes.data(), planes.size(), S(settings_.thickness),
                S(constants::kSettleSlack) * S(settings_.thickness)};
      }
    withFlags([&](auto friction, auto holdPlanes) {
      teamFor((n + 7) / 8, [&](Index b, Index e) {
        respondContacts<friction(), S, holdPlanes()>(8 * b, std::min(8 * e, n), passes_.contacts(), x, xPrev_.data(),
                                                     v, h, damping, level, hold);
      });
    }, hasFriction_, holdPlanes_);
    if (guard_) guardFriction();
    if (!(faces && settings_.propagationRings > 0 && settings_.propagationWeight > 0)) return;
    DRAPE_OMP(single)
    propagation_.beginPass();
    const S weight = S(settings_.propagationWeight);
    // With the angular momentum kept, each share follows the surface's curvature (propagateRing<true>).
    withFlags([&](auto curved) {
      for (int ring = 1; ring <= settings_.propagationRings; ++ring)
        teamFor(vertexCount(), [&](Index b, Index e) {
          propagateRing<curved()>(b, e, ring, passes_.contacts(), propagation_, asset_->vertexNeighbours, v, w,
                                  weight, x);
        });
    }, keepSpin_);
  }

  /// Continuous contact's friction guard (markFrictionCrossings, docs/design.md §18): against every bounded
  /// curved solid, the faces that position friction carried within kFrictionGuard of the thickness of it, and that
  /// it then pierces, mark their corners, which go back to where the contact passes left them. Their velocities
  /// keep the response's.
  void guardFriction() {
    DRAPE_OMP(single)
    guardFrictionAlone();
  }
  /// guardFriction's work, on the one thread that does it.
  void guardFrictionAlone() {
    const Vec3<S>* x = state_.x.data();
    const S reach = S(constants::kFrictionGuard) * S(settings_.thickness);
    // Only a face with a corner friction moved further than the reach is swept: where none did (a resting or
    // slowly sliding cloth) one pass over the vertices is all the guard costs.
    bool far = false;
    for (std::size_t i = 0; i < xBeforeFriction_.size() && !far; ++i)
      far = (x[i] - xBeforeFriction_[i]).squaredNorm() > reach * reach;
    if (!far) return;
    const auto& triangles = asset_->triangles;
    const Vec3<S>* before = xBeforeFriction_.data();
    guardPaths_.gather(triangles, before, x, reach);
    std::uint8_t* marks = guardMarks_.data();
    const int iterations = settings_.pgdIterations;
    const bool exact = settings_.exactGridSearch;
    Index marked = 0;
    forEachCompiled([&](const auto& list) {
      for (const auto& solid : list)
        if constexpr (!std::decay_t<decltype(solid.sdf)>::kLinear)
          if (solid.bounded)
            marked += markFrictionCrossings(solid.sdf, solid.boxLow, solid.boxHigh, triangles, guardPaths_, before,
                                            x, reach, iterations, exact, marks);
    });
    if (marked > 0) {
      for (std::size_t i = 0; i < guardMarks_.size(); ++i)
        if (guardMarks_[i] != 0) state_.x[i] = xBeforeFriction_[i], guardMarks_[i] = 0;
      passes_.addFrictionGuarded(marked);
    }
  }

  std::vector<PinTarget<S>> pinLocal_;
  std::vector<Vec3<S>> xPrev_, xPredicted_;
  std::vector<Vec4<S>> packed_;   ///< (position, 0) of each vertex: what the constraint solve works on
  std::vector<Vec3<S>> startX_, startV_;  ///< the state at the start of a step that may be undone
  std::vector<HeldPoint<S>> startHeld_;  ///< the faces' held deepest points then
  /// The stretch, shear and bending sets as the float SIMD kernels read them, with their lanes' inverse masses
  /// (gatherLaneMasses); the asset holds the topology only.
  DistanceBlocks<S> blocks_[3];
  std::vector<S> lambdaStretch_, lambdaShear_, lambdaBending_, lambdaPins_;
  ContactPasses<S> passes_;  ///< the contact records and the broad phase
  PropagationBuffer<S> propagation_;
  bool hasFriction_ = false;  ///< some solid has friction this substep
  bool repulsive_ = false;    ///< some solid has a repulsion region this substep
  bool reconcile_ = false;    ///< a vertex may touch several surfaces this substep
  bool coupled_ = false;      ///< some solid is a dynamic body this substep
  std::exception_ptr teamError_;  ///< what a body threw inside the threads' team, rethrown after it
  bool sweep_ = false;        ///< continuous contact searches the paths this substep (a bounded solid exists)
  bool guard_ = false;        ///< and friction's moves are guarded (guardFriction)
  bool holdPlanes_ = false;   ///< friction's moves are kept out of the planes (holdOutOfPlane)
  std::vector<Vec3<S>> xBeforeFriction_;  ///< the positions the contact passes left, for the guard
  std::vector<std::uint8_t> guardMarks_;  ///< the guard's marks, cleared as they are undone
  FrictionPaths<S> guardPaths_;           ///< the faces friction moved far this substep, for the guard
  S travel_ = 0;              ///< the substep's farthest vertex travel (shared by the team)
  bool massesChanged_ = false;  ///< an inverse mass changed since the lane copies were gathered
  Tethers<S> tethers_;          ///< Settings::tethers: each free vertex's, for the inverse masses when built
  bool tethersStale_ = true;    ///< an inverse mass changed since the tethers were built
  bool tethering_ = false;      ///< tethers act this substep
  std::vector<Vec3<S>> vStart_, vPre_;                  ///< velocities at the substep's start, before contacts
  std::vector<coupling::BodySums> bodySums_;  ///< what each coupled body's exchange and pinches add up to
  std::vector<coupling::Exchanged> exchanged_;  ///< the vertices in an exchange, and its body
  // Settings::keepAngularMomentum (restoreSpin)
  static constexpr Index kSpinChunk = 1024;
  bool keepSpin_ = false;
  bool spinOn_ = false;                 ///< a rotation restores the moment this substep
  std::vector<Index> fixed_;            ///< the kinematic vertices (inverse mass 0)
  std::vector<SpinSums> spinChunks_;    ///< each chunk's sums
  SpinSums spinExternal_;               ///< the external pushes inside this substep's solve
  Eigen::Vector3d spinOmega_ = Eigen::Vector3d::Zero(), spinCentre_ = Eigen::Vector3d::Zero();
};

template <Scalar S, class... Shapes> void BasicSolver<S, Shapes...>::subStep(double hd) {
  prepareSolids(hd);
  if (massesChanged_) {
    gatherLaneMasses();
    massesChanged_ = false;
  }
  if (settings_.tethers && tethersStale_) {
    tethers_.build(*asset_, state_.invMass.data());
    tethersStale_ = false;
  }
  tethering_ = settings_.tethers && !tethers_.empty();
  passes_.resetStats();
  spinExternal_ = {};  // this substep's own; one an exception cut short leaves nothing behind
  const int threads = settings_.threadCount == 0 ? hardwareThreads() : settings_.threadCount;
  // One team for the whole substep: its loops share the work (teamFor), so the team is made once. One
  // thread opens no team: outside one the directives cost nothing, while a team of one still pays libgomp's
  // barrier (a futex wake-up each) after every loop.
  if (threads > 1) {
    DRAPE_OMP(parallel num_threads(threads))
    subStepBody(S(hd));
  } else {
    subStepBody(S(hd));
  }
  // An exception may not leave a team (the program would terminate): one thrown inside it is kept until here.
  if (teamError_) std::rethrow_exception(std::exchange(teamError_, nullptr));
}

/// The solver with every built-in shape: the analytic ones, the rigid bodies' cylinders and convex hulls, and
/// grid distance fields from meshes.
template <Scalar S> using Solver = BasicSolver<S, DRAPE_BUILT_IN_SHAPES>;

}  // namespace drape

// A program of many source files can compile the built-in solvers once instead of in every file that steps
// one: define DRAPE_EXTERN_SOLVERS in all of them, and include <drape/solver_instances.hpp> in one.
#ifdef DRAPE_EXTERN_SOLVERS
extern template class drape::SolverFront<drape::Solver<float>, float, DRAPE_BUILT_IN_SHAPES>;
extern template class drape::BasicSolver<float, DRAPE_BUILT_IN_SHAPES>;
extern template class drape::SolverFront<drape::Solver<double>, double, DRAPE_BUILT_IN_SHAPES>;
extern template class drape::BasicSolver<double, DRAPE_BUILT_IN_SHAPES>;
#endif
