#include "runtime/scene/precision_check.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

namespace {

double relative_difference(double a, double b) {
  const double scale = std::max(std::abs(a), std::abs(b));
  return scale > 0.0 ? std::abs(a - b) / scale : 0.0;
}

}  // namespace

std::optional<std::string> precision_check_skipped(const Scene& scene, const SimulationSetup& setup,
                                                   const SceneRunResult& run) {
  const double work = static_cast<double>(setup.rest_positions.size()) * static_cast<double>(run.steps_taken);
  if (scene.outputs.precision_check == SceneOutputs::PrecisionCheck::Off) return std::string("off (outputs.precision_check)");
  if (!run.completed) return std::string("the run did not complete");
  if (scene.outputs.precision_check == SceneOutputs::PrecisionCheck::Auto && work > kPrecisionCheckWork) {
    return "skipped: " + format_number(work) + " vertex-steps is above the automatic limit of " +
           format_number(kPrecisionCheckWork) + " (outputs.precision_check: on forces it)";
  }
  return std::nullopt;
}

SimulationSetup precision_check_setup(const SimulationSetup& setup, const SceneRunResult& run) {
  SimulationSetup other = setup;
  other.precision = setup.precision == Precision::Float ? Precision::Double : Precision::Float;
  other.time_step = run.stability.time_step;  // the same step, not the other precision's automatic one
  return other;
}

PrecisionCheckResult compare_precision(const Scene& scene, const SimulationSetup& setup, const SceneRunResult& run,
                                       const SceneState* other_run, DiagnosticList& diagnostics) {
  PrecisionCheckResult check;
  check.other = setup.precision == Precision::Float ? Precision::Double : Precision::Float;
  DiagnosticList ignored;  // the main run reported everything the scene says
  if (other_run == nullptr) {
    check.reason = "the rerun in the other precision did not complete";
    check.agrees = false;
  } else {
    check.ran = true;
    const std::vector<Point3>& start = setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;
    check.displacement_difference =
        relative_difference(largest_displacement(other_run->positions(ignored), start), run.final_max_displacement);
    if (setup.probe && !run.probe_curve.empty()) {
      const ProbeReading reading = other_run->probe_reading(ignored);
      const double length = std::sqrt(dot(setup.probe->target, setup.probe->target));
      const double force = length > 0.0 ? dot(reading.force, setup.probe->target) / length : 0.0;
      check.probe_force_difference = relative_difference(force, run.probe_curve.back().force);
    }
    check.other_inverted = other_run->inversions().largest_count;
    check.agrees = check.displacement_difference <= kPrecisionTolerance &&
                   check.probe_force_difference <= kPrecisionTolerance &&
                   (check.other_inverted == 0) == (run.inversions.largest_count == 0);
  }
  const char* mine = setup.precision == Precision::Float ? "float" : "double";
  const char* theirs = check.other == Precision::Float ? "float" : "double";
  if (check.ran && !check.agrees) {
    std::ostringstream message;
    message << "precision: the answer depends on rounding: in " << theirs << " ";
    if (setup.probe) message << "the final probe force differs by " << 100 * check.probe_force_difference << "% and ";
    message << "the final largest displacement by " << 100 * check.displacement_difference << "% (tolerance "
            << 100 * kPrecisionTolerance << "%), with " << check.other_inverted << " inverted elements against "
            << run.inversions.largest_count << " in " << mine
            << "; an equilibrium that rounding breaks (a symmetric load that can buckle either way) or an element "
               "near inversion: use precision double, or break the symmetry (docs/scenes.md)";
    diagnostics.warning(scene.range_of("precision"), "precision-dependent", message.str());
    check.reason = "differs";
  } else if (check.ran) {
    check.reason = std::string("agrees with ") + theirs;
  }
  return check;
}

}  // namespace fmpc::sim
