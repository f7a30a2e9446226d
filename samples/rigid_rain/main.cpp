// The rigid-body rain sample (the cloth-rigid coupling thesis's Fig 6.6): random rigid bodies fall onto a cloth
// pinned at its corners, coupled two ways; the corners are let go after --release seconds and everything falls
// to the floor. Prints a summary to stderr; --json prints one JSON object on stdout and nothing else there.
// --gpu runs the cloth on the GPU solver (float), and --png DIR draws frames offscreen (cloth, bodies, floor) with
// the same kind of context and writes them as PNGs (both built where drape::gpu is, DRAPE_SAMPLE_GPU).

#include "rigid_rain.hpp"

#if DRAPE_SAMPLE_GPU
#include <drape/gpu/render.hpp>
#include <drape/gpu/solver.hpp>
#include <stb/stb_image_write.h>
#endif

#include <CLI/CLI.hpp>
#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <type_traits>
#include <numbers>
#include <numeric>
#include <vector>

namespace {

using drape::Index;
using drape::TriangleMesh;
using drape::scenes::RainShape;
using Eigen::Vector3d;

/// A closed surface of revolution about z: the profile runs from the bottom pole to the top pole through
/// `rings` (radius, z) pairs, `segments` steps around; counter-clockwise seen from outside.
TriangleMesh lathe(const std::vector<std::pair<double, double>>& rings, double bottom, double top, int segments) {
  TriangleMesh m;
  m.vertices.emplace_back(0, 0, bottom);
  for (const auto& [r, z] : rings)
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * std::numbers::pi * j / segments;
      m.vertices.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
  m.vertices.emplace_back(0, 0, top);
  const Index topPole = Index(m.vertices.size()) - 1;
  auto at = [&](std::size_t ring, int j) { return Index(1 + ring * segments + (j % segments)); };
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0, at(0, j + 1), at(0, j)});
  for (std::size_t k = 0; k + 1 < rings.size(); ++k)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({at(k, j), at(k, j + 1), at(k + 1, j + 1)});
      m.triangles.push_back({at(k, j), at(k + 1, j + 1), at(k + 1, j)});
    }
  const std::size_t last = rings.size() - 1;
  for (int j = 0; j < segments; ++j) m.triangles.push_back({at(last, j), at(last, j + 1), topPole});
  return m;
}

/// A triangulation of a body's shape in its body frame, for the OBJ frames.
TriangleMesh bodyMesh(const drape::RigidShape& shape) {
  struct {
    TriangleMesh operator()(const drape::Sphere& s) const { return drape::makeIcosphere(s.radius, 2); }
    TriangleMesh operator()(const drape::Box& b) const { return drape::makeBoxMesh(b.halfExtents); }
    TriangleMesh operator()(const drape::Capsule& c) const {
      std::vector<std::pair<double, double>> rings;
      const int quarter = 6;
      for (int k = 1; k <= quarter; ++k) {  // bottom hemisphere, then the top one
        const double a = -0.5 * std::numbers::pi + 0.5 * std::numbers::pi * k / quarter;
        rings.emplace_back(c.radius * std::cos(a), -c.halfHeight + c.radius * std::sin(a));
      }
      for (int k = 0; k < quarter; ++k) {
        const double a = 0.5 * std::numbers::pi * k / quarter;
        rings.emplace_back(c.radius * std::cos(a), c.halfHeight + c.radius * std::sin(a));
      }
      return lathe(rings, -c.halfHeight - c.radius, c.halfHeight + c.radius, 16);
    }
    TriangleMesh operator()(const drape::Cylinder& c) const {
      return lathe({{c.radius, -c.halfHeight}, {c.radius, c.halfHeight}}, -c.halfHeight, c.halfHeight, 24);
    }
    TriangleMesh operator()(const drape::ConvexHull& h) const {
      TriangleMesh m;
      m.vertices = h.vertices();
      for (const auto& f : h.faces())
        for (std::size_t k = 1; k + 1 < f.vertices.size(); ++k)
          m.triangles.push_back({Index(f.vertices[0]), Index(f.vertices[k]), Index(f.vertices[k + 1])});
      return m;
    }
  } visitor;
  return std::visit(visitor, shape);
}

template <class Scene>
void writeFrame(const std::string& path, const Scene& scene, const std::vector<TriangleMesh>& meshes) {
  std::ofstream out(path);
  if (!out) throw drape::Error("cannot write " + path);
  char line[128];
  const auto& cloth = scene.cloth();
  out << "o cloth\n";
  for (Index i = 0; i < cloth.vertexCount(); ++i) {
    const Vector3d p = cloth.position(i);
    std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", p.x(), p.y(), p.z());
    out << line;
  }
  for (const auto& t : cloth.asset().triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  Index base = cloth.vertexCount();
  for (int b = 0; b < scene.world().bodyCount(); ++b) {
    const drape::Pose pose = scene.world().body(b).pose();
    out << "o body_" << b << '_' << toString(scene.kinds()[b]) << '\n';
    for (const auto& v : meshes[b].vertices) {
      const Vector3d p = pose.apply(v);
      std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", p.x(), p.y(), p.z());
      out << line;
    }
    for (const auto& t : meshes[b].triangles)
      out << "f " << base + t[0] + 1 << ' ' << base + t[1] + 1 << ' ' << base + t[2] + 1 << '\n';
    base += meshes[b].vertexCount();
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Options {
  drape::scenes::RainConfig config;
  int steps = 300;
  std::string objDir;
  std::string traceFile;
  std::string pngDir;
  int pngEvery = 10;
};

#if DRAPE_SAMPLE_GPU
using Painter = drape::gpu::Renderer;

/// A picture of the scene: the floor (checkered), the cloth (from the GPU solver's buffer, or its positions) and
/// every body posed, seen from above one side of the cloth; written as path (PNG).
template <class Scene>
void drawFrame(Painter& painter, const Scene& scene, const std::vector<TriangleMesh>& meshes, const std::string& path) {
  const auto& cloth = scene.cloth();
  const auto& c = scene.config();
  const double halfX = 0.5 * (c.nx - 1) * c.spacing, halfY = 0.5 * (c.ny - 1) * c.spacing;
  drape::gpu::Camera cam;
  cam.target = {0, 0, 0.25 * c.clothHeight};
  cam.eye = {1.2 * halfX + 0.4, -1.6 * halfY - 0.3, c.clothHeight + 0.8};
  painter.begin(cam);
  drape::gpu::DrawMesh floor;
  for (double a : {-3.0, 3.0})
    for (double b : {-3.0, 3.0}) floor.positions.push_back({a * halfX, b * halfY, 0});
  floor.triangles = {{0, 2, 3}, {0, 3, 1}};
  painter.draw(floor, Eigen::Vector3f(0.75f, 0.75f, 0.72f), true);
  const Eigen::Vector3f clothColour(0.85f, 0.35f, 0.15f);
  if constexpr (std::is_same_v<std::decay_t<decltype(cloth)>, drape::gpu::Solver>) {
    painter.drawTriangles(cloth.positionBuffer(), cloth.origin(), cloth.faceBuffer(), clothColour);
  } else {
    drape::gpu::DrawMesh m;
    m.triangles = cloth.asset().triangles;
    for (Index i = 0; i < cloth.vertexCount(); ++i) m.positions.push_back(cloth.position(i));
    painter.draw(m, clothColour);
  }
  for (int b = 0; b < scene.world().bodyCount(); ++b) {
    const drape::Pose pose = scene.world().body(b).pose();
    drape::gpu::DrawMesh m;
    m.triangles = meshes[std::size_t(b)].triangles;
    for (const auto& v : meshes[std::size_t(b)].vertices) m.positions.push_back(pose.apply(v));
    painter.draw(m, Eigen::Vector3f(0.3f, 0.45f, 0.75f));
  }
  const auto rgba = painter.pixels();
  if (!stbi_write_png(path.c_str(), painter.width(), painter.height(), 4, rgba.data(), painter.width() * 4))
    throw drape::Error("cannot write " + path);
}
#else
struct Painter {};
#endif

template <drape::Scalar S, class Cloth = drape::Solver<S>, class... Prefix>
nlohmann::ordered_json run(const Options& o, [[maybe_unused]] Painter* painter, Prefix&... prefix) {
  using Clock = std::chrono::steady_clock;
  drape::scenes::RigidRain<S, Cloth> scene(o.config, prefix...);
  auto& cloth = scene.cloth();
  auto& world = scene.world();
  const Index n = cloth.vertexCount();
  const int bodies = world.bodyCount();
  const double g = o.config.rigid.gravity.norm();

  double largestRadius = 0, bodiesMass = 0, speedBound = 0;
  std::vector<double> spinBound(std::size_t(bodies), 0.0);  // each body's, from its own energy
  std::vector<TriangleMesh> meshes;
  for (int b = 0; b < bodies; ++b) {
    const auto& body = world.body(b);
    largestRadius = std::max(largestRadius, body.boundingRadius());
    const double m = body.massProperties().mass;
    bodiesMass += m;
    // The speed the body would reach at z = 0 with all its own energy (kinetic and potential) as translation.
    const Vector3d w = body.state.pose.rotation.conjugate() * body.state.angularVelocity;
    const double energy = 0.5 * m * body.state.linearVelocity.squaredNorm() +
                          0.5 * w.dot(body.massProperties().inertia * w) + m * g * body.state.pose.position.z();
    speedBound = std::max(speedBound, std::sqrt(2 * energy / m));
    // The spin it would reach with all of that energy as rotation about its axis of least inertia.
    const double least = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(body.massProperties().inertia).eigenvalues()[0];
    spinBound[std::size_t(b)] = std::sqrt(2 * energy / least);
    if (!o.objDir.empty() || painter) meshes.push_back(bodyMesh(body.shape()));
  }
  double clothMass = 0;
  for (Index i = 0; i < n; ++i) {
    const double w = double(cloth.state().invMass[i]);
    if (w > 0) clothMass += 1 / w;
  }
  auto frameName = [&](int f) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame_%04d.obj", f);
    return o.objDir + name;
  };
  if (!o.objDir.empty()) writeFrame(frameName(0), scene, meshes);
  std::ofstream trace;
  if (!o.traceFile.empty()) {
    trace.open(o.traceFile);
    if (!trace) throw drape::Error("cannot write " + o.traceFile);
    trace << "step,time,released,ms,penetration,max_body_speed,max_cloth_speed,max_strain,cloth_z_min,cloth_z_mean,"
             "body_z_min,body_z_max,manifolds\n";
  }

  std::vector<double> stepMs;
  double maxPen = 0, maxPenPinned = 0, maxPenAtBodies = 0, maxFloorPen = 0, maxBodySpeed = 0, maxClothSpeed = 0,
         maxBodySpin = 0, maxBodySpinBound = 0, maxSpinRatio = 0;
  int maxPenStep = 0, maxBodySpeedStep = 0, maxBodySpinStep = 0;
  int underAtRelease = -1, offAtRelease = -1, throughAtRelease = -1, interiorAtRelease = -1;
  bool finite = true;
  // Bodies that passed through the cloth's sheet, watched substep by substep (SheetCrossings): before the release,
  // while the pinned cloth holds them, and after it.
  drape::scenes::SheetCrossings sheet(cloth.asset());
  // Bodies under the cloth and bodies not over it, measured just before the release. A body is over the cloth
  // where its centre lies inside the outline of the cloth's boundary vertices in x, y (even-odd rule), and under
  // it where the centre is also below the cloth vertex nearest it in x, y: a body that fell past an edge the
  // sagging cloth then swung over counts, so this is not a count of bodies through the cloth.
  std::vector<Index> outline;  // the sheet's boundary vertices in order around it
  {
    const Index nx = o.config.nx, ny = o.config.ny;
    for (Index i = 0; i < nx; ++i) outline.push_back(i);
    for (Index j = 1; j < ny; ++j) outline.push_back(j * nx + nx - 1);
    for (Index i = nx - 2; i >= 0; --i) outline.push_back((ny - 1) * nx + i);
    for (Index j = ny - 2; j >= 1; --j) outline.push_back(j * nx);
  }
  auto insideOutline = [&](const Vector3d& c) {
    bool inside = false;
    for (std::size_t k = 0, l = outline.size() - 1; k < outline.size(); l = k++) {
      const Vector3d a = cloth.position(outline[k]), b = cloth.position(outline[l]);
      if ((a.y() > c.y()) != (b.y() > c.y()) && c.x() < a.x() + (c.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()))
        inside = !inside;
    }
    return inside;
  };
  auto countUnderAndOff = [&] {
    int under = 0, off = 0;
    for (int b = 0; b < bodies; ++b) {
      const Vector3d c = world.body(b).pose().position;
      if (!insideOutline(c)) {
        ++off;
        continue;
      }
      double best = 1e300, z = 0;
      for (Index i = 0; i < n; ++i) {
        const Vector3d p = cloth.position(i);
        const double d = (p - c).head<2>().squaredNorm();
        if (d < best) best = d, z = p.z();
      }
      if (c.z() < z) ++under;
    }
    underAtRelease = under, offAtRelease = off, throughAtRelease = sheet.bodiesThrough();
    interiorAtRelease = sheet.bodiesThroughInterior();
  };
  sheet.observe(cloth, world);
  for (int s = 1; s <= o.steps; ++s) {
    if (!scene.released() && scene.time() >= o.config.release - 1e-9) countUnderAndOff();
    // The sheet is read after every substep, where the straight paths the meter sweeps are the solver's own
    // (docs/design.md §10). The readings' time is left out of the step's.
    double meterMs = 0;
    const auto t0 = Clock::now();
    scene.step([&](const auto&) {
      const auto m0 = Clock::now();
      sheet.observe(cloth, world);
      meterMs += std::chrono::duration<double, std::milli>(Clock::now() - m0).count();
    });
    stepMs.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count() - meterMs);
    const double pen = drape::scenes::bodyPenetration(cloth, largestRadius);
    if (pen > maxPen) maxPen = pen, maxPenStep = s;
    if (!scene.released()) maxPenPinned = std::max(maxPenPinned, pen);
    maxPenAtBodies = std::max(maxPenAtBodies, drape::scenes::bodyPenetrationAtBodies(cloth, world));
    for (Index i = 0; i < n; ++i) {
      const Vector3d p = cloth.position(i), v = cloth.velocity(i);
      finite = finite && p.allFinite() && v.allFinite();
      maxFloorPen = std::max(maxFloorPen, -p.z());
      maxClothSpeed = std::max(maxClothSpeed, v.norm());
    }
    double stepBodySpeed = 0, bodyZMin = bodies ? 1e300 : 0, bodyZMax = bodies ? -1e300 : 0;
    for (int b = 0; b < bodies; ++b) {
      const double v = world.body(b).linearVelocity().norm(), z = world.body(b).pose().position.z();
      finite = finite && std::isfinite(v) && world.body(b).pose().position.allFinite();
      if (v > maxBodySpeed) maxBodySpeed = v, maxBodySpeedStep = s;
      const double w = world.body(b).angularVelocity().norm();
      if (w > maxBodySpin) maxBodySpin = w, maxBodySpinStep = s, maxBodySpinBound = spinBound[std::size_t(b)];
      if (spinBound[std::size_t(b)] > 0) maxSpinRatio = std::max(maxSpinRatio, w / spinBound[std::size_t(b)]);
      stepBodySpeed = std::max(stepBodySpeed, v);
      bodyZMin = std::min(bodyZMin, z), bodyZMax = std::max(bodyZMax, z);
    }
    if (trace.is_open()) {
      double clothSpeed = 0, zMin = 1e300, zMean = 0;
      for (Index i = 0; i < n; ++i) {
        const double z = cloth.position(i).z();
        clothSpeed = std::max(clothSpeed, cloth.velocity(i).norm());
        zMin = std::min(zMin, z), zMean += z / double(n);
      }
      trace << s << ',' << scene.time() << ',' << scene.released() << ',' << stepMs.back() << ',' << pen << ','
            << stepBodySpeed << ',' << clothSpeed << ',' << drape::stretchStrain(cloth.asset(), cloth.state().x).max
            << ',' << zMin << ',' << zMean << ',' << bodyZMin << ',' << bodyZMax << ',' << world.contacts().size()
            << '\n';
    }
    if (!o.objDir.empty()) writeFrame(frameName(s), scene, meshes);
#if DRAPE_SAMPLE_GPU
    if (painter && s % o.pngEvery == 0) {
      char name[32];
      std::snprintf(name, sizeof name, "/frame_%04d.png", s);
      drawFrame(*painter, scene, meshes, o.pngDir + name);
    }
#endif
    if (!finite) break;
  }

  std::vector<double> heights, speedsEnd;
  double lowest = bodies ? 1e300 : 0;
  for (int b = 0; b < bodies; ++b) {
    const auto& body = world.body(b);
    heights.push_back(body.pose().position.z());
    speedsEnd.push_back(body.linearVelocity().norm());
    const auto box = drape::detail::worldAabb(body.shape(), body.pose().rotation.toRotationMatrix(), body.pose().position);
    lowest = std::min(lowest, box.min.z());
  }
  double clothSpeedEnd = 0;
  for (Index i = 0; i < n; ++i) clothSpeedEnd = std::max(clothSpeedEnd, cloth.velocity(i).norm());
  const auto strain = drape::stretchStrain(cloth.asset(), cloth.state().x);
  std::vector<std::string> shapeNames;
  for (RainShape k : drape::scenes::kRainShapes)
    if (o.config.shapes & unsigned(k)) shapeNames.push_back(toString(k));
  std::vector<int> shapeCounts(5, 0);
  for (RainShape k : scene.kinds()) ++shapeCounts[std::countr_zero(unsigned(k))];

  nlohmann::ordered_json j;
  j["bodies"] = bodies;
  j["seed"] = o.config.seed;
  j["estimator"] = drape::toString(o.config.estimator);
  j["scalar"] = std::is_same_v<S, float> ? "float" : "double";
  j["shapes"] = shapeNames;
  j["shape_counts"] = {{"sphere", shapeCounts[0]}, {"box", shapeCounts[1]}, {"capsule", shapeCounts[2]},
                       {"cylinder", shapeCounts[3]}, {"hull", shapeCounts[4]}};
  j["steps"] = int(stepMs.size());
  j["dt"] = o.config.dt;
  j["substeps"] = o.config.subSteps;
  j["iterations"] = o.config.base.iterationCount;
  j["method"] = drape::toString(o.config.base.collisionMethod);
  j["continuous_contact"] = o.config.base.continuousContact;
  j["vertices"] = n;
  j["faces"] = cloth.asset().faceCount();
  j["cloth_mass"] = clothMass;
  j["bodies_mass"] = bodiesMass;
  j["release_s"] = o.config.release;
  j["released"] = scene.released();
  j["ms_per_step"] = median(stepMs);
  j["ms_per_step_mean"] = stepMs.empty() ? 0 : std::accumulate(stepMs.begin(), stepMs.end(), 0.0) / stepMs.size();
  j["ms_per_step_max"] = stepMs.empty() ? 0 : *std::max_element(stepMs.begin(), stepMs.end());
  j["total_step_s"] = std::accumulate(stepMs.begin(), stepMs.end(), 0.0) / 1000;
  j["max_penetration"] = maxPen;
  j["max_penetration_step"] = maxPenStep;
  j["max_penetration_pinned"] = maxPenPinned;
  j["max_penetration_at_bodies"] = maxPenAtBodies;
  j["max_floor_penetration"] = maxFloorPen;
  j["max_body_speed"] = maxBodySpeed;
  j["max_body_speed_step"] = maxBodySpeedStep;
  j["body_speed_energy_bound"] = speedBound;
  j["max_body_spin"] = maxBodySpin;  // rad/s
  j["max_body_spin_step"] = maxBodySpinStep;
  j["max_body_spin_energy_bound"] = maxBodySpinBound;  // that body's, rad/s
  j["max_body_spin_over_bound"] = maxSpinRatio;         // the largest of any body's spin over its own bound
  j["max_cloth_speed"] = maxClothSpeed;
  if (underAtRelease >= 0) {
    j["bodies_through_cloth_at_release"] = throughAtRelease;  // passed through the sheet while it was pinned
    j["bodies_through_cloth_interior_at_release"] = interiorAtRelease;  // of them, away from its border
    j["bodies_under_cloth_at_release"] = underAtRelease;
    j["bodies_off_cloth_at_release"] = offAtRelease;
  }
  j["bodies_through_cloth"] = sheet.bodiesThrough();  // the whole run
  // Of them, those first counted away from the sheet's border (a body rounding a free edge between two readings
  // is counted at the border: SheetCrossings).
  j["bodies_through_cloth_interior"] = sheet.bodiesThroughInterior();
  j["sheet_crossings"] = sheet.crossings();
  j["final_body_z_min"] = heights.empty() ? 0 : *std::min_element(heights.begin(), heights.end());
  j["final_body_z_median"] = median(heights);
  j["final_body_z_max"] = heights.empty() ? 0 : *std::max_element(heights.begin(), heights.end());
  j["final_lowest_body_point"] = lowest;
  j["final_max_body_speed"] = speedsEnd.empty() ? 0 : *std::max_element(speedsEnd.begin(), speedsEnd.end());
  j["final_max_cloth_speed"] = clothSpeedEnd;
  j["final_mean_strain"] = strain.mean;
  j["final_max_strain"] = strain.max;
  j["finite"] = finite;
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  auto& c = o.config;
  std::string estimator = drape::toString(c.estimator), scalar = "float",
              method = drape::toString(c.base.collisionMethod);
  // By default every shape the cloth solver takes as a solid (all five once Solver<S> has Cylinder and ConvexHull).
  std::vector<std::string> shapes;
  for (RainShape k : drape::scenes::kRainShapes)
    if (drape::scenes::supportedRainShapes<drape::Solver<float>>() & unsigned(k)) shapes.push_back(toString(k));
  bool json = false;
  CLI::App app{"drape rigid rain: random rigid bodies fall onto a cloth pinned at its corners (two-way coupling)"};
  app.add_option("--bodies", c.bodies, "number of rigid bodies")->check(CLI::Range(0, 2000))->capture_default_str();
  app.add_option("--seed", c.seed, "random seed (the same seed gives the same run)")->capture_default_str();
  app.add_option("--estimator", estimator, "how the cloth's push on the bodies is estimated")
      ->check(CLI::IsMember({"sub-force", "energy", "impulse"}))
      ->capture_default_str();
  app.add_option("--steps", o.steps, "steps of dt to simulate")->check(CLI::Range(1, 1000000))->capture_default_str();
  app.add_option("--release", c.release, "seconds until the cloth's corners are let go")
      ->check(CLI::Range(0.0, 1e9))
      ->capture_default_str();
  app.add_option("--shapes", shapes, "body shapes to draw from (comma-separated)")
      ->delimiter(',')
      ->check(CLI::IsMember({"sphere", "box", "capsule", "cylinder", "hull"}))
      ->capture_default_str();
  app.add_option("--density", c.density, "density of the bodies (kg/m^3)")->check(CLI::Range(1.0, 1e5))->capture_default_str();
  app.add_option("--dt", c.dt, "seconds per step")->check(CLI::Range(1e-5, 0.1))->capture_default_str();
  app.add_option("--substeps", c.subSteps, "substeps per step")->check(CLI::Range(1, 1000))->capture_default_str();
  app.add_option("--iterations", c.base.iterationCount, "cloth constraint passes per substep")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--continuous", c.base.continuousContact,
                 "continuous contact (Settings::continuousContact): each substep's paths searched, so fast bodies "
                 "do not tunnel through the cloth")
      ->capture_default_str();
  app.add_option("--method", method, "cloth-solid collision method (vertices: vertex contacts only, the thesis's)")
      ->check(CLI::IsMember({"faces", "vertices", "in-solve"}))
      ->capture_default_str();
  app.add_option("--scalar", scalar, "the cloth's floating-point type")->check(CLI::IsMember({"float", "double"}))->capture_default_str();
  app.add_option("--trace", o.traceFile, "CSV per step: time, timing, penetration, speeds, strain, heights");
  app.add_option("--obj", o.objDir, "directory for one OBJ file per frame (cloth and bodies)");
  app.add_flag("--json", json, "print one JSON object on stdout");
  bool gpu = false;
  std::string backend = "auto";
  app.add_flag("--gpu", gpu, "run the cloth on the GPU (float)");
  app.add_option("--backend", backend, "GPU context: auto (EGL hardware device, else OSMesa), egl or osmesa")
      ->check(CLI::IsMember({"auto", "egl", "osmesa"}))
      ->capture_default_str();
  app.add_option("--png", o.pngDir, "directory for pictures of the scene (drawn offscreen with a GL context)");
  app.add_option("--png-every", o.pngEvery, "steps between pictures")->check(CLI::Range(1, 1000000))->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e, std::cerr, std::cerr);
  }
  try {
    c.estimator = drape::scenes::contactForceFromString(estimator);
    c.base.collisionMethod = drape::collisionMethodFromString(method);
    c.shapes = 0;
    for (const auto& s : shapes) c.shapes |= unsigned(drape::scenes::rainShapeFromString(s));
    if (!o.objDir.empty()) std::filesystem::create_directories(o.objDir);
    nlohmann::ordered_json j;
    if (gpu || !o.pngDir.empty()) {
#if DRAPE_SAMPLE_GPU
      drape::gpu::Context context(drape::gpu::backendFromString(backend));
      std::unique_ptr<Painter> painter;
      if (!o.pngDir.empty()) {
        std::filesystem::create_directories(o.pngDir);
        painter = std::make_unique<Painter>(context, 960, 540);
      }
      if (gpu) {
        if (scalar != "float") throw drape::Error("--gpu runs float only");
        j = run<float, drape::gpu::Solver>(o, painter.get(), context);
        j["device"] = std::string("gpu/") + drape::gpu::toString(context.backend());
      } else {
        j = scalar == "double" ? run<double>(o, painter.get()) : run<float>(o, painter.get());
        j["device"] = "cpu";
      }
      j["renderer"] = context.renderer();
#else
      throw drape::Error("this build has no GPU part (it needs glad, Debian python3-glad, libegl-dev and libstb-dev)");
#endif
    } else {
      j = scalar == "double" ? run<double>(o, nullptr) : run<float>(o, nullptr);
      j["device"] = "cpu";
    }
    if (json) std::cout << j.dump() << '\n';
    std::fprintf(stderr,
                 "rigid rain: %d bodies (seed %u, %s, %s), %d steps of %g s x %d substeps, release at %g s\n"
                 "  %.3f ms/step median (%.3f mean, %.2f s in all)\n"
                 "  deepest cloth vertex in a body %.3g m (step %d; %.3g m while pinned; %.3g m at the bodies' end "
                 "poses), below the floor %.3g m\n"
                 "  fastest body %.3g m/s (step %d; own-energy bound %.3g), fastest spin %.3g rad/s (step %d; that "
                 "body's own-energy bound %.3g;\n  largest spin over its body's bound %.3g), fastest cloth vertex %.3g "
                 "m/s\n"
                 "  final body centres z %.3g / %.3g / %.3g m (min/median/max), lowest body point %.3g m, strain max %.3g\n",
                 j["bodies"].get<int>(), c.seed, estimator.c_str(), scalar.c_str(), j["steps"].get<int>(), c.dt,
                 c.subSteps, c.release, j["ms_per_step"].get<double>(), j["ms_per_step_mean"].get<double>(),
                 j["total_step_s"].get<double>(), j["max_penetration"].get<double>(),
                 j["max_penetration_step"].get<int>(), j["max_penetration_pinned"].get<double>(),
                 j["max_penetration_at_bodies"].get<double>(), j["max_floor_penetration"].get<double>(),
                 j["max_body_speed"].get<double>(), j["max_body_speed_step"].get<int>(),
                 j["body_speed_energy_bound"].get<double>(), j["max_body_spin"].get<double>(),
                 j["max_body_spin_step"].get<int>(), j["max_body_spin_energy_bound"].get<double>(),
                 j["max_body_spin_over_bound"].get<double>(), j["max_cloth_speed"].get<double>(),
                 j["final_body_z_min"].get<double>(), j["final_body_z_median"].get<double>(),
                 j["final_body_z_max"].get<double>(), j["final_lowest_body_point"].get<double>(),
                 j["final_max_strain"].get<double>());
    if (j.contains("bodies_through_cloth_at_release"))
      std::fprintf(stderr,
                   "  at the release: %d bodies through the cloth (%d away from its border), %d under it, %d off it\n",
                   j["bodies_through_cloth_at_release"].get<int>(),
                   j["bodies_through_cloth_interior_at_release"].get<int>(),
                   j["bodies_under_cloth_at_release"].get<int>(), j["bodies_off_cloth_at_release"].get<int>());
    std::fprintf(stderr, "  bodies through the cloth over the run: %d, %d away from its border (%d crossings)\n",
                 j["bodies_through_cloth"].get<int>(), j["bodies_through_cloth_interior"].get<int>(),
                 j["sheet_crossings"].get<int>());
    return j["finite"].get<bool>() ? 0 : 3;
  } catch (const std::exception& e) {
    std::cerr << "rigid_rain: " << e.what() << '\n';
    return 2;
  }
}
