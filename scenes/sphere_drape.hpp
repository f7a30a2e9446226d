#pragma once
// A 41x41 cloth (2 cm spacing) lying on the top of a frictionless kinematic 0.3 m sphere at the origin (or of a
// standing capsule with the same top), its centre vertex on the vertical axis through the sphere's centre, where
// it is pinned: nothing can turn the cloth about that axis (docs/design.md §4, "No spin from nothing"). Also a
// standing cylinder (a field with edges) and the sphere as a grid field built from a mesh.

#include <drape/drape.hpp>

#include <memory>

namespace drape::scenes {

struct SphereDrape {
  static constexpr Index kSide = 41;
  static constexpr double kRadius = 0.3;  ///< m
  static constexpr Index kCentre = (kSide / 2) * kSide + kSide / 2;  ///< the vertex on the axis

  template <Scalar S> static std::shared_ptr<const ClothAsset<S>> asset() {
    SheetDesc grid;
    grid.nx = grid.ny = kSide;
    grid.spacing = 0.02;
    grid.placement.position = {0, 0, kRadius + 0.005};  // resting at the default thickness
    return std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid));
  }
  /// The sphere, spinning at `spin` rad/s about the vertical.
  static Solid<Sphere> sphere(double spin = 0) {
    Solid<Sphere> ball;
    ball.shape.radius = kRadius;
    ball.motion = Motion::Kinematic;
    ball.angularVelocity = {0, 0, spin};
    return ball;
  }
  /// A frictionless kinematic capsule of the sphere's radius standing on the vertical axis, its top cap where the
  /// sphere is: the cloth's skirt hangs down its side, where the surface curves about the axis only.
  static Solid<Capsule> standingCapsule(double spin = 0) {
    Solid<Capsule> post;
    post.shape.radius = kRadius;
    post.shape.halfHeight = kRadius;
    post.pose.position = {0, 0, -kRadius};
    post.motion = Motion::Kinematic;
    post.angularVelocity = {0, 0, spin};
    return post;
  }
  /// A frictionless kinematic cylinder of the sphere's radius standing on the vertical axis, its flat top where
  /// the sphere's top is: a field with edges, the cloth folding over its rim.
  static Solid<Cylinder> standingCylinder() {
    Solid<Cylinder> drum;
    drum.shape.radius = kRadius;
    drum.shape.halfHeight = kRadius;
    drum.motion = Motion::Kinematic;
    return drum;
  }
  /// The sphere as a grid field built from a closed mesh (an icosphere of 1 280 faces, 64 cells across): its
  /// faces' normals are not radial, so the field turns the cloth by a little, as a user's mesh would.
  static Solid<MeshShape> meshBall() {
    static const auto grid = buildDistanceGrid(makeIcosphere(kRadius, 3), {64, 0, 0.02});
    Solid<MeshShape> ball;
    ball.shape = MeshShape{grid};
    ball.motion = Motion::Kinematic;
    return ball;
  }
};

/// A cloth's mass-weighted angular momentum about the world's vertical axis (kg m^2/s) and its moment of inertia
/// about it (kg m^2), over the free vertices.
struct AxialSpin {
  double momentum = 0;
  double inertia = 0;
  double rate() const { return momentum / inertia; }  ///< rad/s
};
template <class Solver> AxialSpin axialSpin(const Solver& solver) {
  AxialSpin out;
  for (Index i = 0; i < solver.vertexCount(); ++i) {
    const double w = double(solver.state().invMass[std::size_t(i)]);
    if (w == 0) continue;
    const Eigen::Vector3d p = solver.position(i), v = solver.velocity(i);
    out.momentum += (p.x() * v.y() - p.y() * v.x()) / w;
    out.inertia += (p.x() * p.x() + p.y() * p.y()) / w;
  }
  return out;
}

}  // namespace drape::scenes
