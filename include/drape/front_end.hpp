#pragma once
// What every cloth solver shares, whatever runs its kernels (docs/design.md §8): the asset, the settings and
// the state; the checks on everything a program hands in, made before anything changes; the pins; the solids,
// moved and compiled for each substep in one order; and the local origin that follows the cloth. The CPU
// solver (drape/solver.hpp) and the GPU solver (drape/gpu/solver.hpp) are both this front end over their own
// kernels, and the ClothSolver concept names what templates that take either may use.

#include <drape/cloth/asset.hpp>
#include <drape/cloth/state.hpp>
#include <drape/coupling/anchors.hpp>
#include <drape/sdf/solid.hpp>
#include <drape/settings.hpp>

#include <algorithm>
#include <concepts>
#include <limits>
#include <memory>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

/// Every shape with a built-in distance field, in the order a solver visits them. A macro, so that explicit
/// instantiations, which must spell the list out, share it (drape/solver_instances.hpp).
#define DRAPE_BUILT_IN_SHAPES \
  ::drape::Plane, ::drape::Sphere, ::drape::Box, ::drape::Capsule, ::drape::Cylinder, ::drape::ConvexHull, ::drape::MeshShape

namespace drape {

/// A kinematic attachment of a vertex to a world point.
struct Pin {
  Index vertex;
  Eigen::Vector3d target;  ///< world (m)
};

/// What a program may change of the state through the front end.
enum class StateChange { Positions, Velocities, Masses };

/// Which features this substep's solids declare (prepareSolids): a scene pays only for what it has.
struct SolidFeatures {
  bool friction = false;   ///< some solid has friction
  bool repulsion = false;  ///< some solid has a repulsion region
  bool reconcile = false;  ///< a vertex may touch several surfaces (several solids, or a curved one)
  bool coupled = false;    ///< some solid is a dynamic body
  bool moving = false;     ///< some solid is kinematic or dynamic
  int bounded = 0;         ///< solids with a bounding box (every shape but the plane)
};

/// The front end of a solver over solids of the types Shapes. Backend is the solver itself (it derives from
/// this class), which provides:
///   void loadState() const;                 make state_ current (a GPU reads its buffers back)
///   void storeState(StateChange);           after the front end changed state_
///   void checkSettings(const Settings&);    throw for a valid setting the backend does not run
///   template <class Shape> void checkSolid(const Solid<Shape>&);   the same for a solid
///   template <class Shape> void solidSet(Index k);   solid k of Shape was added or replaced (compiled_[k] holds it)
///   void beginStep();                       before a step's substeps (move the local origin)
///   void keepStart(); void restoreStart();  keep the positions and velocities, put them back (an undone step)
///   void subStep(double h);
template <class Backend, Scalar S, class... Shapes> class SolverFront {
 public:
  using scalar_type = S;
  /// Whether this solver takes solids of that shape type.
  template <class Shape> static constexpr bool kHasShape = (std::is_same_v<Shape, Shapes> || ...);

  // --- settings -------------------------------------------------------------------------------------------
  const Settings& settings() const { return settings_; }
  /// Takes new settings, checked first: a bad field, or one this solver does not run, changes nothing.
  void setSettings(const Settings& s) {
    s.validate();
    backend().checkSettings(s);
    settings_ = s;
  }

  // --- cloth ----------------------------------------------------------------------------------------------
  const ClothAsset<S>& asset() const { return *asset_; }
  Index vertexCount() const { return asset_->vertexCount(); }
  /// The state (for a GPU, read back on the call).
  const ClothState<S>& state() const {
    backend().loadState();
    return state_;
  }
  Eigen::Vector3d position(Index i) const {
    checkVertex(i);
    backend().loadState();
    return state_.origin + state_.x[std::size_t(i)].template cast<double>();
  }
  Eigen::Vector3d velocity(Index i) const {
    checkVertex(i);
    backend().loadState();
    return state_.v[std::size_t(i)].template cast<double>();
  }

  /// Replaces all positions (world, m). Rejects a wrong count, a non-finite position or one beyond 1e9 m, or a
  /// cloth spread over more than 1e5 m, before changing anything. The local origin moves to the new positions,
  /// so float keeps its precision wherever they are.
  void setPositions(const std::vector<Eigen::Vector3d>& world) {
    detail::require(Index(world.size()) == vertexCount(), [&] {
      return "setPositions got " + std::to_string(world.size()) + " positions for " + std::to_string(vertexCount()) +
             " vertices";
    });
    for (std::size_t i = 0; i < world.size(); ++i)
      detail::require(detail::allFinite(world[i]) && world[i].cwiseAbs().maxCoeff() <= limits::kMaxCoordinate,
                      [&] { return "position of vertex " + std::to_string(i) + " is not finite or lies beyond 1e9 m"; });
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : world) centre += p / double(world.size());
    const Eigen::Vector3d origin = snapOrigin(centre);
    for (std::size_t i = 0; i < world.size(); ++i)
      detail::require((world[i] - origin).cwiseAbs().maxCoeff() <= limits::kMaxDistance, [&] {
        return "position of vertex " + std::to_string(i) + " lies more than 1e5 m from the cloth's centre";
      });
    backend().loadState();
    state_.origin = origin;
    for (std::size_t i = 0; i < world.size(); ++i) state_.x[i] = (world[i] - origin).template cast<S>();
    backend().storeState(StateChange::Positions);
    anchorsStale_ = true;
  }
  /// Replaces all velocities (m/s), with the same checks.
  void setVelocities(const std::vector<Eigen::Vector3d>& v) {
    detail::require(Index(v.size()) == vertexCount(), [&] {
      return "setVelocities got " + std::to_string(v.size()) + " velocities for " + std::to_string(vertexCount()) +
             " vertices";
    });
    for (std::size_t i = 0; i < v.size(); ++i)
      detail::require(detail::allFinite(v[i]) && v[i].cwiseAbs().maxCoeff() <= limits::kMaxSpeed, [&] {
        return "velocity of vertex " + std::to_string(i) + " is not finite or has a component beyond 1e5 m/s";
      });
    backend().loadState();
    for (std::size_t i = 0; i < v.size(); ++i) state_.v[i] = v[i].template cast<S>();
    backend().storeState(StateChange::Velocities);
  }
  /// Sets one vertex's inverse mass (1/kg); 0 fixes it where it is.
  void setInverseMass(Index i, double invMass) {
    checkVertex(i);
    constexpr double kLargest = double(std::numeric_limits<S>::max()), kSmallest = double(std::numeric_limits<S>::min());
    detail::require(std::isfinite(invMass) && (invMass == 0 || (invMass >= kSmallest && invMass <= kLargest)), [&] {
      return "inverse mass of vertex " + std::to_string(i) +
             " must be finite, >= 0 and representable in the solver's scalar (got " + std::to_string(invMass) + ")";
    });
    backend().loadState();
    state_.invMass[std::size_t(i)] = S(invMass);
    if (invMass == 0) state_.v[std::size_t(i)].setZero();
    backend().storeState(StateChange::Masses);
    anchorsStale_ = true;
  }
  /// Fixes a vertex where it is (inverse mass 0).
  void pin(Index i) { setInverseMass(i, 0); }
  /// Attaches a vertex to a world target; with pinCompliance 0 and inverse mass 0 it follows the target
  /// exactly, otherwise it is pulled by a zero-length XPBD constraint. Returns the pin's index.
  Index attach(Index i, const Eigen::Vector3d& target) {
    checkVertex(i);
    detail::require(detail::allFinite(target), [&] { return "pin target of vertex " + std::to_string(i) + " is not finite"; });
    pins_.push_back({i, target});
    anchorsStale_ = true;
    return Index(pins_.size()) - 1;
  }
  void setPinTarget(Index pin, const Eigen::Vector3d& target) {
    detail::require(pin >= 0 && pin < Index(pins_.size()), [&] { return "pin index " + std::to_string(pin) + " out of range"; });
    detail::require(detail::allFinite(target), "pin target is not finite");
    pins_[std::size_t(pin)].target = target;
    // An attached vertex of inverse mass 0 follows its target.
    if (!anchorsStale_) {
      const int a = anchorOf_[std::size_t(pins_[std::size_t(pin)].vertex)];
      if (a >= 0) anchors_[std::size_t(a)].world = target;
    }
  }
  const std::vector<Pin>& pins() const { return pins_; }

  // --- solids ---------------------------------------------------------------------------------------------
  /// Adds a solid and returns its index among the solids of its shape type. Solids are visited by shape type
  /// (in the order of Shapes), then in the order they were added.
  template <class Shape> Index addSolid(const Solid<Shape>& solid) {
    static_assert(kHasShape<Shape>, "this solver was not declared with that shape type");
    detail::validateSolid(solid, "solid");
    backend().checkSolid(solid);
    auto& list = std::get<std::vector<Solid<Shape>>>(solids_);
    auto& compiled = std::get<std::vector<CompiledSolid<Shape, S>>>(compiled_);
    compiled.push_back(detail::compileSolid<Shape, S>(solid, state_.origin));
    list.push_back(solid);
    backend().template solidSet<Shape>(Index(list.size()) - 1);
    return Index(list.size()) - 1;
  }
  template <class Shape> const Solid<Shape>& solid(Index k) const {
    static_assert(kHasShape<Shape>, "this solver was not declared with that shape type");
    const auto& list = std::get<std::vector<Solid<Shape>>>(solids_);
    detail::require(k >= 0 && k < Index(list.size()), [&] { return "solid index " + std::to_string(k) + " out of range"; });
    return list[std::size_t(k)];
  }
  /// Replaces solid k of its shape type (the shape itself may differ: nothing of the old one is kept).
  template <class Shape> void setSolid(Index k, const Solid<Shape>& s) {
    static_assert(kHasShape<Shape>, "this solver was not declared with that shape type");
    auto& list = std::get<std::vector<Solid<Shape>>>(solids_);
    detail::require(k >= 0 && k < Index(list.size()), [&] { return "solid index " + std::to_string(k) + " out of range"; });
    detail::validateSolid(s, "solid " + std::to_string(k));
    backend().checkSolid(s);
    std::get<std::vector<CompiledSolid<Shape, S>>>(compiled_)[std::size_t(k)] =
        detail::compileSolid<Shape, S>(s, state_.origin);
    list[std::size_t(k)] = s;
    backend().template solidSet<Shape>(k);
  }
  /// Calls f(const CompiledSolid<Shape, S>&) for every solid, compiled at the current local origin.
  template <class F> void forEachSolid(F&& f) const {
    std::apply(
        [&](const auto&... lists) {
          (
              [&](const auto& list) {
                for (const auto& s : list) f(detail::compileSolid<std::decay_t<decltype(s.shape)>, S>(s, state_.origin));
              }(lists),
              ...);
        },
        solids_);
  }
  Index solidCount() const {
    return std::apply([](const auto&... lists) { return Index((lists.size() + ... + 0)); }, solids_);
  }

  // --- stepping -------------------------------------------------------------------------------------------
  /// Advances by dt seconds in subStepCount substeps.
  void step(double dt) { step(dt, NoObserver{}); }
  /// The same, calling onSubStep(solver) after every substep (for metrics, tests and engines stepped in
  /// between). If a substep or the observer throws, the step is undone: the cloth and its solids are left as
  /// they were, and the exception passes on. Keeping the start for that costs a copy of the state per step,
  /// which a noexcept observer in a scene with no coupled body does not pay.
  template <class Observer> void step(double dt, Observer&& onSubStep) {
    detail::require(std::isfinite(dt) && dt > 0 && dt <= limits::kMaxStep,
                    [&] { return "step dt must be in (0, 10] s (got " + detail::formatNumber(dt) + ")"; });
    detail::require(dt / settings_.subStepCount >= limits::kMinSubStep, [&] {
      return "step dt / subStepCount must be at least 1e-6 s (got " +
             detail::formatNumber(dt / settings_.subStepCount) + ")";
    });
    const double h = dt / settings_.subStepCount;
    if (anchorsStale_) listAnchors();
    auto run = [&] {
      backend().beginStep();
      for (int sub = 0; sub < settings_.subStepCount; ++sub) {
        backend().subStep(h);
        onSubStep(std::as_const(backend()));
      }
    };
    // Only an observer or a coupled body can fail in the middle of a step: a coupled body is read every
    // substep and may turn non-finite when its engine steps between the substeps. Such a step keeps its start,
    // to be undone (a noexcept observer spares the copy). Forces already passed to the bodies stay with their
    // engine (stepCoupled restores drape's own).
    if (std::is_nothrow_invocable_v<Observer&, const Backend&> && !hasDynamicSolid()) return run();
    backend().keepStart();
    start_.origin = state_.origin;
    start_.solids = solids_;
    start_.force = bodyForce_;
    start_.torque = bodyTorque_;
    auto undo = [&] {
      state_.origin = start_.origin;
      solids_ = start_.solids;
      bodyForce_ = start_.force;
      bodyTorque_ = start_.torque;
      backend().restoreStart();
    };
    try {
      run();
    } catch (const Error& e) {
      undo();
      throw Error(std::string(e.what()) + " (the step was undone)");
    } catch (...) {
      undo();
      throw;
    }
  }

  /// The force and torque (about the body's centre of mass) the cloth applied to each coupled body in the last
  /// substep, in the order the dynamic solids were visited (shape type by shape type, then by index).
  const std::vector<Eigen::Vector3d>& bodyForces() const { return bodyForce_; }
  const std::vector<Eigen::Vector3d>& bodyTorques() const { return bodyTorque_; }
  /// The coupled bodies of the last substep, in the same order.
  const std::vector<CoupledBody*>& coupledBodies() const { return bodies_; }
  /// The cloth's pinches in the last substep, in vertex order, then its anchors' (vertices of inverse mass 0 in a
  /// body's contact shell): what holds each pinched body off the surface behind the cloth, or off the anchor
  /// (stepCoupled hands them to the rigid world).
  const std::vector<Spacer>& spacers() const { return spacers_; }

 protected:
  /// The vertices of inverse mass 0 and where they are (an attached one at its pin's target), after a program
  /// changed positions, masses or pins: read once, not every substep.
  void listAnchors() {
    backend().loadState();
    anchors_.clear();
    anchorOf_.assign(state_.invMass.size(), -1);
    for (std::size_t i = 0; i < state_.invMass.size(); ++i)
      if (state_.invMass[i] == S(0)) {
        anchorOf_[i] = int(anchors_.size());
        anchors_.push_back({Index(i), state_.origin + state_.x[i].template cast<double>()});
      }
    for (const Pin& p : pins_) {
      const int a = anchorOf_[std::size_t(p.vertex)];
      if (a >= 0) anchors_[std::size_t(a)].world = p.target;
    }
    anchorsStale_ = false;
  }
  /// Each anchor's support of the coupled bodies whose contact shells hold it (coupling::supportAnchors): added to
  /// `sums`, one per coupled body, and its spacers appended to `spacers` (the cloth's local frame).
  void supportAnchors(double h, std::vector<coupling::BodySums>& sums, std::vector<Spacer>& spacers) {
    if (anchors_.empty()) return;
    std::apply(
        [&](const auto&... lists) {
          (coupling::supportAnchors(lists, anchors_, bodies_, bodyCentre_, state_.origin, h, settings_.thickness,
                                    settings_.normalForceOnly, sums, spacers),
           ...);
        },
        compiled_);
  }

  /// Moves the spacers' points from the cloth's local frame into their bodies' frames where the cloth met them
  /// (a fixed solid's into the world's).
  void spacersToBodyFrames() {
    for (Spacer& p : spacers_) {
      const Pose& body = bodyPose_[std::size_t(p.body)];
      p.onBody = body.rotation.conjugate() * (p.onBody + state_.origin - body.position);
      p.onOther += state_.origin;
      if (p.other >= 0) {
        const Pose& other = bodyPose_[std::size_t(p.other)];
        p.onOther = other.rotation.conjugate() * (p.onOther - other.position);
      }
    }
  }
  SolverFront(std::shared_ptr<const ClothAsset<S>> asset, const Settings& settings, double areaDensity)
      : asset_((detail::require(asset != nullptr, "the cloth asset is null"), std::move(asset))),
        settings_((settings.validate(), Backend::checkSettings(settings), settings)),
        state_(ClothState<S>::fromAsset(*asset_, areaDensity)) {}

  struct NoObserver {
    void operator()(const Backend&) const noexcept {}
  };
  /// What a step that can fail midway restores besides the cloth's positions and velocities, which the backend
  /// keeps (keepStart, restoreStart). Kept between steps so that keeping it does not allocate.
  struct StepStart {
    Eigen::Vector3d origin;
    std::tuple<std::vector<Solid<Shapes>>...> solids;
    std::vector<Eigen::Vector3d> force, torque;
  };
  bool hasDynamicSolid() const {
    return std::apply(
        [](const auto&... lists) {
          return (std::any_of(lists.begin(), lists.end(), [](const auto& s) { return s.motion == Motion::Dynamic; }) ||
                  ... || false);
        },
        solids_);
  }

  Backend& backend() { return static_cast<Backend&>(*this); }
  const Backend& backend() const { return static_cast<const Backend&>(*this); }

  Index checkVertex(Index i) const {
    detail::require(i >= 0 && i < vertexCount(), [&] {
      return "vertex index " + std::to_string(i) + " out of range [0, " + std::to_string(vertexCount()) + ")";
    });
    return i;
  }

  /// p to the nearest point of the origin lattice: a shift by it is exact in float.
  static Eigen::Vector3d snapOrigin(const Eigen::Vector3d& p) {
    return (p * limits::kOriginLattice).array().round().matrix() / limits::kOriginLattice;
  }
  /// Where the cloth's centre (local coordinates) is far enough from the local origin, moves the origin by a
  /// lattice step near it and returns that shift (the caller moves the positions back by it); else zero.
  Eigen::Vector3d moveOrigin(const Eigen::Vector3d& centre) {
    if (!(centre.norm() >= limits::kRebaseDistance)) return Eigen::Vector3d::Zero();
    const Eigen::Vector3d shift = snapOrigin(centre);
    state_.origin += shift;
    return shift;
  }

  /// Moves each kinematic and dynamic solid over the substep h, compiles every solid at the current local
  /// origin, lists the coupled bodies and says which features the scene has; then calls
  /// f(const CompiledSolid<Shape, S>&, const Solid<Shape>&) for each solid, in order.
  template <class F> SolidFeatures prepareSolids(double h, F&& f) {
    SolidFeatures has;
    bodies_.clear();
    bodyCentre_.clear();
    bodyPose_.clear();
    spacers_.clear();  // the coupling's gather lists this substep's
    has.reconcile = solidCount() > 1;
    std::apply(
        [&](auto&... lists) {
          (
              [&](auto& list) {
                using Shape = std::decay_t<decltype(list.front().shape)>;
                auto& out = std::get<std::vector<CompiledSolid<Shape, S>>>(compiled_);
                for (std::size_t k = 0; k < list.size(); ++k) {
                  Solid<Shape>& held = list[k];
                  has.friction = has.friction || held.staticFriction > 0 || held.dynamicFriction > 0;
                  has.repulsion = has.repulsion || held.repulsion.radius > 0;
                  has.reconcile = has.reconcile || !Sdf<Shape, S>::kLinear;
                  has.moving = has.moving || held.motion != Motion::Static;
                  detail::advancePose(held, h);
                  detail::recompileSolid<Shape, S>(out[k], held, state_.origin);
                  has.bounded += out[k].bounded ? 1 : 0;
                  if (held.motion == Motion::Dynamic) {
                    out[k].motion.body = std::int32_t(bodies_.size());
                    bodies_.push_back(held.body);
                    bodyCentre_.push_back(held.pose.position);  // the field's centre, not the body's now
                    bodyPose_.push_back(held.pose);
                  }
                  f(std::as_const(out[k]), std::as_const(held));
                }
              }(lists),
              ...);
        },
        solids_);
    has.coupled = !bodies_.empty();
    bodyForce_.assign(bodies_.size(), Eigen::Vector3d::Zero());
    bodyTorque_.assign(bodies_.size(), Eigen::Vector3d::Zero());
    return has;
  }

  std::shared_ptr<const ClothAsset<S>> asset_;
  Settings settings_;
  mutable ClothState<S> state_;  ///< for a GPU, the copy read back on demand (loadState)
  std::tuple<std::vector<Solid<Shapes>>...> solids_;
  /// Their fields, compiled at the last substep's pose (recompileSolid keeps a hull's query data and a grid).
  std::tuple<std::vector<CompiledSolid<Shapes, S>>...> compiled_;
  std::vector<Pin> pins_;
  std::vector<coupling::Anchor> anchors_;  ///< the vertices of inverse mass 0 (listAnchors)
  std::vector<int> anchorOf_;              ///< each vertex's place in anchors_, -1 for none
  bool anchorsStale_ = true;
  std::vector<CoupledBody*> bodies_;  ///< the dynamic solids' bodies, this substep
  /// Their centres of mass where the substep's contacts were found (advancePose: the start, carried by the
  /// velocity over the substep); torques are taken about them, so a force along a field's normal through a
  /// ball's centre has no moment.
  std::vector<Eigen::Vector3d> bodyCentre_;
  std::vector<Pose> bodyPose_;  ///< their poses there, which the spacers' points are taken in
  std::vector<Eigen::Vector3d> bodyForce_, bodyTorque_;  ///< what the cloth passed to each, this substep
  std::vector<Spacer> spacers_;  ///< this substep's pinches (spacers())
  StepStart start_;  ///< the start of a step that may be undone
};

/// What templates that run a scene on any cloth solver (metrics, coupled bodies, scenes) may use of it.
template <class T>
concept ClothSolver = requires(T& solver, const T& view, double dt, Index i, const std::vector<Eigen::Vector3d>& world) {
  typename T::scalar_type;
  { view.asset() } -> std::same_as<const ClothAsset<typename T::scalar_type>&>;
  { view.state() } -> std::same_as<const ClothState<typename T::scalar_type>&>;
  { view.settings() } -> std::same_as<const Settings&>;
  { view.vertexCount() } -> std::same_as<Index>;
  { view.position(i) } -> std::same_as<Eigen::Vector3d>;
  { view.velocity(i) } -> std::same_as<Eigen::Vector3d>;
  { view.bodyForces() } -> std::same_as<const std::vector<Eigen::Vector3d>&>;
  solver.step(dt);
  solver.setPositions(world);
  solver.setVelocities(world);
  solver.setInverseMass(i, dt);
};

}  // namespace drape
