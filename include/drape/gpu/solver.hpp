#pragma once
// The cloth solver on the GPU (issue 5, DESIGN 9): the CPU solver's substep loop, each kernel a compute
// dispatch on buffers that stay on the GPU. The state is uploaded once, stepped many times, and read back on
// demand (position(), velocity(), state()): nothing crosses the bus between steps unless asked.
//
// What it runs so far: predict, the distance constraints (stretch, shear, bending; one dispatch per colour, all
// iterations, with the XPBD multipliers when several passes meet a compliant set) and the velocity update, for
// float. Fixed vertices are those of inverse mass 0. Solids, pins with targets, repulsion and the rigid-body
// coupling are CPU-only for now: the constructor takes no solids, so a scene cannot silently lose them.
//
// Each kernel in shaders/ has its CPU twin named in its header comment; tests/gpu/ compares each pair.

#include <drape/cloth/asset.hpp>
#include <drape/cloth/state.hpp>
#include <drape/gpu/program.hpp>
#include <drape/gpu/shader_sources.hpp>
#include <drape/settings.hpp>

#include <memory>
#include <string>
#include <vector>

namespace drape::gpu {

class Solver {
 public:
  using scalar_type = float;

  /// Uploads the asset's constraints and its rest state (masses from areaDensity, kg/m^2). `context` must be
  /// current and outlive the solver.
  Solver(Context& context, std::shared_ptr<const ClothAsset<float>> asset, const Settings& settings = {},
         double areaDensity = 0.1)
      : context_((context.makeCurrent(), &context)),  // current before the kernels compile
        asset_((drape::detail::require(asset != nullptr, "the cloth asset is null"), std::move(asset))),
        settings_((settings.validate(), settings)),
        state_(ClothState<float>::fromAsset(*asset_, areaDensity)),
        predict_("predict", shaders::predict),
        solve_("solve_distance", shaders::solve_distance),
        update_("update_velocity", shaders::update_velocity) {
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
    upload();
  }

  const Settings& settings() const { return settings_; }
  /// Takes new settings (validated first: a bad field changes nothing).
  void setSettings(const Settings& s) {
    s.validate();
    settings_ = s;
  }
  const ClothAsset<float>& asset() const { return *asset_; }
  Index vertexCount() const { return asset_->vertexCount(); }

  /// The state as the GPU has it now (read back on each call).
  const ClothState<float>& state() const {
    download();
    return state_;
  }
  Eigen::Vector3d position(Index i) const {
    checkVertex(i);
    download();
    return state_.origin + state_.x[std::size_t(i)].cast<double>();
  }
  Eigen::Vector3d velocity(Index i) const {
    checkVertex(i);
    download();
    return state_.v[std::size_t(i)].cast<double>();
  }

  /// Replaces all velocities (m/s); rejects a wrong count or a non-finite or absurd value before changing anything.
  void setVelocities(const std::vector<Eigen::Vector3d>& v) {
    drape::detail::require(Index(v.size()) == vertexCount(),
                           "setVelocities got " + std::to_string(v.size()) + " velocities for " +
                               std::to_string(vertexCount()) + " vertices");
    for (std::size_t i = 0; i < v.size(); ++i)
      drape::detail::require(drape::detail::allFinite(v[i]) && v[i].cwiseAbs().maxCoeff() <= 1e5,
                             "velocity of vertex " + std::to_string(i) + " is not finite or has a component beyond 1e5 m/s");
    download();
    for (std::size_t i = 0; i < v.size(); ++i) state_.v[i] = v[i].cast<float>();
    upload();
  }
  /// Sets one vertex's inverse mass (1/kg); 0 fixes it where it is.
  void setInverseMass(Index i, double invMass) {
    checkVertex(i);
    drape::detail::require(std::isfinite(invMass) && invMass >= 0 && invMass <= double(std::numeric_limits<float>::max()) &&
                               (invMass == 0 || invMass >= double(std::numeric_limits<float>::min())),
                           "inverse mass of vertex " + std::to_string(i) +
                               " must be finite, >= 0 and representable in float (got " + std::to_string(invMass) + ")");
    download();
    state_.invMass[std::size_t(i)] = float(invMass);
    if (invMass == 0) state_.v[std::size_t(i)].setZero();
    upload();
  }
  /// Fixes a vertex where it is (inverse mass 0).
  void pin(Index i) { setInverseMass(i, 0); }

  /// Advances by dt seconds in subStepCount substeps, on the GPU. Nothing is read back.
  void step(double dt) {
    drape::detail::require(std::isfinite(dt) && dt > 0 && dt <= 10,
                           "step dt must be in (0, 10] s (got " + std::to_string(dt) + ")");
    drape::detail::require(dt / settings_.subStepCount >= 1e-6,
                           "step dt / subStepCount must be at least 1e-6 s (got " +
                               std::to_string(dt / settings_.subStepCount) + ")");
    context_->makeCurrent();
    const double h = dt / settings_.subStepCount;
    for (int sub = 0; sub < settings_.subStepCount; ++sub) subStep(float(h));
    fresh_ = false;
  }

 private:
  void checkVertex(Index i) const {
    drape::detail::require(i >= 0 && i < vertexCount(), "vertex index " + std::to_string(i) + " out of range [0, " +
                                                            std::to_string(vertexCount()) + ")");
  }

  void subStep(float h) {
    const auto n = unsigned(vertexCount());
    positions_.bind(layout::kPositions);
    velocities_.bind(layout::kVelocities);
    predicted_.bind(layout::kPredicted);
    packed_.bind(layout::kPacked);
    constraints_.bind(layout::kConstraints);
    lambdas_.bind(layout::kLambdas);

    // 1. predict
    const Vec3<float> gh = (settings_.gravity * double(h)).cast<float>();
    predict_.set(layout::kCount, n);
    predict_.set(layout::kStep, h);
    predict_.set(layout::kGravityStep, gh.x(), gh.y(), gh.z());
    predict_.dispatch(n);

    // 2. solve, set by set and colour by colour, as the CPU solver orders them
    const float h2 = h * h;
    const float alphas[3] = {float(settings_.stretchCompliance) / h2, float(settings_.shearCompliance) / h2,
                             float(settings_.bendingCompliance) / h2};
    const int iterations = settings_.iterationCount;
    if (iterations > 1) glClearNamedBufferData(lambdas_.id(), GL_R32F, GL_RED, GL_FLOAT, nullptr);
    const DistanceSet<float>* sets[3] = {&asset_->stretch, &asset_->shear, &asset_->bending};
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
    }

    // 3. update velocity
    update_.set(layout::kCount, n);
    update_.set(layout::kInverseStep, 1.0f / h);
    update_.dispatch(n);
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
  std::shared_ptr<const ClothAsset<float>> asset_;
  Settings settings_;
  mutable ClothState<float> state_;  ///< the CPU copy: current when fresh_
  mutable bool fresh_ = true;
  Program predict_, solve_, update_;
  Buffer<layout::Vertex> positions_, velocities_, predicted_, packed_;
  Buffer<layout::Constraint> constraints_;
  Buffer<float> lambdas_;
  std::size_t setStart_[3] = {0, 0, 0};
};

}  // namespace drape::gpu
