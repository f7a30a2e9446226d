#pragma once
// Two-way coupling between a cloth solver and drape's own rigid bodies (docs/design.md §6, §7): a dynamic solid
// per body, and a step that interleaves the two solvers substep by substep, so the forces the cloth estimates in a
// substep act on the bodies in that same substep.

#include <drape/kernel_constants.hpp>
#include <drape/rigid/world.hpp>
#include <drape/sdf/solid.hpp>

#include <type_traits>
#include <utility>
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

namespace detail {

/// Hands the world the cloth's pinches of the substep just taken as spacers (RigidWorld::addSpacer, the vertex's
/// slot as the tag and a thickness as the reach), for bodies of this world; `index` maps each of the cloth's coupled
/// bodies to its index in the world (-1 for another's).
template <class ClothSolver> void passSpacers(const ClothSolver& cloth, RigidWorld& world, std::vector<int>& index) {
  const std::vector<CoupledBody*>& coupled = cloth.coupledBodies();
  if (index.size() != coupled.size()) {
    index.assign(coupled.size(), -1);
    for (std::size_t b = 0; b < coupled.size(); ++b)
      for (int w = 0; w < world.bodyCount(); ++w)
        if (coupled[b] == &world.body(w)) index[b] = w;
  }
  const double reach = cloth.settings().thickness;
  for (const Spacer& p : cloth.spacers()) {
    const int body = index[std::size_t(p.body)];
    const int other = p.other < 0 ? RigidWorld::kGround : index[std::size_t(p.other)];
    const std::int64_t tag = std::int64_t(p.vertex) * constants::kContactSlots + p.slot;
    if (body >= 0 && (p.other < 0 || other >= 0))
      world.addSpacer(tag, other, p.onOther, body, p.onBody, p.normal, reach);
  }
}

}  // namespace detail

/// Advances the cloth and the world by dt together: after each cloth substep has applied its contact forces,
/// the world takes the same substep (its own subStepCount is not used), holding each body the cloth pinches
/// against a surface off it by the cloth (the solver's spacers()). `onSubStep(cloth)` runs after both. A
/// drape::Error in any substep (a body turned non-finite) leaves the cloth, its solids and the world's bodies as
/// they were before the step.
template <class ClothSolver, class Observer>
void stepCoupled(ClothSolver& cloth, RigidWorld& world, double dt, Observer&& onSubStep) {
  const double h = dt / cloth.settings().subStepCount;
  std::vector<BodyState> start(std::size_t(world.bodyCount()));
  for (int b = 0; b < world.bodyCount(); ++b) start[std::size_t(b)] = world.body(b).state;
  RigidWorld::Spacers spacers = world.spacers();
  std::vector<int> index;
  try {
    cloth.step(dt, [&](const ClothSolver& c) {
      detail::passSpacers(c, world, index);
      world.subStep(h);
      onSubStep(c);
    });
  } catch (const Error&) {
    world.restoreSpacers(std::move(spacers));
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
