#pragma once
// A rigid body: shape, mass properties, pose and velocities, contact material. drape's implementation of the
// coupling interface.

#include <drape/coupling/body.hpp>
#include <drape/rigid/shapes.hpp>

#include <optional>
#include <string>

namespace drape {

enum class BodyMotion {
  Dynamic,    ///< moved by gravity, forces and contacts
  Kinematic,  ///< moved by its given velocities only; infinite mass for contacts (velocity 0 makes it static)
};

/// What a body is made of and where it starts. The body frame's origin is the shape's centre of mass.
struct BodyDesc {
  RigidShape shape = Sphere{};
  Pose pose{};
  Eigen::Vector3d linearVelocity = Eigen::Vector3d::Zero();   ///< m/s, of the centre of mass
  Eigen::Vector3d angularVelocity = Eigen::Vector3d::Zero();  ///< rad/s, world axes
  BodyMotion motion = BodyMotion::Dynamic;
  double density = 1000;                 ///< kg/m^3, used when `mass` is empty
  std::optional<MassProperties> mass{};  ///< overrides the density (inertia in body axes)
  double staticFriction = 0.5;           ///< Coulomb coefficient while sticking (combined as sqrt(a b))
  double dynamicFriction = 0.5;          ///< Coulomb coefficient while sliding (combined as sqrt(a b))
  double restitution = 0;                ///< normal velocity kept after an impact, in [0, 1] (combined as max)
};

/// Pose and velocities of a body.
struct BodyState {
  Pose pose{};                                                ///< of the centre of mass frame
  Eigen::Vector3d linearVelocity = Eigen::Vector3d::Zero();   ///< m/s, of the centre of mass
  Eigen::Vector3d angularVelocity = Eigen::Vector3d::Zero();  ///< rad/s, world axes
};

class RigidBody : public CoupledBody {
 public:
  /// Throws drape::Error naming the first bad field of `desc` (prefixed by `name`).
  explicit RigidBody(const BodyDesc& desc, const std::string& name = "body") : shape_(desc.shape) {
    using detail::require;
    detail::validateRigidShape(desc.shape);
    const MassProperties mass = desc.mass ? *desc.mass : massFromDensity(desc.shape, desc.density);
    detail::validateMassProperties(mass, name);
    state.pose = desc.pose;
    state.linearVelocity = desc.linearVelocity;
    state.angularVelocity = desc.angularVelocity;
    motion = desc.motion;
    staticFriction = desc.staticFriction;
    dynamicFriction = desc.dynamicFriction;
    restitution = desc.restitution;
    validateState(name);
    mass_ = mass;
    invInertiaBody_ = mass.inertia.inverse();
    boundingRadius_ = detail::boundingRadius(shape_);
  }

  // --- Public so an application can set them; the world checks them before every substep. -----------------
  BodyState state{};
  BodyMotion motion = BodyMotion::Dynamic;
  double staticFriction = 0.5;
  double dynamicFriction = 0.5;
  double restitution = 0;

  const RigidShape& shape() const { return shape_; }
  const MassProperties& massProperties() const { return mass_; }
  const Eigen::Matrix3d& inverseInertiaBody() const { return invInertiaBody_; }
  double boundingRadius() const { return boundingRadius_; }
  bool isDynamic() const { return motion == BodyMotion::Dynamic; }

  /// Force (N) and torque about the centre of mass (N m), world, accumulated since the last integration.
  const Eigen::Vector3d& accumulatedForce() const { return force_; }
  const Eigen::Vector3d& accumulatedTorque() const { return torque_; }
  void clearForces() { force_.setZero(), torque_.setZero(); }
  /// Adds a torque (N m, world) to the next integration.
  void applyTorque(const Eigen::Vector3d& torque) {
    detail::require(detail::allFinite(torque), "applyTorque: torque must be finite");
    torque_ += torque;
  }

  // --- CoupledBody -------------------------------------------------------------------------------------------
  Pose pose() const override { return state.pose; }
  Eigen::Vector3d linearVelocity() const override { return state.linearVelocity; }
  Eigen::Vector3d angularVelocity() const override { return state.angularVelocity; }
  double inverseMass() const override { return isDynamic() ? 1 / mass_.mass : 0; }
  Eigen::Matrix3d inverseInertiaWorld() const override {
    if (!isDynamic()) return Eigen::Matrix3d::Zero();
    const Eigen::Matrix3d R = state.pose.rotation.toRotationMatrix();
    return R * invInertiaBody_ * R.transpose();
  }
  void applyForceAndTorque(const Eigen::Vector3d& force, const Eigen::Vector3d& torque) override {
    detail::require(detail::allFinite(force) && detail::allFinite(torque),
                    "applyForceAndTorque: force and torque must be finite");
    force_ += force;
    torque_ += torque;
  }
  void applyForceAtPoint(const Eigen::Vector3d& force, const Eigen::Vector3d& point) override {
    detail::require(detail::allFinite(force), "applyForceAtPoint: force must be finite");
    detail::require(detail::allFinite(point), "applyForceAtPoint: point must be finite");
    force_ += force;
    torque_ += (point - state.pose.position).cross(force);
  }

  /// Throws drape::Error if the pose, velocities or material are not usable (non-finite, non-unit
  /// quaternion, negative friction, restitution outside [0, 1]).
  void validateState(const std::string& name) const {
    validateState([&] { return name; });
  }
  /// The same, with the body's name made only for a message (the world checks every body every substep).
  template <class Name>
    requires std::is_invocable_r_v<std::string, Name>
  void validateState(Name&& name) const {
    using detail::require;
    require(detail::allFinite(state.pose.position), [&] { return name() + ": position must be finite"; });
    require(detail::allFinite(state.pose.rotation.coeffs()), [&] { return name() + ": rotation must be finite"; });
    require(std::abs(state.pose.rotation.norm() - 1) < 1e-6, [&] {
      return name() + ": rotation must be a unit quaternion (norm " + detail::formatNumber(state.pose.rotation.norm()) + ")";
    });
    require(detail::allFinite(state.linearVelocity), [&] { return name() + ": linear velocity must be finite"; });
    require(detail::allFinite(state.angularVelocity), [&] { return name() + ": angular velocity must be finite"; });
    require(motion == BodyMotion::Dynamic || motion == BodyMotion::Kinematic,
            [&] { return name() + ": motion is not dynamic or kinematic"; });
    require(std::isfinite(staticFriction) && staticFriction >= 0,
            [&] { return name() + ": staticFriction must be >= 0 (got " + detail::formatNumber(staticFriction) + ")"; });
    require(std::isfinite(dynamicFriction) && dynamicFriction >= 0,
            [&] { return name() + ": dynamicFriction must be >= 0 (got " + detail::formatNumber(dynamicFriction) + ")"; });
    require(std::isfinite(restitution) && restitution >= 0 && restitution <= 1, [&] {
      return name() + ": restitution must be in [0, 1] (got " + detail::formatNumber(restitution) + ")";
    });
    require(detail::allFinite(force_) && detail::allFinite(torque_),
            [&] { return name() + ": accumulated force must be finite"; });
  }

 private:
  RigidShape shape_;
  MassProperties mass_{};
  Eigen::Matrix3d invInertiaBody_ = Eigen::Matrix3d::Identity();
  double boundingRadius_ = 0;
  Eigen::Vector3d force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_ = Eigen::Vector3d::Zero();
};

}  // namespace drape
