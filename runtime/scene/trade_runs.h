#pragma once
// Internal to the simulation trade (runtime/scene/simulation_trade.h): what one run is (RunKey), the scenes built
// for the runs (each built once, shared by the workers that run on it, dropped after its last run), and the runs
// themselves: side by side on every CPU core, one run per thread, or grouped into batches (one Simulation per group
// of runs that can share a launch: the GPU's way). Not installed.
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/simulation_trade.h"

namespace fmpc::sim {

// What is built for a run: the model, its element kind (-1: springs), the mesh and its refinements.
struct BuildKey {
  TradeModel model = trade_reference_model();
  int element_kind = -1;
  TradeMesh mesh = TradeMesh::Scene;
  unsigned refinements = 0;

  auto tied() const { return std::make_tuple(refinements, model, element_kind, mesh); }
  bool operator<(const BuildKey& other) const { return tied() < other.tied(); }
};

// One run: what is built, and how it is stepped.
struct RunKey {
  BuildKey build;
  Precision precision = Precision::Double;
  Integrator integrator = Integrator::SemiImplicitEuler;
  double dt_factor = 1.0;

  auto tied() const { return std::make_tuple(build.tied(), precision, integrator, dt_factor); }
  bool operator<(const RunKey& other) const { return tied() < other.tied(); }
  bool operator==(const RunKey& other) const { return tied() == other.tied(); }
};

// The variant's label: model, element kind (when not linear), precision, integrator and step factor, refinements,
// and "uniform" for the uniform mesh ("SNH quadratic f32 SIE r0", "FEM f64 IE x4 r1 uniform").
std::string run_label(const RunKey& key);

// A scene built for runs, with semi-implicit Euler's automatic step on it and its distinct edges.
struct BuiltRun {
  BuiltScene scene;
  double automatic_step = 0.0;  // s
  std::size_t edges = 0;
};

// The scene as `key` builds it: its model, element kind and mesh over the scene's, the duration the trade runs.
Scene trade_variant_scene(const Scene& scene, const BuildKey& key, double duration);

// The scenes runs are built on, each built once (thread-safe) and kept while runs still need it.
class TradeScenes {
 public:
  TradeScenes(const Scene& scene, double duration) : scene_(scene), duration_(duration) {}
  // Built (or being built by another thread: waits for it); null after appending errors naming the variant.
  std::shared_ptr<const BuiltRun> get(const BuildKey& key, DiagnosticList& diagnostics);
  // Drops the built scene (the next get builds it again): after its last run.
  void drop(const BuildKey& key);
  const Scene& scene() const { return scene_; }

 private:
  struct Slot {
    std::mutex building;
    std::shared_ptr<const BuiltRun> built;
    bool failed = false;
    DiagnosticList errors;
  };
  const Scene& scene_;
  double duration_;
  std::mutex slots_mutex_;
  std::map<BuildKey, std::shared_ptr<Slot>> slots_;
};

// A run's result: its row (errors not yet compared) and the displacement of the compared vertices at the end.
struct RunOutcome {
  SimulationTradeRow row;
  std::vector<Point3> displacement;
  double extent = 0.0;  // m, the diagonal of the rest positions' bounding box
};

// How runs are executed.
struct TradeExecution {
  bool gpu = false;     // Backend::Cuda, in batches
  bool batch = false;   // batches on the CPU too
  unsigned threads = 1;  // CPU workers
  double duration = 0.0;
  std::size_t compared_vertices = 0;
  double prefix_seconds = 0.02;  // cheapest first: SimulationTradeOptions::prefix_seconds
};

// Runs every key (each once), the most work first; outcome i is keys[i]'s, nullopt where it could not be built
// (errors appended). `work[i]` is the run's estimated element-steps; `done` is told the element-steps done (from any
// thread, one call at a time).
std::vector<std::optional<RunOutcome>> execute_trade_runs(const std::vector<RunKey>& keys,
                                                          const std::vector<double>& work, TradeScenes& scenes,
                                                          const TradeExecution& execution,
                                                          const std::function<void(double)>& done,
                                                          DiagnosticList& diagnostics);

// Why a run was not run to its end: its estimated CPU seconds, or (prefix) the CPU seconds its prefix already took,
// above the cheapest run known to meet --max-error.
struct TradeSkip {
  double seconds = 0.0;
  bool prefix = false;
};

struct CheapestFirstRuns {
  std::vector<std::optional<RunOutcome>> outcomes;  // nullopt: skipped (skips[i]) or not built (errors appended)
  std::vector<double> estimates;        // s of CPU, from the prefix; NaN where the run ended within it
  std::vector<std::size_t> prefix_steps;  // the steps the estimate was made from
  std::vector<std::optional<TradeSkip>> skips;
};

// Runs `keys` on the CPU workers cheapest first: each is started and timed over a prefix (execution.prefix_seconds
// of its thread's CPU time, steps in chunks of 1, 2, 4, ... up to a hundredth of the run) and paused; its full CPU
// time is estimated as the prefix's time per step times its steps; then they go on by CheapestFirstSchedule, the
// bound starting at `bound` and lowered by every run that ends and `meets` (E, against the reference). A prefix that
// passes the bound is stopped there. `work` and `done` as for execute_trade_runs.
CheapestFirstRuns execute_cheapest_first(const std::vector<RunKey>& keys, const std::vector<double>& work,
                                         TradeScenes& scenes, const TradeExecution& execution,
                                         const std::function<bool(const RunOutcome&)>& meets, double bound,
                                         const std::function<void(double)>& done, DiagnosticList& diagnostics);

// Whether the model has springs (alone, or with a law beside them): then it has no element kind.
bool trade_has_springs(const TradeModel& model);
// 0.0123 as "1.23%".
std::string trade_percent(double fraction);

// The runs' array sizes in bytes (docs/trade.md, "memory_bytes").
double trade_memory_estimate(const SimulationSetup& setup, std::size_t edges);

}  // namespace fmpc::sim
