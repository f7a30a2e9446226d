#pragma once
// The rigid-body rain of the cloth-rigid coupling thesis's Fig 6.6: a horizontal 50x80 cloth pinned at its four
// corners half a metre above the floor, and N rigid bodies of random shape (sphere, box, capsule, cylinder,
// convex hull), size, position, orientation and velocity falling onto it, each coupled two ways with
// addCoupledBody and stepped with stepCoupled. After `release` seconds the corners are let go and the cloth and
// the bodies fall to the floor together. Everything random comes from one std::mt19937 seeded from the
// configuration, so a seed reproduces the run exactly. Shared by samples/rigid_rain and bench/bench_rigid_rain.
// Needs libccd (link drape::rigid).

#include <drape/drape.hpp>
#include <drape/coupling/rigid_world.hpp>
#include <drape/sdf/grid.hpp>  // detail::closestOnTriangle
#include <drape/sdf/convex.hpp>  // the bodies' own distance fields (bodyPenetrationAtBodies)

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace drape::scenes {

/// The shapes the rain draws from, as bits of RainConfig::shapes.
enum class RainShape : unsigned { Sphere = 1, Box = 2, Capsule = 4, Cylinder = 8, Hull = 16 };
inline constexpr unsigned kAllRainShapes = 31;
inline constexpr std::array<RainShape, 5> kRainShapes{RainShape::Sphere, RainShape::Box, RainShape::Capsule,
                                                     RainShape::Cylinder, RainShape::Hull};

inline const char* toString(RainShape s) {
  switch (s) {
    case RainShape::Sphere: return "sphere";
    case RainShape::Box: return "box";
    case RainShape::Capsule: return "capsule";
    case RainShape::Cylinder: return "cylinder";
    case RainShape::Hull: return "hull";
  }
  return "?";
}
/// The RainShape named by toString, or throws drape::Error.
inline RainShape rainShapeFromString(const std::string& name) {
  for (RainShape s : kRainShapes)
    if (name == toString(s)) return s;
  throw Error("unknown rain shape '" + name + "' (sphere, box, capsule, cylinder, hull)");
}
/// The ContactForce named by toString(ContactForce), or throws drape::Error (settings.hpp).
using drape::contactForceFromString;

/// The RainShape bits whose bodies `ClothSolver` can take as solids (addCoupledBody needs the shape type).
template <class ClothSolver> constexpr unsigned supportedRainShapes() {
  return (ClothSolver::template kHasShape<Sphere> ? unsigned(RainShape::Sphere) : 0u) |
         (ClothSolver::template kHasShape<Box> ? unsigned(RainShape::Box) : 0u) |
         (ClothSolver::template kHasShape<Capsule> ? unsigned(RainShape::Capsule) : 0u) |
         (ClothSolver::template kHasShape<Cylinder> ? unsigned(RainShape::Cylinder) : 0u) |
         (ClothSolver::template kHasShape<ConvexHull> ? unsigned(RainShape::Hull) : 0u);
}
/// The names of the shapes in a RainShape mask, comma-separated.
inline std::string rainShapeNames(unsigned shapes) {
  std::string out;
  for (RainShape s : kRainShapes)
    if (shapes & unsigned(s)) out += (out.empty() ? "" : ",") + std::string(toString(s));
  return out;
}

struct RainConfig {
  int bodies = 20;
  std::uint32_t seed = 1;
  ContactForce estimator = ContactForce::Impulse;
  unsigned shapes = kAllRainShapes;  ///< RainShape bits; each body's shape is drawn uniformly from the set ones
  int nx = 50, ny = 80;              ///< cloth vertices along x and y
  double spacing = 0.02;             ///< m
  double clothHeight = 0.5;          ///< m above the floor
  double areaDensity = 0.1;          ///< kg/m^2
  double dt = 0.01;                  ///< s per step (the thesis's)
  int subSteps = 10;
  double release = 1.5;  ///< s: the corners are let go before the first step that starts at or after it
  double minSize = 0.03, maxSize = 0.08;  ///< m: a body's size d, its largest dimension (see makeRainBody)
  double minDrop = 0.7, maxDrop = 2.0;    ///< m: heights of the bodies' centres at the start
  double maxSpeed = 1.5;                  ///< m/s: largest initial speed (random direction)
  double maxSpin = 5;                     ///< rad/s: largest initial angular speed (random axis)
  double density = 500;                   ///< kg/m^3 of every body
  double bodyFriction = 0.3;   ///< cloth against the bodies (static and dynamic)
  double floorFriction = 0.5;  ///< cloth against the floor (static and dynamic)
  /// Cloth settings besides subStepCount and contactForce (threadCount 1 by default). Continuous contact is on:
  /// the bodies land at up to 6 m/s, more than the thickness per substep, and without it they pass through the
  /// cloth lying on the floor (docs/design.md §17, "Fast bodies").
  Settings base = [] {
    Settings s;
    s.continuousContact = true;
    return s;
  }();
  RigidSettings rigid{};  ///< the world's (its ground at z = 0; subStepCount is not used by stepCoupled)

  void validate() const {
    using detail::require;
    require(bodies >= 0 && bodies <= 10000, "bodies must be in [0, 10000] (got " + std::to_string(bodies) + ")");
    require(shapes != 0 && (shapes & ~kAllRainShapes) == 0, "shapes must name at least one rain shape");
    require(nx >= 2 && ny >= 2, "nx and ny must be >= 2");
    require(std::isfinite(spacing) && spacing > 0, "spacing must be positive");
    require(std::isfinite(clothHeight) && clothHeight > 0, "clothHeight must be positive");
    require(std::isfinite(dt) && dt > 0, "dt must be positive");
    require(subSteps >= 1, "subSteps must be >= 1");
    require(!std::isnan(release) && release >= 0, "release must be >= 0 s (infinity: never)");
    require(std::isfinite(minSize) && minSize > 0 && minSize <= maxSize && std::isfinite(maxSize),
            "sizes must satisfy 0 < minSize <= maxSize");
    require(std::isfinite(minDrop) && std::isfinite(maxDrop) && minDrop <= maxDrop, "drop heights: minDrop <= maxDrop");
    require(std::isfinite(maxSpeed) && maxSpeed >= 0 && std::isfinite(maxSpin) && maxSpin >= 0,
            "maxSpeed and maxSpin must be >= 0");
    require(std::isfinite(density) && density > 0, "density must be positive");
  }
};

namespace rain_detail {

inline double uniform(std::mt19937& rng, double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }

/// A unit vector uniform on the sphere.
inline Eigen::Vector3d randomDirection(std::mt19937& rng) {
  const double z = uniform(rng, -1, 1), phi = uniform(rng, 0, 2 * std::numbers::pi);
  const double r = std::sqrt(std::max(0.0, 1 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

/// A rotation uniform over SO(3) (Shoemake), from `rng` (Eigen's UnitRandom uses std::rand).
inline Eigen::Quaterniond randomRotation(std::mt19937& rng) {
  const double u1 = uniform(rng, 0, 1), u2 = uniform(rng, 0, 2 * std::numbers::pi),
               u3 = uniform(rng, 0, 2 * std::numbers::pi);
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  return Eigen::Quaterniond(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3)).normalized();
}

}  // namespace rain_detail

/// A body's shape of size d (m, its largest dimension): a sphere of diameter d; a box with one edge d and the
/// others 0.5-1 d; a capsule d long, 0.35-0.6 d wide; a cylinder whose diameter and length are each 0.5-1 d,
/// one of them d; a convex hull of 12 points at 0.6-1 times d/2 from the centre in random directions.
inline RigidShape makeRainShape(RainShape kind, double d, std::mt19937& rng) {
  using rain_detail::uniform;
  const double h = 0.5 * d;
  switch (kind) {
    case RainShape::Sphere: return Sphere{h};
    case RainShape::Box: return Box{Eigen::Vector3d(h, h * uniform(rng, 0.5, 1), h * uniform(rng, 0.5, 1))};
    case RainShape::Capsule: {
      const double r = h * uniform(rng, 0.35, 0.6);
      return Capsule{r, h - r};
    }
    case RainShape::Cylinder: {
      const double other = h * uniform(rng, 0.5, 1);
      return uniform(rng, 0, 1) < 0.5 ? Cylinder{h, other} : Cylinder{other, h};
    }
    case RainShape::Hull: {
      std::vector<Eigen::Vector3d> points;
      for (int k = 0; k < 12; ++k) points.push_back(h * uniform(rng, 0.6, 1) * rain_detail::randomDirection(rng));
      return ConvexHull(points);  // 12 points on distinct random directions span a volume (almost surely)
    }
  }
  throw Error("makeRainShape: not a rain shape");
}

/// The scene. Not copyable or movable: the cloth's dynamic solids point at the world's bodies.
template <Scalar S, class ClothSolver = Solver<S>> class RigidRain {
 public:
  /// The scene on a cloth solver made from `prefix...` (e.g. the GPU solver's context), then the asset, settings
  /// and area density.
  template <class... Prefix>
  explicit RigidRain(const RainConfig& c, Prefix&... prefix)
      : config_((c.validate(), c)),
        world_(c.rigid),
        cloth_(prefix..., makeAsset(c), clothSettings(c), c.areaDensity) {
    // The corners, pinned until the release; their inverse masses are kept to give back.
    const Index nx = c.nx, ny = c.ny;
    corners_ = {0, nx - 1, (ny - 1) * nx, ny * nx - 1};
    for (Index i : corners_) {
      cornerInvMass_.push_back(double(cloth_.state().invMass[i]));
      cloth_.pin(i);
    }
    Solid<Plane> floor;  // z = 0, the world's ground as well
    floor.staticFriction = floor.dynamicFriction = c.floorFriction;
    cloth_.addSolid(floor);

    std::mt19937 rng(c.seed);
    using rain_detail::uniform;
    std::vector<RainShape> allowed;
    for (RainShape s : kRainShapes)
      if (c.shapes & unsigned(s)) allowed.push_back(s);
    const double halfX = 0.5 * (c.nx - 1) * c.spacing, halfY = 0.5 * (c.ny - 1) * c.spacing;
    std::vector<Eigen::Vector3d> centres;
    std::vector<double> radii;
    CouplingDesc coupling;
    coupling.staticFriction = coupling.dynamicFriction = c.bodyFriction;
    for (int i = 0; i < c.bodies; ++i) {
      const RainShape kind = allowed[std::uniform_int_distribution<std::size_t>(0, allowed.size() - 1)(rng)];
      BodyDesc b;
      b.shape = makeRainShape(kind, uniform(rng, c.minSize, c.maxSize), rng);
      const double r = drape::detail::boundingRadius(b.shape);
      // Over the cloth (centres at least r inside its edges), not overlapping any earlier body.
      bool placed = false;
      for (int attempt = 0; attempt < 100000 && !placed; ++attempt) {
        const Eigen::Vector3d p(uniform(rng, -halfX + r, halfX - r), uniform(rng, -halfY + r, halfY - r),
                                uniform(rng, c.minDrop, c.maxDrop));
        placed = true;
        for (std::size_t k = 0; k < centres.size() && placed; ++k)
          placed = (p - centres[k]).norm() > r + radii[k] + 0.005;
        if (placed) b.pose.position = p;
      }
      drape::detail::require(placed, "rigid rain: no room for body " + std::to_string(i) +
                                         " without overlapping another; use fewer bodies or a larger drop range");
      centres.push_back(b.pose.position);
      radii.push_back(r);
      b.pose.rotation = rain_detail::randomRotation(rng);
      b.linearVelocity = uniform(rng, 0, c.maxSpeed) * rain_detail::randomDirection(rng);
      b.angularVelocity = uniform(rng, 0, c.maxSpin) * rain_detail::randomDirection(rng);
      b.density = c.density;
      const int index = world_.add(b);
      const bool supported = std::visit(
          [](const auto& shape) { return ClothSolver::template kHasShape<std::decay_t<decltype(shape)>>; },
          b.shape);
      drape::detail::require(supported, std::string("rigid rain: this build's cloth solver has no distance field for ") +
                                            toString(kind) + " bodies; leave " + toString(kind) + " out of the shapes");
      addCoupledBody(cloth_, world_, index, coupling);
      kinds_.push_back(kind);
    }
  }
  RigidRain(const RigidRain&) = delete;
  RigidRain& operator=(const RigidRain&) = delete;

  /// One stepCoupled of config().dt, the corners let go first when it is time; onSubStep(cloth) after each
  /// substep of the cloth and the world.
  template <class Observer> void step(Observer&& onSubStep) {
    if (!released_ && time_ >= config_.release - 1e-9) release();
    stepCoupled(cloth_, world_, config_.dt, std::forward<Observer>(onSubStep));
    time_ += config_.dt;
  }
  void step() {
    step([](const ClothSolver&) {});
  }
  /// Gives the corners back their inverse masses (once).
  void release() {
    if (released_) return;
    for (std::size_t k = 0; k < corners_.size(); ++k) cloth_.setInverseMass(corners_[k], cornerInvMass_[k]);
    released_ = true;
  }

  const RainConfig& config() const { return config_; }
  ClothSolver& cloth() { return cloth_; }
  const ClothSolver& cloth() const { return cloth_; }
  RigidWorld& world() { return world_; }
  const RigidWorld& world() const { return world_; }
  double time() const { return time_; }
  bool released() const { return released_; }
  const std::vector<Index>& corners() const { return corners_; }
  /// Body k's shape kind (body k of world()).
  const std::vector<RainShape>& kinds() const { return kinds_; }

 private:
  static std::shared_ptr<const ClothAsset<S>> makeAsset(const RainConfig& c) {
    SheetDesc grid;
    grid.nx = c.nx;
    grid.ny = c.ny;
    grid.spacing = c.spacing;
    grid.placement.position = Eigen::Vector3d(0, 0, c.clothHeight);
    return std::make_shared<const ClothAsset<S>>(ClothAsset<S>::sheet(grid));
  }
  static Settings clothSettings(const RainConfig& c) {
    Settings s = c.base;
    s.subStepCount = c.subSteps;
    s.contactForce = c.estimator;
    return s;
  }

  RainConfig config_;
  RigidWorld world_;
  ClothSolver cloth_;
  std::vector<Index> corners_;
  std::vector<double> cornerInvMass_;
  std::vector<RainShape> kinds_;
  double time_ = 0;
  bool released_ = false;
};

/// Counts bodies passing through the cloth's sheet. Each observation finds, for every body, the point of the sheet
/// nearest its centre and the side of the sheet the centre is on: along the normal of the face there, or, where
/// the nearest point is on an edge or a corner shared by several faces, along the angle-weighted normal of those
/// faces (Bærentzen and Aanæs, "Signed distance computation using the angle weighted pseudonormal", 2005), which
/// gives the right side at a crease. A body is through when that side flips between two observations in a row,
/// both of them near the sheet (the centre within the body's bounding radius plus `margin` of it), unless the face
/// that was nearest at the first of them still has it on its old side: a cloth folded over a body lies over it in
/// two layers of opposite orientation, and the nearest point can jump from one to the other while the body lies
/// still (a body at rest under the fallen cloth in the rain was counted 13 times without it); nor where that face
/// now has the centre nearest its boundary, which no crossing of the interior leaves (seed 78 of the rain: a body
/// under the fold of a free edge, the nearest point moving from the edge's faces to the layer under them). A centre
/// whose nearest point is on the sheet's boundary has no side: a body that fell past the cloth's edge and that
/// the edge then swung over has gone around the sheet, not through it. A body that crosses is seen on both sides
/// as long as it moves less than `margin` relative to the sheet between two readings (the rain's bodies reach
/// 8 m/s, 8 cm a step, 8 mm a substep). Read after every substep (the rain's sample and tests do): read once a
/// step, a body under a fold near a free edge whose nearest point moved to the other layer, and a body that
/// rounded a free edge, were counted where no reading between them would have. Such a body can still be seen on
/// both sides of the sheet between two substeps, so each body counted through is also counted by where it was:
/// at the border, where the sheet's vertex nearest its centre at the reading that counted it lies within one ring
/// of vertices of the boundary (on a sheet of rows and columns, in the border row or column or the one beside it),
/// or in the interior, where no contact's failure can be mistaken for a walk around the edge.
class SheetCrossings {
 public:
  /// The margin for readings `interval` seconds apart: what a body moving at 30 m/s relative to the sheet covers
  /// between two (the rain's bodies land at up to 8 m/s; its fastest cloth vertices reach 60 m/s rarely). Read
  /// after every substep of 1 ms, 3 cm: a body further than its bounding radius and that from the sheet does not
  /// touch it, and a flip there is the sheet curling past it (seed 57 of the rain, a body falling past a pinned
  /// corner 9 cm from the cloth).
  static double marginFor(double interval) { return 30.0 * interval; }

  template <Scalar S> explicit SheetCrossings(const ClothAsset<S>& asset, double margin = 0.1)
      : triangles_(asset.triangles), margin_(margin), vertexFaces_(std::size_t(asset.vertexCount())) {
    std::map<std::pair<Index, Index>, int> edgeUses;
    for (std::size_t f = 0; f < triangles_.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const Index a = triangles_[f][std::size_t(k)], b = triangles_[f][std::size_t((k + 1) % 3)];
        ++edgeUses[{std::min(a, b), std::max(a, b)}];
        vertexFaces_[std::size_t(a)].push_back(Index(f));
      }
    boundaryVertex_.assign(std::size_t(asset.vertexCount()), false);
    for (const auto& [edge, uses] : edgeUses)
      if (uses == 1) {
        boundaryEdges_.insert(edge);
        boundaryVertex_[std::size_t(edge.first)] = boundaryVertex_[std::size_t(edge.second)] = true;
      }
    // Each vertex's ring: how many edges from the boundary, breadth first from it.
    std::vector<std::vector<Index>> neighbours(std::size_t(asset.vertexCount()));
    for (const auto& entry : edgeUses) {
      const auto& [a, b] = entry.first;
      neighbours[std::size_t(a)].push_back(b);
      neighbours[std::size_t(b)].push_back(a);
    }
    ring_.assign(std::size_t(asset.vertexCount()), -1);
    std::vector<Index> queue;
    for (Index v = 0; v < asset.vertexCount(); ++v)
      if (boundaryVertex_[std::size_t(v)]) ring_[std::size_t(v)] = 0, queue.push_back(v);
    for (std::size_t k = 0; k < queue.size(); ++k)
      for (Index w : neighbours[std::size_t(queue[k])])
        if (ring_[std::size_t(w)] < 0) ring_[std::size_t(w)] = ring_[std::size_t(queue[k])] + 1, queue.push_back(w);
  }

  /// Reads every body's side of the sheet and counts the flips since the last observation.
  template <class ClothSolver> void observe(const ClothSolver& cloth, const RigidWorld& world) {
    const Index n = cloth.vertexCount();
    x_.resize(std::size_t(n));
    for (Index i = 0; i < n; ++i) x_[std::size_t(i)] = cloth.position(i);
    longestEdge_ = 0;
    for (const auto& t : triangles_)
      for (int k = 0; k < 3; ++k)
        longestEdge_ = std::max(longestEdge_, (at(t[std::size_t(k)]) - at(t[std::size_t((k + 1) % 3)])).norm());
    side_.resize(std::size_t(world.bodyCount()), 0);
    face_.resize(std::size_t(world.bodyCount()), -1);
    through_.resize(std::size_t(world.bodyCount()), false);
    atBorder_.resize(std::size_t(world.bodyCount()), false);
    for (int b = 0; b < world.bodyCount(); ++b) {
      const Eigen::Vector3d c = world.body(b).pose().position;
      Index face = -1, nearest = -1;
      const int now = sideOf(c, world.body(b).boundingRadius(), face, nearest);
      int& before = side_[std::size_t(b)];
      if (now == kOnSheet) continue;  // the last side stands
      // A flip does not count where the face that was nearest before still has the body on its old side: under a
      // fold the nearest point can jump between two layers of opposite orientation while the body lies still. Nor
      // where that face now has the body nearest its boundary: it went around that edge, or lies under its fold.
      const int then = now != 0 && before != 0 && now != before ? sideAgainst(c, face_[std::size_t(b)]) : before;
      if (then != before && then != 0) {
        ++crossings_;
        if (!through_[std::size_t(b)]) atBorder_[std::size_t(b)] = ring_[std::size_t(nearest)] <= 1;
        through_[std::size_t(b)] = true;
      }
      before = now;
      face_[std::size_t(b)] = face;
    }
  }

  int crossings() const { return crossings_; }  ///< flips counted so far
  /// Bodies that have passed through the sheet at least once.
  int bodiesThrough() const { return int(std::count(through_.begin(), through_.end(), true)); }
  /// Whether body b has passed through the sheet at least once.
  bool passed(int b) const { return std::size_t(b) < through_.size() && through_[std::size_t(b)]; }
  /// Whether body b, counted through, was at the border when first counted (see the class's comment).
  bool passedAtBorder(int b) const { return passed(b) && atBorder_[std::size_t(b)]; }
  /// Bodies counted through the sheet's interior: their first count away from its border.
  int bodiesThroughInterior() const {
    int count = 0;
    for (std::size_t b = 0; b < through_.size(); ++b) count += through_[b] && !atBorder_[b];
    return count;
  }

 private:
  const Eigen::Vector3d& at(Index i) const { return x_[std::size_t(i)]; }
  Eigen::Vector3d faceNormal(Index f) const {
    const auto& t = triangles_[std::size_t(f)];
    return (at(t[1]) - at(t[0])).cross(at(t[2]) - at(t[0])).normalized();
  }
  static constexpr int kOnSheet = 2;
  /// +1 or -1 for the side of the sheet `c` is on, 0 where it has none (far from the sheet, or nearest its
  /// boundary), kOnSheet on it; `face` is the face holding the nearest point (-1 where there is none), `vertex`
  /// the vertex nearest `c`.
  int sideOf(const Eigen::Vector3d& c, double radius, Index& face, Index& vertex) const {
    face = -1;
    vertex = 0;
    double nearestVertex = 1e300;
    for (std::size_t i = 0; i < x_.size(); ++i) {
      const double d = (x_[i] - c).squaredNorm();
      if (d < nearestVertex) nearestVertex = d, vertex = Index(i);
    }
    nearestVertex = std::sqrt(nearestVertex);
    if (nearestVertex > radius + margin_ + longestEdge_) return 0;
    // The nearest point of the sheet is no further than the nearest vertex, so a face holding it has every
    // corner within that distance plus the face's longest edge.
    const double reach = nearestVertex + longestEdge_;
    double best = 1e300;
    Index bestFace = -1;
    detail::ClosestOnTriangle nearest;
    for (std::size_t f = 0; f < triangles_.size(); ++f) {
      const auto& t = triangles_[f];
      if ((at(t[0]) - c).norm() > reach) continue;
      const detail::ClosestOnTriangle q = detail::closestOnTriangle(c, at(t[0]), at(t[1]), at(t[2]));
      const double d = (q.point - c).squaredNorm();
      if (d < best) best = d, bestFace = Index(f), nearest = q;
    }
    if (bestFace < 0 || std::sqrt(best) > radius + margin_) return 0;
    face = bestFace;
    return sideAt(c, bestFace, nearest);
  }
  /// The side of `c` against face f alone, at its point nearest `c` (0 for none, or no face).
  int sideAgainst(const Eigen::Vector3d& c, Index f) const {
    if (f < 0) return 0;
    const auto& t = triangles_[std::size_t(f)];
    return sideAt(c, f, detail::closestOnTriangle(c, at(t[0]), at(t[1]), at(t[2])));
  }
  /// The side of `c` against the point `nearest` of face `bestFace`, along the pseudonormal of the feature it
  /// lies on.
  int sideAt(const Eigen::Vector3d& c, Index bestFace, const detail::ClosestOnTriangle& nearest) const {
    using detail::TriangleFeature;
    const auto& t = triangles_[std::size_t(bestFace)];
    const Eigen::Vector3d& p = nearest.point;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    auto vertexNormal = [&](Index v) {  // angle-weighted, or none on the boundary
      if (boundaryVertex_[std::size_t(v)]) return Eigen::Vector3d::Zero().eval();
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (Index f : vertexFaces_[std::size_t(v)]) {
        const auto& u = triangles_[std::size_t(f)];
        const int k = u[0] == v ? 0 : (u[1] == v ? 1 : 2);
        const Eigen::Vector3d e1 = at(u[std::size_t((k + 1) % 3)]) - at(v);
        const Eigen::Vector3d e2 = at(u[std::size_t((k + 2) % 3)]) - at(v);
        sum += std::acos(std::clamp(e1.normalized().dot(e2.normalized()), -1.0, 1.0)) * faceNormal(f);
      }
      return sum;
    };
    auto edgeNormal = [&](Index a, Index b) {  // the two faces' normals, or none on the boundary
      if (boundaryEdges_.count({std::min(a, b), std::max(a, b)})) return Eigen::Vector3d::Zero().eval();
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (Index f : vertexFaces_[std::size_t(a)]) {
        const auto& u = triangles_[std::size_t(f)];
        if (u[0] == b || u[1] == b || u[2] == b) sum += faceNormal(f);
      }
      return sum;
    };
    switch (nearest.feature) {
      case TriangleFeature::VertexA: normal = vertexNormal(t[0]); break;
      case TriangleFeature::VertexB: normal = vertexNormal(t[1]); break;
      case TriangleFeature::VertexC: normal = vertexNormal(t[2]); break;
      case TriangleFeature::EdgeAB: normal = edgeNormal(t[0], t[1]); break;
      case TriangleFeature::EdgeBC: normal = edgeNormal(t[1], t[2]); break;
      case TriangleFeature::EdgeCA: normal = edgeNormal(t[2], t[0]); break;
      case TriangleFeature::Face: normal = faceNormal(bestFace); break;
    }
    if (normal.squaredNorm() == 0) return 0;  // the boundary's: no side
    const double s = normal.dot(c - p);
    return s > 0 ? 1 : (s < 0 ? -1 : kOnSheet);
  }
  std::vector<std::array<Index, 3>> triangles_;
  double margin_;
  std::vector<std::vector<Index>> vertexFaces_;
  std::set<std::pair<Index, Index>> boundaryEdges_;
  std::vector<bool> boundaryVertex_;
  std::vector<int> ring_;  ///< each vertex's count of edges from the boundary
  std::vector<Eigen::Vector3d> x_;
  double longestEdge_ = 0;
  std::vector<int> side_;
  std::vector<Index> face_;  ///< each body's nearest face at the last reading
  std::vector<bool> through_;
  std::vector<bool> atBorder_;  ///< by body: first counted through at the border
  int crossings_ = 0;
};

/// Deepest cloth vertex inside any coupled body (m, 0 if none), with the distance fields the cloth solved
/// against in the last substep (forEachSolid; a dynamic solid sits where its body was carried to at that
/// substep's end). The floor plane is left out. Vertices further than `cullRadius` from a solid's centre (at
/// least the largest body's bounding radius) are skipped: they cannot be inside.
template <class ClothSolver> double bodyPenetration(const ClothSolver& cloth, double cullRadius) {
  using S = typename ClothSolver::scalar_type;
  const auto& x = cloth.state().x;
  const S r2 = S(cullRadius * cullRadius);
  double minPhi = 0;
  cloth.forEachSolid([&](const auto& solid) {
    if constexpr (!std::is_same_v<std::decay_t<decltype(solid)>, CompiledSolid<Plane, S>>) {
      for (const auto& p : x) {
        if ((p - solid.motion.centre).squaredNorm() > r2) continue;
        Vec3<S> n;
        minPhi = std::min(minPhi, double(solid.sdf(p, n)));
      }
    }
  });
  return -minPhi;
}

/// The same against the bodies where they are now (after the world's last substep), from their own shapes.
template <class ClothSolver> double bodyPenetrationAtBodies(const ClothSolver& cloth, const RigidWorld& world) {
  using S = typename ClothSolver::scalar_type;
  const auto& x = cloth.state().x;
  const Eigen::Vector3d origin = cloth.state().origin;
  double minPhi = 0;
  for (int b = 0; b < world.bodyCount(); ++b) {
    const RigidBody& body = world.body(b);
    const Pose pose = body.pose();
    const Vec3<S> centre = (pose.position - origin).template cast<S>();
    const S r2 = S(body.boundingRadius() * body.boundingRadius());
    std::visit(
        [&](const auto& shape) {
          const auto sdf = drape::detail::compileSdf<S>(shape, pose, origin);
          for (const auto& p : x) {
            if ((p - centre).squaredNorm() > r2) continue;
            Vec3<S> n;
            minPhi = std::min(minPhi, double(sdf(p, n)));
          }
        },
        body.shape());
  }
  return -minPhi;
}

}  // namespace drape::scenes
