#pragma once
// Internal to runtime/scene: the outputs of one run (docs/scenes.md, "Outputs"), recorded at its events (frames,
// samples and about 100 progress points, the same for every run of the scene with the same step count) and written at
// its end: what run_scene writes for a scene alone and run_cohort for each patient. Not installed.
#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/io/vtk_xml.h"
#include "runtime/scene/scene_run.h"
#include "runtime/scene/scene_state.h"

namespace fmpc::sim {

// `count` steps evenly spread over [0, total], first and last included (one: the last only).
std::vector<std::size_t> spread(int count, std::size_t total);

class SceneRecorder {
 public:
  SceneRecorder(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options, std::size_t total);

  const std::set<std::size_t>& events() const { return events_; }
  bool is_frame(std::size_t step) const { return std::binary_search(frame_steps_.begin(), frame_steps_.end(), step); }
  bool is_sample(std::size_t step) const {
    return std::binary_search(sample_steps_.begin(), sample_steps_.end(), step);
  }
  // Whether the event needs velocities (a frame or a sample) besides the positions.
  bool needs_velocities(std::size_t step) const { return is_frame(step) || is_sample(step); }
  bool records_at_end() const { return scene_.outputs.frames > 0; }
  bool samples_at_end() const { return write_csv_ || with_probe_ || !tool_names_.empty(); }
  void set_timing(const SceneRunTiming& timing) { result_.timing = timing; }

  void record(const SceneState& state, bool frame, bool sample, DiagnosticList& diagnostics);
  // Implicit Euler's records of the steps since the last event (Simulation::take_implicit_steps), before record().
  void add_solver_steps(const std::vector<ImplicitStepRecord>& steps);
  // The run's end: its totals, then the precision check (check(result) gives it), the .pvd, the CSV and the summary.
  std::optional<SceneRunResult> finish(const SceneState& state, bool completed, double wall_seconds,
                                       const std::function<PrecisionCheckResult(const SceneRunResult&)>& check,
                                       DiagnosticList& diagnostics);

 private:
  // A sample's CSV row and probe curve point; positions and velocities may be empty where the state reduces in place.
  void record_sample(const SceneState& state, double largest, const std::vector<Point3>& positions,
                     const std::vector<Point3>& velocities, DiagnosticList& diagnostics);
  // summary.json's text for the run as result_ holds it at its end.
  std::string summary_json(const SceneState& state, DiagnosticList& diagnostics) const;
  const std::vector<Point3>& start_positions() const {
    const SimulationSetup& setup = built_.setup;
    return setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;
  }

  const Scene& scene_;
  const BuiltScene& built_;
  const SceneRunOptions& options_;
  const std::filesystem::path directory_;
  SceneRunResult result_;
  std::vector<std::size_t> frame_steps_, sample_steps_;
  std::set<std::size_t> events_;
  bool write_csv_ = false, with_probe_ = false;
  std::vector<std::string> tool_names_;
  std::vector<ToolReading> tool_readings_;  // at the last sample
  std::vector<double> tool_peaks_;           // the largest |force| of each tool over the samples (N)
  Point3 probe_axis_{0.0, 0.0, 0.0};
  std::string csv_;
  std::vector<PvdFrame> frames_;
  VtuOptions vtu_options_;
  std::optional<VtuCells> vtu_cells_;  // the cells are the same in every frame: encoded once, at the first
  bool outputs_ok_ = true;
  // Implicit Euler: the worst step since the last CSV row, and every step's record for summary.json (up to
  // kMostSummarySolverSteps).
  bool with_solver_ = false;
  int interval_iterations_ = 0;
  double interval_residual_ = 0.0;
  std::vector<int> step_iterations_;
  std::vector<double> step_residuals_;
};

}  // namespace fmpc::sim
