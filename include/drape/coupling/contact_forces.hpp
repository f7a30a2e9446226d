#pragma once
// Phase 2 of the coupling (docs/design.md §6): for every contact vertex, the force its contacts with each
// coupled body put on it, reversed onto that body at the contact point, by the chosen estimator (sub-force,
// energy, impulse); pinched vertices hold their body through the fixed solid behind them instead. The CPU twin
// of shaders/contact_forces.comp. Serial, in vertex order, so the sums do not depend on the thread count.

#include <drape/cloth/state.hpp>
#include <drape/collision/response.hpp>
#include <drape/coupling/body.hpp>
#include <drape/coupling/body_sums.hpp>
#include <drape/kernel_constants.hpp>
#include <drape/settings.hpp>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace drape::coupling {

/// What the estimators read of a substep, all in the cloth's local frame but the bodies' centres (world).
template <Scalar S> struct SubstepView {
  const ContactBuffer<S>& contacts;
  const ClothState<S>& state;       ///< after the contacts acted
  const Vec3<S>* start;             ///< positions at the start of the substep
  const Vec3<S>* vStart;            ///< velocities at the start of the substep
  const Vec3<S>* vPre;              ///< velocities before the contacts acted
  const Adjacency& neighbours;      ///< each vertex's neighbours (the asset's vertexNeighbours)
  const std::vector<CoupledBody*>& bodies;
  /// The bodies' centres of mass where the substep's contacts were found; torques are taken about them.
  const std::vector<Eigen::Vector3d>& centres;
  S h;          ///< the substep (s)
  S thickness;  ///< m
  ContactForce estimator;
  bool normalOnly;  ///< pass bodies only the normal part of each push
  bool propagated;  ///< pass on the impulse propagation gave vertices not in contact
};

/// The options of Settings the estimators read; `propagated` where the impulse estimate passes on what
/// propagation gave vertices not in contact.
inline bool passesPropagatedImpulse(const Settings& s) {
  return s.contactForce == ContactForce::Impulse && s.propagationRings > 0 && s.propagationWeight > 0 &&
         s.collisionMethod == CollisionMethod::Faces;
}

/// A vertex's velocity change in a body's exchange (shareExchanges): the whole change (slot -1, a vertex whose
/// contacts are all with that body), or `part` of it, the share of slot `slot`'s body in a change that several
/// bodies made.
struct Exchanged {
  Index vertex;
  std::int32_t body;
  std::int32_t slot = -1;
  Eigen::Vector3d part = Eigen::Vector3d::Zero();
};

/// What one substep's estimates add up to: the direct pushes go into `force` and `torque` (which hold the
/// repulsion region's already), exchanges and pinches into `sums`, and `exchanged` lists each exchanged vertex
/// with its body; each pinch is listed in `spacers`.
struct Gathered {
  std::vector<Eigen::Vector3d>& force;
  std::vector<Eigen::Vector3d>& torque;
  std::vector<BodySums>& sums;
  std::vector<Exchanged>& exchanged;
  std::vector<Spacer>& spacers;
};

/// Where slot c's push acts on its body, from the body's centre (world axes): on the line along the slot's
/// normal n whose moment is its contacts' mean moment (ContactLine; the foot of the perpendicular from the
/// centre is n x moment / (push . n)), at the height along n where vertex `at` touches the surface. So a
/// normal push has the moment of the contacts that made it (none on a ball), and a vertex pushed through a
/// face's deepest point, which may not touch the body at all, pushes there.
template <Scalar S> Eigen::Vector3d contactPoint(const SubstepView<S>& s, const ContactSlot<S>& c, Index at) {
  const ContactLine<S>& line = s.contacts.lines[std::size_t(at)][std::size_t(&c - s.contacts.slots[at].data())];
  const Eigen::Vector3d n = c.normal.template cast<double>();
  const Eigen::Vector3d touch = (s.state.x[at] - s.thickness * c.normal).template cast<double>() + s.state.origin -
                                s.centres[std::size_t(c.body)];
  const double along = line.push.template cast<double>().dot(n);
  // A slot that took contacts in another direction has no line they share.
  if (!(along > constants::kLineMinAlong)) return touch;
  return n.cross(line.moment.template cast<double>() / along) + touch.dot(n) * n;
}

/// The overlap the projections could not resolve for vertex i's slot k, on the slot's own plane or on an
/// opposing one (weighted by how squarely it opposes): a vertex pinched between slot k's body and another
/// surface ends up behind one of the two planes.
template <Scalar S> S unresolvedOverlap(const ContactBuffer<S>& contacts, const Vec3<S>& x, Index i, int k) {
  const auto& slots = contacts.slots[i];
  const Vec3<S>& n = slots[k].normal;
  S overlap = std::max(slots[k].offset - n.dot(x), S(0));
  for (int j = 0; j < contacts.slotCount[i]; ++j)
    if (j != k)
      overlap += std::max(slots[j].offset - slots[j].normal.dot(x), S(0)) * std::max(-slots[j].normal.dot(n), S(0));
  return overlap;
}

/// A force f on contact slot c's body from vertex `at` (the reverse of what the vertex got: Newton's third
/// law holds exactly), acting at contactPoint, added to (force, torque) about the body's centre.
template <Scalar S>
void addWrench(const SubstepView<S>& s, const ContactSlot<S>& c, Index at, Eigen::Vector3d f, Eigen::Vector3d& force,
               Eigen::Vector3d& torque) {
  // Without friction a contact can only push along its normal: what else the vertex's change holds (its
  // slot's merged normals, propagation from neighbours facing other ways) is not the body's to take.
  if (s.normalOnly || (c.staticFriction == S(0) && c.dynamicFriction == S(0))) {
    const Eigen::Vector3d n = c.normal.template cast<double>();
    f = f.dot(n) * n;
  }
  force += f;
  torque += contactPoint(s, c, at).cross(f);
}

/// The push f of a vertex (mass m) whose contacts are all with slot c's body: it joins the body's exchange, and
/// the vertex is listed as that body's (shareExchanges).
template <Scalar S>
void addExchange(const SubstepView<S>& s, const ContactSlot<S>& c, Index at, const Eigen::Vector3d& f, Index vertex,
                 S m, Gathered& out) {
  BodySums& e = out.sums[std::size_t(c.body)];
  addWrench(s, c, at, f, e.exchangeForce, e.exchangeTorque);
  e.vertexSide += f.squaredNorm() / double(m);
  out.exchanged.push_back({vertex, c.body});  // at most one per slot: the capacity is kContactSlots per vertex
}

/// What share of the normal part of vertex i's velocity change dv along slot k's normal was slot k's, for a vertex
/// whose slots belong to several solids. The change the contacts made is a sum of pushes along the slots'
/// normals, dv = sum_j a_j n_j (the split's nearest velocity approaching no surface is such a sum, with every
/// a_j >= 0), so the a_j solve the normals' Gram system G a = (n_j . dv) and slot k's share is a_k / (n_k . dv):
/// two bodies pressing a vertex side by side then share its change, where each took all of its normal part, and
/// a sideways change goes to the tilted surface that made it. Where the normals nearly span less than their
/// count (two surfaces facing each other), each slot takes its whole normal part (share 1).
template <Scalar S> S ownShare(const ContactBuffer<S>& contacts, Index i, int k, const Vec3<S>& dv) {
  const auto& slots = contacts.slots[i];
  const int count = contacts.slotCount[i];
  const S along = slots[k].normal.dot(dv);
  if (!(along > S(0))) return S(0);
  // The Gram system padded to 3 x 3 with the identity: Cramer's rule for two slots or three.
  Mat3<S> g = Mat3<S>::Identity();
  Vec3<S> b = Vec3<S>::Zero();
  for (int j = 0; j < count; ++j) {
    b[j] = slots[j].normal.dot(dv);
    for (int l = 0; l < count; ++l) g(j, l) = slots[j].normal.dot(slots[l].normal);
  }
  const S det = g.determinant();
  if (!(det > S(constants::kSplitGramMin))) return S(1);
  g.col(k) = b;
  return std::max(g.determinant() / det, S(0)) / along;
}

/// The push f of vertex i's slot k, one of several solids' the vertex touches, `weight` of the normal part of its
/// change being the slot's (ownShare): it joins the body's exchange as a vertex of mass weight * m, and the vertex
/// is listed with that part of its change.
template <Scalar S>
void addSplitExchange(const SubstepView<S>& s, const ContactSlot<S>& c, Index i, int k, const Eigen::Vector3d& f,
                      S weight, S m, Gathered& out) {
  BodySums& e = out.sums[std::size_t(c.body)];
  addWrench(s, c, i, f, e.exchangeForce, e.exchangeTorque);
  e.vertexSide += f.squaredNorm() / double(weight * m);
  const Vec3<S> dv = s.state.v[i] - s.vPre[i];
  out.exchanged.push_back({i, c.body, k, (weight * dv.dot(c.normal) * c.normal).template cast<double>()});
}

/// The slot of vertex i that pinches it against slot k's body: one whose normal opposes slot k's, a fixed
/// (static or kinematic) solid's before another body's; -1 where there is none.
template <Scalar S> int pinchingSlot(const ContactBuffer<S>& contacts, Index i, int k) {
  const auto& slots = contacts.slots[i];
  int fixed = -1, body = -1;
  for (int j = 0; j < contacts.slotCount[i]; ++j) {
    if (j == k || !(slots[j].normal.dot(slots[k].normal) < S(constants::kPinchOpposingCos))) continue;
    if (slots[j].body < 0) fixed = j;
    else if (slots[j].body != slots[k].body) body = j;
  }
  return fixed >= 0 ? fixed : body;
}

/// Vertex i at x pinched between its slot k (c), a body's, and slot o's surface, as a spacer with its points in
/// the cloth's local frame (SolverFront::spacersToBodyFrames moves them). Each slot's plane lies a thickness t out
/// of its surface (`offset`: where the vertex was placed along the normal); `onOther` lies kSpacerGap thicknesses
/// out.
template <Scalar S>
Spacer spacerOf(Index i, int k, const Vec3<S>& x, S t, const ContactSlot<S>& c, const ContactSlot<S>& o) {
  Spacer p;
  p.vertex = std::int32_t(i);
  p.slot = std::int32_t(k);
  p.body = c.body;
  p.other = o.body;
  p.onBody = (x - (c.normal.dot(x) - c.offset + t) * c.normal).template cast<double>();
  const S out = S(constants::kSpacerGap - 1) * t - (o.normal.dot(x) - o.offset);
  p.onOther = (x + out * o.normal).template cast<double>();
  p.normal = o.normal.template cast<double>();
  return p;
}

/// A vertex held between slot k's body and a surface facing it cannot pass on that surface's push through its
/// own momentum: its mass is far too small, and the estimates would hand the body a force of about
/// m_vertex / h^2 per metre of overlap, which let a ball sink through a cloth lying on the floor to the floor
/// itself (where the pinched vertices then shot out sideways at tens of m/s), and let two bodies closing on each
/// other crush the cloth between them (a vertex 5 mm into a hull in the rain). The pinched cloth is a spacer
/// instead: it passes the body the impulse that stops the body's approach to the other surface at that point,
/// plus a share of the overlap per substep (kPinchRate), and Coulomb friction with the slot's coefficients
/// against the body's sliding over the vertex. Against a fixed (static or kinematic) solid the effective mass is
/// the body's alone; against another body it is the pair's, `1 / (k_a + k_b)`, and each body's slot gives it
/// its side of that exchange, so the two pushes are equal and opposite where the normals are. Recorded in the
/// body's sums, shared out among its pinches at the end (addPinches). Returns false (nothing recorded) when the
/// vertex is not pinched (pinchingSlot).
template <Scalar S> bool pinchSupport(const SubstepView<S>& s, Index i, int k, Gathered& out) {
  const auto& slots = s.contacts.slots[i];
  const ContactSlot<S>& c = slots[k];
  const int against = pinchingSlot(s.contacts, i, k);
  if (against < 0) return false;
  const ContactSlot<S>& o = slots[against];
  if (o.body < c.body) out.spacers.push_back(spacerOf(i, k, s.state.x[i], s.thickness, c, o));
  const CoupledBody& body = *s.bodies[std::size_t(c.body)];
  const Eigen::Vector3d n = c.normal.template cast<double>();
  const Eigen::Vector3d r = contactPoint(s, c, i);
  const Eigen::Vector3d centre = s.centres[std::size_t(c.body)];
  // The other surface's velocity at the vertex, and what its inertia adds to the exchange along a direction.
  Eigen::Vector3d wall = o.solidVelocity.template cast<double>(), ro = Eigen::Vector3d::Zero();
  const CoupledBody* other = o.body >= 0 ? s.bodies[std::size_t(o.body)] : nullptr;
  if (other) {
    ro = contactPoint(s, o, i);
    wall = other->velocityAt(s.centres[std::size_t(o.body)] + ro);
  }
  auto inverseMassAlong = [&](const Eigen::Vector3d& d) {
    const Eigen::Vector3d rd = r.cross(d);
    double inverse = body.inverseMass() + rd.dot(body.inverseInertiaWorld() * rd);
    if (other) {
      const Eigen::Vector3d od = ro.cross(d);
      inverse += other->inverseMass() + od.dot(other->inverseInertiaWorld() * od);
    }
    return inverse;
  };
  const double h = double(s.h);
  const double approach = (body.velocityAt(centre + r) - wall).dot(n) +
                          constants::kPinchRate * double(unresolvedOverlap(s.contacts, s.state.x[i], i, k)) / h;
  const double kn = inverseMassAlong(n);
  BodySums& p = out.sums[std::size_t(c.body)];
  ++p.pinches;
  if (!(approach > 0) || !(kn > 0)) return true;
  const double push = approach / (kn * h);  // N, on the body along -n
  Eigen::Vector3d force = -push * n;
  Eigen::Vector3d slide = body.velocityAt(centre + r) - s.state.v[i].template cast<double>();
  slide -= slide.dot(n) * n;
  const double speed = slide.norm();
  if (speed > 0 && !s.normalOnly) {
    slide /= speed;
    const double stop = speed / (inverseMassAlong(slide) * h);
    force -= (stop <= double(c.staticFriction) * push ? stop : std::min(stop, double(c.dynamicFriction) * push)) * slide;
  }
  addWrench(s, c, i, force, p.pinchForce, p.pinchTorque);
  return true;
}

/// Propagation gave vertex i (not in contact) a velocity change on behalf of its contact neighbours: the
/// impulse estimate passes it to the body of the first neighbour in contact with one. (A change that came
/// from further rings, or from a fixed solid's contacts, is not passed on.)
template <Scalar S> void gatherPropagatedImpulse(const SubstepView<S>& s, Index i, Gathered& out) {
  const Vec3<S> dv = s.state.v[i] - s.vPre[i];
  if (dv.isZero(0) || s.state.invMass[i] == S(0)) return;
  for (const Index* j = s.neighbours.begin(i); j != s.neighbours.end(i); ++j) {
    if (!s.contacts.live(*j)) continue;
    const auto& slots = s.contacts.slots[*j];
    for (int k = 0; k < s.contacts.slotCount[*j]; ++k) {
      if (slots[k].body < 0) continue;
      const S m = S(1) / s.state.invMass[i];
      addExchange(s, slots[k], *j, (-(m / s.h) * dv).template cast<double>(), i, m, out);
      return;
    }
  }
}

/// The force on the particle from vertex i's contacts, by the estimator, before it is passed to slot k's body.
/// A vertex's velocity change is one vector however many slots made it, so when all its slots belong to one
/// body (`oneBody`) that body gets the whole of it; a vertex between two bodies (or a body and a fixed solid)
/// passes each body the normal part along its own slot, of which the caller keeps the slot's share (ownShare).
template <Scalar S>
Vec3<S> pushOnBody(const SubstepView<S>& s, Index i, int k, bool oneBody, const Vec3<S>& otherForce,
                   const Vec3<S>& energyForce) {
  const Vec3<S>& n = s.contacts.slots[i][k].normal;
  const S m = S(1) / s.state.invMass[i];
  switch (s.estimator) {
    case ContactForce::SubForce: {
      const S fn = otherForce.dot(n);
      return fn < S(0) ? Vec3<S>(fn * n) : Vec3<S>::Zero();
    }
    case ContactForce::Energy:
      return oneBody ? Vec3<S>(-energyForce) : Vec3<S>(-energyForce.dot(n) * n);
    case ContactForce::Impulse: {
      const Vec3<S> dv = s.state.v[i] - s.vPre[i];  // what the contacts did
      const S dvn = dv.dot(n);
      Vec3<S> impulse = (dvn + unresolvedOverlap(s.contacts, s.state.x[i], i, k) / s.h) * n;
      if (oneBody) impulse += dv - dvn * n;  // the tangential (friction) change
      return -(m / s.h) * impulse;
    }
  }
  return Vec3<S>::Zero();
}

/// The energy estimate's force on vertex i: the work that changed its kinetic energy over its displacement,
/// (dE - F_other . d) / |d|^2 d. Over a tiny displacement the quotient is unbounded (a particle held still under
/// a body launched it at 400 m/s); the contact's force cannot exceed what the momentum balance allows,
/// |m (v - v_start) / h - F_other|, so its magnitude is capped there, its direction kept along d.
template <Scalar S> Vec3<S> energyForceOn(const SubstepView<S>& s, Index i, S m, const Vec3<S>& otherForce) {
  const Vec3<S>& v = s.state.v[i];
  const Vec3<S> d = s.state.x[i] - s.start[i];
  const S d2 = d.squaredNorm();
  const S work = S(0.5) * m * (v.squaredNorm() - s.vStart[i].squaredNorm()) - otherForce.dot(d);
  Vec3<S> f = Vec3<S>::Zero();
  if (d2 > S(constants::kEnergyMinDisplacement2)) f = (work / d2) * d;
  const S cap = (m * (v - s.vStart[i]) / s.h - otherForce).norm();
  const S size = f.norm();
  if (size > cap) f *= cap / size;
  return f;
}

/// Every contact vertex's pushes on the coupled bodies (see the file's comment), into `out`: its sums are reset
/// to one per body and `exchanged` cleared first.
template <Scalar S> void gatherContactForces(const SubstepView<S>& s, Gathered& out) {
  out.sums.assign(s.bodies.size(), BodySums{});
  out.exchanged.clear();
  out.spacers.clear();
  const Index n = Index(s.state.x.size());
  for (Index i = 0; i < n; ++i) {
    if (!s.contacts.live(i)) {
      if (s.propagated) gatherPropagatedImpulse(s, i, out);
      continue;
    }
    const int count = s.contacts.slotCount[i];
    const auto& slots = s.contacts.slots[i];
    bool oneBody = true;
    int top = 0;  // the slot that corrected the vertex most
    for (int k = 1; k < count; ++k) {
      oneBody = oneBody && slots[k].body == slots[0].body;
      if (slots[k].correction > slots[top].correction) top = k;
    }
    const S m = S(1) / s.state.invMass[i];
    const Vec3<S> otherForce = m * (s.vPre[i] - s.vStart[i]) / s.h;  // constraints and gravity this substep
    const Vec3<S> energyForce =
        s.estimator == ContactForce::Energy ? energyForceOn(s, i, m, otherForce) : Vec3<S>(Vec3<S>::Zero());
    for (int k = 0; k < count; ++k) {
      const ContactSlot<S>& c = slots[k];
      if (c.body < 0) continue;
      if (count > 1 && !oneBody && pinchSupport(s, i, k, out)) continue;
      if (oneBody && k != top) continue;
      const Vec3<S> onBody = pushOnBody(s, i, k, oneBody, otherForce, energyForce);
      if (oneBody) {
        addExchange(s, c, i, onBody.template cast<double>(), i, m, out);
        continue;
      }
      const S weight = ownShare(s.contacts, i, k, Vec3<S>(s.state.v[i] - s.vPre[i]));
      if (weight > S(0)) addSplitExchange(s, c, i, k, (weight * onBody).template cast<double>(), weight, m, out);
    }
  }
}

}  // namespace drape::coupling
