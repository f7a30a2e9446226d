#pragma once
// The solids' fields as the collision kernels read them: each shape's compiled field (Sdf<Shape, float>, in the
// cloth's local frame) packed into the five vec4s of the `shape` uniform (layout::kShape), in the order
// shaders/common.glsl unpacks them, and the code that selects its GLSL twin (DRAPE_SHAPE).

#include <drape/gpu/context.hpp>  // GL
#include <drape/gpu/layout.hpp>
#include <drape/sdf/solid.hpp>

#include <array>
#include <string>
#include <type_traits>
#include <vector>

namespace drape::gpu {

/// The shapes the GPU kernels have a field for.
template <class Shape>
inline constexpr bool kGpuShape = std::is_same_v<Shape, Plane> || std::is_same_v<Shape, Sphere> ||
                                  std::is_same_v<Shape, Box> || std::is_same_v<Shape, Capsule> ||
                                  std::is_same_v<Shape, Cylinder> || std::is_same_v<Shape, ConvexHull> ||
                                  std::is_same_v<Shape, MeshShape>;

template <class Shape> constexpr layout::ShapeCode shapeCode() {
  static_assert(kGpuShape<Shape>, "this shape has no GPU field yet");
  if constexpr (std::is_same_v<Shape, Plane>) return layout::kPlane;
  else if constexpr (std::is_same_v<Shape, Sphere>) return layout::kSphere;
  else if constexpr (std::is_same_v<Shape, Box>) return layout::kBox;
  else if constexpr (std::is_same_v<Shape, Capsule>) return layout::kCapsule;
  else if constexpr (std::is_same_v<Shape, Cylinder>) return layout::kCylinder;
  else if constexpr (std::is_same_v<Shape, ConvexHull>) return layout::kHull;
  else return layout::kGridShape;
}

/// The #defines that compile a collision kernel for the shape: which field, and whether it has no edges
/// (kSmoothField).
template <class Shape> std::string shapeDefine() {
  return "#define DRAPE_SHAPE " + std::to_string(int(shapeCode<Shape>())) + "\n#define DRAPE_SMOOTH_FIELD " +
         std::to_string(int(kSmoothField<Shape, float>)) + "\n#define DRAPE_HOLDS_DEEPEST_POINTS " +
         std::to_string(int(kHoldsDeepestPoints<Sdf<Shape, float>>)) + "\n";
}

using PackedShape = std::array<Eigen::Vector4f, 5>;

inline PackedShape packShape(const Sdf<Plane, float>& f) {
  return {Eigen::Vector4f(f.normal.x(), f.normal.y(), f.normal.z(), f.offset), Eigen::Vector4f::Zero(),
          Eigen::Vector4f::Zero(), Eigen::Vector4f::Zero(), Eigen::Vector4f::Zero()};
}
inline PackedShape packShape(const Sdf<Sphere, float>& f) {
  return {Eigen::Vector4f(f.centre.x(), f.centre.y(), f.centre.z(), f.radius), Eigen::Vector4f::Zero(),
          Eigen::Vector4f::Zero(), Eigen::Vector4f::Zero(), Eigen::Vector4f::Zero()};
}
/// The rows of a world-to-shape rotation, each with one scalar in w.
inline PackedShape packRotation(const Vec3<float>& centre, float w0, const Mat3<float>& toLocal, float w1, float w2,
                                float w3) {
  PackedShape p;
  p[4].setZero();
  p[0] << centre, w0;
  p[1] << toLocal.row(0).transpose(), w1;
  p[2] << toLocal.row(1).transpose(), w2;
  p[3] << toLocal.row(2).transpose(), w3;
  return p;
}
inline PackedShape packShape(const Sdf<Box, float>& f) {
  return packRotation(f.centre, 0, f.toLocal, f.halfExtents.x(), f.halfExtents.y(), f.halfExtents.z());
}
inline PackedShape packShape(const Sdf<Capsule, float>& f) {
  const Vec3<float> side = f.axis.unitOrthogonal();  // the gradient on the core segment, as the CPU takes it
  return {Eigen::Vector4f(f.centre.x(), f.centre.y(), f.centre.z(), f.halfHeight),
          Eigen::Vector4f(f.axis.x(), f.axis.y(), f.axis.z(), f.radius), Eigen::Vector4f(side.x(), side.y(), side.z(), 0),
          Eigen::Vector4f::Zero(), Eigen::Vector4f::Zero()};
}
inline PackedShape packShape(const Sdf<Cylinder, float>& f) {
  return packRotation(f.centre, f.radius, f.toLocal, f.halfHeight, 0, 0);
}

/// A convex hull: the centre with the field's nearSurface, the rotation with the face count (its faces and edges go
/// to their own buffer, layout::kShapeData: packHull).
inline PackedShape packShape(const Sdf<ConvexHull, float>& f) {
  return packRotation(f.centre, f.hull->nearSurface, f.toLocal, float(f.hull->faces.size()), 0, 0);
}
/// A hull's faces, then its edges, as shaders/common.glsl reads them: per face (normal, offset) and (first edge,
/// edge count, 0, 0); per edge (start, 1 / |delta|^2), (delta, twin or -1) and (inward, 0). Indices are exact in
/// float up to 2^24.
inline std::vector<layout::Vertex> packHull(const drape::detail::HullField<float>& h) {
  drape::detail::require(h.edges.size() < (1u << 24), "a hull with 2^24 edges or more does not fit the GPU's layout");
  std::vector<layout::Vertex> out;
  out.reserve(2 * h.faces.size() + 3 * h.edges.size());
  for (const auto& f : h.faces) {
    out.push_back({f.normal.x(), f.normal.y(), f.normal.z(), f.offset});
    out.push_back({float(f.firstEdge), float(f.edgeCount), 0, 0});
  }
  for (const auto& e : h.edges) {
    out.push_back({e.start.x(), e.start.y(), e.start.z(), e.invLengthSq});
    out.push_back({e.delta.x(), e.delta.y(), e.delta.z(), float(e.twin)});
    out.push_back({e.inward.x(), e.inward.y(), e.inward.z(), 0});
  }
  return out;
}

/// A distance grid: the rotation and centre, the grid's lower corner, cell size and node counts (its nodes go
/// to their own buffer, layout::kShapeData).
inline PackedShape packShape(const Sdf<MeshShape, float>& f) {
  const auto& s = f.sample;
  PackedShape p = packRotation(f.centre.head<3>(), s.cellSize, f.toLocal.topLeftCorner<3, 3>(), s.lower[0], s.lower[1],
                               s.lower[2]);
  p[4] = Eigen::Vector4f(s.invCellSize, float(s.count[0]), float(s.count[1]), float(s.count[2]));
  return p;
}

/// Sets a program's `shape` uniform.
inline void setShape(GLuint program, const PackedShape& p) {
  glProgramUniform4fv(program, layout::kShape, GLsizei(p.size()), p[0].data());  // the vec4s lie one after another
}

}  // namespace drape::gpu
