// Implicit Euler benchmark on the CPU backend (docs/performance.md, "Implicit Euler on the CPU"): a scene file's
// setup stepped with the given solver settings at each thread count, steps per second of wall time and of the
// process's CPU time (on a machine shared with other sessions the CPU time measures the code, the wall time their
// load too), the solver's iterations and the residuals reached, and a hash of the final state (the same for every
// thread count: the backend's results do not depend on it).
//
//   fmpc_implicit_bench SCENE [--steps N] [--threads 1,2] [--method auto|direct|cg] [--tolerance T]
//                       [--max-iterations N] [--cold] [--state-out PATH] [--pool-runs N]
//
// --steps           steps timed after one untimed warm-up step (default 200)
// --threads         the CPU worker threads of each run, comma-separated (default 1)
// --method, --tolerance, --max-iterations: override the scene's `solver` (docs/scenes.md)
// --cold            the conjugate gradient starts from zero instead of the last step's solution
// --state-out PATH  the last run's final positions and velocities, one vertex a line (x y z vx vy vz, %.17g), to
//                   compare two builds' states where their hashes differ
// --pool-runs N     also times N runs of the worker pool at each thread count, each over the scene's system chunks
//                   doing nothing but one add per chunk: the wall and CPU time one of the step's ~100 runs costs
//
// Checks for NaN/Inf and inversions every 64 steps (advance's default), as fmpc simulate does; no outputs.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "bench/setup/process_clock.h"
#include "runtime/integrate/implicit_system.h"
#include "runtime/io/input_file.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"

using namespace fmpc;
using namespace fmpc::sim;
using fmpc::bench::cpu_seconds;
using fmpc::bench::seconds_since;

namespace {

// FNV-1a over the bits of every coordinate: equal hashes, equal states.
std::uint64_t state_hash(const std::vector<Point3>& positions, const std::vector<Point3>& velocities) {
  std::uint64_t hash = 1469598103934665603ull;
  for (const auto* points : {&positions, &velocities})
    for (const Point3& p : *points)
      for (const double value : p) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, &value, sizeof bits);
        for (int byte = 0; byte < 8; ++byte) {
          hash ^= (bits >> (8 * byte)) & 0xffu;
          hash *= 1099511628211ull;
        }
      }
  return hash;
}

void report_errors(const DiagnosticList& diagnostics) {
  for (const Diagnostic& d : diagnostics.items())
    if (d.severity == Severity::Error) std::cerr << d.range.file << ": error: " << d.message << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: fmpc_implicit_bench SCENE [--steps N] [--threads 1,2] [--method auto|direct|cg] "
                 "[--tolerance T] [--max-iterations N] [--cold] [--state-out PATH] [--pool-runs N]\n";
    return 2;
  }
  const std::string path = argv[1];
  std::size_t steps = 200;
  std::vector<unsigned> threads = {1};
  std::string method, tolerance, max_iterations, state_out;
  std::size_t pool_runs = 0;
  bool cold = false;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (arg == "--steps") {
      steps = static_cast<std::size_t>(std::strtoull(value().c_str(), nullptr, 10));
    } else if (arg == "--threads") {
      threads.clear();
      std::stringstream list(value());
      for (std::string item; std::getline(list, item, ',');) threads.push_back(static_cast<unsigned>(std::stoul(item)));
    } else if (arg == "--method") {
      method = value();
    } else if (arg == "--tolerance") {
      tolerance = value();
    } else if (arg == "--max-iterations") {
      max_iterations = value();
    } else if (arg == "--pool-runs") {
      pool_runs = static_cast<std::size_t>(std::strtoull(value().c_str(), nullptr, 10));
    } else if (arg == "--state-out") {
      state_out = value();
    } else if (arg == "--cold") {
      cold = true;
    } else {
      std::cerr << "fmpc_implicit_bench: unknown argument '" << arg << "'\n";
      return 2;
    }
  }
  DiagnosticList diagnostics;
  std::string read_error;
  const auto text = read_input_file(path, kMaxSceneFileBytes, "scene", read_error);
  if (!text) {
    std::cerr << path << ": " << read_error << "\n";
    return 2;
  }
  auto scene = parse_scene(path, *text, diagnostics);
  if (scene) {
    if (!method.empty())
      scene->solver.method = method == "direct" ? ImplicitMethod::Direct
                             : method == "cg"   ? ImplicitMethod::ConjugateGradient
                                                : ImplicitMethod::Automatic;
    if (!tolerance.empty()) scene->solver.tolerance = std::stod(tolerance);
    if (!max_iterations.empty()) scene->solver.max_iterations = std::stoi(max_iterations);
    scene->solver.warm_start = !cold;
  }
  const auto built = scene ? build_scene(*scene, diagnostics) : std::nullopt;
  if (!built || built->setup.integrator != Integrator::ImplicitEuler) {
    report_errors(diagnostics);
    if (built) std::cerr << path << ": the scene's integrator is not implicit_euler\n";
    return 2;
  }
  std::printf("%s: %zu vertices, %zu tetrahedra, %zu springs, dt %g s, %zu steps timed\n", path.c_str(),
              built->setup.rest_positions.size(), built->setup.tetrahedra.size(), built->setup.springs.size(),
              built->setup.time_step ? *built->setup.time_step : 0.0, steps);
  std::printf("%7s %6s %6s %10s %10s %12s %8s %8s %12s %7s %18s\n", "threads", "method", "warm", "wall_s", "steps/s",
              "cpu_ms/step", "it_mean", "it_max", "resid_max", "capped", "state_hash");
  int status = 0;
  for (const unsigned count : threads) {
    SimulationSetup setup = built->setup;
    setup.threads = count;
    DiagnosticList run_diagnostics;
    auto simulation = Simulation::create(setup, run_diagnostics);
    if (!simulation || !simulation->advance(1, run_diagnostics)) {
      report_errors(run_diagnostics);
      return 2;
    }
    const auto wall_start = std::chrono::steady_clock::now();
    const double cpu_start = cpu_seconds();
    const bool ok = simulation->advance(steps, run_diagnostics);
    const double wall = seconds_since(wall_start), cpu = cpu_seconds() - cpu_start;
    const ImplicitSolverReport report = simulation->implicit_solver();
    const auto positions = simulation->positions(run_diagnostics);
    const auto velocities = simulation->velocities(run_diagnostics);
    std::printf("%7u %6s %6s %10.4f %10.2f %12.4f %8.2f %8d %12.4g %7zu %18llx\n", count, to_string(report.method),
                cold || report.method == ImplicitMethod::Direct ? "no" : "yes", wall,
                static_cast<double>(steps) / wall, 1e3 * cpu / static_cast<double>(steps),
                static_cast<double>(report.iterations_total) / static_cast<double>(report.steps), report.iterations_max,
                report.residual_max, report.capped_steps,
                static_cast<unsigned long long>(state_hash(positions, velocities)));
    if (!ok) {
      report_errors(run_diagnostics);
      status = 2;
    }
    if (!state_out.empty()) {
      std::FILE* out = std::fopen(state_out.c_str(), "w");
      if (out == nullptr) {
        std::cerr << state_out << ": cannot be written\n";
        return 2;
      }
      for (std::size_t v = 0; v < positions.size(); ++v)
        std::fprintf(out, "%.17g %.17g %.17g %.17g %.17g %.17g\n", positions[v][0], positions[v][1], positions[v][2],
                     velocities[v][0], velocities[v][1], velocities[v][2]);
      std::fclose(out);
    }
  }
  const std::size_t chunks = (built->setup.rest_positions.size() + kSystemChunkVertices - 1) / kSystemChunkVertices;
  for (const unsigned count : pool_runs > 0 ? threads : std::vector<unsigned>{}) {
    WorkerPool pool(count);
    std::vector<double> partial(chunks, 0.0);
    const auto wall_start = std::chrono::steady_clock::now();
    const double cpu_start = cpu_seconds();
    for (std::size_t run = 0; run < pool_runs; ++run)
      pool.run(
          chunks,
          [&](std::size_t begin, std::size_t end) {
            for (std::size_t chunk = begin; chunk < end; ++chunk) partial[chunk] += 1.0;
          },
          1);
    const double wall = seconds_since(wall_start), cpu = cpu_seconds() - cpu_start;
    std::printf("pool, %u threads (%s), %zu runs over %zu chunks: %.2f us/run wall, %.2f us/run CPU (all threads)\n",
                count, pool.spins() ? "spinning" : "sleeping", pool_runs, chunks,
                1e6 * wall / static_cast<double>(pool_runs), 1e6 * cpu / static_cast<double>(pool_runs));
  }
  return status;
}
