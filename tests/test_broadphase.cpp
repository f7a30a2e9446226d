// The cloth's broad phase (drape/collision/broadphase.hpp, Settings::broadPhase): the grid finds every vertex
// and face a bounded solid can touch, so a scene gives the same contacts, bit for bit, with and without it,
// while the solids evaluate their fields only near themselves.

#include "rigid_rain.hpp"
#include "state_hash.hpp"

#include <drape/collision/broadphase.hpp>
#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <vector>

namespace {

template <class S> bool inGrownBox(const drape::Vec3<S>& p, const drape::Vec3<S>& lo, const drape::Vec3<S>& hi, S m) {
  return (p.array() >= lo.array() - m).all() && (p.array() <= hi.array() + m).all();
}

/// A 40 x 40 cloth (2 cm) placed at `at`, over the floor (friction `mu`), with the bins on or off.
template <class S>
drape::Solver<S> sheetOverFloor(const Eigen::Vector3d& at, double mu, bool broadPhase, int threads) {
  drape::SheetDesc grid;
  grid.nx = grid.ny = 40;
  grid.spacing = 0.02;
  grid.placement.position = at;
  drape::Settings settings;
  settings.broadPhase = broadPhase;
  settings.threadCount = threads;
  drape::Solver<S> cloth(std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid)), settings);
  drape::Solid<drape::Plane> floor;
  floor.staticFriction = floor.dynamicFriction = mu;
  cloth.addSolid(floor);
  return cloth;
}

/// A 40 x 40 cloth falling onto a floor and five bounded solids of every convex kind, one of them a box
/// sweeping sideways through the cloth at 3 m/s (it drags vertices far from where they were binned).
/// With `draped`, a large ball rising under the cloth comes first among the bounded solids: its box holds most of
/// the cloth, so its passes visit every vertex and face, and the solids after it read the bins it moved vertices in.
template <class S> drape::Solver<S> crowdedScene(bool broadPhase, int threads, bool draped = false) {
  drape::Solver<S> cloth = sheetOverFloor<S>({0.001, -0.002, 0.25}, 0.4, broadPhase, threads);
  if (draped) {
    drape::Solid<drape::Sphere> dome;
    dome.shape.radius = 0.3;
    dome.pose.position = {0.01, 0.02, -0.12};
    dome.motion = drape::Motion::Kinematic;
    dome.linearVelocity = {0, 0, 0.15};
    dome.dynamicFriction = dome.staticFriction = 0.3;
    cloth.addSolid(dome);
  }
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = 0.08;
  ball.pose.position = {-0.2, -0.2, 0.1};
  ball.dynamicFriction = ball.staticFriction = 0.3;
  cloth.addSolid(ball);
  drape::Solid<drape::Box> sweeper;
  sweeper.shape.halfExtents = {0.03, 0.05, 0.08};
  sweeper.pose.position = {-0.45, 0.15, 0.15};
  sweeper.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  sweeper.motion = drape::Motion::Kinematic;
  sweeper.linearVelocity = {3, 0, 0};
  sweeper.angularVelocity = {0, 0, 2};
  cloth.addSolid(sweeper);
  drape::Solid<drape::Capsule> capsule;
  capsule.shape = {0.03, 0.1};
  capsule.pose.position = {0.2, -0.2, 0.05};
  capsule.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitX()));
  cloth.addSolid(capsule);
  drape::Solid<drape::Cylinder> cylinder;
  cylinder.shape = {0.05, 0.06};
  cylinder.pose.position = {0.2, 0.2, 0.06};
  cloth.addSolid(cylinder);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < 14; ++k) points.push_back(0.07 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized());
  drape::Solid<drape::ConvexHull> hull{drape::ConvexHull(points)};
  hull.pose.position = {-0.2, 0.2, 0.07};
  cloth.addSolid(hull);
  return cloth;
}

template <class S> void requireSameState(const drape::Solver<S>& a, const drape::Solver<S>& b) {
  std::int64_t differ = 0;
  for (drape::Index i = 0; i < a.vertexCount(); ++i)
    differ += (a.state().x[i] != b.state().x[i] || a.state().v[i] != b.state().v[i]) ? 1 : 0;
  INFO(differ << " of " << a.vertexCount() << " vertices differ");
  REQUIRE(differ == 0);
}

}  // namespace

TEMPLATE_TEST_CASE("the cloth grid finds exactly the vertices in a box, and every face that can reach it, after "
                   "vertices drift",
                   "[broadphase]", float, double) {
  using S = TestType;
  using V = drape::Vec3<S>;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  // A crumpled 30 x 30 cloth: grid topology, random positions in a 0.6 m cube.
  drape::SheetDesc desc;
  desc.nx = desc.ny = 30;
  const auto asset = drape::ClothAsset<S>::sheet(desc);
  const drape::Index n = asset.vertexCount();
  std::vector<V> x(static_cast<std::size_t>(n));
  for (auto& p : x) p = V(S(0.3 * u(rng)), S(0.3 * u(rng)), S(0.1 * u(rng)));
  drape::VertexBins<S> grid;
  grid.setTopology(asset.triangles, n, S(0.04));
  grid.build(x.data(), asset.triangles);
  std::vector<drape::Index> found;
  int checkedFaces = 0;
  for (int round = 0; round < 2; ++round) {
    if (round == 1) {  // every third vertex moves up to 3 cm: the queries must widen by the drift
      S drift = 0;
      for (drape::Index i = 0; i < n; i += 3) {
        x[std::size_t(i)] += V(S(0.017 * u(rng)), S(0.017 * u(rng)), S(0.017 * u(rng)));
        drift = std::max(drift, (x[std::size_t(i)] - grid.binned()[i]).norm());
      }
      grid.noteDrift(drift);
      REQUIRE(grid.drift() > S(0.01));
    }
    for (int q = 0; q < 200; ++q) {
      const V c(S(0.35 * u(rng)), S(0.35 * u(rng)), S(0.12 * u(rng)));
      const V h(S(0.01 + 0.08 * std::abs(u(rng))), S(0.01 + 0.08 * std::abs(u(rng))), S(0.01 + 0.05 * std::abs(u(rng))));
      const V lo = c - h, hi = c + h;
      const S margin = S(0.005);
      grid.vertices(x.data(), lo, hi, margin, found);
      std::set<drape::Index> got(found.begin(), found.end());
      REQUIRE(got.size() == found.size());  // each once
      std::set<drape::Index> want;
      for (drape::Index i = 0; i < n; ++i)
        if (inGrownBox(x[std::size_t(i)], lo, hi, margin)) want.insert(i);
      REQUIRE(got == want);
      grid.faces(x.data(), lo, hi, margin, found);
      REQUIRE(std::is_sorted(found.begin(), found.end()));
      REQUIRE(std::adjacent_find(found.begin(), found.end()) == found.end());
      // Brute force: a face with any of 31 points (corners, edge points, interior points) in the grown box must
      // be among those found.
      for (drape::Index f = 0; f < asset.faceCount(); ++f) {
        const auto& t = asset.triangles[std::size_t(f)];
        bool reaches = false;
        for (int a = 0; a <= 6 && !reaches; ++a)
          for (int b = 0; a + b <= 6 && !reaches; ++b) {
            const V p = (S(a) * x[std::size_t(t[0])] + S(b) * x[std::size_t(t[1])] +
                         S(6 - a - b) * x[std::size_t(t[2])]) / S(6);
            reaches = inGrownBox(p, lo, hi, margin);
          }
        if (!reaches) continue;
        ++checkedFaces;
        REQUIRE(std::binary_search(found.begin(), found.end(), f));
      }
    }
  }
  CHECK(checkedFaces > 1000);
}

TEMPLATE_TEST_CASE("with the broad phase a crowded scene runs bit for bit as without it, on one and two threads",
                   "[broadphase]", float, double) {
  using S = TestType;
  auto plain = crowdedScene<S>(false, 1);
  auto gridded = crowdedScene<S>(true, 1);
  auto twoThreads = crowdedScene<S>(true, 2);
  std::int64_t plainEvaluations = 0, griddedEvaluations = 0, contacts = 0;
  for (int s = 0; s < 40; ++s) {
    plain.step(1.0 / 60);
    gridded.step(1.0 / 60);
    twoThreads.step(1.0 / 60);
    plainEvaluations += plain.stats().sdfEvaluations;
    griddedEvaluations += gridded.stats().sdfEvaluations;
    contacts += gridded.stats().vertexContacts + gridded.stats().faceContacts;
    REQUIRE(gridded.stats().vertexContacts == plain.stats().vertexContacts);
    REQUIRE(gridded.stats().faceContacts == plain.stats().faceContacts);
  }
  requireSameState(plain, gridded);
  requireSameState(plain, twoThreads);
  // The scene did touch the solids, and the sweeper went through the cloth.
  CHECK(contacts > 1000);
  const double share = double(griddedEvaluations) / double(plainEvaluations);
  INFO("field evaluations with the grid: " << share << " of those without (last substeps of 40 steps)");
  CHECK(share < 0.5);
}

TEMPLATE_TEST_CASE("with a solid that holds most of the cloth, the broad phase still runs bit for bit as without it",
                   "[broadphase]", float, double) {
  using S = TestType;
  auto plain = crowdedScene<S>(false, 1, true);
  auto gridded = crowdedScene<S>(true, 1, true);
  auto twoThreads = crowdedScene<S>(true, 2, true);
  // The dome's box (0.6 m wide, under a 0.8 m cloth) holds more than half of the cloth's vertices.
  drape::Index inside = 0;
  for (const auto& x : gridded.state().x) inside += (x.template head<2>().array().abs() < S(0.3)).all() ? 1 : 0;
  REQUIRE(2 * inside > gridded.vertexCount());
  std::int64_t faceContacts = 0;
  for (int s = 0; s < 40; ++s) {
    plain.step(1.0 / 60);
    gridded.step(1.0 / 60);
    twoThreads.step(1.0 / 60);
    faceContacts += gridded.stats().faceContacts;
    REQUIRE(gridded.stats().vertexContacts == plain.stats().vertexContacts);
    REQUIRE(gridded.stats().faceContacts == plain.stats().faceContacts);
  }
  requireSameState(plain, gridded);
  requireSameState(plain, twoThreads);
  CHECK(faceContacts > 1000);
}

/// A cloth settling on a still ball (0.3 m, its box holds most of the cloth) and the floor, beside a still
/// capsule (its faces come from the bins' lists): the ball's face pass keeps each culled face's clearance between
/// substeps and passes over the faces still clear. The ball is moved into the cloth by setSolid, and the thickness
/// changed, midway: the kept clearances must not outlive either. With `keepSpin` (Settings::keepAngularMomentum)
/// the face pass records the corners' own normals and scales their velocities about the ball's centre.
template <class S> drape::Solver<S> stillBallScene(bool broadPhase, int threads, bool keepSpin = false) {
  drape::Solver<S> cloth = sheetOverFloor<S>({0.003, -0.004, 0.64}, 0.3, broadPhase, threads);
  if (keepSpin) {
    drape::Settings settings = cloth.settings();
    settings.keepAngularMomentum = true;
    cloth.setSettings(settings);
  }
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = 0.3;
  ball.pose.position = {0, 0, 0.3};
  ball.staticFriction = ball.dynamicFriction = 0.3;
  cloth.addSolid(ball);
  drape::Solid<drape::Capsule> capsule;
  capsule.shape = {0.02, 0.1};
  capsule.pose.position = {0.33, 0.1, 0.05};
  cloth.addSolid(capsule);
  return cloth;
}

TEMPLATE_TEST_CASE("faces kept clear of a still ball between substeps are passed over, bit for bit as without the "
                   "broad phase, also when the ball moves or the thickness changes",
                   "[broadphase]", float, double) {
  using S = TestType;
  const bool keepSpin = GENERATE(false, true);
  INFO("angular momentum kept: " << keepSpin);
  auto plain = stillBallScene<S>(false, 1, keepSpin);
  auto gridded = stillBallScene<S>(true, 1, keepSpin);
  auto twoThreads = stillBallScene<S>(true, 2, keepSpin);
  std::int64_t kept = 0, tested = 0, faceContacts = 0, keptBeforeMove = 0, keptOnTwo = 0;
  for (int f = 0; f < 90; ++f) {
    if (f == 40) {  // the ball moves 1 cm up and 2 cm aside, into the cloth resting on it
      drape::Solid<drape::Sphere> ball = plain.template solid<drape::Sphere>(0);
      ball.pose.position += Eigen::Vector3d(0.02, 0, 0.01);
      for (auto* s : {&plain, &gridded, &twoThreads}) s->setSolid(0, ball);
      keptBeforeMove = kept;
    }
    if (f == 65) {  // a thicker cloth: faces kept clear of the thinner one may now be within the thickness
      drape::Settings thicker = plain.settings();
      thicker.thickness = 0.009;
      for (auto* s : {&plain, &gridded, &twoThreads}) s->setSettings(thicker);
    }
    plain.step(1.0 / 60);
    gridded.step(1.0 / 60, [&](const drape::Solver<S>& s) noexcept {
      kept += s.stats().facesKeptClear;
      tested += s.stats().facesTested;
    });
    twoThreads.step(1.0 / 60, [&](const drape::Solver<S>& s) noexcept { keptOnTwo += s.stats().facesKeptClear; });
    faceContacts += gridded.stats().faceContacts;
    REQUIRE(gridded.stats().vertexContacts == plain.stats().vertexContacts);
    REQUIRE(gridded.stats().faceContacts == plain.stats().faceContacts);
    REQUIRE(plain.stats().facesKeptClear == 0);
  }
  requireSameState(plain, gridded);
  requireSameState(plain, twoThreads);
  INFO("faces passed over on kept clearances: " << kept << " of " << tested << " tested");
  CHECK(faceContacts > 10000);
  CHECK(keptBeforeMove > 0);
  CHECK(kept - keptBeforeMove > 0);
  CHECK(double(kept) > 0.1 * double(tested));
  // Two threads bin and keep as one does: their drift is the largest over the threads, not a sum that grows with
  // their number (docs/design.md §12).
  CHECK(keptOnTwo == kept);
}

/// A still cloth (no gravity, 11 x 11 vertices 2 cm apart) shaped as a cap 5.5 mm beyond a ball of 0.3 m, so
/// every vertex is clear of the 5 mm thickness and every face too, though its faces dip up to 0.3 mm below their
/// corners: nothing moves, and the ball's face pass keeps each face's clearance. `change` then brings the faces
/// near the top within the thickness, but not their vertices, so only the face pass can see it: 1 moves the ball
/// 0.45 mm up (setSolid), 2 thickens the cloth to 5.4 mm (setSettings). Returns the face contacts over the
/// substeps of the step after the change.
template <class S> std::int64_t faceContactsAfterChange(bool broadPhase, int change) {
  const double radius = 0.3, gap = 0.0055;
  const Eigen::Vector3d centre(0.001, -0.002, 0.3);
  std::vector<drape::Vec3<S>> points;
  std::vector<std::array<drape::Index, 3>> triangles;
  constexpr int kSide = 11;
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      const double x = 0.02 * (i - kSide / 2), y = 0.02 * (j - kSide / 2);
      const double z = std::sqrt((radius + gap) * (radius + gap) - x * x - y * y);
      points.push_back((centre + (radius + gap) * Eigen::Vector3d(x, y, z).normalized()).cast<S>());
    }
  for (int j = 0; j + 1 < kSide; ++j)
    for (int i = 0; i + 1 < kSide; ++i) {
      const drape::Index a = j * kSide + i;
      triangles.push_back({a, a + 1, a + kSide + 1});
      triangles.push_back({a, a + kSide + 1, a + kSide});
    }
  drape::Settings settings;
  settings.broadPhase = broadPhase;
  settings.gravity.setZero();
  const auto asset = std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::fromMesh(points, triangles));
  drape::Solver<S> cloth(asset, settings);
  drape::Solid<drape::Sphere> ball;
  ball.shape.radius = radius;
  ball.pose.position = centre;
  cloth.addSolid(ball);
  for (int f = 0; f < 3; ++f) cloth.step(1.0 / 60);
  REQUIRE(cloth.stats().faceContacts == 0);
  REQUIRE(cloth.stats().vertexContacts == 0);
  if (broadPhase) REQUIRE(cloth.stats().facesKeptClear > 0);  // the ball holds the cloth: its faces are kept
  if (change == 1) {
    ball.pose.position.z() += 0.00045;
    cloth.setSolid(0, ball);
  } else {
    settings.thickness = 0.0054;
    cloth.setSettings(settings);
  }
  std::int64_t faceContacts = 0, vertexContacts = 0;
  cloth.step(1.0 / 60, [&](const drape::Solver<S>& s) noexcept {
    faceContacts += s.stats().faceContacts;
    vertexContacts += s.stats().vertexContacts;
  });
  CHECK(vertexContacts == 0);
  return faceContacts;
}

TEMPLATE_TEST_CASE("a face's kept clearance does not outlive a moved solid or a thicker cloth", "[broadphase]", float,
                   double) {
  using S = TestType;
  for (int change : {1, 2}) {
    INFO("change " << change);
    const std::int64_t plain = faceContactsAfterChange<S>(false, change);
    CHECK(plain > 0);
    CHECK(faceContactsAfterChange<S>(true, change) == plain);
  }
}

// Where the build fuses multiply-adds, the vertex pass over the bins' list and the one over every vertex are two
// copies of one expression that the compiler may fuse differently: the first contact then rounds differently
// (681 of 720 vertices moved apart by at most 1.0e-7 m, float rounding, at -O3 -march=native), and the rain,
// chaotic, carries that apart (0.13 m after 45 steps). There the runs are compared up to the first step with a
// contact, within a few roundings of the positions.
TEST_CASE("the rigid-body rain gives the same bodies and cloth with and without the broad phase", "[broadphase][coupling]") {
  using S = float;
  drape::scenes::RainConfig c;
  c.bodies = 8;
  c.seed = 5;
  c.nx = 24;
  c.ny = 30;
  c.minDrop = 0.6;
  c.maxDrop = 0.8;
  c.release = 0.3;
  c.base.broadPhase = false;
  drape::scenes::RigidRain<S> plain(c);
  c.base.broadPhase = true;
  drape::scenes::RigidRain<S> gridded(c);
  for (int s = 0; s < 45; ++s) {
    plain.step();
    gridded.step();
    if (drape::test::kMayFuse && gridded.cloth().stats().vertexContacts > 0) break;
  }
  CHECK(gridded.cloth().stats().vertexContacts > 0);
  CHECK(gridded.cloth().stats().vertexContacts == plain.cloth().stats().vertexContacts);
  if (!drape::test::kMayFuse) {
    requireSameState(plain.cloth(), gridded.cloth());
  } else {
    double worst = 0;
    for (drape::Index i = 0; i < plain.cloth().vertexCount(); ++i)
      worst = std::max(worst, double((plain.cloth().position(i) - gridded.cloth().position(i)).norm()));
    INFO("largest distance between the runs at the first contact " << worst << " m");
    CHECK(worst <= 8 * std::numeric_limits<S>::epsilon() * 2);  // positions within 2 m of the origin
  }
  for (int b = 0; b < plain.world().bodyCount(); ++b) {
    INFO("body " << b);
    const Eigen::Vector3d dx = plain.world().body(b).pose().position - gridded.world().body(b).pose().position;
    const Eigen::Vector3d dv = plain.world().body(b).linearVelocity() - gridded.world().body(b).linearVelocity();
    CHECK(dx.norm() <= (drape::test::kMayFuse ? 1e-9 : 0.0));
    CHECK(dv.norm() <= (drape::test::kMayFuse ? 1e-7 : 0.0));
  }
}
