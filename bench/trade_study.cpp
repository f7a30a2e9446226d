// Trade study: accuracy against cost of the solver's settings on three scenes with a
// known answer, single thread.
//
// Scenes (cloth 21 x 31 vertices, 2 cm spacing, dt 1/60 s; all three share the cloth):
//   hanging  scenes/hanging.hpp: a horizontal sheet pinned at the two corners of a short edge swings down and
//            settles (the driver removes 10 % of the velocity per frame; 180 frames). Errors: stretch strain
//            (mean, max; the answer is 0), the drop of the lowest vertex and of the pinned edge's middle vertex
//            below the pins, and the RMS of all positions, each against the reference run.
//   slope    scenes/slope.hpp (runSlope): the cloth lands on a 30 degree plane. Sliding run, mu 0.3, 240 frames:
//            acceleration error against g (sin - mu cos), trembling over the second half, penetration. Sticking
//            run, mu 0.8 > tan 30: creep (mean downhill speed over the second half; the answer is 0).
//   drop     scenes/drop.hpp: the cloth falls 10 cm onto a ball (radius 15 cm, mu 0.3) and drapes, 72 frames.
//            Error: RMS over all vertices and 12 sample times (every 0.1 s) of the distance to the reference
//            run's positions; penetration of vertices and faces (PGD, 64 evaluations) at every frame's end.
//            Once the cloth touches the ball, stick/slip and folding make the trajectory sensitive: the check
//            row (below) gives the error floor this metric can resolve.
// Reference (hanging, drop): double, 1000 substeps, 2 iterations, faces, PGD 12, same dt. A check row
// (double, 500 substeps, same iterations) shows how far the reference itself is from converged. The slope's
// answer is analytic, so it has no reference or check run (a 1000-substep slope run would double the study).
//
// Design: the full factorial (6 x 4 x 2 x 3 x 4 = 576 per scene) is too big; instead, around the default
// (float, faces, 10 substeps, 1 iteration, PGD 12):
//   grid    substeps {1, 2, 5, 10, 20, 50} x iterations {1, 2, 5, 10}    (float, faces, PGD 12)   24
//   method  {in-solve, vertices} x substeps {1, 2, 5, 10, 20, 50}          (float, 1 iteration, PGD 12) 12
//   scalar  double x substeps {1, 2, 5, 10, 20, 50}                      (faces, 1 iteration, PGD 12) 6
//   pgd     PGD {1, 2, 4} x substeps {2, 10}                             (float, faces, 1 iteration) 6
// so every listed value of every axis appears (faces, float and PGD 12 through the grid), each axis is
// crossed with substeps, and substeps are crossed with iterations: 48 configurations on each of the 3 scenes.
// The hanging cloth touches no solid, so its method and PGD rows repeat the default's computation, and the
// slope is a plane (no face pass), so its PGD rows do too: they are listed (axis_applies 0) but left out of the
// Pareto fronts and the plot.
// --quick runs 5 configurations on shortened scenes against a cheap reference (double, 100 substeps): a smoke
// test of the whole pipeline in seconds, not a result.
//
// Cost: after each run the scene goes on from its end state (hanging settled, slope sliding, cloth on the
// ball) and the tool times 5 blocks of frames (each block >= 15 ms), the cost being the median block's
// ms per frame and ns per vertex-substep. The run's own median frame time is kept too (run_ms_per_frame).
//
// Feature costs: for each feature, the scene's state after a default run is copied into two solvers that
// differ only in that feature; they are timed in alternating blocks from the same state (11 pairs) and the
// marginal cost is the median of the paired differences in ns per vertex-substep. Blocks are short (>= 10 ms)
// because the variants' states drift apart within a block (a frictionless cloth starts to slide off the ball),
// and on the ball the face pass's cost depends on the state.
//
// Outputs in --out (default docs/trade in the source tree): trade.csv, trade.md, trade_pareto_<scene>.csv,
// trade_features.csv, trade_features.md, and trade.png drawn by bench/plot_trade.gp when gnuplot is found:
//   gnuplot -e "dir='docs/trade'" bench/plot_trade.gp
//
// Run: build/bench/trade_study [--quick] [--out DIR] [--no-plot]

#include "drop.hpp"
#include "hanging.hpp"
#include "slope.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#ifndef DRAPE_SOURCE_DIR
#define DRAPE_SOURCE_DIR "."
#endif

namespace {

using drape::CollisionMethod;
using drape::Index;
using Clock = std::chrono::steady_clock;
namespace scenes = drape::scenes;

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t k = v.size() / 2;
  return v.size() % 2 ? v[k] : 0.5 * (v[k - 1] + v[k]);
}

// --- configurations -------------------------------------------------------------------------------------

struct Config {
  bool dbl = false;
  CollisionMethod method = CollisionMethod::Faces;
  int substeps = 10, iterations = 1, pgd = 12;
  std::string sweeps;          // the parts of the design that include it, ';'-separated
  std::string role = "sweep";  // sweep, reference or check

  const char* scalar() const { return dbl ? "double" : "float"; }
  std::string key() const {
    return std::string(scalar()) + "/" + drape::toString(method) + "/" + std::to_string(substeps) + "x" +
           std::to_string(iterations) + "/pgd" + std::to_string(pgd) + "/" + role;
  }
  /// The plot's point style: method and scalar, with reduced PGD budgets apart.
  std::string group() const {
    return std::string(drape::toString(method)) + "/" + scalar() + (pgd != 12 ? "/pgd<12" : "");
  }
  std::string label() const {
    std::string s = std::to_string(substeps) + "x" + std::to_string(iterations);
    if (method != CollisionMethod::Faces) s += std::string(" ") + drape::toString(method);
    if (dbl) s += " dbl";
    if (pgd != 12) s += " pgd" + std::to_string(pgd);
    return s;
  }
  drape::Settings settings() const {
    drape::Settings s;
    s.subStepCount = substeps;
    s.iterationCount = iterations;
    s.collisionMethod = method;
    s.pgdIterations = pgd;
    return s;
  }
};

Config make(bool dbl, CollisionMethod method, int substeps, int iterations, int pgd, const char* role = "sweep") {
  Config c;
  c.dbl = dbl;
  c.method = method;
  c.substeps = substeps;
  c.iterations = iterations;
  c.pgd = pgd;
  c.role = role;
  return c;
}

std::vector<Config> design(bool quick, const Config& reference, const Config& check) {
  std::vector<Config> out;
  auto add = [&](Config c, const std::string& sweep) {
    c.sweeps = sweep;
    for (auto& o : out)
      if (o.key() == c.key()) {
        o.sweeps += ";" + sweep;
        return;
      }
    out.push_back(c);
  };
  const CollisionMethod faces = CollisionMethod::Faces;
  if (quick) {
    for (int s : {2, 10}) add(make(false, faces, s, 1, 12), "grid");
    add(make(false, CollisionMethod::Vertices, 10, 1, 12), "method");
    add(make(false, CollisionMethod::InSolve, 10, 1, 12), "method");
    add(make(true, faces, 10, 1, 12), "scalar");
    add(make(false, faces, 10, 1, 2), "pgd");
  } else {
    const int substeps[] = {1, 2, 5, 10, 20, 50};
    for (int s : substeps)
      for (int i : {1, 2, 5, 10}) add(make(false, faces, s, i, 12), "grid");
    for (auto m : {CollisionMethod::InSolve, CollisionMethod::Vertices})
      for (int s : substeps) add(make(false, m, s, 1, 12), "method");
    for (int s : substeps) add(make(false, faces, s, 1, 12), "method");
    for (int s : substeps) add(make(true, faces, s, 1, 12), "scalar");
    for (int s : substeps) add(make(false, faces, s, 1, 12), "scalar");
    for (int s : {2, 10})
      for (int p : {1, 2, 4, 12}) add(make(false, faces, s, 1, p), "pgd");
  }
  add(reference, "reference");
  if (check.substeps > 0) add(check, "check");
  return out;
}

// --- timing ---------------------------------------------------------------------------------------------

struct Cost {
  double msPerFrame = 0, nsPerVertexSubstep = 0;
};

/// Times `reps` blocks of frames from the solver's current state; each block lasts at least blockMs.
template <class SolverT> Cost timeBlocks(SolverT& solver, double dt, int reps, double blockMs) {
  auto t0 = Clock::now();
  solver.step(dt);  // warm and calibrate
  const double one = std::max(msSince(t0), 1e-4);
  const int frames = std::clamp(int(std::ceil(blockMs / one)), 1, 400);
  std::vector<double> perFrame;
  for (int r = 0; r < reps; ++r) {
    t0 = Clock::now();
    for (int f = 0; f < frames; ++f) solver.step(dt);
    perFrame.push_back(msSince(t0) / frames);
  }
  Cost c;
  c.msPerFrame = median(perFrame);
  c.nsPerVertexSubstep = c.msPerFrame * 1e6 / (double(solver.vertexCount()) * solver.settings().subStepCount);
  return c;
}

// --- results --------------------------------------------------------------------------------------------

struct Row {
  std::string scene;
  Config cfg;
  int vertices = 0;
  Cost cost;
  double runMsPerFrame = 0;
  std::map<std::string, double> m;  // metrics by column name
  bool finite = true;
  bool pareto = false;
  double get(const std::string& k) const {
    auto it = m.find(k);
    return it == m.end() ? std::numeric_limits<double>::quiet_NaN() : it->second;
  }
};

// Metric columns, in CSV order; a scene leaves the others empty.
const std::vector<std::string> kColumns = {
    "error",         "strain_mean",    "strain_max",      "lowest_drop",  "lowest_drop_err", "centre_drop",
    "centre_drop_err", "shape_rms_err", "max_speed_end",  "accel",        "accel_analytic",  "accel_err",
    "trembling_rms", "trembling_max",  "trembling_rms_centred", "creep",   "traj_rms_err",    "final_rms_err",
    "penetration",   "shortfall"};

// The error each scene's Pareto front and plot panel uses.
struct Panel {
  std::string name, scene, column, title;
};
const std::vector<Panel> kPanels = {
    {"hanging", "hanging", "lowest_drop_err", "hanging: |lowest drop - reference| (m)"},
    {"hanging_strain", "hanging", "strain_max", "hanging: max stretch strain"},
    {"slope", "slope", "accel_err", "slope: |a - g(sin - mu cos)| (m/s^2)"},
    {"drop", "drop", "traj_rms_err", "drop: trajectory RMS error vs reference (m)"},
};

struct Scenes {
  scenes::HangingConfig hanging;
  scenes::SlopeConfig slide, stick;
  scenes::DropConfig drop;
  int reps = 5;
  double blockMs = 15;
};

Scenes makeScenes(bool quick) {
  Scenes s;
  s.hanging.frames = quick ? 40 : 180;
  s.slide.nx = s.stick.nx = 21;
  s.slide.ny = s.stick.ny = 31;
  s.slide.spacing = s.stick.spacing = 0.02;
  s.slide.friction = 0.3;
  s.stick.friction = 0.8;
  s.slide.frames = s.stick.frames = quick ? 40 : 240;
  s.drop.frames = quick ? 24 : 72;
  s.reps = quick ? 3 : 5;
  s.blockMs = quick ? 2 : 15;
  return s;
}

double rmsDistance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]).squaredNorm();
  return std::sqrt(sum / double(a.size()));
}

template <class S> scenes::HangingResult hangingRun(const Scenes& sc, const Config& cfg, Cost& cost) {
  auto c = sc.hanging;
  c.base = cfg.settings();
  c.subSteps = cfg.substeps;
  c.iterations = cfg.iterations;
  return scenes::runHanging<S>(c, [&](drape::Solver<S>& s) { cost = timeBlocks(s, c.dt, sc.reps, sc.blockMs); });
}

template <class S> scenes::DropResult dropRun(const Scenes& sc, const Config& cfg, Cost& cost) {
  auto c = sc.drop;
  c.base = cfg.settings();
  c.subSteps = cfg.substeps;
  c.iterations = cfg.iterations;
  return scenes::runDrop<S>(c, [&](drape::Solver<S>& s) { cost = timeBlocks(s, c.dt, sc.reps, sc.blockMs); });
}

template <class S> Row slopeRow(const Scenes& sc, const Config& cfg) {
  Row row;
  row.scene = "slope";
  row.cfg = cfg;
  auto slide = sc.slide, stick = sc.stick;
  for (auto* c : {&slide, &stick}) {
    c->base = cfg.settings();
    c->subSteps = cfg.substeps;
    c->iterations = cfg.iterations;
    c->method = cfg.method;
  }
  const auto a = scenes::runSlope<S>(slide);
  const auto b = scenes::runSlope<S>(stick);
  auto solver = scenes::makeSlope<S>(slide);  // cost while sliding, after landing
  for (int f = 0; f < 60; ++f) solver.step(slide.dt);
  row.cost = timeBlocks(solver, slide.dt, sc.reps, sc.blockMs);
  row.vertices = a.vertices;
  row.runMsPerFrame = a.msPerFrame;
  row.finite = a.finite && b.finite;
  row.m["accel"] = a.acceleration;
  row.m["accel_analytic"] = a.analyticAcceleration;
  row.m["accel_err"] = std::abs(a.acceleration - a.analyticAcceleration);
  row.m["trembling_rms"] = a.tremblingRms;
  row.m["trembling_max"] = a.tremblingMax;
  row.m["trembling_rms_centred"] = a.tremblingRmsCentred;
  row.m["creep"] = b.creep;
  row.m["penetration"] = std::max(a.maxPenetration, b.maxPenetration);
  row.m["shortfall"] = std::max(a.maxShortfall, b.maxShortfall);
  row.m["strain_mean"] = a.meanStrain;
  row.m["strain_max"] = a.maxStrain;
  row.m["error"] = row.m["accel_err"];
  return row;
}

struct References {
  scenes::HangingResult hanging;
  scenes::DropResult drop;
};

Row hangingRow(const Scenes& sc, const Config& cfg, const References* ref, scenes::HangingResult* keep) {
  Row row;
  row.scene = "hanging";
  row.cfg = cfg;
  const auto r = cfg.dbl ? hangingRun<double>(sc, cfg, row.cost) : hangingRun<float>(sc, cfg, row.cost);
  row.vertices = r.vertices;
  row.runMsPerFrame = r.msPerFrame;
  row.finite = r.finite;
  row.m["strain_mean"] = r.meanStrain;
  row.m["strain_max"] = r.maxStrain;
  row.m["lowest_drop"] = r.lowestDrop;
  row.m["centre_drop"] = r.centreDrop;
  row.m["max_speed_end"] = r.maxSpeed;
  if (ref) {
    row.m["lowest_drop_err"] = std::abs(r.lowestDrop - ref->hanging.lowestDrop);
    row.m["centre_drop_err"] = std::abs(r.centreDrop - ref->hanging.centreDrop);
    row.m["shape_rms_err"] = rmsDistance(r.x, ref->hanging.x);
    row.m["error"] = row.m["lowest_drop_err"];
  }
  if (keep) *keep = r;
  return row;
}

Row dropRow(const Scenes& sc, const Config& cfg, const References* ref, scenes::DropResult* keep) {
  Row row;
  row.scene = "drop";
  row.cfg = cfg;
  const auto r = cfg.dbl ? dropRun<double>(sc, cfg, row.cost) : dropRun<float>(sc, cfg, row.cost);
  row.vertices = r.vertices;
  row.runMsPerFrame = r.msPerFrame;
  row.finite = r.finite;
  row.m["penetration"] = r.maxPenetration;
  row.m["shortfall"] = r.maxShortfall;
  row.m["strain_mean"] = r.meanStrain;
  row.m["strain_max"] = r.maxStrain;
  if (ref) {
    double sum = 0;
    for (std::size_t k = 0; k < r.samples.size(); ++k) sum += std::pow(rmsDistance(r.samples[k], ref->drop.samples[k]), 2);
    row.m["traj_rms_err"] = std::sqrt(sum / double(r.samples.size()));
    row.m["final_rms_err"] = rmsDistance(r.samples.back(), ref->drop.samples.back());
    row.m["error"] = row.m["traj_rms_err"];
  }
  if (keep) *keep = r;
  return row;
}

/// False where the row differs from the default only along an axis the scene cannot feel, so it repeats the
/// default's computation (the hanging cloth touches no solid: method and PGD do nothing; the slope is a plane,
/// whose face pass is skipped: PGD does nothing). Such rows stay in the tables but not in fronts or plots.
bool axisApplies(const Row& r) {
  if (r.scene == "hanging") return r.cfg.method == CollisionMethod::Faces && r.cfg.pgd == 12;
  if (r.scene == "slope") return r.cfg.pgd == 12;
  return true;
}

// --- Pareto fronts --------------------------------------------------------------------------------------

/// Indices of the sweep rows of `scene` not dominated in (ms per frame, column): sorted by cost, each one more
/// accurate than every cheaper one by more than 1 % (closer errors are the same answer: float and double
/// often agree to a few digits, and the cheaper of the two then stands for both).
std::vector<std::size_t> paretoFront(const std::vector<Row>& rows, const std::string& scene, const std::string& col) {
  std::vector<std::size_t> idx;
  for (std::size_t k = 0; k < rows.size(); ++k)
    if (rows[k].scene == scene && rows[k].cfg.role == "sweep" && axisApplies(rows[k]) &&
        std::isfinite(rows[k].get(col)) && rows[k].finite)
      idx.push_back(k);
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    if (rows[a].cost.msPerFrame != rows[b].cost.msPerFrame) return rows[a].cost.msPerFrame < rows[b].cost.msPerFrame;
    return rows[a].get(col) < rows[b].get(col);
  });
  std::vector<std::size_t> front;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k : idx)
    if (rows[k].get(col) < 0.99 * best) {
      best = rows[k].get(col);
      front.push_back(k);
    }
  return front;
}

// --- output ---------------------------------------------------------------------------------------------

std::string num(double v, int digits = 4) {
  if (!std::isfinite(v)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

void writeConfigHeader(std::ostream& o) {
  o << "scene,role,sweeps,group,label,scalar,method,substeps,iterations,pgd_iterations,vertices,ms_per_frame,"
       "ns_per_vertex_substep,run_ms_per_frame";
}
void writeConfigCells(std::ostream& o, const Row& r) {
  o << r.scene << ',' << r.cfg.role << ',' << r.cfg.sweeps << ',' << r.cfg.group() << ',' << r.cfg.label() << ','
    << r.cfg.scalar() << ',' << drape::toString(r.cfg.method) << ',' << r.cfg.substeps << ',' << r.cfg.iterations
    << ',' << r.cfg.pgd << ',' << r.vertices << ',' << num(r.cost.msPerFrame) << ','
    << num(r.cost.nsPerVertexSubstep) << ',' << num(r.runMsPerFrame);
}

void writeCsv(const std::filesystem::path& path, const std::vector<Row>& rows) {
  std::ofstream o(path);
  writeConfigHeader(o);
  for (const auto& c : kColumns) o << ',' << c;
  o << ",finite,axis_applies,pareto\n";
  for (const auto& r : rows) {
    writeConfigCells(o, r);
    for (const auto& c : kColumns) o << ',' << num(r.get(c), 6);
    o << ',' << (r.finite ? 1 : 0) << ',' << (axisApplies(r) ? 1 : 0) << ',' << (r.pareto ? 1 : 0) << '\n';
  }
}

struct MdColumn {
  std::string head, key;
};

void writeMarkdown(const std::filesystem::path& path, const std::vector<Row>& rows,
                   const std::map<std::string, std::vector<std::size_t>>& fronts, const std::string& preamble) {
  std::ofstream o(path);
  o << preamble;
  const std::map<std::string, std::vector<MdColumn>> cols = {
      {"hanging",
       {{"strain mean", "strain_mean"}, {"strain max", "strain_max"}, {"lowest drop (m)", "lowest_drop"},
        {"lowest err (m)", "lowest_drop_err"}, {"centre drop (m)", "centre_drop"},
        {"centre err (m)", "centre_drop_err"}, {"shape RMS err (m)", "shape_rms_err"},
        {"max speed at end (m/s)", "max_speed_end"}}},
      {"slope",
       {{"accel (m/s²)", "accel"}, {"accel err", "accel_err"}, {"trembling rms (m/s)", "trembling_rms"},
        {"trembling max", "trembling_max"}, {"creep μ0.8 (m/s)", "creep"}, {"penetration (m)", "penetration"},
        {"shortfall (m)", "shortfall"}, {"strain max", "strain_max"}}},
      {"drop",
       {{"trajectory RMS err (m)", "traj_rms_err"}, {"final RMS err (m)", "final_rms_err"},
        {"penetration (m)", "penetration"}, {"shortfall (m)", "shortfall"}, {"strain max", "strain_max"}}},
  };
  for (const char* scene : {"hanging", "slope", "drop"}) {
    o << "\n## " << scene << "\n\n";
    // Pareto summary first.
    for (const auto& p : kPanels) {
      if (p.scene != scene) continue;
      o << "Pareto front of " << p.title << " against ms per frame: ";
      const auto& f = fronts.at(p.name);
      for (std::size_t k = 0; k < f.size(); ++k)
        o << (k ? ", " : "") << rows[f[k]].cfg.label() << " (" << num(rows[f[k]].get(p.column), 3) << " at "
          << num(rows[f[k]].cost.msPerFrame, 3) << " ms)";
      o << ".\n\n";
    }
    o << "| role | sweeps | scalar | method | substeps | iterations | PGD | ms/frame | ns/vertex-substep";
    for (const auto& c : cols.at(scene)) o << " | " << c.head;
    o << " | Pareto |\n|---|---|---|---|---|---|---|---|---";
    for (std::size_t k = 0; k < cols.at(scene).size(); ++k) o << "|---";
    o << "|---|\n";
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const Row& r = rows[k];
      if (r.scene != scene) continue;
      std::string marks;
      for (const auto& p : kPanels)
        if (p.scene == scene && std::count(fronts.at(p.name).begin(), fronts.at(p.name).end(), k))
          marks += (marks.empty() ? "" : ", ") + p.column;
      o << "| " << r.cfg.role << " | " << r.cfg.sweeps << " | " << r.cfg.scalar() << " | "
        << drape::toString(r.cfg.method) << " | " << r.cfg.substeps << " | " << r.cfg.iterations << " | " << r.cfg.pgd
        << " | " << num(r.cost.msPerFrame, 3) << " | " << num(r.cost.nsPerVertexSubstep, 3);
      for (const auto& c : cols.at(scene)) o << " | " << num(r.get(c.key), 3);
      o << " | " << marks << (r.finite ? "" : " NOT FINITE")
        << (axisApplies(r) ? "" : " (axis has no effect here: repeats the default)") << " |\n";
    }
  }
}

// --- feature costs --------------------------------------------------------------------------------------

struct Snapshot {
  std::vector<Eigen::Vector3d> x, v;
};
template <class SolverT> Snapshot snapshot(const SolverT& s) {
  Snapshot out;
  for (Index i = 0; i < s.vertexCount(); ++i) {
    out.x.push_back(s.position(i));
    out.v.push_back(s.velocity(i));
  }
  return out;
}
template <class SolverT> void restore(SolverT& s, const Snapshot& snap) {
  s.setPositions(snap.x);
  s.setVelocities(snap.v);
}

struct Feature {
  std::string name, scene, with, without;
  double onNs = 0, offNs = 0, marginalNs = 0, marginalLowNs = 0, marginalHighNs = 0;
  int pairs = 0, framesPerBlock = 0;
};

/// Times the two variants in alternating blocks from the same state; each factory returns a ready solver.
template <class MakeOn, class MakeOff>
Feature pairedCost(Feature f, const Snapshot& snap, double dt, int pairs, double blockMs, MakeOn makeOn,
                   MakeOff makeOff) {
  // Calibrate the block length on the feature-on variant.
  int frames = 1;
  {
    auto s = makeOn();
    restore(s, snap);
    s.step(dt);
    const auto t0 = Clock::now();
    s.step(dt);
    frames = std::clamp(int(std::ceil(blockMs / std::max(msSince(t0), 1e-4))), 1, 400);
  }
  std::vector<double> on, off, diff;
  for (int p = 0; p < pairs; ++p) {
    double ns[2] = {0, 0};
    for (int k = 0; k < 2; ++k) {
      const bool isOn = (k == 0) == (p % 2 == 0);  // alternate which goes first
      auto time = [&](auto s) {
        restore(s, snap);
        s.step(dt);  // warm: contacts found, caches filled
        const auto t0 = Clock::now();
        for (int i = 0; i < frames; ++i) s.step(dt);
        return msSince(t0) * 1e6 / frames / (double(s.vertexCount()) * s.settings().subStepCount);
      };
      ns[isOn ? 0 : 1] = isOn ? time(makeOn()) : time(makeOff());
    }
    on.push_back(ns[0]);
    off.push_back(ns[1]);
    diff.push_back(ns[0] - ns[1]);
  }
  std::sort(diff.begin(), diff.end());
  f.onNs = median(on);
  f.offNs = median(off);
  f.marginalNs = median(diff);
  f.marginalLowNs = diff.front();
  f.marginalHighNs = diff.back();
  f.pairs = pairs;
  f.framesPerBlock = frames;
  return f;
}

std::vector<Feature> featureCosts(const Scenes& sc, bool quick) {
  const int pairs = quick ? 3 : 11;
  const double blockMs = quick ? 2 : 10;  // short blocks: the two variants' states diverge less within one
  std::vector<Feature> out;
  Config def;  // float, faces, 10 x 1, PGD 12
  const double dt = 1.0 / 60.0;
  auto settle = [&](auto& s, int frames) {
    for (int f = 0; f < frames; ++f) s.step(dt);
  };
  const int settleFrames = quick ? 20 : 90;

  // Hanging: no solids, so the constraint solve alone.
  {
    auto c = sc.hanging;
    c.base = def.settings();
    auto base = scenes::makeHanging<float>(c);
    for (int f = 0; f < settleFrames; ++f) {
      base.step(dt);
      scenes::dampVelocities(base, c.damping);
    }
    const Snapshot snap = snapshot(base);
    auto noBending = c;
    noBending.bending = false;
    out.push_back(pairedCost({"bending constraints", "hanging", "grid asset with bending pairs",
                              "AssetOptions::bending = false"},
                             snap, dt, pairs, blockMs, [&] { return scenes::makeHanging<float>(c); },
                             [&] { return scenes::makeHanging<float>(noBending); }));
    out.push_back(pairedCost(
        {"declared shape types", "hanging", "Solver<float> (plane, sphere, box, capsule declared, none added)",
         "BasicSolver<float> (no shape type)"},
        snap, dt, pairs, blockMs, [&] { return scenes::makeHanging<float>(c); },
        [&] { return scenes::makeHanging<float, drape::BasicSolver<float>>(c); }));
  }
  // Ball: the drop scene's state once the cloth lies on the ball.
  {
    auto c = sc.drop;
    c.base = def.settings();
    auto base = scenes::makeDrop<float>(c);
    settle(base, quick ? 24 : 60);
    const Snapshot snap = snapshot(base);
    auto with = [&](auto edit) {
      return [&c, edit] {
        auto cc = c;
        edit(cc);
        return scenes::makeDrop<float>(cc);
      };
    };
    auto same = [](scenes::DropConfig&) {};
    out.push_back(pairedCost({"face contacts + propagation (faces vs vertices)", "drop (ball)",
                              "method faces", "method vertices"},
                             snap, dt, pairs, blockMs, with(same),
                             with([](scenes::DropConfig& d) { d.base.collisionMethod = CollisionMethod::Vertices; })));
    out.push_back(pairedCost(
        {"face contacts (PGD) alone", "drop (ball)", "method faces, propagationRings 0", "method vertices"}, snap, dt,
        pairs, blockMs, with([](scenes::DropConfig& d) { d.base.propagationRings = 0; }),
        with([](scenes::DropConfig& d) { d.base.collisionMethod = CollisionMethod::Vertices; })));
    out.push_back(pairedCost({"propagation", "drop (ball)", "propagationRings 1", "propagationRings 0"}, snap, dt, pairs,
                             blockMs, with(same),
                             with([](scenes::DropConfig& d) { d.base.propagationRings = 0; })));
    out.push_back(pairedCost({"friction", "drop (ball)", "mu 0.3", "mu 0"}, snap, dt, pairs, blockMs, with(same),
                             with([](scenes::DropConfig& d) { d.friction = 0; })));
    out.push_back(pairedCost({"declared shape types", "drop (ball)", "Solver<float> (4 shape types)",
                              "BasicSolver<float, Sphere>"},
                             snap, dt, pairs, blockMs, with(same),
                             [&c] { return scenes::makeDrop<float, drape::BasicSolver<float, drape::Sphere>>(c); }));
  }
  // Slope: every vertex on the plane, sliding.
  {
    auto c = sc.slide;
    c.base = def.settings();
    c.subSteps = def.substeps;
    c.iterations = def.iterations;
    auto base = scenes::makeSlope<float>(c);
    settle(base, quick ? 20 : 60);
    const Snapshot snap = snapshot(base);
    auto frictionless = c;
    frictionless.friction = 0;
    out.push_back(pairedCost({"friction", "slope (plane)", "mu 0.3", "mu 0"}, snap, dt, pairs, blockMs,
                             [&] { return scenes::makeSlope<float>(c); },
                             [&] { return scenes::makeSlope<float>(frictionless); }));
  }
  return out;
}

void writeFeatures(const std::filesystem::path& dir, const std::vector<Feature>& fs) {
  std::ofstream csv(dir / "trade_features.csv");
  csv << "feature,scene,with,without,ns_with,ns_without,marginal_ns,marginal_min_ns,marginal_max_ns,pairs,"
         "frames_per_block\n";
  for (const auto& f : fs)
    csv << '"' << f.name << "\",\"" << f.scene << "\",\"" << f.with << "\",\"" << f.without << "\"," << num(f.onNs)
        << ',' << num(f.offNs) << ',' << num(f.marginalNs) << ',' << num(f.marginalLowNs) << ','
        << num(f.marginalHighNs) << ',' << f.pairs << ',' << f.framesPerBlock << '\n';
  std::ofstream md(dir / "trade_features.md");
  md << "# Feature costs\n\nFloat, 21 x 31 cloth, 10 substeps x 1 iteration, single thread. Each pair times both "
        "variants from the same state (positions and velocities copied from a default run), in alternating order; "
        "ns per vertex-substep, medians over the pairs; the marginal cost is the median of the paired differences "
        "(min and max in brackets).\n\n"
        "| feature | scene | with | without | ns with | ns without | marginal ns | share |\n"
        "|---|---|---|---|---|---|---|---|\n";
  for (const auto& f : fs)
    md << "| " << f.name << " | " << f.scene << " | " << f.with << " | " << f.without << " | " << num(f.onNs, 3)
       << " | " << num(f.offNs, 3) << " | " << num(f.marginalNs, 3) << " [" << num(f.marginalLowNs, 2) << ", "
       << num(f.marginalHighNs, 2) << "] | " << num(100 * f.marginalNs / f.onNs, 2) << " % |\n";
}

std::string shell(const std::string& cmd) {
  std::string out;
  if (FILE* p = popen(cmd.c_str(), "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    pclose(p);
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char ch : s) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, noPlot = false, noFeatures = false;
  std::string out = std::string(DRAPE_SOURCE_DIR) + "/docs/trade";
  std::string plotScript = std::string(DRAPE_SOURCE_DIR) + "/bench/plot_trade.gp";
  std::string only;
  CLI::App app{"drape trade study: accuracy against cost of substeps, iterations, scalar, collision method and PGD "
               "budget on the hanging, slope and drop scenes"};
  app.add_flag("--quick", quick, "a few configurations on shortened scenes (a smoke test, seconds)");
  app.add_option("--out", out, "output directory")->capture_default_str();
  app.add_flag("--no-plot", noPlot, "do not run gnuplot");
  app.add_option("--plot-script", plotScript, "gnuplot script drawing trade.png")->capture_default_str();
  app.add_flag("--no-features", noFeatures, "skip the feature-cost table");
  app.add_option("--only", only, "run only the sweep configurations whose label contains this (development)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e, std::cerr, std::cerr);
  }
  try {
    const auto start = Clock::now();
    const std::string loadBefore = shell("cut -d' ' -f1-3 /proc/loadavg 2>/dev/null");
    const std::filesystem::path dir(out);
    std::filesystem::create_directories(dir);
    const Scenes sc = makeScenes(quick);
    const Config reference = make(true, CollisionMethod::Faces, quick ? 100 : 1000, quick ? 1 : 2, 12, "reference");
    const Config check = make(true, CollisionMethod::Faces, quick ? 0 : 500, reference.iterations, 12, "check");
    std::vector<Config> configs = design(quick, reference, check);
    if (!only.empty())
      std::erase_if(configs, [&](const Config& c) { return c.role == "sweep" && c.label().find(only) == std::string::npos; });

    // References first: the sweep's errors are measured against them.
    References ref;
    std::vector<Row> rows;
    std::fprintf(stderr, "reference %s ...\n", reference.key().c_str());
    rows.push_back(hangingRow(sc, reference, nullptr, &ref.hanging));
    rows.push_back(dropRow(sc, reference, nullptr, &ref.drop));
    for (auto& r : rows) r.m["error"] = 0;
    rows[0].m["lowest_drop_err"] = rows[0].m["centre_drop_err"] = rows[0].m["shape_rms_err"] = 0;
    rows[1].m["traj_rms_err"] = rows[1].m["final_rms_err"] = 0;
    std::fprintf(stderr, "  %.1f s\n", msSince(start) / 1000);

    int k = 0;
    for (const auto& cfg : configs) {
      ++k;
      if (cfg.role == "reference") continue;
      const auto t0 = Clock::now();
      rows.push_back(hangingRow(sc, cfg, &ref, nullptr));
      const bool slope = cfg.role == "sweep";  // the slope's answer is analytic: no reference or check run
      if (slope) rows.push_back(cfg.dbl ? slopeRow<double>(sc, cfg) : slopeRow<float>(sc, cfg));
      rows.push_back(dropRow(sc, cfg, &ref, nullptr));
      const Row none;
      const auto& h = rows[rows.size() - (slope ? 3 : 2)];
      const auto& s = slope ? rows[rows.size() - 2] : none;
      const auto& d = rows.back();
      std::fprintf(stderr,
                   "[%2d/%zu] %-34s %6.1f s | hanging %.3g ms err %.3g strain %.3g | slope %.3g ms aerr %.3g | drop "
                   "%.3g ms err %.3g pen %.3g\n",
                   k, configs.size(), cfg.key().c_str(), msSince(t0) / 1000, h.cost.msPerFrame, h.get("error"),
                   h.get("strain_max"), s.cost.msPerFrame, s.get("error"), d.cost.msPerFrame, d.get("error"),
                   d.get("penetration"));
    }
    // Sweeps of each row's configuration: make the reference rows carry theirs too.
    for (auto& r : rows)
      for (const auto& c : configs)
        if (c.key() == r.cfg.key()) r.cfg.sweeps = c.sweeps;

    std::map<std::string, std::vector<std::size_t>> fronts;
    for (const auto& p : kPanels) {
      fronts[p.name] = paretoFront(rows, p.scene, p.column);
      for (std::size_t i : fronts[p.name])
        if (p.name == p.scene) rows[i].pareto = true;
      std::ofstream o(dir / ("trade_pareto_" + p.name + ".csv"));
      writeConfigHeader(o);
      o << ",error_column,error\n";
      for (std::size_t i : fronts[p.name]) {
        writeConfigCells(o, rows[i]);
        o << ',' << p.column << ',' << num(rows[i].get(p.column), 6) << '\n';
      }
    }
    writeCsv(dir / "trade.csv", rows);
    const double studySeconds = msSince(start) / 1000;

    std::vector<Feature> features;
    if (!noFeatures) {
      std::fprintf(stderr, "feature costs ...\n");
      features = featureCosts(sc, quick);
      writeFeatures(dir, features);
    }

    std::ostringstream pre;
    const std::string src = DRAPE_SOURCE_DIR;
    const std::string commit = shell("git -C " + shellQuote(src) + " rev-parse --short HEAD 2>/dev/null");
    const std::string dirty = shell("git -C " + shellQuote(src) + " status --porcelain -- include 2>/dev/null");
    pre << "# Trade study" << (quick ? " (--quick smoke run: not a result)" : "") << "\n\n"
        << "Generated by `bench/trade_study" << (quick ? " --quick" : "") << "` (see its header comment for the "
        << "design) from commit " << (commit.empty() ? "unknown" : commit)
        << (dirty.empty() ? "" : " with uncommitted changes under include/") << "; the sweep took "
        << num(studySeconds, 3) << " s on the machine that ran it. Cloth 21 x 31 vertices (651), dt 1/60 s, single thread. "
        << "Cost: median of " << sc.reps << " timed blocks of frames from the scene's end state. "
        << "Errors: hanging against the reference run (double, " << reference.substeps << " substeps x "
        << reference.iterations << " iterations); slope against g (sin 30° - 0.3 cos 30°) = "
        << num(9.81 * (0.5 - 0.3 * std::sqrt(3.0) / 2), 5) << " m/s², creep with μ 0.8 (the answer is 0); drop "
        << "against the reference run. Plot: trade.png; Pareto fronts: trade_pareto_<panel>.csv; feature costs: "
        << "trade_features.md. Load average (1, 5, 15 min) at the start: "
        << loadBefore << ", at the end: " << shell("cut -d' ' -f1-3 /proc/loadavg 2>/dev/null")
        << " (other jobs share the cores, so costs carry their noise).\n";
    writeMarkdown(dir / "trade.md", rows, fronts, pre.str());
    std::fprintf(stderr, "wrote %s (study %.1f s, total %.1f s)\n", dir.c_str(), studySeconds, msSince(start) / 1000);

    if (!noPlot) {
      if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
        std::fprintf(stderr, "gnuplot not found: no trade.png (apt-get install gnuplot-nox, then run: gnuplot -e "
                             "\"dir='%s'\" %s)\n",
                     dir.c_str(), plotScript.c_str());
      } else {
        const std::string cmd = "gnuplot -e " + shellQuote("dir='" + dir.string() + "'") + " " + shellQuote(plotScript);
        if (std::system(cmd.c_str()) != 0) {
          std::fprintf(stderr, "trade_study: gnuplot failed: %s\n", cmd.c_str());
          return 1;
        }
        std::fprintf(stderr, "wrote %s\n", (dir / "trade.png").c_str());
      }
    }
    bool allFinite = true;
    for (const auto& r : rows) allFinite = allFinite && r.finite;
    if (!allFinite) std::fprintf(stderr, "trade_study: some run ended with non-finite positions (see trade.md)\n");
    return allFinite ? 0 : 3;
  } catch (const std::exception& e) {
    std::cerr << "trade_study: " << e.what() << '\n';
    return 2;
  }
}
