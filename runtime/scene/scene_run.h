#pragma once
// Runs a built scene on the CPU or the CUDA backend and writes its outputs (docs/scenes.md, "Outputs"): VTK XML frames (.vtu)
// and their .pvd collection, a CSV time series (probe displacement and force, kinetic and elastic energy) and a JSON
// summary, each written atomically. Nothing is printed: progress goes to a callback the caller may draw.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

struct SceneRunOptions {
  std::string output_directory;  // created when missing
  std::string backend = "cpu";   // "cpu" or "cuda" (the caller decides; the summary records it)
  // Called about 100 times during the run with (steps done, steps planned).
  std::function<void(std::size_t, std::size_t)> progress;
};

struct ProbeCurvePoint {
  double time = 0.0;          // s
  double displacement = 0.0;  // m, along the probe's direction (its target's direction)
  double force = 0.0;         // N, along the same direction
};

// The same scene run again in the other precision (float <-> double), on the same backend, without outputs: whether
// rounding changes the answer. A relative difference above kPrecisionTolerance in the final probe force or the final
// largest displacement, or inverted elements in one precision only, is reported (a warning, code
// `precision-dependent`): an equilibrium that rounding breaks (a symmetric load that buckles either way), or a
// near-inversion.
constexpr double kPrecisionTolerance = 0.01;
// `auto` checks a run whose stepping took at most this long (s, measured): the check runs it again, so it costs about
// as much. A bound on vertex-steps (2e8) once let an FEM run whose elements cost far more than its vertices be
// doubled (35 s of stepping, 80.5 s in all).
constexpr double kPrecisionCheckSeconds = 1.0;
// Displacements below this share of the mesh's size (its bounding box's diagonal) are not compared: float rounds
// positions to about 6e-8 of it, and a scene that barely moves (1e-7 mm) once differed by "100%".
constexpr double kPrecisionDisplacementFloor = 1e-5;

struct PrecisionCheckResult {
  bool ran = false;
  std::string reason;            // why it did not run, or what it found
  Precision other = Precision::Double;
  double probe_force_difference = 0.0;     // relative
  double displacement_difference = 0.0;    // relative, of the final largest displacement
  std::size_t other_inverted = 0;          // the largest count in the other precision
  bool agrees = true;
};

// Where a run's time went (s), for summary.json's `timing`: what the wall time (the stepping rate) includes and what
// it leaves out.
struct SceneRunTiming {
  double simulator = 0.0;      // creating the simulator: copies, conversions, the upload to the device (not in wall)
  double first_advance = 0.0;  // the first advance (in stepping): also graph capture and the first kernel loads
  double stepping = 0.0;       // every advance, with the NaN/Inf and inversion checks
  double recording = 0.0;      // the events: largest displacement, frames and samples (downloads, energies, files)
};

// summary.json lists every implicit step's iterations and residual up to this many steps (about 30 bytes a step);
// past it the per-step arrays are left out (the sums stay, and time_series.csv has each row's worst since the one
// before).
inline constexpr std::size_t kMostSummarySolverSteps = 10000;

struct SceneRunResult {
  bool completed = false;  // false: stopped by a non-finite state (the error says where)
  std::size_t steps_planned = 0;
  std::size_t steps_taken = 0;
  StabilityReport stability;
  double wall_seconds = 0.0;
  double steps_per_second = 0.0;
  SceneRunTiming timing;
  double max_displacement = 0.0;  // m, over every vertex at the recorded times (frames and samples)
  std::vector<ProbeCurvePoint> probe_curve;  // at the samples; empty without a probe
  InversionReport inversions;
  // Implicit Euler: the solves' sums (Simulation::implicit_solver); nullopt for the explicit schemes.
  std::optional<ImplicitSolverReport> solver;
  double final_max_displacement = 0.0;  // m, at the last step
  PrecisionCheckResult precision_check;
  std::vector<Point3> final_positions;       // m, every vertex at the last step (the last finite state if stopped)
  // The run summary (docs/scenes.md, "Outputs"), as written to summary.json when the scene asks for it; built for
  // every run so that callers without files (the Python module) get the same fields.
  std::string summary_json;
  std::vector<std::string> files;            // written, in order
  std::string csv_path;                      // empty when no CSV was written
};

// The backend a scene runs on: `cpu`; `cuda` when a device can be used (an error saying why otherwise); `auto` the
// device when there is one, the CPU otherwise, with `note` saying which it took and why ("backend auto: no GPU
// (this fmpc was built without CUDA); running on the CPU") for the caller to show.
struct BackendChoice {
  std::string backend;  // "cpu" or "cuda", as SceneRunOptions::backend takes it
  std::string note;     // empty unless the scene said `auto`
};
std::optional<BackendChoice> choose_backend(const Scene& scene, DiagnosticList& diagnostics);

// Files an earlier run left in `directory`: every .pvd there that is exactly what run_scene writes (one DataSet
// line per frame_NNNNN.vtu) and the frames it lists. Anything else, a user's file included, is never a candidate.
std::vector<std::filesystem::path> earlier_run_files(const std::filesystem::path& directory);
// Removes those of `earlier` that this run did not write again (`written`: frames past the new count, a .pvd under
// another scene name), so that the folder holds one run. Returns how many files went.
std::size_t remove_stale_files(const std::vector<std::filesystem::path>& earlier,
                               const std::vector<std::string>& written, DiagnosticList& diagnostics);

// Where a run writes when its caller names no folder: the scene's outputs.directory, else SCENE-NAME_output.
std::string default_output_directory(const Scene& scene);

// The backend SceneRunOptions::backend names ("cuda": Backend::Cuda, else the CPU).
Backend run_backend(const std::string& name);

// Steps: scene.steps when set, else ceil(duration / dt) (dt from the stability check when `auto`).
// Returns nullopt when the simulation could not start or an output could not be written (errors appended).
std::optional<SceneRunResult> run_scene(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options,
                                        DiagnosticList& diagnostics);

// A cohort (fmpc simulate --patients, docs/cohorts.md): one scene for many patients, each with its own Scene (its
// material inputs) and BuiltScene, all at one time step (prepare_cohort) and so one step count and the same output
// times, each writing what run_scene writes into its own folder.
struct CohortPatient {
  std::string label;  // names the patient in messages ("patient 'P7': ...")
  const Scene* scene = nullptr;
  const BuiltScene* built = nullptr;
  std::string output_directory;
};

struct CohortRunOptions {
  std::string backend = "cpu";  // every patient in one Simulation batch on this backend ("cpu" or "cuda")
  unsigned threads = 0;         // CPU workers stepping and writing patients side by side (0: every hardware thread)
  // Spread over devices (docs/cohorts.md, "Every GPU of a node"): empty, one batch (on CUDA on the thread's current
  // device). Else the patients split into consecutive ranges (split_patients), one per entry, each run as its own
  // batch in its own host thread: on CUDA on that device (GpuOptions::device, set before anything is allocated), on
  // the CPU as that many batches side by side sharing `threads` (the entries' numbers are not used there). The
  // results are gathered in patient order and are bitwise those of one batch. Entries: distinct, non-negative.
  std::vector<int> devices;
  // (steps done, steps planned) after each output event.
  std::function<void(std::size_t, std::size_t)> progress;
};

struct CohortRunResult {
  // Per patient, in the order given: nullopt when it could not start or its outputs could not be written (errors
  // appended). A non-finite state in one patient stops the batch: every patient then has completed: false.
  std::vector<std::optional<SceneRunResult>> patients;
  // All patients: stepping and recording (outputs and the precision check excluded); over devices, the slowest
  // device's (they run at once).
  double wall_seconds = 0.0;
  double stepping_seconds = 0.0;  // the simulator's advance calls alone (their checks included); the slowest device's
  double spring_steps = 0.0;      // the sum over patients of springs x steps taken
};

// Checks every patient's setup (the stability check included) and gives them one time step: the scene's dt when
// given, else the smallest automatic step of all of them and of `smallest_elsewhere` (the smallest automatic step of
// the cohort's patients that another shard runs, so that a patient's result does not depend on the sharding). Every
// patient then runs the same steps (one batch on the GPU) and its result is bitwise the one run_scene gives its
// setup at that step. Also sets each setup's CPU threads to 1 (run_cohort runs patients side by side; results do
// not depend on the threads). Errors name the patient; returns the time step.
std::optional<double> prepare_cohort(const std::vector<BuiltScene*>& patients, const std::vector<std::string>& labels,
                                     std::optional<double> smallest_elsewhere, DiagnosticList& diagnostics);

// Runs the patients (prepared by prepare_cohort), writing each one's outputs into its own folder (created when
// missing). nullopt when nothing could start (errors appended).
std::optional<CohortRunResult> run_cohort(const std::vector<CohortPatient>& patients, const CohortRunOptions& options,
                                          DiagnosticList& diagnostics);

// The CSV's header for a scene with or without a probe, with implicit Euler's solver columns, and with its tools'
// names (docs/scenes.md lists the columns).
std::vector<std::string> time_series_columns(bool with_probe, bool with_solver = false,
                                             const std::vector<std::string>& tools = {});

// The one warning a run gives when implicit steps stopped at the solver's cap (code `cg-not-converged`): how many,
// the first with its residual, and the largest residual reached; nullopt when none did.
std::optional<std::string> capped_steps_message(const ImplicitSolverReport& report);

}  // namespace fmpc::sim
