#pragma once
// Contact response (docs/design.md §4): project vertices and faces to the thickness, split each contact vertex's
// velocity relative to the solid into a normal part (attenuated) and a tangential part (kept, Coulomb
// friction), and propagate the normal corrections to neighbouring vertices.

#include <drape/kernel_constants.hpp>
#include <drape/cloth/asset.hpp>
#include <drape/collision/pgd.hpp>
#include <drape/collision/sweep.hpp>
#include <drape/sdf/solid.hpp>

#include <drape/detail/parallel.hpp>
#include <drape/detail/simd.hpp>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <type_traits>
#include <vector>

namespace drape {

/// One solid surface a vertex touches in a substep.
template <Scalar S> struct ContactSlot {
  Vec3<S> normal;         ///< outward normal of the solid at the contact
  Vec3<S> solidVelocity;  ///< v_c at the vertex
  S correction;           ///< normal position correction along this normal this substep (m)
  S staticFriction, dynamicFriction;
  S offset;               ///< the surface as a half-space: normal . x >= offset where the vertex was placed
  std::int32_t body;      ///< the coupled body the surface belongs to, -1 for none (SolidMotion::body)
};

/// Where the force a contact slot passes back to a coupled body acts, relative to the body's centre (the solid's
/// frame origin), averaged over the slot's contacts weighted by their corrections. Each contact is found at a
/// point p the thickness out of the surface along its normal n: the vertex, or for a face contact the face's
/// deepest point. `push` is the mean of n and `moment` the mean of (p - centre) x n: the slot's normal push is
/// spread over its contacts' own lines, so force and moment belong together. On a ball every such line passes
/// through the centre and the push has no moment. A lever taken from the vertex's final position (moved since by
/// other contacts, a face's other corners, the response), or from one of the several contacts (the last face, in
/// index order: always the same side), would twist it. Kept only for the slots of coupled bodies, and only in a
/// scene that has them (ContactBuffer::lines).
template <Scalar S> struct ContactLine {
  Vec3<S> push;
  Vec3<S> moment;
};

/// Per-vertex contact records of one substep. A vertex may touch up to kSlots differently-facing surfaces
/// (two planes of a crease, the faces of a box corner), each answered along its own normal: answering only
/// one leaves the velocity into the others in place, which then grows without bound. Contacts whose normals
/// agree within kMergeCos share a slot. A record is live when stamp[i] == current, so nothing is cleared per
/// substep, and a vertex's record is written only by the work item that owns the vertex.
template <Scalar S> struct ContactBuffer {
  static constexpr int kSlots = constants::kContactSlots;
  static constexpr S kMergeCos = S(constants::kMergeCos);

  std::vector<std::uint32_t> stamp;
  std::uint32_t current = 0;
  std::vector<std::array<ContactSlot<S>, kSlots>> slots;
  std::vector<std::uint8_t> slotCount;
  /// == current when a surface of vertex i found every slot taken by other directions (recordMore): it joined the
  /// closest, or two closer slots merged to make room. The slots then misstate a surface, and the planes alone must
  /// not place the vertex.
  std::vector<std::uint32_t> overflow;
  std::vector<S> normalDv;  ///< normal velocity change the response made (m/s), the source of propagation
  /// Per vertex and slot, the lines of a coupled body's contacts (ContactLine): sized by keepLines, written only
  /// by record<true>, read only for slots whose body is >= 0.
  std::vector<std::array<ContactLine<S>, kSlots>> lines;

  void resize(Index n) {
    stamp.assign(n, 0);
    current = 0;
    slots.resize(n);
    slotCount.assign(n, 0);
    overflow.assign(n, 0);
    normalDv.resize(n);
  }
  void begin() {
    if (++current == 0) {  // wrapped after 2^32 substeps: restart the stamps
      std::fill(stamp.begin(), stamp.end(), 0);
      std::fill(overflow.begin(), overflow.end(), 0);
      current = 1;
    }
  }
  /// Keeps the lines of coupled bodies' contacts (a scene with coupled bodies), or frees them.
  void keepLines(bool keep) {
    if (keep && lines.size() != stamp.size()) lines.resize(stamp.size());
    if (!keep && !lines.empty()) std::vector<std::array<ContactLine<S>, kSlots>>().swap(lines);
  }
  bool live(Index i) const { return stamp[i] == current; }
  /// Whether vertex i already holds, this substep, a contact whose normal is further than the merge angle from n.
  bool holdsOtherDirection(Index i, const Vec3<S>& n) const {
    if (!live(i)) return false;
    for (int k = 0; k < slotCount[i]; ++k)
      if (slots[i][k].normal.dot(n) < kMergeCos) return true;
    return false;
  }
  Index size() const { return Index(stamp.size()); }
  /// The vertices in contact this substep, in ascending order (allocates: for tests and tools).
  std::vector<Index> liveVertices() const {
    std::vector<Index> out;
    for (Index i = 0; i < size(); ++i)
      if (live(i)) out.push_back(i);
    return out;
  }
  /// The vertex's contact normal: the slots' normals weighted by their corrections (the first slot's if none).
  Vec3<S> normal(Index i) const {
    Vec3<S> sum = Vec3<S>::Zero();
    for (int k = 0; k < slotCount[i]; ++k) sum += slots[i][k].correction * slots[i][k].normal;
    const S len = sum.norm();
    return len > S(0) ? Vec3<S>(sum / len) : slots[i][0].normal;
  }
  const Vec3<S>& solidVelocity(Index i) const { return slots[i][0].solidVelocity; }
  /// Total normal position correction this substep (m).
  S correction(Index i) const {
    S sum = 0;
    for (int k = 0; k < slotCount[i]; ++k) sum += slots[i][k].correction;
    return sum;
  }

  /// Records that vertex i was placed at x, dn along n, out of a solid moving with m; `anchor` is the placed point
  /// the contact was found at (x itself for a vertex contact, the face's deepest point for a face contact, the
  /// point where a swept path met the solid) and vc the solid's velocity the contact answers to (the slot's
  /// solidVelocity: m.velocityAt(x) for a vertex contact, m.contactVelocityAt(x, n, anchor) for the others, which
  /// a vertex contact need not pay for). kBody: the solid is a coupled body (m.body >= 0), whose slots
  /// keep a ContactLine; other solids' contacts write none, so a scene without bodies does not pay for them. A
  /// vertex's first contact of the substep takes the inlined path; further ones merge in recordMore, but for
  /// kRepeats (the face pass, whose corners are mostly recorded already) the same surface seen again by a
  /// one-slot vertex, updated inline as recordMore would.
  template <bool kBody, bool kRepeats = false>
  DRAPE_ALWAYS_INLINE void record(Index i, const Vec3<S>& x, const Vec3<S>& n, S dn, const SolidMotion<S>& m,
                                  const Vec3<S>& anchor, const Vec3<S>& vc) {
    if (stamp[i] != current) {
      stamp[i] = current;
      slotCount[i] = 1;
      slots[i][0] = {n, vc, dn, m.staticFriction, m.dynamicFriction, n.dot(x), m.body};
      if constexpr (kBody) lines[i][0] = {n, (anchor - m.centre).cross(n)};
      return;
    }
    if constexpr (kRepeats && !kBody) {
      // recordMore's answer for its one slot, without the call (docs/design.md §3, "Speed").
      if (slotCount[i] == 1 && slots[i][0].normal.dot(n) >= kMergeCos) {
        seenAgain(slots[i][0], x, n, dn, m, vc);
        return;
      }
    }
    recordMore<kBody>(i, x, n, dn, m, anchor, vc);
  }

 private:
  /// The same surface seen again: the slot takes its latest normal, placement and velocity, and adds the push.
  DRAPE_ALWAYS_INLINE static void seenAgain(ContactSlot<S>& slot, const Vec3<S>& x, const Vec3<S>& n, S dn,
                                            const SolidMotion<S>& m, const Vec3<S>& vc) {
    slot.normal = n;
    slot.offset = n.dot(x);
    slot.body = m.body;
    slot.solidVelocity = vc;
    slot.correction += dn;
  }
  template <bool kBody>
  void recordMore(Index i, const Vec3<S>& x, const Vec3<S>& n, S dn, const SolidMotion<S>& m, const Vec3<S>& anchor,
                  const Vec3<S>& vc) {
    auto& own = slots[i];
    int best = -1;
    S bestCos = kMergeCos;
    for (int k = 0; k < slotCount[i]; ++k) {
      const S c = own[k].normal.dot(n);
      if (c >= bestCos) best = k, bestCos = c;
    }
    if (best < 0 && slotCount[i] < kSlots) {
      if constexpr (kBody) lines[i][slotCount[i]] = {n, (anchor - m.centre).cross(n)};
      own[slotCount[i]++] = {n, vc, dn, m.staticFriction, m.dynamicFriction, n.dot(x), m.body};
      return;
    }
    if (best < 0) {  // all slots taken by other directions: join the closest, or make room (below)
      overflow[i] = current;
      bestCos = -2;
      for (int k = 0; k < kSlots; ++k)
        if (own[k].normal.dot(n) > bestCos) best = k, bestCos = own[k].normal.dot(n);
      // A direction facing away from every recorded one (the floor under three faces of a body's corner: the
      // vertex is pinched) is the one the slots know least: joined to a face of the body, nothing would keep the
      // vertex out of the floor. Nor should one solid's contact join another's when two slots hold faces of one
      // body. The two closest such recorded directions then share a slot, and it takes the other. Any other
      // direction joins its closest: on one solid the first three seen (on a ball hit fast, the vertex's own
      // normal among them) say most about where the vertex may go; merging the closest pair there instead let a
      // cloth thrown at a ball at 50 m/s 3 cm deeper into it.
      int keep = -1, give = -1;
      S pairCos = bestCos;
      for (int j = 0; j < kSlots; ++j)
        for (int k = j + 1; k < kSlots; ++k) {
          const bool oneBody = own[j].body >= 0 && own[j].body == own[k].body && own[j].body != m.body;
          const S c = own[j].normal.dot(own[k].normal);
          if ((bestCos < S(0) || oneBody) && c > pairCos) keep = j, give = k, pairCos = c;
        }
      if (keep >= 0) {
        mergeSlot<kBody>(i, keep, give, x);
        if constexpr (kBody) lines[i][give] = {n, (anchor - m.centre).cross(n)};
        own[give] = {n, vc, dn, m.staticFriction, m.dynamicFriction, n.dot(x), m.body};
        return;
      }
    }
    if constexpr (kBody) {
      ContactLine<S>& line = lines[i][best];
      const S total = own[best].correction + dn;
      if (own[best].body != m.body) {
        if (bestCos >= kMergeCos) line = {n, (anchor - m.centre).cross(n)};  // the slot becomes this body's
      } else if (total > S(0)) {  // this contact's share of the slot's push and moment
        const S share = dn / total;
        line.push += share * (n - line.push);
        line.moment += share * ((anchor - m.centre).cross(n) - line.moment);
      }
    }
    if (bestCos >= kMergeCos) {
      seenAgain(own[best], x, n, dn, m, vc);
      return;
    }
    // Another direction joins the slot, whose normal stays.
    own[best].offset = std::max(own[best].offset, own[best].normal.dot(x));
    own[best].solidVelocity = vc;
    own[best].correction += dn;
  }

  /// Slot `give` of vertex i joins slot `keep`, as a contact of another direction joins a slot (recordMore): the
  /// kept normal, friction and solid stay, the half-space moves out to the vertex at x if it is beyond it, the
  /// corrections add up. A body's kernels (kBody) also merge the lines where both slots are the same body's,
  /// weighted by their corrections; other solids' kernels keep the kept slot's line as it is (the GPU's load no
  /// lines there).
  template <bool kBody> void mergeSlot(Index i, int keep, int give, const Vec3<S>& x) {
    ContactSlot<S>& a = slots[i][keep];
    const ContactSlot<S>& b = slots[i][give];
    const S total = a.correction + b.correction;
    if constexpr (kBody) {
      if (a.body == b.body && total > S(0)) {
        ContactLine<S>& la = lines[i][keep];
        const ContactLine<S>& lb = lines[i][give];
        const S share = b.correction / total;
        la.push += share * (lb.push - la.push);
        la.moment += share * (lb.moment - la.moment);
      }
    }
    a.offset = std::max(a.offset, a.normal.dot(x));
    a.correction = total;
  }
};

/// Counters of the last substep's collision work, for tests and benches.
struct CollisionStats {
  std::int64_t facesTested = 0;   ///< face-solid pairs considered
  std::int64_t facesCulled = 0;   ///< of those, rejected by their bounding boxes or spheres
  std::int64_t facesKeptClear = 0;  ///< of those, passed over on a clearance kept from an earlier substep
  std::int64_t faceContacts = 0;  ///< face-solid pairs whose deepest point was within the thickness
  std::int64_t vertexContacts = 0;
  std::int64_t sdfEvaluations = 0;
  std::int64_t vertexSweeps = 0;  ///< vertex paths searched by continuous contact
  std::int64_t faceSweeps = 0;    ///< face paths searched by continuous contact
  std::int64_t sweepContacts = 0;  ///< of those paths, the ones that came within the thickness on the way
  std::int64_t frictionGuarded = 0;  ///< faces whose corners the friction guard put back (guardFriction)

  CollisionStats& operator+=(const CollisionStats& o) {
    facesTested += o.facesTested, facesCulled += o.facesCulled, facesKeptClear += o.facesKeptClear;
    faceContacts += o.faceContacts, vertexContacts += o.vertexContacts, sdfEvaluations += o.sdfEvaluations;
    vertexSweeps += o.vertexSweeps, faceSweeps += o.faceSweeps, sweepContacts += o.sweepContacts;
    frictionGuarded += o.frictionGuarded;
    return *this;
  }
};

/// What continuous contact reads (docs/design.md §18): where each vertex started the substep, the substep, and
/// the squared length below which a path relative to the solid is left to the discrete passes.
template <Scalar S> struct SweepInputs {
  const Vec3<S>* start = nullptr;
  S h = 0;
  S gate2 = 0;
  /// Where vertex i started, carried with the solid's motion over the substep (the solid's point there moves
  /// by h v_c): the start of its path in the frame of the solid as compiled, at the substep's end.
  DRAPE_ALWAYS_INLINE Vec3<S> startOf(Index i, const SolidMotion<S>& m) const {
    return start[i] + h * m.velocityAt(start[i]);
  }
};

/// What the face pass keeps between substeps for a solid that does not move and meets most of the cloth
/// (ContactPasses, docs/design.md §13 "Clearances kept between substeps"): for each face, how far its vertices may
/// move from where the bins took them before the face can come within the thickness, as its last test showed.
/// Each vertex's distance from its binned position is measured when the pass starts (`gap2`), so a face whose
/// clearance exceeds its corners' distances is still culled, and the pass passes over it without a test. A face in
/// contact stamps the corners it moved: the faces visited after it that share such a corner may now be further than
/// that from their binned positions, so they are tested and keep no clearance this time. Faces that share a corner
/// are visited in index order (on any number of threads, FaceWave), so a stamp a face reads was left by a face
/// before it. What a face reads thus depends only on the faces that share its corners, not on the order of the
/// others.
template <Scalar S> struct KeptClearance {
  /// By face index: -infinity where the face was not culled or not yet tested, kTouched where it was in contact.
  S* clear = nullptr;
  /// By vertex index: its squared distance from its binned position when the pass starts (at most the square of
  /// the bins' drift).
  const S* gap2 = nullptr;
  /// By vertex index: `pass` where a face of this pass moved the vertex (one store per moved corner). Integers, so
  /// that the stamps' stores cannot alias the positions the pass reads.
  std::uint32_t* moved = nullptr;
  std::uint32_t pass = 0;
  /// Whether a corner of face t has moved in this pass.
  DRAPE_ALWAYS_INLINE bool cornerMoved(const std::array<Index, 3>& t) const {
    return (moved[t[0]] == pass) | (moved[t[1]] == pass) | (moved[t[2]] == pass);
  }
  /// The squared distance of face t's farthest corner from its binned position.
  DRAPE_ALWAYS_INLINE S farthest2(const std::array<Index, 3>& t) const {
    return std::max({gap2[t[0]], gap2[t[1]], gap2[t[2]]});
  }
  /// Whether face f (corners t) may be passed over: its clearance exceeds its corners' distances from their binned
  /// positions and no corner of it has moved.
  DRAPE_ALWAYS_INLINE bool clearOf(Index f, const std::array<Index, 3>& t) const {
    const S c = clear[f];
    return c > S(0) && c * c > farthest2(t) && !cornerMoved(t);
  }
  /// After a face moved vertex v.
  DRAPE_ALWAYS_INLINE void stamp(Index v) const { moved[v] = pass; }
  /// A face in contact at its last test keeps this clearance, which passes over nothing: its next test goes
  /// straight to its search (queryFace's `boundsFirst`). Any other face that was not culled keeps -infinity.
  static constexpr S kTouched = -std::numeric_limits<S>::max();
  DRAPE_ALWAYS_INLINE bool touchedLast(Index f) const { return clear[f] == kTouched; }
  DRAPE_ALWAYS_INLINE void touched(Index f) const { clear[f] = kTouched; }
  /// The clearance face f keeps: what its test found less its farthest corner's distance from its binned position,
  /// or none where a corner has moved.
  DRAPE_ALWAYS_INLINE void keep(Index f, const std::array<Index, 3>& t, S found) const {
    clear[f] = cornerMoved(t) ? -std::numeric_limits<S>::infinity() : found - rootOf(farthest2(t));
  }
};

/// Where each face was deepest in a solid the last time it touched one (ContactPasses; docs/design.md §3, "Ties
/// between deepest points"): the barycentric weights and the solid's place among all the solids (-1: none). Where
/// a face lies parallel to an edge or a side of the solid, its deepest points make a segment or a patch, and the
/// search ends at whichever point its cuts reach first: the substep's rounding then moves the push, and with it
/// which corners it moves, from one end to the other. A held point as deep as the search's, within a hundredth of
/// the search's own tolerance (kHeldPointSlack), is kept instead.
template <Scalar S> struct HeldPoint {
  Vec3<S> barycentric = Vec3<S>::Zero();
  std::int32_t place = -1;
};
template <Scalar S> struct HeldPoints {
  HeldPoint<S>* points = nullptr;  ///< by face index; null: the pass holds nothing
  std::int32_t place = -1;         ///< the solid's place among all the solids
};

/// With Settings::keepAngularMomentum (docs/design.md §4): a contact moved a vertex from `before` to `after`, out
/// of a smooth solid, and leaves its velocity v to the response. Moved out along a ball's normal from radius r0 to
/// r1 with its velocity unchanged, the vertex would gain m (r1 - r0) n x v of angular momentum about the centre;
/// at few substeps that feeds back into the cloth's turn, which grows each second. So the velocity across the
/// line to the centre of curvature (relative to that centre's motion) is scaled by r0 / r1: the vertex's moment
/// about the centre stays what it was. About a capsule's side, only the velocity around the axis is. On a plane
/// nothing is scaled, as no smooth field is flat. A vertex a swept contact brings back across a thin solid's centre
/// is left alone, and no speed is raised: the scale is at most 1.
template <class Shape, Scalar S>
DRAPE_ALWAYS_INLINE void keepTurnAbout(const Sdf<Shape, S>& sdf, const SolidMotion<S>& m, const Vec3<S>& before,
                                       const Vec3<S>& after, Vec3<S>& v) {
  Vec3<S> axis;
  const Vec3<S> c = sdf.curvatureCentre(after, axis);
  Vec3<S> d0 = before - c, d1 = after - c;
  d0 -= axis.dot(d0) * axis;
  d1 -= axis.dot(d1) * axis;
  const S r1 = d1.norm();
  if (!(r1 > S(0)) || !(d0.dot(d1) > S(0))) return;
  const Vec3<S> u = d1 / r1;
  const Vec3<S> rel = v - m.velocityAt(c);
  const Vec3<S> across = rel - u.dot(rel) * u - axis.dot(rel) * axis;
  v += (std::min(d0.norm() / r1, S(1)) - S(1)) * across;
}

/// The direction a face contact pushes along, and how far (docs/design.md §3, "Feature normals"). At a sharp
/// feature of a solid (a box's edge or corner) the field's gradient at the face's deepest point, inside the
/// solid, is the normal of whichever of the feature's sides is nearer: it flips between them from substep to
/// substep and throws the face sideways off the feature, so a cloth over a ridge never rests. A rigid contact
/// of a solid's corner or edge on a flat face takes the face's normal; so does this one. A deepest point inside
/// the face is pushed along the face's normal, one on an edge of the face across that edge (the gradient
/// without its part along the edge; on a field with edges, the gradients to either side of the point mixed so,
/// which is across the solid's edge too); one at a corner of the face keeps the gradient. On a smooth field the
/// deepest point already has its gradient along the face's normal (inside) or across the edge (on it), so
/// nothing changes there: only a gradient further off than kFeatureInteriorCos or kFeatureEdgeSine is replaced.
/// The push then carries the deepest point to the thickness along the new direction, by Newton steps on
/// phi(point + s u) = thickness from the linear estimate. Returns the push's length (`depth` if unchanged), and
/// sets q.normal to its direction.
template <class Shape, Scalar S>
S featureAlignedPush(const Sdf<Shape, S>& sdf, const Vec3<S>& x0, const Vec3<S>& x1, const Vec3<S>& x2,
                     S thickness, S depth, FaceQuery<S>& q, int& evaluations) {
  int onEdge = 0, zero = -1;
  for (int k = 0; k < 3; ++k)
    if (q.barycentric[k] <= S(constants::kFeatureBarycentric)) ++onEdge, zero = k;
  Vec3<S> u;
  if (onEdge == 0) {
    u = (x1 - x0).cross(x2 - x0);
    const S length = u.norm();
    if (!(length > S(0))) return depth;
    u /= length;
    if (u.dot(q.normal) < S(0)) u = -u;
    if (u.dot(q.normal) >= S(constants::kFeatureInteriorCos)) return depth;
  } else if (onEdge == 1) {
    const Vec3<S>* corners[3] = {&x0, &x1, &x2};
    Vec3<S> e = *corners[(zero + 2) % 3] - *corners[(zero + 1) % 3];
    const S length = e.norm();
    if (!(length > S(0))) return depth;
    e /= length;
    const S along = q.normal.dot(e);
    if (std::abs(along) <= S(constants::kFeatureEdgeSine)) return depth;
    u = q.normal - along * e;
    if constexpr (!kSmoothField<Shape, S>) {
      // Where the edge crosses an edge of the solid, the deepest point sits on the kink between two of its sides,
      // and the gradient there is whichever side is nearer. The gradients a little to either side of it, g- and
      // g+, are the two sides': the mix of them with no part along the edge is the push across both edges, the
      // same whichever side the search ended on.
      const S probe = S(constants::kFeatureEdgeProbe) * length;
      Vec3<S> before, after;
      sdf(Vec3<S>(q.point - probe * e), before);
      sdf(Vec3<S>(q.point + probe * e), after);
      evaluations += 2;
      const S down = before.dot(e), up = after.dot(e);
      if (down < S(0) && up > S(0)) {
        const S a = up / (up - down);
        u = a * before + (S(1) - a) * after;
        u -= u.dot(e) * e;
      }
    }
    const S across = u.norm();
    if (!(across > S(constants::kFeatureMinRate))) return depth;
    u /= across;
  } else {
    return depth;
  }
  const S rate = u.dot(q.normal);
  if (!(rate > S(constants::kFeatureMinRate))) return depth;
  S s = depth / rate;
  for (int it = 0; it < constants::kFeatureNewtonSteps; ++it) {
    Vec3<S> g;
    const S phi = sdf(Vec3<S>(q.point + s * u), g);
    ++evaluations;
    const S grows = g.dot(u);
    if (!(grows > S(constants::kFeatureMinRate))) break;
    s += (thickness - phi) / grows;
  }
  q.normal = u;
  return std::max(s, S(0));
}

/// Which vertices (or faces) a pass visits: all of them, or a list from the broad phase. Both are inlined, so
/// the full pass pays nothing for the choice.
struct AllItems {
  Index operator[](Index k) const { return k; }
};
struct ItemList {
  const Index* items;
  Index operator[](Index k) const { return items[k]; }
};
/// The order of a face pass on one thread: every position of the list, in turn. (A team shares a pass through
/// WaveGate, collision/wave.hpp, which visits this thread's segments and waits where a face shares a corner with a
/// face of another thread's segment before it.)
struct SerialGate {
  static Index first(Index) { return 0; }
  static Index next(Index f, Index) { return f + 1; }
  static void wait(Index) {}
  static Index share(Index count) { return count; }
};

/// What one share of a vertex pass did: how many vertices it moved and how many it looked at, and the largest
/// distance of a moved vertex from where the broad phase binned it (the caller adds it to the bins' drift).
template <Scalar S> struct VertexPassShare {
  std::int64_t found = 0, evaluated = 0, swept = 0, sweptFound = 0;
  S moved = 0;
};

#if DRAPE_SSE2
namespace detail {

/// The vertex test of projectVertexContactsAs against a plane for vertices i .. i + 3, lane by lane the scalar
/// loop's operations in its order (so its bits): phi, the move out to the thickness, the plane's velocity there
/// and the move from the binned position in four lanes. A vertex's first contact of the substep is written from
/// the lanes as ContactBuffer::record writes it; a further one (and a coupled body's) goes through record.
template <bool kBody>
inline void planeVertexFour(Index i, const CompiledSolid<Plane, float>& solid, float limit, float thickness,
                            Vec3<float>* x, const float* invMass, ContactBuffer<float>& contacts,
                            const Vec3<float>* binned, VertexPassShare<float>& share, float& moved) {
  static_assert(sizeof(ContactSlot<float>) == 11 * sizeof(float), "ContactSlot<float> is written as 11 floats");
  const Sdf<Plane, float>& plane = solid.sdf;
  const __m128 nx = _mm_set1_ps(plane.normal.x()), ny = _mm_set1_ps(plane.normal.y()),
               nz = _mm_set1_ps(plane.normal.z());
  __m128 px, py, pz;
  loadVec3Four(x + i, px, py, pz);
  const __m128 phi = _mm_sub_ps(dotFour(nx, ny, nz, px, py, pz), _mm_set1_ps(plane.offset));
  // Free (inverse mass not 0) and not phi >= limit (a NaN phi counts as inside, as in the scalar loop).
  const __m128 hit = _mm_andnot_ps(_mm_cmpeq_ps(_mm_loadu_ps(invMass + i), _mm_setzero_ps()),
                                   _mm_cmpnge_ps(phi, _mm_set1_ps(limit)));
  const int lanes = _mm_movemask_ps(hit);
  if (lanes == 0) return;
  const __m128 dn = _mm_sub_ps(_mm_set1_ps(thickness), phi);
  const __m128 qx = _mm_add_ps(px, _mm_mul_ps(dn, nx)), qy = _mm_add_ps(py, _mm_mul_ps(dn, ny)),
               qz = _mm_add_ps(pz, _mm_mul_ps(dn, nz));
  storeVec3Four(x + i, select(hit, qx, px), select(hit, qy, py), select(hit, qz, pz));
  // velocityAt: linearVelocity + w x (x - centre), written out as SolidMotion::spin is.
  const SolidMotion<float>& m = solid.motion;
  const Vec3<float>& w = m.angularVelocity;
  const __m128 dx = _mm_sub_ps(qx, _mm_set1_ps(m.centre.x())), dy = _mm_sub_ps(qy, _mm_set1_ps(m.centre.y())),
               dz = _mm_sub_ps(qz, _mm_set1_ps(m.centre.z()));
  const __m128 wx = _mm_set1_ps(w.x()), wy = _mm_set1_ps(w.y()), wz = _mm_set1_ps(w.z());
  const __m128 vcx = _mm_add_ps(_mm_set1_ps(m.linearVelocity.x()), _mm_sub_ps(_mm_mul_ps(wy, dz), _mm_mul_ps(wz, dy)));
  const __m128 vcy = _mm_add_ps(_mm_set1_ps(m.linearVelocity.y()), _mm_sub_ps(_mm_mul_ps(wz, dx), _mm_mul_ps(wx, dz)));
  const __m128 vcz = _mm_add_ps(_mm_set1_ps(m.linearVelocity.z()), _mm_sub_ps(_mm_mul_ps(wx, dy), _mm_mul_ps(wy, dx)));
  // The largest squared move from the binned positions, Eigen's order (x^2 + (y^2 + z^2)); 0 in lanes not moved.
  __m128 bx, by, bz;
  loadVec3Four(binned + i, bx, by, bz);
  const __m128 ex = _mm_sub_ps(qx, bx), ey = _mm_sub_ps(qy, by), ez = _mm_sub_ps(qz, bz);
  alignas(16) float far[4];
  _mm_store_ps(far, _mm_and_ps(hit, dotFour(ex, ey, ez, ex, ey, ez)));
  // A first contact's slot as ContactBuffer::record writes it, its first eight fields transposed from the lanes.
  __m128 a0 = nx, a1 = ny, a2 = nz, a3 = vcx;
  _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
  __m128 b0 = vcy, b1 = vcz, b2 = dn, b3 = _mm_set1_ps(m.staticFriction);
  _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
  const __m128 rowA[4] = {a0, a1, a2, a3}, rowB[4] = {b0, b1, b2, b3};
  alignas(16) float offset[4], lane[7][4];
  _mm_store_ps(offset, dotFour(nx, ny, nz, qx, qy, qz));
  _mm_store_ps(lane[0], qx), _mm_store_ps(lane[1], qy), _mm_store_ps(lane[2], qz), _mm_store_ps(lane[3], dn);
  _mm_store_ps(lane[4], vcx), _mm_store_ps(lane[5], vcy), _mm_store_ps(lane[6], vcz);
  for (int l = 0; l < 4; ++l) {
    if (!(lanes & (1 << l))) continue;
    const Index j = i + l;
    if (!kBody && contacts.stamp[j] != contacts.current) {
      contacts.stamp[j] = contacts.current;
      contacts.slotCount[j] = 1;
      ContactSlot<float>& slot = contacts.slots[j][0];
      float* f = reinterpret_cast<float*>(&slot);
      _mm_storeu_ps(f, rowA[l]);
      _mm_storeu_ps(f + 4, rowB[l]);
      slot.dynamicFriction = m.dynamicFriction;
      slot.offset = offset[l];
      slot.body = m.body;
    } else {
      const Vec3<float> q(lane[0][l], lane[1][l], lane[2][l]), vc(lane[4][l], lane[5][l], lane[6][l]);
      contacts.template record<kBody>(j, q, plane.normal, lane[3][l], m, q, vc);
    }
    moved = std::max(moved, far[l]);
    ++share.found;
  }
}

}  // namespace detail
#endif

/// Moves every free vertex of ids[begin, end) closer than `thickness` (by more than `slack`) out along the
/// normal and records the contact. Without a broad phase, `binned` is the positions themselves.
///
/// With kSweep (continuous contact), a vertex whose path this substep, relative to the solid, is longer than the
/// gate is first searched along that path (sweepPoint). Where the path came within the thickness, the vertex goes
/// to the thickness beyond the field's tangent plane there: the side the path came from, whatever side of a thin
/// solid it ended on. The discrete test then runs on where that left it.
///
/// With kKeepTurn (a smooth field, Settings::keepAngularMomentum), a moved vertex's velocity in `v` keeps its moment
/// about the solid's centre of curvature (keepTurnAbout).
template <bool kBody, bool kSweep, bool kKeepTurn = false, class Shape, Scalar S, class Ids>
VertexPassShare<S> projectVertexContactsAs(Index begin, Index end, const CompiledSolid<Shape, S>& solid,
                                           S thickness, Vec3<S>* x, const S* invMass, Ids ids,
                                           ContactBuffer<S>& contacts, const Vec3<S>* binned, S slack,
                                           const SweepInputs<S>& sweep, [[maybe_unused]] Vec3<S>* v = nullptr) {
  VertexPassShare<S> share;
  S moved = 0;
  for (Index k = begin; k < end; ++k) {
#if DRAPE_SSE2
    // A plane's test four vertices at a time where the vertices are consecutive, k is a multiple of four (the
    // same vertices on any number of threads) and nothing is swept: most vertices of a cloth lying on the floor
    // or a slope are in contact, and the test and the move are the same few operations for each.
    if constexpr (std::is_same_v<S, float> && std::is_same_v<Shape, Plane> && std::is_same_v<Ids, AllItems> &&
                  !kSweep && !kKeepTurn) {
      if (k % 4 == 0 && k + 4 <= end) {
        detail::planeVertexFour<kBody>(k, solid, thickness - slack, thickness, x, invMass, contacts, binned, share,
                                       moved);
        k += 3;
        continue;
      }
    }
#endif
    const Index i = ids[k];
    if (invMass[i] == S(0)) continue;
    [[maybe_unused]] Vec3<S> start = x[i];  // kKeepTurn: where the last move started
    if constexpr (kSweep) {
      const Vec3<S> from = sweep.startOf(i, solid.motion);
      if ((x[i] - from).squaredNorm() > sweep.gate2) {
        const SweepHit<S> hit = sweepPoint(solid.sdf, from, x[i], thickness);
        ++share.swept;
        share.evaluated += hit.evaluations;
        const S beyond = hit.phi + hit.normal.dot(x[i] - hit.point);  // the end against the tangent plane
        if (hit.hit && beyond < thickness) {
          const S dn = thickness - beyond;
          x[i] += dn * hit.normal;
          // A coupled body's push acts on the line through the point where the path met the solid.
          contacts.template record<kBody>(i, x[i], hit.normal, dn, solid.motion, hit.point,
                                          solid.motion.contactVelocityAt(x[i], hit.normal, hit.point));
          if constexpr (kKeepTurn) {
            keepTurnAbout(solid.sdf, solid.motion, start, x[i], v[i]);
            start = x[i];
          }
          moved = std::max(moved, (x[i] - binned[i]).squaredNorm());
          ++share.sweptFound;
        }
      }
    }
    // A ball's or capsule's vertex clear of the thickness is passed over on its squared distance (Sdf::beyond).
    if constexpr (requires { solid.sdf.beyond(x[i], thickness); })
      if (solid.sdf.beyond(x[i], thickness - slack)) continue;
    Vec3<S> n;
    const S phi = solid.sdf(x[i], n);
    if (phi >= thickness - slack) continue;
    const S dn = thickness - phi;
    x[i] += dn * n;
    contacts.template record<kBody>(i, x[i], n, dn, solid.motion, x[i], solid.motion.velocityAt(x[i]));
    if constexpr (kKeepTurn) keepTurnAbout(solid.sdf, solid.motion, start, x[i], v[i]);
    moved = std::max(moved, (x[i] - binned[i]).squaredNorm());
    ++share.found;
  }
  share.evaluated += end - begin;
  share.moved = std::sqrt(moved);
  return share;
}
template <bool kSweep = false, class Shape, Scalar S, class Ids>
VertexPassShare<S> projectVertexContacts(Index begin, Index end, const CompiledSolid<Shape, S>& solid, S thickness,
                                         Vec3<S>* x, const S* invMass, Ids ids, ContactBuffer<S>& contacts,
                                         const Vec3<S>* binned, S slack = S(0), const SweepInputs<S>& sweep = {},
                                         Vec3<S>* keepTurn = nullptr) {
  if constexpr (kSmoothField<Shape, S>) {
    if (keepTurn != nullptr && solid.motion.body < 0)
      return projectVertexContactsAs<false, kSweep, true>(begin, end, solid, thickness, x, invMass, ids, contacts,
                                                          binned, slack, sweep, keepTurn);
  }
  return withFlags([&](auto body) {
    return projectVertexContactsAs<body(), kSweep>(begin, end, solid, thickness, x, invMass, ids, contacts, binned,
                                                   slack, sweep);
  }, solid.motion.body >= 0);
}

/// How far inside the thickness a face's deepest point may read and still be no contact: a share of the thickness
/// and a few roundings of the point's largest coordinate (kFaceContactSlack, kFaceContactRoundings).
template <Scalar S> S faceContactSlack(S thickness, const Vec3<S>& point) {
  return thickness * S(constants::kFaceContactSlack) +
         S(constants::kFaceContactRoundings) * std::numeric_limits<S>::epsilon() * point.cwiseAbs().maxCoeff();
}
/// For every face: cull by bounding sphere (when kCull), find the deepest point by PGD, and if it is closer
/// than `thickness` by more than faceContactSlack, move the face's vertices, weighted by barycentric weight and
/// inverse mass (dx_i = w_i c_i / sum_j w_j c_j b_j * depth * n, c = b on balls and capsules and b + kFaceSpread
/// on fields with edges), so that point reaches the thickness. Visits the
/// faces `ids` (count of them) in order. Returns the largest distance of a moved vertex from `binned`. Serial:
/// neighbouring faces share vertices.
///
/// With kBoxed and kCull (a bounded solid, given the faces the broad phase found near it), a face whose bounding
/// box misses the solid's box grown by the thickness is passed over before any field evaluation: outside its box
/// a solid's field is at least the distance to the box (placeBounds), so no point of such a face is within the
/// thickness.
/// The box is read when the face's turn comes, on the positions as the faces before it left them, so the
/// contacts are bit for bit those of the pass without the check. Such faces count as culled. In the 80-body
/// rain the grid hands on 125 faces per body and substep, and 115 of them were culled by a field evaluation each.
///
/// With kSweep (continuous contact), a face whose corners travelled further than the gate relative to the solid
/// is first searched along its path (sweepFace); from its first contact on, no corner goes further against the
/// contact normal than it was then. The discrete query then runs on where that left it. With kOwnNormals (a
/// smooth field, Settings::keepAngularMomentum), each corner's record takes the field's normal at the corner, and
/// where `keepTurn` is given (the velocities, after the update), a moved corner's velocity keeps its moment about
/// the centre of curvature (keepTurnAbout).
///
/// With kSkip (a solid that does not move, with the bins on, visiting every face in index order), a face whose
/// kept clearance exceeds how far any vertex may be from its binned position is passed over, and every culled
/// face's clearance is kept (KeptClearance). A face whose corners this pass has moved is tested and keeps none, so
/// the contacts are bit for bit those of the pass without it.
///
/// With kHold, a face in contact is pushed from its held point (HeldPoints) where that is as deep as the search's
/// answer (within kHeldPointSlack of its tolerance), and the point it is pushed from is held for the next substep.
///
/// `gate` says which positions of the list this thread visits and when (SerialGate: all, in turn).
template <bool kCull, bool kBody, bool kBoxed, bool kSweep, bool kOwnNormals = false, bool kSkip = false,
          bool kHold = false, class Shape, Scalar S, class Ids, class Gate = SerialGate>
S projectFaceContactsAs(const CompiledSolid<Shape, S>& solid, S thickness, int pgdIterations,
                        const std::vector<std::array<Index, 3>>& triangles, Ids ids, Index count, Vec3<S>* x,
                        const S* invMass, ContactBuffer<S>& contacts, CollisionStats& stats, const Vec3<S>* binned,
                        bool exactSearch, const SweepInputs<S>& sweep, [[maybe_unused]] Vec3<S>* keepTurn = nullptr,
                        [[maybe_unused]] KeptClearance<S> skip = {}, [[maybe_unused]] HeldPoints<S> held = {},
                        Gate gate = {}) {
  static_assert(!kSkip || (kCull && kBoxed && !kSweep && !kBody), "a kept clearance is a cull's, on a still solid");
  S moved = 0;
  CollisionStats counts;  // kept apart from `stats`, which the moves below may alias
  [[maybe_unused]] const Vec3<S> boxLow = solid.boxLow.array() - thickness;
  [[maybe_unused]] const Vec3<S> boxHigh = solid.boxHigh.array() + thickness;
  // kSkip: the rounding slack of a clearance read off the box check.
  [[maybe_unused]] const S boxSlack =
      S(kClearanceSlack) * std::max(boxLow.cwiseAbs().maxCoeff(), boxHigh.cwiseAbs().maxCoeff());
  for (Index f = gate.first(count); f < count; f = gate.next(f, count)) {
    gate.wait(f);
    const auto& t = triangles[std::size_t(ids[f])];
    // kSkip: a face in contact at its last test goes to its search without the cheap culls before it, which would
    // mostly fail (the answer is the same either way: they cull only faces the search finds clear).
    [[maybe_unused]] bool boundsFirst = true;
    if constexpr (kSkip) {
      if (skip.clearOf(ids[f], t)) {
        ++counts.facesCulled;
        ++counts.facesKeptClear;
        continue;
      }
      boundsFirst = !skip.touchedLast(ids[f]);
    }
    if constexpr (kSweep) {
      // Continuous contact: a face whose corners travelled further than the gate relative to the solid is
      // searched along its path first (sweepFace).
      const Vec3<S> from[3] = {sweep.startOf(t[0], solid.motion), sweep.startOf(t[1], solid.motion),
                               sweep.startOf(t[2], solid.motion)};
      const Vec3<S> to[3] = {x[t[0]], x[t[1]], x[t[2]]};
      if (std::max({(to[0] - from[0]).squaredNorm(), (to[1] - from[1]).squaredNorm(),
                    (to[2] - from[2]).squaredNorm()}) > sweep.gate2) {
        bool near = true;
        if constexpr (kBoxed) {  // the box of the whole path against the solid's
          const Vec3<S> low =
              from[0].cwiseMin(from[1]).cwiseMin(from[2]).cwiseMin(to[0]).cwiseMin(to[1]).cwiseMin(to[2]);
          const Vec3<S> high =
              from[0].cwiseMax(from[1]).cwiseMax(from[2]).cwiseMax(to[0]).cwiseMax(to[1]).cwiseMax(to[2]);
          near = (high.array() >= boxLow.array()).all() && (low.array() <= boxHigh.array()).all();
        }
        if (near) {
          ++counts.faceSweeps;
          FaceQuery<S> hit;
          int evaluations = 0;
          S when = 0;
          if (sweepFace(solid.sdf, from, to, thickness, pgdIterations, exactSearch, hit, evaluations, when)) {
            // From the first contact on, no corner goes further against the contact normal than it was then: the
            // face keeps its travel along the surface and loses the rest of its approach. A corner that already
            // holds a contact of another direction goes back along its own path instead: kept travel along two
            // tangent planes of a thin solid leaves the path for where they meet, beyond both, and substep after
            // substep that ratchets a corner away from the solid (docs/design.md §18, "The face's response").
            const Vec3<S>& n = hit.normal;
            bool any = false;
            for (int k = 0; k < 3; ++k) {
              if (invMass[t[k]] == S(0)) continue;
              const Vec3<S> then = from[k] + when * (to[k] - from[k]);
              const S dn = n.dot(then - x[t[k]]);
              if (!(dn > S(0))) continue;
              if (contacts.holdsOtherDirection(t[k], n))
                x[t[k]] = then;
              else
                x[t[k]] += dn * n;
              contacts.template record<kBody>(t[k], x[t[k]], n, dn, solid.motion, hit.point,
                                              solid.motion.contactVelocityAt(x[t[k]], n, hit.point));
              moved = std::max(moved, (x[t[k]] - binned[t[k]]).squaredNorm());
              any = true;
            }
            counts.sweepContacts += any;
          }
          counts.sdfEvaluations += evaluations;
        }
      }
    }
    if (kBoxed && kCull && boundsFirst) {
      const Vec3<S> faceLow = x[t[0]].cwiseMin(x[t[1]]).cwiseMin(x[t[2]]);
      const Vec3<S> faceHigh = x[t[0]].cwiseMax(x[t[1]]).cwiseMax(x[t[2]]);
      if (!((faceHigh.array() >= boxLow.array()).all() && (faceLow.array() <= boxHigh.array()).all())) {
        // Moved by less than the widest gap along an axis, the face's box still misses the grown one.
        if constexpr (kSkip)
          skip.keep(ids[f], t, std::max((boxLow - faceHigh).maxCoeff(), (faceLow - boxHigh).maxCoeff()) - boxSlack);
        ++counts.facesCulled;
        continue;
      }
    }
    FaceQuery<S> q;
    [[maybe_unused]] S clearance = 0;
    if (!queryFace<kCull, kSkip>(solid.sdf, x[t[0]], x[t[1]], x[t[2]], thickness, pgdIterations, q, exactSearch,
                                 &clearance, boundsFirst)) {
      if constexpr (kSkip) skip.keep(ids[f], t, clearance);
      ++counts.facesCulled;
      ++counts.sdfEvaluations;
      continue;
    }
    if constexpr (kSkip) skip.clear[ids[f]] = -std::numeric_limits<S>::infinity();
    counts.sdfEvaluations += q.evaluations;
    if (q.phi >= thickness - faceContactSlack(thickness, q.point)) continue;
    if constexpr (kSkip) skip.touched(ids[f]);
    if constexpr (kHold) {
      HeldPoint<S>& h = held.points[ids[f]];
      if (h.place == held.place) {
        const Vec3<S> p = detail::pointOnFace(x[t[0]], x[t[1]], x[t[2]], h.barycentric[1], h.barycentric[2]);
        Vec3<S> n;
        const S phi = solid.sdf(p, n);
        ++counts.sdfEvaluations;
        const S extent = rootOf(std::max({(x[t[1]] - x[t[0]]).squaredNorm(), (x[t[2]] - x[t[1]]).squaredNorm(),
                                          (x[t[0]] - x[t[2]]).squaredNorm()}));
        if (phi < thickness && phi <= q.phi + S(constants::kHeldPointSlack * constants::kFaceSearchGap) * extent)
          q = {h.barycentric, p, n, phi, q.evaluations};
      }
      h = {q.barycentric, held.place};
    }
    // Corner k moves wb_k / denom times the depth, which carries the deepest point to the thickness. Where faces
    // lie along edges and sides (the fields whose deepest points are held), the shares are spread toward an even
    // lift (kFaceSpread), so that a face along an edge is not tilted about one end of it (docs/design.md §4,
    // "Spread shares"); a ball's or a capsule's push keeps its line through the centre or the axis.
    constexpr S spread = kHoldsDeepestPoints<Sdf<Shape, S>> ? S(constants::kFaceSpread) : S(0);
    const Vec3<S> wb(invMass[t[0]] * (q.barycentric[0] + spread), invMass[t[1]] * (q.barycentric[1] + spread),
                     invMass[t[2]] * (q.barycentric[2] + spread));
    const S denom = wb.dot(q.barycentric);
    if (denom <= S(0)) continue;
    ++counts.faceContacts;
    S depth = thickness - q.phi;
    // A ball's nearest point (queryFace's closed form) already has its gradient along the face's normal inside the
    // face and across the edge on one, which the feature push keeps (docs/design.md §3, "Feature normals").
    if constexpr (!requires { Sdf<Shape, S>::kPointCore; }) {
      int extra = 0;
      depth = featureAlignedPush(solid.sdf, x[t[0]], x[t[1]], x[t[2]], thickness, depth, q, extra);
      counts.sdfEvaluations += extra;
    }
    // The moves are unbounded where the free corners carry little of the deepest point (a body pressing a
    // hammock beside its pinned border threw the next row 0.6 m in one substep). Capped at kFaceMoveCap times
    // the depth, the point is cleared over several substeps instead.
    const S most = std::max({wb[0], wb[1], wb[2]}) / denom;
    if (most > S(constants::kFaceMoveCap)) depth *= S(constants::kFaceMoveCap) / most;
    const Vec3<S> placed = movedAlong(q.point, depth, q.normal);  // the moves below carry the deepest point there
    for (int k = 0; k < 3; ++k) {
      if (wb[k] <= S(0)) continue;
      const S dn = wb[k] / denom * depth;
      [[maybe_unused]] const Vec3<S> before = x[t[k]];
      // Moved in a local and stored whole: read back from memory right after a store of its parts, the
      // position cost a store-forwarding stall per corner.
      const Vec3<S> p = movedAlong(x[t[k]], dn, q.normal);
      x[t[k]] = p;
      Vec3<S> n = q.normal, anchor = placed;
      if constexpr (kOwnNormals) {
        // On a smooth field each corner answers along its own normal, whose line meets the ball's centre or
        // the capsule's axis as the push's does: the face's normal at its corners turns the cloth about them
        // (docs/design.md §4). A corner beyond a thin capsule, facing the other way, keeps the face's.
        Vec3<S> g;
        const S phi = solid.sdf(p, g);
        if (g.dot(q.normal) >= S(constants::kMergeCos)) n = g, anchor = p - phi * g;
        if (keepTurn != nullptr) keepTurnAbout(solid.sdf, solid.motion, before, p, keepTurn[t[k]]);
      }
      // A still solid's (kSkip) surface does not move: its velocity is zero without the products.
      contacts.template record<kBody, true>(t[k], p, n, dn, solid.motion, anchor,
                                            kSkip ? Vec3<S>::Zero() : solid.motion.contactVelocityAt(p, n, anchor));
      moved = std::max(moved, (p - binned[t[k]]).squaredNorm());
      if constexpr (kSkip) skip.stamp(t[k]);
    }
  }
  counts.facesTested += gate.share(count);
  stats += counts;
  return std::sqrt(moved);
}
template <bool kCull, bool kBoxed = false, bool kSweep = false, class Shape, Scalar S, class Ids,
          class Gate = SerialGate>
S projectFaceContacts(const CompiledSolid<Shape, S>& solid, S thickness, int pgdIterations,
                      const std::vector<std::array<Index, 3>>& triangles, Ids ids, Index count, Vec3<S>* x,
                      const S* invMass, ContactBuffer<S>& contacts, CollisionStats& stats, const Vec3<S>* binned,
                      bool exactSearch = true, const SweepInputs<S>& sweep = {}, bool ownNormals = false,
                      Vec3<S>* keepTurn = nullptr, KeptClearance<S> skip = {}, HeldPoints<S> held = {},
                      Gate gate = {}) {
  const bool body = solid.motion.body >= 0;
  constexpr bool kMayHold = kHoldsDeepestPoints<Sdf<Shape, S>>;
  return withFlags([&](auto holdFlag) {
    constexpr bool kHold = kMayHold && holdFlag();
    if constexpr (kCull && kBoxed && !kSweep) {
      if (skip.clear != nullptr && !body) {
        if constexpr (kSmoothField<Shape, S>) {
          if (ownNormals)  // the corners' own normals change the records, not which faces are culled
            return projectFaceContactsAs<kCull, false, kBoxed, kSweep, true, true, kHold, Shape, S, Ids, Gate>(
                solid, thickness, pgdIterations, triangles, ids, count, x, invMass, contacts, stats, binned,
                exactSearch, sweep, keepTurn, skip, held, gate);
        }
        return projectFaceContactsAs<kCull, false, kBoxed, kSweep, false, true, kHold, Shape, S, Ids, Gate>(
            solid, thickness, pgdIterations, triangles, ids, count, x, invMass, contacts, stats, binned,
            exactSearch, sweep, keepTurn, skip, held, gate);
      }
    }
    if constexpr (kSmoothField<Shape, S>) {
      if (ownNormals && !body)
        return projectFaceContactsAs<kCull, false, kBoxed, kSweep, true, false, kHold, Shape, S, Ids, Gate>(
            solid, thickness, pgdIterations, triangles, ids, count, x, invMass, contacts, stats, binned,
            exactSearch, sweep, keepTurn, KeptClearance<S>{}, held, gate);
    }
    return withFlags([&](auto isBody) {
      return projectFaceContactsAs<kCull, isBody(), kBoxed, kSweep, false, false, kHold, Shape, S, Ids, Gate>(
          solid, thickness, pgdIterations, triangles, ids, count, x, invMass, contacts, stats, binned, exactSearch,
          sweep, static_cast<Vec3<S>*>(nullptr), KeptClearance<S>{}, held, gate);
    }, body);
  }, kMayHold && held.points != nullptr);
}


/// The eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations, kEigenSweeps sweeps: `a` ends
/// diagonal (its eigenvalues on the diagonal), the columns of `v` its unit eigenvectors. Written out so that the
/// GLSL twin (shaders/common.glsl) does the same arithmetic in the same order.
template <Scalar S> void symmetricEigen3(S (&a)[3][3], S (&v)[3][3]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) v[i][j] = i == j ? S(1) : S(0);
  for (int sweep = 0; sweep < constants::kEigenSweeps; ++sweep)
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        const S apq = a[p][q];
        // Negligible beside the diagonal: left as it is (and theta, below, stays far from overflowing).
        if (std::abs(apq) <= S(constants::kEigenNegligible) * (std::abs(a[p][p]) + std::abs(a[q][q]))) continue;
        // The rotation in the (p, q) plane that zeroes a[p][q] (the smaller angle; tan = t).
        const S theta = (a[q][q] - a[p][p]) / (S(2) * apq);
        const S t = (theta >= S(0) ? S(1) : S(-1)) / (std::abs(theta) + std::sqrt(theta * theta + S(1)));
        const S c = S(1) / std::sqrt(t * t + S(1)), sn = t * c;
        for (int k = 0; k < 3; ++k) {  // a J
          const S akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - sn * akq;
          a[k][q] = sn * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {  // J^T (a J)
          const S apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - sn * aqk;
          a[q][k] = sn * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {  // v J
          const S vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - sn * vkq;
          v[k][q] = sn * vkp + c * vkq;
        }
      }
}

/// One pass of leastSquaresCompromise from y: over the planes y violates, sum_k r_k n_k resolved along the
/// eigen-directions of sum_k n_k n_k^T whose eigenvalue is at least `weakest`. One or two planes (most pinches: a
/// body over the floor) in closed form: for unit normals p and q the eigen-directions in their plane are p + q and
/// p - q, with eigenvalues |p + q|^2 / 2 and |p - q|^2 / 2, and the move along each is (r_p +- r_q) (p +- q) /
/// |p +- q|^2. Jacobi rotations for three: their sweeps' roots and divisions had been 13 % of a rain of bodies'
/// step (docs/design.md §16).
template <Scalar S> Vec3<S> leastSquaresMove(const Vec3<S>* n, const S* b, int count, const Vec3<S>& y, S weakest) {
  int violated = 0, which[ContactBuffer<S>::kSlots];
  S r[ContactBuffer<S>::kSlots];
  for (int k = 0; k < count; ++k) {
    const S rk = b[k] - n[k].dot(y);
    if (rk > S(0)) which[violated] = k, r[violated++] = rk;
  }
  if (violated == 0) return Vec3<S>::Zero();
  if (violated == 1) {
    const Vec3<S>& p = n[which[0]];
    const S length2 = p.squaredNorm();
    return length2 >= weakest ? Vec3<S>((r[0] / length2) * p) : Vec3<S>::Zero();
  }
  Vec3<S> move = Vec3<S>::Zero();
  if (violated == 2) {
    const Vec3<S>& p = n[which[0]];
    const Vec3<S>& q = n[which[1]];
    const Vec3<S> sum = p + q, difference = p - q;
    const S sum2 = sum.squaredNorm(), difference2 = difference.squaredNorm();
    if (sum2 >= S(2) * weakest) move += ((r[0] + r[1]) / sum2) * sum;
    if (difference2 >= S(2) * weakest) move += ((r[0] - r[1]) / difference2) * difference;
    return move;
  }
  S a[3][3] = {}, v[3][3];
  Vec3<S> g = Vec3<S>::Zero();  // sum_k r_k n_k over the violated planes
  for (int m = 0; m < violated; ++m) {
    const Vec3<S>& nk = n[which[m]];
    g += r[m] * nk;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) a[i][j] += nk[i] * nk[j];
  }
  symmetricEigen3(a, v);
  for (int i = 0; i < 3; ++i) {
    if (!(a[i][i] >= weakest)) continue;
    const Vec3<S> e(v[0][i], v[1][i], v[2][i]);
    move += (e.dot(g) / a[i][i]) * e;
  }
  return move;
}

/// The least-squares compromise for a point that no nearby point puts outside all of up to three half-spaces
/// n_k . y >= b_k (a cloth pinched in a gap narrower than twice its thickness): from `from`, the violated planes'
/// least-squares move along the directions they determine well. Two nearly facing planes pin the point along
/// the axis between them and hardly at all across it; their exact least-squares point is where they meet, far to
/// the side, and a step toward it every substep feeds the constraint solve a sideways jump (docs/design.md §16).
/// So eigen-directions of sum_k n_k n_k^T whose eigenvalue is below 1/kReach^2, along which the planes would move
/// the point more than kReach times its violation, are left out: between two facing planes the point goes to the
/// middle of the gap. kLeastSquaresPasses passes, each on the planes still violated.
/// `reach` sets that cut (a refused exact point of the settle takes kRefusedReach).
template <Scalar S>
Vec3<S> leastSquaresCompromise(const Vec3<S>* n, const S* b, int count, const Vec3<S>& from,
                               double reach = constants::kReach) {
  const S weakest = S(1 / (reach * reach));
  Vec3<S> y = from;
  for (int pass = 0; pass < constants::kLeastSquaresPasses; ++pass) y += leastSquaresMove(n, b, count, y, weakest);
  return y;
}

/// Whether y lies in every half-space n_k . y >= b_k, up to kFeasibleSlack times max(1, |b_k|).
template <Scalar S> bool insideHalfSpaces(const Vec3<S>* n, const S* b, int count, const Vec3<S>& y) {
  for (int k = 0; k < count; ++k)
    if (n[k].dot(y) < b[k] - S(constants::kFeasibleSlack) * std::max(S(1), std::abs(b[k]))) return false;
  return true;
}

/// How far y0 is outside up to three half-spaces, summed over them.
template <Scalar S> S halfSpaceViolation(const Vec3<S>* n, const S* b, int count, const Vec3<S>& y0) {
  S violation = 0;
  for (int k = 0; k < count; ++k) violation += std::max(b[k] - n[k].dot(y0), S(0));
  return violation;
}

/// The exact point of nearestInHalfSpaces: the nearest feasible point to y0 (outside some half-space) among the
/// projections onto every subset of the planes, within `reach` of y0; false where there is none.
template <Scalar S>
bool nearestOnPlanes(const Vec3<S>* n, const S* b, int count, const Vec3<S>& y0, S reach, Vec3<S>& best) {
  const S reach2 = reach * reach;
  S bestDist = std::numeric_limits<S>::infinity();
  auto consider = [&](const Vec3<S>& y) {
    const S d = (y - y0).squaredNorm();
    if (d < bestDist && d <= reach2 && insideHalfSpaces(n, b, count, y)) best = y, bestDist = d;
  };
  for (int k = 0; k < count; ++k) consider(y0 + (b[k] - n[k].dot(y0)) * n[k]);
  for (int j = 0; j < count; ++j)
    for (int k = j + 1; k < count; ++k) {  // the line where planes j and k meet
      const S ab = n[j].dot(n[k]), det = S(1) - ab * ab;
      if (det < S(constants::kParallelPlanes)) continue;  // (nearly) parallel: the single-plane candidates cover it
      const S ra = b[j] - n[j].dot(y0), rb = b[k] - n[k].dot(y0);
      consider(y0 + ((ra - ab * rb) / det) * n[j] + ((rb - ab * ra) / det) * n[k]);
    }
  if (count == 3) {  // the corner where all three meet
    Mat3<S> m;
    m << n[0].transpose(), n[1].transpose(), n[2].transpose();
    if (std::abs(m.determinant()) > S(constants::kCornerDeterminant)) consider(m.partialPivLu().solve(Vec3<S>(b[0], b[1], b[2])));
  }
  return bestDist < std::numeric_limits<S>::infinity();
}

/// The point nearest to y0 in {y : n_k . y >= b_k} for up to three half-spaces: the nearest feasible point
/// among the projections onto every subset of the planes, which is the exact projection onto their
/// intersection. The planes are tangents of curved surfaces, so far from y0 they say nothing: two nearly
/// facing planes (a cloth pinched under a box whose merged normal is tilted a little) meet far away, and going
/// there would throw the point sideways. A candidate further than kReach times the total violation (or than
/// `minReach`, if that is more) counts as none; where there is none (also when the half-spaces do not meet, as
/// in a gap narrower than twice the thickness), the answer is the least-squares compromise from `fallback`
/// (leastSquaresCompromise: between two facing planes, the middle of the gap).
template <Scalar S>
Vec3<S> nearestInHalfSpaces(const Vec3<S>* n, const S* b, int count, const Vec3<S>& y0, const Vec3<S>& fallback,
                            S minReach = S(0)) {
  if (insideHalfSpaces(n, b, count, y0)) return y0;
  const S reach = std::max(S(constants::kReach) * halfSpaceViolation(n, b, count, y0), minReach);
  Vec3<S> best;
  if (nearestOnPlanes(n, b, count, y0, reach, best)) return best;
  return leastSquaresCompromise(n, b, count, fallback);
}

/// The settle's exact point for one vertex, before the true fields have judged it (docs/design.md §16, "Exact
/// points tested"): the vertex `from`, the point `to` on its planes, the slack (kExactPointSlack of the vertex's
/// violation), and the planes `to` lies on within that slack (bit k: slot k).
template <Scalar S> struct SettlePoint {
  Vec3<S> from, to;
  S slack;
  unsigned planes;
};

/// Whether q lies outside a bounded solid's box grown by `grow`, where its field reads more than `grow`.
template <class Shape, Scalar S> bool beyondBox(const CompiledSolid<Shape, S>& solid, const Vec3<S>& q, S grow) {
  return solid.bounded &&
         ((q.array() < solid.boxLow.array() - grow).any() || (q.array() > solid.boxHigh.array() + grow).any());
}

/// Bits of p.planes that the solid's surface backs at p.to: its box grown by the thickness and the slack holds
/// the point, its field reads at most the thickness and the slack there, and its gradient is within kBackedCos
/// of the plane's normal. A flat wall backs its plane everywhere; an edge's or a curved solid's tangent only near
/// where it touched.
template <class Shape, Scalar S>
unsigned backedPlanes(const CompiledSolid<Shape, S>& solid, const SettlePoint<S>& p, const Vec3<S>* normals,
                      S thickness) {
  const S reach = thickness + p.slack;
  if (beyondBox(solid, p.to, reach)) return 0u;
  Vec3<S> g;
  if (!(solid.sdf(p.to, g) <= reach)) return 0u;
  unsigned backed = 0;
  for (int k = 0; k < constants::kContactSlots; ++k)
    if ((p.planes >> k & 1u) && g.dot(normals[k]) >= S(constants::kBackedCos)) backed |= 1u << k;
  return backed;
}

/// Bits of the segment's fractions (bit j: from + (j + 1) / kSegmentFractions of the way to `to`) where the solid
/// reads at least the thickness less the slack (a point outside its box grown by the thickness does).
template <class Shape, Scalar S>
std::uint32_t clearFractions(const CompiledSolid<Shape, S>& solid, const SettlePoint<S>& p, S thickness) {
  std::uint32_t clear = 0;
  const S limit = thickness - p.slack;
  for (int j = 0; j < constants::kSegmentFractions; ++j) {
    const Vec3<S> q = p.from + (S(j + 1) / S(constants::kSegmentFractions)) * (p.to - p.from);
    Vec3<S> g;
    if (beyondBox(solid, q, thickness) || !(solid.sdf(q, g) < limit))
      clear |= std::uint32_t(1) << j;
  }
  return clear;
}

/// Where a vertex whose exact point the fields judged goes: the point itself where every plane it lies on is
/// backed; the least-squares compromise from `fallback`, its weak directions cut at 1/kRefusedReach^2, where
/// some is (a floor backs its plane, an edge's tangent does not); else the first fraction of the segment that
/// every solid leaves clear (two tangents of a rod), or the point where not even it is clear.
template <Scalar S>
Vec3<S> placeSettlePoint(const SettlePoint<S>& p, unsigned backed, std::uint32_t clear, const Vec3<S>* n,
                         const S* b, int count, const Vec3<S>& fallback) {
  if ((backed & p.planes) == p.planes) return p.to;
  if (backed != 0u) return leastSquaresCompromise(n, b, count, fallback, constants::kRefusedReach);
  constexpr int kLast = constants::kSegmentFractions - 1;
  if (!(clear >> kLast & 1u)) return p.to;
  const int j = std::countr_zero(clear);
  return p.from + (S(j + 1) / S(constants::kSegmentFractions)) * (p.to - p.from);
}

/// The fields a settle tests its exact points against: every solid of `compiled` (a tuple of vectors of
/// CompiledSolid). With no solid at all, no plane is backed and every fraction is clear.
template <Scalar S, class Solids> struct SettleFields {
  const Solids& compiled;
  S thickness;

  unsigned backed(const SettlePoint<S>& p, const Vec3<S>* normals) const {
    unsigned bits = 0;
    std::apply([&](const auto&... lists) {
      (..., [&](const auto& list) {
        for (const auto& solid : list) bits |= backedPlanes(solid, p, normals, thickness);
      }(lists));
    }, compiled);
    return bits;
  }
  std::uint32_t clear(const SettlePoint<S>& p) const {
    std::uint32_t bits = ~std::uint32_t(0);
    std::apply([&](const auto&... lists) {
      (..., [&](const auto& list) {
        for (const auto& solid : list) bits &= clearFractions(solid, p, thickness);
      }(lists));
    }, compiled);
    return bits;
  }
};

/// Takes every exact point as it is: the planes alone decide (the placement's geometry, without the fields).
struct PlanesTrusted {};

/// A vertex pushed out of several surfaces one after another (a crease, a box corner, a cloth pinched
/// between two solids) may end up back inside an earlier one, and alternating projections close in slowly
/// when the surfaces meet at a sharp angle. This places each such vertex at the nearest point outside all its
/// contact half-spaces at once (nearestInHalfSpaces). A pinched vertex starts its least-squares placement
/// from `reference` (where it was before this substep's contacts moved it): the projections it went through
/// on the way, some of them sideways off an edge, are forgotten rather than repeated every substep, which
/// would feed the constraint solve a sideways jump each substep. An exact point is tested against `fields`
/// (SettleFields; placeSettlePoint) unless they are PlanesTrusted. For vertices [begin, end); returns the
/// largest distance of a moved vertex from `binned`.
template <Scalar S, class Fields = PlanesTrusted>
S projectOntoContactPlanes(Index begin, Index end, const ContactBuffer<S>& contacts, Vec3<S>* x,
                           const Vec3<S>* reference, const Vec3<S>* binned, const Fields& fields = {}) {
  S moved = 0;
  for (Index i = begin; i < end; ++i) {
    if (!contacts.live(i)) continue;
    const int count = contacts.slotCount[i];
    // A surface that joined another direction's slot is not in the planes: the corner they make may lie deep
    // inside it (two faces of a box and a third body's face, with the floor joined to that face, meet far
    // below the floor). Such a vertex is left to the passes on the true fields.
    if (count < 2 || contacts.overflow[i] == contacts.current) continue;
    const auto& sl = contacts.slots[i];
    Vec3<S> normals[ContactBuffer<S>::kSlots];
    S offsets[ContactBuffer<S>::kSlots];
    for (int k = 0; k < count; ++k) normals[k] = sl[k].normal, offsets[k] = sl[k].offset;
    if constexpr (std::is_same_v<Fields, PlanesTrusted>) {
      x[i] = nearestInHalfSpaces(normals, offsets, count, x[i], reference[i]);
    } else {
      if (!insideHalfSpaces(normals, offsets, count, x[i])) {
        const S violation = halfSpaceViolation(normals, offsets, count, x[i]);
        SettlePoint<S> p{x[i], x[i], S(constants::kExactPointSlack) * violation, 0u};
        if (nearestOnPlanes(normals, offsets, count, x[i], S(constants::kReach) * violation, p.to)) {
          for (int k = 0; k < count; ++k)
            if (normals[k].dot(p.to) - offsets[k] <= p.slack) p.planes |= 1u << k;
          const unsigned backed = fields.backed(p, normals);
          // The segment is searched only where no plane is backed (it decides only there).
          const std::uint32_t clear = backed != 0u ? 0u : fields.clear(p);
          x[i] = placeSettlePoint(p, backed, clear, normals, offsets, count, reference[i]);
        } else {
          x[i] = leastSquaresCompromise(normals, offsets, count, reference[i]);
        }
      }
    }
    moved = std::max(moved, (x[i] - binned[i]).squaredNorm());
  }
  return std::sqrt(moved);
}

/// Coulomb friction on positions for one contact surface: the tangential displacement of this substep
/// (relative to the solid) within staticFriction * dn is undone entirely (stick, returns true); beyond it,
/// dynamicFriction * dn of it is undone. So a cloth that should stick does not creep g sin(theta) h per substep.
template <Scalar S>
DRAPE_ALWAYS_INLINE bool applyPositionFriction(const ContactSlot<S>& c, Vec3<S>& x, const Vec3<S>& xPrev, S h) {
  const Vec3<S>& n = c.normal;
  const Vec3<S> disp = (x - xPrev) - h * c.solidVelocity;
  const Vec3<S> dispT = disp - n.dot(disp) * n;
  const S slip = dispT.norm();
  if (slip <= c.staticFriction * c.correction) {
    x -= dispT;
    return true;
  }
  x -= std::min(S(1), c.dynamicFriction * c.correction / slip) * dispT;
  return false;
}

#if DRAPE_SSE2
namespace detail {

/// respondContacts for vertices i .. i + 3, each live with one contact slot: lane by lane the scalar loop's
/// operations in its order (so its bits), four vertices at a time. A vertex's friction waits on two square roots
/// and two divisions; one at a time, the processor overlapped little of one vertex's wait with the next's.
template <bool kFriction>
inline void respondFour(Index i, ContactBuffer<float>& contacts, Vec3<float>* x, const Vec3<float>* xPrev,
                        Vec3<float>* v, float h, float invH, float normalDamping) {
  static_assert(sizeof(ContactSlot<float>) == 11 * sizeof(float), "ContactSlot<float> is read as 11 floats");
  // Rows (nx ny nz vcx), (vcy vcz correction staticFriction) of each slot, transposed to one field per register.
  const float* s0 = reinterpret_cast<const float*>(contacts.slots[i].data());
  const float* s1 = reinterpret_cast<const float*>(contacts.slots[i + 1].data());
  const float* s2 = reinterpret_cast<const float*>(contacts.slots[i + 2].data());
  const float* s3 = reinterpret_cast<const float*>(contacts.slots[i + 3].data());
  __m128 nx = _mm_loadu_ps(s0), ny = _mm_loadu_ps(s1), nz = _mm_loadu_ps(s2), cx = _mm_loadu_ps(s3);
  _MM_TRANSPOSE4_PS(nx, ny, nz, cx);
  __m128 cy = _mm_loadu_ps(s0 + 4), cz = _mm_loadu_ps(s1 + 4), dn = _mm_loadu_ps(s2 + 4), muS = _mm_loadu_ps(s3 + 4);
  _MM_TRANSPOSE4_PS(cy, cz, dn, muS);
  __m128 vx, vy, vz;
  loadVec3Four(v + i, vx, vy, vz);
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  const __m128 rx = _mm_sub_ps(vx, cx), ry = _mm_sub_ps(vy, cy), rz = _mm_sub_ps(vz, cz);
  const __m128 vn = dotFour(nx, ny, nz, rx, ry, rz);
  __m128 tx = _mm_sub_ps(rx, _mm_mul_ps(vn, nx)), ty = _mm_sub_ps(ry, _mm_mul_ps(vn, ny)),
         tz = _mm_sub_ps(rz, _mm_mul_ps(vn, nz));
  const __m128 vnNew = _mm_andnot_ps(_mm_cmplt_ps(vn, zero), _mm_mul_ps(vn, _mm_set1_ps(1.0f - normalDamping)));
  if constexpr (kFriction) {
    const __m128 muD = _mm_setr_ps(s0[8], s1[8], s2[8], s3[8]);
    const __m128 slideLimit = _mm_mul_ps(muD, dn);  // dynamicFriction * correction
    const __m128 speed = _mm_sqrt_ps(dotFour(tx, ty, tz, tx, ty, tz));
    const __m128 slow = _mm_mul_ps(slideLimit, _mm_set1_ps(invH));
    const __m128 fast = _mm_cmpgt_ps(speed, slow);
    const __m128 keep = _mm_and_ps(fast, _mm_div_ps(_mm_sub_ps(speed, slow), select(fast, speed, one)));
    __m128 px, py, pz, qx, qy, qz;
    loadVec3Four(x + i, px, py, pz);
    loadVec3Four(xPrev + i, qx, qy, qz);
    const __m128 hv = _mm_set1_ps(h);
    const __m128 dx = _mm_sub_ps(_mm_sub_ps(px, qx), _mm_mul_ps(hv, cx));
    const __m128 dy = _mm_sub_ps(_mm_sub_ps(py, qy), _mm_mul_ps(hv, cy));
    const __m128 dz = _mm_sub_ps(_mm_sub_ps(pz, qz), _mm_mul_ps(hv, cz));
    const __m128 dd = dotFour(nx, ny, nz, dx, dy, dz);
    const __m128 ex = _mm_sub_ps(dx, _mm_mul_ps(dd, nx)), ey = _mm_sub_ps(dy, _mm_mul_ps(dd, ny)),
                 ez = _mm_sub_ps(dz, _mm_mul_ps(dd, nz));
    const __m128 slip = _mm_sqrt_ps(dotFour(ex, ey, ez, ex, ey, ez));
    const __m128 stick = _mm_cmple_ps(slip, _mm_mul_ps(muS, dn));
    const __m128 undo = select(stick, one, _mm_min_ps(_mm_div_ps(slideLimit, select(stick, one, slip)), one));
    storeVec3Four(x + i, _mm_sub_ps(px, _mm_mul_ps(undo, ex)), _mm_sub_ps(py, _mm_mul_ps(undo, ey)),
                  _mm_sub_ps(pz, _mm_mul_ps(undo, ez)));
    tx = _mm_andnot_ps(stick, _mm_mul_ps(tx, keep));
    ty = _mm_andnot_ps(stick, _mm_mul_ps(ty, keep));
    tz = _mm_andnot_ps(stick, _mm_mul_ps(tz, keep));
  }
  storeVec3Four(v + i, _mm_add_ps(_mm_add_ps(cx, _mm_mul_ps(vnNew, nx)), tx),
                _mm_add_ps(_mm_add_ps(cy, _mm_mul_ps(vnNew, ny)), ty),
                _mm_add_ps(_mm_add_ps(cz, _mm_mul_ps(vnNew, nz)), tz));
  _mm_storeu_ps(contacts.normalDv.data() + i, _mm_add_ps(zero, _mm_max_ps(zero, _mm_sub_ps(vnNew, vn))));
}

#if DRAPE_AVX2
DRAPE_TARGET_AVX2 inline __m256 join(__m128 lo, __m128 hi) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
}
DRAPE_TARGET_AVX2 inline void loadVec3Eight(const Vec3<float>* p, __m256& ax, __m256& ay, __m256& az) {
  __m128 lx, ly, lz, hx, hy, hz;
  loadVec3Four(p, lx, ly, lz);
  loadVec3Four(p + 4, hx, hy, hz);
  ax = join(lx, hx), ay = join(ly, hy), az = join(lz, hz);
}
DRAPE_TARGET_AVX2 inline void storeVec3Eight(Vec3<float>* p, __m256 ax, __m256 ay, __m256 az) {
  storeVec3Four(p, _mm256_castps256_ps128(ax), _mm256_castps256_ps128(ay), _mm256_castps256_ps128(az));
  storeVec3Four(p + 4, _mm256_extractf128_ps(ax, 1), _mm256_extractf128_ps(ay, 1), _mm256_extractf128_ps(az, 1));
}
DRAPE_TARGET_AVX2 inline __m256 dotEight(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz) {
  return _mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_add_ps(_mm256_mul_ps(ay, by), _mm256_mul_ps(az, bz)));
}

/// respondFour for vertices i .. i + 7, eight lanes at once (AVX2, without FMA, so the same bits): where the
/// processor has it, two fours' waits on their square roots and divisions become one.
template <bool kFriction>
DRAPE_TARGET_AVX2 inline void respondEight(Index i, ContactBuffer<float>& contacts, Vec3<float>* x,
                                           const Vec3<float>* xPrev, Vec3<float>* v, float h, float invH,
                                           float normalDamping) {
  // The slots' rows as in respondFour, four vertices per transpose.
  __m128 r[2][8];
  float muDyn[8];
  for (int half = 0; half < 2; ++half) {
    const float* s[4];
    for (int k = 0; k < 4; ++k) s[k] = reinterpret_cast<const float*>(contacts.slots[i + 4 * half + k].data());
    for (int k = 0; k < 4; ++k) muDyn[4 * half + k] = s[k][8];
    __m128* q = r[half];
    q[0] = _mm_loadu_ps(s[0]), q[1] = _mm_loadu_ps(s[1]), q[2] = _mm_loadu_ps(s[2]), q[3] = _mm_loadu_ps(s[3]);
    _MM_TRANSPOSE4_PS(q[0], q[1], q[2], q[3]);
    q[4] = _mm_loadu_ps(s[0] + 4), q[5] = _mm_loadu_ps(s[1] + 4), q[6] = _mm_loadu_ps(s[2] + 4);
    q[7] = _mm_loadu_ps(s[3] + 4);
    _MM_TRANSPOSE4_PS(q[4], q[5], q[6], q[7]);
  }
  const __m256 nx = join(r[0][0], r[1][0]), ny = join(r[0][1], r[1][1]), nz = join(r[0][2], r[1][2]);
  const __m256 cx = join(r[0][3], r[1][3]), cy = join(r[0][4], r[1][4]), cz = join(r[0][5], r[1][5]);
  const __m256 dn = join(r[0][6], r[1][6]), muS = join(r[0][7], r[1][7]);
  __m256 vx, vy, vz;
  loadVec3Eight(v + i, vx, vy, vz);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 rx = _mm256_sub_ps(vx, cx), ry = _mm256_sub_ps(vy, cy), rz = _mm256_sub_ps(vz, cz);
  const __m256 vn = dotEight(nx, ny, nz, rx, ry, rz);
  __m256 tx = _mm256_sub_ps(rx, _mm256_mul_ps(vn, nx)), ty = _mm256_sub_ps(ry, _mm256_mul_ps(vn, ny)),
         tz = _mm256_sub_ps(rz, _mm256_mul_ps(vn, nz));
  const __m256 vnNew =
      _mm256_andnot_ps(_mm256_cmp_ps(vn, zero, _CMP_LT_OS), _mm256_mul_ps(vn, _mm256_set1_ps(1.0f - normalDamping)));
  if constexpr (kFriction) {
    const __m256 slideLimit = _mm256_mul_ps(_mm256_loadu_ps(muDyn), dn);
    const __m256 speed = _mm256_sqrt_ps(dotEight(tx, ty, tz, tx, ty, tz));
    const __m256 slow = _mm256_mul_ps(slideLimit, _mm256_set1_ps(invH));
    const __m256 fast = _mm256_cmp_ps(speed, slow, _CMP_GT_OS);
    const __m256 keep =
        _mm256_and_ps(fast, _mm256_div_ps(_mm256_sub_ps(speed, slow), _mm256_blendv_ps(one, speed, fast)));
    __m256 px, py, pz, qx, qy, qz;
    loadVec3Eight(x + i, px, py, pz);
    loadVec3Eight(xPrev + i, qx, qy, qz);
    const __m256 hv = _mm256_set1_ps(h);
    const __m256 dx = _mm256_sub_ps(_mm256_sub_ps(px, qx), _mm256_mul_ps(hv, cx));
    const __m256 dy = _mm256_sub_ps(_mm256_sub_ps(py, qy), _mm256_mul_ps(hv, cy));
    const __m256 dz = _mm256_sub_ps(_mm256_sub_ps(pz, qz), _mm256_mul_ps(hv, cz));
    const __m256 dd = dotEight(nx, ny, nz, dx, dy, dz);
    const __m256 ex = _mm256_sub_ps(dx, _mm256_mul_ps(dd, nx)), ey = _mm256_sub_ps(dy, _mm256_mul_ps(dd, ny)),
                 ez = _mm256_sub_ps(dz, _mm256_mul_ps(dd, nz));
    const __m256 slip = _mm256_sqrt_ps(dotEight(ex, ey, ez, ex, ey, ez));
    const __m256 stick = _mm256_cmp_ps(slip, _mm256_mul_ps(muS, dn), _CMP_LE_OS);
    const __m256 undo = _mm256_blendv_ps(
        _mm256_min_ps(_mm256_div_ps(slideLimit, _mm256_blendv_ps(slip, one, stick)), one), one, stick);
    storeVec3Eight(x + i, _mm256_sub_ps(px, _mm256_mul_ps(undo, ex)), _mm256_sub_ps(py, _mm256_mul_ps(undo, ey)),
                   _mm256_sub_ps(pz, _mm256_mul_ps(undo, ez)));
    tx = _mm256_andnot_ps(stick, _mm256_mul_ps(tx, keep));
    ty = _mm256_andnot_ps(stick, _mm256_mul_ps(ty, keep));
    tz = _mm256_andnot_ps(stick, _mm256_mul_ps(tz, keep));
  }
  storeVec3Eight(v + i, _mm256_add_ps(_mm256_add_ps(cx, _mm256_mul_ps(vnNew, nx)), tx),
                 _mm256_add_ps(_mm256_add_ps(cy, _mm256_mul_ps(vnNew, ny)), ty),
                 _mm256_add_ps(_mm256_add_ps(cz, _mm256_mul_ps(vnNew, nz)), tz));
  _mm256_storeu_ps(contacts.normalDv.data() + i, _mm256_add_ps(zero, _mm256_max_ps(zero, _mm256_sub_ps(vnNew, vn))));
}
#endif

}  // namespace detail
#endif

/// The planes the response keeps friction's moves out of (docs/design.md §4, "Friction and the planes"): position
/// friction moves a vertex in its slots' tangent planes, toward where their solids carry it, after every contact
/// pass. With several slots, or a solid moving toward a plane the vertex does not touch, that can take it into the
/// plane: a vertex pinched under a body that falls onto the floor rides it below the floor. A vertex friction took
/// deeper into a plane than the thickness and than the contact passes left it goes back to the shallower of the two
/// (a pinch's compromise inside the thickness stays where the settle put it), and none stays below a plane's
/// surface, where a solid's push may leave it; one within `slack` of where it goes stays.
template <Scalar S> struct PlaneHold {
  const CompiledSolid<Plane, S>* planes = nullptr;
  std::size_t count = 0;
  S thickness = 0, slack = 0;
};

/// One vertex, at `before` ahead of the response and at x after it, out of one plane (PlaneHold); two dot products.
template <Scalar S>
DRAPE_ALWAYS_INLINE void holdOutOfPlane(Vec3<S>& x, const Vec3<S>& before, const Sdf<Plane, S>& plane, S thickness,
                                        S slack) {
  Vec3<S> n;
  const S gap = std::min(thickness, std::max(plane(before, n), S(0))) - plane(x, n);
  if (gap > slack) x = movedAlong(x, gap, n);
}

/// The contact vertices of [begin, end) out of one plane (the GPU's hold_planes.comp; respondContacts does the
/// same vertex by vertex).
template <Scalar S>
void holdOutOfPlane(Index begin, Index end, const ContactBuffer<S>& contacts, const Sdf<Plane, S>& plane,
                    S thickness, S slack, Vec3<S>* x, const Vec3<S>* before) {
  for (Index i = begin; i < end; ++i)
    if (contacts.live(i)) holdOutOfPlane(x[i], before[i], plane, thickness, slack);
}

/// The velocity split of the SDF collision paper (Fig 3) for every contact vertex of [begin, end) and each surface it
/// touches, relative to that solid: the approaching normal velocity is removed, a separating one is damped by
/// normalDamping, the tangential velocity is kept minus Coulomb friction. Friction acts on positions
/// (applyPositionFriction); a stuck vertex keeps no tangential velocity, a sliding one loses dynamicFriction * dn / h
/// of its tangential speed, the same as its position lost, so a slip never carries on as velocity what friction took
/// from the position (that mismatch makes a stuck cloth crawl downhill in stick-slip waves). kFriction false (no solid
/// of the scene has friction) compiles the friction out. `level` (simdLevelFor) lets float take eight or four
/// contact vertices at a time in SIMD lanes, with the same bits; Scalar keeps to the loop. With kHold each
/// contact vertex then goes out of `hold`'s planes (PlaneHold).
template <bool kFriction, Scalar S, bool kHold = false>
void respondContacts(Index begin, Index end, ContactBuffer<S>& contacts, Vec3<S>* x, const Vec3<S>* xPrev,
                     Vec3<S>* v, S h, S normalDamping, SimdLevel level = SimdLevel::Scalar,
                     const PlaneHold<S>& hold = {}) {
  const S invH = S(1) / h;
  Vec3<S> before[8];  // with kHold, the positions of the vertices in hand ahead of the response
  const auto keepBefore = [&](Index first, Index count) {
    if constexpr (kHold) std::copy(x + first, x + first + count, before);
  };
  const auto holdOut = [&](Index first, Index count) {
    if constexpr (kHold)
      for (std::size_t p = 0; p < hold.count; ++p)
        for (Index j = 0; j < count; ++j)
          holdOutOfPlane(x[first + j], before[j], hold.planes[p].sdf, hold.thickness, hold.slack);
  };
  for (Index i = begin; i < end; ++i) {
#if DRAPE_SSE2
    if constexpr (std::is_same_v<S, float>) {
      // Eight or four at a time where i is a multiple of that (so the same vertices whatever the threads'
      // shares) and each of them touches one surface.
      auto oneSurface = [&](Index first, Index count) {
        if (i % count != 0 || first + count > end) return false;
        for (Index j = first; j < first + count; ++j)
          if (!contacts.live(j) || contacts.slotCount[j] != 1) return false;
        return true;
      };
#if DRAPE_AVX2
      if (level == SimdLevel::Avx2 && oneSurface(i, 8)) {
        keepBefore(i, 8);
        detail::respondEight<kFriction>(i, contacts, x, xPrev, v, h, invH, normalDamping);
        holdOut(i, 8);
        i += 7;
        continue;
      }
#endif
      if (level != SimdLevel::Scalar && oneSurface(i, 4)) {
        keepBefore(i, 4);
        detail::respondFour<kFriction>(i, contacts, x, xPrev, v, h, invH, normalDamping);
        holdOut(i, 4);
        i += 3;
        continue;
      }
    }
#endif
    if (!contacts.live(i)) continue;
    keepBefore(i, 1);
    S dvnSum = 0;
    for (int k = 0; k < contacts.slotCount[i]; ++k) {
      const ContactSlot<S>& c = contacts.slots[i][k];
      const Vec3<S>& n = c.normal;
      const Vec3<S> vRel = v[i] - c.solidVelocity;
      const S vn = n.dot(vRel);
      Vec3<S> vt = vRel - vn * n;
      const S vnNew = vn < S(0) ? S(0) : vn * (S(1) - normalDamping);
      if constexpr (kFriction) {
        // The tangential speed is taken before the position's friction decides: the two square roots and
        // divisions then overlap instead of waiting on each other.
        const S speed = vt.norm();
        const S slow = c.dynamicFriction * c.correction * invH;
        const S keep = speed > slow ? (speed - slow) / speed : S(0);
        if (applyPositionFriction(c, x[i], xPrev[i], h))
          vt.setZero();
        else
          vt *= keep;
      }
      v[i] = c.solidVelocity + vnNew * n + vt;
      dvnSum += std::max(vnNew - vn, S(0));
    }
    // Answering a later surface can restore velocity into an earlier one. The velocity goes to the nearest
    // one that approaches none of the surfaces (in a wedge, that leaves only motion along its edge); where the
    // surfaces close in on each other faster than that allows, the least-squares compromise.
    if (contacts.slotCount[i] > 1) {
      const int count = contacts.slotCount[i];
      Vec3<S> normals[ContactBuffer<S>::kSlots];
      S bounds[ContactBuffer<S>::kSlots];
      for (int k = 0; k < count; ++k) {
        const ContactSlot<S>& c = contacts.slots[i][k];
        normals[k] = c.normal;
        bounds[k] = c.normal.dot(c.solidVelocity);
      }
      // A velocity may lose all of itself (a vertex driven into a wedge stops), but a surface closing in on
      // the cloth must not fling it sideways along a far meeting line.
      v[i] = nearestInHalfSpaces(normals, bounds, count, v[i], v[i], v[i].norm());
    }
    contacts.normalDv[i] = dvnSum;
    holdOut(i, 1);
  }
}

/// The in-solve method's friction: position-level Coulomb friction for every contact of the current solve pass,
/// on vertices [begin, end).
template <Scalar S>
void applyContactFriction(Index begin, Index end, const ContactBuffer<S>& contacts, Vec3<S>* x, const Vec3<S>* xPrev,
                          S h) {
  for (Index i = begin; i < end; ++i)
    if (contacts.live(i))
      for (int k = 0; k < contacts.slotCount[i]; ++k) applyPositionFriction(contacts.slots[i][k], x[i], xPrev[i], h);
}

/// Scratch for propagation rings. reach[r & 1][j] records that ring r reached vertex j in call `pass`; ring r
/// reads the other parity's entries and writes its own, so no entry is read and written in the same loop.
template <Scalar S> struct PropagationBuffer {
  std::uint64_t pass = 0;
  std::vector<std::uint64_t> reach[2];
  std::vector<Vec3<S>> normal;
  std::vector<S> normalSpeed, amount;

  void resize(Index n) {
    pass = 0;
    reach[0].assign(n, 0);
    reach[1].assign(n, 0);
    normal.resize(n);
    normalSpeed.resize(n);
    amount.resize(n);
  }
  /// Starts a propagation: the rings of earlier ones no longer count as reached.
  void beginPass() { ++pass; }
  std::uint64_t key(int ring) const { return pass * 16 + std::uint64_t(ring); }
  bool reachedThisPass(Index j) const { return reach[0][j] >= pass * 16 || reach[1][j] >= pass * 16; }
};

/// Spreads the contacts' normal velocity corrections to the vertices around them (the SDF collision paper): ring r gets
/// weight^r of the mean correction of its sources, along their mean normal, and only as much as removes its
/// own approach toward the solid (relative to the solids' speed along that normal), so a neighbour is never
/// pushed away (which would make the seam shake).
/// Each vertex gathers from its neighbours in the ring before (the GPU kernel gathers the same way), so the
/// sums have one order whatever the thread count. This is ring `ring` (1, 2, ...) for vertices [begin, end),
/// after buf.beginPass(); ring r + 1 starts when every vertex is done with ring r.
///
/// With kCurved (Settings::keepAngularMomentum, docs/design.md §4) a share follows the surface's curvature: the
/// sources' mean normal, on a line through the vertex it moves rather than through the sources, turns the cloth
/// on a curved solid (on a ball that line misses the centre by about the offset between the vertex and its
/// sources). So the normal is carried from the sources' mean position `x` to the vertex with the curvature
/// their positions and normals give, sum (d_i - mean d) . (n_i - mean n) / sum |d_i - mean d|^2 (exact on a
/// ball, 0 on a plane), where at least two sources are spread apart.
template <bool kCurved, bool kFirst, Scalar S>
void propagateRingAs(Index begin, Index end, int ring, const ContactBuffer<S>& contacts, PropagationBuffer<S>& buf,
                     const Adjacency& neighbours, Vec3<S>* v, const S* invMass, S weight,
                     [[maybe_unused]] const Vec3<S>* x) {
  const std::uint32_t mark = contacts.current;
  const std::uint64_t from = buf.key(ring - 1), to = buf.key(ring);
  const std::uint64_t* reachFrom = buf.reach[(ring - 1) & 1].data();
  std::uint64_t* reachTo = buf.reach[ring & 1].data();
  for (Index j = begin; j < end; ++j) {
    if (contacts.stamp[j] == mark || invMass[j] == S(0)) continue;
    if (!kFirst && buf.reachedThisPass(j)) continue;  // settled in an earlier ring
    Vec3<S> normalSum = Vec3<S>::Zero();
    // kCurved: the sources' offsets d = x_i - x_j and the sums the curvature is fitted from
    [[maybe_unused]] Vec3<S> offsetSum = Vec3<S>::Zero();
    [[maybe_unused]] S offsetNormal = 0, offsetSquared = 0;
    S speedSum = 0, amountSum = 0;
    int count = 0;
    for (const Index* it = neighbours.begin(j); it != neighbours.end(j); ++it) {
      const Index i = *it;
      Vec3<S> ni;
      if constexpr (kFirst) {
        if (contacts.stamp[i] != mark || contacts.normalDv[i] <= S(0)) continue;
        ni = contacts.normal(i);
        speedSum += ni.dot(contacts.solidVelocity(i));
        amountSum += contacts.normalDv[i];
      } else {
        if (reachFrom[i] != from || buf.amount[i] <= S(0)) continue;
        ni = buf.normal[i];
        speedSum += buf.normalSpeed[i];
        amountSum += buf.amount[i];
      }
      normalSum += ni;
      if constexpr (kCurved) {
        const Vec3<S> d = x[i] - x[j];
        offsetSum += d;
        offsetNormal += d.dot(ni);
        offsetSquared += d.squaredNorm();
      }
      ++count;
    }
    if (count == 0) continue;
    reachTo[j] = to;
    buf.amount[j] = 0;
    const S len = normalSum.norm();
    if (len <= S(0)) continue;
    const S inv = S(1) / S(count);
    Vec3<S> nj = normalSum / len;
    if constexpr (kCurved) {
      const Vec3<S> mean = offsetSum * inv;  // the sources' mean position, from the vertex
      const S spread = offsetSquared - S(count) * mean.squaredNorm();
      if (count > 1 && spread > S(1e-4) * offsetSquared) {
        const S curvature = (offsetNormal - mean.dot(normalSum)) / spread;
        const Vec3<S> carried = nj - curvature * (mean - nj.dot(mean) * nj);
        const S carriedLength = carried.norm();
        if (carriedLength > S(0) && std::isfinite(carriedLength)) nj = carried / carriedLength;
      }
    }
    // The solids' speed along nj: each source's own normal speed, summed as nj sums their normals. A spinning
    // solid's surface moves along itself, and its material velocity's tangential part, averaged over points
    // with different normals, is not a speed toward the cloth.
    const S vcn = speedSum / len;
    const S approach = -(nj.dot(v[j]) - vcn);
    const S give = weight * amountSum * inv;
    if (approach > S(0)) v[j] += std::min(approach, give) * nj;
    // The next ring sees this ring's share, not what it happened to need.
    buf.amount[j] = give;
    buf.normal[j] = nj;
    buf.normalSpeed[j] = vcn;
  }
}
template <bool kCurved = false, Scalar S>
void propagateRing(Index begin, Index end, int ring, const ContactBuffer<S>& contacts, PropagationBuffer<S>& buf,
                   const Adjacency& neighbours, Vec3<S>* v, const S* invMass, S weight,
                   const Vec3<S>* x = nullptr) {
  // The first ring gathers from the contacts, the others from the ring before: two loops, so that the test
  // is not made per neighbour.
  if (ring == 1)
    propagateRingAs<kCurved, true>(begin, end, ring, contacts, buf, neighbours, v, invMass, weight, x);
  else
    propagateRingAs<kCurved, false>(begin, end, ring, contacts, buf, neighbours, v, invMass, weight, x);
}

}  // namespace drape
