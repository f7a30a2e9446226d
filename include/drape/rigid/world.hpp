#pragma once
// A world of rigid bodies stepped in substeps, like the cloth (docs/design.md §1 and §7). Needs libccd
// (link drape::rigid).
//
// Contacts are resolved with extended position-based dynamics (XPBD) for rigid bodies, after Mueller et al.
// 2020, "Detailed Rigid Body Simulation with Extended Position Based Dynamics": per substep, positional
// non-penetration, then a velocity pass for restitution and friction. It is the same substep loop as the
// cloth's, so the cloth solver can interleave the two substep by substep, and with small substeps it keeps
// resting contact and stacks still without warm starting or many iterations, which sequential impulses need.
// Where drape departs from that paper (friction, steps 5 and 6), step 6 gives the measured reason.
//
// Each substep, in this order:
//   1. integrate: v += h (g + F / m); w by Euler's equations (body frame, implicit midpoint: a torque-free body
//      keeps its kinetic energy and the magnitude of its angular momentum); x += h v; q = q exp(h w_mid / 2).
//      Kinematic bodies move by their given velocities.
//   2. detect: bounding boxes, sweep and prune, libccd MPR per overlapping pair and per body near the ground,
//      a manifold of up to four points per pair (narrowphase.hpp).
//   3. solve positions (iterationCount passes): per point, push the bodies apart along the normal (XPBD with
//      zero compliance, generalised inverse masses with the rotational terms).
//   4. velocities from positions: v = v_integrated + (x - x_integrated) / h, and the same for the rotation.
//   5. solve velocities: restitution per point (normal velocity set to -e times the one before the solve;
//      e = 0 below 2 |g| h so resting contact does not bounce); Coulomb friction per manifold at its centre,
//      and about its normal (twist): stop the sliding if that takes at most staticFriction times the
//      manifold's normal impulse, else brake with dynamicFriction times it.
//   6. hold: a manifold that stuck has its centre's tangential displacement over the substep undone (bodies
//      translated, velocities untouched), so a body that should stick does not creep by h^2 F / m per
//      substep. The paper's positional static friction per point made stacks of three tremble at cm/s.

#include <drape/rigid/body.hpp>
#include <drape/rigid/broadphase.hpp>
#include <drape/rigid/narrowphase.hpp>

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace drape {

struct RigidSettings {
  int subStepCount = 10;                 ///< substeps per step(dt); h = dt / subStepCount
  int iterationCount = 1;                ///< passes of the position solve over the contacts per substep
  Eigen::Vector3d gravity{0, 0, -9.81};  ///< m/s^2
  bool ground = true;                    ///< a ground plane z = groundHeight, normal +z
  double groundHeight = 0;               ///< m
  double groundStaticFriction = 0.5;     ///< combined with a body's as sqrt(a b)
  double groundDynamicFriction = 0.5;    ///< combined with a body's as sqrt(a b)
  double groundRestitution = 0;          ///< combined with a body's as max(a, b)
  /// m: manifold points this far apart are kept with the overlapping ones; they push only once they touch
  /// within the substep, which keeps a landing face from hitting on one corner first.
  double contactMargin = 0.01;

  void validate() const {
    using detail::require;
    require(subStepCount >= 1 && subStepCount <= 10000,
            "subStepCount must be in [1, 10000] (got " + std::to_string(subStepCount) + ")");
    require(iterationCount >= 1 && iterationCount <= 1000,
            "iterationCount must be in [1, 1000] (got " + std::to_string(iterationCount) + ")");
    require(detail::allFinite(gravity), "gravity must be finite");
    detail::requireFinite(groundHeight, "groundHeight");
    detail::requireRange(groundStaticFriction, 0, 1e3, "groundStaticFriction");
    detail::requireRange(groundDynamicFriction, 0, 1e3, "groundDynamicFriction");
    detail::requireRange(groundRestitution, 0, 1, "groundRestitution");
    detail::requireRange(contactMargin, 0, 1, "contactMargin");
  }
};

/// A contact manifold of the last substep, between bodies `first` and `second` (`first` is kGround for the
/// ground). The normal points from first to second.
struct RigidContact {
  struct Point {
    Eigen::Vector3d localFirst = Eigen::Vector3d::Zero();   ///< on `first`, its body frame (world for the ground)
    Eigen::Vector3d localSecond = Eigen::Vector3d::Zero();  ///< on `second`, its body frame
    double depth = 0;             ///< m, at detection
    double lambdaNormal = 0;      ///< kg m: normal position multiplier of this substep (lambda / h^2 is a force)
    double normalVelocityBefore = 0;  ///< m/s, relative normal velocity before the solve (> 0 separating)
  };
  int first = -1;
  int second = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int count = 0;
  std::array<Point, 4> points;
  double staticFriction = 0;
  double dynamicFriction = 0;
  double restitution = 0;
  double lambdaTangent = 0;  ///< kg m: static friction multiplier of the manifold in this substep
  bool sticking = false;     ///< static friction held it in this substep
  bool spacer = false;       ///< a one-point contact given from outside (RigidWorld::addSpacer)
};

namespace detail {

/// The rotation by |r| about r / |r|.
inline Eigen::Quaterniond expMap(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  if (angle == 0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, r / angle));
}
/// The rotation vector of q (the shorter way round).
inline Eigen::Vector3d logMap(Eigen::Quaterniond q) {
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const double s = q.vec().norm();
  if (s == 0) return Eigen::Vector3d::Zero();
  return q.vec() * (2 * std::atan2(s, q.w()) / s);
}
/// The matrix of the cross product v x.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace detail

class RigidWorld {
 public:
  static constexpr int kGround = -1;

  explicit RigidWorld(const RigidSettings& settings = {}) {
    settings.validate();
    settings_ = settings;
  }

  const RigidSettings& settings() const { return settings_; }
  void setSettings(const RigidSettings& settings) {
    settings.validate();
    settings_ = settings;
  }

  /// Adds a body and returns its index. References to bodies stay valid as bodies are added.
  int add(const BodyDesc& desc) {
    const int index = static_cast<int>(bodies_.size());
    bodies_.emplace_back(desc, "body " + std::to_string(index));
    return index;
  }

  int bodyCount() const { return static_cast<int>(bodies_.size()); }
  RigidBody& body(int i) { return bodies_.at(static_cast<std::size_t>(i)); }
  const RigidBody& body(int i) const { return bodies_.at(static_cast<std::size_t>(i)); }

  /// Advances by dt seconds in settings().subStepCount substeps. Forces and torques applied before the call
  /// act over the whole step, then are cleared.
  void step(double dt) {
    detail::require(std::isfinite(dt) && dt > 0, "step: dt must be positive and finite (got " + detail::formatNumber(dt) + ")");
    validateBodies();
    const double h = dt / settings_.subStepCount;
    for (int s = 0; s < settings_.subStepCount; ++s) advance(h);
    for (auto& b : bodies_) b.clearForces();
  }

  /// Advances by one substep of h seconds. Forces and torques applied before the call act over it, then are
  /// cleared: a cloth solver applies its contact forces every substep, then calls this.
  void subStep(double h) {
    detail::require(std::isfinite(h) && h > 0,
                    [&] { return "subStep: h must be positive and finite (got " + detail::formatNumber(h) + ")"; });
    validateBodies();
    advance(h);
    for (auto& b : bodies_) b.clearForces();
  }

  /// Contact manifolds found in the last substep, with the multipliers of its solve.
  const std::vector<RigidContact>& contacts() const { return contacts_; }

  /// Substeps a spacer is kept for after it was last given (addSpacer).
  static constexpr int kSpacerLife = 10;

  /// Something thin held between body `second` and body `first` (or the fixed world, kGround): a one-point
  /// contact, solved with the world's own from the next substep on, that keeps the point `onSecond` of `second`
  /// from coming closer than the point `onFirst` of `first` along `normal` (unit, world, from first to second).
  /// Points are in their body's own frame (the world's for kGround). Given again under the same `tag` (with the
  /// same pair) it replaces the last; else it is kept for kSpacerLife substeps while `onSecond` stays within
  /// `reach` of `onFirst`, and pushes only where the bodies come back into it, as the world's own contacts
  /// within their margin do. A cloth pinched between a body and the floor passes its pinches this way
  /// (stepCoupled, the cloth vertex as the tag), so that another body pressing on the first, which only the
  /// world's solve sees, cannot drive it through the cloth (docs/design.md §6). No friction: the cloth's own
  /// pinch support carries it. Throws drape::Error, before any change, for a bad index, a `second` that is not
  /// dynamic, a non-finite point or normal, or a reach that is not positive and finite.
  void addSpacer(std::int64_t tag, int first, const Eigen::Vector3d& onFirst, int second,
                 const Eigen::Vector3d& onSecond, const Eigen::Vector3d& normal, double reach) {
    using detail::require;
    require(first == kGround || (first >= 0 && first < bodyCount()),
            [&] { return "addSpacer: first body index " + std::to_string(first) + " out of range"; });
    require(second >= 0 && second < bodyCount() && second != first,
            [&] { return "addSpacer: second body index " + std::to_string(second) + " out of range or first"; });
    require(bodies_[std::size_t(second)].isDynamic(),
            [&] { return "addSpacer: body " + std::to_string(second) + " is not dynamic"; });
    require(detail::allFinite(onFirst) && detail::allFinite(onSecond), "addSpacer: points must be finite");
    require(detail::allFinite(normal) && std::abs(normal.norm() - 1) <= 1e-3, "addSpacer: normal must be unit");
    require(std::isfinite(reach) && reach > 0,
            [&] { return "addSpacer: reach must be positive and finite (got " + detail::formatNumber(reach) + ")"; });
    KeptSpacer& k = spacers_[{first, second, tag}];
    k.onFirst = onFirst;
    k.onSecond = onSecond;
    k.normal = normal.normalized();
    k.reach = reach;
    k.age = 0;
  }
  /// The spacers held (addSpacer), by first, second and tag; a failed coupled step puts them back.
  struct KeptSpacer {
    Eigen::Vector3d onFirst, onSecond, normal;
    double reach = 0;
    int age = 0;  ///< substeps since it was last given
  };
  using Spacers = std::map<std::tuple<int, int, std::int64_t>, KeptSpacer>;
  const Spacers& spacers() const { return spacers_; }
  void restoreSpacers(Spacers spacers) { spacers_ = std::move(spacers); }

  /// Total linear momentum of the dynamic bodies (kg m/s).
  Eigen::Vector3d linearMomentum() const {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (const auto& b : bodies_)
      if (b.isDynamic()) p += b.massProperties().mass * b.state.linearVelocity;
    return p;
  }
  /// Total angular momentum of the dynamic bodies about `point` (kg m^2/s).
  Eigen::Vector3d angularMomentum(const Eigen::Vector3d& point = Eigen::Vector3d::Zero()) const {
    Eigen::Vector3d l = Eigen::Vector3d::Zero();
    for (const auto& b : bodies_) {
      if (!b.isDynamic()) continue;
      const Eigen::Matrix3d R = b.state.pose.rotation.toRotationMatrix();
      l += (b.state.pose.position - point).cross(b.massProperties().mass * b.state.linearVelocity) +
           R * b.massProperties().inertia * R.transpose() * b.state.angularVelocity;
    }
    return l;
  }
  /// Total kinetic energy of the dynamic bodies (J).
  double kineticEnergy() const {
    double e = 0;
    for (const auto& b : bodies_) {
      if (!b.isDynamic()) continue;
      const Eigen::Vector3d wb = b.state.pose.rotation.conjugate() * b.state.angularVelocity;
      e += 0.5 * b.massProperties().mass * b.state.linearVelocity.squaredNorm() +
           0.5 * wb.dot(b.massProperties().inertia * wb);
    }
    return e;
  }

 private:
  struct Scratch {  // per body, per substep
    Eigen::Vector3d previousPosition, predictedPosition, integratedVelocity, integratedAngularVelocity;
    Eigen::Quaterniond previousRotation, predictedRotation;
    Eigen::Matrix3d invInertiaWorld;  // at the start of the solve
  };

  void validateBodies() const {
    for (std::size_t i = 0; i < bodies_.size(); ++i) bodies_[i].validateState([i] { return "body " + std::to_string(i); });
  }

  void integrate(double h) {
    scratch_.resize(bodies_.size());
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      RigidBody& b = bodies_[i];
      Scratch& s = scratch_[i];
      BodyState& st = b.state;
      s.previousPosition = st.pose.position;
      s.previousRotation = st.pose.rotation;
      if (b.isDynamic()) {
        const MassProperties& m = b.massProperties();
        st.linearVelocity += h * (settings_.gravity + b.accumulatedForce() / m.mass);
        // Euler's equations in the body frame by the implicit midpoint rule, I (w1 - w0) + h wm x (I wm) = h tau
        // with wm = (w0 + w1) / 2, solved by Newton's method from the explicit guess. The midpoint rule keeps
        // the quadratic invariants w.Iw and |Iw| of the torque-free motion; explicit Euler would gain energy.
        const Eigen::Matrix3d R = st.pose.rotation.toRotationMatrix();
        const Eigen::Matrix3d& I = m.inertia;
        const Eigen::Vector3d w0 = R.transpose() * st.angularVelocity;
        const Eigen::Vector3d tau = R.transpose() * b.accumulatedTorque();
        Eigen::Vector3d w1 = w0 + h * b.inverseInertiaBody() * (tau - w0.cross(I * w0));
        for (int it = 0; it < 4; ++it) {
          const Eigen::Vector3d wm = 0.5 * (w0 + w1), Iwm = I * wm;
          const Eigen::Vector3d f = I * (w1 - w0) + h * wm.cross(Iwm) - h * tau;
          if (f.norm() <= 1e-15 * (I * w1).norm()) break;
          const Eigen::Matrix3d J = I + 0.5 * h * (detail::skew(wm) * I - detail::skew(Iwm));
          w1 -= J.inverse() * f;
        }
        st.pose.position += h * st.linearVelocity;
        st.pose.rotation = (st.pose.rotation * detail::expMap(0.5 * h * (w0 + w1))).normalized();
        st.angularVelocity = st.pose.rotation * w1;
      } else {
        st.pose.position += h * st.linearVelocity;
        st.pose.rotation = (detail::expMap(h * st.angularVelocity) * st.pose.rotation).normalized();
      }
      s.predictedPosition = st.pose.position;
      s.predictedRotation = st.pose.rotation;
      s.integratedVelocity = st.linearVelocity;
      s.integratedAngularVelocity = st.angularVelocity;
      s.invInertiaWorld = b.inverseInertiaWorld();
    }
  }

  void detect() {
    const int n = bodyCount();
    contacts_.clear();
    boxes_.resize(n);
    rotations_.resize(n);
    for (int i = 0; i < n; ++i) {
      const RigidBody& b = bodies_[i];
      rotations_[i] = b.state.pose.rotation.toRotationMatrix();
      boxes_[i] = detail::worldAabb(b.shape(), rotations_[i], b.state.pose.position);
    }
    broadPhase_.findPairs(boxes_, pairs_, [&](int i, int j) { return !bodies_[i].isDynamic() && !bodies_[j].isDynamic(); });
    Manifold m;
    const double margin = settings_.contactMargin;
    if (settings_.ground) {
      for (int i = 0; i < n; ++i) {
        const RigidBody& b = bodies_[i];
        if (!b.isDynamic() || boxes_[i].min.z() > settings_.groundHeight) continue;
        if (!collideGround(b.shape(), rotations_[i], b.state.pose.position, settings_.groundHeight, margin, m)) continue;
        addContact(kGround, i, m, settings_.groundStaticFriction, settings_.groundDynamicFriction,
                   settings_.groundRestitution);
      }
    }
    for (const auto& [i, j] : pairs_) {
      const RigidBody& a = bodies_[i];
      const RigidBody& b = bodies_[j];
      if (!collide(a.shape(), rotations_[i], a.state.pose.position, b.shape(), rotations_[j], b.state.pose.position,
                   margin, m))
        continue;
      addContact(i, j, m, a.staticFriction, a.dynamicFriction, a.restitution);
    }
    // After the world's own contacts: with one pass, a body pressed by another is then lifted off the spacer
    // last, and the pair's overlap is the next substep's.
    for (auto s = spacers_.begin(); s != spacers_.end();) {
      const int first = std::get<0>(s->first), second = std::get<1>(s->first);
      KeptSpacer& k = s->second;
      const Eigen::Vector3d a = toWorld(first, k.onFirst), d = toWorld(second, k.onSecond) - a;
      const double along = d.dot(k.normal);
      if (k.age++ >= kSpacerLife || along > k.reach || (d - along * k.normal).norm() > k.reach) {
        s = spacers_.erase(s);
        continue;
      }
      RigidContact c;
      c.first = first;
      c.second = second;
      c.normal = k.normal;
      c.count = 1;
      c.spacer = true;
      c.points[0].localFirst = k.onFirst;
      c.points[0].localSecond = k.onSecond;
      c.points[0].depth = -along;
      contacts_.push_back(c);
      ++s;
    }
  }

  void addContact(int first, int second, const Manifold& m, double staticFriction, double dynamicFriction,
                  double restitution) {
    const RigidBody& b = bodies_[second];
    RigidContact c;
    c.first = first;
    c.second = second;
    c.normal = m.normal;
    c.count = m.count;
    c.staticFriction = std::sqrt(staticFriction * b.staticFriction);
    c.dynamicFriction = std::sqrt(dynamicFriction * b.dynamicFriction);
    c.restitution = std::max(restitution, b.restitution);
    for (int k = 0; k < m.count; ++k) {
      RigidContact::Point& p = c.points[k];
      p.localFirst = toLocal(first, m.points[k].pointA);
      p.localSecond = toLocal(second, m.points[k].pointB);
      p.depth = m.points[k].depth;
      p.normalVelocityBefore =
          c.normal.dot(velocityAt(second, m.points[k].pointB) - velocityAt(first, m.points[k].pointA));
    }
    contacts_.push_back(c);
  }

  // --- Per-body helpers; index kGround is the static ground, whose local frame is the world. ----------------
  bool movable(int i) const { return i != kGround && bodies_[i].isDynamic(); }
  Eigen::Vector3d toLocal(int i, const Eigen::Vector3d& p) const {
    if (i == kGround) return p;
    const Pose& pose = bodies_[i].state.pose;
    return pose.rotation.conjugate() * (p - pose.position);
  }
  Eigen::Vector3d toWorld(int i, const Eigen::Vector3d& local) const {
    return i == kGround ? local : bodies_[i].state.pose.apply(local);
  }
  Eigen::Vector3d previousWorld(int i, const Eigen::Vector3d& local) const {
    return i == kGround ? local : scratch_[i].previousRotation * local + scratch_[i].previousPosition;
  }
  Eigen::Vector3d velocityAt(int i, const Eigen::Vector3d& p) const {
    if (i == kGround) return Eigen::Vector3d::Zero();
    const BodyState& s = bodies_[i].state;
    return s.linearVelocity + s.angularVelocity.cross(p - s.pose.position);
  }
  /// Generalised inverse mass of body i at world point p in unit direction d.
  double inverseMassAt(int i, const Eigen::Vector3d& p, const Eigen::Vector3d& d) const {
    if (!movable(i)) return 0;
    const Eigen::Vector3d rn = (p - bodies_[i].state.pose.position).cross(d);
    return bodies_[i].inverseMass() + rn.dot(scratch_[i].invInertiaWorld * rn);
  }
  /// Moves body i by a positional impulse P (kg m) at world point p.
  void applyPositionImpulse(int i, const Eigen::Vector3d& P, const Eigen::Vector3d& p) {
    if (!movable(i)) return;
    Pose& pose = bodies_[i].state.pose;
    const Eigen::Vector3d dw = scratch_[i].invInertiaWorld * (p - pose.position).cross(P);
    pose.position += P * bodies_[i].inverseMass();
    Eigen::Quaterniond dq(0, 0.5 * dw.x(), 0.5 * dw.y(), 0.5 * dw.z());
    pose.rotation.coeffs() += (dq * pose.rotation).coeffs();
    pose.rotation.normalize();
  }
  /// Changes body i's velocities by an impulse J (kg m/s) at world point p.
  void applyVelocityImpulse(int i, const Eigen::Vector3d& J, const Eigen::Vector3d& p) {
    if (!movable(i)) return;
    BodyState& s = bodies_[i].state;
    s.linearVelocity += J * bodies_[i].inverseMass();
    s.angularVelocity += scratch_[i].invInertiaWorld * (p - s.pose.position).cross(J);
  }

  void solvePositions() {
    for (auto& c : contacts_)
      for (int k = 0; k < c.count; ++k) c.points[k].lambdaNormal = 0;
    for (int it = 0; it < settings_.iterationCount; ++it)
      for (auto& c : contacts_) solveContactPositions(c);
  }

  void solveContactPositions(RigidContact& c) {
    const Eigen::Vector3d& n = c.normal;
    for (int k = 0; k < c.count; ++k) {
      RigidContact::Point& q = c.points[k];
      const Eigen::Vector3d pa = toWorld(c.first, q.localFirst), pb = toWorld(c.second, q.localSecond);
      const double d = (pa - pb).dot(n);
      if (d <= 0) continue;
      const double w = inverseMassAt(c.first, pa, n) + inverseMassAt(c.second, pb, n);
      if (w <= 0) continue;
      const double dl = d / w;
      q.lambdaNormal += dl;
      applyPositionImpulse(c.first, -dl * n, pa);
      applyPositionImpulse(c.second, dl * n, pb);
    }
  }

  void updateVelocities(double h) {
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      RigidBody& b = bodies_[i];
      if (!b.isDynamic()) continue;
      const Scratch& s = scratch_[i];
      b.state.linearVelocity = s.integratedVelocity + (b.state.pose.position - s.predictedPosition) / h;
      b.state.angularVelocity =
          s.integratedAngularVelocity + detail::logMap(b.state.pose.rotation * s.predictedRotation.conjugate()) / h;
    }
  }

  /// Velocity pass, per manifold: restitution per point, then friction at the manifold's centre (its points
  /// weighted by their normal multipliers) with the manifold's normal impulse, plus torsional friction about
  /// the normal (lever: the points' mean distance from the centre). One friction impulse per manifold instead
  /// of one per point: per point, a corner with a small share of the load slips while its neighbours stick,
  /// and the box creeps. Each impulse acts on both bodies at one point, so momentum and angular momentum are
  /// exchanged, not made.
  void solveVelocities(double h) {
    const double restingSpeed = 2 * settings_.gravity.norm() * h;
    for (auto& c : contacts_) {
      const Eigen::Vector3d& n = c.normal;
      c.sticking = false;
      double lambdaN = 0, velocityImpulse = 0;
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (int k = 0; k < c.count; ++k) {
        const RigidContact::Point& q = c.points[k];
        if (q.lambdaNormal <= 0) continue;
        const Eigen::Vector3d m = 0.5 * (toWorld(c.first, q.localFirst) + toWorld(c.second, q.localSecond));
        lambdaN += q.lambdaNormal;
        centre += q.lambdaNormal * m;
        const Eigen::Vector3d v = velocityAt(c.second, m) - velocityAt(c.first, m);
        const double e = std::abs(q.normalVelocityBefore) <= restingSpeed ? 0.0 : c.restitution;
        const double target = std::max(-e * q.normalVelocityBefore, 0.0);
        const double w = inverseMassAt(c.first, m, n) + inverseMassAt(c.second, m, n);
        if (w <= 0) continue;
        const double impulse = (target - v.dot(n)) / w;
        velocityImpulse += impulse;
        applyVelocityImpulse(c.first, -impulse * n, m);
        applyVelocityImpulse(c.second, impulse * n, m);
      }
      if (lambdaN <= 0) continue;
      centre /= lambdaN;
      // The substep's normal impulse: the position pass's lambda / h and what the velocity pass added.
      const double normalImpulse = std::max(lambdaN / h + velocityImpulse, 0.0);

      // Sliding at the centre.
      const Eigen::Vector3d v = velocityAt(c.second, centre) - velocityAt(c.first, centre);
      Eigen::Vector3d vt = v - v.dot(n) * n;
      const double speedT = vt.norm();
      bool stuck = true;
      if (speedT > 0) {
        vt /= speedT;
        const double w = inverseMassAt(c.first, centre, vt) + inverseMassAt(c.second, centre, vt);
        if (w > 0) {
          const double stop = speedT / w;
          stuck = stop <= c.staticFriction * normalImpulse;
          const double impulse = stuck ? stop : std::min(stop, c.dynamicFriction * normalImpulse);
          applyVelocityImpulse(c.first, impulse * vt, centre);
          applyVelocityImpulse(c.second, -impulse * vt, centre);
        }
      }
      // Twisting about the normal.
      if (c.count > 1) {
        double lever = 0;
        for (int k = 0; k < c.count; ++k) {
          const RigidContact::Point& q = c.points[k];
          if (q.lambdaNormal <= 0) continue;
          const Eigen::Vector3d r = toWorld(c.second, q.localSecond) - centre;
          lever += q.lambdaNormal * (r - r.dot(n) * n).norm();
        }
        lever /= lambdaN;
        const double spin = n.dot(angularVelocityOf(c.second) - angularVelocityOf(c.first));
        const double k = n.dot(inverseInertiaOf(c.first) * n) + n.dot(inverseInertiaOf(c.second) * n);
        if (spin != 0 && k > 0) {
          const double stop = std::abs(spin) / k;
          const bool held = stop <= c.staticFriction * normalImpulse * lever;
          stuck = stuck && held;
          const double impulse = std::copysign(held ? stop : std::min(stop, c.dynamicFriction * normalImpulse * lever), spin);
          applyAngularImpulse(c.first, impulse * n);
          applyAngularImpulse(c.second, -impulse * n);
        }
      }
      c.sticking = stuck;
    }
  }

  Eigen::Vector3d angularVelocityOf(int i) const {
    return i == kGround ? Eigen::Vector3d::Zero() : bodies_[i].state.angularVelocity;
  }
  Eigen::Matrix3d inverseInertiaOf(int i) const {
    return movable(i) ? scratch_[i].invInertiaWorld : Eigen::Matrix3d::Zero();
  }
  void applyAngularImpulse(int i, const Eigen::Vector3d& L) {
    if (movable(i)) bodies_[i].state.angularVelocity += scratch_[i].invInertiaWorld * L;
  }

  /// Static friction's position part: where the velocity pass found a manifold sticking, the relative
  /// tangential displacement of its centre (its points weighted by their normal multipliers) over the substep
  /// is undone too, so that a body that should stick does not creep by h times its tangential velocity gain
  /// per substep. Positions only, and by translation only: the
  /// velocities were settled by the velocity pass, and corrections at the contact points that also turned
  /// the bodies (Mueller et al.'s positional static friction) tilted them and made stacks tremble.
  void holdStickingContacts() {
    for (auto& c : contacts_) {
      c.lambdaTangent = 0;
      double lambdaN = 0;
      const bool sticking = c.sticking;
      Eigen::Vector3d la = Eigen::Vector3d::Zero(), lb = Eigen::Vector3d::Zero();
      for (int k = 0; k < c.count; ++k) {
        const RigidContact::Point& q = c.points[k];
        if (q.lambdaNormal <= 0) continue;
        lambdaN += q.lambdaNormal;
        la += q.lambdaNormal * q.localFirst, lb += q.lambdaNormal * q.localSecond;
      }
      if (!sticking || lambdaN <= 0) continue;
      la /= lambdaN, lb /= lambdaN;
      const Eigen::Vector3d& n = c.normal;
      const Eigen::Vector3d dp = (toWorld(c.first, la) - previousWorld(c.first, la)) -
                                 (toWorld(c.second, lb) - previousWorld(c.second, lb));
      const Eigen::Vector3d dt = dp - dp.dot(n) * n;
      const double wa = movable(c.first) ? bodies_[c.first].inverseMass() : 0;
      const double wb = movable(c.second) ? bodies_[c.second].inverseMass() : 0;
      if (wa + wb <= 0) continue;
      // The velocity pass decided that the manifold sticks, with the generalised masses at its centre; the
      // displacement undone here includes the tipping of the bodies about that centre, which the cone of the
      // translation alone (m |dt| <= mu lambda) would wrongly count as slip.
      c.lambdaTangent = dt.norm() / (wa + wb);
      if (wa > 0) bodies_[c.first].state.pose.position -= dt * (wa / (wa + wb));
      if (wb > 0) bodies_[c.second].state.pose.position += dt * (wb / (wa + wb));
    }
  }

  void advance(double h) {
    integrate(h);
    detect();
    solvePositions();
    updateVelocities(h);
    solveVelocities(h);
    holdStickingContacts();
  }

  RigidSettings settings_{};
  std::deque<RigidBody> bodies_;
  std::vector<Scratch> scratch_;
  std::vector<Aabb> boxes_;
  std::vector<Eigen::Matrix3d> rotations_;
  std::vector<std::pair<int, int>> pairs_;
  std::vector<RigidContact> contacts_;
  Spacers spacers_;
  SweepAndPrune broadPhase_;
};

}  // namespace drape
