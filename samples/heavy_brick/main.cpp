// The heavy-brick sample (the cloth-rigid coupling thesis's Fig 6.4): a kinematic brick presses a cloth to the
// floor and the cloth is drawn out from under it by one edge. Prints a summary to stderr; --json prints one JSON
// object on stdout and nothing else there.

#include "heavy_brick.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <iostream>

int main(int argc, char** argv) {
  drape::scenes::BrickConfig c;
  std::string scalar = "float";
  bool json = false;
  CLI::App app{"drape heavy brick: a cloth drawn out from under a brick pressing it to the floor"};
  app.add_option("--squeeze", c.squeeze, "brick bottom above the floor while pressing, in cloth thicknesses")
      ->check(CLI::Range(0.5, 4.0))->capture_default_str();
  app.add_option("--friction", c.friction, "Coulomb friction of the brick and the floor")->check(CLI::Range(0.0, 10.0))->capture_default_str();
  app.add_option("--pull-speed", c.pullSpeed, "m/s of the pulled edge")->check(CLI::Range(0.0, 10.0))->capture_default_str();
  app.add_option("--pull", c.pull, "seconds of pulling")->check(CLI::Range(0.0, 100.0))->capture_default_str();
  app.add_option("--substeps", c.subSteps, "substeps per frame")->check(CLI::Range(1, 10000))->capture_default_str();
  app.add_option("--iterations", c.iterations, "constraint passes per substep")->check(CLI::Range(1, 1000))->capture_default_str();
  app.add_option("--scalar", scalar, "floating-point type")->check(CLI::IsMember({"float", "double"}))->capture_default_str();
  app.add_flag("--json", json, "print one JSON object on stdout");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e, std::cerr, std::cerr);
  }
  try {
    const auto r = scalar == "double" ? drape::scenes::runHeavyBrick<double>(c) : drape::scenes::runHeavyBrick<float>(c);
    nlohmann::ordered_json j;
    j["vertices"] = r.vertices;
    j["frames"] = r.frames;
    j["dt"] = c.dt;
    j["substeps"] = c.subSteps;
    j["iterations"] = c.iterations;
    j["scalar"] = scalar;
    j["squeeze"] = c.squeeze;
    j["friction"] = c.friction;
    j["pulled_m"] = r.pulled;
    j["share_under_brick_start"] = r.underAtStart;
    j["share_under_brick_end"] = r.underAtEnd;
    j["max_floor_penetration"] = r.maxFloorPenetration;
    j["max_brick_penetration"] = r.maxBrickPenetration;
    j["max_speed"] = r.maxSpeed;
    j["trembling_rms_under_brick"] = r.tremblingRms;
    j["max_strain"] = r.maxStrain;
    j["ms_per_frame"] = r.msPerFrame;
    j["finite"] = r.finite;
    if (json) std::cout << j.dump() << '\n';
    std::fprintf(stderr,
                 "%s %d vertices, squeeze %.2f thicknesses, mu %.2f, pulled %.3f m: under the brick %.0f%% -> %.0f%% "
                 "of the cloth\n  penetration floor %.3g m, brick %.3g m; fastest vertex %.3g m/s; vertical rms under "
                 "the brick while pulled %.3g m/s; strain max %.3g; %.3f ms/frame\n",
                 scalar.c_str(), r.vertices, c.squeeze, c.friction, r.pulled, 100 * r.underAtStart,
                 100 * r.underAtEnd, r.maxFloorPenetration, r.maxBrickPenetration, r.maxSpeed, r.tremblingRms,
                 r.maxStrain, r.msPerFrame);
    return r.finite ? 0 : 3;
  } catch (const std::exception& e) {
    std::cerr << "heavy_brick: " << e.what() << '\n';
    return 2;
  }
}
