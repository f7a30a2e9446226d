// Continuous contact (docs/design.md §18): a substep's travel must not carry the cloth through a solid thinner than
// it. The tunnelling cases run with continuous contact and without, and assert that the run without it does
// tunnel: the scene is one the discrete passes alone get wrong. The others check what its answers do to the cloth.
#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include "rest_scenes.hpp"
#include "sanitizer.hpp"
#include "stability_helpers.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>
#include <vector>

// Each test source keeps its helpers in a namespace of its own: the tests build as unity batches.
namespace continuous_tests {

namespace {

using stability::V3;

using stability::gridAsset;

/// Mean and highest height of the cloth's vertices (m).
template <class Solver> std::pair<double, double> heights(const Solver& s) {
  double sum = 0, top = -1e9;
  for (drape::Index i = 0; i < s.vertexCount(); ++i) {
    sum += s.position(i).z();
    top = std::max(top, s.position(i).z());
  }
  return {sum / double(s.vertexCount()), top};
}

struct RodDrop {
  double lowestMean = 1e9;  ///< the cloth's lowest mean height at the end of a frame (m), the rod's axis at 0
  double top = 0;           ///< its highest vertex at the end (m)
  double depth = 0;         ///< the deepest vertex or face point inside the rod at the end of any frame (m)
  std::int64_t sweeps = 0;  ///< paths swept, over the run
  std::int64_t guarded = 0;  ///< faces the friction guard put back, over the run
};

/// A 40 x 40 cloth of 2 cm spacing dropped from 10 cm onto a horizontal capsule of radius 3 mm along y at x = 0,
/// midway between two columns of vertices, at 2 substeps of 1/60 s: 1.2 cm of travel per substep at the
/// landing, not far short of the rod and the thickness on both sides (1.6 cm), and the faces straddling the rod
/// pass it between their corners. Hung at its middle, the cloth's halves (39 cm) put its mean height near
/// -0.2 m. `shift`: the cloth's start moved along x (m).
template <class S> RodDrop dropOnRod(bool continuous, drape::CollisionMethod method, double shift = 0) {
  drape::Settings settings;
  settings.subStepCount = 2;
  settings.collisionMethod = method;
  settings.continuousContact = continuous;
  drape::Solver<S> solver(gridAsset<S>(40, 0.02, V3(shift, 0, 0.1)), settings);
  drape::Solid<drape::Capsule> rod;
  rod.shape.radius = 0.003;
  rod.shape.halfHeight = 0.5;
  rod.pose.rotation = Eigen::AngleAxisd(0.5 * M_PI, V3::UnitX());  // the capsule's axis (z) along y
  rod.staticFriction = rod.dynamicFriction = 0.5;
  solver.addSolid(rod);
  RodDrop out;
  for (int f = 0; f < 120; ++f) {
    solver.step(1.0 / 60.0, [&](const auto& s) {
      out.sweeps += s.stats().vertexSweeps + s.stats().faceSweeps;
      out.guarded += s.stats().frictionGuarded;
    });
    out.lowestMean = std::min(out.lowestMean, heights(solver).first);
    out.depth = std::max(out.depth, drape::penetration(solver).depth);
  }
  out.top = heights(solver).second;
  return out;
}

}  // namespace

TEMPLATE_TEST_CASE("a cloth dropped on a 3 mm rod at 2 substeps stays on it", "[continuous]", float, double) {
  using S = TestType;
  const RodDrop on = dropOnRod<S>(true, drape::CollisionMethod::Faces);
  const RodDrop off = dropOnRod<S>(false, drape::CollisionMethod::Faces);
  const RodDrop vertices = dropOnRod<S>(true, drape::CollisionMethod::Vertices);
  std::printf("[continuous] 3 mm rod, 2 substeps, %s: lowest mean height %.4g m, top at the end %.4g m, deepest "
              "point in the rod %.3g m, %lld paths swept; without continuous contact lowest mean %.4g m; vertex "
              "method %.4g m\n",
              stability::name<S>(), on.lowestMean, on.top, on.depth, static_cast<long long>(on.sweeps),
              off.lowestMean, vertices.lowestMean);
  // Held: hanging from the rod, never inside it.
  CHECK(on.lowestMean > -0.3);
  CHECK(on.top > 0.003);
  CHECK(on.depth == 0);
  CHECK(on.sweeps > 0);
  // Without the sweeps the cloth falls through (the scene tests what it claims to).
  CHECK(off.lowestMean < -1);
  // The vertex method sees no face, and a rod between two columns of vertices lets the faces through.
  CHECK(vertices.lowestMean < -1);
}

TEMPLATE_TEST_CASE("position friction carries no face across a 3 mm rod (the friction guard)", "[continuous]", float,
                   double) {
  // From such starts the cloth's free edges whip over the rod, and undoing a corner's slide along its contact
  // plane, which on a rod thinner than a face is no guide, carried a face across it: without the guard the rod
  // ended 3.0 mm (the axis) and 0.4 mm inside a face, in float and in double, from the starts first chosen here
  // (docs/design.md §18).
  using S = TestType;
  std::int64_t guarded = 0;
  for (const double shift : {0.007, -0.004, -0.0005, -0.00025}) {
    const RodDrop on = dropOnRod<S>(true, drape::CollisionMethod::Faces, shift);
    std::printf("[continuous] 3 mm rod, start moved %.2f mm, %s: deepest point in the rod %.3g m, %lld faces put "
                "back by the friction guard, lowest mean height %.4g m\n",
                shift * 1e3, stability::name<S>(), on.depth, static_cast<long long>(on.guarded), on.lowestMean);
    CHECK(on.depth == 0);
    CHECK(on.lowestMean > -0.3);
    guarded += on.guarded;
  }
  // The guard acted. Which start needs it follows the landing's chaotic fold, which the build's arithmetic and the
  // contact rules move. Of the starts moved -10 to 10 mm in steps of 0.25 mm it acted from +2.5 and +7 mm in float
  // and -4 and 0 mm in double, and with fused multiply-adds (CI's -march=native pass) from -0.5 mm in float and
  // -0.25 mm in double only; the four starts cover both builds (they were -5 and -6 mm before the settle's exact
  // points were judged by the fields, -4 and -7 mm before swept corners stopped ratcheting up the rod).
  CHECK(guarded > 0);
}

TEMPLATE_TEST_CASE("no contact lifts a cloth above where it was dropped onto a 3 mm rod, from 8 starts", "[continuous]",
                   float, double) {
  // The rest scenes' rod (scenes/rest_scenes.hpp): a 40 x 40 cloth of 2 cm dropped from 10 cm above a 3 mm rod
  // along x, mu 0.5, 2 substeps, continuous contact on, its start moved by up to half a cell. A swept face's corner
  // that already held a contact of another direction used to keep its travel along the face's tangent plane too;
  // two tangent planes of the rod meet above both, and the pulls of the hanging halves ratcheted such corners up
  // by up to a centimetre a substep: vertices rose up to 11 cm above the height the cloth fell from, edges
  // stretched to 4.4-14.8 times their length within 3 s, and the rod came through a face from 3 of the 16 runs
  // (docs/design.md §18, "The face's response").
  using S = TestType;
  const int starts = drape::test::kSanitized ? 2 : 8;
  const int frames = drape::test::kSanitized ? 90 : 180;
  for (int k = 0; k < starts; ++k) {
    drape::scenes::Distance distance;
    auto solver = drape::scenes::makeRestScene<S>(drape::scenes::RestScene::Rod, drape::CollisionMethod::Faces, 2,
                                                  distance, drape::scenes::shiftOf(k));
    const double start = heights(solver).second;
    double top = -1, strain = 0;
    int pierced = 0;
    std::vector<drape::Vec3<S>> x(std::size_t(solver.vertexCount()));
    for (int f = 0; f < frames; ++f) {
      solver.step(1.0 / 60.0);
      top = std::max(top, heights(solver).second);
      // A face the rod's axis (y = z = 0) passes through: its corners, seen along x, surround the axis.
      for (const auto& t : solver.asset().triangles) {
        double turn[3];
        for (int e = 0; e < 3; ++e) {
          const V3 a = solver.position(t[std::size_t(e)]), b = solver.position(t[std::size_t((e + 1) % 3)]);
          turn[e] = a.y() * b.z() - a.z() * b.y();
        }
        pierced += (turn[0] > 0 && turn[1] > 0 && turn[2] > 0) || (turn[0] < 0 && turn[1] < 0 && turn[2] < 0);
      }
      for (drape::Index i = 0; i < solver.vertexCount(); ++i) x[std::size_t(i)] = solver.position(i).template cast<S>();
      strain = std::max(strain, drape::stretchStrain(solver.asset(), x).max);
    }
    std::printf("[continuous] 3 mm rod, start %d, %s: highest vertex %.4f m (dropped from %.4f m), largest strain "
                "%.3g, %d face-frames pierced by the rod\n",
                k, stability::name<S>(), top, start, strain, pierced);
    CHECK(top <= start);
    CHECK(pierced == 0);
  }
}

TEMPLATE_TEST_CASE("a kinematic 3 mm rod at 10 m/s catches a cloth it rises into", "[continuous]", float, double) {
  using S = TestType;
  // The rod moves 1.7 cm per substep at the defaults: through the thickness on both sides of it in one.
  auto run = [](bool continuous) {
    drape::Settings settings;
    settings.continuousContact = continuous;
    drape::Solver<S> solver(gridAsset<S>(16, 0.02, V3(0, 0, 0)), settings);
    drape::Solid<drape::Capsule> rod;
    rod.shape.radius = 0.003;
    rod.shape.halfHeight = 0.3;
    rod.motion = drape::Motion::Kinematic;
    rod.pose.rotation = Eigen::AngleAxisd(0.5 * M_PI, V3::UnitX());
    rod.pose.position = {0, 0, -0.05};
    rod.linearVelocity = {0, 0, 10};
    solver.addSolid(rod);
    double depth = 0;
    for (int f = 0; f < 3; ++f) {
      solver.step(1.0 / 60.0);
      depth = std::max(depth, drape::penetration(solver).depth);
    }
    const double rodZ = -0.05 + 10 * 3 / 60.0;
    return std::pair{heights(solver).first - rodZ, depth};  // the cloth's mean height against the rod's axis
  };
  const auto [on, depth] = run(true);
  const double off = run(false).first;
  std::printf("[continuous] rod rising at 10 m/s, %s: the cloth's mean height %.4g m from the rod's axis, deepest "
              "point in the rod %.3g m; without continuous contact %.4g m\n",
              stability::name<S>(), on, depth, off);
  // Carried: the 30 cm cloth hangs from the rod, its mean within its half length below it. Passed through: left
  // behind, 0.45 m below.
  CHECK(on > -0.15);
  CHECK(depth == 0);
  CHECK(off < -0.3);
}

TEMPLATE_TEST_CASE("a cloth thrown at 50 m/s stops at a 1 cm board without gaining energy", "[continuous]", float,
                   double) {
  using S = TestType;
  const int substeps = GENERATE(10, 40);
  struct Throw {
    double maxSpeed = 0, energyRise = -1e9, e0 = 0, lowest = 1e9, penetration = 0;
  };
  auto run = [&](bool continuous) {
    drape::Settings settings;
    settings.subStepCount = substeps;
    settings.continuousContact = continuous;
    drape::Solver<S> solver(gridAsset<S>(20, 0.02, V3(0, 0, 0.3)), settings);
    drape::Solid<drape::Box> board;
    board.shape.halfExtents = {0.5, 0.5, 0.005};
    board.staticFriction = board.dynamicFriction = 0.3;
    solver.addSolid(board);
    solver.setVelocities(std::vector<V3>(std::size_t(solver.vertexCount()), V3(0, 0, -50)));
    Throw out;
    out.e0 = stability::mechanicalEnergy(solver);
    for (int f = 0; f < 12; ++f)
      solver.step(1.0 / 60.0, [&](const auto& s) {
        out.energyRise = std::max(out.energyRise, stability::mechanicalEnergy(s) - out.e0);
        for (drape::Index i = 0; i < s.vertexCount(); ++i) {
          out.maxSpeed = std::max(out.maxSpeed, double(s.state().v[std::size_t(i)].norm()));
          out.lowest = std::min(out.lowest, s.position(i).z());
        }
      });
    out.penetration = drape::penetration(solver).depth;
    return out;
  };
  const Throw on = run(true), off = run(false);
  std::printf("[continuous] 50 m/s at a 1 cm board, %d substeps, %s: lowest vertex over the run %.4g m (board top "
              "0.005), end penetration %.3g m, max speed %.4g m/s, energy rise %.3g J of %.3g J; without continuous "
              "contact lowest %.4g m\n",
              substeps, stability::name<S>(), on.lowest, on.penetration, on.maxSpeed, on.energyRise, on.e0,
              off.lowest);
  CHECK(on.lowest > 0.005);
  CHECK(on.penetration <= 1e-4);
  // No energy from the stop: no vertex faster than the throw plus 0.2 s of free fall, and a total that never
  // rises beyond the rounding of the start energy.
  CHECK(on.maxSpeed <= 50 + 9.81 * 0.2);
  CHECK(on.energyRise <= 1e-6 * on.e0);
  if (substeps == 10) CHECK(off.lowest < -0.1);  // at 40 (2.1 cm per substep) the discrete passes held it here
}

}  // namespace continuous_tests

namespace continuous_tests {

TEMPLATE_TEST_CASE("a cloth thrown at 50 m/s at a ball gains no energy from continuous contact", "[continuous]",
                   float, double) {
  using S = TestType;
  // The case where a swept test that stopped vertices where their paths met the ball doubled the top speed
  // (docs/design.md §4). Here the stretched cloth's solve drags vertices through the ball, and the sweeps hold
  // them on its near side: the cloth stays wrapped around the ball rather than slipping off it.
  struct Throw {
    double maxSpeed = 0, energyRise = -1e9, e0 = 0, faceDepth = 0, lowestVertex = 1e9, speedBound = 0;
  };
  auto run = [](bool continuous) {
    drape::Settings settings;
    settings.continuousContact = continuous;
    drape::Solver<S> solver(gridAsset<S>(20, 0.02, V3(0.005, 0.003, 0.5)), settings);
    drape::Solid<drape::Sphere> ball;
    ball.shape.radius = 0.1;
    ball.staticFriction = ball.dynamicFriction = 0.5;
    solver.addSolid(ball);
    solver.setVelocities(std::vector<V3>(std::size_t(solver.vertexCount()), V3(0, 0, -50)));
    Throw out;
    out.e0 = stability::mechanicalEnergy(solver);
    // No vertex can carry more than the whole cloth's energy after a 0.5 s fall (test_extremes.cpp, case 4).
    double mMin = 1e9;
    for (auto w : solver.state().invMass) mMin = std::min(mMin, 1.0 / double(w));
    const double drop = 50 * 0.5 + 0.5 * stability::kG * 0.25;
    out.speedBound = std::sqrt(2 * (out.e0 + stability::freeMass(solver) * stability::kG * drop) / mMin);
    for (int f = 0; f < 30; ++f)
      solver.step(1.0 / 60.0, [&](const auto& s) {
        out.energyRise = std::max(out.energyRise, stability::mechanicalEnergy(s) - out.e0);
        for (const auto& v : s.state().v) out.maxSpeed = std::max(out.maxSpeed, double(v.norm()));
        for (drape::Index i = 0; i < s.vertexCount(); ++i)
          out.lowestVertex = std::min(out.lowestVertex, (s.position(i) - V3(0, 0, 0)).norm() - 0.1);
        out.faceDepth = std::max(out.faceDepth, drape::penetration(s).depth);
      });
    return out;
  };
  const Throw on = run(true), off = run(false);
  std::printf("[continuous] 50 m/s at a 0.1 m ball, %s: max speed %.4g m/s (bound %.4g; without continuous contact "
              "%.4g), energy rise %.3g J of %.3g J, nearest vertex %.3g m from the surface, deepest face point %.3g m "
              "inside (without %.3g m)\n",
              stability::name<S>(), on.maxSpeed, on.speedBound, off.maxSpeed, on.energyRise, on.e0, on.lowestVertex,
              on.faceDepth, off.faceDepth);
  CHECK(on.energyRise <= 1e-6 * on.e0);
  CHECK(on.maxSpeed < on.speedBound);
  CHECK(on.lowestVertex >= 0);
}

}  // namespace continuous_tests
