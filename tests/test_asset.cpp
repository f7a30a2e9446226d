// Cloth assets: topology, constraint colouring and masses.
#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <memory>
#include <set>

namespace {

template <class S> void requireValidColouring(const drape::DistanceSet<S>& set, drape::Index vertexCount) {
  REQUIRE(set.colourOffsets.front() == 0);
  REQUIRE(set.colourOffsets.back() == set.size());
  for (drape::Index c = 0; c < set.colourCount(); ++c) {
    std::vector<char> seen(vertexCount, 0);
    for (drape::Index k = set.colourOffsets[c]; k < set.colourOffsets[c + 1]; ++k) {
      const auto [a, b] = set.pairs[k];
      REQUIRE(!seen[a]);  // no vertex twice in one colour
      REQUIRE(!seen[b]);
      seen[a] = seen[b] = 1;
    }
  }
}

}  // namespace

TEMPLATE_TEST_CASE("a grid asset has the expected topology and a valid colouring", "[asset]", float, double) {
  drape::SheetDesc g;
  g.nx = 7;
  g.ny = 5;
  g.spacing = 0.1;
  const auto a = drape::ClothAsset<TestType>::sheet(g);
  const int nx = 7, ny = 5;
  CHECK(a.vertexCount() == nx * ny);
  CHECK(a.faceCount() == 2 * (nx - 1) * (ny - 1));
  CHECK(a.stretch.size() == (nx - 1) * ny + nx * (ny - 1));
  CHECK(a.shear.size() == (nx - 1) * (ny - 1));
  CHECK(a.edges.size() == std::size_t(a.stretch.size() + a.shear.size()));
  // Every interior edge has a bend pair: edges - boundary edges.
  const int boundary = 2 * (nx - 1) + 2 * (ny - 1);
  CHECK(a.bendPairs.size() == a.edges.size() - boundary);
  CHECK(std::size_t(a.bending.size()) == a.bendPairs.size());
  requireValidColouring(a.stretch, a.vertexCount());
  requireValidColouring(a.shear, a.vertexCount());
  requireValidColouring(a.bending, a.vertexCount());
  CHECK(a.stretch.colourCount() <= 4);  // a grid's axis edges need 4 colours at most
  for (drape::Index k = 0; k < a.stretch.size(); ++k) CHECK(a.stretch.restLength[k] == Approx(0.1).epsilon(1e-6));
  for (drape::Index k = 0; k < a.shear.size(); ++k)
    CHECK(a.shear.restLength[k] == Approx(0.1 * std::sqrt(2.0)).epsilon(1e-6));
  // Adjacency is symmetric and matches the edges.
  for (drape::Index i = 0; i < a.vertexCount(); ++i)
    for (const drape::Index* j = a.vertexNeighbours.begin(i); j != a.vertexNeighbours.end(i); ++j) {
      const auto back = std::find(a.vertexNeighbours.begin(*j), a.vertexNeighbours.end(*j), i);
      CHECK(back != a.vertexNeighbours.end(*j));
    }
}

TEMPLATE_TEST_CASE("vertex masses come from the area density", "[asset]", float, double) {
  drape::SheetDesc g;
  g.nx = 11;
  g.ny = 6;
  g.spacing = 0.02;
  const auto a = drape::ClothAsset<TestType>::sheet(g);
  const auto s = drape::ClothState<TestType>::fromAsset(a, 0.25);
  double total = 0;
  for (auto w : s.invMass) total += 1.0 / double(w);
  CHECK(total == Approx(0.25 * 10 * 0.02 * 5 * 0.02).epsilon(1e-5));
}

TEMPLATE_TEST_CASE("a mesh asset colours every edge and finds bend pairs", "[asset]", float, double) {
  using V = drape::Vec3<TestType>;
  // A square fan: a centre vertex and four around it.
  std::vector<V> p{V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(-1, 0, 0), V(0, -1, 0)};
  std::vector<std::array<drape::Index, 3>> t{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1}};
  const auto a = drape::ClothAsset<TestType>::fromMesh(p, t);
  CHECK(a.edges.size() == 8);
  CHECK(a.stretch.size() == 8);
  CHECK(a.shear.size() == 0);
  CHECK(a.bendPairs.size() == 4);  // the four spokes are interior
  requireValidColouring(a.stretch, a.vertexCount());
  CHECK(a.stretch.colourCount() >= 4);  // the centre has degree 4
}

TEST_CASE("a float cloth placed 20 km from the origin keeps exact rest lengths and positions", "[asset]") {
  drape::SheetDesc g;
  g.nx = g.ny = 5;
  g.spacing = 0.02;
  g.placement.position = {1e4, -2e4, 5e3};
  const auto asset = std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::sheet(g));
  for (drape::Index k = 0; k < asset->stretch.size(); ++k) CHECK(asset->stretch.restLength[k] == Approx(0.02).epsilon(1e-6));
  drape::Solver<float> solver(asset);
  CHECK((solver.position(0) - Eigen::Vector3d(1e4 - 0.04, -2e4 - 0.04, 5e3)).norm() < 1e-6);
  // Moving it 2 km further keeps float's precision too: the local origin follows.
  std::vector<Eigen::Vector3d> moved(solver.vertexCount());
  for (drape::Index i = 0; i < solver.vertexCount(); ++i) moved[i] = solver.position(i) + Eigen::Vector3d(2000.001, 0, 0);
  solver.setPositions(moved);
  for (drape::Index i = 0; i < solver.vertexCount(); ++i) CHECK((solver.position(i) - moved[i]).norm() < 1e-6);
}
