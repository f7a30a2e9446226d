// The deepest-point search (projectToSimplex, deepestPointOnFace) against brute force, and bounding-sphere
// culling: exact per face, and invisible at the solver level.

#include "face_search_helpers.hpp"
#include "sanitizer.hpp"

#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

// Each test source keeps its helpers in a namespace of its own: the tests build as unity batches.
namespace pgd_tests {

namespace {

using drape::Vec3;
using V3 = Eigen::Vector3d;

// ------------------------------------------------------------------------------------------------------------
// Helpers

using drape::test::faces::bruteMinimum;
using drape::test::faces::randomUnit;
using drape::test::faces::uniform;

/// A point uniformly inside the ball of the given radius.
V3 randomInBall(std::mt19937& rng, double radius) {
  for (;;) {
    const V3 v(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    if (v.squaredNorm() <= 1) return radius * v;
  }
}

Eigen::Quaterniond randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q;
}

/// A world-space triangle (double).
struct Tri {
  std::array<V3, 3> x;
  double meanEdge() const { return ((x[1] - x[0]).norm() + (x[2] - x[1]).norm() + (x[0] - x[2]).norm()) / 3; }
};

Tri randomTriangle(std::mt19937& rng, const V3& centre, double edge) {
  return {drape::test::faces::randomTriangle(rng, centre, edge)};
}

template <class S> std::array<Vec3<S>, 3> toLocal(const Tri& t, const V3& origin) {
  return {(t.x[0] - origin).cast<S>(), (t.x[1] - origin).cast<S>(), (t.x[2] - origin).cast<S>()};
}

/// deepestPointOnFace called exactly as projectFaceContacts calls it.
template <class S, class Field>
drape::FaceQuery<S> pgdQuery(const Field& sdf, const std::array<Vec3<S>, 3>& x, int iterations) {
  const drape::FaceSphere<S> sphere = drape::faceSphere<S>(x[0], x[1], x[2]);
  Vec3<S> gradC;
  const S phiC = sdf(sphere.centre, gradC);
  return drape::deepestPointOnFace<S>(sdf, x[0], x[1], x[2], sphere.centre, phiC, gradC, iterations);
}

// ------------------------------------------------------------------------------------------------------------
// Scenarios: a solid and a way to place triangles on its features.

struct Scenario {
  std::string name;
  /// Makes one random (world) triangle near the solid's feature of interest.
  std::function<Tri(std::mt19937&, double /*reach*/)> triangle;
};

constexpr double kEdge = 0.02;  // cloth spacing (m)

/// Where every scenario's solid sits: far from the world origin, so the compile-relative-to-origin path is used.
const V3 kWorld(312.5, -47.25, 8.0);
/// The local origin the solids are compiled against (as the solver's would be, near the cloth).
const V3 kOrigin(312.5, -47.25, 8.0 - 1.0 / 64);

/// A point on the boundary of a box (half extents h) in its own frame: on one of its 12 edges, or at a corner.
V3 boxEdgePoint(std::mt19937& rng, const V3& h, bool corner) {
  V3 p;
  for (int k = 0; k < 3; ++k) p[k] = (rng() & 1u) ? h[k] : -h[k];
  if (!corner) {
    const int axis = int(rng() % 3u);
    p[axis] = uniform(rng, -h[axis], h[axis]);
  }
  return p;
}

/// Applies f(name, sdf, makeTriangle) to every scenario's compiled field in scalar S.
template <class S, class F> void forEachScenario(std::mt19937& rng, F&& f) {
  using namespace drape;
  // Planes, several orientations.
  for (int k = 0; k < 4; ++k) {
    Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.2)};
    const auto sdf = detail::compileSdf<S>(Plane{}, pose, kOrigin);
    const V3 n = pose.rotation * V3::UnitZ();
    f("plane " + std::to_string(k), sdf, [=](std::mt19937& r, double reach) {
      const V3 onPlane = pose.position + pose.rotation * V3(uniform(r, -0.3, 0.3), uniform(r, -0.3, 0.3), 0);
      return randomTriangle(r, onPlane + uniform(r, -reach, reach) * n, kEdge);
    });
  }
  // Spheres: a large one, and one smaller than a face.
  for (const double radius : {0.3, 0.005}) {
    Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.2)};
    const auto sdf = detail::compileSdf<S>(Sphere{radius}, pose, kOrigin);
    f("sphere r=" + std::to_string(radius), sdf, [=](std::mt19937& r, double reach) {
      const V3 c = radius > kEdge ? V3(pose.position + (radius + uniform(r, -reach, reach)) * randomUnit(r))
                                  : V3(pose.position + randomInBall(r, radius + reach));
      return randomTriangle(r, c, kEdge);
    });
  }
  // Boxes: corners and ridges of a cube, and of thin plates.
  for (const V3& h : {V3(0.1, 0.1, 0.1), V3(0.1, 0.07, 0.004), V3(0.004, 0.004, 0.1)}) {
    for (const bool corner : {true, false}) {
      Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.2)};
      const auto sdf = detail::compileSdf<S>(Box{h}, pose, kOrigin);
      char name[96];
      std::snprintf(name, sizeof name, "box %.3gx%.3gx%.3g %s", h[0], h[1], h[2], corner ? "corner" : "ridge");
      f(name, sdf, [=](std::mt19937& r, double reach) {
        const V3 p = boxEdgePoint(r, h, corner) + randomInBall(r, reach);
        return randomTriangle(r, pose.apply(p), kEdge);
      });
    }
  }
  // A thin capsule (a rod thinner than a face), around its side and its caps.
  {
    const Capsule cap{0.003, 0.1};
    Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.2)};
    const auto sdf = detail::compileSdf<S>(cap, pose, kOrigin);
    f("capsule r=0.003", sdf, [=](std::mt19937& r, double reach) {
      const V3 onAxis(0, 0, uniform(r, -cap.halfHeight - 0.01, cap.halfHeight + 0.01));
      return randomTriangle(r, pose.apply(onAxis + randomInBall(r, cap.radius + reach)), kEdge);
    });
  }
}

// ------------------------------------------------------------------------------------------------------------
// Exact projection onto the triangle simplex by enumerating its faces (interior, edges, vertices).

Eigen::Vector3d exactProjection(const Eigen::Vector3d& y) {
  Eigen::Vector3d best = Eigen::Vector3d::Zero();
  double bestD = std::numeric_limits<double>::infinity();
  auto consider = [&](const Eigen::Vector3d& b) {
    if ((b.array() < 0).any()) return;
    const double d = (b - y).squaredNorm();
    if (d < bestD) bestD = d, best = b;
  };
  consider((y.array() + (1 - y.sum()) / 3).matrix());  // interior: shift along (1,1,1)
  for (int z = 0; z < 3; ++z) {                          // edge b_z = 0
    const int i = (z + 1) % 3, j = (z + 2) % 3;
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    const double s = (1 - y[i] - y[j]) / 2;
    b[i] = y[i] + s;
    b[j] = y[j] + s;
    consider(b);
  }
  for (int k = 0; k < 3; ++k) consider(Eigen::Vector3d::Unit(k));
  return best;
}

}  // namespace

// ============================================================================================================
// 1. projectToSimplex

TEMPLATE_TEST_CASE("projectToSimplex returns the nearest point of the simplex", "[pgd]", float, double) {
  using S = TestType;
  std::mt19937 rng(20240611);
  std::normal_distribution<double> normal(0, 1);
  constexpr S eps = std::numeric_limits<S>::epsilon();
  constexpr int kGrid = 200;

  // Kinds of input: near the simplex, offset by +-1e3, huge spread between coordinates, ties, and corner cases.
  std::vector<Eigen::Vector3d> inputs;
  for (int k = 0; k < 300; ++k) inputs.push_back(Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
  for (int k = 0; k < 150; ++k)
    inputs.push_back(Eigen::Vector3d(normal(rng), normal(rng), normal(rng)) + Eigen::Vector3d::Constant(1e3));
  for (int k = 0; k < 150; ++k)
    inputs.push_back(Eigen::Vector3d(normal(rng), normal(rng), normal(rng)) - Eigen::Vector3d::Constant(1e3));
  for (int k = 0; k < 300; ++k) {
    Eigen::Vector3d y;
    for (int i = 0; i < 3; ++i) y[i] = ((rng() & 1u) ? 1 : -1) * std::pow(10.0, uniform(rng, -4, 6));
    inputs.push_back(y);
  }
  inputs.push_back(Eigen::Vector3d(1.0 / 3, 1.0 / 3, 1.0 / 3));
  inputs.push_back(Eigen::Vector3d(0, 0, 0));
  inputs.push_back(Eigen::Vector3d(5, 5, 5));
  inputs.push_back(Eigen::Vector3d(-5, -5, -5));
  inputs.push_back(Eigen::Vector3d(1, 0, 0));
  inputs.push_back(Eigen::Vector3d(2, 2, -7));
  inputs.push_back(Eigen::Vector3d(1e6, 1e6 + 1, -1e6));

  // The barycentric grid, once.
  std::vector<Eigen::Vector3d> grid;
  for (int i = 0; i <= kGrid; ++i)
    for (int j = 0; j <= kGrid - i; ++j)
      grid.push_back(Eigen::Vector3d(double(i) / kGrid, double(j) / kGrid, double(kGrid - i - j) / kGrid));

  for (const Eigen::Vector3d& yd : inputs) {
    const Vec3<S> y = yd.cast<S>();
    const Eigen::Vector3d yIn = y.template cast<double>();  // what the projection actually saw
    const Vec3<S> b = drape::projectToSimplex<S>(y);
    const Eigen::Vector3d bd = b.template cast<double>();
    // Rounding in y - theta is relative to the largest magnitude involved.
    const double scale = 1 + yIn.cwiseAbs().maxCoeff();
    const double tol = 16 * double(eps) * scale;
    INFO("y = " << yIn.transpose() << ", b = " << bd.transpose());
    REQUIRE(b.allFinite());
    REQUIRE((b.array() >= S(0)).all());
    REQUIRE(std::abs(bd.sum() - 1) <= tol);

    double gridBest = std::numeric_limits<double>::infinity();
    for (const auto& g : grid) gridBest = std::min(gridBest, (g - yIn).norm());
    const double dProj = (bd - yIn).norm();
    INFO("projection distance " << dProj << ", grid best " << gridBest);
    REQUIRE(dProj <= gridBest + tol);
    // And it matches the exact projection found by enumerating the simplex's faces.
    REQUIRE((bd - exactProjection(yIn)).cwiseAbs().maxCoeff() <= tol);
  }
}

// ============================================================================================================
// 2. PGD accuracy

TEMPLATE_TEST_CASE("PGD finds a face's deepest point within 1e-3 edge of brute force", "[pgd]", float, double) {
  using S = TestType;
  const int iterations = drape::Settings{}.pgdIterations;
  constexpr int kTriangles = 250;
  constexpr int kGrid = 200;
  std::mt19937 rng(77);
  long long total = 0, totalEvaluations = 0;
  forEachScenario<S>(rng, [&](const std::string& name, const auto& sdf, const auto& makeTriangle) {
    long long evaluations = 0, beaten = 0, misses = 0;
    double worst = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < kTriangles; ++k) {
      // Mostly touching or crossing the feature; some a little off it.
      const Tri tri = makeTriangle(rng, k % 5 == 0 ? 0.02 : 0.008);
      const auto x = toLocal<S>(tri, kOrigin);
      const drape::FaceQuery<S> q = pgdQuery<S>(sdf, x, iterations);
      const S brute = bruteMinimum<S>(sdf, x, kGrid);
      const double edge = tri.meanEdge();
      const double excess = (double(q.phi) - double(brute)) / edge;
      worst = std::max(worst, excess);
      evaluations += q.evaluations;
      if (q.phi < brute) ++beaten;
      if (double(q.phi) > double(brute) + 1e-3 * edge) ++misses;
      INFO(name << " triangle " << k << ": pgd " << q.phi << " (b = " << q.barycentric.transpose() << ", "
                << q.evaluations << " evaluations), brute " << brute << ", edge " << edge);
      CHECK(q.evaluations <= iterations);
      CHECK(q.barycentric.allFinite());
      CHECK((q.barycentric.array() >= S(0)).all());
      CHECK(std::abs(double(q.barycentric.sum()) - 1) <= 1e-5);
      // The reported point and value are the field at the reported barycentric point.
      const Vec3<S> p = q.barycentric[0] * x[0] + q.barycentric[1] * x[1] + q.barycentric[2] * x[2];
      CHECK((q.point - p).norm() <= S(1e-5) * S(edge));
      Vec3<S> g;
      CHECK(std::abs(double(sdf(q.point, g) - q.phi)) <= 1e-6);
      CHECK(double(q.phi) <= double(brute) + 1e-3 * edge);
    }
    const double mean = double(evaluations) / kTriangles;
    std::printf("[pgd] %-6s %-28s mean evaluations %.2f, worst (pgd - brute) / edge %+.2e, beat grid %lld, missed %lld of %d\n",
                sizeof(S) == 4 ? "float" : "double", name.c_str(), mean, worst, beaten, misses, kTriangles);
    total += kTriangles;
    totalEvaluations += evaluations;
  });
  std::printf("[pgd] %-6s all shapes: mean evaluations %.2f (budget %d)\n", sizeof(S) == 4 ? "float" : "double",
              double(totalEvaluations) / double(total), iterations);
}

// ============================================================================================================
// 2b. The ball's closed form

namespace {

/// The distance from p to the triangle t, in double, by another route than nearestOnTriangle's: the projection
/// onto the plane where it falls inside, else the nearest of the three edges.
double distanceToTriangle(const V3& p, const std::array<V3, 3>& t) {
  auto toSegment = [&](const V3& a, const V3& b) {
    const V3 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + s * ab - p).norm();
  };
  double best = std::min({toSegment(t[0], t[1]), toSegment(t[1], t[2]), toSegment(t[2], t[0])});
  const V3 n = (t[1] - t[0]).cross(t[2] - t[0]);
  if (n.squaredNorm() > 0) {
    const V3 u = n.normalized();
    const V3 q = p - u.dot(p - t[0]) * u;
    bool inside = true;
    for (int k = 0; k < 3; ++k) inside = inside && (t[(k + 1) % 3] - t[k]).cross(q - t[k]).dot(n) >= 0;
    if (inside) best = std::min(best, (q - p).norm());
  }
  return best;
}

}  // namespace

TEMPLATE_TEST_CASE("on a ball the face search is the face's point nearest the centre, exact to rounding", "[pgd]",
                   float, double) {
  using S = TestType;
  constexpr S eps = std::numeric_limits<S>::epsilon();
  const S thickness = S(drape::Settings{}.thickness);
  const int iterations = drape::Settings{}.pgdIterations;
  std::mt19937 rng(515);
  for (const double radius : {0.3, 0.005}) {
    const drape::Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.2)};
    const auto sdf = drape::detail::compileSdf<S>(drape::Sphere{radius}, pose, kOrigin);
    int closedForm = 0, culled = 0, flat = 0;
    double worst = 0;
    for (int k = 0; k < 600; ++k) {
      const double reach = k % 3 == 0 ? 0.02 : 0.006;
      const V3 near = radius > kEdge ? V3(pose.position + (radius + uniform(rng, -reach, reach)) * randomUnit(rng))
                                     : V3(pose.position + randomInBall(rng, radius + reach));
      Tri tri = randomTriangle(rng, near, kEdge);
      if (k % 10 == 1) tri.x[2] = tri.x[0] + uniform(rng, 1e-4, 1e-2) * (tri.x[2] - tri.x[0]);  // a sliver
      if (k % 10 == 3) {  // the centre on the face: its distance is 0
        const V3 shift = pose.position - (0.2 * tri.x[0] + 0.5 * tri.x[1] + 0.3 * tri.x[2]);
        for (V3& v : tri.x) v += shift;
      }
      auto x = toLocal<S>(tri, kOrigin);
      if (k % 10 == 2) x[2] = S(0.5) * (x[0] + x[1]);  // no area, as rounding leaves it
      // The reference in the frame the field was compiled in, from what the search saw.
      const std::array<V3, 3> seen = {x[0].template cast<double>(), x[1].template cast<double>(),
                                      x[2].template cast<double>()};
      const double exact = distanceToTriangle(sdf.centre.template cast<double>(), seen) - double(sdf.radius);
      drape::FaceQuery<S> q;
      REQUIRE(drape::queryFace<false>(sdf, x[0], x[1], x[2], S(0), iterations, q));
      const S brute = bruteMinimum<S>(sdf, x, 200);
      const double edge = tri.meanEdge();
      // Rounding: the coordinates (within a metre of the local origin) and the centre's distance.
      const double tolerance = 64 * double(eps);
      INFO("radius " << radius << " triangle " << k << ": search " << q.phi << " (b = " << q.barycentric.transpose()
                     << "), exact " << exact << ", brute " << brute);
      CHECK(q.barycentric.allFinite());
      CHECK((q.barycentric.array() >= S(0)).all());
      CHECK(double(q.phi) <= double(brute) + 1e-3 * edge);
      Vec3<S> g;
      CHECK(std::abs(double(sdf(q.point, g) - q.phi)) <= tolerance);
      Vec3<S> b;
      if (drape::nearestOnTriangle<S>(sdf.centre, x[0], x[1], x[2], b)) {
        ++closedForm;
        worst = std::max(worst, std::abs(double(q.phi) - exact));
        CHECK(std::abs(double(q.phi) - exact) <= tolerance);
      } else {
        ++flat;  // searched by the cutting planes
      }
      // The culling search drops only faces clear of the thickness.
      drape::FaceQuery<S> kept;
      if (!drape::queryFace<true>(sdf, x[0], x[1], x[2], thickness, iterations, kept)) {
        ++culled;
        CHECK(exact > double(thickness) - tolerance);
      }
    }
    std::printf("[pgd] %-6s ball r=%g: closed form on %d faces, worst |search - exact| %.1e m, %d flat, %d culled\n",
                sizeof(S) == 4 ? "float" : "double", radius, closedForm, worst, flat, culled);
    CHECK(closedForm >= 500);
    CHECK(culled > 0);
  }
}

namespace {

/// An equilateral face of side `side` square to the unit u, its centroid at `centre`, turned by a random angle.
Tri equilateralFace(std::mt19937& rng, const V3& centre, const V3& u, double side) {
  const V3 a = u.unitOrthogonal(), b = u.cross(a);
  const double turn = uniform(rng, 0, 2 * std::numbers::pi), r = side / std::sqrt(3.0);
  Tri tri;
  for (int j = 0; j < 3; ++j) {
    const double angle = turn + 2 * std::numbers::pi * j / 3;
    tri.x[std::size_t(j)] = centre + r * (std::cos(angle) * a + std::sin(angle) * b);
  }
  return tri;
}

/// A face at the edge of the thickness, against the culling search: one just inside must be kept, with its deepest
/// point within the thickness; one just outside must not be a contact, and is counted where it was culled.
template <class S, class Field>
void checkAtThickness(const Field& sdf, const Tri& tri, bool inside, S thickness, int iterations, int& kept,
                      int& culled) {
  const auto x = toLocal<S>(tri, kOrigin);
  drape::FaceQuery<S> q;
  const bool found = drape::queryFace<true>(sdf, x[0], x[1], x[2], thickness, iterations, q);
  if (inside) {
    REQUIRE(found);
    CHECK(q.phi < thickness);
    ++kept;
  } else {
    CHECK((!found || q.phi >= thickness));
    culled += !found;
  }
}

}  // namespace

TEMPLATE_TEST_CASE("a face is culled from a ball by its corners only where no point of it comes within the thickness",
                   "[pgd][culling]", float, double) {
  // An equilateral face whose centroid lies straight out from the centre is where the corners' bound (the nearest
  // corner's squared distance less a third of the longest edge's square) is exact: a face there just inside the
  // thickness must be kept, and just outside it is clear. A bound taking less than a third would cull the first.
  using S = TestType;
  const S thickness = S(drape::Settings{}.thickness);
  const int iterations = drape::Settings{}.pgdIterations;
  std::mt19937 rng(733);
  int kept = 0, culled = 0;
  for (const double radius : {0.3, 0.005}) {
    const drape::Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.2)};
    const auto sdf = drape::detail::compileSdf<S>(drape::Sphere{radius}, pose, kOrigin);
    const double reach = radius + double(thickness);
    for (int k = 0; k < 300; ++k) {
      const double side = std::array{0.005, 0.02, 0.05}[std::size_t(k % 3)];
      const bool inside = k % 2 == 0;
      // Within a thousandth of the reach of the thickness' edge, either side of it.
      const double height = reach * (inside ? 1 - 1e-3 : 1 + 1e-3);
      const V3 u = randomUnit(rng);
      const Tri tri = equilateralFace(rng, pose.position + height * u, u, side);
      INFO("radius " << radius << " side " << side << (inside ? " inside" : " outside") << " the thickness");
      checkAtThickness<S>(sdf, tri, inside, thickness, iterations, kept, culled);
    }
  }
  std::printf("[pgd] %-6s ball, equilateral faces at the thickness: %d kept inside, %d of %d culled outside\n",
              sizeof(S) == 4 ? "float" : "double", kept, culled, kept);
  CHECK(culled > kept / 2);
}

TEMPLATE_TEST_CASE("the vertex pass's cull of a ball or a capsule passes over no vertex within the thickness",
                   "[pgd][culling]", float, double) {
  // Points straight out from the centre or the core within a few hundred thousandths of the reach, where the
  // roundings of the field's root and subtraction decide: a point the squared distance passes over (Sdf::beyond)
  // must read at least the level, and one more than 1e-5 of the reach out is passed over. A cull a millionth of the
  // reach squared too eager passes over some within the level.
  using S = TestType;
  const S level = S(drape::Settings{}.thickness) * S(1 - 1e-6);
  std::mt19937 rng(735);
  int passed = 0, tested = 0, wrongIfEager = 0;
  // `squared`: the point's squared distance from the core, as the field takes its root
  const auto check = [&](const auto& sdf, S squared, S radius, const Vec3<S>& x, bool far) {
    Vec3<S> g;
    const S phi = sdf(x, g);
    const bool beyond = sdf.beyond(x, level);
    INFO("point " << x.transpose() << ", phi " << phi << ", radius " << radius);
    if (beyond) REQUIRE(phi >= level);
    if (far) REQUIRE(beyond);
    ++tested;
    passed += beyond;
    wrongIfEager += phi < level && squared > (radius + level) * (radius + level) * S(1 - 1e-6);
  };
  for (const double radius : {0.3, 0.05, 0.003}) {
    const drape::Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.5)};
    const auto ball = drape::detail::compileSdf<S>(drape::Sphere{radius}, pose, kOrigin);
    const auto cap = drape::detail::compileSdf<S>(drape::Capsule{radius, 0.2}, pose, kOrigin);
    const double reach = radius + double(level);
    for (int k = 0; k < 4000; ++k) {
      // Half of them within a few float roundings of the reach.
      const double spread = k % 2 == 0 ? 4e-5 : 4e-7;
      const double out = reach * (1 + uniform(rng, -spread, spread));
      const V3 u = randomUnit(rng);
      const Vec3<S> onBall = (pose.position + out * u - kOrigin).cast<S>();
      const bool far = out > reach * (1 + 1e-5);
      check(ball, (onBall - ball.centre).squaredNorm(), ball.radius, onBall, far);
      // Beside the capsule's side or over a cap.
      const double along = uniform(rng, -0.3, 0.3);
      const V3 axis = pose.rotation * V3::UnitZ();
      const V3 side = u - u.dot(axis) * axis;
      if (side.norm() < 1e-3) continue;
      const V3 core = pose.position + std::clamp(along, -0.2, 0.2) * axis;
      const V3 outward = std::abs(along) < 0.2 ? V3(side.normalized()) : u.dot(axis) * along >= 0 ? u : V3(-u);
      const Vec3<S> onCapsule = (core + out * outward - kOrigin).cast<S>();
      const Vec3<S> r = onCapsule - cap.centre;
      const S t = std::clamp(r.dot(cap.axis), -cap.halfHeight, cap.halfHeight);
      check(cap, Vec3<S>(r - t * cap.axis).squaredNorm(), cap.radius, onCapsule, far);
    }
  }
  std::printf("[culling] %-6s ball and capsule, points within 4e-5 of the reach: %d of %d passed over; %d within "
              "the level would be by a cull a millionth too eager\n",
              sizeof(S) == 4 ? "float" : "double", passed, tested, wrongIfEager);
  CHECK(wrongIfEager > 0);
}

// ============================================================================================================
// 2c. The capsule's closed form

namespace {

/// The distance from the segment [a, b] to the triangle t, in double, by another route than nearestToSegment's:
/// the distance from a point of the segment to the triangle is convex along it, so a golden-section search over
/// the segment finds its least value.
double segmentToTriangle(const V3& a, const V3& b, const std::array<V3, 3>& t) {
  const double ratio = (std::sqrt(5.0) - 1) / 2;
  double lo = 0, hi = 1;
  double m1 = hi - ratio * (hi - lo), m2 = lo + ratio * (hi - lo);
  double f1 = distanceToTriangle(a + m1 * (b - a), t), f2 = distanceToTriangle(a + m2 * (b - a), t);
  for (int k = 0; k < 120; ++k) {
    if (f1 <= f2) {
      hi = m2, m2 = m1, f2 = f1;
      m1 = hi - ratio * (hi - lo);
      f1 = distanceToTriangle(a + m1 * (b - a), t);
    } else {
      lo = m1, m1 = m2, f1 = f2;
      m2 = lo + ratio * (hi - lo);
      f2 = distanceToTriangle(a + m2 * (b - a), t);
    }
  }
  return std::min({f1, f2, distanceToTriangle(a, t), distanceToTriangle(b, t)});
}

}  // namespace

TEMPLATE_TEST_CASE("on a capsule the face search is the face's point nearest the core segment, exact to rounding",
                   "[pgd]", float, double) {
  using S = TestType;
  constexpr S eps = std::numeric_limits<S>::epsilon();
  const S thickness = S(drape::Settings{}.thickness);
  const int iterations = drape::Settings{}.pgdIterations;
  std::mt19937 rng(616);
  // An arm's capsule, a finger's, one shorter than a face, and a 3 mm rod narrower than a face, whose faces keep
  // the cutting planes (queryFace: the closed form only where the capsule's reach spans the longest edge).
  struct Case {
    drape::Capsule cap;
    int closedAtLeast, closedAtMost;
  };
  for (const Case& item : {Case{{0.15, 0.45}, 450, 600}, Case{{0.02, 0.2}, 300, 600}, Case{{0.03, 0.005}, 300, 600},
                        Case{{0.0015, 0.2}, 0, 0}}) {
    const drape::Capsule& cap = item.cap;
    const drape::Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.2)};
    const auto sdf = drape::detail::compileSdf<S>(cap, pose, kOrigin);
    const V3 axis = pose.rotation * V3::UnitZ();
    int closedForm = 0, culled = 0, other = 0;
    double worst = 0;
    for (int k = 0; k < 600; ++k) {
      const double reach = k % 3 == 0 ? 0.02 : 0.006;
      // On the side or beyond a cap, within the reach of the surface or of the core.
      const double along = uniform(rng, -cap.halfHeight - 0.3 * cap.radius, cap.halfHeight + 0.3 * cap.radius);
      const V3 core = pose.position + std::clamp(along, -cap.halfHeight, cap.halfHeight) * axis;
      V3 out = randomUnit(rng);
      if (std::abs(along) <= cap.halfHeight) out = (out - out.dot(axis) * axis).normalized();
      const V3 near = cap.radius > kEdge ? V3(core + (cap.radius + uniform(rng, -reach, reach)) * out)
                                         : V3(core + randomInBall(rng, cap.radius + reach));
      Tri tri = randomTriangle(rng, near, kEdge);
      if (k % 10 == 1) tri.x[2] = tri.x[0] + uniform(rng, 1e-4, 1e-2) * (tri.x[2] - tri.x[0]);  // a sliver
      if (k % 10 == 3) {  // the core through the face
        const V3 shift = core - (0.2 * tri.x[0] + 0.5 * tri.x[1] + 0.3 * tri.x[2]);
        for (V3& v : tri.x) v += shift;
      }
      if (k % 10 == 5) {  // an edge along the axis, a cloth lying along the capsule
        const V3 side = axis.cross(out).normalized();
        tri.x[0] = near - 0.5 * kEdge * axis;
        tri.x[1] = near + 0.5 * kEdge * axis + uniform(rng, -1e-5, 1e-5) * out;
        tri.x[2] = near + uniform(rng, -0.5, 0.5) * kEdge * axis + kEdge * side + uniform(rng, -0.3, 0.3) * kEdge * out;
      }
      auto x = toLocal<S>(tri, kOrigin);
      if (k % 10 == 2) x[2] = S(0.5) * (x[0] + x[1]);  // no area, as rounding leaves it
      // The reference in the frame the field was compiled in, from what the search saw.
      const std::array<V3, 3> seen = {x[0].template cast<double>(), x[1].template cast<double>(),
                                      x[2].template cast<double>()};
      const V3 c = sdf.centre.template cast<double>(), u = sdf.axis.template cast<double>();
      const double h = double(sdf.halfHeight);
      const double exact = segmentToTriangle(c - h * u, c + h * u, seen) - double(sdf.radius);
      drape::FaceQuery<S> q;
      REQUIRE(drape::queryFace<false>(sdf, x[0], x[1], x[2], S(0), iterations, q));
      const S brute = bruteMinimum<S>(sdf, x, 200);
      const double edge = tri.meanEdge();
      // Rounding: the coordinates (within a metre of the local origin) and the core's distance.
      const double tolerance = 64 * double(eps);
      INFO("capsule r=" << cap.radius << " h=" << cap.halfHeight << " triangle " << k << ": search " << q.phi
                        << " (b = " << q.barycentric.transpose() << "), exact " << exact << ", brute " << brute);
      CHECK(q.barycentric.allFinite());
      CHECK((q.barycentric.array() >= S(0)).all());
      CHECK(double(q.phi) <= double(brute) + 1e-3 * edge);
      Vec3<S> g;
      CHECK(std::abs(double(sdf(q.point, g) - q.phi)) <= tolerance);
      Vec3<S> b;
      const S longest =
          std::max({(x[1] - x[0]).squaredNorm(), (x[2] - x[1]).squaredNorm(), (x[0] - x[2]).squaredNorm()});
      if (S(4) * sdf.radius * sdf.radius >= longest &&
          drape::nearestToSegment<S>(sdf.centre - sdf.halfHeight * sdf.axis, sdf.centre + sdf.halfHeight * sdf.axis,
                                     x[0], x[1], x[2], b)) {
        ++closedForm;
        worst = std::max(worst, std::abs(double(q.phi) - exact));
        CHECK(std::abs(double(q.phi) - exact) <= tolerance);
      } else {
        ++other;  // flat, crossed by the core or wider than the capsule: searched by the cutting planes
      }
      // The culling search drops only faces clear of the thickness.
      drape::FaceQuery<S> kept;
      if (!drape::queryFace<true>(sdf, x[0], x[1], x[2], thickness, iterations, kept)) {
        ++culled;
        CHECK(exact > double(thickness) - tolerance);
      }
    }
    std::printf("[pgd] %-6s capsule r=%g h=%g: closed form on %d faces, worst |search - exact| %.1e m, %d flat, "
                "crossed or narrow, %d culled\n",
                sizeof(S) == 4 ? "float" : "double", cap.radius, cap.halfHeight, closedForm, worst, other, culled);
    CHECK(closedForm >= item.closedAtLeast);  // around a thin capsule, many random faces are crossed by its core
    CHECK(closedForm <= item.closedAtMost);
    CHECK(culled > 0);
  }
}

TEMPLATE_TEST_CASE("a face is culled from a capsule by its corners only where no point of it comes within the "
                   "thickness",
                   "[pgd][culling]", float, double) {
  // Equilateral faces square to the surface, just inside and just outside the thickness: over a cap, straight out
  // from its centre, the corners' bound is exact, as on a ball; along the side it is looser. Those inside must be
  // kept.
  using S = TestType;
  const S thickness = S(drape::Settings{}.thickness);
  const int iterations = drape::Settings{}.pgdIterations;
  std::mt19937 rng(734);
  int kept = 0, culled = 0;
  for (const drape::Capsule cap : {drape::Capsule{0.15, 0.45}, drape::Capsule{0.003, 0.2}}) {
    const drape::Pose pose{randomRotation(rng), kWorld + randomInBall(rng, 0.2)};
    const auto sdf = drape::detail::compileSdf<S>(cap, pose, kOrigin);
    const V3 axis = pose.rotation * V3::UnitZ();
    const double reach = cap.radius + double(thickness);
    for (int k = 0; k < 300; ++k) {
      const double side = std::array{0.005, 0.02, 0.05}[std::size_t(k % 3)];
      const bool inside = k % 2 == 0;
      const double height = reach * (inside ? 1 - 1e-3 : 1 + 1e-3);
      const bool overCap = k % 4 < 2;
      V3 base, u;
      if (overCap) {  // beyond an end, straight out from the cap's centre
        const double end = (k % 8 < 4 ? 1.0 : -1.0) * cap.halfHeight;
        const V3 tilt = randomUnit(rng);
        u = (end * axis / cap.halfHeight + 0.5 * (tilt - tilt.dot(axis) * axis)).normalized();
        if (u.dot(axis) * end <= 0) u = (end > 0 ? 1.0 : -1.0) * axis;
        base = pose.position + end * axis;
      } else {  // beside the side
        u = randomUnit(rng).cross(axis).normalized();
        base = pose.position + uniform(rng, -0.5, 0.5) * cap.halfHeight * axis;
      }
      const Tri tri = equilateralFace(rng, base + height * u, u, side);
      INFO("capsule r=" << cap.radius << " side " << side << (overCap ? " over a cap" : " beside the side")
                        << (inside ? ", inside" : ", outside") << " the thickness");
      checkAtThickness<S>(sdf, tri, inside, thickness, iterations, kept, culled);
    }
  }
  std::printf("[pgd] %-6s capsule, equilateral faces at the thickness: %d kept inside, %d of %d culled outside\n",
              sizeof(S) == 4 ? "float" : "double", kept, culled, kept);
  CHECK(culled > kept / 2);
}

// ============================================================================================================
// 3. Culling

TEMPLATE_TEST_CASE("bounding-sphere culling never rejects a face within the thickness", "[culling]", float, double) {
  using S = TestType;
  const S thickness = S(drape::Settings{}.thickness);
  constexpr int kTriangles = 300;
  constexpr int kGrid = 100;
  std::mt19937 rng(4242);
  forEachScenario<S>(rng, [&](const std::string& name, const auto& sdf, const auto& makeTriangle) {
    int culled = 0, kept = 0;
    double tightest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < kTriangles; ++k) {
      const Tri tri = makeTriangle(rng, 0.03);
      const auto x = toLocal<S>(tri, kOrigin);
      const drape::FaceSphere<S> sphere = drape::faceSphere<S>(x[0], x[1], x[2]);
      // The sphere holds the face.
      for (const auto& v : x) REQUIRE((v - sphere.centre).norm() <= sphere.radius * (1 + S(1e-5)));
      Vec3<S> gradC;
      const S phiC = sdf(sphere.centre, gradC);
      if (!(phiC > sphere.radius + thickness)) {
        ++kept;
        continue;
      }
      ++culled;
      const S brute = bruteMinimum<S>(sdf, x, kGrid);
      tightest = std::min(tightest, double(brute - thickness));
      INFO(name << " triangle " << k << ": phi(centre) " << phiC << ", radius " << sphere.radius << ", brute "
                << brute);
      REQUIRE(brute > thickness);
    }
    std::printf("[culling] %-6s %-28s culled %d, kept %d, closest culled face %.2e m beyond the thickness\n",
                sizeof(S) == 4 ? "float" : "double", name.c_str(), culled, kept, tightest);
    CHECK(culled > 0);
    CHECK(kept > 0);
  });
}

namespace {

struct Run {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::vector<drape::Index>> contactLists;  // after every substep
  std::vector<drape::Index> lastContacts;
  std::vector<Eigen::Vector3d> lastNormals;
  std::int64_t culledInAir = 0;
  std::int64_t faceContacts = 0;
};

Run dropOnSphereAndBox(bool culling, int frames) {
  using namespace drape;
  SheetDesc grid;
  grid.nx = 20;
  grid.ny = 20;
  grid.spacing = 0.02;
  grid.placement.position = V3(0.01, 0.02, 0.12);
  auto asset = std::make_shared<const ClothAsset<double>>(ClothAsset<double>::sheet(grid));
  Settings settings;
  settings.culling = culling;
  Solver<double> solver(asset, settings);
  Solid<Sphere> ball;
  ball.shape.radius = 0.08;
  ball.pose.position = V3(-0.09, 0, 0);
  ball.staticFriction = ball.dynamicFriction = 0.3;
  solver.addSolid(ball);
  Solid<Box> box;
  box.shape.halfExtents = V3(0.06, 0.05, 0.04);
  box.pose.position = V3(0.1, 0.03, 0.02);
  box.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.6, V3(0.3, 1, 0.2).normalized()));
  box.staticFriction = box.dynamicFriction = 0.3;
  solver.addSolid(box);

  Run run;
  for (int f = 0; f < frames; ++f) {
    solver.step(1.0 / 60.0, [&](const Solver<double>& s) {
      run.contactLists.push_back(s.contacts().liveVertices());
      run.faceContacts += s.stats().faceContacts;
      if (f == 0) run.culledInAir += s.stats().facesCulled;
    });
  }
  for (Index i = 0; i < solver.vertexCount(); ++i) run.positions.push_back(solver.position(i));
  run.lastContacts = solver.contacts().liveVertices();
  for (const Index i : run.lastContacts) run.lastNormals.push_back(solver.contacts().normal(i));
  return run;
}

}  // namespace

TEST_CASE("culling changes nothing in a simulation: positions and contacts are bit-identical", "[culling]") {
  constexpr int kFrames = 60;
  const Run with = dropOnSphereAndBox(true, kFrames);
  const Run without = dropOnSphereAndBox(false, kFrames);
  // The scene is meaningful: the cloth starts in the air (so faces are culled) and lands on both solids.
  CHECK(with.culledInAir > 0);
  CHECK(without.culledInAir == 0);
  CHECK(with.faceContacts > 0);
  CHECK_FALSE(with.lastContacts.empty());
  std::printf("[culling] solver: %lld faces culled in the first frame, %zu contacts at the end, %lld face contacts\n",
              (long long)with.culledInAir, with.lastContacts.size(), (long long)with.faceContacts);

  REQUIRE(with.positions.size() == without.positions.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < with.positions.size(); ++i)
    if (with.positions[i] != without.positions[i]) ++differing;  // exact comparison: bit-identical
  CHECK(differing == 0);
  CHECK(with.lastContacts == without.lastContacts);
  CHECK(with.lastNormals == without.lastNormals);
  CHECK(with.contactLists == without.contactLists);
}

// ============================================================================================================
// 4. Non-convex fields: the descent

namespace {

/// An exact torus SDF (ring radius R about the z axis, tube radius r) in the solver's field interface, declared
/// non-convex: the saddle-shaped inner wall, the hole and the ring's two sides are what a grid SDF of a torus
/// mesh presents to a face.
template <class S> struct TorusField {
  static constexpr bool kLinear = false;
  static constexpr bool kConvex = false;
  Vec3<S> centre;
  S ringRadius, tubeRadius;
  S operator()(const Vec3<S>& x, Vec3<S>& gradient) const {
    const Vec3<S> p = x - centre;
    const S rho = std::sqrt(p.x() * p.x() + p.y() * p.y());
    const Vec3<S> radial = rho > S(0) ? Vec3<S>(p.x() / rho, p.y() / rho, 0) : Vec3<S>::UnitX();
    const Vec3<S> d = p - ringRadius * radial;  // from the nearest point of the ring
    const S len = d.norm();
    gradient = len > S(0) ? Vec3<S>(d / len) : Vec3<S>::UnitZ();
    return len - tubeRadius;
  }
};

}  // namespace

TEMPLATE_TEST_CASE("on a non-convex field the descent finds the deepest point of faces near a torus", "[pgd]", float,
                   double) {
  using S = TestType;
  constexpr int kTriangles = 400, kGrid = 200;
  const int iterations = drape::Settings{}.pgdIterations;
  std::mt19937 rng(5);
  for (const double tube : {0.1, 0.03}) {
    const double ring = 0.25;
    const TorusField<S> torus{(kWorld - kOrigin).cast<S>(), S(ring), S(tube)};
    long long misses = 0, evaluations = 0;
    double worst = -1;
    for (int k = 0; k < kTriangles; ++k) {
      // A point on the tube's surface (all around, the inner saddle included), then a little in or out.
      const double u = uniform(rng, 0, 2 * std::numbers::pi), v = uniform(rng, 0, 2 * std::numbers::pi);
      const double reach = k % 5 == 0 ? 0.02 : 0.008;
      const double rr = tube + uniform(rng, -reach, reach);
      const V3 p = kWorld + V3((ring + rr * std::cos(v)) * std::cos(u), (ring + rr * std::cos(v)) * std::sin(u),
                               rr * std::sin(v));
      const Tri tri = randomTriangle(rng, p, kEdge);
      const auto x = toLocal<S>(tri, kOrigin);
      drape::FaceQuery<S> q;
      REQUIRE(drape::queryFace<false>(torus, x[0], x[1], x[2], S(0), iterations, q));
      const S brute = bruteMinimum<S>(torus, x, kGrid);
      const double edge = tri.meanEdge();
      worst = std::max(worst, (double(q.phi) - double(brute)) / edge);
      evaluations += q.evaluations;
      if (double(q.phi) > double(brute) + 1e-3 * edge) {
        ++misses;
        // A miss is the budget running out, not a wrong basin: with three times the budget it is found.
        drape::FaceQuery<S> longer;
        drape::queryFace<false>(torus, x[0], x[1], x[2], S(0), 3 * iterations, longer);
        CHECK(double(longer.phi) <= double(brute) + 1e-3 * edge);
      }
      CHECK(q.evaluations <= iterations);
      CHECK((q.barycentric.array() >= S(0)).all());
      CHECK(std::abs(double(q.barycentric.sum()) - 1) <= 1e-5);
      Vec3<S> g;
      CHECK(std::abs(double(torus(q.point, g) - q.phi)) <= 1e-6);
      // Never worse than the face's centroid, which a descent starts from.
      const Vec3<S> c = (x[0] + x[1] + x[2]) / S(3);
      CHECK(q.phi <= torus(c, g));
    }
    std::printf("[pgd] %-6s torus tube %.2f: mean evaluations %.2f, worst (descent - brute) / edge %+.2e, missed "
                "%lld of %d\n",
                sizeof(S) == 4 ? "float" : "double", tube, double(evaluations) / kTriangles, worst, misses,
                kTriangles);
    // On a field this smooth at the scale of a face (tube radius 1.5 to 5 face edges), phi along a face has one
    // minimum, which the descent finds within the default budget on at least 99 % of faces, and never more than
    // a hundredth of an edge short of it.
    CHECK(misses <= kTriangles / 100);
    CHECK(worst <= 1e-2);
  }
}

namespace {

/// A face the search found within the thickness of `sdf`, moved rigidly as the face pass would push it, with the
/// field's gradient at the deepest point (`aligned` false) or with featureAlignedPush (true); the brute-force
/// minimum of the field over the moved face.
template <class S, class Field>
S pushedMinimum(const Field& sdf, std::array<Vec3<S>, 3> x, S thickness, const drape::FaceQuery<S>& found,
                bool aligned) {
  drape::FaceQuery<S> q = found;
  int evaluations = 0;
  const S depth = aligned ? drape::featureAlignedPush(sdf, x[0], x[1], x[2], thickness, thickness - q.phi, q,
                                                      evaluations)
                          : thickness - q.phi;
  for (auto& c : x) c += depth * q.normal;
  return bruteMinimum<S>(sdf, x, 200);
}

/// A 2 cm face over a cube's corner (the cube stands on the opposite one) or its top edge (turned 45 degrees
/// about x), tilted up to 20 degrees and within a few millimetres of the feature, so the feature is inside the
/// face's thickness.
template <class S> std::array<Vec3<S>, 3> faceOverFeature(std::mt19937& rng) {
  const V3 tilt = (V3::UnitZ() + 0.36 * uniform(rng, 0, 1) * randomUnit(rng)).normalized();
  const V3 u = tilt.unitOrthogonal(), v = tilt.cross(u);
  const V3 centre(uniform(rng, -0.004, 0.004), uniform(rng, -0.004, 0.004), uniform(rng, -0.003, 0.004));
  const double a0 = uniform(rng, 0, 2 * std::numbers::pi);
  std::array<Vec3<S>, 3> x;
  for (int k = 0; k < 3; ++k) {
    const double a = a0 + k * 2 * std::numbers::pi / 3;
    x[std::size_t(k)] = (centre + 0.0115 * (std::cos(a) * u + std::sin(a) * v)).cast<S>();
  }
  return x;
}

}  // namespace

TEMPLATE_TEST_CASE("a face on a box's corner or edge is pushed clear along its own normal", "[pgd][feature]", float,
                   double) {
  using S = TestType;
  const S thickness = S(0.005);
  // Fewer under the sanitizers, where each brute force costs about 20 times as much (120 meet every check).
  const int trials = drape::test::kSanitized ? 120 : 400;
  for (const bool corner : {true, false}) {
    // The feature at the origin: the cube's top corner, or the top edge of a box along x.
    drape::Box box;
    box.halfExtents = corner ? V3(0.2, 0.2, 0.2) : V3(1.0, 0.2, 0.2);
    drape::Pose pose;
    pose.rotation = corner ? Eigen::Quaterniond::FromTwoVectors(V3(1, 1, 1), V3::UnitZ())
                           : Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 4, V3::UnitX()));
    pose.position = {0, 0, -0.2 * (corner ? std::sqrt(3.0) : std::sqrt(2.0))};
    const auto sdf = drape::detail::compileSdf<S>(box, pose, V3::Zero());
    std::mt19937 rng(corner ? 11 : 12);
    int cases = 0, inside = 0, onEdge = 0;
    S worstAligned = std::numeric_limits<S>::infinity(), worstGradient = worstAligned;
    for (int trial = 0; trial < trials; ++trial) {
      const auto x = faceOverFeature<S>(rng);
      drape::FaceQuery<S> q;
      if (!drape::queryFace<true>(sdf, x[0], x[1], x[2], thickness, 12, q) || q.phi >= thickness) continue;
      ++cases;
      const S least = q.barycentric.minCoeff();
      inside += least > S(drape::constants::kFeatureBarycentric);
      onEdge += least <= S(drape::constants::kFeatureBarycentric);
      worstAligned = std::min(worstAligned, pushedMinimum(sdf, x, thickness, q, true));
      worstGradient = std::min(worstGradient, pushedMinimum(sdf, x, thickness, q, false));
    }
    INFO((corner ? "corner" : "edge") << ": " << cases << " faces in contact (" << inside << " inside, " << onEdge
                                      << " on an edge); worst clearance after the push " << worstAligned
                                      << " m aligned, " << worstGradient << " m along the gradient");
    std::printf("feature push (%s, %s): %d faces (%d inside, %d on an edge), worst clearance %.6f aligned, %.6f "
                "gradient (thickness %.3f)\n",
                sizeof(S) == 4 ? "float" : "double", corner ? "corner" : "edge", cases, inside, onEdge,
                double(worstAligned), double(worstGradient), double(thickness));
    // Measured (float and double): over the corner 4.89 mm of the 5 mm clearance with the aligned push, -0.21 /
    // -0.03 mm (the corner still inside the solid) along the gradient; over the edge 4.57 mm against 0.64 /
    // -0.28 mm. Over the edge, the gradient without its part along the face's edge (the push before it mixed the
    // gradients to either side of the point) cleared 1.9-2.0 mm only: it is not across the box's edge.
    CHECK(cases >= trials / 2);
    if (corner) {
      CHECK(worstAligned >= S(0.95) * thickness);
      CHECK(worstGradient < S(0.5) * thickness);
    } else {
      CHECK(worstAligned >= S(0.9) * thickness);
      CHECK(worstGradient < S(0.2) * thickness);
    }
  }
}

TEMPLATE_TEST_CASE("on a ball or a capsule the feature push keeps the field's gradient", "[pgd][feature]", float,
                   double) {
  using S = TestType;
  const S thickness = S(0.005);
  drape::Sphere ball;
  ball.radius = 0.2;
  drape::Capsule capsule;
  capsule.radius = 0.05;
  capsule.halfHeight = 0.3;
  drape::Pose pose;
  pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, V3(1, 2, 3).normalized()));
  const auto ballSdf = drape::detail::compileSdf<S>(ball, pose, V3::Zero());
  const auto capsuleSdf = drape::detail::compileSdf<S>(capsule, pose, V3::Zero());
  std::mt19937 rng(13);
  const V3 axis = pose.rotation * V3::UnitZ();
  auto check = [&](const auto& sdf, bool onCapsule) {
    int cases = 0, changed = 0;
    for (int trial = 0; trial < 300; ++trial) {
      V3 dir = randomUnit(rng);
      if (onCapsule) dir = (dir - dir.dot(axis) * axis).normalized();
      const double radius = onCapsule ? capsule.radius : ball.radius;
      const V3 c = (radius + uniform(rng, -0.004, 0.006)) * dir + (onCapsule ? uniform(rng, -0.2, 0.2) : 0.0) * axis;
      const auto t = drape::test::faces::randomTriangle(rng, c, 0.02);
      const std::array<Vec3<S>, 3> x = {t[0].cast<S>(), t[1].cast<S>(), t[2].cast<S>()};
      drape::FaceQuery<S> q;
      if (!drape::queryFace<true>(sdf, x[0], x[1], x[2], thickness, 12, q) || q.phi >= thickness) continue;
      ++cases;
      drape::FaceQuery<S> aligned = q;
      int evaluations = 0;
      const S depth = drape::featureAlignedPush(sdf, x[0], x[1], x[2], thickness, thickness - q.phi, aligned,
                                                evaluations);
      changed += !(depth == thickness - q.phi && aligned.normal == q.normal);
    }
    return std::pair(cases, changed);
  };
  const auto [ballCases, ballChanged] = check(ballSdf, false);
  // The capsule's side, between its caps.
  const auto [capsuleCases, capsuleChanged] = check(capsuleSdf, true);
  INFO("ball: " << ballChanged << " of " << ballCases << " changed; capsule: " << capsuleChanged << " of "
                << capsuleCases);
  CHECK(ballCases >= 100);
  CHECK(capsuleCases >= 100);
  CHECK(ballChanged == 0);
  CHECK(capsuleChanged == 0);
}

}  // namespace pgd_tests
