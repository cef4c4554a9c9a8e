#pragma once
// The simulation side of `fmpc trade SCENE.yaml` (docs/trade.md, "Scenes"): one scene run as variants (force model,
// precision, integrator and step, mesh refinement) against a reference (co-rotational FEM in double at the finest
// refinement, with a smaller step), each measured for accuracy (displacement field and probe force at the final
// time), speed and memory. The reference's own convergence is measured too: it is rerun with twice its step and on
// the mesh one refinement coarser, and the differences are reported as its estimated error. Nothing is printed:
// the caller gets rows, text for them, and diagnostics.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

// A force model compared: springs with a Young's modulus mapping, or an element law of the registry
// (runtime/fem/element_law_registry.h): one beside the springs (the scene's mapping, calibrated to its Poisson ratio)
// or a finite-element model of its own.
struct TradeModel {
  int element_law = -1;  // -1: springs alone
  StiffnessMapping mapping = StiffnessMapping::VanGelder1998;  // springs alone: their mapping

  // Springs (by mapping), then the laws beside springs, then the finite-element laws: the order of runs and rows.
  int rank() const;
  bool operator==(const TradeModel& other) const { return rank() == other.rank(); }
  bool operator<(const TradeModel& other) const { return rank() < other.rank(); }
};

// Every model, in rank order: springs_van_gelder, springs_lloyd, then each registry law's trade name.
std::vector<TradeModel> trade_models();
// The reference's model: the default finite-element law (default_fem_law).
TradeModel trade_reference_model();
// The spelling of --models: "springs_van_gelder", "springs_lloyd", or a law's trade name.
std::string trade_model_name(const TradeModel& model);
std::optional<TradeModel> parse_trade_model(const std::string& name);

// An integrator and its step: dt_factor times the automatic step of semi-implicit Euler for the same model and mesh
// (stability_margin x the critical step), rounded down so that a whole number of steps ends at the duration.
struct TradeIntegrator {
  Integrator integrator = Integrator::SemiImplicitEuler;
  double dt_factor = 1.0;
};

// A mesh from a surface (`mesh: {surface}`, docs/meshing.md) is run as the scene grades it (fine within
// near_distance of the probe and tools, size_far elsewhere) and uniform at size_near everywhere; any other mesh is
// the scene's.
enum class TradeMesh { Scene, Uniform };

// The axes a trade varies, one row each (`--variants` names them): an axis left out holds the scene's own value.
// A new value of an axis (a law, an element kind in the registry) is a row of its registry, not a new axis.
enum class TradeAxis { Laws, Elements, Meshes, Precisions, Integrators, Refinements };
struct TradeAxisRow {
  TradeAxis axis;
  const char* name;    // in --variants
  const char* option;  // the option giving its values
  const char* held;    // what it is when --variants leaves it out
};
const std::vector<TradeAxisRow>& trade_axes();
std::optional<TradeAxis> parse_trade_axis(const std::string& name);

// Which relative errors a decision keeps under --max-error.
struct TradeMeasures {
  bool displacement = true;  // the displacement's max relative error
  bool probe_force = false;  // the probe force's relative error (trade_probe_force_source)
};

// What a trade compares as the probe force (docs/trade.md, "Columns"): a displacement probe's reaction along its
// target; without one, the first rigid tool's force against its path (from its first keyframe's position to its
// last: a scripted press). None with neither (a force probe's force is given, and a tool that does not travel
// presses nothing).
enum class TradeForceSource { None, Probe, Tool };
TradeForceSource trade_probe_force_source(const Scene& scene);

// The most refinements a trade runs (each multiplies the tetrahedra by 8 and, for the explicit schemes, the steps
// by 2): 3 turns the demo's 1,536 tetrahedra into 786,432.
inline constexpr unsigned kMaxTradeRefinements = 3;
// The largest mesh a trade builds, in tetrahedra (after refinement), checked before anything is built.
inline constexpr std::size_t kMaxTradeTetrahedra = std::size_t{1} << 22;
// The most work a trade plans, in element-steps (tetrahedra x steps, summed over its runs; the demo scene's default
// trade plans 6e9), checked with every run's steps (at most kMaxSimulationSteps, as simulate's) and the largest
// run's memory (within memory_limit()) before anything runs: --duration 1e12 or a step factor of 1e-9 once ran
// until killed, and --refinements 3 on an 8^3 box ran for minutes with no estimate.
inline constexpr double kMaxTradeWork = 1e11;

// What a trade will cost, estimated from the scene's own mesh before anything runs: each refinement multiplies the
// tetrahedra by 8 and halves the automatic step (the critical step scales with the edge length).
struct TradePlan {
  std::size_t runs = 0;
  double element_steps = 0.0;       // tetrahedra x steps, all runs
  double largest_tetrahedra = 0.0;  // of the largest run
  double largest_steps = 0.0;       // of the run taking the most steps
  double largest_memory_bytes = 0.0;
  bool cheapest_first = false;  // the runs are at most these: a variant that cannot win is skipped
};

struct SimulationTradeOptions {
  std::vector<TradeModel> models = trade_models();
  // Element kinds (indices of element_kind_rows()) of the finite-element models; springs have none. Empty: all.
  std::vector<int> element_kinds;
  std::vector<TradeMesh> meshes{TradeMesh::Scene, TradeMesh::Uniform};
  bool meshes_given = false;  // uniform was asked for: an error on a mesh that is not from a surface
  std::vector<Precision> precisions{Precision::Float, Precision::Double};
  std::vector<TradeIntegrator> integrators{{Integrator::SemiImplicitEuler, 1.0}, {Integrator::ImplicitEuler, 4.0}};
  std::vector<unsigned> refinements{0, 1};
  // The axes that vary (--variants); the others hold the scene's value (TradeAxisRow::held). Default: all.
  std::vector<TradeAxis> axes{TradeAxis::Laws,       TradeAxis::Elements,    TradeAxis::Meshes,
                              TradeAxis::Precisions, TradeAxis::Integrators, TradeAxis::Refinements};
  // The reference's mesh: nullopt, the finest of `refinements` (with max_error: at least 1, and refined further
  // until its estimated error is under a fifth of it).
  std::optional<unsigned> reference_refinements;
  // The reference's step as a factor of semi-implicit Euler's automatic step, in (0, 0.5]: its step check runs at
  // twice it (with max_error: halved until the check is under a fifth of it).
  double reference_dt_factor = 0.5;
  std::optional<double> duration;  // s; nullopt: the scene's
  // The decision (docs/trade.md, "Deciding"): the cheapest variant (CPU seconds of stepping) whose errors
  // (`measures`) are at most this.
  std::optional<double> max_error;
  std::optional<TradeMeasures> measures;  // nullopt: displacement, and the probe force when there is a probe
  // The reference is refined no further when its next round is estimated (from the speed of its last) to take
  // longer than this, in seconds of one core.
  double max_reference_seconds = 300.0;
  // CPU: runs side by side on this many threads (0: every hardware thread), each run on one. GPU: runs grouped into
  // batches (one Simulation per group of runs that can share a launch), one batch at a time.
  unsigned threads = 0;
  // With max_error on the CPU (not gpu, not batch) the variants go cheapest first (docs/trade.md, "Cheapest
  // first"): each is timed over a prefix of this many CPU seconds (at least one step) to estimate its cost.
  double prefix_seconds = 0.02;
  bool gpu = false;    // run on CUDA (the caller checked a device is there)
  bool batch = false;  // group the runs into batches on the CPU too (what the GPU does; for tests)
  // Called before each round of runs with (runs done, runs planned, what runs next).
  std::function<void(std::size_t, std::size_t, const std::string&)> progress;
  // Called once the plan is checked, before the first run.
  std::function<void(const TradePlan&)> plan;
  // Called during the runs with (element-steps done, element-steps planned): the time left.
  std::function<void(double, double)> work_progress;
};

// Relative errors of a run's final state against the reference's (docs/trade.md, "Scenes"): the displacement
// u = x(T) - x(0) at the scene's own (coarse) vertices, which keep their indices in every refinement.
struct TradeErrors {
  double displacement_max = 0.0;  // max_i |u_i - u_ref,i| / max_i |u_ref,i|
  double displacement_rms = 0.0;  // sqrt(mean_i |u_i - u_ref,i|^2) / sqrt(mean_i |u_ref,i|^2)
  std::optional<double> probe_force;  // |F - F_ref| / |F_ref| along the probe or the tool's path; none without one
};

struct SimulationTradeRow {
  std::string variant;  // a short label, e.g. "FEM f32 SIE r1"
  bool reference = false;
  TradeModel model = trade_reference_model();
  int element_kind = -1;  // index of element_kind_rows(); -1 for springs
  TradeMesh mesh = TradeMesh::Scene;
  StiffnessMapping mapping = StiffnessMapping::VanGelder1998;  // springs only
  Precision precision = Precision::Double;
  TradeIntegrator integrator;
  unsigned refinements = 0;
  double dt = 0.0;  // s
  std::size_t steps = 0;
  std::size_t vertices = 0;
  std::size_t tetrahedra = 0;
  bool completed = false;
  std::string failure;  // why it did not complete (the first error), empty when it did
  std::string skipped;  // why it was not run (it cannot be the cheapest within --max-error), empty when it ran
  TradeErrors errors;   // zeros when it did not complete
  double final_probe_force = 0.0;  // N, along the probe's target direction (or against the tool's path)
  double final_max_displacement = 0.0;  // m, over the coarse vertices
  double cpu_seconds = 0.0;   // of the stepping, the run's thread (a batch: its wall time)
  double wall_seconds = 0.0;  // of the stepping (a batch: the whole batch's)
  double steps_per_second = 0.0;  // per CPU second
  double real_time_factor = 0.0;  // simulated seconds per wall second
  double memory_bytes = 0.0;  // an estimate from the array sizes (docs/trade.md)
  std::size_t inverted_elements = 0;  // the largest count seen during the run
  // Cheapest first (--max-error on the CPU): its CPU seconds as estimated from its first estimate_steps steps; 0
  // when not estimated (the run ended within them, or ran without the estimate).
  double estimated_seconds = 0.0;
  std::size_t estimate_steps = 0;
};

struct SimulationTradeResult {
  std::string scene_name;
  double duration = 0.0;  // s, the simulated time every run ends at
  std::size_t coarse_vertices = 0;  // the vertices compared
  bool has_probe_force = false;
  std::vector<SimulationTradeRow> rows;  // the reference first
  // The reference against itself with twice its step (time) and one refinement coarser (mesh; none when the
  // reference is on the scene's own mesh): estimates of its own error, assuming it converges at least at first
  // order in each (then its error is at most the difference).
  TradeErrors reference_time_difference;
  std::optional<TradeErrors> reference_mesh_difference;
  std::string reference_description;
  // The decision (with max_error): the errors it keeps, the reference's refinement rounds (one line each), and the
  // cheapest row meeting it (the fewest CPU seconds of stepping; on a GPU, of its batch's wall time); nullopt when
  // none does.
  std::optional<double> max_error;
  TradeMeasures measures;
  std::vector<std::string> reference_rounds;
  std::optional<std::size_t> chosen;
  std::size_t meeting = 0;  // variants meeting max_error
  std::string backend;      // "CPU, 2 threads" or "CUDA (NAME), batches"
};

// Runs every variant (models x element kinds x meshes x precisions x integrators x refinements) and the reference,
// on every CPU core (one run per thread) or as GPU batches.
// Errors (appended, nullopt returned): a scene that cannot be compared (no tetrahedra, spring constants instead of
// Young's modulus, a force model the scene cannot build), a mesh above kMaxTradeTetrahedra after refinement, a run
// planned above kMaxSimulationSteps or the memory this process may use, a plan above kMaxTradeWork, a reference
// that does not complete or does not move, a max_error the reference cannot be refined to within its limits
// (kMaxTradeRefinements, kMaxTradeTetrahedra, max_reference_seconds: the message says which). A variant that does
// not complete is a row saying why.
std::optional<SimulationTradeResult> run_simulation_trade(const Scene& scene, const SimulationTradeOptions& options,
                                                          DiagnosticList& diagnostics);

// The CSV's columns: the eleven, then mapping, refinements, tetrahedra, steps, inverted_elements, status.
std::vector<std::string> simulation_trade_columns();
std::string simulation_trade_csv(const SimulationTradeResult& result);
// The markdown report: what was compared, the reference and its estimated error, one row per run.
std::string simulation_trade_markdown(const SimulationTradeResult& result);
// The decision line: the chosen variant, its errors and speed, or why none meets max_error (empty without one).
std::string simulation_trade_decision(const SimulationTradeResult& result);
// Whether a row meets the result's max_error on every measure.
bool meets_max_error(const SimulationTradeResult& result, const SimulationTradeRow& row);
// The scene `text` (read from scene.path) as the chosen row runs it: its model, law, element kind, mesh, precision,
// integrator and step, with its measured errors and speed in a comment at the top; file paths are rewritten
// relative to `out_path`'s folder. nullopt after an error (the emitted scene is parsed back and must be valid).
std::optional<std::string> chosen_scene_text(const Scene& scene, const std::string& text,
                                             const SimulationTradeResult& result, const std::string& out_path,
                                             DiagnosticList& diagnostics);

}  // namespace fmpc::sim
