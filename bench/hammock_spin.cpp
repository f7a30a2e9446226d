// Spin from nothing in a hammock (docs/design.md §4): a 31x31 cloth (2 cm) pinned at its four corners, its faces'
// diagonals pointing to its centre in each quadrant, so that the mesh is its own mirror image across both axes
// through the centre. A rigid ball (5 cm, 300 kg/m^3) is dropped at 1 m/s onto that centre, coupled both ways.
// The scene is symmetric under those mirrors, which reverse a turn about the vertical axis, so the cloth's
// mass-weighted angular momentum about that axis, L_z = sum m (x v_y - y v_x), should stay at zero. Printed for
// every collision method, float and double, frictionless and with friction 0.4, at each substep count given:
// the largest turn L_z / I_z over the run and the turn at its end (rad/s). With --mirror the vertices are
// numbered from the other side (the same mesh): a turn that then changes sign, and nothing else, comes from the
// order in which the solver visits the vertices and faces. --keep turns Settings::keepAngularMomentum on;
// --no-ball leaves the cloth to sag from its pins alone (the constraint solve's share).
// Run: build/bench/hammock_spin [--mirror] [--keep] [--no-ball] [seconds, default 3] [substep counts..., default 2 10]
#include <drape/drape.hpp>
#include <drape/coupling/rigid_world.hpp>
#include <drape/rigid/world.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

namespace {

using namespace drape;

constexpr int kSide = 31;
constexpr double kSpacing = 0.02;

/// The mirror-symmetric hammock's mesh; `mirror` numbers its vertices from the other side along x.
template <class S> std::shared_ptr<const ClothAsset<S>> symmetricSheet(bool mirror) {
  const int h = kSide / 2;
  const double sx = mirror ? -1.0 : 1.0;
  std::vector<Vec3<S>> p;
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) p.emplace_back(S(sx * kSpacing * (i - h)), S(kSpacing * (j - h)), S(0));
  std::vector<std::array<Index, 3>> t;
  for (int j = 0; j + 1 < kSide; ++j)
    for (int i = 0; i + 1 < kSide; ++i) {
      const Index a = j * kSide + i, b = a + 1, c = a + kSide, d = a + kSide + 1;
      std::array<Index, 3> f0{a, b, d}, f1{a, d, c};  // the diagonal a-d points to the centre
      if ((i < h) != (j < h)) f0 = {a, b, c}, f1 = {b, d, c};  // the diagonal b-c does
      if (mirror) std::swap(f0[1], f0[2]), std::swap(f1[1], f1[2]);  // counter-clockwise after the mirror
      t.push_back(f0);
      t.push_back(f1);
    }
  return std::make_shared<const ClothAsset<S>>(ClothAsset<S>::fromMesh(p, t));
}

struct Turn {
  double largest = 0, last = 0;
};

template <class S>
Turn run(CollisionMethod method, int substeps, double friction, bool mirror, bool keep, bool withBall,
         double seconds) {
  Settings settings;
  settings.keepAngularMomentum = keep;
  settings.collisionMethod = method;
  settings.subStepCount = substeps;
  Solver<S> cloth(symmetricSheet<S>(mirror), settings, 0.2);
  for (Index corner : {0, kSide - 1, kSide * (kSide - 1), kSide * kSide - 1}) cloth.pin(corner);
  RigidSettings rigid;
  rigid.ground = false;
  rigid.subStepCount = substeps;
  RigidWorld world(rigid);
  BodyDesc ball;
  ball.shape = Sphere{0.05};
  ball.pose.position = {0, 0, 0.08};
  ball.linearVelocity = {0, 0, -1};
  ball.density = 300;
  const int body = world.add(ball);
  CouplingDesc coupling;
  coupling.staticFriction = coupling.dynamicFriction = friction;
  if (withBall) addCoupledBody(cloth, world, body, coupling);
  Turn turn;
  for (int step = 0; step < int(seconds * 100 + 0.5); ++step) {
    if (withBall)
      stepCoupled(cloth, world, 0.01);
    else
      cloth.step(0.01);
    double momentum = 0, inertia = 0;
    for (Index i = 0; i < cloth.vertexCount(); ++i) {
      const double w = double(cloth.state().invMass[std::size_t(i)]);
      if (w == 0) continue;
      const Eigen::Vector3d x = cloth.position(i), v = cloth.velocity(i);
      momentum += (x.x() * v.y() - x.y() * v.x()) / w;
      inertia += (x.x() * x.x() + x.y() * x.y()) / w;
    }
    turn.last = momentum / inertia;
    if (std::abs(turn.last) > std::abs(turn.largest)) turn.largest = turn.last;
  }
  return turn;
}

}  // namespace

int main(int argc, char** argv) {
  int a = 1;
  bool mirror = false, keep = false, withBall = true;
  for (; a < argc && std::strncmp(argv[a], "--", 2) == 0; ++a) {
    if (std::strcmp(argv[a], "--mirror") == 0) {
      mirror = true;
    } else if (std::strcmp(argv[a], "--keep") == 0) {
      keep = true;
    } else if (std::strcmp(argv[a], "--no-ball") == 0) {
      withBall = false;
    } else {
      std::fprintf(stderr, "hammock_spin: unknown option %s\n", argv[a]);
      return 2;
    }
  }
  const double seconds = argc > a ? std::atof(argv[a]) : 3.0;
  std::vector<int> substeps;
  for (int k = a + 1; k < argc; ++k) substeps.push_back(std::atoi(argv[k]));
  if (substeps.empty()) substeps = {2, 10};
  if (!(seconds > 0) || seconds > 600) {
    std::fprintf(stderr, "hammock_spin: seconds must be in (0, 600]\n");
    return 2;
  }
  for (int n : substeps)
    if (n < 1 || n > 1000) {
      std::fprintf(stderr, "hammock_spin: substep counts must be in [1, 1000]\n");
      return 2;
    }
  std::printf("The cloth's turn L_z / I_z (rad/s) over %g s, %s, vertices numbered %s, angular momentum %s: "
              "largest, and at the end.\n\n",
              seconds, withBall ? "a ball dropped on it" : "no ball", mirror ? "from the other side" : "as built",
              keep ? "kept" : "not kept");
  std::printf("| substeps | friction | method | float largest | float end | double largest | double end |\n");
  std::printf("|---:|---:|---|---:|---:|---:|---:|\n");
  for (int n : substeps)
    for (double friction : {0.0, 0.4})
      for (CollisionMethod m : {CollisionMethod::Faces, CollisionMethod::Vertices, CollisionMethod::InSolve}) {
        const Turn f = run<float>(m, n, friction, mirror, keep, withBall, seconds);
        const Turn d = run<double>(m, n, friction, mirror, keep, withBall, seconds);
        std::printf("| %d | %.1f | %s | %+.2e | %+.1e | %+.2e | %+.1e |\n", n, friction, toString(m), f.largest,
                    f.last, d.largest, d.last);
        std::fflush(stdout);
      }
  return 0;
}
