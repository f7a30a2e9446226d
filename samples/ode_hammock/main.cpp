// drape coupled to the Open Dynamics Engine (the cloth-rigid coupling thesis coupled its cloth to ODE): a cloth
// hung by its whole border is a hammock, and ODE's bodies (a box, a ball and a capsule) drop into it from a few
// centimetres. (Hung by its corners only, or dropped from 15-25 cm, the bodies bounce on the springy cloth and
// a ball rolls about in it freely: whether one left over an edge by 4 s changed with the substep count, so the
// check measured luck.) ODE
// integrates the bodies and resolves their contacts with each other and with the ground; drape moves the cloth,
// resolves cloth-body contacts against each body's distance field and hands the reaction back through
// drape::CoupledBody, which OdeBody implements with ODE's own calls. Nothing of drape's rigid-body code is used.
//
// The sample checks what it shows: once the bodies have landed, the force the cloth passes to them, averaged
// over the rest of the run, balances their weight within 5 %; no body goes through the cloth and the cloth
// never reaches the floor. It exits 1 if not (3 on a non-finite state). The bodies settle slowly (inextensible
// cloth has no damping of its own; 7 mm/s after 5 s, 2 mm/s after 10 s), which averages out of the force.
// --json prints one JSON object on stdout; ODE_TRACE=1 prints the bodies' heights and speeds every 0.1 s.

#include <drape/drape.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace {

using Eigen::Vector3d;

/// An ODE body as drape sees it. ODE keeps the centre of mass at the body's origin, which is what
/// drape::CoupledBody expects; forces go to ODE's accumulators, which its next step applies and clears.
class OdeBody final : public drape::CoupledBody {
 public:
  explicit OdeBody(dBodyID body) : body_(body) {}

  drape::Pose pose() const override {
    const dReal* p = dBodyGetPosition(body_);
    const dReal* q = dBodyGetQuaternion(body_);  // (w, x, y, z)
    drape::Pose out;
    out.position = Vector3d(p[0], p[1], p[2]);
    out.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
    return out;
  }
  Vector3d linearVelocity() const override { return toVector(dBodyGetLinearVel(body_)); }
  Vector3d angularVelocity() const override { return toVector(dBodyGetAngularVel(body_)); }
  double inverseMass() const override {
    dMass m;
    dBodyGetMass(body_, &m);
    return 1.0 / m.mass;
  }
  Eigen::Matrix3d inverseInertiaWorld() const override {
    dMass m;
    dBodyGetMass(body_, &m);
    Eigen::Matrix3d inertia;  // ODE's dMatrix3 is three rows of four
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) inertia(r, c) = m.I[4 * r + c];
    const Eigen::Matrix3d rotation = pose().rotation.toRotationMatrix();
    return rotation * inertia.inverse() * rotation.transpose();
  }
  void applyForceAtPoint(const Vector3d& force, const Vector3d& point) override {
    drape::detail::require(drape::detail::allFinite(force) && drape::detail::allFinite(point),
                           "OdeBody::applyForceAtPoint: force or point not finite");
    dBodyAddForceAtPos(body_, force.x(), force.y(), force.z(), point.x(), point.y(), point.z());
  }
  void applyForceAndTorque(const Vector3d& force, const Vector3d& torque) override {
    drape::detail::require(drape::detail::allFinite(force) && drape::detail::allFinite(torque),
                           "OdeBody::applyForceAndTorque: force or torque not finite");
    dBodyAddForce(body_, force.x(), force.y(), force.z());
    dBodyAddTorque(body_, torque.x(), torque.y(), torque.z());
  }

 private:
  static Vector3d toVector(const dReal* v) { return Vector3d(v[0], v[1], v[2]); }
  dBodyID body_;
};

/// ODE's world: gravity, the ground plane z = 0, a space for collisions and the contact joints of one step.
class OdeWorld {
 public:
  OdeWorld() {
    dInitODE2(0);
    world_ = dWorldCreate();
    dWorldSetGravity(world_, 0, 0, -9.81);
    space_ = dHashSpaceCreate(nullptr);
    contacts_ = dJointGroupCreate(0);
    dCreatePlane(space_, 0, 0, 1, 0);
  }
  ~OdeWorld() {
    dJointGroupDestroy(contacts_);
    dSpaceDestroy(space_);  // destroys its geoms
    dWorldDestroy(world_);  // and its bodies
    dCloseODE();
  }
  OdeWorld(const OdeWorld&) = delete;
  OdeWorld& operator=(const OdeWorld&) = delete;

  /// A body with a box (half extents), sphere (radius) or capsule (radius, half height, along its z) geometry.
  dBodyID addBox(const Vector3d& half, double mass, const drape::Pose& pose) {
    dMass m;
    dMassSetBoxTotal(&m, mass, 2 * half.x(), 2 * half.y(), 2 * half.z());
    return attach(dCreateBox(space_, 2 * half.x(), 2 * half.y(), 2 * half.z()), m, pose);
  }
  dBodyID addSphere(double radius, double mass, const drape::Pose& pose) {
    dMass m;
    dMassSetSphereTotal(&m, mass, radius);
    return attach(dCreateSphere(space_, radius), m, pose);
  }
  dBodyID addCapsule(double radius, double halfHeight, double mass, const drape::Pose& pose) {
    dMass m;
    dMassSetCapsuleTotal(&m, mass, 3, radius, 2 * halfHeight);
    return attach(dCreateCapsule(space_, radius, 2 * halfHeight), m, pose);
  }

  /// One ODE step of h: contacts between bodies and with the ground, then the integration, which applies and
  /// clears the forces the cloth added.
  void step(double h) {
    dSpaceCollide(space_, this, &OdeWorld::nearCallback);
    dWorldStep(world_, h);
    dJointGroupEmpty(contacts_);
  }

 private:
  dBodyID attach(dGeomID geom, const dMass& mass, const drape::Pose& pose) {
    dBodyID body = dBodyCreate(world_);
    dBodySetMass(body, &mass);
    dGeomSetBody(geom, body);
    dBodySetPosition(body, pose.position.x(), pose.position.y(), pose.position.z());
    const dQuaternion q = {pose.rotation.w(), pose.rotation.x(), pose.rotation.y(), pose.rotation.z()};
    dBodySetQuaternion(body, q);
    return body;
  }

  static void nearCallback(void* data, dGeomID a, dGeomID b) {
    auto* self = static_cast<OdeWorld*>(data);
    dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
    if (ba && bb && dAreConnectedExcluding(ba, bb, dJointTypeContact)) return;
    constexpr int kMax = 4;
    dContact contact[kMax];
    std::memset(contact, 0, sizeof contact);
    const int n = dCollide(a, b, kMax, &contact[0].geom, sizeof(dContact));
    for (int i = 0; i < n; ++i) {
      contact[i].surface.mode = dContactSoftERP | dContactSoftCFM;
      contact[i].surface.mu = 0.5;
      contact[i].surface.soft_erp = 0.2;
      contact[i].surface.soft_cfm = 1e-5;
      dJointAttach(dJointCreateContact(self->world_, self->contacts_, &contact[i]), ba, bb);
    }
  }

  dWorldID world_;
  dSpaceID space_;
  dJointGroupID contacts_;
};

struct Options {
  double seconds = 4;       ///< simulated time
  double settle = 1.5;      ///< s before the averages start
  double dt = 0.01;         ///< s per step
  int substeps = 10;
  int iterations = 4;
  int side = 31;            ///< cloth vertices per side (2 cm apart)
  std::string estimator = "impulse";
  bool json = false;
};

template <class S> int run(const Options& o) {
  using Cloth = drape::Solver<S>;  // compiled once for every program of the build (drape_solvers)
  drape::SheetDesc grid;
  grid.nx = grid.ny = o.side;
  grid.spacing = 0.02;
  grid.placement.position = {0, 0, 0.4};
  auto asset = std::make_shared<const drape::ClothAsset<S>>(drape::ClothAsset<S>::sheet(grid));
  drape::Settings settings;
  settings.subStepCount = o.substeps;
  settings.iterationCount = o.iterations;
  settings.contactForce = drape::contactForceFromString(o.estimator);
  Cloth cloth(asset, settings, 0.1);
  for (int k = 0; k < o.side; ++k)  // the border: rows 0 and side-1, columns 0 and side-1
    for (drape::Index i : {k, o.side * (o.side - 1) + k, o.side * k, o.side * k + o.side - 1}) cloth.pin(i);
  cloth.addSolid(drape::Solid<drape::Plane>{});  // the floor, which ODE's bodies meet as its ground plane

  OdeWorld ode;
  std::vector<std::unique_ptr<OdeBody>> bodies;
  double totalMass = 0;
  auto couple = [&](dBodyID id, auto shape, double mass) {
    bodies.push_back(std::make_unique<OdeBody>(id));
    drape::Solid<decltype(shape)> solid{shape};
    solid.pose = bodies.back()->pose();
    solid.motion = drape::Motion::Dynamic;
    solid.body = bodies.back().get();
    solid.staticFriction = solid.dynamicFriction = 0.4;
    cloth.addSolid(solid);
    totalMass += mass;
  };
  drape::Pose pose;
  pose.position = {-0.1, 0.05, 0.45};  // 2 cm above the cloth
  const Vector3d boxHalf(0.05, 0.04, 0.03);
  couple(ode.addBox(boxHalf, 0.06, pose), drape::Box{boxHalf}, 0.06);
  pose.position = {0.1, 0.0, 0.47};
  couple(ode.addSphere(0.05, 0.04, pose), drape::Sphere{0.05}, 0.04);
  pose.position = {0.0, -0.12, 0.45};
  pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Vector3d::UnitX()));
  couple(ode.addCapsule(0.03, 0.06, 0.05, pose), drape::Capsule{0.03, 0.06}, 0.05);

  const double weight = totalMass * 9.81;
  const int steps = int(std::lround(o.seconds / o.dt)), settleSteps = int(std::lround(o.settle / o.dt));
  const double h = o.dt / o.substeps;
  Vector3d forceSum = Vector3d::Zero();
  long samples = 0;
  double lowest = 1e9, fastest = 0, lowestCloth = 1e9;
  bool finite = true;
  for (int s = 0; s < steps && finite; ++s) {
    cloth.step(o.dt, [&](const Cloth& c) {
      ode.step(h);  // the bodies take the same substep, with the cloth's push in their accumulators
      if (s < settleSteps) return;
      for (const auto& f : c.bodyForces()) forceSum += f;
      ++samples;
    });
    if (std::getenv("ODE_TRACE") && s % 10 == 0) {
      std::fprintf(stderr, "t %.2f", (s + 1) * o.dt);
      for (const auto& b : bodies)
        std::fprintf(stderr, "  z %.3f v %.3f w %.2f", b->pose().position.z(), b->linearVelocity().norm(),
                     b->angularVelocity().norm());
      std::fprintf(stderr, "\n");
    }
    for (const auto& b : bodies) {
      lowest = std::min(lowest, b->pose().position.z());
      finite = finite && drape::detail::allFinite(b->pose().position);
      if (s >= settleSteps) fastest = std::max(fastest, b->linearVelocity().norm());
    }
    for (drape::Index i = 0; i < cloth.vertexCount(); ++i) {
      const Vector3d p = cloth.position(i);
      finite = finite && drape::detail::allFinite(p);
      lowestCloth = std::min(lowestCloth, p.z());
    }
  }
  if (!finite) {
    std::fprintf(stderr, "ode_hammock: the state went non-finite\n");
    return 3;
  }
  const Vector3d mean = samples > 0 ? Vector3d(forceSum / double(samples)) : Vector3d::Zero();
  const bool balanced = std::abs(mean.z() - weight) <= 0.05 * weight && mean.head<2>().norm() <= 0.05 * weight;
  // The hammock never touched the floor, and no body went through it (a body centre below every cloth vertex).
  const bool held = lowestCloth > settings.thickness && lowest > lowestCloth;
  if (o.json) {
    nlohmann::json j;
    j["bodies"] = bodies.size();
    j["steps"] = steps;
    j["dt"] = o.dt;
    j["substeps"] = o.substeps;
    j["estimator"] = o.estimator;
    j["weight_n"] = weight;
    j["mean_cloth_force_n"] = {mean.x(), mean.y(), mean.z()};
    j["force_over_weight"] = mean.z() / weight;
    j["lowest_body_centre_m"] = lowest;
    j["lowest_cloth_vertex_m"] = lowestCloth;
    j["fastest_body_after_settling_m_per_s"] = fastest;
    j["balanced"] = balanced;
    j["held"] = held;
    std::cout << j.dump() << '\n';
  }
  std::fprintf(stderr,
               "ode_hammock: %zu ODE bodies in a %dx%d cloth hammock, %s estimate: the cloth pushes them with %.4f N "
               "against their %.4f N weight (ratio %.4f); lowest cloth vertex %.3f m, lowest body centre %.3f m; "
               "fastest body after %.1f s %.3f m/s\n",
               bodies.size(), o.side, o.side, o.estimator.c_str(), mean.z(), weight, mean.z() / weight, lowestCloth,
               lowest, o.settle, fastest);
  return balanced && held ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"drape cloth coupled to ODE rigid bodies: bodies dropped into a cloth hammock"};
  Options o;
  std::string scalar = "float";
  app.add_option("--seconds", o.seconds, "simulated time (s)")->check(CLI::Range(0.5, 600.0));
  app.add_option("--settle", o.settle, "time before the force is averaged (s)")->check(CLI::Range(0.0, 600.0));
  app.add_option("--dt", o.dt, "step (s)")->check(CLI::Range(1e-4, 0.05));
  app.add_option("--substeps", o.substeps, "cloth and ODE substeps per step")->check(CLI::Range(1, 1000));
  app.add_option("--iterations", o.iterations, "cloth constraint passes per substep")->check(CLI::Range(1, 100));
  app.add_option("--estimator", o.estimator, "how the cloth's push on the bodies is estimated")
      ->check(CLI::IsMember({"sub-force", "energy", "impulse"}));
  app.add_option("--scalar", scalar, "the cloth's scalar")->check(CLI::IsMember({"float", "double"}));
  app.add_flag("--json", o.json, "print one JSON object on stdout");
  CLI11_PARSE(app, argc, argv);
  if (o.settle >= o.seconds) {
    std::fprintf(stderr, "ode_hammock: --settle (%g s) must be shorter than --seconds (%g s)\n", o.settle, o.seconds);
    return 2;
  }
  try {
    return scalar == "float" ? run<float>(o) : run<double>(o);
  } catch (const drape::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}
