#pragma once
// What `fmpc simulate` and its cohort mode (--patients, tools/fmpc/simulate_cohort.cpp) share: the options, the
// command-line overrides and the force-displacement picture (the backend choice and the cleaning of an earlier
// run's files are the library's: runtime/scene/scene_run.h).
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"
#include "tools/fmpc/commands.h"
#include "tools/plot/canvas.h"

namespace fmpc::cli {

struct SimulateOptions {
  std::string scene;
  std::string backend;
  std::string precision;
  std::optional<std::size_t> steps;
  std::optional<double> duration;
  std::string output_directory;
  std::string patients;  // a cohort's patients file (CSV); empty: the scene alone
  std::string shard;     // I/N: every N-th patient from the I-th (0-based); empty: all
  std::string devices;   // "all" or a list of CUDA devices ("0,1") the cohort is spread over; empty: one batch
};

// Six significant digits (hiding residues such as 0.6000000000000001): tick labels and the run's report.
std::string six_digits(double value);

// Force (N) against probe displacement (mm) of one run, the ramp and the hold drawn apart.
std::string render_force_displacement(const std::vector<sim::ProbeCurvePoint>& curve, const sim::Scene& scene,
                                      const sim::BuiltScene& built, plot::ImageFormat format);

// The scene file read (its text kept in `sources`), parsed and with the command-line overrides applied; nullopt
// after errors.
std::optional<sim::Scene> read_scene(const SimulateOptions& options, SourceFiles& sources, DiagnosticList& diagnostics);

// Applies the command-line overrides; errors name the option and what is allowed.
bool apply_overrides(const SimulateOptions& options, sim::Scene& scene, DiagnosticList& diagnostics);

// Diagnostics in file order, printed.
void report(DiagnosticList& diagnostics, const SourceFiles& sources);

// fmpc simulate SCENE --patients FILE [--shard I/N] [--devices LIST|all] (docs/cohorts.md).
int run_cohort_command(const SimulateOptions& options);

}  // namespace fmpc::cli
