// The inclined-plane sample (the SDF collision paper's Figs 5 and 8): a cloth falls onto a slope and slides down it.
// Prints a summary to stderr; --json prints one JSON object on stdout and nothing else there. --gpu runs the
// same scene on the GPU solver (float), and --png DIR draws frames offscreen with the same kind of context and
// writes them as PNGs (both built where drape::gpu is, DRAPE_SAMPLE_GPU; PNGs through Debian's stb).

#include "slope.hpp"

#if DRAPE_SAMPLE_GPU
#include <drape/gpu/render.hpp>
#include <drape/gpu/solver.hpp>

#include <stb/stb_image_write.h>

#include <memory>
#endif

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <numbers>
#include <string>

int main(int argc, char** argv) {
  drape::scenes::SlopeConfig c;
  std::string method = "faces", scalar = "float";
  bool json = false, gpu = false;
  std::string backend = "auto", pngDir;
  int pngEvery = 30;
  CLI::App app{"drape inclined plane: a cloth falls onto a slope and slides"};
  app.add_option("--angle", c.angleDeg, "slope angle in degrees")->check(CLI::Range(0.0, 80.0))->capture_default_str();
  app.add_option("--friction", c.friction, "Coulomb friction coefficient")->check(CLI::Range(0.0, 100.0))->capture_default_str();
  app.add_option("--substeps", c.subSteps, "substeps per frame")->check(CLI::Range(1, 10000))->capture_default_str();
  app.add_option("--iterations", c.iterations, "constraint passes per substep")->check(CLI::Range(1, 1000))->capture_default_str();
  app.add_option("--frames", c.frames, "frames to simulate")->check(CLI::Range(1, 1000000))->capture_default_str();
  app.add_option("--dt", c.dt, "seconds per frame")->check(CLI::Range(1e-6, 1.0))->capture_default_str();
  app.add_option("--nx", c.nx, "vertices across")->check(CLI::Range(2, 4096))->capture_default_str();
  app.add_option("--ny", c.ny, "vertices down the slope")->check(CLI::Range(2, 4096))->capture_default_str();
  app.add_option("--spacing", c.spacing, "vertex spacing in metres")->check(CLI::Range(1e-4, 1.0))->capture_default_str();
  app.add_option("--gap", c.gap,
                 "m from the cloth's uphill edge down to the slope at the start; negative starts that edge inside")
      ->check(CLI::Range(-1.0, 100.0))
      ->capture_default_str();
  app.add_flag("--ridge", c.ridge,
               "a ridge in place of the slope: a box turned 45 deg about x, one edge on top at height 0 (--angle unused)");
  app.add_flag("--continuous", c.base.continuousContact, "continuous contact: search each substep's paths for solids they crossed");
  app.add_option("--method", method, "collision method")->check(CLI::IsMember({"faces", "vertices", "in-solve"}))->capture_default_str();
  app.add_option("--scalar", scalar, "floating-point type")->check(CLI::IsMember({"float", "double"}))->capture_default_str();
  app.add_flag("--json", json, "print one JSON object on stdout");
  app.add_flag("--gpu", gpu, "run on the GPU (float; every method)");
  app.add_option("--backend", backend, "GPU context: auto (EGL hardware device, else OSMesa), egl or osmesa")
      ->check(CLI::IsMember({"auto", "egl", "osmesa"}))
      ->capture_default_str();
  app.add_option("--trace", c.traceFile, "CSV per frame: time, tracked vertex height above the slope, metrics");
  app.add_option("--obj", c.objDir, "directory for one OBJ file per frame");
  app.add_option("--png", pngDir, "directory for pictures of the scene (drawn offscreen with a GL context)");
  app.add_option("--png-every", pngEvery, "frames between pictures")->check(CLI::Range(1, 1000000))->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e, std::cerr, std::cerr);
  }
  c.method = drape::collisionMethodFromString(method);
  try {
    if (!c.objDir.empty()) std::filesystem::create_directories(c.objDir);
    drape::scenes::SlopeResult r;
    std::string device = "cpu", renderer;
#if DRAPE_SAMPLE_GPU
    std::unique_ptr<drape::gpu::Context> context;
    if (gpu || !pngDir.empty()) {
      context = std::make_unique<drape::gpu::Context>(drape::gpu::backendFromString(backend));
      renderer = context->renderer();
    }
    std::unique_ptr<drape::gpu::Renderer> painter;
    if (!pngDir.empty()) {
      std::filesystem::create_directories(pngDir);
      painter = std::make_unique<drape::gpu::Renderer>(*context, 960, 540);
    }
    // A picture of frame f: the camera follows the cloth's centre from the side and above, the slope a checkered
    // rectangle around it. drawCloth draws the cloth itself (from the GPU's buffer or from CPU positions).
    const Eigen::Vector3d down = drape::scenes::downhill(c.angleDeg);
    const Eigen::Vector3d slopeNormal = drape::scenes::slopeRotation(c.angleDeg) * Eigen::Vector3d::UnitZ();
    auto picture = [&](int f, const Eigen::Vector3d& centre, const std::function<void()>& drawCloth) {
      if (!painter || f % pngEvery != 0) return;
      drape::gpu::Camera cam;
      cam.target = centre;
      cam.eye = centre + Eigen::Vector3d(1.9, 0.7, 1.9);
      painter->begin(cam);
      const Eigen::Vector3d onSlope = centre - slopeNormal.dot(centre) * slopeNormal, across = Eigen::Vector3d::UnitX();
      drape::gpu::DrawMesh slope;
      if (c.ridge) {  // the two upper faces of the ridge, from its top edge down
        const double side = 2 * drape::scenes::kRidgeHalfSide;
        for (double a : {-2.0, 2.0})
          for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, -side, -side), Eigen::Vector3d(0, 0, 0),
                                           Eigen::Vector3d(0, side, -side)})
            slope.positions.push_back(p / std::numbers::sqrt2 + Eigen::Vector3d(centre.x() + a, 0, 0));
        slope.triangles = {{0, 3, 4}, {0, 4, 1}, {1, 4, 5}, {1, 5, 2}};
      } else {
        for (double a : {-2.0, 2.0})
          for (double b : {-3.0, 3.0}) slope.positions.push_back(onSlope + a * across + b * down);
        slope.triangles = {{0, 2, 3}, {0, 3, 1}};
      }
      painter->draw(slope, Eigen::Vector3f(0.75f, 0.75f, 0.72f), true);
      drawCloth();
      const auto rgba = painter->pixels();
      char name[32];
      std::snprintf(name, sizeof name, "/frame_%04d.png", f);
      if (!stbi_write_png((pngDir + name).c_str(), painter->width(), painter->height(), 4, rgba.data(), painter->width() * 4))
        throw drape::Error("cannot write " + pngDir + name);
    };
    const Eigen::Vector3f clothColour(0.85f, 0.35f, 0.15f);
#endif
    if (gpu) {
#if DRAPE_SAMPLE_GPU
      if (scalar != "float") throw drape::Error("--gpu runs float only");
      const auto parts = drape::scenes::slopeParts<float>(c);
      drape::gpu::Solver solver(*context, parts.asset, parts.settings, c.areaDensity);
      parts.addSolidsTo(solver);
      r = drape::scenes::runSlopeOn(solver, c, [&](int f) {
        if (!painter || f % pngEvery != 0) return;
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (drape::Index i = 0; i < solver.vertexCount(); ++i) centre += solver.position(i) / double(solver.vertexCount());
        picture(f, centre, [&] { painter->drawTriangles(solver.positionBuffer(), solver.origin(), solver.faceBuffer(), clothColour); });
      });
      device = std::string("gpu/") + drape::gpu::toString(context->backend());
#else
      throw drape::Error("this build has no GPU part (it needs glad, Debian python3-glad, and libegl-dev)");
#endif
    } else if (!pngDir.empty()) {
#if DRAPE_SAMPLE_GPU
      auto run = [&](auto& solver) {
        drape::gpu::DrawMesh cloth;
        cloth.triangles = solver.asset().triangles;
        return drape::scenes::runSlopeOn(solver, c, [&](int f) {
          if (f % pngEvery != 0) return;
          cloth.positions.resize(std::size_t(solver.vertexCount()));
          Eigen::Vector3d centre = Eigen::Vector3d::Zero();
          for (drape::Index i = 0; i < solver.vertexCount(); ++i)
            centre += (cloth.positions[std::size_t(i)] = solver.position(i)) / double(solver.vertexCount());
          picture(f, centre, [&] { painter->draw(cloth, clothColour); });
        });
      };
      if (scalar == "double") {
        auto solver = drape::scenes::makeSlope<double>(c);
        r = run(solver);
      } else {
        auto solver = drape::scenes::makeSlope<float>(c);
        r = run(solver);
      }
#else
      throw drape::Error("this build cannot draw pictures (it needs glad, Debian python3-glad, and libegl-dev)");
#endif
    } else {
      r = scalar == "double" ? drape::scenes::runSlope<double>(c) : drape::scenes::runSlope<float>(c);
    }
    nlohmann::ordered_json j;
    j["device"] = device;
    if (!renderer.empty()) j["renderer"] = renderer;
    j["vertices"] = r.vertices;
    j["faces"] = r.faces;
    j["substeps"] = c.subSteps;
    j["iterations"] = c.iterations;
    j["scalar"] = scalar;
    j["method"] = method;
    j["angle_deg"] = c.angleDeg;
    j["friction"] = c.friction;
    j["gap"] = c.gap;
    j["ridge"] = c.ridge;
    j["continuous_contact"] = c.base.continuousContact;
    j["frames"] = c.frames;
    j["dt"] = c.dt;
    j["ms_per_frame"] = r.msPerFrame;
    j["ns_per_vertex_substep"] = r.nsPerVertexSubstep;
    j["mean_ms_per_frame"] = r.meanMsPerFrame;  // the whole run, the landing included
    j["mean_ns_per_vertex_substep"] = r.meanNsPerVertexSubstep;
    j["trembling_rms"] = r.tremblingRms;
    j["trembling_max"] = r.tremblingMax;
    j["trembling_rms_centred"] = r.tremblingRmsCentred;
    j["trembling_max_centred"] = r.tremblingMaxCentred;
    if (r.fitted())
      j["acceleration"] = r.acceleration;
    else
      j["acceleration"] = nullptr;
    j["analytic_acceleration"] = r.analyticAcceleration;
    j["creep"] = r.creep;
    j["max_penetration"] = r.maxPenetration;
    j["max_thickness_shortfall"] = r.maxShortfall;
    j["mean_strain"] = r.meanStrain;
    j["max_strain"] = r.maxStrain;
    j["contact_fraction"] = r.contactFraction;
    j["finite"] = r.finite;
    j["diverged"] = r.diverged();
    if (json) std::cout << j.dump() << '\n';
    char acceleration[64];
    if (r.fitted())
      std::snprintf(acceleration, sizeof acceleration, "%.4f m/s^2", r.acceleration);
    else
      std::snprintf(acceleration, sizeof acceleration, "not fitted (%d frames in the window)", r.fittedFrames);
    std::fprintf(stderr,
                 "%s: %s/%s %dx%d, %d substeps x %d iterations, %s, mu %.2f, %d frames: %.3f ms/frame "
                 "(%.1f ns per vertex-substep; mean %.1f with the landing)\n  trembling rms %.3g m/s (max %.3g), acceleration %s "
                 "(analytic %.4f), creep %.3g m/s, penetration %.3g m, strain mean %.3g max %.3g, contact %.0f%%\n",
                 device.c_str(), method.c_str(), scalar.c_str(), c.nx, c.ny, c.subSteps, c.iterations,
                 c.ridge ? "ridge" : (std::to_string(int(std::lround(c.angleDeg))) + " deg").c_str(), c.friction,
                 c.frames, r.msPerFrame, r.nsPerVertexSubstep, r.meanNsPerVertexSubstep, r.tremblingRms, r.tremblingMax, acceleration,
                 r.analyticAcceleration, r.creep, r.maxPenetration, r.meanStrain, r.maxStrain,
                 100 * r.contactFraction);
    // Exit codes: 3, the run diverged and its figures mean nothing; 4, too short to fit the acceleration.
    if (r.diverged()) {
      char why[96];
      if (!r.finite)
        std::snprintf(why, sizeof why, "positions are not finite");
      else if (r.maxStrain > drape::scenes::SlopeResult::kDivergedStrain)
        std::snprintf(why, sizeof why, "edges up to %.3g times their rest length", 1 + r.maxStrain);
      else
        std::snprintf(why, sizeof why, "a vertex %.3g m inside the solid: the cloth went through it", r.maxPenetration);
      std::fprintf(stderr,
                   "inclined_plane: the run diverged (%s): its figures are meaningless; try more substeps or a "
                   "shorter --dt\n",
                   why);
      return 3;
    }
    if (!r.fitted()) {
      int enough = c.frames;  // the fewest frames whose window holds kMinFitFrames
      while (enough - std::clamp(int(c.windowStart * enough), 1, enough) < drape::scenes::SlopeResult::kMinFitFrames)
        ++enough;
      std::fprintf(stderr, "inclined_plane: %d frames are too few to fit an acceleration: run at least %d\n",
                   c.frames, enough);
      return 4;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "inclined_plane: " << e.what() << '\n';
    return 2;
  }
}
