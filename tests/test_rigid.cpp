// Rigid bodies: shapes and mass properties, libccd contacts, the broad phase, the XPBD world, the coupling
// interface. Tolerances are stated where they are asserted, with the reason for their size.

#include <drape/rigid/world.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

// Each test source keeps its helpers in a namespace of its own: the tests build as unity batches.
namespace rigid_tests {

using namespace drape;
using Eigen::Vector3d;

namespace {

constexpr double kG = 9.81;

Pose at(const Vector3d& p, const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  Pose pose;
  pose.position = p;
  pose.rotation = q;
  return pose;
}

Eigen::Quaterniond rot(double angle, const Vector3d& axis) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

/// Whether f throws a drape::Error whose message contains `what`.
template <class F> bool throwsWith(F f, const std::string& what) {
  try {
    f();
  } catch (const Error& e) {
    return std::string(e.what()).find(what) != std::string::npos;
  }
  return false;
}

Manifold contactOf(const RigidShape& a, const Pose& pa, const RigidShape& b, const Pose& pb, bool& hit) {
  Manifold m;
  hit = collide(a, pa.rotation.toRotationMatrix(), pa.position, b, pb.rotation.toRotationMatrix(), pb.position, 0.01, m);
  return m;
}

Manifold groundContactOf(const RigidShape& s, const Pose& p, bool& hit) {
  Manifold m;
  hit = collideGround(s, p.rotation.toRotationMatrix(), p.position, 0.0, 0.01, m);
  return m;
}

std::vector<Vector3d> boxCorners(const Vector3d& h) {
  std::vector<Vector3d> p;
  for (int i = 0; i < 8; ++i) p.emplace_back((i & 1 ? 1 : -1) * h.x(), (i & 2 ? 1 : -1) * h.y(), (i & 4 ? 1 : -1) * h.z());
  return p;
}

}  // namespace

// --- Shapes and mass properties ----------------------------------------------------------------------------------

TEST_CASE("a hull of a box's corners has the box's volume and inertia", "[rigid]") {
  const Vector3d h(0.3, 0.5, 0.9);
  auto pts = boxCorners(h);
  for (auto& p : pts) p += Vector3d(1, -2, 3);  // off the origin: the hull recentres itself
  const ConvexHull hull(pts);
  CHECK(hull.shift().isApprox(Vector3d(1, -2, 3), 1e-12));
  CHECK(hull.vertices().size() == 8);
  CHECK(hull.faces().size() == 6);  // coplanar triangles merged
  const MassProperties a = massFromDensity(hull, 700), b = massFromDensity(Box{h}, 700);
  CHECK(a.mass == Approx(b.mass).epsilon(1e-12));
  CHECK((a.inertia - b.inertia).norm() <= 1e-12 * b.inertia.norm());
}

TEST_CASE("hulls of dense point samples approach the analytic sphere, cylinder and capsule", "[rigid]") {
  // A hull of points on the surface is inscribed: its volume and inertia fall short by O(spacing^2).
  // 40 x 80 samples per surface leave under 1 % (measured: see the CHECKs).
  auto sampleCylinder = [](double r, double hh, bool capsule) {
    std::vector<Vector3d> p;
    const int nu = 80, nv = 40;
    for (int i = 0; i < nu; ++i) {
      const double a = 2 * std::numbers::pi * i / nu;
      for (int j = 0; j <= nv; ++j) {
        if (!capsule) {
          p.emplace_back(r * std::cos(a), r * std::sin(a), -hh + 2 * hh * j / nv);
        } else {
          const double t = std::numbers::pi * j / nv - std::numbers::pi / 2;  // latitude
          const double z = r * std::sin(t) + (t >= 0 ? hh : -hh);
          p.emplace_back(r * std::cos(t) * std::cos(a), r * std::cos(t) * std::sin(a), z);
        }
      }
    }
    if (capsule) p.emplace_back(0, 0, hh + r), p.emplace_back(0, 0, -hh - r);
    return p;
  };
  const double r = 0.4, hh = 0.7;
  for (bool capsule : {false, true}) {
    CAPTURE(capsule);
    const ConvexHull hull(sampleCylinder(r, hh, capsule));
    const RigidShape exact = capsule ? RigidShape(Capsule{r, hh}) : RigidShape(Cylinder{r, hh});
    const MassProperties a = massFromDensity(hull, 1), b = massFromDensity(exact, 1);
    CHECK(a.mass == Approx(b.mass).epsilon(0.01));
    for (int k = 0; k < 3; ++k) CHECK(a.inertia(k, k) == Approx(b.inertia(k, k)).epsilon(0.01));
  }
  std::vector<Vector3d> sphere;
  for (int i = 0; i < 80; ++i)
    for (int j = 0; j <= 40; ++j) {
      const double a = 2 * std::numbers::pi * i / 80, t = std::numbers::pi * j / 40 - std::numbers::pi / 2;
      sphere.emplace_back(0.5 * std::cos(t) * std::cos(a), 0.5 * std::cos(t) * std::sin(a), 0.5 * std::sin(t));
    }
  const MassProperties a = massFromDensity(ConvexHull(sphere), 1), b = massFromDensity(Sphere{0.5}, 1);
  CHECK(a.mass == Approx(b.mass).epsilon(0.01));
  CHECK(a.inertia(0, 0) == Approx(b.inertia(0, 0)).epsilon(0.01));
}

TEST_CASE("bad shapes, masses, inertias and states are rejected, naming what is wrong", "[rigid]") {
  CHECK(throwsWith([] { RigidBody b(BodyDesc{Sphere{-1}}); }, "sphere radius"));
  CHECK(throwsWith([] { RigidBody b(BodyDesc{Box{Vector3d(1, 0, 1)}}); }, "box half extents"));
  CHECK(throwsWith([] { RigidBody b(BodyDesc{Capsule{0.1, NAN}}); }, "capsule halfHeight"));
  CHECK(throwsWith([] { RigidBody b(BodyDesc{Cylinder{0, 1}}); }, "cylinder radius"));
  CHECK(throwsWith([] { ConvexHull h({Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(1, 1, 0)}); },
                   "coplanar"));
  CHECK(throwsWith([] { ConvexHull h({Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(2, 0, 0), Vector3d(3, 0, 0)}); },
                   "collinear"));
  CHECK(throwsWith([] { ConvexHull h({Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)}); }, "at least 4"));
  CHECK(throwsWith([] { ConvexHull h({Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0, 0, 1e300)}); },
                   "within 1e5 m"));
  CHECK(throwsWith([] { RigidBody b(BodyDesc{Sphere{1e300}}); }, "sphere radius"));
  CHECK(throwsWith([] { massFromDensity(Sphere{}, 0); }, "density"));
  CHECK(throwsWith([] { massFromMass(Sphere{}, -2); }, "mass must be positive"));
  BodyDesc d{Box{}};
  d.mass = MassProperties{1, Vector3d(1, 1, 3).asDiagonal()};  // 3 > 1 + 1
  CHECK(throwsWith([&] { RigidBody b(d); }, "triangle inequality"));
  d.mass = MassProperties{1, Vector3d(1, -1, 1).asDiagonal()};
  CHECK(throwsWith([&] { RigidBody b(d); }, "positive definite"));
  Eigen::Matrix3d asym = Eigen::Matrix3d::Identity();
  asym(0, 1) = 0.1;
  d.mass = MassProperties{1, asym};
  CHECK(throwsWith([&] { RigidBody b(d); }, "symmetric"));
  d.mass = MassProperties{0, Eigen::Matrix3d::Identity()};
  CHECK(throwsWith([&] { RigidBody b(d); }, "mass must be positive"));
  d.mass.reset();
  d.pose.rotation.coeffs() << 0.5, 0, 0, 1;
  CHECK(throwsWith([&] { RigidBody b(d); }, "unit quaternion"));
  d.pose = Pose{};
  d.linearVelocity.x() = NAN;
  CHECK(throwsWith([&] { RigidBody b(d); }, "linear velocity"));
  d.linearVelocity.setZero();
  d.restitution = 2;
  CHECK(throwsWith([&] { RigidBody b(d); }, "restitution"));

  // A world refuses to step a body made bad after it was added, and changes nothing.
  RigidWorld world;
  world.add(BodyDesc{Sphere{0.5}, at(Vector3d(0, 0, 2))});
  const int bad = world.add(BodyDesc{Sphere{0.5}, at(Vector3d(3, 0, 2))});
  world.body(bad).state.angularVelocity.y() = INFINITY;
  CHECK(throwsWith([&] { world.step(0.01); }, "body 1: angular velocity"));
  CHECK(world.body(0).state.pose.position == Vector3d(0, 0, 2));
  CHECK(world.body(0).state.linearVelocity == Vector3d::Zero());
  world.body(bad).state.angularVelocity.setZero();
  world.body(bad).state.pose.rotation.coeffs() *= 1.01;
  CHECK(throwsWith([&] { world.subStep(0.01); }, "body 1: rotation must be a unit quaternion"));
  CHECK(throwsWith([&] { world.body(0).applyForceAtPoint(Vector3d(NAN, 0, 0), Vector3d::Zero()); }, "force must be finite"));
  CHECK(world.body(0).accumulatedForce() == Vector3d::Zero());
  CHECK(throwsWith([&] { world.step(-1); }, "dt must be positive"));
  RigidSettings s;
  s.subStepCount = 0;
  CHECK(throwsWith([&] { RigidWorld w(s); }, "subStepCount"));
}

// --- Narrow phase through libccd against analytic contacts -------------------------------------------------------

TEST_CASE("libccd contacts match analytic depth and normal", "[rigid]") {
  // libccd's MPR stops when the portal is within 1e-10 m of the surface (drape sets mpr_tolerance); the manifold's
  // depths are then recomputed from the supporting features. 1e-8 m and 1e-8 rad leave room for rounding.
  constexpr double kTol = 1e-8;
  bool hit = false;
  SECTION("sphere-sphere") {
    const Vector3d c1(0.1, -0.2, 0.3), dir = Vector3d(1, 2, -0.5).normalized();
    const Vector3d c2 = c1 + 0.75 * dir;  // radii 0.5 and 0.4: depth 0.15
    const Manifold m = contactOf(Sphere{0.5}, at(c1), Sphere{0.4}, at(c2), hit);
    REQUIRE(hit);
    REQUIRE(m.count == 1);
    CHECK((m.normal - dir).norm() < kTol);
    CHECK(m.points[0].depth == Approx(0.15).margin(kTol));
    CHECK((m.points[0].pointA - (c1 + 0.5 * dir)).norm() < kTol);
    CHECK((m.points[0].pointB - (c2 - 0.4 * dir)).norm() < kTol);
    CHECK_FALSE(contactOf(Sphere{0.5}, at(c1), Sphere{0.4}, at(c1 + 0.91 * dir), hit).count > 10);
    CHECK_FALSE(hit);
  }
  SECTION("sphere-ground") {
    const Manifold m = groundContactOf(Sphere{0.5}, at(Vector3d(3, -7, 0.46)), hit);
    REQUIRE(hit);
    REQUIRE(m.count == 1);
    CHECK((m.normal - Vector3d::UnitZ()).norm() < kTol);
    CHECK(m.points[0].depth == Approx(0.04).margin(kTol));
    CHECK((m.points[0].pointB - Vector3d(3, -7, -0.04)).norm() < kTol);
    groundContactOf(Sphere{0.5}, at(Vector3d(3, -7, 0.51)), hit);
    CHECK_FALSE(hit);
  }
  SECTION("box-ground, flat and turned about z: four corners at the same depth") {
    const Vector3d h(0.4, 0.25, 0.1);
    const Manifold m = groundContactOf(Box{h}, at(Vector3d(1, 2, 0.097), rot(0.7, Vector3d::UnitZ())), hit);
    REQUIRE(hit);
    CHECK((m.normal - Vector3d::UnitZ()).norm() < kTol);
    REQUIRE(m.count == 4);
    for (int i = 0; i < 4; ++i) {
      CHECK(m.points[i].depth == Approx(0.003).margin(kTol));
      CHECK(m.points[i].pointB.z() == Approx(-0.003).margin(kTol));
      CHECK(m.points[i].pointA.z() == Approx(0).margin(kTol));
    }
  }
  SECTION("box-ground, tilted onto one edge") {
    const Vector3d h(0.4, 0.25, 0.1);
    const double tilt = 0.3;  // about x: the lowest edge is at z = -(h.y sin + h.z cos)
    const double low = h.y() * std::sin(tilt) + h.z() * std::cos(tilt);
    const Manifold m = groundContactOf(Box{h}, at(Vector3d(0, 0, low - 0.002), rot(tilt, Vector3d::UnitX())), hit);
    REQUIRE(hit);
    CHECK((m.normal - Vector3d::UnitZ()).norm() < kTol);
    CHECK(m.count == 2);
    for (int i = 0; i < m.count; ++i) CHECK(m.points[i].depth == Approx(0.002).margin(kTol));
  }
  SECTION("box-box face to face") {
    const Vector3d h(0.5, 0.5, 0.5);
    const Manifold m = contactOf(Box{h}, at(Vector3d::Zero()), Box{Vector3d(0.2, 0.2, 0.2)},
                                 at(Vector3d(0.1, -0.1, 0.69), rot(0.3, Vector3d::UnitZ())), hit);
    REQUIRE(hit);
    CHECK((m.normal - Vector3d::UnitZ()).norm() < kTol);
    CHECK(m.count == 4);
    for (int i = 0; i < m.count; ++i) CHECK(m.points[i].depth == Approx(0.01).margin(kTol));
    // The other way round the reference face is the upper box's: depths must not change sign.
    const Manifold r = contactOf(Box{Vector3d(0.2, 0.2, 0.2)}, at(Vector3d(0.1, -0.1, -0.69), rot(0.3, Vector3d::UnitZ())),
                                 Box{h}, at(Vector3d::Zero()), hit);
    REQUIRE(hit);
    CHECK((r.normal - Vector3d::UnitZ()).norm() < kTol);
    CHECK(r.count == 4);
    for (int i = 0; i < r.count; ++i) {
      CHECK(r.points[i].depth == Approx(0.01).margin(kTol));
      CHECK(r.points[i].pointA.z() == Approx(-0.49).margin(kTol));
      CHECK(r.points[i].pointB.z() == Approx(-0.5).margin(kTol));
    }
  }
  SECTION("capsule lying on the ground, cylinder standing and lying, hull") {
    Manifold m = groundContactOf(Capsule{0.1, 0.5}, at(Vector3d(0, 0, 0.095), rot(std::numbers::pi / 2, Vector3d::UnitY())), hit);
    REQUIRE(hit);
    CHECK(m.count == 2);
    for (int i = 0; i < m.count; ++i) CHECK(m.points[i].depth == Approx(0.005).margin(kTol));
    m = groundContactOf(Cylinder{0.3, 0.2}, at(Vector3d(0, 0, 0.199)), hit);
    REQUIRE(hit);
    CHECK(m.count == 4);  // the cap's octagon, reduced to four
    for (int i = 0; i < m.count; ++i) CHECK(m.points[i].depth == Approx(0.001).margin(kTol));
    m = groundContactOf(Cylinder{0.3, 0.2}, at(Vector3d(0, 0, 0.299), rot(std::numbers::pi / 2, Vector3d::UnitX())), hit);
    REQUIRE(hit);
    CHECK(m.count == 2);
    for (int i = 0; i < m.count; ++i) CHECK(m.points[i].depth == Approx(0.001).margin(kTol));
    const ConvexHull tetra({Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0, 0, 1)});
    // The tetrahedron's centre of mass is (1/4, 1/4, 1/4) of the input frame; put its base 0.01 under ground.
    m = groundContactOf(tetra, at(Vector3d(0, 0, 0.25 - 0.01)), hit);
    REQUIRE(hit);
    CHECK(m.count == 3);
    for (int i = 0; i < m.count; ++i) CHECK(m.points[i].depth == Approx(0.01).margin(kTol));
  }
}

namespace {

/// Brute force: the smallest overlap of the two shapes' extents over n directions spread evenly on the sphere
/// (a Fibonacci lattice), max_A(d) - min_B(d) minimised over d. The true penetration depth is the minimum over all
/// directions, so this is an upper bound on it, tight to O(size / n) for these small shapes; negative when a
/// sampled direction separates the shapes.
double overlapUpperBound(const RigidShape& a, const Eigen::Matrix3d& Ra, const Vector3d& xa, const RigidShape& b,
                         const Eigen::Matrix3d& Rb, const Vector3d& xb, int n) {
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  double best = INFINITY;
  for (int k = 0; k < n; ++k) {
    const double z = 1 - (k + 0.5) * 2.0 / n, r = std::sqrt(1 - z * z);
    const Vector3d d(r * std::cos(golden * k), r * std::sin(golden * k), z);
    const double maxA = (Ra * detail::supportLocal(a, Ra.transpose() * d) + xa).dot(d);
    const double minB = (Rb * detail::supportLocal(b, -(Rb.transpose() * d)) + xb).dot(d);
    best = std::min(best, maxA - minB);
  }
  return best;
}

}  // namespace

TEST_CASE("contact depths never exceed the shapes' overlap where MPR's normal is poor", "[rigid]") {
  auto deepest = [](const Manifold& m) {
    double d = -INFINITY;
    for (int i = 0; i < m.count; ++i) d = std::max(d, m.points[i].depth);
    return d;
  };
  SECTION("two cylinders of the rigid rain that MPR said just touch") {
    // Found in the rain (seed 42, step 90): MPR stopped on a degenerate portal with depth 0, and the supporting
    // features along its normal overlapped by 4.4 cm, which the world resolved in one substep and spun the small
    // cylinder to 566 rad/s.
    const Cylinder small{0.012860488727351412, 0.015575565016610195}, large{0.036962888929463866, 0.025950541393204025};
    const Eigen::Quaterniond qa(0.3112979675672744, 0.27243130501254403, -0.73819342310531022, -0.53286511381559865);
    const Eigen::Quaterniond qb(0.75384564951913358, -0.083004024727620626, 0.44630719741088587, 0.47501258311684014);
    const Vector3d xa(0.18183166412671151, 0.39971787982163404, 0.064676029787391662);
    const Vector3d xb(0.11702306261522749, 0.40601089279156793, 0.060605131068567068);
    const Eigen::Matrix3d Ra = qa.normalized().toRotationMatrix(), Rb = qb.normalized().toRotationMatrix();
    const double bound = overlapUpperBound(small, Ra, xa, large, Rb, xb, 20000);
    Manifold m;
    if (collide(small, Ra, xa, large, Rb, xb, 0.01, m)) {
      INFO("deepest point " << deepest(m) << " m, brute-force overlap at most " << bound << " m");
      CHECK(deepest(m) <= std::max(bound, 0.0) + 1e-6);
    }
  }
  SECTION("random pairs of small shapes: never deeper than MPR's depth, rarely far above the true one") {
    // Rain-sized shapes (3-8 cm) at random poses, centres 0.3-1 times the sum of their bounding radii apart.
    // MPR's normal is not the minimum-depth direction, so its depth may exceed the true one: measured, 4 of the
    // 2704 overlapping pairs exceed 1.5 times the brute-force bound plus 1 mm (46 before the manifold was held to
    // MPR's depth). Apart pairs (a sampled direction separates them) get no positive depth.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    auto direction = [&] {
      const double z = 2 * u(rng) - 1, phi = 2 * std::numbers::pi * u(rng), r = std::sqrt(1 - z * z);
      return Vector3d(r * std::cos(phi), r * std::sin(phi), z);
    };
    auto shape = [&]() -> RigidShape {
      const double h = 0.5 * (0.03 + 0.05 * u(rng));
      switch (rng() % 5) {
        case 0: return Sphere{h};
        case 1: return Box{Vector3d(h, h * (0.5 + 0.5 * u(rng)), h * (0.5 + 0.5 * u(rng)))};
        case 2: {
          const double r = h * (0.35 + 0.25 * u(rng));
          return Capsule{r, h - r};
        }
        case 3: return Cylinder{h * (0.5 + 0.5 * u(rng)), h};
        default: {
          std::vector<Vector3d> p;
          for (int k = 0; k < 12; ++k) p.push_back(h * (0.6 + 0.4 * u(rng)) * direction());
          return ConvexHull(p);
        }
      }
    };
    int overlapping = 0, far = 0, apartWithDepth = 0;
    for (int t = 0; t < 4000; ++t) {
      const RigidShape a = shape(), b = shape();
      const Eigen::Matrix3d Ra = rot(2 * std::numbers::pi * u(rng), direction()).toRotationMatrix();
      const Eigen::Matrix3d Rb = rot(2 * std::numbers::pi * u(rng), direction()).toRotationMatrix();
      const Vector3d xa = Vector3d::Zero();
      const Vector3d xb = (0.3 + 0.7 * u(rng)) * (detail::boundingRadius(a) + detail::boundingRadius(b)) * direction();
      Manifold m;
      if (!collide(a, Ra, xa, b, Rb, xb, 0.01, m)) continue;
      CHECK(deepest(m) <= std::max(m.ccdDepth, 0.0) + 1e-12);
      const double bound = overlapUpperBound(a, Ra, xa, b, Rb, xb, 2000);
      if (bound < -1e-6) {
        apartWithDepth += deepest(m) > 1e-6;
      } else {
        ++overlapping;
        far += deepest(m) > 1.5 * std::max(bound, 0.0) + 1e-3;
      }
    }
    INFO(far << " of " << overlapping << " overlapping pairs deeper than 1.5 x the brute-force bound + 1 mm");
    CHECK(overlapping > 2000);
    CHECK(far <= overlapping / 200);  // 0.5 %
    CHECK(apartWithDepth == 0);
  }
}

// --- Broad phase ---------------------------------------------------------------------------------------------------

TEST_CASE("sweep and prune finds exactly the pairs brute force finds", "[rigid]") {
  std::mt19937 rng(7);
  SweepAndPrune sap;
  std::vector<std::pair<int, int>> pairs;
  for (int scene = 0; scene < 40; ++scene) {
    const int n = 1 + scene * 7;
    const double spread = 0.5 + scene % 5;  // dense to sparse
    std::uniform_real_distribution<double> pos(-spread, spread), size(0.01, 0.6);
    std::vector<Aabb> boxes(n);
    for (auto& b : boxes) {
      const Vector3d c(pos(rng), pos(rng), 0.2 * pos(rng));  // flat: the sweep axis is x or y
      const Vector3d e(size(rng), size(rng), size(rng));
      b = {c - e, c + e};
    }
    if (scene % 3 == 0) boxes[0] = boxes[n - 1];  // identical boxes overlap
    for (int pass = 0; pass < 3; ++pass) {  // the kept order of the previous pass must not matter
      sap.findPairs(boxes, pairs);
      CAPTURE(scene, pass, n);
      REQUIRE(pairs == bruteForcePairs(boxes));
      for (auto& b : boxes) {
        const Vector3d move(0.1 * pos(rng), 0.1 * pos(rng), 0.1 * pos(rng));
        b.min += move, b.max += move;
      }
    }
  }
}

// --- Integration ---------------------------------------------------------------------------------------------------

TEST_CASE("free fall follows the analytic trajectory", "[rigid]") {
  // Symplectic Euler in substeps h: v_n = v0 + g t exactly, x_n = x0 + v0 t + g t^2 / 2 + g h t / 2. The last
  // term is the scheme's first-order error; halving h halves it.
  for (int subSteps : {10, 20}) {
    RigidSettings s;
    s.ground = false;
    s.subStepCount = subSteps;
    RigidWorld world(s);
    const Vector3d x0(1, 2, 100), v0(0.5, -1, 3);
    BodyDesc d{Box{Vector3d(0.1, 0.2, 0.3)}, at(x0)};
    d.linearVelocity = v0;
    world.add(d);
    const double dt = 1.0 / 60;
    const int frames = 120;
    for (int f = 0; f < frames; ++f) world.step(dt);
    const double t = frames * dt, h = dt / subSteps;
    const Vector3d g = s.gravity;
    const Vector3d exact = x0 + v0 * t + 0.5 * g * t * t;
    const Vector3d& x = world.body(0).state.pose.position;
    CAPTURE(subSteps, (x - exact).transpose());
    CHECK((world.body(0).state.linearVelocity - (v0 + g * t)).norm() < 1e-12);
    CHECK((x - (exact + 0.5 * g * h * t)).norm() < 1e-10);
    CHECK((x - exact).norm() <= 0.5 * g.norm() * h * t * (1 + 1e-9));
    CHECK(world.body(0).state.angularVelocity == Vector3d::Zero());
  }
}

TEST_CASE("a torque-free spinning asymmetric body keeps its angular momentum and kinetic energy", "[rigid]") {
  // Implicit midpoint on Euler's equations keeps w.Iw and |Iw| in the body frame to the Newton tolerance; the
  // world angular momentum R I w also depends on the orientation update, whose error is O(h^2) per unit time.
  RigidSettings s;
  s.ground = false;
  s.gravity.setZero();
  RigidWorld world(s);
  BodyDesc d{Box{Vector3d(0.1, 0.25, 0.45)}, at(Vector3d::Zero(), rot(0.4, Vector3d(1, 2, 3)))};
  d.angularVelocity = Vector3d(0.3, 6, 0.4);  // about the intermediate axis, perturbed: it tumbles
  world.add(d);
  const Vector3d L0 = world.angularMomentum();
  const double E0 = world.kineticEnergy();
  double maxL = 0, maxE = 0;
  Vector3d wBody0 = world.body(0).state.pose.rotation.conjugate() * world.body(0).state.angularVelocity;
  double minW = INFINITY, maxW = 0;
  for (int f = 0; f < 600; ++f) {  // 10 s at 60 Hz, 10 substeps
    world.step(1.0 / 60);
    maxL = std::max(maxL, (world.angularMomentum() - L0).norm() / L0.norm());
    maxE = std::max(maxE, std::abs(world.kineticEnergy() - E0) / E0);
    const Vector3d wb = world.body(0).state.pose.rotation.conjugate() * world.body(0).state.angularVelocity;
    minW = std::min(minW, wb.y() / wBody0.y()), maxW = std::max(maxW, wb.y() / wBody0.y());
  }
  WARN("spin: max relative drift of L " << maxL << ", of E " << maxE << "; w_y/w_y0 in [" << minW << ", " << maxW << "]");
  CHECK(minW < 0);  // it really tumbled (the intermediate axis flips)
  CHECK(maxE < 1e-9);
  CHECK(maxL < 1e-4);
}

TEST_CASE("applyForceAtPoint gives the analytic linear and angular acceleration", "[rigid]") {
  RigidSettings s;
  s.ground = false;
  s.gravity.setZero();
  RigidWorld world(s);
  world.add(BodyDesc{Box{Vector3d(0.2, 0.3, 0.5)}, at(Vector3d(1, 2, 3), rot(0.8, Vector3d(1, -1, 2)))});
  RigidBody& b = world.body(0);
  CoupledBody& coupled = b;  // through the coupling interface
  const Vector3d F(3, -1, 2), p = Vector3d(1, 2, 3) + Vector3d(0.1, 0.25, -0.4);
  const Vector3d alpha = coupled.inverseInertiaWorld() * ((p - coupled.pose().position).cross(F));
  const Vector3d a = coupled.inverseMass() * F;
  coupled.applyForceAtPoint(F, p);
  const double h = 1e-5;
  world.subStep(h);
  // Starting from rest the midpoint rule's gyroscopic term is O(h) relative to alpha.
  CHECK((b.state.linearVelocity / h - a).norm() < 1e-9 * a.norm());
  CHECK((b.state.angularVelocity / h - alpha).norm() < 1e-4 * alpha.norm());
  CHECK(b.accumulatedForce() == Vector3d::Zero());  // consumed by the substep
}

// --- Contacts ------------------------------------------------------------------------------------------------------

TEST_CASE("two bodies colliding without gravity or ground conserve linear and angular momentum", "[rigid]") {
  // Every contact correction is an equal and opposite pair of impulses on the line of the normal through
  // the two contact points, so the linear momentum is kept to rounding. The angular momentum about a point is
  // kept up to the lever arm between the two bodies' contact points (they are on one normal line when
  // detected, and drift apart by the in-substep motion), the O(h^2) rotation update, and the position-only
  // corrections (static friction's hold moves a body without changing its momentum p, which changes x × p).
  // Measured: at most 1.3e-3 of |L0| over the three restitutions.
  for (double restitution : {0.0, 0.5, 1.0}) {
    RigidSettings s;
    s.ground = false;
    s.gravity.setZero();
    RigidWorld world(s);
    BodyDesc a{Box{Vector3d(0.3, 0.2, 0.25)}, at(Vector3d(-1, 0.05, 0), rot(0.3, Vector3d(0, 1, 1)))};
    a.linearVelocity = Vector3d(2, 0, 0.1);
    a.angularVelocity = Vector3d(0, 1, -2);
    a.restitution = restitution;
    std::vector<Vector3d> pts;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.3, 0.3);
    for (int i = 0; i < 20; ++i) pts.emplace_back(u(rng), u(rng), u(rng));
    BodyDesc b{ConvexHull(pts), at(Vector3d(0.5, -0.1, 0.1))};
    b.linearVelocity = Vector3d(-1, 0.2, 0);
    b.angularVelocity = Vector3d(3, 0, 1);
    b.density = 500;
    b.restitution = restitution;
    world.add(a);
    world.add(b);
    const Vector3d P0 = world.linearMomentum(), L0 = world.angularMomentum(Vector3d(0.3, -0.2, 0.1));
    const double E0 = world.kineticEnergy();
    double maxP = 0, maxL = 0, maxE = 0;
    for (int f = 0; f < 90; ++f) {
      world.step(1.0 / 60);
      maxP = std::max(maxP, (world.linearMomentum() - P0).norm() / P0.norm());
      maxL = std::max(maxL, (world.angularMomentum(Vector3d(0.3, -0.2, 0.1)) - L0).norm() / L0.norm());
      maxE = std::max(maxE, (world.kineticEnergy() - E0) / E0);
    }
    WARN("collision e=" << restitution << ": max relative drift of P " << maxP << ", of L " << maxL
                        << ", energy gain " << maxE << ", final energy / initial " << world.kineticEnergy() / E0);
    CHECK((world.body(1).state.linearVelocity - Vector3d(-1, 0.2, 0)).norm() > 0.5);  // they did collide
    CHECK(maxP < 1e-12);
    CHECK(maxL < 5e-3);
    CHECK(maxE < 1e-3);  // no contact creates energy beyond the O(h) of the position projection
  }
}

TEST_CASE("a box dropped on the ground comes to rest without jitter or sinking", "[rigid]") {
  RigidWorld world;
  const Vector3d h(0.3, 0.2, 0.1);
  world.add(BodyDesc{Box{h}, at(Vector3d(0, 0, 0.5), rot(0.2, Vector3d(1, 2, 0)))});
  double maxSpeed = 0, maxSpin = 0, maxPenetration = 0;
  for (int f = 0; f < 240; ++f) {  // 4 s at 60 Hz
    world.step(1.0 / 60);
    const BodyState& st = world.body(0).state;
    const Eigen::Matrix3d R = st.pose.rotation.toRotationMatrix();
    const double lowest = st.pose.position.z() - (R.cwiseAbs() * h).z();
    if (f >= 180) {  // the last second
      maxSpeed = std::max(maxSpeed, st.linearVelocity.norm());
      maxSpin = std::max(maxSpin, st.angularVelocity.norm());
      maxPenetration = std::max(maxPenetration, -lowest);
    }
  }
  WARN("resting box, last second: max speed " << maxSpeed << " m/s, max spin " << maxSpin << " rad/s, max penetration "
                                              << maxPenetration << " m");
  CHECK(maxSpeed < 1e-3);
  CHECK(maxSpin < 1e-3);
  CHECK(maxPenetration < 1e-4);
  CHECK(world.body(0).state.pose.position.z() == Approx(h.z()).margin(1e-4));
}

TEST_CASE("a stack of three boxes stays stacked", "[rigid]") {
  RigidWorld world;
  const Vector3d h(0.25, 0.25, 0.25);
  for (int i = 0; i < 3; ++i)
    world.add(BodyDesc{Box{h}, at(Vector3d(0.01 * i, -0.01 * i, h.z() + 2 * h.z() * i + 0.001 * i), rot(0.05 * i, Vector3d::UnitZ()))});
  double maxSpeed = 0;
  for (int f = 0; f < 300; ++f) {  // 5 s
    world.step(1.0 / 60);
    if (f >= 240)
      for (int i = 0; i < 3; ++i) maxSpeed = std::max(maxSpeed, world.body(i).state.linearVelocity.norm());
  }
  double maxDrift = 0, maxHeightError = 0;
  for (int i = 0; i < 3; ++i) {
    const Vector3d x = world.body(i).state.pose.position;
    maxDrift = std::max(maxDrift, (x.head<2>() - Eigen::Vector2d(0.01 * i, -0.01 * i)).norm());
    maxHeightError = std::max(maxHeightError, std::abs(x.z() - (h.z() + 2 * h.z() * i)));
  }
  WARN("stack: max speed over the last second " << maxSpeed << " m/s, horizontal drift " << maxDrift
                                                << " m, height error " << maxHeightError << " m");
  CHECK(maxSpeed < 1e-3);
  CHECK(maxDrift < 1e-3);
  CHECK(maxHeightError < 1e-3);
}

TEST_CASE("a spacer holds a body pressed by another off the ground, for its life, and bad ones are refused",
          "[rigid]") {
  // A light box under a heavy one, each substep given a spacer that keeps its bottom 1 cm off the ground (what a
  // cloth pinched under it passes, RigidWorld::addSpacer): the pair's contact pushes the light box down in the
  // solve, and the spacer, solved after the world's own contacts, lifts it back within the substep.
  const Vector3d lowHalf(0.02, 0.02, 0.01), topHalf(0.02, 0.02, 0.02);
  const double lift = 0.01;
  auto scene = [&](RigidWorld& world) {
    BodyDesc low{Box{lowHalf}, at(Vector3d(0, 0, lift + lowHalf.z()))};
    low.density = 600;
    BodyDesc top{Box{topHalf}, at(Vector3d(0, 0, lift + 2 * lowHalf.z() + topHalf.z() + 0.1))};
    top.density = 2000;
    world.add(low);
    world.add(top);
  };
  // The four bottom corners of the light box, each its own spacer (tag k).
  auto hold = [&](RigidWorld& world) {
    for (int k = 0; k < 4; ++k) {
      const Vector3d corner((k & 1) ? lowHalf.x() : -lowHalf.x(), (k & 2) ? lowHalf.y() : -lowHalf.y(), -lowHalf.z());
      const Vector3d below = world.body(0).pose().apply(corner);
      const Vector3d on(below.x(), below.y(), lift);
      world.addSpacer(k, RigidWorld::kGround, on, 0, corner, Vector3d::UnitZ(), 0.005);
    }
  };
  RigidWorld held, bare;
  scene(held);
  scene(bare);
  double lowestHeld = 1, lowestBare = 1;
  for (int s = 0; s < 1000; ++s) {  // 1 s
    hold(held);
    held.subStep(0.001);
    bare.subStep(0.001);
    lowestHeld = std::min(lowestHeld, held.body(0).pose().position.z() - lowHalf.z());
    lowestBare = std::min(lowestBare, bare.body(0).pose().position.z() - lowHalf.z());
  }
  INFO("the light box's lowest bottom: " << lowestHeld << " m held, " << lowestBare << " m on its own");
  CHECK(lowestBare < 0.002);            // premise: with nothing under it the box falls to the ground
  CHECK(lowestHeld >= lift - 5e-4);  // one pass over the four points leaves a residual
  CHECK(held.body(0).pose().position.z() - lowHalf.z() <= lift + 1e-4);  // and resting on it
  int spacers = 0;
  for (const RigidContact& c : held.contacts()) spacers += c.spacer ? 1 : 0;
  CHECK(spacers == 4);
  CHECK(held.spacers().size() == 4);

  // Not given again, the spacers still hold for their life, then are dropped and the box falls.
  for (int s = 0; s < RigidWorld::kSpacerLife - 1; ++s) held.subStep(0.001);
  CHECK(held.spacers().size() == 4);
  CHECK(held.body(0).pose().position.z() - lowHalf.z() >= lift - 2e-4);
  for (int s = 0; s < 200; ++s) held.subStep(0.001);
  CHECK(held.spacers().empty());
  CHECK(held.body(0).pose().position.z() - lowHalf.z() < 0.002);

  // A spacer whose body has moved beyond its reach is dropped at once.
  RigidWorld far;
  scene(far);
  far.addSpacer(7, RigidWorld::kGround, Vector3d(0, 0, -0.02), 0, Vector3d(0, 0, -lowHalf.z()), Vector3d::UnitZ(),
                0.005);
  far.subStep(0.001);
  CHECK(far.spacers().empty());

  RigidWorld world;
  scene(world);
  BodyDesc kinematic{Box{lowHalf}, at(Vector3d(1, 0, 1))};
  kinematic.motion = BodyMotion::Kinematic;
  const int fixed = world.add(kinematic);
  const Vector3d p = Vector3d::Zero(), n = Vector3d::UnitZ();
  CHECK(throwsWith([&] { world.addSpacer(0, 5, p, 0, p, n, 0.01); }, "first body index 5 out of range"));
  CHECK(throwsWith([&] { world.addSpacer(0, RigidWorld::kGround, p, 9, p, n, 0.01); }, "second body index 9"));
  CHECK(throwsWith([&] { world.addSpacer(0, 0, p, 0, p, n, 0.01); }, "second body index 0"));
  CHECK(throwsWith([&] { world.addSpacer(0, RigidWorld::kGround, p, fixed, p, n, 0.01); }, "is not dynamic"));
  CHECK(throwsWith([&] { world.addSpacer(0, 1, Vector3d(NAN, 0, 0), 0, p, n, 0.01); }, "points must be finite"));
  CHECK(throwsWith([&] { world.addSpacer(0, 1, p, 0, p, 2 * n, 0.01); }, "normal must be unit"));
  CHECK(throwsWith([&] { world.addSpacer(0, 1, p, 0, p, n, 0); }, "reach must be positive"));
  CHECK(world.spacers().empty());
}

TEST_CASE("a box pushed sideways on the ground obeys Coulomb friction", "[rigid]") {
  // mu = 0.5 for the box and the ground (combined sqrt(a b) = 0.5). Below mu m g it sticks: the static part
  // undoes the substep's tangential displacement, so it must not creep at h F / m per substep. Above, it
  // accelerates at F / m - mu g.
  const double mu = 0.5;
  for (double ratio : {0.5, 0.9, 1.5, 3.0}) {
    RigidSettings s;
    s.groundStaticFriction = s.groundDynamicFriction = mu;
    RigidWorld world(s);
    BodyDesc d{Box{Vector3d(0.2, 0.15, 0.1)}, at(Vector3d(0, 0, 0.1))};
    d.staticFriction = d.dynamicFriction = mu;
    world.add(d);
    RigidBody& b = world.body(0);
    for (int f = 0; f < 60; ++f) world.step(1.0 / 60);  // settle
    const double m = b.massProperties().mass, F = ratio * mu * m * kG;
    const Vector3d x0 = b.state.pose.position;
    double v1 = 0, xHalf = 0;
    const int frames = 120;
    for (int f = 0; f < frames; ++f) {
      b.applyForceAtPoint(Vector3d(F, 0, 0), b.state.pose.position);
      world.step(1.0 / 60);
      if (f == frames / 2 - 1) v1 = b.state.linearVelocity.x(), xHalf = b.state.pose.position.x();
    }
    const double v2 = b.state.linearVelocity.x();
    const double travelled = b.state.pose.position.x() - x0.x();
    if (ratio < 1) {
      // The speed that matters is the mean over the last second; the instantaneous one at the end of a step
      // holds the last substep's friction impulse, applied at the ground below the centre of mass, which
      // tips the box until the next substep's contacts level it (up to h F / m at the centre of mass).
      const double meanSpeed = b.state.pose.position.x() - xHalf;
      WARN("Coulomb F = " << ratio << " mu m g: travelled " << travelled << " m in 2 s, mean speed over the last second "
                          << meanSpeed << " m/s, instantaneous " << v2);
      CHECK(std::abs(travelled) < 1e-6);
      CHECK(std::abs(meanSpeed) < 1e-6);
      CHECK(std::abs(v2) <= ratio * mu * kG / 600 * 1.01);
    } else {
      const double a = (v2 - v1) / (frames / 2 / 60.0), expected = F / m - mu * kG;
      WARN("Coulomb F = " << ratio << " mu m g: acceleration " << a << " m/s^2, expected " << expected);
      CHECK(a == Approx(expected).epsilon(0.01));
    }
    CHECK(std::abs(b.state.pose.position.y() - x0.y()) < 1e-6);  // no sideways drift
  }
}

TEST_CASE("a kinematic body moves by its velocities only and pushes dynamic bodies", "[rigid]") {
  RigidWorld world;
  BodyDesc k{Box{Vector3d(0.5, 0.5, 0.5)}, at(Vector3d(-2, 0, 0.5))};
  k.motion = BodyMotion::Kinematic;
  k.linearVelocity = Vector3d(1, 0, 0);
  k.angularVelocity = Vector3d(0, 0, 0.5);
  const int kin = world.add(k);
  const int ball = world.add(BodyDesc{Sphere{0.3}, at(Vector3d(0, 0.1, 0.3))});
  CHECK(world.body(kin).inverseMass() == 0);
  CHECK(world.body(kin).inverseInertiaWorld() == Eigen::Matrix3d::Zero());
  world.body(kin).applyForceAtPoint(Vector3d(1e6, 0, 0), Vector3d(-2, 0.3, 0.5));  // ignored by a kinematic body
  const double dt = 1.0 / 60;
  bool pushed = false;
  for (int f = 0; f < 180; ++f) {
    world.step(dt);
    pushed = pushed || world.body(ball).state.linearVelocity.x() > 0.5;
  }
  const double t = 180 * dt;
  const RigidBody& kb = world.body(kin);
  CHECK((kb.state.pose.position - Vector3d(-2 + t, 0, 0.5)).norm() < 1e-12);
  CHECK(kb.state.pose.rotation.angularDistance(rot(0.5 * t, Vector3d::UnitZ())) < 1e-9);
  CHECK(kb.state.linearVelocity == Vector3d(1, 0, 0));
  CHECK(pushed);
  CHECK(world.body(ball).state.pose.position.x() > 0.5);
}

TEST_CASE("an application couples through CoupledBody: pose, velocity, mass properties, forces", "[rigid]") {
  // What a cloth solver does each substep, against the interface only.
  RigidSettings s;
  s.ground = false;
  s.gravity.setZero();
  RigidWorld world(s);
  BodyDesc d{Cylinder{0.2, 0.4}, at(Vector3d(0, 0, 1), rot(0.3, Vector3d::UnitX()))};
  d.linearVelocity = Vector3d(0, 1, 0);
  d.angularVelocity = Vector3d(0, 0, 2);
  world.add(d);
  std::vector<CoupledBody*> coupled{&world.body(0)};
  const Vector3d p = coupled[0]->pose().apply(Vector3d(0.2, 0, 0));
  CHECK((coupled[0]->velocityAt(p) - (Vector3d(0, 1, 0) + Vector3d(0, 0, 2).cross(p - Vector3d(0, 0, 1)))).norm() < 1e-12);
  const MassProperties mp = massFromDensity(Cylinder{0.2, 0.4}, 1000);
  CHECK(coupled[0]->inverseMass() == Approx(1 / mp.mass));
  const Eigen::Matrix3d R = rot(0.3, Vector3d::UnitX()).toRotationMatrix();
  CHECK((coupled[0]->inverseInertiaWorld() - R * mp.inertia.inverse() * R.transpose()).norm() < 1e-12);
  // Equal and opposite forces at two points: no net force, a pure torque r x F.
  const Vector3d F(0, 0, 5);
  coupled[0]->applyForceAtPoint(F, Vector3d(0.3, 0, 1));
  coupled[0]->applyForceAtPoint(-F, Vector3d(-0.3, 0, 1));
  CHECK(world.body(0).accumulatedForce().norm() < 1e-12);
  CHECK((world.body(0).accumulatedTorque() - Vector3d(0.6, 0, 0).cross(F)).norm() < 1e-12);
}

}  // namespace rigid_tests
