#include "runtime/scene/precision_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

namespace {

double relative_difference(double a, double b) {
  const double scale = std::max(std::abs(a), std::abs(b));
  return scale > 0.0 ? std::abs(a - b) / scale : 0.0;
}

}  // namespace

std::optional<std::string> precision_check_skipped(const Scene& scene, const SceneRunResult& run,
                                                   double stepping_seconds) {
  if (scene.outputs.precision_check == SceneOutputs::PrecisionCheck::Off) return std::string("off (outputs.precision_check)");
  if (!run.completed) return std::string("the run did not complete");
  if (scene.outputs.precision_check == SceneOutputs::PrecisionCheck::Auto && stepping_seconds > kPrecisionCheckSeconds) {
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, "%.3g", stepping_seconds);
    return std::string("skipped: the run took ") + seconds + " s, and the check would take about as long again; `auto` "
           "checks runs of at most " + format_number(kPrecisionCheckSeconds) +
           " s (outputs.precision_check: on forces it)";
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
    const double other_displacement = largest_displacement(other_run->positions(ignored), start);
    check.displacement_difference = relative_difference(other_displacement, run.final_max_displacement);
    // A scene that barely moves has nothing rounding could change: below the floor both answers are rounding.
    Point3 low = start.empty() ? Point3{} : start.front(), high = low;
    for (const Point3& p : start)
      for (std::size_t a = 0; a < 3; ++a) low[a] = std::min(low[a], p[a]), high[a] = std::max(high[a], p[a]);
    const double floor = kPrecisionDisplacementFloor * distance(low, high);
    if (std::max(other_displacement, run.final_max_displacement) < floor) {
      check.displacement_difference = 0.0;
      check.other_inverted = other_run->inversions().largest_count;
      check.agrees = (check.other_inverted == 0) == (run.inversions.largest_count == 0);
      check.reason = std::string("agrees with ") + (check.other == Precision::Float ? "float" : "double") +
                     ": the scene moves less than " + format_number(kPrecisionDisplacementFloor) +
                     " of its size, which rounding cannot tell apart";
      if (check.agrees) return check;
    }
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
