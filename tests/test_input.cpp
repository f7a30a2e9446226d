// Bad input: every rejected input throws drape::Error naming the problem, before any state changes.
//
// Each rejected call runs with main.cpp's floating-point traps turned off (FpQuiet) and then checks that the
// rejection itself raised no invalid / divide-by-zero / overflow flag. So a check the library does not make,
// or makes by computing with the bad value (inf - inf, an overflowing cast), fails as a test instead of
// killing the whole run with SIGFPE.
#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <cfenv>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace {

using Catch::Matchers::Contains;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Floating-point traps off for a scope; raised() tells whether the scope raised invalid, divide-by-zero or
/// overflow. The traps main.cpp enabled are restored (and the flags cleared) on exit.
class FpQuiet {
 public:
  FpQuiet() {
#if defined(__GLIBC__)
    saved_ = fegetexcept();
    fedisableexcept(FE_ALL_EXCEPT);
#endif
    std::feclearexcept(FE_ALL_EXCEPT);
  }
  ~FpQuiet() {
    std::feclearexcept(FE_ALL_EXCEPT);
#if defined(__GLIBC__)
    feenableexcept(saved_);
#endif
  }
  FpQuiet(const FpQuiet&) = delete;
  FpQuiet& operator=(const FpQuiet&) = delete;
  bool raised() const { return std::fetestexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW) != 0; }

 private:
  int saved_ = 0;
};

}  // namespace

/// expr throws drape::Error whose what() contains `word` (case-insensitive), and rejecting it did no
/// floating-point arithmetic on the bad value. expr is evaluated twice (type, then message): the state
/// checks that follow each use show that neither evaluation changed anything.
#define CHECK_REJECTS(expr, word)                                                                   \
  do {                                                                                              \
    FpQuiet fpQuiet_;                                                                               \
    CHECK_THROWS_AS(expr, drape::Error);                                                            \
    CHECK_THROWS_WITH(expr, Contains(word, Catch::CaseSensitive::No));                              \
    INFO("rejecting `" #expr "` raised a floating-point exception (arithmetic on the bad value)");  \
    CHECK_FALSE(fpQuiet_.raised());                                                                 \
  } while (false)

/// The message of the drape::Error that expr throws also contains `text` (traps off, as above).
#define CHECK_MESSAGE_HAS(expr, text)                                 \
  do {                                                                \
    FpQuiet fpQuiet_;                                                 \
    CHECK_THROWS_WITH(expr, Contains(text));                          \
  } while (false)

/// expr throws drape::Error (any message) without raising a floating-point exception.
#define CHECK_REJECTS_ANY(expr)                                                                     \
  do {                                                                                              \
    FpQuiet fpQuiet_;                                                                               \
    CHECK_THROWS_AS(expr, drape::Error);                                                            \
    INFO("rejecting `" #expr "` raised a floating-point exception (arithmetic on the bad value)");  \
    CHECK_FALSE(fpQuiet_.raised());                                                                 \
  } while (false)

namespace {

template <class S> using Mesh = std::pair<std::vector<drape::Vec3<S>>, std::vector<std::array<drape::Index, 3>>>;

/// A unit square in two triangles: valid input that each fromMesh case spoils in one way.
template <class S> Mesh<S> unitSquare() {
  using V = drape::Vec3<S>;
  return {{V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0)}, {{{0, 1, 2}}, {{0, 2, 3}}}};
}

drape::SheetDesc smallSheetDesc() {
  drape::SheetDesc g;
  g.nx = 4;
  g.ny = 4;
  g.spacing = 0.1;
  g.placement.position = {0.3, -0.2, 1.0};
  return g;
}

template <class S> std::shared_ptr<const drape::ClothAsset<S>> smallGrid() {
  return std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(smallSheetDesc()));
}

/// Everything observable about a solver's cloth, pins and solid count, in world units.
struct Snapshot {
  std::vector<Eigen::Vector3d> position, velocity;
  std::vector<double> invMass;
  Eigen::Vector3d origin;
  std::vector<drape::Pin> pins;
};

template <class Solver> Snapshot snapshot(const Solver& s) {
  Snapshot snap;
  for (drape::Index i = 0; i < s.vertexCount(); ++i) {
    snap.position.push_back(s.position(i));
    snap.velocity.push_back(s.velocity(i));
    snap.invMass.push_back(double(s.state().invMass[i]));
  }
  snap.origin = s.state().origin;
  snap.pins = s.pins();
  return snap;
}

/// Exact comparison (== on doubles is quiet: a NaN that slipped in compares unequal without trapping).
void checkUnchanged(const Snapshot& before, const Snapshot& after) {
  REQUIRE(before.position.size() == after.position.size());
  int moved = 0, sped = 0, reweighed = 0;
  for (std::size_t i = 0; i < before.position.size(); ++i) {
    moved += !(before.position[i] == after.position[i]);
    sped += !(before.velocity[i] == after.velocity[i]);
    reweighed += !(before.invMass[i] == after.invMass[i]);
  }
  CHECK(moved == 0);
  CHECK(sped == 0);
  CHECK(reweighed == 0);
  CHECK(before.origin == after.origin);
  REQUIRE(before.pins.size() == after.pins.size());
  for (std::size_t k = 0; k < before.pins.size(); ++k) {
    CHECK(before.pins[k].vertex == after.pins[k].vertex);
    CHECK(before.pins[k].target == after.pins[k].target);
  }
}

bool sameSettings(const drape::Settings& a, const drape::Settings& b) {
  return a.subStepCount == b.subStepCount && a.iterationCount == b.iterationCount && a.gravity == b.gravity &&
         a.stretchCompliance == b.stretchCompliance && a.shearCompliance == b.shearCompliance &&
         a.bendingCompliance == b.bendingCompliance && a.pinCompliance == b.pinCompliance &&
         a.collisionMethod == b.collisionMethod && a.thickness == b.thickness &&
         a.normalDamping == b.normalDamping && a.pgdIterations == b.pgdIterations && a.culling == b.culling &&
         a.propagationWeight == b.propagationWeight && a.propagationRings == b.propagationRings &&
         a.airDamping == b.airDamping;
}

/// A valid non-default Settings, so "unchanged" is not confused with "reset to defaults".
drape::Settings customSettings() {
  drape::Settings s;
  s.subStepCount = 4;
  s.iterationCount = 2;
  s.gravity = {0.5, 0, -9};
  s.bendingCompliance = 2e-3;
  s.thickness = 0.004;
  s.normalDamping = 0.8;
  s.airDamping = 0.5;
  s.pgdIterations = 6;
  s.propagationWeight = 0.25;
  s.propagationRings = 2;
  return s;
}

struct BadSettings {
  const char* name;
  std::function<void(drape::Settings&)> spoil;
  const char* word;  ///< what the error message must contain
};

/// One entry per check in Settings::validate(), plus the non-finite variants.
std::vector<BadSettings> badSettingsList() {
  return {
      {"subStepCount 0", [](drape::Settings& s) { s.subStepCount = 0; }, "subStepCount"},
      {"subStepCount -1", [](drape::Settings& s) { s.subStepCount = -1; }, "subStepCount"},
      {"subStepCount 10001", [](drape::Settings& s) { s.subStepCount = 10001; }, "subStepCount"},
      {"iterationCount 0", [](drape::Settings& s) { s.iterationCount = 0; }, "iterationCount"},
      {"iterationCount 1001", [](drape::Settings& s) { s.iterationCount = 1001; }, "iterationCount"},
      {"NaN gravity", [](drape::Settings& s) { s.gravity.y() = kNaN; }, "gravity"},
      {"infinite gravity", [](drape::Settings& s) { s.gravity.z() = -kInf; }, "gravity"},
      {"gravity -1e300", [](drape::Settings& s) { s.gravity.z() = -1e300; }, "gravity"},
      {"gravity 2e6 sideways", [](drape::Settings& s) { s.gravity.x() = 2e6; }, "gravity"},
      {"negative stretchCompliance", [](drape::Settings& s) { s.stretchCompliance = -1e-6; }, "stretchCompliance"},
      {"NaN stretchCompliance", [](drape::Settings& s) { s.stretchCompliance = kNaN; }, "stretchCompliance"},
      {"negative shearCompliance", [](drape::Settings& s) { s.shearCompliance = -1; }, "shearCompliance"},
      {"infinite shearCompliance", [](drape::Settings& s) { s.shearCompliance = kInf; }, "shearCompliance"},
      {"negative bendingCompliance", [](drape::Settings& s) { s.bendingCompliance = -1e-3; }, "bendingCompliance"},
      {"NaN bendingCompliance", [](drape::Settings& s) { s.bendingCompliance = kNaN; }, "bendingCompliance"},
      {"negative pinCompliance", [](drape::Settings& s) { s.pinCompliance = -1; }, "pinCompliance"},
      {"pinCompliance above 1e6", [](drape::Settings& s) { s.pinCompliance = 2e6; }, "pinCompliance"},
      {"unknown collisionMethod", [](drape::Settings& s) { s.collisionMethod = drape::CollisionMethod(7); },
       "collisionMethod"},
      {"thickness 0", [](drape::Settings& s) { s.thickness = 0; }, "thickness"},
      {"negative thickness", [](drape::Settings& s) { s.thickness = -0.01; }, "thickness"},
      {"NaN thickness", [](drape::Settings& s) { s.thickness = kNaN; }, "thickness"},
      {"thickness 2 m", [](drape::Settings& s) { s.thickness = 2; }, "thickness"},
      {"normalDamping 2", [](drape::Settings& s) { s.normalDamping = 2; }, "normalDamping"},
      {"normalDamping -0.1", [](drape::Settings& s) { s.normalDamping = -0.1; }, "normalDamping"},
      {"NaN normalDamping", [](drape::Settings& s) { s.normalDamping = kNaN; }, "normalDamping"},
      {"airDamping -1", [](drape::Settings& s) { s.airDamping = -1; }, "airDamping"},
      {"NaN airDamping", [](drape::Settings& s) { s.airDamping = kNaN; }, "airDamping"},
      {"airDamping 2e4", [](drape::Settings& s) { s.airDamping = 2e4; }, "airDamping"},
      {"pgdIterations 0", [](drape::Settings& s) { s.pgdIterations = 0; }, "pgdIterations"},
      {"pgdIterations 1001", [](drape::Settings& s) { s.pgdIterations = 1001; }, "pgdIterations"},
      {"propagationWeight -1", [](drape::Settings& s) { s.propagationWeight = -1; }, "propagationWeight"},
      {"propagationWeight 1.5", [](drape::Settings& s) { s.propagationWeight = 1.5; }, "propagationWeight"},
      {"NaN propagationWeight", [](drape::Settings& s) { s.propagationWeight = kNaN; }, "propagationWeight"},
      {"propagationRings 100", [](drape::Settings& s) { s.propagationRings = 100; }, "propagationRings"},
      {"propagationRings -1", [](drape::Settings& s) { s.propagationRings = -1; }, "propagationRings"},
  };
}

}  // namespace

// ------------------------------------------------------------------------------------------------------------
// ClothAsset::fromMesh

TEMPLATE_TEST_CASE("fromMesh rejects non-finite positions", "[input]", float, double) {
  using S = TestType;
  using Asset = drape::ClothAsset<S>;
  auto [p, t] = unitSquare<S>();
  REQUIRE_NOTHROW(Asset::fromMesh(p, t));

  SECTION("NaN") {
    p[2].y() = std::numeric_limits<S>::quiet_NaN();
    CHECK_REJECTS(Asset::fromMesh(p, t), "non-finite");
    CHECK_MESSAGE_HAS(Asset::fromMesh(p, t), "vertex 2");
  }
  SECTION("+inf") {
    p[1].x() = std::numeric_limits<S>::infinity();
    CHECK_REJECTS(Asset::fromMesh(p, t), "non-finite");
    CHECK_MESSAGE_HAS(Asset::fromMesh(p, t), "vertex 1");
  }
  SECTION("-inf") {
    p[3].z() = -std::numeric_limits<S>::infinity();
    CHECK_REJECTS(Asset::fromMesh(p, t), "non-finite");
  }
  SECTION("NaN in a vertex no triangle uses") {
    p.push_back(drape::Vec3<S>(std::numeric_limits<S>::quiet_NaN(), 0, 0));
    CHECK_REJECTS(Asset::fromMesh(p, t), "non-finite");
  }
}

TEMPLATE_TEST_CASE("fromMesh rejects out-of-range and negative indices", "[input]", float, double) {
  using S = TestType;
  using Asset = drape::ClothAsset<S>;
  auto [p, t] = unitSquare<S>();
  for (drape::Index bad : {drape::Index(-1), drape::Index(4), drape::Index(1000),
                           std::numeric_limits<drape::Index>::max(), std::numeric_limits<drape::Index>::min()}) {
    for (int k = 0; k < 3; ++k) {
      auto tt = t;
      tt[1][k] = bad;
      CAPTURE(bad, k);
      CHECK_REJECTS(Asset::fromMesh(p, tt), "out of range");
      CHECK_MESSAGE_HAS(Asset::fromMesh(p, tt), "triangle 1");
    }
  }
}

TEMPLATE_TEST_CASE("fromMesh rejects degenerate triangles", "[input]", float, double) {
  using S = TestType;
  using V = drape::Vec3<S>;
  using Asset = drape::ClothAsset<S>;
  auto [p, t] = unitSquare<S>();

  SECTION("a repeated index") {
    for (std::array<drape::Index, 3> bad : {std::array<drape::Index, 3>{0, 0, 2}, {0, 2, 2}, {2, 1, 2}, {3, 3, 3}}) {
      auto tt = t;
      tt[0] = bad;
      CAPTURE(bad[0], bad[1], bad[2]);
      CHECK_REJECTS(Asset::fromMesh(p, tt), "degenerate");
    }
  }
  SECTION("three collinear vertices (zero area)") {
    p.push_back(V(2, 0, 0));  // on the line through vertices 0 and 1
    t.push_back({0, 1, 4});
    CHECK_REJECTS(Asset::fromMesh(p, t), "degenerate");
    CHECK_MESSAGE_HAS(Asset::fromMesh(p, t), "triangle 2");
  }
  SECTION("two coincident vertices with distinct indices") {
    p.push_back(V(1, 1, 0));  // the same point as vertex 2
    t.push_back({1, 2, 4});
    CHECK_REJECTS(Asset::fromMesh(p, t), "degenerate");
  }
  SECTION("all three vertices at one point") {
    p = {V(0.5, 0.5, 0), V(0.5, 0.5, 0), V(0.5, 0.5, 0)};
    t = {{0, 1, 2}};
    CHECK_REJECTS(Asset::fromMesh(p, t), "degenerate");
  }
  SECTION("a sliver whose height is far below its length") {
    p.push_back(V(0.5, S(1e-9), 0));
    t.push_back({0, 1, 4});
    CHECK_REJECTS(Asset::fromMesh(p, t), "degenerate");
  }
}

TEMPLATE_TEST_CASE("fromMesh rejects an edge shared by three faces", "[input]", float, double) {
  using S = TestType;
  using V = drape::Vec3<S>;
  using Asset = drape::ClothAsset<S>;
  // A fan of three fins around the edge (0, 1): each face is fine on its own.
  std::vector<V> p{V(0, 0, 0), V(1, 0, 0), V(0.5, 1, 0), V(0.5, -1, 0), V(0.5, 0, 1)};
  std::vector<std::array<drape::Index, 3>> t{{0, 1, 2}, {1, 0, 3}};
  REQUIRE_NOTHROW(Asset::fromMesh(p, t));
  t.push_back({0, 1, 4});
  CHECK_REJECTS(Asset::fromMesh(p, t), "manifold");
  CHECK_THROWS_WITH(Asset::fromMesh(p, t), Contains("(0, 1)") && Contains("3 faces"));

  SECTION("also without bending constraints") {
    drape::AssetOptions noBending;
    noBending.bending = false;
    CHECK_REJECTS(Asset::fromMesh(p, t, noBending), "manifold");
  }
}

TEMPLATE_TEST_CASE("fromMesh rejects a face given twice, in either winding", "[input]", float, double) {
  using S = TestType;
  using Asset = drape::ClothAsset<S>;
  auto [p, t] = unitSquare<S>();
  SECTION("the same face twice") {
    t.push_back({1, 2, 0});  // triangle 0 again, its corners rotated
    CHECK_THROWS_WITH(Asset::fromMesh(p, t), Contains("triangle 2 repeats triangle 0"));
  }
  SECTION("the same face reversed") {
    t.insert(t.begin(), {2, 1, 0});  // triangle 1 (was 0) wound the other way
    CHECK_THROWS_WITH(Asset::fromMesh(p, t), Contains("repeats") && Contains("triangle 0") && Contains("triangle 1"));
  }
}

TEMPLATE_TEST_CASE("fromMesh rejects empty and too-small input", "[input]", float, double) {
  using S = TestType;
  using Asset = drape::ClothAsset<S>;
  auto [p, t] = unitSquare<S>();
  const std::vector<drape::Vec3<S>> noPositions;
  const std::vector<std::array<drape::Index, 3>> noTriangles;
  CHECK_REJECTS(Asset::fromMesh(noPositions, noTriangles), "at least 3 vertices");
  CHECK_REJECTS(Asset::fromMesh(p, noTriangles), "at least 3 vertices and 1 triangle");
  CHECK_REJECTS(Asset::fromMesh(noPositions, t), "at least 3 vertices");
  const std::vector<drape::Vec3<S>> two(p.begin(), p.begin() + 2);
  const std::vector<std::array<drape::Index, 3>> tri{{0, 1, 1}};
  CHECK_REJECTS(Asset::fromMesh(two, tri), "at least 3 vertices");
}

// A vertex that no triangle uses passes fromMesh (the documented checks do not cover it) but has no mass: the
// solver must refuse it rather than divide by zero.
TEMPLATE_TEST_CASE("a solver rejects a mesh vertex that belongs to no face", "[input]", float, double) {
  using S = TestType;
  auto [p, t] = unitSquare<S>();
  p.push_back(drape::Vec3<S>(5, 5, 5));
  auto asset = std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::fromMesh(p, t));
  CHECK_REJECTS(drape::Solver<S>(asset), "vertex 4");
  CHECK_MESSAGE_HAS(drape::Solver<S>(asset), "no face");
}

// ------------------------------------------------------------------------------------------------------------
// ClothAsset::grid

TEMPLATE_TEST_CASE("grid rejects too few vertices", "[input]", float, double) {
  using Asset = drape::ClothAsset<TestType>;
  REQUIRE_NOTHROW(Asset::sheet(smallSheetDesc()));
  for (drape::Index n : {1, 0, -3}) {
    CAPTURE(n);
    auto g = smallSheetDesc();
    g.nx = n;
    CHECK_REJECTS(Asset::sheet(g), "nx >= 2");
    g = smallSheetDesc();
    g.ny = n;
    CHECK_REJECTS(Asset::sheet(g), "ny >= 2");
  }
  auto huge = smallSheetDesc();
  huge.nx = 100000;
  huge.ny = 100000;
  CHECK_REJECTS(Asset::sheet(huge), "too large");
}

TEMPLATE_TEST_CASE("grid rejects a bad spacing", "[input]", float, double) {
  using Asset = drape::ClothAsset<TestType>;
  for (double spacing : {0.0, -0.0, -0.1, kNaN, kInf, -kInf}) {
    CAPTURE(spacing);
    auto g = smallSheetDesc();
    g.spacing = spacing;
    CHECK_REJECTS(Asset::sheet(g), "spacing");
  }
}

TEMPLATE_TEST_CASE("grid rejects a bad placement", "[input]", float, double) {
  using Asset = drape::ClothAsset<TestType>;
  SECTION("non-unit quaternion") {
    auto g = smallSheetDesc();
    g.placement.rotation = Eigen::Quaterniond(2, 0, 0, 0);
    CHECK_REJECTS(Asset::sheet(g), "unit quaternion");
    g.placement.rotation = Eigen::Quaterniond(0.5, 0.5, 0.5, 0.4);
    CHECK_REJECTS(Asset::sheet(g), "unit quaternion");
  }
  SECTION("zero quaternion") {
    auto g = smallSheetDesc();
    g.placement.rotation = Eigen::Quaterniond(0, 0, 0, 0);
    CHECK_REJECTS(Asset::sheet(g), "unit quaternion");
  }
  SECTION("NaN quaternion") {
    auto g = smallSheetDesc();
    g.placement.rotation = Eigen::Quaterniond(kNaN, 0, 0, 0);
    CHECK_REJECTS(Asset::sheet(g), "finite");
  }
  SECTION("infinite quaternion") {
    auto g = smallSheetDesc();
    g.placement.rotation = Eigen::Quaterniond(1, kInf, 0, 0);
    CHECK_REJECTS(Asset::sheet(g), "finite");
  }
  SECTION("NaN position") {
    auto g = smallSheetDesc();
    g.placement.position.x() = kNaN;
    CHECK_REJECTS(Asset::sheet(g), "finite");
  }
  SECTION("infinite position") {
    auto g = smallSheetDesc();
    g.placement.position.z() = kInf;
    CHECK_REJECTS(Asset::sheet(g), "finite");
  }
}

// ------------------------------------------------------------------------------------------------------------
// Solver construction

TEMPLATE_TEST_CASE("a solver rejects a null asset", "[input]", float, double) {
  using S = TestType;
  const std::shared_ptr<const drape::ClothAsset<S>> none;
  CHECK_REJECTS(drape::Solver<S>(none), "null");
}

TEMPLATE_TEST_CASE("a solver rejects a bad area density", "[input]", float, double) {
  using S = TestType;
  const auto asset = smallGrid<S>();
  REQUIRE_NOTHROW(drape::Solver<S>(asset, drape::Settings{}, 0.2));
  for (double density : {0.0, -0.0, -0.1, kNaN, kInf, -kInf}) {
    CAPTURE(density);
    CHECK_REJECTS(drape::Solver<S>(asset, drape::Settings{}, density), "areaDensity");
  }
}

TEMPLATE_TEST_CASE("a solver rejects invalid settings at construction", "[input]", float, double) {
  using S = TestType;
  const auto asset = smallGrid<S>();
  REQUIRE_NOTHROW(drape::Solver<S>(asset, customSettings()));
  for (const auto& bad : badSettingsList()) {
    INFO(bad.name);
    drape::Settings s = customSettings();
    bad.spoil(s);
    CHECK_REJECTS(s.validate(), bad.word);
    CHECK_REJECTS(drape::Solver<S>(asset, s), bad.word);
  }
}

// ------------------------------------------------------------------------------------------------------------
// Solver methods

TEMPLATE_TEST_CASE("setSettings rejects invalid settings and keeps the old ones", "[input]", float, double) {
  using S = TestType;
  drape::Solver<S> solver(smallGrid<S>(), customSettings());
  for (const auto& bad : badSettingsList()) {
    INFO(bad.name);
    drape::Settings s = customSettings();
    s.culling = false;  // a valid change alongside the bad one must not be applied either
    bad.spoil(s);
    CHECK_REJECTS(solver.setSettings(s), bad.word);
    CHECK(sameSettings(solver.settings(), customSettings()));
  }
}

TEMPLATE_TEST_CASE("setPositions rejects a wrong count or a non-finite value and changes nothing", "[input]",
                   float, double) {
  using S = TestType;
  drape::Solver<S> solver(smallGrid<S>());
  const drape::Index n = solver.vertexCount();
  // Valid new positions, so "unchanged" is not confused with "set to the same values".
  std::vector<Eigen::Vector3d> moved(n);
  for (drape::Index i = 0; i < n; ++i) moved[i] = solver.position(i) + Eigen::Vector3d(0.01 * i, 0.02, -0.03);
  const Snapshot before = snapshot(solver);

  SECTION("too few") {
    moved.pop_back();
    CHECK_REJECTS(solver.setPositions(moved), "setPositions got 15 positions for 16 vertices");
  }
  SECTION("too many") {
    moved.push_back(Eigen::Vector3d::Zero());
    CHECK_REJECTS(solver.setPositions(moved), "17 positions");
  }
  SECTION("none") {
    CHECK_REJECTS(solver.setPositions({}), "0 positions");
  }
  SECTION("NaN in the last vertex") {
    moved.back().y() = kNaN;
    CHECK_REJECTS(solver.setPositions(moved), "not finite");
    CHECK_MESSAGE_HAS(solver.setPositions(moved), "vertex 15");
  }
  SECTION("inf in a middle vertex") {
    moved[7].x() = kInf;
    CHECK_REJECTS(solver.setPositions(moved), "not finite");
  }
  SECTION("-inf in the first vertex") {
    moved[0].z() = -kInf;
    CHECK_REJECTS(solver.setPositions(moved), "not finite");
  }
  checkUnchanged(before, snapshot(solver));
}

TEMPLATE_TEST_CASE("setVelocities rejects a wrong count or a non-finite value and changes nothing", "[input]",
                   float, double) {
  using S = TestType;
  drape::Solver<S> solver(smallGrid<S>());
  const drape::Index n = solver.vertexCount();
  std::vector<Eigen::Vector3d> start(n), fresh(n);
  for (drape::Index i = 0; i < n; ++i) {
    start[i] = Eigen::Vector3d(0.1, -0.2, 0.01 * i);
    fresh[i] = Eigen::Vector3d(-1, 2, 3);
  }
  solver.setVelocities(start);
  const Snapshot before = snapshot(solver);

  SECTION("too few") {
    fresh.pop_back();
    CHECK_REJECTS(solver.setVelocities(fresh), "setVelocities got 15 velocities for 16 vertices");
  }
  SECTION("too many") {
    fresh.push_back(Eigen::Vector3d::Zero());
    CHECK_REJECTS(solver.setVelocities(fresh), "17 velocities");
  }
  SECTION("NaN in the last vertex") {
    fresh.back().x() = kNaN;
    CHECK_REJECTS(solver.setVelocities(fresh), "not finite");
    CHECK_MESSAGE_HAS(solver.setVelocities(fresh), "vertex 15");
  }
  SECTION("inf in a middle vertex") {
    fresh[5].z() = kInf;
    CHECK_REJECTS(solver.setVelocities(fresh), "not finite");
  }
  checkUnchanged(before, snapshot(solver));
}

TEMPLATE_TEST_CASE("setInverseMass rejects negative, non-finite or out-of-range input and changes nothing",
                   "[input]", float, double) {
  using S = TestType;
  drape::Solver<S> solver(smallGrid<S>());
  std::vector<Eigen::Vector3d> v(solver.vertexCount(), Eigen::Vector3d(0.3, 0, -0.1));
  solver.setVelocities(v);  // pinning zeroes a velocity: a rejected call must not
  const Snapshot before = snapshot(solver);

  for (double bad : {-1.0, -1e-12, -5.0, kNaN, kInf, -kInf}) {
    CAPTURE(bad);
    CHECK_REJECTS(solver.setInverseMass(3, bad), "inverse mass");
  }
  for (drape::Index i : {drape::Index(-1), drape::Index(16), std::numeric_limits<drape::Index>::max(),
                         std::numeric_limits<drape::Index>::min()}) {
    CAPTURE(i);
    CHECK_REJECTS(solver.setInverseMass(i, 1.0), "out of range");
    CHECK_REJECTS(solver.setInverseMass(i, 0.0), "out of range");
    CHECK_REJECTS(solver.setInverseMass(i, -1.0), "vertex index");
    CHECK_REJECTS(solver.pin(i), "out of range");
  }
  checkUnchanged(before, snapshot(solver));
}

TEMPLATE_TEST_CASE("attach and setPinTarget reject bad vertices, pins and targets", "[input]", float, double) {
  using S = TestType;
  drape::Solver<S> solver(smallGrid<S>());
  const Eigen::Vector3d target(0.1, 0.2, 1.5);
  REQUIRE(solver.attach(0, target) == 0);
  const Snapshot before = snapshot(solver);

  SECTION("attach: vertex out of range") {
    for (drape::Index i : {drape::Index(-1), drape::Index(16), std::numeric_limits<drape::Index>::max()}) {
      CAPTURE(i);
      CHECK_REJECTS(solver.attach(i, target), "out of range");
    }
  }
  SECTION("attach: non-finite target") {
    CHECK_REJECTS(solver.attach(5, Eigen::Vector3d(kNaN, 0, 0)), "not finite");
    CHECK_REJECTS(solver.attach(5, Eigen::Vector3d(0, kInf, 0)), "not finite");
    CHECK_REJECTS(solver.attach(5, Eigen::Vector3d(0, 0, -kInf)), "not finite");
  }
  SECTION("setPinTarget: pin index out of range") {
    for (drape::Index k : {drape::Index(-1), drape::Index(1), drape::Index(100)}) {
      CAPTURE(k);
      CHECK_REJECTS(solver.setPinTarget(k, target), "out of range");
    }
  }
  SECTION("setPinTarget: non-finite target") {
    CHECK_REJECTS(solver.setPinTarget(0, Eigen::Vector3d(kNaN, 0, 0)), "not finite");
    CHECK_REJECTS(solver.setPinTarget(0, Eigen::Vector3d(0, kInf, 0)), "not finite");
  }
  checkUnchanged(before, snapshot(solver));
  REQUIRE(solver.pins().size() == 1);
  CHECK(solver.pins()[0].target == target);
}

TEMPLATE_TEST_CASE("addSolid rejects bad shapes, poses, velocities and friction, and adds nothing", "[input]",
                   float, double) {
  using S = TestType;
  using drape::Box;
  using drape::Capsule;
  using drape::Plane;
  using drape::Solid;
  using drape::Sphere;
  drape::Settings settings;
  settings.subStepCount = 4;
  drape::Solver<S> solver(smallGrid<S>(), settings);
  drape::Solver<S> reference(smallGrid<S>(), settings);

  // A reasonable solid of each shape touching the cloth (at z = 1), each spoiled in one way per check.
  Solid<Plane> plane;
  plane.pose.position = {0, 0, 0.998};
  Solid<Sphere> sphere;
  sphere.shape.radius = 0.2;
  sphere.pose.position = {0.3, -0.2, 0.9};
  Solid<Box> box;
  box.shape.halfExtents = {0.2, 0.3, 0.1};
  box.pose.position = {0.3, -0.2, 0.95};
  Solid<Capsule> capsule;
  capsule.shape.radius = 0.1;
  capsule.shape.halfHeight = 0.2;
  capsule.pose.position = {0.3, -0.2, 0.95};
  capsule.pose.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX());

  // Applies `spoil` to a copy of `good`, checks addSolid rejects it with `word` and that nothing was added.
  auto rejects = [&](const auto& good, auto spoil, const char* word) {
    auto bad = good;
    spoil(bad);
    using Shape = std::decay_t<decltype(bad.shape)>;
    CHECK_REJECTS(solver.addSolid(bad), word);
    CHECK_REJECTS(solver.template solid<Shape>(0), "out of range");
  };

  SECTION("sphere radius") {
    rejects(sphere, [](auto& s) { s.shape.radius = 0; }, "sphere radius");
    rejects(sphere, [](auto& s) { s.shape.radius = -0.2; }, "sphere radius");
    rejects(sphere, [](auto& s) { s.shape.radius = kNaN; }, "sphere radius");
    rejects(sphere, [](auto& s) { s.shape.radius = kInf; }, "sphere radius");
    rejects(sphere, [](auto& s) { s.shape.radius = 1e300; }, "sphere radius");
  }
  SECTION("box half extents") {
    rejects(box, [](auto& s) { s.shape.halfExtents.y() = 0; }, "box half extents");
    rejects(box, [](auto& s) { s.shape.halfExtents.z() = -0.1; }, "box half extents");
    rejects(box, [](auto& s) { s.shape.halfExtents.x() = kNaN; }, "box half extents");
    rejects(box, [](auto& s) { s.shape.halfExtents.x() = kInf; }, "box half extents");
    rejects(box, [](auto& s) { s.shape.halfExtents.z() = 2e5; }, "box half extents");
  }
  SECTION("capsule radius and half height") {
    rejects(capsule, [](auto& s) { s.shape.radius = -0.1; }, "capsule radius");
    rejects(capsule, [](auto& s) { s.shape.radius = 0; }, "capsule radius");
    rejects(capsule, [](auto& s) { s.shape.radius = kNaN; }, "capsule radius");
    rejects(capsule, [](auto& s) { s.shape.halfHeight = -0.2; }, "halfHeight");
    rejects(capsule, [](auto& s) { s.shape.halfHeight = kNaN; }, "halfHeight");
    rejects(capsule, [](auto& s) { s.shape.radius = 1e300; }, "capsule radius");
    rejects(capsule, [](auto& s) { s.shape.halfHeight = 1e6; }, "halfHeight");
  }
  SECTION("pose") {
    rejects(sphere, [](auto& s) { s.pose.rotation = Eigen::Quaterniond(2, 0, 0, 0); }, "unit quaternion");
    rejects(plane, [](auto& s) { s.pose.rotation = Eigen::Quaterniond(0.9, 0.1, 0, 0); }, "unit quaternion");
    rejects(box, [](auto& s) { s.pose.rotation = Eigen::Quaterniond(0, 0, 0, 0); }, "unit quaternion");
    rejects(capsule, [](auto& s) { s.pose.rotation = Eigen::Quaterniond(kNaN, 0, 0, 0); }, "pose");
    rejects(capsule, [](auto& s) { s.pose.rotation = Eigen::Quaterniond(1, 0, kInf, 0); }, "pose");
    rejects(sphere, [](auto& s) { s.pose.position.x() = kNaN; }, "pose");
    rejects(plane, [](auto& s) { s.pose.position.z() = -kInf; }, "pose");
  }
  SECTION("velocities") {
    auto kinematic = [](auto s) {
      s.motion = drape::Motion::Kinematic;
      return s;
    };
    rejects(kinematic(sphere), [](auto& s) { s.linearVelocity.x() = kNaN; }, "velocities must be finite");
    rejects(kinematic(box), [](auto& s) { s.angularVelocity.z() = kNaN; }, "velocities must be finite");
    rejects(kinematic(capsule), [](auto& s) { s.linearVelocity.y() = kInf; }, "velocities must be finite");
    rejects(kinematic(plane), [](auto& s) { s.angularVelocity.x() = -kInf; }, "velocities must be finite");
  }
  SECTION("a static solid with a velocity") {
    rejects(sphere, [](auto& s) { s.linearVelocity = {0, 0, 0.1}; }, "static solid must have zero velocity");
    rejects(box, [](auto& s) { s.angularVelocity = {0, 1e-9, 0}; }, "static solid must have zero velocity");
    rejects(plane, [](auto& s) { s.linearVelocity = {1, 0, 0}; }, "static solid must have zero velocity");
  }
  SECTION("friction") {
    rejects(sphere, [](auto& s) { s.staticFriction = -0.1; }, "staticFriction");
    rejects(box, [](auto& s) { s.dynamicFriction = -0.1; }, "dynamicFriction");
    rejects(capsule, [](auto& s) { s.staticFriction = kNaN; }, "staticFriction");
    rejects(plane, [](auto& s) { s.dynamicFriction = kInf; }, "dynamicFriction");
  }

  // Nothing was added: the first valid solid of each type gets index 0, and the solvers step alike.
  CHECK(solver.addSolid(sphere) == 0);
  CHECK(reference.addSolid(sphere) == 0);
  {
    FpQuiet quiet;  // if a bad solid slipped in, a NaN shows below as a failed comparison, not a SIGFPE
    solver.step(1.0 / 60);
    reference.step(1.0 / 60);
    CHECK_FALSE(quiet.raised());
  }
  checkUnchanged(snapshot(reference), snapshot(solver));
  CHECK(solver.stats().vertexContacts == reference.stats().vertexContacts);
}

// The limits are where the state stays finite: the strongest accepted gravity over the longest accepted step,
// and the cloth inside the largest accepted sphere, pushed out across it in one step.
TEMPLATE_TEST_CASE("at the largest accepted gravity and sphere a step leaves a finite state", "[input]", float,
                   double) {
  using S = TestType;
  auto finite = [](const auto& solver) {
    for (drape::Index i = 0; i < solver.vertexCount(); ++i)
      if (!solver.position(i).allFinite() || !solver.velocity(i).allFinite()) return false;
    return true;
  };
  SECTION("gravity 1e6 m/s^2 in every component, a 10 s step") {
    drape::Settings settings;
    settings.gravity = Eigen::Vector3d::Constant(-drape::limits::kMaxAcceleration);
    drape::Solver<S> solver(smallGrid<S>(), settings);
    drape::Solid<drape::Plane> floor;
    solver.addSolid(floor);
    solver.step(drape::limits::kMaxStep);
    CHECK(finite(solver));
  }
  SECTION("a sphere of radius 1e5 m around the cloth") {
    drape::Solver<S> solver(smallGrid<S>());
    drape::Solid<drape::Sphere> ball;
    ball.shape.radius = drape::limits::kMaxShapeSize;
    ball.pose.position = {0.1, 0, 0};
    solver.addSolid(ball);
    solver.step(1.0 / 60);
    CHECK(finite(solver));
    CHECK((solver.position(0) - Eigen::Vector3d(0.1, 0, 0)).norm() >= 0.99 * drape::limits::kMaxShapeSize);
  }
}

TEMPLATE_TEST_CASE("setSolid rejects a bad solid and keeps the old one", "[input]", float, double) {
  using S = TestType;
  drape::Solver<S> solver(smallGrid<S>());
  drape::Solid<drape::Sphere> sphere;
  sphere.shape.radius = 0.2;
  REQUIRE(solver.addSolid(sphere) == 0);
  auto bad = sphere;
  bad.shape.radius = -1;
  CHECK_REJECTS(solver.setSolid(0, bad), "sphere radius");
  bad = sphere;
  bad.linearVelocity.x() = 1;  // still static
  CHECK_REJECTS(solver.setSolid(0, bad), "static solid");
  CHECK_REJECTS(solver.setSolid(1, sphere), "out of range");
  CHECK(solver.template solid<drape::Sphere>(0).shape.radius == 0.2);
  CHECK(solver.template solid<drape::Sphere>(0).linearVelocity.isZero(0));
}

TEMPLATE_TEST_CASE("step rejects a bad dt before changing anything", "[input]", float, double) {
  using S = TestType;
  drape::Solver<S> solver(smallGrid<S>());
  // Moved 2 m away from the local origin, so a step that started before its check would rebase at once.
  const drape::Index n = solver.vertexCount();
  std::vector<Eigen::Vector3d> x(n), v(n, Eigen::Vector3d(0.5, 0, 0.25));
  for (drape::Index i = 0; i < n; ++i) x[i] = solver.position(i) + Eigen::Vector3d(2, 0, 0);
  solver.setPositions(x);
  solver.setVelocities(v);
  solver.attach(0, x[0]);
  solver.setInverseMass(0, 0);
  const Snapshot before = snapshot(solver);
  const auto rawBefore = solver.state().x;

  for (double dt : {0.0, -0.0, -1.0 / 60, kNaN, kInf, -kInf, 10.5}) {
    CAPTURE(dt);
    CHECK_REJECTS(solver.step(dt), "dt");
    int calls = 0;
    CHECK_REJECTS(solver.step(dt, [&](const auto&) { ++calls; }), "dt");
    CHECK(calls == 0);
  }
  checkUnchanged(before, snapshot(solver));
  CHECK(solver.state().x == rawBefore);
}

// ------------------------------------------------------------------------------------------------------------
// Values that pass "finite" but that the solver cannot represent or compute with: each must be rejected with a
// drape::Error rather than end in inf or NaN (a SIGFPE under main.cpp's traps).

TEMPLATE_TEST_CASE("step rejects a dt so small that the substep squared underflows", "[input]", float, double) {
  using S = TestType;
  drape::Solver<S> solver(smallGrid<S>());
  const Snapshot before = snapshot(solver);
  // dt in (0, 10] as documented, but h = dt / subStepCount rounds to 0 (or h * h does) in S: the XPBD
  // compliance / (h * h) is then 0 / 0 and 1 / h divides by zero.
  const double tiny = double(std::numeric_limits<S>::min());
  CHECK_REJECTS_ANY(solver.step(tiny));
  checkUnchanged(before, snapshot(solver));
}

TEST_CASE("a float solver rejects finite doubles that float cannot hold", "[input]") {
  using S = float;
  const double huge = 1e300;  // finite as a double, inf once cast to float
  drape::Solver<S> solver(smallGrid<S>());
  const Snapshot before = snapshot(solver);

  SECTION("setPositions") {
    std::vector<Eigen::Vector3d> x(solver.vertexCount(), Eigen::Vector3d(0, 0, 1));
    x[3].x() = huge;
    CHECK_REJECTS_ANY(solver.setPositions(x));
  }
  SECTION("setVelocities") {
    std::vector<Eigen::Vector3d> v(solver.vertexCount(), Eigen::Vector3d::Zero());
    v[3].x() = huge;
    CHECK_REJECTS_ANY(solver.setVelocities(v));
  }
  SECTION("setInverseMass") { CHECK_REJECTS_ANY(solver.setInverseMass(3, huge)); }
  SECTION("grid spacing") {
    auto g = smallSheetDesc();
    g.spacing = huge;
    CHECK_REJECTS_ANY(drape::ClothAsset<S>::sheet(g));
  }
  SECTION("area density so small that 1 / mass overflows") {
    CHECK_REJECTS_ANY(drape::Solver<S>(smallGrid<S>(), drape::Settings{}, 1e-300));
  }
  SECTION("area density so large that the inverse mass rounds to 0 (silently pinning every vertex)") {
    CHECK_REJECTS_ANY(drape::Solver<S>(smallGrid<S>(), drape::Settings{}, 1e300));
  }
  SECTION("fromMesh positions whose squared edge lengths overflow") {
    auto [p, t] = unitSquare<S>();
    for (auto& q : p) q *= 1e20f;
    CHECK_REJECTS_ANY(drape::ClothAsset<S>::fromMesh(p, t));
  }
  checkUnchanged(before, snapshot(solver));
}
