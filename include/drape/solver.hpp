#pragma once
// The substep loop (docs/design.md §1; Algorithm 1 of the SDF-based PBD collision paper for cloth-solid interaction):
//   for each substep: predict, iterationCount constraint passes, velocity update, collide.
// Solid types are template parameters: a type the scene does not use is an empty array that no loop visits.

#include <drape/cloth/asset.hpp>
#include <drape/cloth/integrate.hpp>
#include <drape/cloth/state.hpp>
#include <drape/collision/broadphase.hpp>
#include <drape/collision/pgd.hpp>
#include <drape/collision/response.hpp>
#include <drape/constraints/distance.hpp>
#include <drape/detail/parallel.hpp>
#include <drape/front_end.hpp>
#include <drape/kernel_constants.hpp>
#include <drape/sdf/grid.hpp>
#include <drape/sdf/solid.hpp>
#include <drape/settings.hpp>

#include <algorithm>
#include <cstdint>
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
    gatherLaneMasses();
    lambdaStretch_.resize(asset_->stretch.lambdaCount());
    lambdaShear_.resize(asset_->shear.lambdaCount());
    lambdaBending_.resize(asset_->bending.lambdaCount());
    contacts_.resize(n);
    propagation_.resize(n);
    // Grid cells of two mean edge lengths: a cell holds a few vertices of a flat cloth.
    double edgeSum = 0;
    for (const auto& e : asset_->edges)
      edgeSum += double((asset_->restPositions[e[1]] - asset_->restPositions[e[0]]).norm());
    const double meanEdge = asset_->edges.empty() ? 1.0 : edgeSum / double(asset_->edges.size());
    grid_.setTopology(asset_->triangles, n, S(2 * std::max(meanEdge, 1e-6)));
  }

  /// Collision work of the last substep.
  const CollisionStats& stats() const { return stats_; }
  /// Contact records of the last substep (improved and vertex methods).
  const ContactBuffer<S>& contacts() const { return contacts_; }

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
    if (change == StateChange::Positions) gridFresh_ = false;  // the grid's binned positions are not these
    if (change == StateChange::Masses) massesChanged_ = true;  // the lane copies are gathered again
  }
  static void checkSettings(const Settings&) {}  // the CPU runs every valid setting
  template <class Shape> static void checkSolid(const Solid<Shape>&) {}
  template <class Shape> void solidSet(Index) {}

  /// Moves the local origin to follow the cloth, in steps of 1/64 m so the shift is exact in float.
  void beginStep() {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : state_.x) centre += p.template cast<double>();
    centre /= double(state_.x.size());
    const Eigen::Vector3d shift = this->moveOrigin(centre);
    if (shift.isZero(0)) return;
    const Vec3<S> shiftS = shift.cast<S>();
    for (auto& p : state_.x) p -= shiftS;
    gridFresh_ = false;
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
    pinLocal_.resize(pins_.size());
    lambdaPins_.resize(pins_.size());
    for (std::size_t k = 0; k < pins_.size(); ++k)
      pinLocal_[k] = {pins_[k].vertex, (pins_[k].target - state_.origin).template cast<S>()};
    gridded_ = settings_.broadPhase && has.bounded > 0;
    gridFresh_ = gridFresh_ && gridded_;  // a grid not kept up in a substep without it is built anew
    moveBound_ = 0;
    contacts_.keepLines(coupled_);
    if (coupled_ && vStart_.size() != state_.v.size()) {
      vStart_.resize(state_.v.size());
      vPre_.resize(state_.v.size());
      exchanged_.reserve(state_.v.size());
    }
  }

  void subStep(double hd) {
    prepareSolids(hd);
    if (massesChanged_) {
      gatherLaneMasses();
      massesChanged_ = false;
    }
    stats_ = {};
    const int threads = settings_.threadCount == 0 ? hardwareThreads() : settings_.threadCount;
    // One team for the whole substep: the loops inside are work-shared, so the team is made once. One thread
    // opens no team: outside one the directives cost nothing, while a team of one still pays libgomp's barrier
    // (a futex wake-up each) for every work-shared loop.
    if (threads > 1) {
      DRAPE_OMP(parallel num_threads(threads))
      subStepBody(S(hd));
    } else {
      subStepBody(S(hd));
    }
  }

  void subStepBody(const S h) {
    const Index n = vertexCount();
    Vec3<S>* x = state_.x.data();
    Vec3<S>* v = state_.v.data();
    Vec3<S>* x0 = xPrev_.data();
    const S* w = state_.invMass.data();
    const ClothAsset<S>& a = *asset_;

    // 0. repulsion (phase 1), only in a scene that declares it
    if (repulsive_) repel(S(settings_.thickness), h);
    if (coupled_) copyVelocities(vStart_);  // the estimators' velocity at the start of the substep

    // 1. predict, into the packed positions the solve works on (the start positions are kept aside only for
    //    friction and the energy estimate, their readers after the velocity update)
    const Vec3<S> gh = (settings_.gravity * double(h)).template cast<S>();
    Vec3<S>* xp = xPredicted_.data();
    Vec4<S>* xw = packed_.data();
    if (hasFriction_ || coupled_)
      predictPositions<true>(n, x, v, w, gh, h, x0, xp, xw);
    else
      predictPositions<false>(n, x, v, w, gh, h, x0, xp, xw);

    // 2. solve
    const S h2 = h * h;
    const S stretchAlpha = S(settings_.stretchCompliance) / h2, shearAlpha = S(settings_.shearCompliance) / h2,
            bendingAlpha = S(settings_.bendingCompliance) / h2, pinAlpha = S(settings_.pinCompliance) / h2;
    const S thickness = S(settings_.thickness);
    const bool baseline = settings_.collisionMethod == CollisionMethod::Baseline;
    const int iterations = settings_.iterationCount;
    if (iterations > 1) {  // one pass needs no multipliers (see solveDistanceSet)
      DRAPE_OMP(single)
      {
        std::fill(lambdaStretch_.begin(), lambdaStretch_.end(), S(0));
        std::fill(lambdaShear_.begin(), lambdaShear_.end(), S(0));
        std::fill(lambdaBending_.begin(), lambdaBending_.end(), S(0));
      }
    }
    for (int it = 0; it < iterations; ++it) {
      solveSet(a.stretch, laneMasses_[0], stretchAlpha, lambdaStretch_.data(), iterations);
      solveSet(a.shear, laneMasses_[1], shearAlpha, lambdaShear_.data(), iterations);
      solveSet(a.bending, laneMasses_[2], bendingAlpha, lambdaBending_.data(), iterations);
      if (!pinLocal_.empty()) {
        DRAPE_OMP(single)
        {
          if (it == 0) std::fill(lambdaPins_.begin(), lambdaPins_.end(), S(0));
          solvePins(pinLocal_.data(), Index(pinLocal_.size()), pinAlpha, lambdaPins_.data(), xw, w);
        }
      }
      if (baseline) {  // the previous method collides inside the solve, on the unpacked positions
        unpack(x, xw);
        collideBaseline(h, thickness);
        DRAPE_OMP(for schedule(static))
        for (Index i = 0; i < n; ++i) xw[i].template head<3>() = x[i];
      }
    }

    // 3. update velocity (updateVelocities). Where a vertex may touch several surfaces, the positions the
    //    contacts start from are kept (in the prediction's buffer, free from here on) for the pinched vertices'
    //    least-squares placement.
    //    With the broad phase, the update also measures how far the vertices got from where the grid binned them,
    //    so the grid is rebuilt only when queries would have to grow too much.
    const S invH = S(1) / h;
    if (gridded_ && gridFresh_) {
      const S far = reconcile_ ? updateVelocities<true, true>(n, xw, xp, x, v, invH, grid_.binned())
                               : updateVelocities<false, true>(n, xw, xp, x, v, invH, grid_.binned());
      addMoveBound(moveBound_, std::sqrt(far));
      DRAPE_OMP(barrier)
    } else if (reconcile_) {
      updateVelocities<true, false>(n, xw, xp, x, v, invH);
    } else {
      updateVelocities<false, false>(n, xw, xp, x, v, invH);
    }

    // 4. collide
    if (coupled_) copyVelocities(vPre_);  // before any contact acts
    if (!baseline) collide(h, thickness);

    // 5. the cloth's push on the coupled bodies, applied before they move (docs/design.md §6)
    if (coupled_) {
      DRAPE_OMP(single)
      {
        gatherContactForces(h, thickness);
        for (std::size_t b = 0; b < bodies_.size(); ++b) bodies_[b]->applyForceAndTorque(bodyForce_[b], bodyTorque_[b]);
      }
    }
  }

  /// The constraint blocks' copies of the inverse masses, after any change of a mass. Only the float SIMD kernels
  /// read them: double runs the scalar kernel on the masses themselves.
  void gatherLaneMasses() {
    if constexpr (!std::is_same_v<S, float>) return;
    laneMasses_[0].gather(asset_->stretch, state_.invMass.data());
    laneMasses_[1].gather(asset_->shear, state_.invMass.data());
    laneMasses_[2].gather(asset_->bending, state_.invMass.data());
  }

  /// The packed positions back into the state (a work-shared loop).
  void unpack(Vec3<S>* x, const Vec4<S>* xw) {
    DRAPE_OMP(for schedule(static))
    for (Index i = 0; i < vertexCount(); ++i) x[i] = xw[i].template head<3>();
  }

  void copyVelocities(std::vector<Vec3<S>>& to) {
    const Vec3<S>* v = state_.v.data();
    Vec3<S>* out = to.data();
    DRAPE_OMP(for schedule(static))
    for (Index i = 0; i < vertexCount(); ++i) out[i] = v[i];
  }

  void repel(S thickness, S h) {
    Vec3<S>* v = state_.v.data();
    forEachCompiled([&](auto& list) {
      for (const auto& solid : list) {
        if (!(solid.repulsionRadius > S(0))) continue;
        if (solid.motion.body >= 0) copyVelocities(vPre_);  // scratch: what the region changes is an impulse
        if (solid.falloff == Falloff::Linear)
          repelVertices<Falloff::Linear>(solid, thickness, state_.x.data(), v, state_.invMass.data(), vertexCount());
        else
          repelVertices<Falloff::Smooth>(solid, thickness, state_.x.data(), v, state_.invMass.data(), vertexCount());
        if (solid.motion.body >= 0) {
          DRAPE_OMP(single)
          gatherRepulsionForces(solid, h);
        }
      }
    });
  }

  /// The velocity the region took from each particle near a dynamic solid, m dv / h, reversed onto the body at
  /// the particle's closest point on it.
  template <class Solid> void gatherRepulsionForces(const Solid& solid, S h) {
    const std::int32_t b = solid.motion.body;
    const Eigen::Vector3d& centre = bodyCentre_[b];
    for (Index i = 0; i < vertexCount(); ++i) {
      const Vec3<S> dv = state_.v[i] - vPre_[i];
      if (dv.isZero(0)) continue;
      Vec3<S> n;
      const S phi = solid.sdf(state_.x[i], n);
      Eigen::Vector3d force = -(dv / (state_.invMass[i] * h)).template cast<double>();
      if (settings_.normalForceOnly) force = force.dot(n.template cast<double>()) * n.template cast<double>();
      const Eigen::Vector3d point = state_.origin + (state_.x[i] - phi * n).template cast<double>();
      bodyForce_[b] += force;
      bodyTorque_[b] += (point - centre).cross(force);
    }
  }

  /// Phase 2 (docs/design.md §6): for every contact vertex, the force its contacts with each coupled body put on it,
  /// reversed onto that body at the contact point (the vertex moved back by the thickness along the normal).
  /// A vertex's velocity change is one vector however many slots made it, so when all its slots belong to one
  /// body that body gets the whole of it, along the normal of the slot that corrected the vertex most; a vertex
  /// between two bodies (or a body and a fixed solid) passes each body the normal part along its own slot.
  /// Serial, in vertex order, so the sums do not depend on the thread count.
  void gatherContactForces(S h, S thickness) {
    const ContactForce estimator = settings_.contactForce;
    const bool propagated = estimator == ContactForce::Impulse && settings_.propagationRings > 0 &&
                            settings_.propagationWeight > 0 && settings_.collisionMethod == CollisionMethod::Improved;
    pinch_.assign(bodies_.size(), Pinch{});
    exchange_.assign(bodies_.size(), Exchange{});
    exchanged_.clear();
    for (Index i = 0; i < vertexCount(); ++i) {
      if (!contacts_.live(i)) {
        if (propagated) gatherPropagatedImpulse(i, h, thickness);
        continue;
      }
      const int count = contacts_.slotCount[i];
      const auto& slots = contacts_.slots[i];
      bool oneBody = true;
      int top = 0;  // the slot that corrected the vertex most
      for (int k = 1; k < count; ++k) {
        oneBody = oneBody && slots[k].body == slots[0].body;
        if (slots[k].correction > slots[top].correction) top = k;
      }
      const S m = S(1) / state_.invMass[i];
      const Vec3<S>& v = state_.v[i];
      const Vec3<S> dv = v - vPre_[i];                                // what the contacts did
      const Vec3<S> otherForce = m * (vPre_[i] - vStart_[i]) / h;  // constraints and gravity this substep
      Vec3<S> energyForce = Vec3<S>::Zero();                          // on the particle
      if (estimator == ContactForce::Energy) {
        const Vec3<S> d = state_.x[i] - xPrev_[i];
        const S d2 = d.squaredNorm();
        const S work = S(0.5) * m * (v.squaredNorm() - vStart_[i].squaredNorm()) - otherForce.dot(d);
        if (d2 > S(constants::kEnergyMinDisplacement2)) energyForce = (work / d2) * d;
        // Over a tiny displacement the work / |d| quotient is unbounded (a particle held still under a body
        // launched it at 400 m/s). The contact's force cannot exceed what the momentum balance allows,
        // |m (v - v_start) / h - F_other|, so its magnitude is capped there; its direction stays along d.
        const S cap = (m * (v - vStart_[i]) / h - otherForce).norm();
        const S size = energyForce.norm();
        if (size > cap) energyForce *= cap / size;
      }
      for (int k = 0; k < count; ++k) {
        const ContactSlot<S>& c = slots[k];
        if (c.body < 0) continue;
        if (count > 1 && !oneBody && pinchSupport(i, k, h, thickness)) continue;
        if (oneBody && k != top) continue;
        const Vec3<S>& n = c.normal;
        Vec3<S> onBody = Vec3<S>::Zero();
        switch (estimator) {
          case ContactForce::SubForce: {
            const S fn = otherForce.dot(n);
            if (fn < S(0)) onBody = fn * n;
            break;
          }
          case ContactForce::Energy:
            onBody = oneBody ? Vec3<S>(-energyForce) : Vec3<S>(-energyForce.dot(n) * n);
            break;
          case ContactForce::Impulse: {
            const S dvn = dv.dot(n);
            Vec3<S> impulse = (dvn + unresolvedOverlap(i, k) / h) * n;
            if (oneBody) impulse += dv - dvn * n;  // the tangential (friction) change
            onBody = -(m / h) * impulse;
            break;
          }
        }
        if (oneBody)
          addExchange(c, i, onBody.template cast<double>(), thickness, i, m);
        else
          addBodyForce(c, i, onBody.template cast<double>(), thickness);
      }
    }
    shareExchanges();
    // Each pinch's support was sized to hold the body alone; a body on several shares it among them.
    for (std::size_t b = 0; b < pinch_.size(); ++b) {
      if (pinch_[b].count == 0) continue;
      bodyForce_[b] += pinch_[b].force / pinch_[b].count;
      bodyTorque_[b] += pinch_[b].torque / pinch_[b].count;
    }
  }

  /// The overlap the projections could not resolve for vertex i's slot k, on the slot's own plane or on an
  /// opposing one (weighted by how squarely it opposes): a vertex pinched between slot k's body and another
  /// surface ends up behind one of the two planes.
  S unresolvedOverlap(Index i, int k) const {
    const auto& slots = contacts_.slots[i];
    const Vec3<S>& n = slots[k].normal;
    S overlap = std::max(slots[k].offset - n.dot(state_.x[i]), S(0));
    for (int j = 0; j < contacts_.slotCount[i]; ++j)
      if (j != k)
        overlap += std::max(slots[j].offset - slots[j].normal.dot(state_.x[i]), S(0)) *
                   std::max(-slots[j].normal.dot(n), S(0));
    return overlap;
  }

  /// A vertex held between slot k's body and a fixed (static or kinematic) solid facing it cannot pass on the
  /// solid's push through its own momentum: its mass is far too small, and the estimates above would hand the
  /// body a force of about m_vertex / h^2 per metre of overlap, which let a ball sink through a cloth lying on
  /// the floor to the floor itself (where the pinched vertices then shot out sideways at tens of m/s). The
  /// pinched cloth is a spacer instead: the solid holds the body through it, with the impulse that stops the
  /// body's approach at that point (its effective mass there), plus a fifth of the overlap per substep, and
  /// Coulomb friction with the slot's coefficients against the body's sliding over the vertex. Recorded in
  /// pinch_ and shared out among the body's pinches at the end. Returns false (nothing recorded) when the
  /// vertex is not pinched against a fixed solid.
  bool pinchSupport(Index i, int k, S h, S thickness) {
    const auto& slots = contacts_.slots[i];
    const ContactSlot<S>& c = slots[k];
    int against = -1;
    for (int j = 0; j < contacts_.slotCount[i]; ++j)
      if (j != k && slots[j].body < 0 && slots[j].normal.dot(c.normal) < S(constants::kPinchOpposingCos)) against = j;
    if (against < 0) return false;
    const CoupledBody& body = *bodies_[std::size_t(c.body)];
    const Eigen::Vector3d n = c.normal.template cast<double>();
    const Eigen::Vector3d r = contactPoint(c, i, thickness);
    const Eigen::Vector3d centre = bodyCentre_[std::size_t(c.body)];
    const Eigen::Vector3d wall = slots[against].solidVelocity.template cast<double>();
    const double approach =
        (body.velocityAt(centre + r) - wall).dot(n) + constants::kPinchRate * double(unresolvedOverlap(i, k)) / double(h);
    const Eigen::Vector3d rn = r.cross(n);
    const double kn = body.inverseMass() + rn.dot(body.inverseInertiaWorld() * rn);
    Pinch& p = pinch_[std::size_t(c.body)];
    ++p.count;
    if (!(approach > 0) || !(kn > 0)) return true;
    const double push = approach / (kn * double(h));  // N, on the body along -n
    Eigen::Vector3d force = -push * n;
    Eigen::Vector3d slide = body.velocityAt(centre + r) - state_.v[i].template cast<double>();
    slide -= slide.dot(n) * n;
    const double speed = slide.norm();
    if (speed > 0 && !settings_.normalForceOnly) {
      slide /= speed;
      const Eigen::Vector3d rt = r.cross(slide);
      const double stop = speed / ((body.inverseMass() + rt.dot(body.inverseInertiaWorld() * rt)) * double(h));
      force -= (stop <= double(c.staticFriction) * push ? stop : std::min(stop, double(c.dynamicFriction) * push)) * slide;
    }
    addWrench(c, i, force, thickness, p.force, p.torque);
    return true;
  }

  /// A force f on contact slot c's body from vertex `at` (the reverse of what the vertex got: Newton's third
  /// law holds exactly), acting at contactPoint, added to (force, torque) about the body's centre.
  void addWrench(const ContactSlot<S>& c, Index at, Eigen::Vector3d f, S thickness, Eigen::Vector3d& force,
                 Eigen::Vector3d& torque) const {
    // Without friction a contact can only push along its normal: what else the vertex's change holds (its
    // slot's merged normals, propagation from neighbours facing other ways) is not the body's to take.
    if (settings_.normalForceOnly || (c.staticFriction == S(0) && c.dynamicFriction == S(0))) {
      const Eigen::Vector3d n = c.normal.template cast<double>();
      f = f.dot(n) * n;
    }
    force += f;
    torque += contactPoint(c, at, thickness).cross(f);
  }
  void addBodyForce(const ContactSlot<S>& c, Index at, const Eigen::Vector3d& f, S thickness) {
    addWrench(c, at, f, thickness, bodyForce_[std::size_t(c.body)], bodyTorque_[std::size_t(c.body)]);
  }
  /// addBodyForce for the push f of a vertex (mass m) whose contacts are all with slot c's body: it joins the
  /// body's Exchange, and the vertex is listed as that body's (shareExchanges).
  void addExchange(const ContactSlot<S>& c, Index at, const Eigen::Vector3d& f, S thickness, Index vertex, S m) {
    Exchange& e = exchange_[std::size_t(c.body)];
    addWrench(c, at, f, thickness, e.force, e.torque);
    e.vertexSide += f.squaredNorm() / double(m);
    exchanged_.push_back({vertex, c.body});  // at most one per vertex: the capacity is the vertex count
  }

  /// The estimates take each vertex's push as if the body could not move. Where the vertices pushing a light
  /// body together outweigh it, the body got all of their momentum change and left faster than they came, with
  /// energy from nowhere: a 1.3 g hull met by a dozen vertices spun up to 870 rad/s in one substep. So each
  /// body's exchange with the vertices that touch only it is an inelastic collision of the two: each push f_i is
  /// an impulse h f_i between the vertex's mass m_i and the body, and both sides take the share
  /// s = Q / (Q + J^T M^-1 J) of it, with Q = sum h^2 |f_i|^2 / m_i, J = (F h, T h) the body's summed impulse and M
  /// its mass matrix. For vertices of total mass M_c pushing alike along n at r, s = 1 / (1 + M_c k) with
  /// k = 1/m + (r x n)^T I^-1 (r x n): the impulse of two masses meeting, m_eff M_c / (m_eff + M_c) against the
  /// immovable body's M_c. A heavy body (k M_c -> 0) keeps all of it. The vertices keep the rest of their change
  /// undone, so they meet the body again the next substep: with the impulse estimate, momentum is still
  /// exchanged exactly, only later. Pinches, and vertices that also touch another surface, are not scaled.
  void shareExchanges() {
    bool partial = false;
    for (std::size_t b = 0; b < exchange_.size(); ++b) {
      Exchange& e = exchange_[b];
      const CoupledBody& body = *bodies_[b];
      // Both sides of Q / (Q + J^T M^-1 J) without their common factor h^2.
      const double bodySide =
          body.inverseMass() * e.force.squaredNorm() + e.torque.dot(body.inverseInertiaWorld() * e.torque);
      e.share = bodySide > 0 ? e.vertexSide / (e.vertexSide + bodySide) : 1.0;
      bodyForce_[b] += e.share * e.force;
      bodyTorque_[b] += e.share * e.torque;
      partial = partial || e.share < 1;
    }
    if (!partial) return;
    Vec3<S>* v = state_.v.data();
    for (const auto& [i, b] : exchanged_) {
      const S share = S(exchange_[std::size_t(b)].share);
      v[i] = vPre_[i] + share * (v[i] - vPre_[i]);
    }
  }
  /// Where slot c's push acts on its body, from the body's centre (world axes): on the line along the slot's
  /// normal n whose moment is its contacts' mean moment (ContactLine; the foot of the perpendicular
  /// from the centre is n x moment / (push . n)), at the height along n where vertex `at` touches the surface.
  /// So a normal push has the moment of the contacts that made it (none on a ball), and a vertex pushed through a
  /// face's deepest point, which may not touch the body at all, pushes there.
  Eigen::Vector3d contactPoint(const ContactSlot<S>& c, Index at, S thickness) const {
    const ContactLine<S>& line = contacts_.lines[std::size_t(at)][std::size_t(&c - contacts_.slots[at].data())];
    const Eigen::Vector3d n = c.normal.template cast<double>();
    const Eigen::Vector3d touch =
        (state_.x[at] - thickness * c.normal).template cast<double>() + state_.origin - bodyCentre_[std::size_t(c.body)];
    const double along = line.push.template cast<double>().dot(n);
    if (!(along > constants::kLineMinAlong)) return touch;  // the slot took in another direction: its contacts do not share a line
    return n.cross(line.moment.template cast<double>() / along) + touch.dot(n) * n;
  }

  /// Propagation gave vertex i (not in contact) a velocity change on behalf of its contact neighbours: the
  /// impulse estimate passes it to the body of the first neighbour in contact with one. (A change that came
  /// from further rings, or from a fixed solid's contacts, is not passed on.)
  void gatherPropagatedImpulse(Index i, S h, S thickness) {
    const Vec3<S> dv = state_.v[i] - vPre_[i];
    if (dv.isZero(0) || state_.invMass[i] == S(0)) return;
    const Adjacency& around = asset_->vertexNeighbours;
    for (const Index* j = around.begin(i); j != around.end(i); ++j) {
      if (!contacts_.live(*j)) continue;
      const auto& slots = contacts_.slots[*j];
      for (int k = 0; k < contacts_.slotCount[*j]; ++k) {
        if (slots[k].body < 0) continue;
        const S m = S(1) / state_.invMass[i];
        addExchange(slots[k], *j, (-(m / h) * dv).template cast<double>(), thickness, i, m);
        return;
      }
    }
  }

  void solveSet(const DistanceSet<S>& set, const LaneMasses<S>& lanes, S alpha, S* lambda, int iterations) {
    if (iterations > 1 && alpha > S(0))
      solveDistanceSet<true>(set, lanes, alpha, lambda, packed_.data(), state_.invMass.data());
    else
      solveDistanceSet<false>(set, lanes, alpha, lambda, packed_.data(), state_.invMass.data());
  }

  /// Projects every vertex, then (when kFaces and the field is not linear) every face, out of each solid in
  /// turn, recording the contacts. On a linear field a face is deepest at a vertex, which the vertex pass has
  /// already handled. Vertices already within `slack` of the thickness are left where they are. With the broad
  /// phase on, a bounded solid visits only the vertices and faces the grid finds near its box.
  template <bool kFaces, bool kCull> void projectContacts(S thickness, S slack = S(0)) {
    Vec3<S>* x = state_.x.data();
    const S* w = state_.invMass.data();
    const Index n = vertexCount();
    forEachCompiled([&](auto& list) {
      for (const auto& solid : list) {
        constexpr bool kFacePass = kFaces && !std::decay_t<decltype(solid.sdf)>::kLinear;
        if (gridded_ && solid.bounded) {
          DRAPE_OMP(single)
          {
            if (grid_.stale()) grid_.build(x, this->asset_->triangles);
            grid_.vertices(x, solid.boxLow, solid.boxHigh, thickness, nearVertices_);
          }
          projectVertexContacts(solid, thickness, x, w, ItemList{nearVertices_.data()}, Index(nearVertices_.size()),
                                contacts_, stats_, grid_.binned(), moveBound_, slack);
          DRAPE_OMP(single)
          {
            grid_.noteDrift(moveBound_);
            moveBound_ = 0;
            if constexpr (kFacePass) {
              grid_.faces(x, solid.boxLow, solid.boxHigh, thickness, nearFaces_);
              grid_.noteDrift(projectFaceContacts<kCull, true>(
                  solid, thickness, this->settings_.pgdIterations, this->asset_->triangles, ItemList{nearFaces_.data()},
                  Index(nearFaces_.size()), x, w, contacts_, stats_, grid_.binned()));
            }
          }
        } else {
          // Without a grid, the binned positions are the positions: nothing drifts.
          const Vec3<S>* binned = gridded_ ? grid_.binned() : x;
          projectVertexContacts(solid, thickness, x, w, AllItems{}, n, contacts_, stats_, binned, moveBound_, slack);
          if constexpr (kFacePass) {
            DRAPE_OMP(single)
            {
              const S moved = projectFaceContacts<kCull>(solid, thickness, this->settings_.pgdIterations, this->asset_->triangles,
                                                         AllItems{}, Index(this->asset_->triangles.size()), x, w, contacts_,
                                                         stats_, binned);
              if (gridded_) grid_.noteDrift(moved);
            }
          }
          if (gridded_) {
            DRAPE_OMP(single)
            {
              grid_.noteDrift(moveBound_);
              moveBound_ = 0;
            }
          }
        }
      }
    });
  }

  /// All contacts of a substep: the projections, then where surfaces meet (a crease, a box corner, a cloth
  /// pinched between a ball and the floor) pushing a vertex out of one can put it back into another, so such
  /// vertices go outside all their contact planes at once and, where several solids exist, the vertex passes
  /// repeat on the true fields until no vertex moves by more than a ten-thousandth of the thickness.
  void projectAllContacts(S thickness, bool faces) {
    DRAPE_OMP(single)
    {
      contacts_.begin();
      if (gridded_) {
        grid_.noteDrift(moveBound_);  // the prediction's and the solve's moves (updateVelocities)
        // The baseline collides inside the solve, before the update has measured the solve's moves.
        const bool inSolve = settings_.collisionMethod == CollisionMethod::Baseline;
        if (!gridFresh_ || inSolve || grid_.stale()) grid_.build(state_.x.data(), asset_->triangles);
        gridFresh_ = true;
      }
      moveBound_ = 0;
    }
    if (faces && settings_.culling)
      projectContacts<true, true>(thickness);
    else if (faces)
      projectContacts<true, false>(thickness);
    else
      projectContacts<false, false>(thickness);
    if (!reconcile_) return;  // a lone plane gives each vertex one surface: nothing to reconcile
    settleOntoContactPlanes();
    if (solidCount() < 2) return;
    for (int pass = 0; pass < constants::kSettlePasses; ++pass) {
      // Every thread reads the count here, between two barriers (the one ending the loop above and the one
      // ending the vertex pass below), so all take the same branch.
      const auto before = stats_.vertexContacts;
      DRAPE_OMP(barrier)
      projectContacts<false, false>(thickness, S(constants::kSettleSlack) * thickness);
      if (stats_.vertexContacts == before) break;
      settleOntoContactPlanes();
    }
  }

  void settleOntoContactPlanes() {
    projectOntoContactPlanes(contacts_, state_.x.data(), xPredicted_.data(),
                             gridded_ ? grid_.binned() : state_.x.data(), moveBound_);
    if (gridded_) {
      DRAPE_OMP(single)
      {
        grid_.noteDrift(moveBound_);
        moveBound_ = 0;
      }
    }
  }

  /// The "previous method": the same vertex and face contacts, projected inside the solve pass, with
  /// position-level friction; the velocity update then turns every projection into velocity.
  void collideBaseline(S h, S thickness) {
    projectAllContacts(thickness, true);
    if (hasFriction_) applyContactFriction(contacts_, state_.x.data(), xPrev_.data(), h);
  }

  void collide(S h, S thickness) {
    Vec3<S>* x = state_.x.data();
    Vec3<S>* v = state_.v.data();
    const S* w = state_.invMass.data();
    const bool faces = settings_.collisionMethod == CollisionMethod::Improved;
    projectAllContacts(thickness, faces);
    if (hasFriction_)
      respondContacts<true>(contacts_, x, xPrev_.data(), v, h, S(settings_.normalDamping));
    else
      respondContacts<false>(contacts_, x, xPrev_.data(), v, h, S(settings_.normalDamping));
    if (faces && settings_.propagationRings > 0 && settings_.propagationWeight > 0)
      propagateCorrections(contacts_, propagation_, asset_->vertexNeighbours, v, w, S(settings_.propagationWeight),
                           settings_.propagationRings);
  }


  std::vector<PinTarget<S>> pinLocal_;
  std::vector<Vec3<S>> xPrev_, xPredicted_;
  std::vector<Vec4<S>> packed_;   ///< (position, 0) of each vertex: what the constraint solve works on
  LaneMasses<S> laneMasses_[3];  ///< the stretch, shear and bending blocks' inverse masses (gatherLaneMasses)
  std::vector<S> lambdaStretch_, lambdaShear_, lambdaBending_, lambdaPins_;
  ContactBuffer<S> contacts_;
  PropagationBuffer<S> propagation_;
  CollisionStats stats_;
  bool hasFriction_ = false;  ///< some solid has friction this substep
  bool repulsive_ = false;    ///< some solid has a repulsion region this substep
  bool reconcile_ = false;    ///< a vertex may touch several surfaces this substep
  bool coupled_ = false;      ///< some solid is a dynamic body this substep
  bool gridded_ = false;      ///< contacts with bounded solids go through the grid this substep
  bool gridFresh_ = false;    ///< the grid was built, and every move since is in its drift
  bool massesChanged_ = false;  ///< an inverse mass changed since the lane copies were gathered
  ClothGrid<S> grid_;
  std::vector<Index> nearVertices_, nearFaces_;  ///< what the grid found near the current solid
  S moveBound_ = 0;  ///< the passes' largest vertex moves, summed (shared by the team)
  std::vector<Vec3<S>> vStart_, vPre_;                  ///< velocities at the substep's start, before contacts
  /// A body's exchange with the vertices whose contacts are all with it, this substep (shareExchanges).
  struct Exchange {
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();  ///< estimated, on the body
    double vertexSide = 0;    ///< sum of |f|^2 / m over those vertices' pushes f
    double share = 1;         ///< of the estimate both sides take
  };
  std::vector<Exchange> exchange_;
  std::vector<std::pair<Index, std::int32_t>> exchanged_;  ///< the vertices in an Exchange, and its body
  struct Pinch {  ///< a body's pinchSupport sums this substep
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
    int count = 0;
  };
  std::vector<Pinch> pinch_;
};

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
