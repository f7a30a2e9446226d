#pragma once
// The coupling interface (docs/design.md §6): what the cloth solver needs from a rigid body, whoever simulates
// it. drape's own bodies (rigid/body.hpp) implement it; an application that already has a rigid-body engine
// wraps each of its bodies in a small class implementing it and hands those to the cloth solver instead.
//
// Per substep the cloth solver calls, for each coupled body (never per vertex): pose(), linearVelocity(),
// angularVelocity() to place and move the body's solid; then, for the contacts it resolved, applyForceAtPoint() with
// the reaction forces (the cloth-rigid coupling thesis, 5.2: the force on the particle, reversed). The engine
// integrates the accumulated force and torque in its next (sub)step and clears them. inverseMass() and
// inverseInertiaWorld() let a solver weigh a contact between cloth and body (0 for a kinematic body).

#include <drape/math.hpp>

#include <cstdint>

namespace drape {

class CoupledBody {
 public:
  virtual ~CoupledBody() = default;

  /// Pose of the body frame, whose origin is the centre of mass (m, world).
  virtual Pose pose() const = 0;
  /// Velocity of the centre of mass (m/s, world).
  virtual Eigen::Vector3d linearVelocity() const = 0;
  /// Angular velocity (rad/s, world axes).
  virtual Eigen::Vector3d angularVelocity() const = 0;
  /// 1 / mass (1/kg); 0 for a body that forces do not move (kinematic, static).
  virtual double inverseMass() const = 0;
  /// Inverse inertia tensor about the centre of mass in world axes (1/(kg m^2)); 0 where forces do not turn it.
  virtual Eigen::Matrix3d inverseInertiaWorld() const = 0;
  /// Adds a force (N, world) acting at a world point (m) to what the next integration applies: the force
  /// itself and the torque (point - centre of mass) x force. Throws drape::Error if either is not finite.
  virtual void applyForceAtPoint(const Eigen::Vector3d& force, const Eigen::Vector3d& point) = 0;

  /// Adds a force acting at the centre of mass and a torque (N m, world). The cloth solver sums its contacts into
  /// one such pair per body per substep. The default passes them on as three forces at points; an engine with
  /// a torque accumulator should override it.
  virtual void applyForceAndTorque(const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
    const Eigen::Vector3d c = pose().position;
    applyForceAtPoint(force, c);
    const double t = torque.norm();
    if (!(t > 0)) return;
    // A couple: f at c + u and -f at c, with u a unit vector normal to the torque and f = torque x u.
    const Eigen::Vector3d u = torque.unitOrthogonal();
    const Eigen::Vector3d f = torque.cross(u);
    applyForceAtPoint(f, c + u);
    applyForceAtPoint(-f, c);
  }

  /// Velocity of the body's material point at `point` (m/s): v + w x (point - centre of mass).
  Eigen::Vector3d velocityAt(const Eigen::Vector3d& point) const {
    return linearVelocity() + angularVelocity().cross(point - pose().position);
  }
};

/// A cloth vertex pinched in the last substep between coupled body `body` and a surface facing it, a fixed
/// solid's (`other` -1) or another coupled body's (`other`, by the higher index's record only), as a spacer for a
/// rigid world's next substep (RigidWorld::addSpacer, which stepCoupled calls): the body's surface beside the
/// vertex stays constants::kSpacerGap thicknesses (nearly the cloth's two) off the other surface along that
/// surface's normal. Bodies are numbered as bodyForces() lists them. Taken from the two contacts' planes: `onBody`
/// on the body's surface, in its frame where the cloth met it; `onOther` that far out of the other surface, in the
/// other body's frame (world for a fixed solid); `normal` the other surface's (world). docs/design.md §6.
struct Spacer {
  std::int32_t vertex = 0;
  std::int32_t body = -1, other = -1;
  std::int32_t slot = 0;  ///< the vertex's contact slot of the body: a vertex on two faces of a box has two
  Eigen::Vector3d onBody = Eigen::Vector3d::Zero(), onOther = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

}  // namespace drape
