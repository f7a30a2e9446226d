// Kinematic solids: the contact velocity v_c = v + w x (x - x_r) drives friction and the velocity split.
#include <drape/drape.hpp>
#include <sphere_drape.hpp>

#include "sanitizer.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <type_traits>
#include <vector>

namespace {

template <class S> drape::Solver<S> clothOnFloor(const drape::Solid<drape::Plane>& floor) {
  drape::SheetDesc grid;
  grid.nx = grid.ny = 10;
  grid.spacing = 0.02;
  grid.placement.position = {0, 0, 0.005};  // resting at the thickness
  auto asset = std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid));
  drape::Solver<S> solver(asset);
  solver.addSolid(floor);
  return solver;
}

}  // namespace

TEMPLATE_TEST_CASE("a sliding floor carries a cloth by friction and not without it", "[kinematic]", float, double) {
  drape::Solid<drape::Plane> floor;
  floor.motion = drape::Motion::Kinematic;
  floor.linearVelocity = {0.5, 0, 0};  // sliding in its own plane: the surface stays at z = 0
  SECTION("sticky floor: the cloth moves with it") {
    floor.staticFriction = floor.dynamicFriction = 1.0;
    auto solver = clothOnFloor<TestType>(floor);
    for (int f = 0; f < 60; ++f) solver.step(1.0 / 60.0);
    for (drape::Index i = 0; i < solver.vertexCount(); ++i) {
      CHECK(solver.velocity(i).x() == Approx(0.5).margin(1e-4));
      CHECK(solver.position(i).z() == Approx(0.005).margin(1e-5));
    }
  }
  SECTION("frictionless floor: the cloth stays where it is") {
    auto solver = clothOnFloor<TestType>(floor);
    const Eigen::Vector3d before = solver.position(0);
    for (int f = 0; f < 60; ++f) solver.step(1.0 / 60.0);
    CHECK((solver.position(0) - before).norm() < 1e-5);
  }
}

TEMPLATE_TEST_CASE("a vertex pinned to a moving target has the velocity of its pin's moves, frame after frame",
                   "[kinematic][pins]", float, double) {
  // A cloth pulled along the floor by one corner fixed (inverse mass 0) to a target that moves 5 mm at the start of
  // each frame (0.3 m/s). The corner jumps in the frame's first substep and stays in the others, so its velocity,
  // integrated over the frame's substeps, is the target's move. A pinned vertex whose velocity the prediction
  // kept added each move's velocity to the last: 3, 6, 9 m/s ... after the frames.
  auto solver = clothOnFloor<TestType>(drape::Solid<drape::Plane>{});
  const double dt = 1.0 / 60.0, speed = 0.3;
  const double h = dt / solver.settings().subStepCount;
  solver.pin(0);
  Eigen::Vector3d target = solver.position(0);
  const drape::Index pin = solver.attach(0, target);
  double worst = 0, fastest = 0;
  for (int f = 0; f < 30; ++f) {
    target.x() += speed * dt;
    solver.setPinTarget(pin, target);
    Eigen::Vector3d travelled = Eigen::Vector3d::Zero();
    solver.step(dt, [&](const drape::Solver<TestType>& s) {
      travelled += h * s.velocity(0);
      fastest = std::max(fastest, s.velocity(0).norm());
    });
    worst = std::max(worst, (travelled - Eigen::Vector3d(speed * dt, 0, 0)).norm());
  }
  INFO("largest gap between the corner's integrated velocity and its pin's move in a frame " << worst
       << " m; fastest " << fastest << " m/s");
  CHECK((solver.position(0) - target).norm() < 1e-6);
  CHECK(worst <= 1e-6 * speed * dt * 30);
  CHECK(fastest <= speed * dt / h * (1 + 1e-4));  // the whole move in one substep, and no more
}

TEMPLATE_TEST_CASE("a turntable spins a sticky cloth at w x r", "[kinematic]", float, double) {
  drape::Solid<drape::Plane> table;
  table.motion = drape::Motion::Kinematic;
  table.angularVelocity = {0, 0, 2.0};  // rad/s about the world z axis through the frame origin
  table.staticFriction = table.dynamicFriction = 1.0;
  auto solver = clothOnFloor<TestType>(table);
  for (int f = 0; f < 60; ++f) solver.step(1.0 / 60.0);
  for (drape::Index i = 0; i < solver.vertexCount(); ++i) {
    const Eigen::Vector3d p = solver.position(i);
    const Eigen::Vector3d expected = Eigen::Vector3d(0, 0, 2.0).cross(Eigen::Vector3d(p.x(), p.y(), 0));
    CHECK((solver.velocity(i) - expected).norm() < 1e-3);
  }
}

TEMPLATE_TEST_CASE("a frictionless spinning sphere answers a cloth's contacts as the same sphere at rest",
                   "[kinematic][spin]", float, double) {
  // A 41x41 cloth draped over a 0.3 m sphere from its top, its centre pinned on the axis. Without friction
  // nothing can pass the sphere's spin to the cloth: its surface moves only along itself. A face contact moves
  // corners that lie off the surface, where the spinning sphere's material velocity has a normal part; answered
  // there (and with propagation dotting the sources' mean velocity with their mean normal), the spinning sphere
  // turned the cloth with it (docs/design.md §4). The cloth drapes for 1/3 s, then both solvers take one
  // substep from the same state, one with the sphere spinning at 2 rad/s about the vertical: the velocities must
  // agree to rounding. Measured: 6.2e-8 m/s apart in float, 1.2e-16 in double; 4.0e-2 and 3.1e-2 before.
  using S = TestType;
  using drape::scenes::SphereDrape;
  const auto asset = SphereDrape::asset<S>();
  drape::Solver<S> still(asset), spinning(asset);
  for (auto* solver : {&still, &spinning}) {
    solver->addSolid(SphereDrape::sphere());
    solver->pin(SphereDrape::kCentre);
    for (int f = 0; f < 20; ++f) solver->step(1.0 / 60.0);
  }
  spinning.setSolid(0, SphereDrape::sphere(2.0));
  drape::Settings one;
  one.subStepCount = 1;
  for (auto* solver : {&still, &spinning}) {
    solver->setSettings(one);
    solver->step(1.0 / 600.0);
  }
  REQUIRE(still.stats().faceContacts > 100);
  double apart = 0, fastest = 0;
  for (drape::Index i = 0; i < still.vertexCount(); ++i) {
    apart = std::max(apart, (spinning.velocity(i) - still.velocity(i)).norm());
    fastest = std::max(fastest, still.velocity(i).norm());
  }
  INFO("face contacts " << still.stats().faceContacts << ", fastest vertex " << fastest
                        << " m/s, largest velocity difference " << apart << " m/s");
  // Rounding of the spinning sphere's 0.6 m/s surface velocity: a few ulps of it.
  CHECK(apart <= (std::is_same_v<S, float> ? 1e-6 : 1e-14));
}

TEMPLATE_TEST_CASE("a frictionless turntable leaves the cloth lying on it at rest", "[kinematic][spin]", float,
                   double) {
  drape::Solid<drape::Plane> table;
  table.motion = drape::Motion::Kinematic;
  table.angularVelocity = {0, 0, 2.0};
  auto solver = clothOnFloor<TestType>(table);
  for (int f = 0; f < 60; ++f) solver.step(1.0 / 60.0);
  double fastest = 0;
  for (drape::Index i = 0; i < solver.vertexCount(); ++i) fastest = std::max(fastest, solver.velocity(i).norm());
  const double momentum = drape::scenes::axialSpin(solver).momentum;
  INFO("fastest vertex " << fastest << " m/s, angular momentum about the axis " << momentum);
  CHECK(fastest <= 1e-6);
  CHECK(std::abs(momentum) <= 1e-12);
}

namespace {

/// The sphere drape (scenes/sphere_drape.hpp) for `seconds`, the sphere spinning at `spin` rad/s: the cloth's
/// turn about the axis (rad/s) at the end.
struct DrapeRun {
  int threads = 1;
  int substeps = drape::Settings{}.subStepCount;
  bool capsule = false;  ///< the standing capsule instead of the sphere
  std::vector<Eigen::Vector3d>* positions = nullptr;
};

template <class S>
double drapeTurn(drape::CollisionMethod method, bool keep, double spin, double seconds, const DrapeRun& run = {}) {
  using drape::scenes::SphereDrape;
  drape::Settings settings;
  settings.subStepCount = run.substeps;
  settings.collisionMethod = method;
  settings.keepAngularMomentum = keep;
  settings.threadCount = run.threads;
  drape::Solver<S> solver(SphereDrape::asset<S>(), settings);
  if (run.capsule)
    solver.addSolid(SphereDrape::standingCapsule(spin));
  else
    solver.addSolid(SphereDrape::sphere(spin));
  solver.pin(SphereDrape::kCentre);
  for (int f = 0; f < int(seconds * 60 + 0.5); ++f) solver.step(1.0 / 60.0);
  if (run.positions != nullptr)
    for (drape::Index i = 0; i < solver.vertexCount(); ++i) run.positions->push_back(solver.position(i));
  return drape::scenes::axialSpin(solver).rate();
}

}  // namespace

TEMPLATE_TEST_CASE("with the angular momentum kept, a cloth pinned on a frictionless sphere's axis stays unturned "
                   "with every method", "[kinematic][spin]", float, double) {
  // Nothing can turn the cloth about the axis: the sphere pushes along lines through its centre, the pin is on
  // the axis, gravity is along it. What turns it without the setting (docs/design.md §4): XPBD's solve, a face
  // contact's corners answered along the face's normal, and propagation's shares given along their sources'
  // mean normal at the vertex they move. Measured after 5 s at 10 substeps with the moment kept
  // (bench/spin_drift 5 10): at most 3.5e-3 rad/s for every method, the sphere at rest or spinning, float and
  // double; without it this scene turns 0.08-0.16 rad/s with faces and 0.26-0.32 with vertex contacts.
  using S = TestType;
  using M = drape::CollisionMethod;
  const double seconds = 5, bound = 1e-2;
  struct Case {
    M method;
    double spin;
  };
  // Under the sanitizers (about 20 times slower) the default method only, on the same code paths.
  const std::vector<Case> cases = drape::test::kSanitized
                                      ? std::vector<Case>{{M::Faces, 0.0}}
                                      : std::vector<Case>{{M::Faces, 0.0}, {M::Faces, 2.0}, {M::Vertices, 0.0},
                                                          {M::InSolve, 0.0}};
  for (const Case& c : cases) {
    const double turn = drapeTurn<S>(c.method, true, c.spin, seconds);
    INFO(drape::toString(c.method) << ", sphere spinning at " << c.spin << " rad/s: turn " << turn << " rad/s");
    CHECK(std::abs(turn) <= bound);
  }
  // The scene turns the cloth where the moment is not kept: the meter above sees what it claims to. Shown on the
  // vertex method, which turns most (0.26-0.32 rad/s); the faces method's own turn without the setting (0.08-0.16,
  // smaller since a ball's vertex pass was left to its face pass) is the defect the setting answers, not asserted.
  const double baseline = drapeTurn<S>(M::Vertices, false, 0.0, seconds);
  INFO("vertices without: turn " << baseline << " rad/s");
  CHECK(std::abs(baseline) >= 10 * bound);
}

TEMPLATE_TEST_CASE("with the angular momentum kept, the cloth on a frictionless sphere stays unturned at 2 "
                   "substeps", "[kinematic][spin]", float, double) {
  // A contact moves a vertex out along the ball's normal without changing its velocity, which adds
  // m (r1 - r0) n x v to its moment about the centre; at 2 substeps that fed back into the turn, which grew by a
  // quarter each second (faces: -2.3e-3 rad/s after 1 s, -0.37 after 20 s; vertices: -0.010 after 20 s). With the
  // moved vertex's velocity across the line to the centre scaled by r0 / r1 (docs/design.md §4), measured after
  // 20 s (bench/spin_drift 20 2): faces 4.3e-4 / 4.6e-4 rad/s (float / double), vertices 2.6e-8 / 1.8e-17.
  using S = TestType;
  using M = drape::CollisionMethod;
  const double seconds = 20;
  struct Case {
    M method;
    double bound;  ///< rad/s; the vertex method's contacts keep the moment to rounding
  };
  // Under the sanitizers (about 20 times slower) the vertex method only: the same scaling, without face searches.
  const std::vector<Case> cases = drape::test::kSanitized ? std::vector<Case>{{M::Vertices, 1e-5}}
                                                          : std::vector<Case>{{M::Faces, 2e-3}, {M::Vertices, 1e-5}};
  for (const Case& c : cases) {
    const double turn = drapeTurn<S>(c.method, true, 0.0, seconds, {.substeps = 2});
    INFO(drape::toString(c.method) << ": turn " << turn << " rad/s after " << seconds << " s");
    CHECK(std::abs(turn) <= c.bound);
  }
}

TEMPLATE_TEST_CASE("with the angular momentum kept, the cloth on a frictionless standing capsule stays unturned",
                   "[kinematic][spin]", float, double) {
  // The sphere drape's cloth on a capsule with the same top: its corners hang down the side, which curves about
  // the axis only, so a contact there keeps only the velocity around the axis (keepTurnAbout). Measured after
  // 10 s at 2 substeps (bench/spin_drift 10 2), vertices -2.3e-8 / -1.7e-17 rad/s (float / double); with the
  // side's contacts left unscaled the vertices method turned at 1.4e-4 / 1.7e-4, which its bound here sees;
  // without the setting, 0.23-0.47. The faces method's remainder is gained while the cloth lands and is chaotic:
  // with the capsule moved 0 to 6 mm down its axis (seven starts, float and double) it ends between -2.0e-3 and
  // +2.2e-3 rad/s (+2.2e-3 from this start, in double), and ended between -2.5e-3 and +4.1e-3 when the capsule's
  // faces were searched by cutting planes rather than in closed form. The bound sits above that spread, 50 times
  // below the turn without the setting.
  using S = TestType;
  using M = drape::CollisionMethod;
  const double seconds = 10;
  struct Case {
    M method;
    double bound;
  };
  const std::vector<Case> cases = drape::test::kSanitized ? std::vector<Case>{{M::Vertices, 1e-5}}
                                                          : std::vector<Case>{{M::Faces, 5e-3}, {M::Vertices, 1e-5}};
  for (const Case& c : cases) {
    const double turn = drapeTurn<S>(c.method, true, 0.0, seconds, {.substeps = 2, .capsule = true});
    INFO(drape::toString(c.method) << ": turn " << turn << " rad/s after " << seconds << " s");
    CHECK(std::abs(turn) <= c.bound);
  }
  if (drape::test::kSanitized) return;
  // Where it is not kept, the same scene turns the cloth: the meter sees what it claims to.
  const double baseline = drapeTurn<S>(M::Faces, false, 0.0, seconds, {.substeps = 2, .capsule = true});
  INFO("faces without: turn " << baseline << " rad/s");
  CHECK(std::abs(baseline) >= 0.1);
}

TEMPLATE_TEST_CASE("with the angular momentum kept, a cloth hanging from one pin keeps its angular momentum",
                   "[kinematic][spin]", float, double) {
  // No solid: the pin can push the cloth but has no moment about itself, so the cloth's angular momentum about
  // the vertical through the pin stays at zero. Without the restoring rotation XPBD's solve gives it 4.4e-4
  // (float) and 1.1e-3 kg m^2/s (double) in 5 s; with it, rounding (measured 2e-10 in float, 2e-19 in double).
  using S = TestType;
  using drape::scenes::SphereDrape;
  for (const bool keep : {true, false}) {
    drape::Settings settings;
    settings.keepAngularMomentum = keep;
    drape::Solver<S> solver(SphereDrape::asset<S>(), settings);
    solver.pin(SphereDrape::kCentre);
    for (int f = 0; f < 300; ++f) solver.step(1.0 / 60.0);
    const double momentum = drape::scenes::axialSpin(solver).momentum;
    INFO((keep ? "kept" : "not kept") << ": angular momentum about the axis " << momentum << " kg m^2/s");
    if (keep)
      CHECK(std::abs(momentum) <= (std::is_same_v<S, float> ? 1e-8 : 1e-15));
    else
      CHECK(std::abs(momentum) >= 1e-4);
  }
}

TEST_CASE("the kept angular momentum does not depend on the thread count", "[kinematic][spin][threads]") {
  // The restoring rotation adds its sums chunk by chunk in a fixed order: one thread and two give the same bits.
  using drape::scenes::SphereDrape;
  std::vector<Eigen::Vector3d> one, two;
  drapeTurn<float>(drape::CollisionMethod::Faces, true, 2.0, 0.5, {.threads = 1, .positions = &one});
  drapeTurn<float>(drape::CollisionMethod::Faces, true, 2.0, 0.5, {.threads = 2, .positions = &two});
  REQUIRE(one.size() == two.size());
  int differ = 0;
  for (std::size_t i = 0; i < one.size(); ++i) differ += one[i] != two[i];
  CHECK(differ == 0);
}
