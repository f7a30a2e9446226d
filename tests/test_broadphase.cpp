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

/// A 40 x 40 cloth falling onto a floor and five bounded solids of every convex kind, one of them a box
/// sweeping sideways through the cloth at 3 m/s (it drags vertices far from where they were binned).
/// With `draped`, a large ball rising under the cloth comes first among the bounded solids: its box holds most of
/// the cloth, so its passes visit every vertex and face, and the solids after it read the bins it moved vertices in.
template <class S> drape::Solver<S> crowdedScene(bool broadPhase, int threads, bool draped = false) {
  drape::SheetDesc grid;
  grid.nx = grid.ny = 40;
  grid.spacing = 0.02;
  grid.placement.position = {0.001, -0.002, 0.25};
  drape::Settings settings;
  settings.broadPhase = broadPhase;
  settings.threadCount = threads;
  drape::Solver<S> cloth(std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid)), settings);
  drape::Solid<drape::Plane> floor;
  floor.staticFriction = floor.dynamicFriction = 0.4;
  cloth.addSolid(floor);
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
