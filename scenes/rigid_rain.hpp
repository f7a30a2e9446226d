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

  /// The scene's mechanical energy (J): the dynamic bodies' and the free cloth vertices' kinetic energy and their
  /// gravitational potential above the floor (z = 0). Nothing does work on the scene (the pinned corners stand
  /// still, the floor is fixed), so it never rises above its start.
  double mechanicalEnergy() const {
    double e = world_.kineticEnergy();
    for (int b = 0; b < world_.bodyCount(); ++b) {
      const auto& body = world_.body(b);
      if (body.isDynamic())
        e -= body.massProperties().mass * world_.settings().gravity.dot(body.state.pose.position);
    }
    const Eigen::Vector3d g = cloth_.settings().gravity;
    for (Index i = 0; i < cloth_.vertexCount(); ++i) {
      const double w = double(cloth_.state().invMass[i]);
      if (w > 0) e += (0.5 * cloth_.velocity(i).squaredNorm() - g.dot(cloth_.position(i))) / w;
    }
    return e;
  }

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

/// Counts bodies passing through the cloth's sheet. Between two readings every cloth vertex and every body's centre
/// are taken to move in straight lines, as the solver moves a vertex within a substep, and a body is through when its
/// centre's path meets a face of the sheet swept along its corners' paths: when the centre crosses the plane of a
/// face, at a moment it lies inside that face (the coplanarity cubic of a point and a moving triangle, as continuous
/// collision detection solves it; Provot, "Collision and self-collision handling in cloth model dedicated to design
/// garments", 1997). So a body that goes around a free edge, lies under a fold whose layers swap as the nearest, or
/// sits beside a fold of the sheet that turns over through itself (the solver has no cloth-cloth contact) is not
/// counted, however the sheet's nearest point and its side jump: no face passed through its centre. A body counted
/// through is also counted by where: at the border, where the corner of the crossed face nearest the crossing lies
/// within one ring of vertices of the boundary (on a sheet of rows and columns, the border row or column or the one
/// beside it), or in the interior. Read after every substep (the rain's sample and tests do), the straight paths are
/// the solver's own; read once a step they approximate curved ones.
class SheetCrossings {
 public:
  template <Scalar S> explicit SheetCrossings(const ClothAsset<S>& asset) : triangles_(asset.triangles) {
    std::map<std::pair<Index, Index>, int> edgeUses;
    for (const auto& t : triangles_)
      for (int k = 0; k < 3; ++k) {
        const Index a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
        ++edgeUses[{std::min(a, b), std::max(a, b)}];
      }
    // Each vertex's ring: how many edges from the boundary, breadth first from it.
    std::vector<std::vector<Index>> neighbours(std::size_t(asset.vertexCount()));
    ring_.assign(std::size_t(asset.vertexCount()), -1);
    std::vector<Index> queue;
    for (const auto& [edge, uses] : edgeUses) {
      neighbours[std::size_t(edge.first)].push_back(edge.second);
      neighbours[std::size_t(edge.second)].push_back(edge.first);
      if (uses == 1)
        for (Index v : {edge.first, edge.second})
          if (ring_[std::size_t(v)] < 0) ring_[std::size_t(v)] = 0, queue.push_back(v);
    }
    for (std::size_t k = 0; k < queue.size(); ++k)
      for (Index w : neighbours[std::size_t(queue[k])])
        if (ring_[std::size_t(w)] < 0) ring_[std::size_t(w)] = ring_[std::size_t(queue[k])] + 1, queue.push_back(w);
  }

  /// Reads the sheet and the bodies' centres and counts the crossings since the last reading.
  template <class ClothSolver> void observe(const ClothSolver& cloth, const RigidWorld& world) {
    const std::size_t n = std::size_t(cloth.vertexCount()), bodies = std::size_t(world.bodyCount());
    x1_.resize(n);
    for (std::size_t i = 0; i < n; ++i) x1_[i] = cloth.position(Index(i));
    c1_.resize(bodies);
    for (std::size_t b = 0; b < bodies; ++b) c1_[b] = world.body(int(b)).pose().position;
    if (x0_.size() == n) {
      c0_.resize(bodies, Eigen::Vector3d::Zero());
      for (std::size_t b = seen_; b < bodies; ++b) c0_[b] = c1_[b];  // a body added since stands still
      through_.resize(bodies, false);
      atBorder_.resize(bodies, false);
      sweep();
    }
    seen_ = bodies;
    std::swap(x0_, x1_);
    std::swap(c0_, c1_);
  }

  int crossings() const { return crossings_; }  ///< crossings counted so far
  /// Bodies that have passed through the sheet at least once.
  int bodiesThrough() const { return int(std::count(through_.begin(), through_.end(), true)); }
  /// Whether body b has passed through the sheet at least once.
  bool passed(int b) const { return std::size_t(b) < through_.size() && through_[std::size_t(b)]; }
  /// Whether body b, counted through, was at the border when first counted (see the class's comment).
  bool passedAtBorder(int b) const { return passed(b) && atBorder_[std::size_t(b)]; }
  /// Bodies counted through the sheet's interior: their first crossing away from its border.
  int bodiesThroughInterior() const {
    int count = 0;
    for (std::size_t b = 0; b < through_.size(); ++b) count += through_[b] && !atBorder_[b];
    return count;
  }

  /// When `p`, moving from p0 to p1, meets the triangle whose corners move from a0, b0, c0 to a1, b1, c1, each
  /// along a straight line over t in [0, 1]: the first such t, or a negative value where it does not. The point
  /// crosses the triangle's plane where the sign of det(a - p, b - p, c - p), a cubic in t, changes (zero counts
  /// as below, so a point that stops on the sheet and goes on is counted once), and meets the triangle if it lies
  /// inside it then (its barycentric weights at least -1e-9; `corner` is the largest weight's corner, 0 to 2). A
  /// point that moves in the plane of a flat triangle makes no crossing.
  static double meetTriangle(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                             const std::array<Eigen::Vector3d, 3>& from, const std::array<Eigen::Vector3d, 3>& to,
                             int& corner) {
    const Eigen::Vector3d a = from[0] - p0, b = from[1] - p0, c = from[2] - p0;
    const Eigen::Vector3d da = to[0] - p1 - a, db = to[1] - p1 - b, dc = to[2] - p1 - c;
    const double k3 = da.dot(db.cross(dc));
    const double k2 = a.dot(db.cross(dc)) + da.dot(b.cross(dc)) + da.dot(db.cross(c));
    const double k1 = a.dot(b.cross(dc)) + a.dot(db.cross(c)) + da.dot(b.cross(c));
    const double k0 = a.dot(b.cross(c));
    auto f = [&](double t) { return ((k3 * t + k2) * t + k1) * t + k0; };
    // Pieces on which the cubic is monotone: split at its derivative's roots in (0, 1).
    std::array<double, 4> cut{0, 1, 1, 1};
    int cuts = 1;
    const double qa = 3 * k3, qb = 2 * k2, qc = k1;
    auto addCut = [&](double t) {
      if (t > 0 && t < 1) cut[std::size_t(cuts++)] = t;
    };
    if (qa != 0) {
      const double disc = qb * qb - 4 * qa * qc;
      if (disc > 0) {
        const double q = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
        addCut(q / qa);
        if (q != 0) addCut(qc / q);
      }
    } else if (qb != 0) {
      addCut(-qc / qb);
    }
    if (cuts == 3 && cut[1] > cut[2]) std::swap(cut[1], cut[2]);
    cut[std::size_t(cuts)] = 1;
    for (int k = 0; k < cuts; ++k) {
      double lo = cut[std::size_t(k)], hi = cut[std::size_t(k + 1)];
      const bool above = f(lo) > 0;
      if ((f(hi) > 0) == above) continue;
      for (int it = 0; it < 100 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > 0) == above ? lo = mid : hi = mid;
      }
      const double t = hi;
      const Eigen::Vector3d q = p0 + t * (p1 - p0);
      std::array<Eigen::Vector3d, 3> at;
      for (std::size_t i = 0; i < 3; ++i) at[i] = from[i] + t * (to[i] - from[i]) - q;
      const Eigen::Vector3d normal = (at[1] - at[0]).cross(at[2] - at[0]);
      const double area2 = normal.squaredNorm();
      if (!(area2 > 0)) continue;
      const std::array<double, 3> w{normal.dot(at[1].cross(at[2])) / area2, normal.dot(at[2].cross(at[0])) / area2,
                                    normal.dot(at[0].cross(at[1])) / area2};
      if (w[0] < -1e-9 || w[1] < -1e-9 || w[2] < -1e-9) continue;
      corner = int(std::max_element(w.begin(), w.end()) - w.begin());
      return t;
    }
    return -1;
  }

 private:
  /// The crossings between the last two readings: each face's swept box filed in a grid of cells in x and y, each
  /// body's path met with the faces whose boxes its own box meets.
  void sweep() {
    const std::size_t faces = triangles_.size();
    boxes_.resize(faces);
    Eigen::AlignedBox3d all;
    for (std::size_t f = 0; f < faces; ++f) {
      Eigen::AlignedBox3d box;
      for (Index v : triangles_[f]) box.extend(x0_[std::size_t(v)]).extend(x1_[std::size_t(v)]);
      boxes_[f] = box;
      all.extend(box);
    }
    if (all.isEmpty()) return;
    // Cells of at least 5 cm, at most 64 along a side.
    const Eigen::Vector3d size = all.sizes();
    const double cell = std::max({0.05, size.x() / 64, size.y() / 64});
    const int nx = int(size.x() / cell) + 1, ny = int(size.y() / cell) + 1;
    auto cellRange = [&](const Eigen::AlignedBox3d& box, int& i0, int& i1, int& j0, int& j1) {
      i0 = std::clamp(int((box.min().x() - all.min().x()) / cell), 0, nx - 1);
      i1 = std::clamp(int((box.max().x() - all.min().x()) / cell), 0, nx - 1);
      j0 = std::clamp(int((box.min().y() - all.min().y()) / cell), 0, ny - 1);
      j1 = std::clamp(int((box.max().y() - all.min().y()) / cell), 0, ny - 1);
    };
    start_.assign(std::size_t(nx * ny + 1), 0);
    for (int pass = 0; pass < 2; ++pass) {  // count, then file
      if (pass == 1) {
        for (std::size_t k = 1; k < start_.size(); ++k) start_[k] += start_[k - 1];
        filed_.resize(std::size_t(start_.back()));
        fill_.assign(start_.begin(), start_.end() - 1);
      }
      for (std::size_t f = 0; f < faces; ++f) {
        int i0, i1, j0, j1;
        cellRange(boxes_[f], i0, i1, j0, j1);
        for (int j = j0; j <= j1; ++j)
          for (int i = i0; i <= i1; ++i) {
            const std::size_t c = std::size_t(j * nx + i);
            if (pass == 0)
              ++start_[c + 1];
            else
              filed_[std::size_t(fill_[c]++)] = Index(f);
          }
      }
    }
    stamp_.assign(faces, -1);
    for (std::size_t b = 0; b < c1_.size(); ++b) {
      Eigen::AlignedBox3d path;
      path.extend(c0_[b]).extend(c1_[b]);
      if (!path.intersects(all)) continue;
      times_.clear();
      int i0, i1, j0, j1;
      cellRange(path, i0, i1, j0, j1);
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const std::size_t c = std::size_t(j * nx + i);
          for (int k = start_[c]; k < start_[c + 1]; ++k) {
            const Index f = filed_[std::size_t(k)];
            if (stamp_[std::size_t(f)] == int(b) || !boxes_[std::size_t(f)].intersects(path)) continue;
            stamp_[std::size_t(f)] = int(b);
            const auto& tri = triangles_[std::size_t(f)];
            std::array<Eigen::Vector3d, 3> from, to;
            for (std::size_t v = 0; v < 3; ++v) from[v] = x0_[std::size_t(tri[v])], to[v] = x1_[std::size_t(tri[v])];
            int corner = 0;
            const double t = meetTriangle(c0_[b], c1_[b], from, to, corner);
            if (t < 0) continue;
            times_.push_back({t, ring_[std::size_t(tri[std::size_t(corner)])]});
          }
        }
      if (times_.empty()) continue;
      // A path through an edge or a corner meets each face around it at once: one crossing.
      std::sort(times_.begin(), times_.end());
      if (!through_[b]) atBorder_[b] = times_.front().second <= 1;
      through_[b] = true;
      for (std::size_t k = 0; k < times_.size(); ++k)
        crossings_ += k == 0 || times_[k].first - times_[k - 1].first > 1e-9;
    }
  }

  std::vector<std::array<Index, 3>> triangles_;
  std::vector<int> ring_;  ///< each vertex's count of edges from the boundary
  std::vector<Eigen::Vector3d> x0_, x1_;  ///< the sheet at the last reading and at this one
  std::vector<Eigen::Vector3d> c0_, c1_;  ///< the bodies' centres, the same
  std::size_t seen_ = 0;  ///< bodies at the last reading
  std::vector<Eigen::AlignedBox3d> boxes_;  ///< each face's box over both readings
  std::vector<int> start_, fill_;  ///< the grid's cells: where each one's faces start in filed_
  std::vector<Index> filed_;
  std::vector<int> stamp_;  ///< the last body each face was met with
  std::vector<std::pair<double, int>> times_;  ///< a body's crossings: when, and the ring of the nearest corner
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
