// Haptic-loop benchmark (issue 27 item 4; docs/performance.md, "Haptic loop"): what a surgical simulator's 1 kHz
// haptic loop gets from fmpc::runtime's Session (runtime/session/session.h). A 0.1 m block of 20^3 cells (9,261
// vertices, 48,000 tetrahedra of co-rotational FEM, E = 5 kPa, nu = 0.49, fixed at its base) and a sphere of 1 cm
// radius on a scripted path (pressed 4 mm into the top face over 0.5 s, then circling 2 cm around its centre every
// 4 s while its depth swings between 3 and 5 mm once a second). Every tick sets the tool's pose, advances the
// simulated time by 1 ms and reads the tool's force: its latency (pose in -> force out) is what a haptic device
// waits for. Two modes: one implicit Euler step of 1 ms per tick, and explicit (semi-implicit Euler at the scene's
// critical step, `dt: auto`) substeps per tick.
//
// The force a tick reports is what a haptic device should render for it: the tool's impulse over the tick's steps
// divided by their duration (Session::step_to_averaging: each substep's force, read at its start for semi-implicit
// Euler and at its end for implicit Euler). The reading at the tick's end alone chatters with explicit substeps (a
// vertex pressed by the penalty bounces between substeps); it stays in the CSV. --force end steps each tick in one
// call (step_to) and reports only that reading: the loop without the per-substep readings, for its latency.
//
// --tissue liver takes the meshed liver instead (rulesets/scenes/liver_meshed.yaml: SOFA's liver-smooth.obj meshed to
// the thesis's 8,508 vertices, co-rotational FEM, E from the liver rules for patient 3, nu 0.45, held at SOFA's three
// points; its probe gives way to the sphere): the same sphere, pressed 4 mm straight down into the upper face where
// the scene's probe presses, then circling 5 mm around that point (the upper face falls away by up to 4.5 mm within
// 1 cm of it, so the block's 2 cm circle would leave the surface). The mesh is fine along the probe's old path
// (`refine_near`), as in the scene.
//
// Ticks are paced at 1 kHz of wall time: a tick starts at its deadline (k ms after the first), or at once when the
// loop is behind; each mode runs for --seconds of wall time. The real-time factor is the simulated time over the wall
// time (1 when the loop keeps up; below 1 it falls behind); an overrun is a tick whose latency exceeds 1 ms.
//
//   fmpc_haptic_bench [--seconds S | --ticks N] [--modes implicit,explicit] [--backend cpu|cuda] [--cells N]
//                     [--threads N] [--precision float|double] [--force mean|end] [--contact-damping R]
//                     [--tissue block|liver [--liver-scene FILE]]
//                     [--out DIR]
//
// --seconds     wall time per mode (default 30)
// --ticks       exactly N ticks per mode instead (the ctest smoke test: 150 ticks on --cells 4, about a second)
// --modes       which modes, comma-separated (default implicit,explicit)
// --backend     cpu (default) or cuda (a build with -DFMPC_CUDA=ON)
// --cells       cells per edge of the block (default 20)
// --threads     CPU worker threads (the scene's `threads`; default 0: the scene's default)
// --precision   double (default) or float
// --force       mean (default): the tick's mean force, one step and one reading at a time; end: the tick-end reading
// --contact-damping  the scene's contact.damping_ratio in explicit mode (default 0: none; implicit mode takes none)
// --tissue      block (default: the 20^3 block above) or liver (the meshed liver; --cells does not apply)
// --liver-scene the meshed liver's scene (default: rulesets/scenes/liver_meshed.yaml of the source tree; its surface
//               is ../shared/data/sofa-liver beside the repository)
// --tolerance, --max-iterations  implicit mode's solver (the scene's `solver: {tolerance, max_iterations}`; default:
//               the scene's default, the CG to 1e-10): what a haptic loop trades for its 1 ms
// --contact-rounds  implicit mode's solves per step with the tool's contact (the scene's `solver: {contact_rounds}`,
//               1 to 8; default: the scene's, 8): 1 solves once with the contact found at the step's start, as SOFA
//               does; the line of implicit solves counts the steps whose contact still changed after their last solve
// --out DIR     writes haptic.csv (one row per mode) and haptic_force_MODE.csv (every tick: time, pose, the mean
//               force, the tick-end force, contacts, latency) into DIR
// Prints one line per mode and a Markdown table. Exit status 0, 1 when a step or a reading fails, 2 on bad arguments.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bench/setup/process_clock.h"
#include "runtime/session/session.h"

using fmpc::DiagnosticList;
using fmpc::runtime::Session;
using fmpc::runtime::SessionOptions;
using fmpc::runtime::ToolPose;
using fmpc::runtime::ToolReading;

namespace {

constexpr double kTick = 1e-3;         // s: a haptic device's period
constexpr double kBlock = 0.1;         // m: the block's edge
constexpr double kRadius = 0.01;       // m: the sphere's radius
constexpr double kCircle = 0.02;       // m: the circle's radius
constexpr double kCirclePeriod = 4.0;  // s
constexpr double kPressTime = 0.5;     // s
constexpr double kDepth = 0.004;       // m: the mean depth once pressed
constexpr double kDepthSwing = 0.001;  // m
constexpr double kStartGap = 0.0005;   // m: the sphere's gap to the top face at t = 0
constexpr double kPi = 3.14159265358979323846;

struct Options {
  double seconds = 30.0;
  std::size_t ticks = 0;  // 0: as many as --seconds allows
  std::vector<std::string> modes = {"implicit", "explicit"};
  std::string backend = "cpu";
  int cells = 20;
  int threads = 0;
  std::string precision = "double";
  bool mean_force = true;  // --force mean
  double contact_damping = 0.0;
  std::string tissue = "block";
  std::string liver_scene = FMPC_SOURCE_DIR "/rulesets/scenes/liver_meshed.yaml";
  std::string out;
  // Implicit Euler's solver (the scene's `solver: {tolerance, max_iterations, contact_rounds}`; 0: the scene default).
  double tolerance = 0.0;
  long max_iterations = 0;
  long contact_rounds = 0;
};

// Where and how the sphere presses (m): the surface point under it, the unit direction it presses along, the radius
// of its circle.
struct Press {
  double contact[3];
  double down[3];
  double circle;
};

constexpr Press kBlockPress = {{kBlock / 2, kBlock / 2, kBlock}, {0.0, 0.0, -1.0}, kCircle};
// liver_meshed.yaml's probe: its ray from (-1.5, 8, 0.5) along -y hits the upper face at y = 5.1205 (mesh units of
// 3.2 cm; found by intersecting the ray with liver-smooth.obj's triangles).
constexpr double kLiverUnit = 0.032;
constexpr Press kLiverPress = {{-1.5 * kLiverUnit, 5.1205 * kLiverUnit, 0.5 * kLiverUnit}, {0.0, -1.0, 0.0}, 0.005};

const Press& press_of(const Options& options) { return options.tissue == "liver" ? kLiverPress : kBlockPress; }

// The meshed liver's scene without its probe and run settings, the sphere and the mode's in their place: the scene's
// top-level sections but loads, integrator, dt, duration, precision, threads and outputs, kept as written, with
// `refine_near` along the probe's path (1 cm down from its hit point) so that the mesh is the scene's.
std::string liver_yaml(const std::string& scene_text, const Press& press) {
  std::istringstream in(scene_text);
  std::ostringstream kept;
  kept.precision(17);
  bool skipping = false;
  for (std::string line; std::getline(in, line);) {
    const bool top = !line.empty() && line[0] != ' ' && line[0] != '#';
    if (top) {
      const std::string key = line.substr(0, line.find(':'));
      skipping = key == "loads" || key == "integrator" || key == "dt" || key == "duration" || key == "precision" ||
                 key == "threads" || key == "outputs" || key == "name";
    }
    if (skipping) continue;
    kept << line << "\n";
    if (line == "mesh:")
      kept << "  refine_near: [[" << press.contact[0] / kLiverUnit << ", " << press.contact[1] / kLiverUnit << ", "
           << press.contact[2] / kLiverUnit << ", " << press.contact[0] / kLiverUnit << ", "
           << (press.contact[1] - 0.01) / kLiverUnit << ", " << press.contact[2] / kLiverUnit << "]]\n";
  }
  return kept.str();
}

// The scene of a mode as YAML (docs/scenes.md); `liver_text` is the meshed liver's scene (--tissue liver).
std::string scene_yaml(const Options& options, const std::string& mode, const std::string& liver_text) {
  std::ostringstream yaml;
  yaml.precision(17);
  const Press& press = press_of(options);
  const double unit = options.tissue == "liver" ? kLiverUnit : 1.0;  // the tool is in mesh units
  const double lift = kRadius + kStartGap;
  yaml << "name: haptic_" << mode << "\n";
  if (options.tissue == "liver") {
    yaml << liver_yaml(liver_text, press);
  } else {
    yaml << "mesh:\n  box: {size: [" << kBlock << ", " << kBlock << ", " << kBlock << "], cells: [" << options.cells
         << ", " << options.cells << ", " << options.cells << "]}\n  units: m\n"
         << "model: corotational_fem\n"
         << "material: {youngs_modulus: 5, poisson_ratio: 0.49}\n"
         << "mass: {density: 1060}\n"
         << "damping: {ratio: 0.9}\n"
         << "fixed:\n  plane: {point: [0, 0, 0], normal: [0, 0, 1]}\n";
  }
  yaml << "tools:\n  - name: tip\n    shape: sphere\n    radius: " << kRadius / unit << "\n"
       << "    pose: {position: [" << (press.contact[0] - lift * press.down[0]) / unit << ", "
       << (press.contact[1] - lift * press.down[1]) / unit << ", " << (press.contact[2] - lift * press.down[2]) / unit
       << "]}\n"
       << (mode == "explicit" && options.contact_damping > 0.0
               ? "contact: {damping_ratio: " + std::to_string(options.contact_damping) + "}\n"
               : std::string())
       << "integrator: " << (mode == "implicit" ? "implicit_euler" : "semi_implicit_euler") << "\n";
  if (mode == "implicit" && (options.tolerance > 0.0 || options.max_iterations > 0 || options.contact_rounds > 0)) {
    const char* separator = "";
    yaml << "solver: {";
    if (options.tolerance > 0.0) yaml << std::exchange(separator, ", ") << "tolerance: " << options.tolerance;
    if (options.max_iterations > 0)
      yaml << std::exchange(separator, ", ") << "max_iterations: " << options.max_iterations;
    if (options.contact_rounds > 0) yaml << separator << "contact_rounds: " << options.contact_rounds;
    yaml << "}\n";
  }
  yaml << "dt: " << (mode == "implicit" ? "0.001" : "auto") << "\n"
       << "duration: 3600\n"
       << "precision: " << options.precision << "\n"
       << "threads: " << options.threads << "\n"
       << "outputs: {frames: 0, precision_check: off}\n";
  return yaml.str();
}

// The tool's scripted pose at simulated time t (s).
// Straight down for kPressTime, then a spiral out to the circle over 1 s, the depth swinging as it goes. The circle
// lies in the plane across `down`: along x and (-down) x x (y on the block).
ToolPose tool_pose(const Press& press, double t) {
  const double pressed = std::min(1.0, t / kPressTime);
  const double after = std::max(0.0, t - kPressTime);
  const double circling = std::min(1.0, after);
  const double lowered = (kStartGap + kDepth) * pressed + kDepthSwing * circling * std::sin(2.0 * kPi * after);
  const double angle = 2.0 * kPi * after / kCirclePeriod;
  const double* d = press.down;
  const double across[3] = {0.0, -d[2], d[1]};  // (-down) x (1, 0, 0)
  const double lift = kRadius + kStartGap - lowered;
  const double c = press.circle * circling * std::cos(angle), s = press.circle * circling * std::sin(angle);
  ToolPose pose;
  for (int axis = 0; axis < 3; ++axis)
    pose.position[static_cast<std::size_t>(axis)] =
        press.contact[axis] - lift * d[axis] + (axis == 0 ? c : 0.0) + s * across[axis];
  return pose;
}

double magnitude(const fmpc::sim::Point3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

fmpc::sim::Point3 difference(const fmpc::sim::Point3& a, const fmpc::sim::Point3& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

double percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(values.size()))) - 1;
  return values[std::min(values.size() - 1, index)];
}

struct ModeResult {
  std::string mode;
  std::size_t vertices = 0;
  std::size_t ticks = 0;
  double steps_per_tick = 0.0;
  double dt = 0.0;
  double wall = 0.0, cpu = 0.0, setup = 0.0;
  double p50 = 0.0, p99 = 0.0, max = 0.0;  // ms
  // Where a tick's latency goes (--force end): setting the pose, stepping, reading the force (p50 and p99, ms).
  double pose_p50 = 0.0, pose_p99 = 0.0, step_p50 = 0.0, step_p99 = 0.0, reading_p50 = 0.0, reading_p99 = 0.0;
  double reread_p50 = 0.0, reread_p99 = 0.0;  // the reading repeated at once (--force end)
  std::size_t overruns = 0;
  double real_time_factor = 0.0;
  double final_force = 0.0, peak_force = 0.0;  // N, magnitudes of the reported force (--force)
  // How much the reported force jumps from tick to tick once in contact: the mean |F(k) - F(k-1)| (N), for the mean
  // and for the tick-end force (the chatter).
  double mean_step = 0.0, end_step = 0.0;
  // Implicit Euler's solves (all contact rounds of a step counted): iterations per step, the largest residual.
  double iterations_mean = 0.0;
  int iterations_max = 0;
  double residual_max = 0.0;
  std::size_t capped_steps = 0;
  int contact_rounds = 0;                    // the scene's solver.contact_rounds
  std::size_t contact_unsettled_steps = 0;   // steps whose contact set still changed after their last solve
};

bool run_mode(const Options& options, const std::string& mode, ModeResult& result) {
  result.mode = mode;
  DiagnosticList diagnostics;
  SessionOptions session_options;
  session_options.backend = options.backend == "cuda" ? SessionOptions::Backend::Cuda : SessionOptions::Backend::Cpu;
  const auto setup_start = std::chrono::steady_clock::now();
  std::string liver_text;
  if (options.tissue == "liver") {
    std::ifstream in(options.liver_scene);
    std::stringstream text;
    text << in.rdbuf();
    if (!in) {
      std::cerr << "fmpc_haptic_bench: --liver-scene: cannot read '" << options.liver_scene << "'\n";
      return false;
    }
    liver_text = text.str();
  }
  // The liver's scene is named by its own path, so that its surface and rule file resolve as in the scene.
  const auto session = Session::from_yaml(scene_yaml(options, mode, liver_text),
                                          options.tissue == "liver" ? options.liver_scene : "haptic_" + mode + ".yaml",
                                          diagnostics, session_options);
  if (!session) {
    std::cerr << fmpc::render_all(diagnostics, fmpc::SourceFiles{});
    return false;
  }
  result.setup = fmpc::bench::seconds_since(setup_start);
  result.vertices = session->vertex_count();
  result.dt = session->time_step();
  std::ofstream curve;
  if (!options.out.empty()) {
    curve.open(std::filesystem::path(options.out) / ("haptic_force_" + mode + ".csv"));
    curve << "tick,time_s,tool_x_m,tool_y_m,tool_z_m,fx_N,fy_N,fz_N,fx_end_N,fy_end_N,fz_end_N,contacts,latency_ms\n";
    curve.precision(9);
  }
  std::vector<double> latencies, pose_ms, step_ms, reading_ms, reread_ms;
  std::optional<ToolReading> previous_end, previous_mean;
  std::size_t steps_compared = 0;
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = fmpc::bench::cpu_seconds();
  const std::size_t steps_before = session->steps_taken();
  for (std::size_t tick = 1;; ++tick) {
    const auto deadline = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(static_cast<double>(tick - 1) * kTick));
    std::this_thread::sleep_until(deadline);
    if (options.ticks > 0 ? tick > options.ticks : fmpc::bench::seconds_since(start) >= options.seconds && tick > 1)
      break;
    const double t = static_cast<double>(tick) * kTick;
    const ToolPose pose = tool_pose(press_of(options), t);
    const auto tick_start = std::chrono::steady_clock::now();
    std::vector<ToolReading> mean, end;
    bool stepped = session->set_tool_pose(0, pose, diagnostics);
    const auto posed = std::chrono::steady_clock::now();
    stepped = stepped && (options.mean_force ? session->step_to_averaging(t, mean, diagnostics, &end)
                                             : session->step_to(t, diagnostics));
    const auto step_end = std::chrono::steady_clock::now();
    if (stepped && !options.mean_force) end = session->tool_readings(diagnostics);
    const double latency = 1e3 * fmpc::bench::seconds_since(tick_start);
    pose_ms.push_back(1e3 * std::chrono::duration<double>(posed - tick_start).count());
    step_ms.push_back(1e3 * std::chrono::duration<double>(step_end - posed).count());
    reading_ms.push_back(latency - pose_ms.back() - step_ms.back());
    if (stepped && !options.mean_force) {
      // The same reading again, outside the latency: what the reading costs once nothing is left on the stream.
      const auto again = std::chrono::steady_clock::now();
      if (session->tool_readings(diagnostics).size() != 1) stepped = false;
      reread_ms.push_back(1e3 * fmpc::bench::seconds_since(again));
    }
    if (!stepped || end.size() != 1 || (options.mean_force && mean.size() != 1)) {
      std::cerr << session->render(diagnostics);
      return false;
    }
    latencies.push_back(latency);
    const ToolReading& reading = options.mean_force ? mean.front() : end.front();
    const double force = magnitude(reading.force);
    result.peak_force = std::max(result.peak_force, force);
    result.final_force = force;
    result.ticks = tick;
    if (previous_end) {
      result.end_step += magnitude(difference(end.front().force, previous_end->force));
      if (options.mean_force) result.mean_step += magnitude(difference(reading.force, previous_mean->force));
      ++steps_compared;
    }
    // From the first tick in contact on.
    if (previous_end || end.front().contacts > 0 || force > 0.0) {
      previous_end = end.front();
      previous_mean = reading;
    }
    if (curve.is_open()) {
      curve << tick << "," << t << "," << pose.position[0] << "," << pose.position[1] << "," << pose.position[2] << ",";
      if (options.mean_force) curve << reading.force[0] << "," << reading.force[1] << "," << reading.force[2];
      else curve << ",,";
      curve << "," << end.front().force[0] << "," << end.front().force[1] << "," << end.front().force[2] << ","
            << end.front().contacts << "," << latency << "\n";
    }
  }
  if (steps_compared > 0) {
    result.mean_step /= static_cast<double>(steps_compared);
    result.end_step /= static_cast<double>(steps_compared);
  }
  result.wall = fmpc::bench::seconds_since(start);
  result.cpu = fmpc::bench::cpu_seconds() - cpu_start;
  result.steps_per_tick =
      static_cast<double>(session->steps_taken() - steps_before) / static_cast<double>(result.ticks);
  result.p50 = percentile(latencies, 0.50);
  result.p99 = percentile(latencies, 0.99);
  result.pose_p50 = percentile(pose_ms, 0.50);
  result.pose_p99 = percentile(pose_ms, 0.99);
  result.step_p50 = percentile(step_ms, 0.50);
  result.step_p99 = percentile(step_ms, 0.99);
  result.reading_p50 = percentile(reading_ms, 0.50);
  result.reading_p99 = percentile(reading_ms, 0.99);
  if (!reread_ms.empty()) {
    result.reread_p50 = percentile(reread_ms, 0.50);
    result.reread_p99 = percentile(reread_ms, 0.99);
  }
  result.max = *std::max_element(latencies.begin(), latencies.end());
  result.overruns = static_cast<std::size_t>(
      std::count_if(latencies.begin(), latencies.end(), [](double ms) { return ms > 1e3 * kTick; }));
  result.real_time_factor = static_cast<double>(result.ticks) * kTick / result.wall;
  if (mode == "implicit") {
    const fmpc::sim::ImplicitSolverReport solver = session->simulation().implicit_solver(0);
    result.iterations_mean =
        static_cast<double>(solver.iterations_total) / static_cast<double>(std::max<std::size_t>(1, solver.steps));
    result.iterations_max = solver.iterations_max;
    result.residual_max = solver.residual_max;
    result.capped_steps = solver.capped_steps;
    result.contact_rounds = session->simulation().setup().implicit.contact_rounds;
    result.contact_unsettled_steps = solver.contact_unsettled_steps;
  }
  // The sphere reaches the surface at kPressTime kStartGap / (kStartGap + kDepth): a run past twice that which felt
  // nothing is broken, not slow.
  const double touch = kPressTime * kStartGap / (kStartGap + kDepth);
  if (static_cast<double>(result.ticks) * kTick > 2.0 * touch && !(result.peak_force > 0.0)) {
    std::cerr << "fmpc_haptic_bench: " << mode << ": the tool felt no force after " << result.ticks
              << " ticks (it touches the tissue at t = " << touch << " s)\n";
    return false;
  }
  return true;
}

bool parse(int argc, char** argv, Options& options) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) {
      std::cerr << "fmpc_haptic_bench: " << arg << " needs a value\n";
      return false;
    }
    const std::string value = argv[++i];
    char* end = nullptr;
    // An integer option's value in [lowest, highest], or the message saying what was expected.
    const auto integer_in = [&](long long lowest, long long highest, long long& number) {
      number = std::strtoll(value.c_str(), &end, 10);
      if (*end == '\0' && number >= lowest && number <= highest) return true;
      std::cerr << "fmpc_haptic_bench: " << arg << ": expected an integer from " << lowest << " to " << highest
                << ", got '" << value << "'\n";
      return false;
    };
    long long number = 0;
    if (arg == "--seconds") {
      options.seconds = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(options.seconds > 0.0 && options.seconds <= 3600.0)) {
        std::cerr << "fmpc_haptic_bench: --seconds: expected a number of seconds in (0, 3600], got '" << value << "'\n";
        return false;
      }
    } else if (arg == "--ticks") {
      if (!integer_in(1, 3600000, number)) return false;
      options.ticks = static_cast<std::size_t>(number);
    } else if (arg == "--modes") {
      options.modes.clear();
      std::stringstream list(value);
      for (std::string mode; std::getline(list, mode, ',');) {
        if (mode != "implicit" && mode != "explicit") {
          std::cerr << "fmpc_haptic_bench: --modes: unknown mode '" << mode << "' (implicit, explicit)\n";
          return false;
        }
        options.modes.push_back(mode);
      }
    } else if (arg == "--backend") {
      if (value != "cpu" && value != "cuda") {
        std::cerr << "fmpc_haptic_bench: --backend: expected cpu or cuda, got '" << value << "'\n";
        return false;
      }
      options.backend = value;
    } else if (arg == "--cells" || arg == "--threads") {
      if (!(arg == "--cells" ? integer_in(1, 100, number) : integer_in(0, 256, number))) return false;
      (arg == "--cells" ? options.cells : options.threads) = static_cast<int>(number);
    } else if (arg == "--precision") {
      if (value != "float" && value != "double") {
        std::cerr << "fmpc_haptic_bench: --precision: expected float or double, got '" << value << "'\n";
        return false;
      }
      options.precision = value;
    } else if (arg == "--contact-damping") {
      options.contact_damping = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(options.contact_damping >= 0.0 && options.contact_damping <= 100.0)) {
        std::cerr << "fmpc_haptic_bench: --contact-damping: expected a ratio from 0 to 100, got '" << value << "'\n";
        return false;
      }
    } else if (arg == "--force") {
      if (value != "mean" && value != "end") {
        std::cerr << "fmpc_haptic_bench: --force: expected mean or end, got '" << value << "'\n";
        return false;
      }
      options.mean_force = value == "mean";
    } else if (arg == "--tissue") {
      if (value != "block" && value != "liver") {
        std::cerr << "fmpc_haptic_bench: --tissue: expected block or liver, got '" << value << "'\n";
        return false;
      }
      options.tissue = value;
    } else if (arg == "--tolerance") {
      options.tolerance = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(options.tolerance > 0.0 && options.tolerance < 1.0)) {
        std::cerr << "fmpc_haptic_bench: --tolerance: expected a relative residual in (0, 1), got '" << value << "'\n";
        return false;
      }
    } else if (arg == "--max-iterations") {
      if (!integer_in(1, 100000, number)) return false;
      options.max_iterations = static_cast<long>(number);
    } else if (arg == "--contact-rounds") {
      if (!integer_in(1, fmpc::kernels::kMostContactRounds, number)) return false;
      options.contact_rounds = static_cast<long>(number);
    } else if (arg == "--liver-scene") {
      options.liver_scene = value;
    } else if (arg == "--out") {
      options.out = value;
    } else {
      std::cerr
          << "usage: fmpc_haptic_bench [--seconds S | --ticks N] [--modes implicit,explicit] [--backend cpu|cuda] "
             "[--cells N] [--threads N] [--precision float|double] [--force mean|end] [--contact-damping R] "
             "[--tissue block|liver] [--liver-scene FILE] [--tolerance T] [--max-iterations N] "
             "[--contact-rounds N] [--out DIR]\n";
      return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!parse(argc, argv, options)) return 2;
  if (!options.out.empty()) {
    std::error_code error;
    std::filesystem::create_directories(options.out, error);
    if (error) {
      std::cerr << "fmpc_haptic_bench: --out: cannot create '" << options.out << "': " << error.message() << "\n";
      return 2;
    }
  }
  std::vector<ModeResult> results;
  for (const std::string& mode : options.modes) {
    ModeResult result;
    if (!run_mode(options, mode, result)) return 1;
    std::printf(
        "%s on %s: %zu vertices, dt %.3g s (%.3g steps per tick), %zu ticks in %.2f s wall (%.2f s CPU), "
        "latency p50 %.3f ms, p99 %.3f ms, max %.3f ms, %zu overruns of 1 ms, real-time factor %.3f, "
        "%s force %.4f N (peak %.4f N)\n",
        mode.c_str(), options.backend.c_str(), result.vertices, result.dt, result.steps_per_tick, result.ticks,
        result.wall, result.cpu, result.p50, result.p99, result.max, result.overruns, result.real_time_factor,
        options.mean_force ? "mean" : "tick-end", result.final_force, result.peak_force);
    std::printf(
        "  latency by part (p50 / p99 ms): pose %.3f / %.3f, stepping %.3f / %.3f, force reading %.3f / %.3f "
        "(repeated at once: %.3f / %.3f)\n",
        result.pose_p50, result.pose_p99, result.step_p50, result.step_p99, result.reading_p50, result.reading_p99,
        result.reread_p50, result.reread_p99);
    if (options.mean_force)
      std::printf(
          "  force change from tick to tick in contact: %.4g N for the tick's mean force, %.4g N at tick ends "
          "(contact damping ratio %g)\n",
          result.mean_step, result.end_step, mode == "explicit" ? options.contact_damping : 0.0);
    if (mode == "implicit")
      std::printf(
          "  implicit solves: %.1f iterations per step (at most %d), largest relative residual %.3g, %zu "
          "steps at the cap; contact rounds %d, %zu steps whose contact still changed after their last solve\n",
          result.iterations_mean, result.iterations_max, result.residual_max, result.capped_steps,
          result.contact_rounds, result.contact_unsettled_steps);
    results.push_back(result);
  }
  std::printf(
      "\n| mode | backend | vertices | steps per tick | ticks | latency p50 ms | p99 ms | max ms | overruns | "
      "real-time factor | peak force N |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (const ModeResult& r : results)
    std::printf("| %s | %s | %zu | %.3g | %zu | %.3f | %.3f | %.3f | %zu | %.3f | %.4f |\n", r.mode.c_str(),
                options.backend.c_str(), r.vertices, r.steps_per_tick, r.ticks, r.p50, r.p99, r.max, r.overruns,
                r.real_time_factor, r.peak_force);
  if (!options.out.empty()) {
    std::ofstream csv(std::filesystem::path(options.out) / "haptic.csv");
    csv << "mode,backend,precision,cells,vertices,dt_s,steps_per_tick,ticks,wall_s,cpu_s,setup_s,latency_p50_ms,"
           "latency_p99_ms,latency_max_ms,overruns,real_time_factor,force,final_force_N,peak_force_N,"
           "mean_force_change_N,end_force_change_N,contact_damping_ratio,iterations_mean,iterations_max,residual_max,"
           "capped_steps,contact_rounds,contact_unsettled_steps\n";
    for (const ModeResult& r : results)
      csv << r.mode << "," << options.backend << "," << options.precision << "," << options.cells << "," << r.vertices
          << "," << r.dt << "," << r.steps_per_tick << "," << r.ticks << "," << r.wall << "," << r.cpu << "," << r.setup
          << "," << r.p50 << "," << r.p99 << "," << r.max << "," << r.overruns << "," << r.real_time_factor << ","
          << (options.mean_force ? "mean" : "end") << "," << r.final_force << "," << r.peak_force << ","
          << r.mean_step << "," << r.end_step << "," << (r.mode == "explicit" ? options.contact_damping : 0.0) << ","
          << r.iterations_mean << "," << r.iterations_max << ","
          << r.residual_max << "," << r.capped_steps << "," << r.contact_rounds << ","
          << r.contact_unsettled_steps << "\n";
  }
  return 0;
}
