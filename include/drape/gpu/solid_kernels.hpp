#pragma once
// The GPU kernels that act on one solid (docs/design.md §9): each shape type's vertex pass, face pass and
// repulsion, compiled for that shape on its first solid (and again, keeping where each push acts, for a coupled
// body's), and the shape data a field reads from its own buffer (a mesh's grid nodes, a hull's faces and
// edges), uploaded once per grid or hull.

#include <drape/gpu/program.hpp>
#include <drape/gpu/shader_sources.hpp>
#include <drape/gpu/shapes.hpp>
#include <drape/sdf/solid.hpp>

#include <algorithm>
#include <array>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace drape::gpu {

/// One solid as this substep's kernels see it.
struct SolidPass {
  layout::ShapeCode code;
  PackedShape field;
  SolidMotion<float> motion;
  bool curved;  ///< has a face pass (a field that is not linear)
  bool facesAnswerVertices;  ///< its face pass answers every vertex within the thickness (kFacesAnswerVertices)
  float repulsionRadius;
  Falloff falloff;
  const Buffer<layout::Vertex>* data;  ///< a mesh's grid nodes or a hull's faces and edges, else null
  Vec3<float> boxLow, boxHigh;         ///< where phi may be below the distance to the box (+-FLT_MAX: anywhere)
};

class SolidKernels {
 public:
  /// The shape's vertex, face and repulsion kernels (the face pass only for a curved one), once per shape type.
  template <class Shape> void compileFor(bool body) {
    ShapeKernels& k = kernels_[shapeCode<Shape>()];
    const std::string define = shapeDefine<Shape>();
    if (!k.ready) {
      k.vertices = Program("collide_vertices", shaders::collide_vertices, define);
      k.repel = Program("repel", shaders::repel, define);
      if constexpr (!Sdf<Shape, float>::kLinear) k.faces = Program("collide_faces", shaders::collide_faces, define);
      k.holds = kHoldsDeepestPoints<Sdf<Shape, float>>;
      k.ready = true;
    }
    if (body && !k.bodyReady) {  // a coupled body's twins, which keep where each push acts
      const std::string bodyDefine = define + "#define DRAPE_BODY 1\n";
      k.verticesBody = Program("collide_vertices", shaders::collide_vertices, bodyDefine);
      k.repelBody = Program("repel", shaders::repel, bodyDefine);
      if constexpr (!Sdf<Shape, float>::kLinear)
        k.facesBody = Program("collide_faces", shaders::collide_faces, bodyDefine);
      k.bodyReady = true;
    }
  }

  /// Continuous contact's twins of the shape's vertex and face kernels (a coupled body's too, `body`), with the
  /// path searches compiled in (DRAPE_SWEEP); compiled on the first substep that sweeps, before anything moves.
  /// The other kernels leave that code out rather than branch around it: a driver that runs both sides of a
  /// branch (Mesa's llvmpipe does) would pay for it in every pass (docs/design.md §9).
  template <class Shape> void compileSweepFor(const CompiledSolid<Shape, float>&, bool body) {
    if constexpr (!Sdf<Shape, float>::kLinear) {
      ShapeKernels& k = kernels_[shapeCode<Shape>()];
      const std::string define = shapeDefine<Shape>() + "#define DRAPE_SWEEP 1\n";
      if (!k.sweepReady) {
        k.sweepVertices = Program("collide_vertices", shaders::collide_vertices, define);
        k.sweepFaces = Program("collide_faces", shaders::collide_faces, define);
        k.sweepReady = true;
      }
      if (body && !k.sweepBodyReady) {
        const std::string bodyDefine = define + "#define DRAPE_BODY 1\n";
        k.sweepVerticesBody = Program("collide_vertices", shaders::collide_vertices, bodyDefine);
        k.sweepFacesBody = Program("collide_faces", shaders::collide_faces, bodyDefine);
        k.sweepBodyReady = true;
      }
    }
  }

  /// The settle's judgement of exact points by the shape's field (settle_fields.comp), for a scene where vertices
  /// may touch several surfaces; compiled before anything moves.
  template <class Shape> void compileSettleFor(const CompiledSolid<Shape, float>&) {
    ShapeKernels& k = kernels_[shapeCode<Shape>()];
    if (!k.settleReady) {
      k.settle = Program("settle_fields", shaders::settle_fields, shapeDefine<Shape>());
      k.settleReady = true;
    }
  }

  /// The shape data a solid's field reads from its own buffer (layout::kShapeData): a mesh's grid nodes, a hull's
  /// faces and edges. Each grid is uploaded once, however many solids share it; each hull solid builds its own
  /// query data (compileSolid), so it has its own upload.
  template <class Shape> static std::shared_ptr<const void> shapeDataKey(const CompiledSolid<Shape, float>& c) {
    if constexpr (std::is_same_v<Shape, MeshShape>) return c.sdf.grid;
    else if constexpr (std::is_same_v<Shape, ConvexHull>) return c.sdf.hull;
    else return nullptr;
  }
  template <class Shape> void upload(const CompiledSolid<Shape, float>& c) {
    const std::shared_ptr<const void> key = shapeDataKey(c);
    if (!key || shapeData(key)) return;
    std::vector<layout::Vertex> v;
    if constexpr (std::is_same_v<Shape, MeshShape>) {
      const auto& nodes = c.sdf.grid->nodes;
      v.resize(nodes.size());
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = {nodes[i].x(), nodes[i].y(), nodes[i].z(), nodes[i].w()};
    } else if constexpr (std::is_same_v<Shape, ConvexHull>) {
      v = packHull(*c.sdf.hull);
    }
    shapeData_.push_back({key, Buffer<layout::Vertex>(v)});
  }
  const Buffer<layout::Vertex>* shapeData(const std::shared_ptr<const void>& key) const {
    for (const auto& d : shapeData_)
      if (d.key == key) return &d.data;
    return nullptr;
  }
  /// Frees the data no solid uses any more (held only here) after a solid was replaced.
  void dropUnused() {
    std::erase_if(shapeData_, [](const ShapeData& d) { return d.key.use_count() == 1; });
  }

  /// Solid `compiled` as this substep's kernels see it (its field packed by packShape).
  template <class Shape> SolidPass pass(const CompiledSolid<Shape, float>& compiled) const {
    SolidPass p{shapeCode<Shape>(), packShape(compiled.sdf), compiled.motion, !Sdf<Shape, float>::kLinear,
                kFacesAnswerVertices<Sdf<Shape, float>>, compiled.repulsionRadius, compiled.falloff,
                shapeData(shapeDataKey(compiled)),
                Vec3<float>::Constant(-std::numeric_limits<float>::max()),
                Vec3<float>::Constant(std::numeric_limits<float>::max())};
    if (compiled.bounded) p.boxLow = compiled.boxLow, p.boxHigh = compiled.boxHigh;
    return p;
  }

  /// A kernel's uniforms for one solid (its field and motion; for a collision kernel, `collide`, its friction and
  /// box as well), and its shape data bound.
  static void setUniforms(const Program& k, const SolidPass& p, float thickness, bool collide = true) {
    const SolidMotion<float>& m = p.motion;
    k.set(layout::kThickness, thickness);
    setShape(k.id(), p.field);
    k.set(layout::kSolidCentre, m.centre.x(), m.centre.y(), m.centre.z());
    k.set(layout::kSolidLinear, m.linearVelocity.x(), m.linearVelocity.y(), m.linearVelocity.z());
    k.set(layout::kSolidAngular, m.angularVelocity.x(), m.angularVelocity.y(), m.angularVelocity.z());
    if (p.data) p.data->bind(layout::kShapeData);
    if (m.body >= 0) glProgramUniform1i(k.id(), layout::kBody, m.body);
    if (!collide) return;  // the repel kernel declares no friction or box
    glProgramUniform2f(k.id(), layout::kFriction, m.staticFriction, m.dynamicFriction);
    k.set(layout::kBoxLow, p.boxLow.x(), p.boxLow.y(), p.boxLow.z());
    k.set(layout::kBoxHigh, p.boxHigh.x(), p.boxHigh.y(), p.boxHigh.z());
  }

  /// One solid's vertex pass (projectVertexContacts): `fresh` for the substep's first, which starts every
  /// record; `pass` the settle pass (-1: the first pass), `slack` what the settle passes leave alone.
  /// `sweep`: continuous contact's substep and gate squared, (0, 0) for none (a settle pass, or the setting off).
  /// `command` >= 0: dispatched by the command at that byte offset of buffer `commands` (Program::dispatchIndirect).
  void vertexPass(const SolidPass& p, float thickness, unsigned vertexCount, bool fresh, int pass, float slack,
                  const Eigen::Vector2f& sweep = Eigen::Vector2f::Zero(), GLuint commands = 0,
                  GLintptr command = -1) const {
    const ShapeKernels& ks = kernels_[p.code];
    const bool body = p.motion.body >= 0, swept = sweep.y() > 0;  // no sweep: the same as the kernel without it
    const Program& k =
        swept ? (body ? ks.sweepVerticesBody : ks.sweepVertices) : (body ? ks.verticesBody : ks.vertices);
    setUniforms(k, p, thickness);
    if (swept) k.set(layout::kSweep, sweep.x(), sweep.y());
    k.set(layout::kCount, vertexCount);
    k.set(layout::kSlack, slack);
    glProgramUniform1i(k.id(), layout::kPass, pass);
    k.set(layout::kFresh, unsigned(fresh));
    if (command >= 0) k.dispatchIndirect(commands, command);
    else k.dispatch(vertexCount);
  }

  /// One solid's judgement of the settle's waiting exact points (backedPlanes, clearFractions), dispatched like the
  /// settle it belongs to (`command` >= 0: by the command at that byte offset of buffer `commands`).
  void settlePass(const SolidPass& p, float thickness, unsigned vertexCount, GLuint commands = 0,
                  GLintptr command = -1) const {
    const Program& k = kernels_[p.code].settle;
    setShape(k.id(), p.field);
    k.set(layout::kThickness, thickness);
    k.set(layout::kBoxLow, p.boxLow.x(), p.boxLow.y(), p.boxLow.z());
    k.set(layout::kBoxHigh, p.boxHigh.x(), p.boxHigh.y(), p.boxHigh.z());
    k.set(layout::kCount, vertexCount);
    if (p.data) p.data->bind(layout::kShapeData);
    if (command >= 0) k.dispatchIndirect(commands, command);
    else k.dispatch(vertexCount);
  }

  /// One curved solid's face pass (projectFaceContacts), colour by colour. `heldPlace`: the solid's place among all
  /// the solids + 1, whose held deepest points the pass reads and writes (layout::kHeld), 0 for none.
  void facePass(const SolidPass& p, float thickness, int pgdIterations, const std::vector<std::size_t>& colourOffsets,
                const Eigen::Vector2f& sweep = Eigen::Vector2f::Zero(), unsigned heldPlace = 0) const {
    const ShapeKernels& ks = kernels_[p.code];
    const bool body = p.motion.body >= 0, swept = sweep.y() > 0;
    const Program& k = swept ? (body ? ks.sweepFacesBody : ks.sweepFaces) : (body ? ks.facesBody : ks.faces);
    setUniforms(k, p, thickness);
    if (ks.holds) k.set(layout::kHeldPlace, heldPlace);
    if (swept) k.set(layout::kSweep, sweep.x(), sweep.y());
    glProgramUniform1i(k.id(), layout::kPgdIterations, pgdIterations);
    for (std::size_t c = 0; c + 1 < colourOffsets.size(); ++c) {
      const std::size_t count = colourOffsets[c + 1] - colourOffsets[c];
      k.set(layout::kFirst, unsigned(colourOffsets[c]));
      k.set(layout::kCount, unsigned(count));
      k.dispatch(count);
    }
  }

  /// Continuous contact's friction guard against one curved solid (markFrictionCrossings): each of the `faceCount`
  /// faces that friction carried within `reach` of the solid on the way, and that the solid then pierces, marks
  /// its corners. The kernel is compiled on a guarded scene's first substep, before anything moves.
  template <class Shape> void compileGuardFor(const CompiledSolid<Shape, float>&) {
    ShapeKernels& k = kernels_[shapeCode<Shape>()];
    if constexpr (!Sdf<Shape, float>::kLinear)
      if (!k.guardReady) {
        k.guard = Program("collide_faces", shaders::collide_faces, shapeDefine<Shape>() + "#define DRAPE_GUARD 1\n");
        k.guardReady = true;
      }
  }
  /// Whether the solid's shape has the guard's kernel (compileGuardFor).
  bool guards(const SolidPass& p) const { return kernels_[p.code].guardReady; }
  void guardPass(const SolidPass& p, float reach, int pgdIterations, std::size_t faceCount) const {
    const Program& k = kernels_[p.code].guard;
    setUniforms(k, p, reach);
    glProgramUniform1i(k.id(), layout::kPgdIterations, pgdIterations);
    k.set(layout::kFirst, 0u);
    k.set(layout::kCount, unsigned(faceCount));
    k.dispatch(faceCount);
  }

  /// One solid's repulsion region over `vertexCount` vertices; a coupled body's kernel also writes each vertex's
  /// push on the body (h the substep, `normalOnly` as Settings::normalForceOnly).
  void repel(const SolidPass& p, float thickness, unsigned vertexCount, float h, bool normalOnly) const {
    const bool body = p.motion.body >= 0;
    const Program& k = body ? kernels_[p.code].repelBody : kernels_[p.code].repel;
    setUniforms(k, p, thickness, false);
    k.set(layout::kCount, vertexCount);
    glProgramUniform2f(k.id(), layout::kRepulsion, 1.0f / p.repulsionRadius, p.falloff == Falloff::Smooth ? 1.0f : 0.0f);
    if (body) {
      k.set(layout::kStep, h);
      k.set(layout::kNormalOnly, unsigned(normalOnly));
    }
    k.dispatch(vertexCount);
  }

 private:
  struct ShapeKernels {  ///< the collision kernels compiled for one shape type (compileFor)
    Program vertices, faces, repel;
    Program verticesBody, facesBody, repelBody;  ///< for a coupled body's solid: its lines and pushes kept too
    Program guard;                               ///< the friction guard (compileGuardFor)
    Program settle;                              ///< the settle's judgement of exact points (compileSettleFor)
    Program sweepVertices, sweepFaces, sweepVerticesBody, sweepFacesBody;  ///< with the path searches (compileSweepFor)
    bool ready = false, bodyReady = false, guardReady = false, sweepReady = false, sweepBodyReady = false,
         settleReady = false;
    bool holds = false;  ///< the face pass holds deepest points (kHoldsDeepestPoints): it takes layout::kHeldPlace
  };
  std::array<ShapeKernels, 8> kernels_;  ///< by layout::ShapeCode
  struct ShapeData {
    std::shared_ptr<const void> key;  ///< the grid or hull query data it was made from
    Buffer<layout::Vertex> data;
  };
  std::vector<ShapeData> shapeData_;  ///< every grid and hull the solids use, uploaded once each
};

}  // namespace drape::gpu
