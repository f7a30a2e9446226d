// The face search on grid fields built from meshes (branch and bound, drape/sdf/grid_search.hpp): its pieces
// against direct evaluation, and whole searches against a 200-subdivision brute force on meshes with sharp
// edges and corners, concave edges and curved surfaces, at several resolutions and orientations.

#include "face_search_helpers.hpp"
#include "sanitizer.hpp"

#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace grid_search_tests {

namespace {

using drape::Index;
using drape::Vec3;
using V3 = Eigen::Vector3d;

using drape::test::faces::bruteMinimum;
using drape::test::faces::randomTriangle;
using drape::test::faces::uniform;

/// A mesh, the resolution of its grid, and how far from its surface the test's faces are centred.
struct Case {
  std::string name;
  drape::TriangleMesh mesh;
  Index resolution;
};

std::vector<Case> cases() {
  return {{"cube, 16 cells", drape::makeBoxMesh(V3(0.1, 0.1, 0.1)), 16},
          {"cube, 48 cells", drape::makeBoxMesh(V3(0.1, 0.1, 0.1)), 48},
          {"thin board, 40 cells", drape::makeBoxMesh(V3(0.2, 0.15, 0.005)), 40},
          {"L block, 32 cells", drape::makeLBlock(0.4, 0.15, 0.1), 32},
          {"torus, 24 cells", drape::makeTorus(0.15, 0.05, 48, 24), 24},
          {"torus, 64 cells", drape::makeTorus(0.15, 0.05, 48, 24), 64},
          {"icosphere, 32 cells", drape::makeIcosphere(0.12, 3), 32}};
}

/// A point on the mesh's surface: a random triangle (by area) and a random point of it, with its normal.
V3 surfacePoint(std::mt19937& rng, const drape::TriangleMesh& m, V3& normal) {
  std::vector<double> area;
  for (const auto& f : m.triangles)
    area.push_back((m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]).norm());
  std::discrete_distribution<std::size_t> pick(area.begin(), area.end());
  const auto& f = m.triangles[pick(rng)];
  double a = uniform(rng, 0, 1), b = uniform(rng, 0, 1);
  if (a + b > 1) a = 1 - a, b = 1 - b;
  normal = (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]).normalized();
  return m.vertices[f[0]] + a * (m.vertices[f[1]] - m.vertices[f[0]]) + b * (m.vertices[f[2]] - m.vertices[f[0]]);
}

}  // namespace

TEMPLATE_TEST_CASE("a cell's trilinear polynomial expands exactly about any point", "[pgd][meshsdf]", float, double) {
  using S = TestType;
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    S v[8];
    for (S& x : v) x = S(uniform(rng, -1, 1));
    auto trilinear = [&](const Vec3<S>& t) {
      S sum = 0;
      for (int k = 0; k < 8; ++k)
        sum += v[k] * (k & 1 ? t.x() : 1 - t.x()) * (k & 2 ? t.y() : 1 - t.y()) * (k & 4 ? t.z() : 1 - t.z());
      return sum;
    };
    const Vec3<S> c(S(uniform(rng, -0.5, 1.5)), S(uniform(rng, -0.5, 1.5)), S(uniform(rng, -0.5, 1.5)));
    const auto p = drape::detail::CellPolynomial<S>::expand(v, c);
    const Vec3<S> d(S(uniform(rng, -1, 1)), S(uniform(rng, -1, 1)), S(uniform(rng, -1, 1)));
    const S series = p.value + p.slope.dot(d) + p.xy * d.x() * d.y() + p.xz * d.x() * d.z() + p.yz * d.y() * d.z() +
                     p.xyz * d.x() * d.y() * d.z();
    CHECK(std::abs(double(series - trilinear(c + d))) <= 40 * double(std::numeric_limits<S>::epsilon()));
    CHECK(p.lowestNode == *std::min_element(v, v + 8));
  }
}

TEMPLATE_TEST_CASE("the quadratic part's minimum over a triangle is exact", "[pgd][meshsdf]", float, double) {
  using S = TestType;
  std::mt19937 rng(4);
  int interior = 0, edges = 0;
  for (int trial = 0; trial < 300; ++trial) {
    drape::detail::CellPolynomial<S> p{};
    p.value = S(uniform(rng, -1, 1));
    p.slope = Vec3<S>(S(uniform(rng, -1, 1)), S(uniform(rng, -1, 1)), S(uniform(rng, -1, 1)));
    p.xy = S(uniform(rng, -3, 3)), p.xz = S(uniform(rng, -3, 3)), p.yz = S(uniform(rng, -3, 3));
    Vec3<S> d[3];
    for (auto& x : d) x = Vec3<S>(S(uniform(rng, -0.6, 0.6)), S(uniform(rng, -0.6, 0.6)), S(uniform(rng, -0.6, 0.6)));
    if (trial % 2 == 1) {
      // A bowl: with xy = xz = yz = -k the quadratic part is k (|d|^2 - (dx + dy + dz)^2) / 2, convex on any plane
      // normal to (1, 1, 1), so a triangle in such a plane, on a gentle slope, holds its minimum inside.
      p.xy = p.xz = p.yz = S(-2);
      p.slope *= S(0.3);
      const Vec3<S> axis = Vec3<S>::Ones().normalized();
      for (auto& x : d) x -= x.dot(axis) * axis;
    }
    auto model = [&](const Vec3<S>& x) {
      return p.value + p.slope.dot(x) + p.xy * x.x() * x.y() + p.xz * x.x() * x.z() + p.yz * x.y() * x.z();
    };
    S alpha, beta;
    const S lowest = drape::detail::lowestOfQuadratic(p, d, alpha, beta);
    // It is the model's value at the place it names, a point of the triangle...
    REQUIRE(alpha >= S(0));
    REQUIRE(beta >= S(0));
    REQUIRE(alpha + beta <= S(1) + S(1e-6));
    CHECK(std::abs(double(lowest - model(d[0] + alpha * (d[1] - d[0]) + beta * (d[2] - d[0])))) <= 1e-5);
    // ... and no lattice point of the triangle is lower.
    constexpr int n = 200;
    S brute = std::numeric_limits<S>::infinity();
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n - i; ++j)
        brute = std::min(brute, model(d[0] + S(i) / S(n) * (d[1] - d[0]) + S(j) / S(n) * (d[2] - d[0])));
    CHECK(double(lowest) <= double(brute) + 1e-5);
    const bool inside = alpha > S(0) && beta > S(0) && alpha + beta < S(1);
    interior += inside ? 1 : 0;
    edges += !inside && (alpha > S(0) || beta > S(0)) && alpha != S(1) && beta != S(1) ? 1 : 0;
  }
  // The cases the minimum has were all met: inside the triangle and inside an edge.
  CHECK(interior >= 10);
  CHECK(edges >= 10);
}

TEMPLATE_TEST_CASE("on grid fields built from meshes the face search finds the deepest point within 1e-3 edge",
                   "[pgd][meshsdf]", float, double) {
  using S = TestType;
  constexpr double kEdge = 0.02;
  const int faces = drape::test::kSanitized ? 30 : 300;
  const int brute = drape::test::kSanitized ? 60 : 200;
  const int budget = drape::Settings{}.pgdIterations;  // what the descent gets; the grid search has its own
  std::mt19937 rng(11);
  for (const Case& c : cases()) {
    // Padded so that every test face lies in the grid's box, where the field is trilinear (see below for beyond).
    const auto grid = drape::buildDistanceGrid(c.mesh, {c.resolution, 0, 0.04});
    for (const bool turned : {false, true}) {
      drape::Pose pose;
      pose.position = V3(12.5, -4.25, 3.0);
      if (turned) pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, V3(1, 2, 3).normalized()));
      const V3 origin = pose.position + V3(0.01, -0.02, 0.015);
      const auto sdf = drape::detail::compileSdf<S>(drape::MeshShape{grid}, pose, origin);
      long long evaluations = 0, misses = 0, descentMisses = 0;
      int most = 0;
      double worst = -1, descentWorst = -1;
      for (int k = 0; k < faces; ++k) {
        V3 n;
        const V3 p = surfacePoint(rng, c.mesh, n);
        const double reach = k % 5 == 0 ? 0.02 : 0.006;
        const auto tri = randomTriangle(rng, pose.position + pose.rotation * V3(p + uniform(rng, -reach, reach) * n), kEdge);
        const std::array<Vec3<S>, 3> x{(tri[0] - origin).template cast<S>(),
                                       (tri[1] - origin).template cast<S>(),
                                       (tri[2] - origin).template cast<S>()};
        const double edge = ((tri[1] - tri[0]).norm() + (tri[2] - tri[1]).norm() + (tri[0] - tri[2]).norm()) / 3;
        drape::FaceQuery<S> q;
        REQUIRE(drape::queryFace<false>(sdf, x[0], x[1], x[2], S(0), budget, q));
        const S lowest = bruteMinimum<S>(sdf, x, brute);
        const double miss = (double(q.phi) - double(lowest)) / edge;
        worst = std::max(worst, miss);
        evaluations += q.evaluations;
        most = std::max(most, q.evaluations);
        misses += miss > 1e-3 ? 1 : 0;
        INFO(c.name << (turned ? ", turned" : "") << ", face " << k << ": search " << q.phi << " at b = "
                    << q.barycentric.transpose() << " in " << q.evaluations << " evaluations, brute " << lowest);
        CHECK(miss <= 1e-3);
        CHECK((q.barycentric.array() >= S(0)).all());
        CHECK(std::abs(double(q.barycentric.sum()) - 1) <= 1e-5);
        CHECK((q.point - (q.barycentric[0] * x[0] + q.barycentric[1] * x[1] + q.barycentric[2] * x[2])).norm() <=
              S(1e-5) * S(edge));
        Vec3<S> g;
        CHECK(std::abs(double(sdf(q.point, g) - q.phi)) <= 1e-6);
        // The descent it replaced, for the record.
        const Vec3<S> centre = (x[0] + x[1] + x[2]) / S(3);
        const S phiC = sdf(centre, g);
        const auto d = drape::descendOnFace<S>(sdf, x[0], x[1], x[2], centre, phiC, g, budget);
        const double descentMiss = (double(d.phi) - double(lowest)) / edge;
        descentWorst = std::max(descentWorst, descentMiss);
        descentMisses += descentMiss > 1e-3 ? 1 : 0;
      }
      std::printf("[grid search] %-6s %-22s %-6s: evaluations mean %5.1f, most %4d; worst miss %+.1e edge "
                  "(%lld of %d beyond 1e-3); the descent: worst %+.1e, %lld beyond\n",
                  sizeof(S) == 4 ? "float" : "double", c.name.c_str(), turned ? "turned" : "square",
                  double(evaluations) / faces, most, worst, misses, faces, descentWorst, descentMisses);
    }
  }
}

TEMPLATE_TEST_CASE("on grid fields the face pass's cull and search never lose a face within the thickness",
                   "[pgd][meshsdf][culling]", float, double) {
  // The grids as built by default (one cell of padding), so faces reach beyond the grid's box, where the
  // search falls back on the Lipschitz bound; with a floor at the thickness it still settles every face.
  using S = TestType;
  constexpr double kEdge = 0.02, kThickness = 0.005;
  const int faces = drape::test::kSanitized ? 40 : 400;
  const int brute = drape::test::kSanitized ? 60 : 200;
  std::mt19937 rng(12);
  for (const Case& c : cases()) {
    const auto grid = drape::buildDistanceGrid(c.mesh, {c.resolution});
    drape::Pose pose;
    pose.position = V3(-2.5, 1.25, 0.5);
    pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-0.4, V3(2, -1, 1).normalized()));
    const V3 origin = pose.position + V3(-0.01, 0.02, 0.005);
    const auto sdf = drape::detail::compileSdf<S>(drape::MeshShape{grid}, pose, origin);
    long long evaluations = 0, searched = 0, within = 0;
    int most = 0;
    for (int k = 0; k < faces; ++k) {
      V3 n;
      const V3 p = surfacePoint(rng, c.mesh, n);
      const auto tri = randomTriangle(rng, pose.position + pose.rotation * V3(p + uniform(rng, -0.004, 0.016) * n), kEdge);
      const std::array<Vec3<S>, 3> x{(tri[0] - origin).template cast<S>(), (tri[1] - origin).template cast<S>(),
                                     (tri[2] - origin).template cast<S>()};
      const double edge = ((tri[1] - tri[0]).norm() + (tri[2] - tri[1]).norm() + (tri[0] - tri[2]).norm()) / 3;
      drape::FaceQuery<S> q{};  // left as is when the face is culled
      const bool kept = drape::queryFace<true>(sdf, x[0], x[1], x[2], S(kThickness), 12, q);
      const S lowest = bruteMinimum<S>(sdf, x, brute);
      INFO(c.name << ", face " << k << ": " << (kept ? "searched" : "culled") << ", phi " << q.phi << " in "
                  << q.evaluations << " evaluations; brute " << lowest);
      if (kept) {
        ++searched;
        evaluations += q.evaluations;
        most = std::max(most, q.evaluations);
      }
      if (double(lowest) < kThickness - 1e-3 * edge) {
        ++within;
        REQUIRE(kept);
        // Within the thickness the search is exact: the contact moves the face by the right depth.
        CHECK(double(q.phi) <= double(lowest) + 1e-3 * edge);
      }
    }
    std::printf("[grid search] %-6s %-22s cull at 5 mm: %lld of %d faces within it, %lld searched, evaluations mean "
                "%5.1f, most %d\n",
                sizeof(S) == 4 ? "float" : "double", c.name.c_str(), within, faces, searched,
                double(evaluations) / double(std::max(searched, 1LL)), most);
    CHECK(within >= faces / 4);  // the faces do meet the solid
  }
}

}  // namespace grid_search_tests
