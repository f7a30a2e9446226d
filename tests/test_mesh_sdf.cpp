// Grid distance fields from closed meshes (drape/sdf/mesh.hpp, grid.hpp, obj.hpp). References are brute force
// and share no code with the builder (scenes/mesh_shapes.hpp): the distance to the mesh by projection onto each
// triangle, the inside test by the winding number, and the analytic distance of each shape.
#include <drape/sdf/grid.hpp>
#include <drape/sdf/obj.hpp>

#include <mesh_shapes.hpp>

#include <catch2/catch.hpp>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

// Each test source keeps its helpers in a namespace of its own: the tests build as unity batches.
namespace mesh_sdf_tests {

namespace {

using namespace drape;
using Catch::Matchers::Contains;
using Vec = Eigen::Vector3d;

const std::vector<scenes::MeshShapeCase>& shapes() {
  static const std::vector<scenes::MeshShapeCase> cases = scenes::meshShapeCases();
  return cases;
}

/// Padding around each mesh's box: the grids' margin, and where the random points are drawn.
double padOf(const TriangleMesh& m) {
  const auto [lo, hi] = scenes::meshBounds(m);
  return 0.1 * (hi - lo).maxCoeff();
}

/// Grids are built once per shape and resolution and shared by the float and double instantiations.
std::shared_ptr<const DistanceGrid> gridFor(std::size_t shape, Index resolution) {
  static std::map<std::pair<std::size_t, Index>, std::shared_ptr<const DistanceGrid>> cache;
  auto& g = cache[{shape, resolution}];
  if (!g) {
    DistanceGridOptions o;
    o.resolution = resolution;
    o.margin = padOf(shapes()[shape].mesh);
    g = buildDistanceGrid(shapes()[shape].mesh, o);
  }
  return g;
}

/// Random points in the mesh's box grown by the pad (inside every grid built by gridFor).
std::vector<Vec> randomPoints(const TriangleMesh& m, int count, unsigned seed) {
  const auto [lo, hi] = scenes::meshBounds(m);
  const double pad = padOf(m);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Vec> out(count);
  for (auto& p : out)
    p = (lo.array() - pad + Eigen::Array3d(unit(rng), unit(rng), unit(rng)) * ((hi - lo).array() + 2 * pad)).matrix();
  return out;
}

/// sum_i w_i |x - node_i| over the 8 nodes of x's cell: the most a trilinear interpolant of a 1-Lipschitz
/// field can be off at x (the nodes are exact), at most sqrt(3)/2 cells.
double lipschitzBound(const DistanceGrid& g, const Vec& x) {
  const Vec u = (x - g.lower) / g.cellSize;
  const Vec c(std::floor(u.x()), std::floor(u.y()), std::floor(u.z()));
  const Vec t = u - c;
  double bound = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec bits((corner & 1) ? 1 : 0, (corner & 2) ? 1 : 0, (corner & 4) ? 1 : 0);
    const double w = (bits.x() ? t.x() : 1 - t.x()) * (bits.y() ? t.y() : 1 - t.y()) * (bits.z() ? t.z() : 1 - t.z());
    bound += w * (t - bits).norm() * g.cellSize;
  }
  return bound;
}

double angleBetween(const Vec& a, const Vec& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

template <Scalar S>
Sdf<MeshShape, S> identitySdf(const std::shared_ptr<const DistanceGrid>& g) {
  return detail::compileSdf<S>(MeshShape{g}, Pose{}, Vec::Zero());
}

template <Scalar S>
double sampleAt(const Sdf<MeshShape, S>& sdf, const Vec& x, Vec* gradient = nullptr) {
  Vec3<S> g;
  const double phi = double(sdf(x.cast<S>(), g));
  if (gradient) *gradient = g.template cast<double>();
  return phi;
}

/// Float rounding of a sample: the query's coordinates (about 1 m, 6e-8 relative) and the stored floats.
template <Scalar S>
constexpr double kRounding = std::is_same_v<S, float> ? 2e-6 : 1e-9;

}  // namespace

// --- Meshes --------------------------------------------------------------------------------------------------

TEST_CASE("generated meshes are closed, outward, and lie on their analytic shapes", "[meshsdf]") {
  for (const auto& s : shapes()) {
    INFO(s.name);
    REQUIRE_NOTHROW(validateClosedMesh(s.mesh));
    // Euler characteristic V - E + F: 2 for a sphere-like surface, 0 for the torus (E = 3F/2 when closed).
    const int euler = s.mesh.vertexCount() - 3 * s.mesh.triangleCount() / 2 + s.mesh.triangleCount();
    CHECK(euler == (s.name == "torus" ? 0 : 2));
    for (const auto& v : s.mesh.vertices) CHECK(std::abs(s.analytic(v)) < 1e-12);
    // Outward: the winding number is 1 at a point inside and 0 outside.
    const Vec inside = s.name == "torus" ? Vec(0.4, 0, 0) : s.name == "L block" ? Vec(-0.3, -0.3, 0) : Vec::Zero();
    CHECK(scenes::windingNumber(s.mesh, inside) == Approx(1).margin(1e-9));
    CHECK(scenes::windingNumber(s.mesh, Vec(3, 1, 2)) == Approx(0).margin(1e-9));
  }
  CHECK(makeIcosphere(1, 2).triangleCount() == 320);
  CHECK(makeTorus(1, 0.3, 10, 7).triangleCount() == 140);
  CHECK(makeBoxMesh(Vec(1, 2, 3)).triangleCount() == 12);
  CHECK(makeLBlock(1, 0.3, 0.2).triangleCount() == 20);
  CHECK_THROWS_WITH(makeIcosphere(-1, 2), Contains("radius"));
  CHECK_THROWS_WITH(makeTorus(0.2, 0.3, 10, 7), Contains("R > r"));
  CHECK_THROWS_WITH(makeLBlock(1, 1.5, 0.2), Contains("armWidth"));
}

TEST_CASE("closed-mesh validation names what is wrong", "[meshsdf]") {
  const TriangleMesh box = makeBoxMesh(Vec(1, 1, 1));
  auto fails = [](const TriangleMesh& m, const std::string& what) {
    CHECK_THROWS_AS(validateClosedMesh(m), Error);
    CHECK_THROWS_WITH(validateClosedMesh(m), Contains(what));
    // The builder rejects it the same way, before building anything.
    CHECK_THROWS_WITH(buildDistanceGrid(m), Contains(what));
  };
  fails(TriangleMesh{}, "at least 4 triangles");
  {
    TriangleMesh m = box;
    m.vertices[5].y() = std::numeric_limits<double>::quiet_NaN();
    fails(m, "vertex 5 is not finite");
  }
  {
    TriangleMesh m = box;
    m.vertices[3].z() = 1e300;  // finite, but the field's arithmetic would overflow
    fails(m, "vertex 3 is not finite or lies beyond 1e5 m");
  }
  {
    TriangleMesh m = box;
    m.triangles[3][1] = 8;
    fails(m, "triangle 3 has vertex index 8 outside [0, 8)");
  }
  {
    TriangleMesh m = box;
    m.triangles[2] = {4, 4, 7};
    fails(m, "triangle 2 repeats a vertex");
  }
  {
    TriangleMesh m = box;
    m.vertices[7] = (m.vertices[4] + m.vertices[5]) / 2;  // triangle {4, 5, 7} collapses onto a line
    fails(m, "degenerate");
  }
  {
    TriangleMesh m = box;
    m.triangles.pop_back();
    fails(m, "not closed");
  }
  {
    TriangleMesh m = box;
    std::swap(m.triangles[0][1], m.triangles[0][2]);
    fails(m, "inconsistent orientation");
  }
  {
    TriangleMesh m = box;  // a fin on the edge (0, 2): a third face there
    m.vertices.push_back(Vec(-2, 0, -2));
    m.triangles.push_back({0, 2, 8});
    m.triangles.push_back({2, 0, 8});
    fails(m, "more than two faces");
  }
  {
    // Two tetrahedra touching at one vertex: every edge is fine, the shared vertex is not.
    TriangleMesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 5, 4}, {0, 4, 6}, {0, 6, 5}, {4, 5, 6}};
    fails(m, "vertex 0 is non-manifold");
  }
  {
    TriangleMesh m = box;
    for (auto& f : m.triangles) std::swap(f[1], f[2]);
    fails(m, "inside out");
  }
}

TEST_CASE("distance grid options and mesh shapes are checked before use", "[meshsdf]") {
  const TriangleMesh box = makeBoxMesh(Vec(1, 1, 1));
  DistanceGridOptions o;
  o.resolution = 1;
  CHECK_THROWS_WITH(buildDistanceGrid(box, o), Contains("resolution must be in [2, 1024]"));
  o = {};
  o.margin = -0.1;
  CHECK_THROWS_WITH(buildDistanceGrid(box, o), Contains("margin"));
  o = {};
  o.cellSize = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(buildDistanceGrid(box, o), Contains("cellSize"));
  o = {};
  o.cellSize = 1e-4;  // 20000 cells per axis
  CHECK_THROWS_WITH(buildDistanceGrid(box, o), Contains("cells along one axis"));
  o.cellSize = 2.0 / 1000;  // 1002^3 nodes
  CHECK_THROWS_WITH(buildDistanceGrid(box, o), Contains("nodes (at most 2^26"));

  CHECK_THROWS_WITH(detail::validateShape(MeshShape{}), Contains("no grid"));
  auto broken = std::make_shared<DistanceGrid>(*buildDistanceGrid(box, DistanceGridOptions{4, 0, 0}));
  broken->nodes.pop_back();
  CHECK_THROWS_WITH(detail::validateShape(MeshShape{broken}), Contains("not nodeCount's product"));
  CHECK_NOTHROW(detail::validateShape(MeshShape{buildDistanceGrid(box, DistanceGridOptions{4, 0, 0})}));
}

// --- The grid's nodes ----------------------------------------------------------------------------------------

TEST_CASE("every node holds the exact signed distance, its sign and the direction from its closest point",
          "[meshsdf]") {
  for (std::size_t s = 0; s < shapes().size(); ++s) {
    const auto& shape = shapes()[s];
    INFO(shape.name);
    const auto grid = gridFor(s, 16);
    const double h = grid->cellSize;
    int wrongSign = 0, wrongDistance = 0, wrongNormal = 0;
    for (Index k = 0; k < grid->nodeCount[2]; ++k)
      for (Index j = 0; j < grid->nodeCount[1]; ++j)
        for (Index i = 0; i < grid->nodeCount[0]; ++i) {
          const Vec p = grid->nodePosition(i, j, k);
          const Eigen::Vector4f node = grid->nodes[grid->nodeIndex(i, j, k)];
          const double phi = node[3];
          const double exact = scenes::meshDistance(shape.mesh, p);
          wrongDistance += std::abs(std::abs(phi) - exact) > 1e-6;
          // Nodes on a face (the box's and the L block's faces fall on grid planes) hold 0, of either sign.
          if (exact > 1e-9) wrongSign += (phi < 0) != (scenes::windingNumber(shape.mesh, p) > 0.5);
          // Stepping back along the normal by the distance lands on the surface, even where the closest point
          // is not unique (the medial axis).
          const Vec n = node.head<3>().cast<double>();
          wrongNormal += std::abs(n.norm() - 1) > 1e-6 || scenes::meshDistance(shape.mesh, p - phi * n) > 1e-5 * h;
        }
    CHECK(wrongSign == 0);
    CHECK(wrongDistance == 0);
    CHECK(wrongNormal == 0);
  }
}

TEST_CASE("the sign is right around acute edges and vertices, where a face normal alone would get it wrong",
          "[meshsdf]") {
  // A thin tetrahedron: dihedral angles far below 90 degrees, so outside an edge the direction from the edge can
  // point into the half-space behind one of its faces. Only the edge's and vertex's pseudonormals decide it.
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0.45, 0.2, 0}, {0.5, 0.08, 0.25}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  REQUIRE_NOTHROW(validateClosedMesh(m));
  const auto grid = buildDistanceGrid(m, DistanceGridOptions{40, 0, 0.1});
  int checked = 0, wrongSign = 0;
  for (Index k = 0; k < grid->nodeCount[2]; ++k)
    for (Index j = 0; j < grid->nodeCount[1]; ++j)
      for (Index i = 0; i < grid->nodeCount[0]; ++i) {
        const Vec p = grid->nodePosition(i, j, k);
        if (scenes::meshDistance(m, p) < 1e-9) continue;
        ++checked;
        wrongSign += (grid->nodes[grid->nodeIndex(i, j, k)][3] < 0) != (scenes::windingNumber(m, p) > 0.5);
      }
  CHECK(checked > 10000);
  CHECK(wrongSign == 0);
}

// --- Sampling inside the grid --------------------------------------------------------------------------------

TEMPLATE_TEST_CASE("sampled field: error within a fraction of a cell, falling with resolution, sign beyond it",
                   "[meshsdf]", float, double) {
  using S = TestType;
  const double nearBand = 0.05;  // m: "near the surface", where cloth meets the solid
  for (std::size_t s = 0; s < shapes().size(); ++s) {
    const auto& shape = shapes()[s];
    INFO(shape.name);
    const auto points = randomPoints(shape.mesh, 2000, 11 + unsigned(s));
    std::vector<double> exact, analytic;
    for (const auto& p : points) {
      exact.push_back(scenes::meshSignedDistance(shape.mesh, p));
      analytic.push_back(shape.analytic(p));
    }
    std::vector<double> maxNear, rms;
    for (Index resolution : {16, 32, 64}) {
      INFO("resolution " << resolution);
      const auto grid = gridFor(s, resolution);
      const auto sdf = identitySdf<S>(grid);
      const double h = grid->cellSize;
      double worstNear = 0, sum2 = 0;
      int beyondBound = 0, wrongSign = 0, nearTooFar = 0, offAnalytic = 0;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const double phi = sampleAt(sdf, points[i]);
        const double err = std::abs(phi - exact[i]);
        const double bound = lipschitzBound(*grid, points[i]) + kRounding<S>;
        beyondBound += err > bound;
        wrongSign += std::abs(exact[i]) > bound && (phi < 0) != (exact[i] < 0);
        if (std::abs(exact[i]) < nearBand) {
          nearTooFar += err > 0.5 * h;
          worstNear = std::max(worstNear, err);
        }
        offAnalytic += std::abs(phi - analytic[i]) > bound + shape.tessellation;
        sum2 += err * err;
      }
      CHECK(beyondBound == 0);  // |error| <= sum_i w_i |x - node_i| <= sqrt(3)/2 cell everywhere
      CHECK(wrongSign == 0);    // the sign is right wherever the distance exceeds that bound
      CHECK(nearTooFar == 0);   // half a cell near the surface (creases of the field cost up to 0.43 cells)
      CHECK(offAnalytic == 0);  // the analytic shape, within the bound plus the tessellation
      maxNear.push_back(worstNear);
      rms.push_back(std::sqrt(sum2 / double(points.size())));
    }
    // In metres, the error falls as the cells shrink.
    CHECK(rms[1] < rms[0]);
    CHECK(rms[2] < rms[1]);
    CHECK(maxNear[1] < maxNear[0]);
    CHECK(maxNear[2] < maxNear[1]);
  }
}

TEMPLATE_TEST_CASE("sampled normals match the analytic gradients away from edges and creases", "[meshsdf]", float,
                   double) {
  using S = TestType;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1, 1);

  SECTION("box: exact near the middle of its faces, inside and out") {
    const auto grid = gridFor(1, 32);
    const auto sdf = identitySdf<S>(grid);
    const double h = grid->cellSize;
    const Vec half(0.4, 0.3, 0.2);
    double worst = 0;
    for (int i = 0; i < 600; ++i) {
      const int axis = i % 3;
      const double side = (i / 3) % 2 ? 1 : -1;
      const bool inside = (i / 6) % 2;
      Vec p;
      for (int a = 0; a < 3; ++a) p[a] = unit(rng) * (half[a] - 3 * h);
      // Depth along the face's normal, and inside far enough from the other faces that every corner of the
      // cell has this face as its nearest (no crease in the cell).
      const double depth = h * (0.1 + 2 * std::abs(unit(rng)));
      p[axis] = side * (half[axis] + (inside ? -depth : depth));
      if (inside) {
        bool clear = true;
        for (int a = 0; a < 3; ++a)
          if (a != axis) clear = clear && half[a] - std::abs(p[a]) > depth + 2 * std::sqrt(3.0) * h;
        if (!clear) continue;
      }
      Vec g;
      sampleAt(sdf, p, &g);
      worst = std::max(worst, angleBetween(g, side * Vec::Unit(axis)));
    }
    CHECK(worst < (std::is_same_v<S, float> ? 1e-5 : 1e-7));
  }

  SECTION("box: outside its edges, where the field turns smoothly, closer as the cells shrink") {
    const Vec half(0.4, 0.3, 0.2);
    std::vector<double> mean;
    for (Index resolution : {16, 32, 64}) {
      const auto sdf = identitySdf<S>(gridFor(1, resolution));
      std::mt19937_64 local(7);
      std::uniform_real_distribution<double> u(-1, 1);
      double sum = 0;
      for (int i = 0; i < 500; ++i) {
        const int along = i % 3;  // the edge's axis; the other two coordinates lie beyond the box
        Vec p;
        p[along] = u(local) * 0.8 * half[along];
        const double angle = (0.1 + 0.8 * std::abs(u(local))) * std::numbers::pi / 2,
                     r = 0.03 + 0.02 * std::abs(u(local));
        const int a1 = (along + 1) % 3, a2 = (along + 2) % 3;
        const double s1 = u(local) < 0 ? -1 : 1, s2 = u(local) < 0 ? -1 : 1;
        p[a1] = s1 * (half[a1] + r * std::cos(angle));
        p[a2] = s2 * (half[a2] + r * std::sin(angle));
        Vec edge = p;
        edge[a1] = s1 * half[a1];
        edge[a2] = s2 * half[a2];
        Vec g;
        sampleAt(sdf, p, &g);
        sum += angleBetween(g, p - edge);
      }
      mean.push_back(sum / 500);
    }
    INFO("mean angle error at 16, 32, 64: " << mean[0] << ", " << mean[1] << ", " << mean[2]);
    CHECK(mean[1] < 0.6 * mean[0]);  // first order in the cell size at least
    CHECK(mean[2] < 0.6 * mean[1]);
  }

  SECTION("icosphere and torus: near the surface, within the facets' tilt of the analytic normal") {
    for (std::size_t s : {std::size_t(0), std::size_t(2)}) {
      const auto& shape = shapes()[s];
      INFO(shape.name);
      auto analyticGradient = [&](const Vec& x) {
        Vec g;
        for (int a = 0; a < 3; ++a)
          g[a] = shape.analytic(x + 1e-6 * Vec::Unit(a)) - shape.analytic(x - 1e-6 * Vec::Unit(a));
        return g;
      };
      // The mesh's own normals deviate from the analytic ones by up to the largest angle between a facet's
      // normal and the analytic normal at its corners.
      double tilt = 0;
      for (const auto& f : shape.mesh.triangles) {
        const Vec n = (shape.mesh.vertices[f[1]] - shape.mesh.vertices[f[0]])
                          .cross(shape.mesh.vertices[f[2]] - shape.mesh.vertices[f[0]]);
        for (Index v : f) tilt = std::max(tilt, angleBetween(n, analyticGradient(shape.mesh.vertices[v])));
      }
      const auto points = randomPoints(shape.mesh, 4000, 3);
      for (Index resolution : {16, 32, 64}) {
        const auto sdf = identitySdf<S>(gridFor(s, resolution));
        const double h = gridFor(s, resolution)->cellSize;
        double worst = 0;
        int n = 0;
        for (const auto& p : points) {
          const double a = shape.analytic(p);
          if (std::abs(a) > 2 * h || std::abs(a) > 0.05) continue;  // near the surface, away from the medial axis
          Vec g;
          sampleAt(sdf, p, &g);
          worst = std::max(worst, angleBetween(g, analyticGradient(p)));
          ++n;
        }
        REQUIRE(n > 50);
        INFO("resolution " << resolution << ": worst " << worst << " rad, tilt " << tilt << " rad");
        CHECK(worst < tilt + h / 0.15);  // the facets' tilt plus the turn of the surface across a cell (r >= 0.15)
      }
    }
  }
}

TEMPLATE_TEST_CASE("sampled field is 1-Lipschitz along axes and at most sqrt(3)-Lipschitz, gradients are unit",
                   "[meshsdf]", float, double) {
  using S = TestType;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> normal(0, 1);
  for (std::size_t s = 0; s < shapes().size(); ++s) {
    const auto& shape = shapes()[s];
    INFO(shape.name);
    const auto grid = gridFor(s, 32);
    const auto sdf = identitySdf<S>(grid);
    const double step = 0.3 * grid->cellSize;
    double worstAxis = 0, worstAny = 0;
    int count = 0;
    for (const auto& p : randomPoints(shape.mesh, 3000, 21)) {
      Vec dir(normal(rng), normal(rng), normal(rng));
      dir.normalize();
      Vec g;
      const double phi = sampleAt(sdf, p, &g);
      CHECK(std::abs(g.norm() - 1) < 1e-5);
      worstAny = std::max(worstAny, std::abs(sampleAt(sdf, p + step * dir) - phi) / step);
      const Vec axis = Vec::Unit(count++ % 3);
      worstAxis = std::max(worstAxis, std::abs(sampleAt(sdf, p + step * axis) - phi) / step);
    }
    INFO("largest slope: " << worstAny << " in any direction, " << worstAxis << " along an axis");
    CHECK(worstAxis <= 1 + 20 * kRounding<S> / step);
    CHECK(worstAny <= std::sqrt(3.0) + 20 * kRounding<S> / step);
  }
}

// --- Outside the grid ----------------------------------------------------------------------------------------

TEMPLATE_TEST_CASE("outside the grid the field grows, stays a lower bound, and joins the inside continuously",
                   "[meshsdf]", float, double) {
  using S = TestType;
  const auto& sphere = shapes()[0];
  DistanceGridOptions o;
  o.resolution = 32;  // no margin: one padding cell around the mesh's box
  const auto grid = buildDistanceGrid(sphere.mesh, o);
  const auto sdf = identitySdf<S>(grid);
  const Vec lo = grid->lower, hi = grid->upper(), centre = (lo + hi) / 2;
  auto boxDistance = [&](const Vec& x) { return (lo - x).cwiseMax(x - hi).cwiseMax(0.0).norm(); };
  std::mt19937_64 rng(13);
  std::normal_distribution<double> normal(0, 1);

  for (int ray = 0; ray < 200; ++ray) {
    Vec dir(normal(rng), normal(rng), normal(rng));
    dir.normalize();
    double previous = -1;
    for (double t = 0.4; t < 12; t *= 1.1) {
      const Vec x = centre + t * dir;
      Vec g;
      const double phi = sampleAt(sdf, x, &g);
      CHECK(phi > previous);  // grows outward along every ray
      previous = phi;
      if (boxDistance(x) == 0) continue;
      CHECK(phi > 0);
      CHECK(phi >= boxDistance(x) - kRounding<S>);
      // sqrt(e^2 + g^2) never exceeds the true distance (g itself is exact to interpolation error, far below
      // a thousandth of a cell out here where the sphere's field is smooth).
      CHECK(phi <= scenes::meshDistance(sphere.mesh, x) + 1e-3 * grid->cellSize + kRounding<S>);
      CHECK(g.dot(x - centre) > 0);  // the normal points away
    }
  }
  // Far away: at least the distance to the box's circumscribed sphere, at most the true distance (999.5 m).
  const Vec far(600, -800, 0);
  CHECK(sampleAt(sdf, far) >= 1000 - (hi - lo).norm() / 2 - 1e-3);
  CHECK(sampleAt(sdf, far) <= scenes::meshDistance(sphere.mesh, far) + 1e-3);

  // Continuous across the box: just inside and just outside a face, an edge or a corner.
  std::uniform_real_distribution<double> unit(0, 1);
  const double delta = 1e-3 * grid->cellSize;
  for (int i = 0; i < 600; ++i) {
    Vec onBox = (lo.array() + Eigen::Array3d(unit(rng), unit(rng), unit(rng)) * (hi - lo).array()).matrix();
    Vec outward = Vec::Zero();
    for (int a = 0; a < 3; ++a)
      if (a == i % 3 || (a < i % 3 && i % 4 == 0)) {  // one, two or three clamped axes
        outward[a] = unit(rng) < 0.5 ? -1 : 1;
        onBox[a] = outward[a] < 0 ? lo[a] : hi[a];
      }
    outward.normalize();
    const double in = sampleAt(sdf, onBox - delta * outward), out = sampleAt(sdf, onBox + delta * outward);
    CHECK(std::abs(out - in) <= 2 * delta + 2 * kRounding<S>);
  }
  // 1-Lipschitz outside (up to the boundary values' interpolation, smooth out here).
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    Vec a(normal(rng), normal(rng), normal(rng)), b(normal(rng), normal(rng), normal(rng));
    a = centre + (0.6 + 2 * unit(rng)) * a.normalized();
    b = a + 0.05 * b;
    if (boxDistance(a) == 0 || boxDistance(b) == 0) continue;
    worst = std::max(worst, std::abs(sampleAt(sdf, a) - sampleAt(sdf, b)) / (a - b).norm());
  }
  INFO("largest slope outside: " << worst);
  CHECK(worst <= 1 + 1e-3);
}

// --- Pose --------------------------------------------------------------------------------------------------

TEMPLATE_TEST_CASE("a posed grid matches the posed analytic field and the built-in box", "[meshsdf]", float, double) {
  using S = TestType;
  Pose pose;
  pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Vec(1, 2, -1).normalized()));
  pose.position = Vec(3.0, -2.0, 1.2);
  const Vec origin(2.5, -2.2, 0.7);  // the cloth's local origin
  std::mt19937_64 rng(17);

  SECTION("L block: world samples are local samples turned by the pose, within the analytic bound") {
    const auto& shape = shapes()[3];
    const auto grid = gridFor(3, 64);
    const auto posed = detail::compileSdf<S>(MeshShape{grid}, pose, origin);
    const auto local = identitySdf<S>(grid);
    for (const auto& p : randomPoints(shape.mesh, 1500, 19)) {
      Vec g, gl;
      const double phi = sampleAt(posed, pose.apply(p) - origin, &g);
      const double phiLocal = sampleAt(local, p, &gl);
      CHECK(std::abs(phi - phiLocal) <= 10 * kRounding<S>);
      CHECK((g - pose.rotation * gl).norm() <= (std::is_same_v<S, float> ? 1e-3 : 1e-9));
      CHECK(std::abs(phi - shape.analytic(p)) <= lipschitzBound(*grid, p) + 10 * kRounding<S>);
    }
  }

  SECTION("box mesh against Sdf<Box>: the same field near the faces, the same normal off the edges") {
    const Vec half(0.4, 0.3, 0.2);
    const auto grid = gridFor(1, 64);
    const double h = grid->cellSize;
    const auto mesh = detail::compileSdf<S>(MeshShape{grid}, pose, origin);
    const auto box = detail::compileSdf<S>(Box{half}, pose, origin);
    std::uniform_real_distribution<double> unit(-1, 1);
    for (int i = 0; i < 1500; ++i) {
      const Vec p(unit(rng) * 0.5, unit(rng) * 0.4, unit(rng) * 0.3);
      const Vec x = pose.apply(p) - origin;
      Vec gm, gb;
      const double phiMesh = sampleAt(mesh, x, &gm);
      Vec3<S> gbS;
      const double phiBox = double(box(x.cast<S>(), gbS));
      gb = gbS.template cast<double>();
      CHECK(std::abs(phiMesh - phiBox) <= lipschitzBound(*grid, p) + 10 * kRounding<S>);
      // Outside, over the middle of a face, both normals are that face's.
      const Vec q = p.cwiseAbs() - half;
      int over = -1;
      for (int a = 0; a < 3; ++a)
        if (q[a] > 0.1 * h && q[(a + 1) % 3] < -2 * h && q[(a + 2) % 3] < -2 * h) over = a;
      if (over >= 0) CHECK((gm - gb).norm() < (std::is_same_v<S, float> ? 1e-4 : 1e-9));
    }
  }
}

// --- OBJ files -----------------------------------------------------------------------------------------------

namespace {
struct TempDir {
  std::filesystem::path path = std::filesystem::temp_directory_path() / ("drape_meshsdf_" + std::to_string(::getpid()));
  TempDir() { std::filesystem::create_directories(path); }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::string file(const std::string& name, const std::string& text = "") const {
    const std::string p = (path / name).string();
    if (!text.empty()) std::ofstream(p) << text;
    return p;
  }
};
}  // namespace

TEST_CASE("OBJ files: a saved mesh loads back the same, quads are split, errors name the file", "[meshsdf]") {
  const TempDir dir;
  SECTION("round trip") {
    const TriangleMesh torus = makeTorus(0.4, 0.15, 24, 12);
    const std::string path = dir.file("torus.obj");
    saveObj(torus, path);
    const TriangleMesh back = loadObj(path);
    REQUIRE(back.vertexCount() == torus.vertexCount());
    REQUIRE(back.triangles == torus.triangles);
    double worst = 0;
    for (Index v = 0; v < torus.vertexCount(); ++v)
      worst = std::max(worst, (back.vertices[v] - torus.vertices[v]).norm());
    CHECK(worst <= 1e-15);  // 17 significant digits, read back in double
    CHECK_NOTHROW(validateClosedMesh(back));
  }
  SECTION("a hand-written box of quads, with normals, comments and an object name") {
    const std::string path =
        dir.file("box.obj",
                 "# unit box\no cube\n"
                 "v -1 -1 -1\nv 1 -1 -1\nv -1 1 -1\nv 1 1 -1\nv -1 -1 1\nv 1 -1 1\nv -1 1 1\nv 1 1 1\n"
                 "vn 0 0 1\n"
                 "f 1//1 3//1 4//1 2//1\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n");
    const TriangleMesh box = loadObj(path);
    CHECK(box.vertexCount() == 8);
    CHECK(box.triangleCount() == 12);
    const auto grid = buildDistanceGrid(box, DistanceGridOptions{16, 0, 0});
    const auto sdf = identitySdf<double>(grid);
    CHECK(sampleAt(sdf, Vec(0, 0, 0)) == Approx(-1).margin(1e-6));
    CHECK(sampleAt(sdf, Vec(1.1, 0.2, -0.3)) == Approx(0.1).margin(1e-6));
  }
  SECTION("errors") {
    const std::string missing = dir.file("missing.obj");
    CHECK_THROWS_WITH(loadObj(missing), Contains("cannot load OBJ file '" + missing + "'"));
    const std::string bad = dir.file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    CHECK_THROWS_WITH(loadObj(bad), Contains(bad));
    const std::string empty = dir.file("points.obj", "v 0 0 0\nv 1 0 0\n");
    CHECK_THROWS_WITH(loadObj(empty), Contains("'" + empty + "' has no faces"));
    const std::string open = dir.file("open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    CHECK_THROWS_WITH(buildDistanceGrid(loadObj(open)), Contains("at least 4 triangles"));
    CHECK_THROWS_WITH(saveObj(makeBoxMesh(Vec(1, 1, 1)), (dir.path / "no" / "such" / "dir.obj").string()),
                      Contains("dir.obj"));
    // A directory is named as one, not as a file without faces.
    CHECK_THROWS_WITH(loadObj(dir.path.string()), Contains("is a directory"));
    // A coordinate that is not a finite number is reported with its line (the parser would read it as 0).
    const std::string tetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    CHECK_NOTHROW(validateClosedMesh(loadObj(dir.file("tetra.obj", tetra))));
    const std::string nan = dir.file("nan.obj", "# a comment\nv 0 0 0\nv nan 0 0\n" + tetra.substr(16));
    CHECK_THROWS_WITH(loadObj(nan), Contains("line 3") && Contains("'nan' is not a finite number"));
    const std::string huge = dir.file("huge.obj", "v 0 0 0\nv 1 0 1e999\n" + tetra.substr(16));
    CHECK_THROWS_WITH(loadObj(huge), Contains("line 2") && Contains("'1e999'"));
    const std::string word = dir.file("word.obj", "v 0 0 0\nv 1 0 0\nv 0 1x 0\n" + tetra.substr(24));
    CHECK_THROWS_WITH(loadObj(word), Contains("line 3") && Contains("'1x'"));
    const std::string shortLine = dir.file("short.obj", "v 0 0\n" + tetra.substr(8));
    CHECK_THROWS_WITH(loadObj(shortLine), Contains("line 1") && Contains("coordinate 3 is missing"));
  }
}

}  // namespace mesh_sdf_tests
