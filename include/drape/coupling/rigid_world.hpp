#pragma once
// Two-way coupling between a cloth solver and drape's own rigid bodies (docs/design.md §6, §7): a dynamic solid
// per body, and a step that interleaves the two solvers substep by substep, so the forces the cloth estimates in a
// substep act on the bodies in that same substep.

#include <drape/rigid/world.hpp>
#include <drape/sdf/solid.hpp>

#include <type_traits>
#include <variant>
#include <vector>

namespace drape {

/// How a body's solid meets the cloth: friction and the repulsion region (the shape and motion come from the
/// body).
struct CouplingDesc {
  double staticFriction = 0;
  double dynamicFriction = 0;
  Repulsion repulsion{};
};

/// Adds to `cloth` a Motion::Dynamic solid with the shape of body `index` of `world`, following and pushing it.
/// Returns the solid's index among the solids of its shape type. Throws drape::Error, before any change, if the
/// index is out of range, the body is not dynamic, or the cloth solver was not declared with the body's shape.
template <class ClothSolver>
Index addCoupledBody(ClothSolver& cloth, RigidWorld& world, int index, const CouplingDesc& desc = {}) {
  detail::require(index >= 0 && index < world.bodyCount(),
                  "addCoupledBody: body index " + std::to_string(index) + " out of range");
  RigidBody& body = world.body(index);
  detail::require(body.isDynamic(), "addCoupledBody: body " + std::to_string(index) +
                                        " is kinematic; couple it as a Motion::Kinematic solid instead");
  return std::visit(
      [&](const auto& shape) -> Index {
        using Shape = std::decay_t<decltype(shape)>;
        if constexpr (ClothSolver::template kHasShape<Shape>) {
          Solid<Shape> solid{shape};  // a hull has no default to start from
          solid.pose = body.pose();
          solid.motion = Motion::Dynamic;
          solid.body = &body;
          solid.staticFriction = desc.staticFriction;
          solid.dynamicFriction = desc.dynamicFriction;
          solid.repulsion = desc.repulsion;
          return cloth.addSolid(solid);
        } else {
          detail::require(false, "addCoupledBody: the cloth solver has no distance field for body " +
                                     std::to_string(index) + "'s shape type");
          return -1;
        }
      },
      body.shape());
}

/// Advances the cloth and the world by dt together: after each cloth substep has applied its contact forces,
/// the world takes the same substep (its own subStepCount is not used). `onSubStep(cloth)` runs after both. A
/// drape::Error in any substep (a body turned non-finite) leaves the cloth, its solids and the world's bodies as
/// they were before the step.
template <class ClothSolver, class Observer>
void stepCoupled(ClothSolver& cloth, RigidWorld& world, double dt, Observer&& onSubStep) {
  const double h = dt / cloth.settings().subStepCount;
  std::vector<BodyState> start(std::size_t(world.bodyCount()));
  for (int b = 0; b < world.bodyCount(); ++b) start[std::size_t(b)] = world.body(b).state;
  try {
    cloth.step(dt, [&](const ClothSolver& c) {
      world.subStep(h);
      onSubStep(c);
    });
  } catch (const Error&) {
    for (int b = 0; b < world.bodyCount(); ++b) {
      world.body(b).state = start[std::size_t(b)];
      world.body(b).clearForces();
    }
    throw;
  }
}
template <class ClothSolver> void stepCoupled(ClothSolver& cloth, RigidWorld& world, double dt) {
  stepCoupled(cloth, world, dt, [](const ClothSolver&) {});
}

}  // namespace drape
