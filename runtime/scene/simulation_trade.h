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
};

struct SimulationTradeOptions {
  std::vector<TradeModel> models = trade_models();
  std::vector<Precision> precisions{Precision::Float, Precision::Double};
  std::vector<TradeIntegrator> integrators{{Integrator::SemiImplicitEuler, 1.0}, {Integrator::ImplicitEuler, 4.0}};
  std::vector<unsigned> refinements{0, 1};
  // The reference's mesh: nullopt, the finest of `refinements`.
  std::optional<unsigned> reference_refinements;
  // The reference's step as a factor of semi-implicit Euler's automatic step, in (0, 0.5]: its step check runs at
  // twice it.
  double reference_dt_factor = 0.5;
  std::optional<double> duration;  // s; nullopt: the scene's
  // Called before each run with (runs done, runs planned, what runs next).
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
  std::optional<double> probe_force;  // |F - F_ref| / |F_ref| along the probe; none without a displacement probe
};

struct SimulationTradeRow {
  std::string variant;  // a short label, e.g. "FEM f32 SIE r1"
  bool reference = false;
  TradeModel model = trade_reference_model();
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
  TradeErrors errors;   // zeros when it did not complete
  double final_probe_force = 0.0;  // N, along the probe's target direction
  double final_max_displacement = 0.0;  // m, over the coarse vertices
  double cpu_seconds = 0.0;  // of the stepping, all threads of the process
  double steps_per_second = 0.0;
  double memory_bytes = 0.0;  // an estimate from the array sizes (docs/trade.md)
  std::size_t inverted_elements = 0;  // the largest count seen during the run
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
};

// Runs every variant (models x precisions x integrators x refinements) and the reference on the CPU, one thread.
// Errors (appended, nullopt returned): a scene that cannot be compared (no tetrahedra, spring constants instead of
// Young's modulus, a force model the scene cannot build), a mesh above kMaxTradeTetrahedra after refinement, a run
// planned above kMaxSimulationSteps or the memory this process may use, a plan above kMaxTradeWork, a reference
// that does not complete or does not move. A variant that does not complete is a row saying why.
std::optional<SimulationTradeResult> run_simulation_trade(const Scene& scene, const SimulationTradeOptions& options,
                                                          DiagnosticList& diagnostics);

// The CSV's columns: the eleven, then mapping, refinements, tetrahedra, steps, inverted_elements, status.
std::vector<std::string> simulation_trade_columns();
std::string simulation_trade_csv(const SimulationTradeResult& result);
// The markdown report: what was compared, the reference and its estimated error, one row per run.
std::string simulation_trade_markdown(const SimulationTradeResult& result);

}  // namespace fmpc::sim
