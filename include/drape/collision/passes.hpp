#pragma once
// The contact stage of a substep (docs/design.md §4, §13, §16): every solid's vertex pass, then its face pass
// (a curved solid's, with faces on), through the broad phase's bins for bounded solids; where surfaces meet,
// the placement outside all of a vertex's contact planes and the settle passes. It owns the contact records,
// the bins and the bookkeeping of how far the vertices have moved since they were binned. Called by every
// thread of the solver's team: the vertex passes share their vertices (teamFor), a long face pass runs as a wave
// (FaceWave: each thread follows the one before it, to the one thread's result), short ones and the bins run on
// one thread.

#include <drape/collision/broadphase.hpp>
#include <drape/collision/response.hpp>
#include <drape/collision/wave.hpp>
#include <drape/detail/parallel.hpp>
#include <drape/kernel_constants.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <tuple>
#include <vector>

namespace drape {

/// What the passes read of the cloth and the settings in one substep.
template <Scalar S> struct PassInputs {
  Vec3<S>* x;                  ///< positions, moved out of the solids
  const S* invMass;
  const Vec3<S>* settleStart;  ///< where a pinched vertex's least-squares placement starts (the prediction)
  const std::vector<std::array<Index, 3>>& triangles;
  S thickness;
  int pgdIterations;
  bool culling;
  bool exactGridSearch;
  /// Face contacts on smooth fields record each corner's own normal (Settings::keepAngularMomentum).
  bool ownNormals = false;
  /// The velocities after the update, whose moment about a smooth solid's centre of curvature the contacts keep
  /// (Settings::keepAngularMomentum, after the solve; keepTurnAbout). Null: left alone.
  Vec3<S>* keepTurn = nullptr;
  /// Continuous contact (docs/design.md §18): the start positions and the substep (sweep.start null: off), and
  /// the farthest any vertex travelled this substep.
  SweepInputs<S> sweep = {};
  S travel = 0;
};

template <Scalar S> class ContactPasses {
  /// One solid's kept clearances (clearancesFor), with the bins' reset, the solids' version and the thickness
  /// they hold for.
  struct Clearances {
    std::vector<S> faces;
    std::uint64_t resets = 0, solidsVersion = 0;
    S thickness = 0;
  };

 public:
  /// Sizes the records and the bins for a cloth of `vertexCount` vertices; cells of `cell` metres.
  void setTopology(const std::vector<std::array<Index, 3>>& triangles, Index vertexCount, S cell) {
    contacts_.resize(vertexCount);
    held_.assign(triangles.size(), HeldPoint<S>{});
    bins_.setTopology(triangles, vertexCount, cell);
    every_.resize(std::max(std::size_t(vertexCount), triangles.size()));
    for (std::size_t k = 0; k < every_.size(); ++k) every_[k] = Index(k);
    movedStamps_.assign(std::size_t(vertexCount), 0u);
    gaps_.assign(std::size_t(vertexCount), S(0));
    wave_.forget();
    facePass_ = 0;
  }

  /// Before a substep: whether contacts with bounded solids go through the bins, and whether to keep the
  /// records' lines of action (a scene with coupled bodies).
  void prepare(bool useBins, bool keepLines) {
    useBins_ = useBins;
    binsFresh_ = binsFresh_ && useBins_;  // bins not kept up in a substep without them are built anew
    moveBound_ = 0;
    contacts_.keepLines(keepLines);
  }
  /// The positions were replaced: the bins no longer know where the vertices are.
  void positionsReplaced() { binsFresh_ = false; }
  /// A solid was added or replaced: the faces' kept clearances may belong to another solid now.
  void solidsChanged() {
    ++solidsVersion_;
    std::fill(held_.begin(), held_.end(), HeldPoint<S>{});  // a place may now hold another solid
  }
  /// The faces' held deepest points, which an undone step puts back (docs/design.md §3, "Ties between deepest
  /// points").
  const std::vector<HeldPoint<S>>& heldPoints() const { return held_; }
  void restoreHeldPoints(const std::vector<HeldPoint<S>>& held) { held_ = held; }
  /// Whether the velocity update should measure how far the vertices got from where the bins took them.
  bool measuresDrift() const { return useBins_ && binsFresh_; }
  const Vec3<S>* binned() const { return bins_.binned(); }
  /// The velocity update's largest squared distance from the binned positions, on each thread.
  void addUpdateDrift(S farSquared) { teamMax(moveBound_, std::sqrt(farSquared)); }

  /// All contacts of a substep with the solids of `compiled` (a tuple of vectors of CompiledSolid): the
  /// projections, then, where surfaces meet (a crease, a box corner, a cloth pinched between a ball and the
  /// floor) and pushing a vertex out of one can put it back into another, such vertices go outside all their
  /// contact planes at once (`reconcile`) and, where several solids exist, the vertex passes repeat on the true
  /// fields until no vertex moves by more than kSettleSlack of the thickness. `rebuild` builds the bins anew
  /// (contacts inside the solve come before the update has measured the solve's moves).
  template <class Solids>
  void projectAll(const Solids& compiled, const PassInputs<S>& in, bool faces, bool reconcile, Index solidCount,
                  bool rebuild) {
    DRAPE_OMP(single)
    {
      // The in-solve method's passes rebuild the bins each time, so clearances would never outlive a pass.
      keepClearances_ = !rebuild;
      contacts_.begin();
      if (useBins_) {
        bins_.noteDrift(moveBound_);  // the prediction's and the solve's moves (updateVelocities)
        if (!binsFresh_ || rebuild) {
          ++resets_;  // the binned positions no longer bound where the vertices have been: no clearance holds
          bins_.build(in.x, in.triangles);
        } else if (bins_.stale()) {
          rebuildBins(in.x, in.triangles);
        }
        binsFresh_ = true;
      }
      moveBound_ = 0;
    }
    withFlags([&](auto withFaces, auto cull) { project<withFaces(), withFaces() && cull(), true>(compiled, in); },
              faces, in.culling);
    if (!reconcile) return;  // a lone plane gives each vertex one surface: nothing to reconcile
    settle(compiled, in);
    if (solidCount < 2) return;
    for (int pass = 0; pass < constants::kSettlePasses; ++pass) {
      // Every thread reads the count here, between two barriers (the one ending the loop above and the one
      // ending the vertex pass below), so all take the same branch.
      const auto before = stats_.vertexContacts;
      DRAPE_OMP(barrier)
      project<false, false, false>(compiled, in, S(constants::kSettleSlack) * in.thickness);
      if (stats_.vertexContacts == before) break;
      settle(compiled, in);
    }
  }

  const ContactBuffer<S>& contacts() const { return contacts_; }
  ContactBuffer<S>& contacts() { return contacts_; }
  const CollisionStats& stats() const { return stats_; }
  void resetStats() { stats_ = {}; }
  /// The friction guard's count (the solver runs it after the response, in a single thread).
  void addFrictionGuarded(std::int64_t faces) { stats_.frictionGuarded += faces; }

 private:
  /// Projects every vertex, then (when kFaces and the field is not linear) every face, out of each solid in
  /// turn, recording the contacts. On a linear field a face is deepest at a vertex, which the vertex pass has
  /// already handled. Vertices already within `slack` of the thickness are left where they are. With the bins
  /// on, a bounded solid visits only the vertices and faces they find near its box. With kMaySweep, continuous
  /// contact searches the paths of the substep where they may be long enough to matter (sweepReach).
  template <bool kFaces, bool kCull, bool kMaySweep, class Solids>
  void project(const Solids& compiled, const PassInputs<S>& in, S slack = S(0)) {
    const Index n = Index(contacts_.slotCount.size());
    Index first = 0;  // each solid's place among all the solids, in the order they are visited
    std::apply(
        [&](const auto&... lists) {
          ((projectList<kFaces, kCull, kMaySweep>(lists, in, slack, n, first), first += Index(lists.size())), ...);
        },
        compiled);
  }

  /// How far a vertex's path this substep can reach relative to a solid: its own travel and the solid's motion
  /// where the vertex may be (the box grown by the thickness and the travel). 0 where nothing is swept: continuous
  /// contact off, or a linear field (a half-space has no far side to reach).
  template <class Solid> static S sweepReach(const Solid& solid, const PassInputs<S>& in) {
    if (in.sweep.start == nullptr || std::decay_t<decltype(solid.sdf)>::kLinear) return S(0);
    const SolidMotion<S>& m = solid.motion;
    const S around = (solid.boxHigh - m.centre).cwiseAbs().cwiseMax((solid.boxLow - m.centre).cwiseAbs()).norm() +
                     in.thickness + S(2) * in.travel;
    return in.travel + in.sweep.h * (m.linearVelocity.norm() + m.angularVelocity.norm() * around);
  }

  template <bool kFaces, bool kCull, bool kMaySweep, class List>
  void projectList(const List& list, const PassInputs<S>& in, S slack, Index n, Index first) {
    for (std::size_t k = 0; k < list.size(); ++k) {
      const auto& solid = list[k];
      const Index place = first + Index(k);
      if constexpr (kMaySweep) {
        const S reach = sweepReach(solid, in);
        if (reach * reach > in.sweep.gate2) {
          projectSolid<kFaces, kCull, true>(solid, in, slack, n, reach, place);
          continue;
        }
      }
      projectSolid<kFaces, kCull, false>(solid, in, slack, n, S(0), place);
    }
  }

  /// The faces' kept clearances (KeptClearance) for the solid at `place`, where they can be kept: a solid that
  /// does not move (no velocity, not a coupled body: its compiled field is the same every substep while the local
  /// origin stays, and the origin moving rebuilds the bins) and that visits every face. Cleared when the bins are
  /// rebuilt, a solid is added or replaced or the thickness changes. Null elsewhere. Called by one thread.
  template <class Solid> Clearances* clearancesFor(const Solid& solid, Index place, const PassInputs<S>& in) {
    const SolidMotion<S>& m = solid.motion;
    if (!keepClearances_ || m.body >= 0 || !m.linearVelocity.isZero(0) || !m.angularVelocity.isZero(0))
      return nullptr;
    if (clearances_.size() <= std::size_t(place)) clearances_.resize(std::size_t(place) + 1);
    Clearances& c = clearances_[std::size_t(place)];
    const std::size_t faces = in.triangles.size();
    if (c.resets != resets_ || c.solidsVersion != solidsVersion_ || c.thickness != in.thickness ||
        c.faces.size() != faces) {
      c.faces.assign(faces, -std::numeric_limits<S>::infinity());
      c.resets = resets_;
      c.solidsVersion = solidsVersion_;
      c.thickness = in.thickness;
    }
    return &c;
  }

  /// One solid's passes; with kSweep, the broad phase's queries grow by `reach`, the farthest a path can come
  /// from where it ends. `place`: the solid's place among all the solids.
  template <bool kFaces, bool kCull, bool kSweep, class Solid>
  void projectSolid(const Solid& solid, const PassInputs<S>& in, S slack, Index n, S reach, Index place) {
    Vec3<S>* x = in.x;
    const S thickness = in.thickness;
    using Field = std::decay_t<decltype(solid.sdf)>;
    constexpr bool kFacePass = kFaces && !Field::kLinear;
    // Where the face pass answers every vertex within the thickness (a ball's), the vertex pass would only repeat
    // that work. Kept where paths are swept: the vertex pass sweeps each vertex's own path.
    constexpr bool kVertexPass = !(kFacePass && !kSweep && kFacesAnswerVertices<Field>);
    if (useBins_ && solid.bounded) {
      DRAPE_OMP(single)
      {
        if (bins_.stale()) rebuildBins(x, in.triangles);
        // A solid whose box holds most of the cloth (a ball it is draped over) visits every vertex and face, each
        // face behind its box check: the bins' lists would cost more than they save. Same contacts either way.
        whole_ = 2 * bins_.countNear(solid.boxLow, solid.boxHigh, thickness + reach) >= n;
        if (!whole_) bins_.vertices(x, solid.boxLow, solid.boxHigh, thickness + reach, nearVertices_);
        kept_ = kFacePass && kCull && whole_ && !kSweep ? clearancesFor(solid, place, in) : nullptr;
      }
      const std::vector<Index>& near = whole_ ? every_ : nearVertices_;
      if constexpr (kVertexPass)
        projectVertices<kSweep>(solid, in, ItemList{near.data()}, whole_ ? n : Index(nearVertices_.size()),
                                bins_.binned(), slack);
      DRAPE_OMP(single)
      {
        bins_.noteDrift(moveBound_);
        moveBound_ = 0;
        if constexpr (kFacePass) {
          if (!whole_) bins_.faces(x, solid.boxLow, solid.boxHigh, thickness + reach, nearFaces_);
          skip_ = {};
          if (kept_ != nullptr) {
            if (++facePass_ == 0) {  // wrapped: no stamp may look like this pass's
              facePass_ = 1;
              std::fill(movedStamps_.begin(), movedStamps_.end(), 0u);
            }
            skip_ = {kept_->faces.data(), gaps_.data(), movedStamps_.data(), facePass_};
          }
        }
      }
      if (kFacePass && kept_ != nullptr) {
        // How far each vertex is from its binned position: a face whose corners all stay within its kept clearance
        // is passed over, where the bins' drift, the farthest any vertex has gone, would hold back most of them.
        const Vec3<S>* binned = bins_.binned();
        S* gaps = gaps_.data();
        teamFor(n, [&](Index b, Index e) {
          for (Index i = b; i < e; ++i) gaps[i] = (x[i] - binned[i]).squaredNorm();
        });
      }
      if constexpr (kFacePass) {
        const ItemList faces{whole_ ? every_.data() : nearFaces_.data()};
        const Index count = whole_ ? Index(in.triangles.size()) : Index(nearFaces_.size());
        const S moved = projectFaces<kCull, true, kSweep>(solid, in, faces, count, n, bins_.binned(), place, skip_);
        DRAPE_OMP(single)
        bins_.noteDrift(moved);
      }
    } else {
      // Without the bins, the binned positions are the positions: nothing drifts.
      const Vec3<S>* binned = useBins_ ? bins_.binned() : x;
      if constexpr (kVertexPass) projectVertices<kSweep>(solid, in, AllItems{}, n, binned, slack);
      if constexpr (kFacePass) {
        const S moved = projectFaces<kCull, false, kSweep>(solid, in, AllItems{}, Index(in.triangles.size()), n,
                                                           binned, place, KeptClearance<S>{});
        if (useBins_) {
          DRAPE_OMP(single)
          bins_.noteDrift(moved);
        }
      }
      if (useBins_) {
        DRAPE_OMP(single)
        {
          bins_.noteDrift(moveBound_);
          moveBound_ = 0;
        }
      }
    }
  }

  /// Bins the vertices where they are now, the bins having drifted too far. A kept clearance held against the
  /// binned positions; against the new ones it holds less each face's farthest corner's move between the two, so
  /// the clearances survive the build (docs/design.md §13). Called by one thread.
  void rebuildBins(const Vec3<S>* x, const std::vector<std::array<Index, 3>>& triangles) {
    bool any = false;
    for (const Clearances& c : clearances_) any |= c.resets == resets_ && !c.faces.empty();
    if (any) {
      const Vec3<S>* binned = bins_.binned();
      for (std::size_t i = 0; i < gaps_.size(); ++i) gaps_[i] = (x[i] - binned[i]).squaredNorm();
      for (Clearances& c : clearances_) {
        if (c.resets != resets_ || c.faces.size() != triangles.size()) continue;
        for (std::size_t f = 0; f < triangles.size(); ++f) {
          S& clear = c.faces[f];
          if (!(clear > S(0))) continue;  // none, or a face in contact at its last test (KeptClearance::kTouched)
          const auto& t = triangles[f];
          // Less four roundings of the clearance: the root's and the difference's, so that a clearance carried
          // over many builds never grows past what it holds.
          const S moved =
              rootOf(std::max({gaps_[std::size_t(t[0])], gaps_[std::size_t(t[1])], gaps_[std::size_t(t[2])]}));
          const S left = clear - moved - S(4) * std::numeric_limits<S>::epsilon() * clear;
          clear = left > S(0) ? left : -std::numeric_limits<S>::infinity();
        }
      }
    }
    bins_.build(x, triangles);
  }

  static const Index* items(ItemList ids) { return ids.items; }
  static const Index* items(AllItems) { return nullptr; }

  /// One solid's face pass over ids[0, count), called by every thread of the team: shared as a wave (FaceWave)
  /// where the list is long enough, else on one thread. The result is the one thread's, bit for bit, on any
  /// number of threads. Returns the largest distance of a moved vertex from `binned`, to every thread.
  template <bool kCull, bool kBoxed, bool kSweep, class Solid, class Ids>
  S projectFaces(const Solid& solid, const PassInputs<S>& in, Ids ids, Index count, Index n, const Vec3<S>* binned,
                 Index place, KeptClearance<S> skip) {
    const HeldPoints<S> held{held_.data(), std::int32_t(place)};
    DRAPE_OMP(single)
    {
      waved_ = wave_.ready(count, in.triangles, n, teamThreads());
      faceMoved_ = 0;
      if (!waved_)
        faceMoved_ = projectFaceContacts<kCull, kBoxed, kSweep>(
            solid, in.thickness, in.pgdIterations, in.triangles, ids, count, in.x, in.invMass, contacts_, stats_,
            binned, in.exactGridSearch, in.sweep, in.ownNormals, in.keepTurn, skip, held);
    }
    if (waved_) {
      CollisionStats mine;
      const S moved = projectFaceContacts<kCull, kBoxed, kSweep>(
          solid, in.thickness, in.pgdIterations, in.triangles, ids, count, in.x, in.invMass, contacts_, mine, binned,
          in.exactGridSearch, in.sweep, in.ownNormals, in.keepTurn, skip, held, wave_.gate(teamThread(), items(ids)));
      DRAPE_OMP(critical(drape_face_stats))
      stats_ += mine;
      teamMax(faceMoved_, moved);
      DRAPE_OMP(barrier)
    }
    return faceMoved_;
  }

  /// One solid's vertex pass over ids[0, count), shared by the team. The counts and the move bound are added
  /// once per thread, the largest move kept as the largest over the threads (so the bins, and the kept clearances
  /// that read their drift, do the same on any number of threads); the barrier after them lets every thread read
  /// the totals.
  template <bool kSweep, class Solid, class Ids>
  void projectVertices(const Solid& solid, const PassInputs<S>& in, Ids ids, Index count, const Vec3<S>* binned,
                       S slack) {
    VertexPassShare<S> share;
    // Shares of whole fours: a plane's test takes aligned fours (projectVertexContactsAs), the same ones on any
    // number of threads.
    teamForNoWait((count + 3) / 4, [&](Index b, Index e) {
      share = projectVertexContacts<kSweep>(4 * b, std::min(4 * e, count), solid, in.thickness, in.x, in.invMass,
                                            ids, contacts_, binned, slack, in.sweep, in.keepTurn);
    });
    teamAdd(stats_.vertexContacts, share.found);
    teamAdd(stats_.sdfEvaluations, share.evaluated);
    if constexpr (kSweep) {
      teamAdd(stats_.vertexSweeps, share.swept);
      teamAdd(stats_.sweepContacts, share.sweptFound);
    }
    teamMax(moveBound_, share.moved);
    DRAPE_OMP(barrier)
  }

  /// The placement outside each vertex's contact planes, its exact points tested against every solid's field.
  template <class Solids> void settle(const Solids& compiled, const PassInputs<S>& in) {
    const Vec3<S>* binned = useBins_ ? bins_.binned() : in.x;
    const SettleFields<S, Solids> fields{compiled, in.thickness};
    S moved = 0;
    teamForNoWait(Index(contacts_.size()), [&](Index b, Index e) {
      moved = projectOntoContactPlanes(b, e, contacts_, in.x, in.settleStart, binned, fields);
    });
    teamMax(moveBound_, moved);
    DRAPE_OMP(barrier)
    if (useBins_) {
      DRAPE_OMP(single)
      {
        bins_.noteDrift(moveBound_);
        moveBound_ = 0;
      }
    }
  }

  ContactBuffer<S> contacts_;
  CollisionStats stats_;
  std::vector<Clearances> clearances_;  ///< by the solid's place among all the solids
  std::vector<HeldPoint<S>> held_;      ///< by face: where it was last deepest in a solid
  std::uint64_t solidsVersion_ = 0;
  std::uint64_t resets_ = 0;  ///< bins built where no earlier binned position bounds the vertices (clearancesFor)
  bool keepClearances_ = false;  ///< this substep's passes may keep clearances (shared by the team)
  Clearances* kept_ = nullptr;   ///< the current solid's, or null (shared by the team)
  VertexBins<S> bins_;
  std::vector<Index> nearVertices_, nearFaces_;  ///< what the bins found near the current solid
  std::vector<Index> every_;  ///< 0, 1, 2, ...: every vertex and face, for a solid that holds most of the cloth
  std::vector<std::uint32_t> movedStamps_;        ///< by vertex (KeptClearance::moved)
  std::vector<S> gaps_;                          ///< by vertex (KeptClearance::gap2)
  std::uint32_t facePass_ = 0;                   ///< face passes with kept clearances so far
  KeptClearance<S> skip_;                        ///< the current face pass's (shared by the team)
  FaceWave wave_;                                ///< the face passes' plan for a team
  bool waved_ = false;                           ///< the current face pass is shared (shared by the team)
  S faceMoved_ = 0;                              ///< its largest move (shared by the team)
  bool whole_ = false;        ///< the current solid visits every vertex and face (shared by the team)
  S moveBound_ = 0;         ///< the passes' largest distance from the binned positions (shared by the team)
  bool useBins_ = false;    ///< contacts with bounded solids go through the bins this substep
  bool binsFresh_ = false;  ///< the bins were built, and every move since is in their drift
};

}  // namespace drape
