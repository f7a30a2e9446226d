// Spin from nothing (docs/design.md §4): a 41x41 cloth (2 cm) draped from the top of a frictionless 0.3 m sphere,
// its centre vertex pinned on the vertical axis through the sphere's centre. No force can turn the cloth about
// that axis, so its mass-weighted angular momentum about it, L_z = sum m (x v_y - y v_x), should stay at zero.
// Printed for every collision method, float and double, the sphere at rest and spinning at 2 rad/s, a standing
// capsule with the same top (the skirt hangs down its side, curved about the axis only), a standing cylinder
// with the same top (a field with edges: the cloth folds over its rim) and the sphere as a grid field built from a
// mesh (whose faces' normals are not radial: it can turn the cloth by a little), at each substep count given,
// with Settings::keepAngularMomentum off and on: L_z after the run, and L_z / I_z (the cloth's turn, rad/s). The
// same cloth hanging from its pin with no solid at all shows the constraint solve's share.
// Run: build/bench/spin_drift [seconds, default 10] [substep counts..., default 2 10]
#include <drape/drape.hpp>

#include <sphere_drape.hpp>

#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

using namespace drape;

enum class Under { Nothing, Sphere, Capsule, Cylinder, MeshBall };

template <class S>
scenes::AxialSpin run(CollisionMethod method, int substeps, double spin, Under under, double seconds, bool keep) {
  using scenes::SphereDrape;
  Settings settings;
  settings.collisionMethod = method;
  settings.subStepCount = substeps;
  settings.keepAngularMomentum = keep;
  Solver<S> solver(SphereDrape::asset<S>(), settings);
  if (under == Under::Sphere) solver.addSolid(SphereDrape::sphere(spin));
  if (under == Under::Capsule) solver.addSolid(SphereDrape::standingCapsule(spin));
  if (under == Under::Cylinder) solver.addSolid(SphereDrape::standingCylinder());
  if (under == Under::MeshBall) solver.addSolid(SphereDrape::meshBall());
  solver.pin(SphereDrape::kCentre);
  for (int f = 0; f < int(seconds * 60 + 0.5); ++f) solver.step(1.0 / 60.0);
  return scenes::axialSpin(solver);
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 10.0;
  std::vector<int> substeps;
  for (int a = 2; a < argc; ++a) substeps.push_back(std::atoi(argv[a]));
  if (substeps.empty()) substeps = {2, 10};
  if (!(seconds > 0) || seconds > 600) {
    std::fprintf(stderr, "spin_drift: seconds must be in (0, 600]\n");
    return 2;
  }
  for (int n : substeps)
    if (n < 1 || n > 1000) {
      std::fprintf(stderr, "spin_drift: substep counts must be in [1, 1000]\n");
      return 2;
    }
  std::printf("After %g s. L_z in kg m^2/s; the turn L_z / I_z in rad/s.\n\n", seconds);
  std::printf("| scene | substeps | method | moment kept | float L_z | float turn | double L_z | double turn |\n");
  std::printf("|---|---:|---|---|---:|---:|---:|---:|\n");
  struct Scene {
    const char* name;
    Under under;
    double spin;
  };
  for (const Scene scene : {Scene{"sphere at rest", Under::Sphere, 0.0},
                            Scene{"sphere spinning at 2 rad/s", Under::Sphere, 2.0},
                            Scene{"standing capsule at rest", Under::Capsule, 0.0},
                            Scene{"standing cylinder at rest", Under::Cylinder, 0.0},
                            Scene{"sphere from a mesh, at rest", Under::MeshBall, 0.0},
                            Scene{"no solid", Under::Nothing, 0.0}})
    for (int n : substeps)
      for (CollisionMethod m : {CollisionMethod::Faces, CollisionMethod::Vertices, CollisionMethod::InSolve})
        for (const bool keep : {false, true}) {
          const bool solid = scene.under != Under::Nothing;
          if (!solid && m != CollisionMethod::Faces) continue;  // no contact: the methods are one
          const scenes::AxialSpin f = run<float>(m, n, scene.spin, scene.under, seconds, keep);
          const scenes::AxialSpin d = run<double>(m, n, scene.spin, scene.under, seconds, keep);
          std::printf("| %s | %d | %s | %s | %+.2e | %+.1e | %+.2e | %+.1e |\n", scene.name, n,
                      solid ? toString(m) : "any", keep ? "yes" : "no", f.momentum, f.rate(), d.momentum,
                      d.rate());
          std::fflush(stdout);
        }
  return 0;
}
