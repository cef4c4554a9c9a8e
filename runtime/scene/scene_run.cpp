#include "runtime/scene/scene_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>
#include <utility>
#include <thread>

#include "diagnostics/number_format.h"
#include "runtime/io/atomic_file.h"
#include "runtime/io/input_file.h"
#include "runtime/io/json_text.h"
#include "runtime/io/vtk_xml.h"
#include "runtime/integrate/worker_pool.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#endif

namespace fmpc::sim {

std::vector<std::string> time_series_columns(bool with_probe) {
  if (!with_probe) return {"time_s", "kinetic_energy_J", "elastic_energy_J", "max_displacement_m"};
  return {"time_s",          "probe_displacement_m", "probe_force_N",    "probe_dx_m",        "probe_dy_m",
          "probe_dz_m",      "probe_fx_N",           "probe_fy_N",       "probe_fz_N",        "kinetic_energy_J",
          "elastic_energy_J", "max_displacement_m"};
}

namespace {

// `count` steps evenly spread over [0, total], first and last included (one: the last only).
std::vector<std::size_t> spread(int count, std::size_t total) {
  std::vector<std::size_t> steps;
  if (count <= 0) return steps;
  if (count == 1) return {total};
  for (int i = 0; i < count; ++i) {
    const double fraction = static_cast<double>(i) / static_cast<double>(count - 1);
    steps.push_back(static_cast<std::size_t>(std::llround(fraction * static_cast<double>(total))));
  }
  steps.erase(std::unique(steps.begin(), steps.end()), steps.end());
  return steps;
}

double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// A run's state as the outputs read it, whichever backend holds it (called per output event, never per element).
class SceneState {
 public:
  virtual ~SceneState() = default;
  virtual std::size_t steps_taken() const = 0;
  virtual double time() const = 0;
  virtual const StabilityReport& stability() const = 0;
  virtual std::vector<Point3> positions(DiagnosticList& diagnostics) const = 0;
  virtual std::vector<Point3> velocities(DiagnosticList& diagnostics) const = 0;
  virtual ProbeReading probe_reading(DiagnosticList& diagnostics) const = 0;
  virtual std::vector<double> current_stiffness(DiagnosticList& diagnostics) const = 0;
  virtual const InversionReport& inversions() const = 0;
  // The largest distance of a vertex from `start` (its start positions): from positions() here; a backend whose
  // state lives elsewhere reduces it there (what every progress event asks, so it must not move the state).
  virtual std::optional<double> largest_displacement(const std::vector<Point3>& start,
                                                     DiagnosticList& diagnostics) const;
  // The kinetic and the elastic energy of the state whose positions and velocities are given (a sample's CSV row):
  // summed here from them; a backend whose state lives elsewhere sums there (on CUDA: in another order, so the
  // last bits may differ from the CPU's sums).
  virtual std::optional<std::pair<double, double>> energies(const SimulationSetup& setup,
                                                            const std::vector<Point3>& positions,
                                                            const std::vector<Point3>& velocities,
                                                            DiagnosticList& diagnostics) const;
  // Whether largest_displacement and energies reduce where the state lives and ignore the positions and velocities
  // passed: then a sample without a frame downloads nothing (on a 14M-vertex box, two samples' downloads and
  // host loops cost 1.6 s of a 4.1 s run).
  virtual bool reduces_in_place() const { return false; }
};

// A run that steps itself (one scene alone).
class SceneStepper : public SceneState {
 public:
  virtual bool advance(std::size_t steps, DiagnosticList& diagnostics) = 0;
};

class CpuStepper final : public SceneStepper {
 public:
  explicit CpuStepper(std::unique_ptr<CpuSimulation> simulation) : simulation_(std::move(simulation)) {}
  bool advance(std::size_t steps, DiagnosticList& diagnostics) override { return simulation_->advance(steps, diagnostics); }
  std::size_t steps_taken() const override { return simulation_->steps_taken(); }
  double time() const override { return simulation_->time(); }
  const StabilityReport& stability() const override { return simulation_->stability(); }
  std::vector<Point3> positions(DiagnosticList&) const override { return simulation_->positions(); }
  std::vector<Point3> velocities(DiagnosticList&) const override { return simulation_->velocities(); }
  ProbeReading probe_reading(DiagnosticList&) const override { return simulation_->probe_reading(); }
  std::vector<double> current_stiffness(DiagnosticList&) const override { return simulation_->current_stiffness(); }
  const InversionReport& inversions() const override { return simulation_->inversions(); }

 private:
  std::unique_ptr<CpuSimulation> simulation_;
};

#if defined(FMPC_RUNTIME_HAVE_CUDA)
class CudaStepper final : public SceneStepper {
 public:
  explicit CudaStepper(std::unique_ptr<gpu::GpuSimulation> simulation) : simulation_(std::move(simulation)) {}
  bool advance(std::size_t steps, DiagnosticList& diagnostics) override { return simulation_->advance(steps, diagnostics); }
  std::size_t steps_taken() const override { return simulation_->steps_taken(); }
  double time() const override { return simulation_->time(); }
  const StabilityReport& stability() const override { return simulation_->stability(); }
  std::vector<Point3> positions(DiagnosticList& diagnostics) const override {
    return simulation_->positions(diagnostics);
  }
  std::vector<Point3> velocities(DiagnosticList& diagnostics) const override {
    return simulation_->velocities(diagnostics);
  }
  ProbeReading probe_reading(DiagnosticList& diagnostics) const override {
    return simulation_->probe_reading(diagnostics);
  }
  std::vector<double> current_stiffness(DiagnosticList& diagnostics) const override {
    return simulation_->current_stiffness(diagnostics);
  }
  const InversionReport& inversions() const override { return simulation_->inversions(); }
  std::optional<double> largest_displacement(const std::vector<Point3>&, DiagnosticList& diagnostics) const override {
    return simulation_->largest_displacement(diagnostics);
  }
  bool reduces_in_place() const override { return true; }
  std::optional<std::pair<double, double>> energies(const SimulationSetup&, const std::vector<Point3>&,
                                                    const std::vector<Point3>&,
                                                    DiagnosticList& diagnostics) const override {
    const auto kinetic = simulation_->kinetic_energy(diagnostics);
    const auto elastic = simulation_->elastic_energy(diagnostics);
    if (!kinetic || !elastic) return std::nullopt;
    return std::make_pair(*kinetic, *elastic);
  }

 private:
  std::unique_ptr<gpu::GpuSimulation> simulation_;
};
#endif

std::unique_ptr<SceneStepper> create_stepper(const SimulationSetup& setup, const std::string& backend,
                                             DiagnosticList& diagnostics) {
  if (backend == "cuda") {
#if defined(FMPC_RUNTIME_HAVE_CUDA)
    auto simulation = gpu::GpuSimulation::create(setup, diagnostics);
    if (!simulation) return nullptr;
    return std::make_unique<CudaStepper>(std::move(simulation));
#else
    diagnostics.error(SourceRange{}, "this fmpc was built without CUDA; run the scene with backend cpu or auto");
    return nullptr;
#endif
  }
  auto simulation = CpuSimulation::create(setup, diagnostics);
  if (!simulation) return nullptr;
  return std::make_unique<CpuStepper>(std::move(simulation));
}

// The largest distance of any vertex from its start.
double largest_displacement(const std::vector<Point3>& positions, const std::vector<Point3>& start) {
  double largest = 0.0;
  for (std::size_t v = 0; v < positions.size() && v < start.size(); ++v)
    largest = std::max(largest, distance(positions[v], start[v]));
  return largest;
}

std::optional<std::pair<double, double>> SceneState::energies(const SimulationSetup& setup,
                                                              const std::vector<Point3>& positions,
                                                              const std::vector<Point3>& velocities,
                                                              DiagnosticList&) const {
  return std::make_pair(kinetic_energy(setup, velocities), elastic_energy(setup, positions));
}

std::optional<double> SceneState::largest_displacement(const std::vector<Point3>& start,
                                                       DiagnosticList& diagnostics) const {
  const std::vector<Point3> now = positions(diagnostics);
  if (now.size() != start.size()) return std::nullopt;  // a device error, already reported
  return sim::largest_displacement(now, start);
}

double relative_difference(double a, double b) {
  const double scale = std::max(std::abs(a), std::abs(b));
  return scale > 0.0 ? std::abs(a - b) / scale : 0.0;
}

// Why the precision check does not run for this run, or nullopt when it does (outputs.precision_check, and `auto`'s
// limit on the vertex-steps).
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

// The setup of the rerun: the other precision at the run's step.
SimulationSetup precision_check_setup(const SimulationSetup& setup, const SceneRunResult& run) {
  SimulationSetup other = setup;
  other.precision = setup.precision == Precision::Float ? Precision::Double : Precision::Float;
  other.time_step = run.stability.time_step;  // the same step, not the other precision's automatic one
  return other;
}

// The rerun's final state (null: it did not complete) against the run's final answers, warned about when they differ.
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

// The scene again in the other precision, to its last step, compared with the run's final answers.
PrecisionCheckResult check_precision(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options,
                                     const SceneRunResult& run, DiagnosticList& diagnostics) {
  const SimulationSetup& setup = built.setup;
  if (const auto skipped = precision_check_skipped(scene, setup, run)) {
    PrecisionCheckResult check;
    check.other = setup.precision == Precision::Float ? Precision::Double : Precision::Float;
    check.reason = *skipped;
    return check;
  }
  DiagnosticList ignored;
  const auto simulation = create_stepper(precision_check_setup(setup, run), options.backend, ignored);
  const bool completed = simulation && simulation->advance(run.steps_taken, ignored);
  return compare_precision(scene, setup, run, completed ? simulation.get() : nullptr, diagnostics);
}

std::string frame_name(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05zu.vtu", index);
  return name;
}

// The outputs of one run, recorded at its events (frames, samples and about 100 progress points, the same for every
// run of the scene with the same step count) and written at its end: what run_scene writes for a scene alone and
// run_cohort for each patient.
class SceneRecorder {
 public:
  SceneRecorder(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options, std::size_t total)
      : scene_(scene), built_(built), options_(options), directory_(options.output_directory) {
    const SimulationSetup& setup = built.setup;
    result_.steps_planned = total;
    frame_steps_ = scene.outputs.frames > 0 ? spread(scene.outputs.frames, total) : std::vector<std::size_t>{};
    write_csv_ = scene.outputs.csv && scene.outputs.samples > 0;
    with_probe_ = setup.probe.has_value();
    sample_steps_ = write_csv_ || with_probe_ ? spread(std::max(scene.outputs.samples, 2), total)
                                              : std::vector<std::size_t>{};
    events_.insert(frame_steps_.begin(), frame_steps_.end());
    events_.insert(sample_steps_.begin(), sample_steps_.end());
    for (int i = 1; i <= 100; ++i) events_.insert(total * static_cast<std::size_t>(i) / 100);
    events_.insert(total);
    if (with_probe_) {
      const double length = std::sqrt(dot(setup.probe->target, setup.probe->target));
      if (length > 0.0)
        for (std::size_t i = 0; i < 3; ++i) probe_axis_[i] = setup.probe->target[i] / length;
    }
    if (write_csv_) {
      const auto columns = time_series_columns(with_probe_);
      for (std::size_t i = 0; i < columns.size(); ++i) csv_ += (i ? "," : "") + columns[i];
      csv_ += "\n";
    }
    vtu_options_.format = scene.outputs.vtu;
  }

  const std::set<std::size_t>& events() const { return events_; }
  bool is_frame(std::size_t step) const { return std::binary_search(frame_steps_.begin(), frame_steps_.end(), step); }
  bool is_sample(std::size_t step) const {
    return std::binary_search(sample_steps_.begin(), sample_steps_.end(), step);
  }
  // Whether the event needs velocities (a frame or a sample) besides the positions.
  bool needs_velocities(std::size_t step) const { return is_frame(step) || is_sample(step); }
  bool records_at_end() const { return scene_.outputs.frames > 0; }
  bool samples_at_end() const { return write_csv_ || with_probe_; }
  void set_timing(const SceneRunTiming& timing) { result_.timing = timing; }

  // The state at an event: the largest displacement always, a frame and a CSV row (with the probe curve's point)
  // where asked.
  void record(const SceneState& state, bool frame, bool sample, DiagnosticList& diagnostics) {
    const SimulationSetup& setup = built_.setup;
    const std::vector<Point3>& rest = start_positions();
    if (!frame && (!sample || state.reduces_in_place())) {
      // A progress event (the largest displacement alone), or a sample reduced where the state lives.
      const std::optional<double> largest = state.largest_displacement(rest, diagnostics);
      if (largest) result_.max_displacement = std::max(result_.max_displacement, *largest);
      else outputs_ok_ = false;
      if (largest && sample) record_sample(state, *largest, {}, {}, diagnostics);
      return;
    }
    const std::vector<Point3> positions = state.positions(diagnostics);
    if (positions.size() != rest.size()) {  // a device error, already reported
      outputs_ok_ = false;
      return;
    }
    std::vector<Point3> displacement(positions.size());
    double largest = 0.0;
    for (std::size_t v = 0; v < positions.size(); ++v) {
      for (std::size_t i = 0; i < 3; ++i) displacement[v][i] = positions[v][i] - rest[v][i];
      largest = std::max(largest, std::sqrt(dot(displacement[v], displacement[v])));
    }
    result_.max_displacement = std::max(result_.max_displacement, largest);
    const double time = state.time();
    // Downloaded once for the frame and the sample of the same event.
    const bool write_frame = frame && outputs_ok_;
    const std::vector<Point3> velocities =
        write_frame || sample ? state.velocities(diagnostics) : std::vector<Point3>{};
    if (write_frame) {
      const std::string name = frame_name(frames_.size());
      if (!vtu_cells_) vtu_cells_ = encode_vtu_cells(built_.mesh, vtu_options_, diagnostics);
      // Element stresses as cell data where the cells are the elements: the FEM's von Mises stress, or the volume
      // term's pressure magnitude (springs carry no continuum stress).
      std::vector<double> stress;
      std::vector<VtuArray> cell_data;
      if (setup.tetrahedron_field && vtu_cells_ && vtu_cells_->size() == setup.tetrahedra.size()) {
        stress = element_von_mises_stress(setup, positions);
        cell_data.push_back(vtu_scalars(
            setup.model == ForceModel::CorotationalFem ? "von_mises_stress_Pa" : "volume_term_pressure_Pa", stress));
      }
      const auto vtu = vtu_cells_ ? vtu_document(positions, *vtu_cells_,
                                                 {vtu_vectors("displacement", displacement),
                                                  vtu_vectors("velocity", velocities)},
                                                 cell_data, vtu_options_, diagnostics)
                                  : std::nullopt;
      outputs_ok_ = vtu && write_file_atomically((directory_ / name).string(), *vtu, diagnostics);
      frames_.push_back({time, name});
      result_.files.push_back((directory_ / name).string());
    }
    if (sample) record_sample(state, largest, positions, velocities, diagnostics);
  }

  // A sample's CSV row and probe curve point; positions and velocities may be empty where the state reduces in place.
  void record_sample(const SceneState& state, double largest, const std::vector<Point3>& positions,
                     const std::vector<Point3>& velocities, DiagnosticList& diagnostics) {
    const double time = state.time();
    const auto energies = state.energies(built_.setup, positions, velocities, diagnostics);
    if (!energies) {  // a device error, already reported
      outputs_ok_ = false;
      return;
    }
    const auto [kinetic, elastic] = *energies;
    std::vector<double> row = {time};
    if (with_probe_) {
      const ProbeReading reading = state.probe_reading(diagnostics);
      const ProbeCurvePoint point{time, dot(reading.displacement, probe_axis_), dot(reading.force, probe_axis_)};
      result_.probe_curve.push_back(point);
      row.insert(row.end(), {point.displacement, point.force, reading.displacement[0], reading.displacement[1],
                             reading.displacement[2], reading.force[0], reading.force[1], reading.force[2]});
    }
    row.insert(row.end(), {kinetic, elastic, largest});
    if (write_csv_) {
      for (std::size_t i = 0; i < row.size(); ++i) csv_ += (i ? "," : "") + format_number(row[i]);
      csv_ += "\n";
    }
  }

  // The run's end: its totals, then the precision check (check(result) gives it), the .pvd, the CSV and the summary.
  std::optional<SceneRunResult> finish(const SceneState& state, bool completed, double wall_seconds,
                                       const std::function<PrecisionCheckResult(const SceneRunResult&)>& check,
                                       DiagnosticList& diagnostics) {
    const SimulationSetup& setup = built_.setup;
    SceneRunResult& result = result_;
    result.stability = state.stability();
    result.wall_seconds = wall_seconds;
    result.completed = completed;
    result.steps_taken = state.steps_taken();
    result.steps_per_second =
        result.wall_seconds > 0.0 ? static_cast<double>(result.steps_taken) / result.wall_seconds : 0.0;
    result.inversions = state.inversions();
    result.final_positions = state.positions(diagnostics);
    result.final_max_displacement = largest_displacement(result.final_positions, start_positions());
    result.precision_check = check(result);
    const Scene& scene = scene_;
    const BuiltScene& built = built_;
    const SceneRunOptions& options = options_;
    const std::filesystem::path& directory = directory_;
    const std::vector<PvdFrame>& frames = frames_;
    const bool write_csv = write_csv_, with_probe = with_probe_;
    const double dt = result.stability.time_step;
    bool outputs_ok = outputs_ok_;
    if (outputs_ok && !frames.empty()) {
      const std::string pvd = (directory / (scene.name + ".pvd")).string();
      outputs_ok = write_file_atomically(pvd, pvd_document(frames), diagnostics);
      result.files.push_back(pvd);
    }
    if (outputs_ok && write_csv) {
      result.csv_path = (directory / "time_series.csv").string();
      outputs_ok = write_file_atomically(result.csv_path, csv_, diagnostics);
      result.files.push_back(result.csv_path);
    }
  {
    const std::vector<double> stiffness = state.current_stiffness(diagnostics);
    double k_min = 0.0, k_max = 0.0, k_sum = 0.0;
    if (!stiffness.empty()) {
      k_min = *std::min_element(stiffness.begin(), stiffness.end());
      k_max = *std::max_element(stiffness.begin(), stiffness.end());
      for (const double k : stiffness) k_sum += k;
    }
    JsonDocument json;
    json["scene"] = scene.name;
    json["scene_file"] = scene.path;
    json["completed"] = result.completed;
    json["model"] = scene_name(setup.model);
    json["inverted_elements"] = result.inversions.largest_count;
    json["backend"] = options.backend;
    json["precision"] = setup.precision == Precision::Float ? "float" : "double";
    json["integrator"] = scene_name(setup.integrator);
    json["dt_s"] = dt;
    json["dt_auto"] = result.stability.automatic;
    json["critical_dt_s"] = result.stability.critical_time_step;
    json["steps"] = result.steps_taken;
    json["steps_planned"] = result.steps_planned;
    json["simulated_time_s"] = state.time();
    json["wall_time_s"] = result.wall_seconds;
    json["steps_per_second"] = result.steps_per_second;
    JsonDocument& timing = json["timing"];
    timing["simulator_s"] = result.timing.simulator;
    timing["first_advance_s"] = result.timing.first_advance;
    timing["stepping_s"] = result.timing.stepping;
    timing["recording_s"] = result.timing.recording;
    json["threads"] = static_cast<std::size_t>(setup.threads);
    json["max_displacement_m"] = result.max_displacement;
    JsonDocument& mesh = json["mesh"];
    mesh["source"] = built.mesh.source;
    mesh["vertices"] = built.mesh.points.size();
    mesh["tetrahedra"] = built.mesh.tetrahedra.size();
    mesh["triangles"] = built.mesh.triangles.size();
    mesh["springs"] = setup.springs.size();
    mesh["volume_term"] = setup.model == ForceModel::Springs && setup.tetrahedron_field.has_value();
    mesh["fixed_vertices"] = setup.fixed_vertices.size();
    mesh["metres_per_unit"] = scene.mesh.unit;
    JsonDocument& material = json["stiffness"];
    material["description"] = built.stiffness_description;
    material["k_min_N_per_m"] = k_min;
    material["k_mean_N_per_m"] = stiffness.empty() ? 0.0 : k_sum / static_cast<double>(stiffness.size());
    material["k_max_N_per_m"] = k_max;
    material["strain_table"] = setup.strain_stiffness.has_value();
    if (built.material) {
      material["rules"] = scene.material.file;
      material["system"] = built.material->system;
      material["output"] = built.material->output;
      material["patient"] = scene.material.patient;
      material["youngs_modulus_min_kPa"] = built.material->modulus_min / 1000.0;
      material["youngs_modulus_max_kPa"] = built.material->modulus_max / 1000.0;
      material["evaluations"] = built.material->evaluations;
      JsonDocument& inputs = material["inputs"] = JsonDocument::object();
      for (const InputBinding& binding : scene.material.bindings) {
        if (binding.kind == InputBinding::Kind::Constant) inputs[binding.input] = binding.value;
        else inputs[binding.input] = binding.kind == InputBinding::Kind::Strain ? "strain" : "per region";
      }
    }
    if (with_probe) {
      double max_force = 0.0;
      for (const ProbeCurvePoint& point : result.probe_curve) max_force = std::max(max_force, std::abs(point.force));
      JsonDocument& probe = json["probe"];
      probe["mode"] = setup.probe->mode == ProbeLoad::Mode::Displacement ? "displacement" : "force";
      probe["vertices"] = setup.probe->vertices.size();
      probe["final_displacement_m"] = result.probe_curve.empty() ? 0.0 : result.probe_curve.back().displacement;
      probe["final_force_N"] = result.probe_curve.empty() ? 0.0 : result.probe_curve.back().force;
      probe["max_abs_force_N"] = max_force;
    }
    JsonDocument& inversions = json["inversions"];
    inversions["largest_count"] = result.inversions.largest_count;
    inversions["final_count"] = result.inversions.current_count;
    inversions["checked_every_steps"] = kCheckEvery;
    inversions["policy"] = setup.on_inversion == InversionPolicy::Stop ? "stop" : "warn";
    if (result.inversions.largest_count > 0) {
      inversions["first_step"] = result.inversions.first_step;
      inversions["first_time_s"] = result.inversions.first_time;
      inversions["first_element"] = static_cast<std::size_t>(result.inversions.first_element);
    }
    const PrecisionCheckResult& precision = result.precision_check;
    JsonDocument& precision_json = json["precision_check"];
    precision_json["ran"] = precision.ran;
    precision_json["other_precision"] = precision.other == Precision::Float ? "float" : "double";
    precision_json["result"] = precision.reason;
    precision_json["tolerance"] = kPrecisionTolerance;
    if (precision.ran) {
      precision_json["probe_force_relative_difference"] = precision.probe_force_difference;
      precision_json["max_displacement_relative_difference"] = precision.displacement_difference;
      precision_json["other_inverted_elements"] = precision.other_inverted;
      precision_json["agrees"] = precision.agrees;
    }
    JsonDocument& outputs = json["outputs"];
    outputs["directory"] = options.output_directory;
    outputs["frames"] = frames.size();
    outputs["pvd"] = frames.empty() ? std::string() : scene.name + ".pvd";
    outputs["csv"] = write_csv ? std::string("time_series.csv") : std::string();
    result.summary_json = json_text(json);
  }
  if (outputs_ok && scene.outputs.summary) {
    const std::string summary = (directory / "summary.json").string();
    outputs_ok = write_file_atomically(summary, result.summary_json, diagnostics);
    result.files.push_back(summary);
  }
    if (!outputs_ok) return std::nullopt;
    return result;
  }

 private:
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
  Point3 probe_axis_{0.0, 0.0, 0.0};
  std::string csv_;
  std::vector<PvdFrame> frames_;
  VtuOptions vtu_options_;
  std::optional<VtuCells> vtu_cells_;  // the cells are the same in every frame: encoded once, at the first
  bool outputs_ok_ = true;
};

// A patient's messages as its own: "patient 'P7': " before each (given `patient`), or a GPU batch's "scene N: ..."
// and "... in scene N" named by the patient they are about (a batch of one names no scene).
void append_for_patients(const DiagnosticList& from, const std::vector<CohortPatient>& patients,
                         std::optional<std::size_t> patient, DiagnosticList& to) {
  static const std::regex batch_scene(R"(^scene ([0-9]+): |in scene ([0-9]+))");
  const auto named = [&](std::size_t p) { return "patient '" + patients[p].label + "'"; };
  for (Diagnostic diagnostic : from.items()) {
    std::smatch match;
    if (patient) {
      diagnostic.message = named(*patient) + ": " + diagnostic.message;
    } else if (std::regex_search(diagnostic.message, match, batch_scene)) {
      const std::size_t who = std::stoull(match[1].matched ? match[1].str() : match[2].str());
      if (who < patients.size()) {
        diagnostic.message = match[1].matched ? named(who) + ": " + match.suffix().str()
                                              : match.prefix().str() + "in " + named(who) + match.suffix().str();
      }
    } else if (patients.size() == 1) {
      diagnostic.message = named(0) + ": " + diagnostic.message;
    }
    to.add(std::move(diagnostic));
  }
}

#if defined(FMPC_RUNTIME_HAVE_CUDA)
// One patient of a GPU batch as the recorder reads it: the state downloaded at the event for every patient at once
// (GpuBatchSimulation::scene_states), the probe read on the host from it exactly as GpuBatchSimulation::probe_reading
// reads it (sim::read_probe on the same positions, velocities and stiffness), so each patient's outputs are those of
// its run alone.
class BatchMemberState final : public SceneState {
 public:
  BatchMemberState(const gpu::GpuBatchSimulation& batch, std::size_t index, const SimulationSetup& setup)
      : batch_(batch), index_(index), setup_(setup) {}
  // The springs' stiffness is constant without a strain table: read once.
  bool read_stiffness(DiagnosticList& diagnostics) {
    if (setup_.strain_stiffness) return true;
    stiffness_ = batch_.current_stiffness(index_, diagnostics);
    return stiffness_.size() == setup_.springs.size();
  }
  void set_state(std::vector<Point3>* positions, std::vector<Point3>* velocities) {
    positions_ = positions;
    velocities_ = velocities;
  }
  std::size_t steps_taken() const override { return batch_.steps_taken(); }
  double time() const override { return static_cast<double>(steps_taken()) * stability().time_step; }
  const StabilityReport& stability() const override { return batch_.stability(index_); }
  std::vector<Point3> positions(DiagnosticList&) const override { return positions_ ? *positions_ : std::vector<Point3>{}; }
  std::vector<Point3> velocities(DiagnosticList&) const override {
    return velocities_ ? *velocities_ : std::vector<Point3>{};
  }
  ProbeReading probe_reading(DiagnosticList& diagnostics) const override {
    if (!setup_.probe || !positions_ || !velocities_) return {};
    return read_probe(setup_, time(), *positions_, *velocities_, current_stiffness(diagnostics));
  }
  std::vector<double> current_stiffness(DiagnosticList& diagnostics) const override {
    if (setup_.strain_stiffness) return batch_.current_stiffness(index_, diagnostics);
    return stiffness_;
  }
  const InversionReport& inversions() const override { return batch_.inversions(index_); }

 private:
  const gpu::GpuBatchSimulation& batch_;
  std::size_t index_;
  const SimulationSetup& setup_;
  std::vector<double> stiffness_;
  std::vector<Point3>* positions_ = nullptr;
  std::vector<Point3>* velocities_ = nullptr;
};

// Every patient's state now, one download per array for the whole batch.
bool read_members(const gpu::GpuBatchSimulation& batch, bool with_velocities, std::vector<std::vector<Point3>>& positions,
                  std::vector<std::vector<Point3>>& velocities, std::vector<BatchMemberState>& members,
                  DiagnosticList& diagnostics) {
  if (!batch.scene_states(positions, with_velocities ? &velocities : nullptr, diagnostics)) return false;
  for (std::size_t p = 0; p < members.size(); ++p)
    members[p].set_state(&positions[p], with_velocities ? &velocities[p] : nullptr);
  return true;
}

std::optional<CohortRunResult> run_cohort_on_gpu(const std::vector<CohortPatient>& patients,
                                                 const CohortRunOptions& options, DiagnosticList& diagnostics) {
  std::vector<SimulationSetup> setups;
  for (const CohortPatient& patient : patients) setups.push_back(patient.built->setup);
  DiagnosticList batch_diagnostics;
  const auto batch = gpu::GpuBatchSimulation::create(setups, gpu::GpuOptions{}, batch_diagnostics);
  append_for_patients(batch_diagnostics, patients, std::nullopt, diagnostics);
  if (!batch) return std::nullopt;
  std::vector<BatchMemberState> members;
  for (std::size_t p = 0; p < patients.size(); ++p) members.emplace_back(*batch, p, patients[p].built->setup);
  for (BatchMemberState& member : members)
    if (!member.read_stiffness(diagnostics)) return std::nullopt;
  const Scene& scene = *patients.front().scene;
  const auto planned = planned_step_count(scene, batch->stability(0).time_step, diagnostics);
  if (!planned) return std::nullopt;
  const std::size_t total = *planned;
  std::vector<SceneRunOptions> run_options(patients.size());
  std::vector<std::unique_ptr<SceneRecorder>> recorders;
  for (std::size_t p = 0; p < patients.size(); ++p) {
    run_options[p].output_directory = patients[p].output_directory;
    run_options[p].backend = "cuda";
    recorders.push_back(std::make_unique<SceneRecorder>(*patients[p].scene, *patients[p].built, run_options[p], total));
  }
  // Every patient has the same events (same scene outputs, same step count): the first recorder's.
  const SceneRecorder& plan = *recorders.front();
  std::vector<std::vector<Point3>> positions, velocities;
  std::vector<DiagnosticList> patient_diagnostics(patients.size());
  const auto record_all = [&](bool frame, bool sample) {
    if (!read_members(*batch, frame || sample, positions, velocities, members, diagnostics)) return false;
    for (std::size_t p = 0; p < patients.size(); ++p) recorders[p]->record(members[p], frame, sample, patient_diagnostics[p]);
    return true;
  };
  const auto start = std::chrono::steady_clock::now();
  bool running = true;
  if (plan.is_frame(0) || plan.is_sample(0)) running = record_all(plan.is_frame(0), plan.is_sample(0));
  DiagnosticList run_diagnostics;
  for (const std::size_t event : plan.events()) {
    if (!running || event == 0) continue;
    running = batch->advance(event - batch->steps_taken(), run_diagnostics);
    if (!running) break;
    if (!record_all(plan.is_frame(event), plan.is_sample(event))) {
      append_for_patients(run_diagnostics, patients, std::nullopt, diagnostics);
      return std::nullopt;
    }
    if (options.progress) options.progress(event, total);
  }
  append_for_patients(run_diagnostics, patients, std::nullopt, diagnostics);
  if (!running) record_all(plan.records_at_end(), plan.samples_at_end());
  CohortRunResult result;
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The precision check: every patient again in the other precision, in a second batch at the same step.
  SceneRunResult provisional;
  provisional.completed = running;
  provisional.steps_taken = batch->steps_taken();
  std::vector<SimulationSetup> other_setups;  // outlives other_members, which refer to it
  std::unique_ptr<gpu::GpuBatchSimulation> other;
  std::vector<BatchMemberState> other_members;
  std::vector<std::vector<Point3>> other_positions, other_velocities;
  if (!precision_check_skipped(scene, setups.front(), provisional)) {
    provisional.stability = batch->stability(0);
    for (const SimulationSetup& setup : setups) other_setups.push_back(precision_check_setup(setup, provisional));
    DiagnosticList ignored;  // the main run reported everything the scene says
    other = gpu::GpuBatchSimulation::create(other_setups, gpu::GpuOptions{}, ignored);
    if (other && other->advance(provisional.steps_taken, ignored)) {
      for (std::size_t p = 0; p < patients.size(); ++p) other_members.emplace_back(*other, p, other_setups[p]);
      bool read = read_members(*other, true, other_positions, other_velocities, other_members, ignored);
      for (BatchMemberState& member : other_members) read = read && member.read_stiffness(ignored);
      if (!read) other_members.clear();
    }
  }
  for (std::size_t p = 0; p < patients.size(); ++p) {
    const SceneState* other_state = other_members.empty() ? nullptr : &other_members[p];
    const SimulationSetup& setup = patients[p].built->setup;
    result.patients.push_back(recorders[p]->finish(
        members[p], running, result.wall_seconds,
        [&](const SceneRunResult& run) {
          if (const auto skipped = precision_check_skipped(*patients[p].scene, setup, run)) {
            PrecisionCheckResult check;
            check.other = setup.precision == Precision::Float ? Precision::Double : Precision::Float;
            check.reason = *skipped;
            return check;
          }
          return compare_precision(*patients[p].scene, setup, run, other_state, patient_diagnostics[p]);
        },
        patient_diagnostics[p]));
    append_for_patients(patient_diagnostics[p], patients, p, diagnostics);
    result.spring_steps += static_cast<double>(setup.springs.size()) * static_cast<double>(batch->steps_taken());
  }
  return result;
}
#endif

std::optional<CohortRunResult> run_cohort_on_cpu(const std::vector<CohortPatient>& patients,
                                                 const CohortRunOptions& options, DiagnosticList& diagnostics) {
  CohortRunResult result;
  result.patients.resize(patients.size());
  std::vector<DiagnosticList> patient_diagnostics(patients.size());
  std::mutex progress_lock;
  std::size_t done = 0;
  const unsigned threads = options.threads != 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  WorkerPool pool(static_cast<unsigned>(std::min<std::size_t>(threads, patients.size())));
  const auto start = std::chrono::steady_clock::now();
  // One patient per index: chunks of whole patients, each run exactly as run_scene runs it alone.
  pool.run(
      patients.size(),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p < end; ++p) {
          SceneRunOptions run_options;
          run_options.output_directory = patients[p].output_directory;
          run_options.backend = "cpu";
          result.patients[p] = run_scene(*patients[p].scene, *patients[p].built, run_options, patient_diagnostics[p]);
          const std::lock_guard<std::mutex> lock(progress_lock);
          ++done;
          if (options.progress) options.progress(done, patients.size());
        }
      },
      1);
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t p = 0; p < patients.size(); ++p) {
    append_for_patients(patient_diagnostics[p], patients, p, diagnostics);
    if (result.patients[p])
      result.spring_steps += static_cast<double>(patients[p].built->setup.springs.size()) *
                             static_cast<double>(result.patients[p]->steps_taken);
  }
  return result;
}

}  // namespace

std::vector<std::filesystem::path> earlier_run_files(const std::filesystem::path& directory) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  std::error_code error;
  if (!fs::is_directory(directory, error)) return files;
  static const std::regex frame_line(
      R"re(    <DataSet timestep="[-+0-9.eE]+" group="" part="0" file="(frame_[0-9]{5}\.vtu)"/>)re");
  const std::string head =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  const std::string tail = "  </Collection>\n</VTKFile>\n";
  for (const fs::directory_entry& entry : fs::directory_iterator(directory, error)) {
    if (entry.path().extension() != ".pvd" || !entry.is_regular_file(error)) continue;
    std::string read_error;
    const std::optional<std::string> text = read_input_file(entry.path().string(), kMaxSceneFileBytes, "pvd", read_error);
    if (!text || text->compare(0, head.size(), head) != 0 || text->size() < head.size() + tail.size() ||
        text->compare(text->size() - tail.size(), tail.size(), tail) != 0)
      continue;
    std::vector<fs::path> frames;
    std::istringstream lines(text->substr(head.size(), text->size() - head.size() - tail.size()));
    bool fmpc_wrote_it = true;
    for (std::string line; std::getline(lines, line);) {
      std::smatch match;
      if (!std::regex_match(line, match, frame_line)) {
        fmpc_wrote_it = false;
        break;
      }
      frames.push_back(directory / match[1].str());
    }
    if (!fmpc_wrote_it) continue;
    files.push_back(entry.path());
    for (const fs::path& frame : frames)
      if (fs::is_regular_file(frame, error)) files.push_back(frame);
  }
  return files;
}

std::size_t remove_stale_files(const std::vector<std::filesystem::path>& earlier, const std::vector<std::string>& written,
                               DiagnosticList& diagnostics) {
  std::size_t removed = 0;
  for (const std::filesystem::path& path : earlier) {
    bool rewritten = false;
    for (const std::string& file : written)
      rewritten = rewritten || std::filesystem::path(file).lexically_normal() == path.lexically_normal();
    if (rewritten) continue;
    std::error_code error;
    if (std::filesystem::remove(path, error)) ++removed;
    else if (error)
      diagnostics.error(SourceRange{path.string(), 0, 0, 0, 0},
                        "cannot remove this file of an earlier run: " + error.message());
  }
  return removed;
}

std::optional<BackendChoice> choose_backend(const Scene& scene, DiagnosticList& diagnostics) {
  std::string device;
#if defined(FMPC_RUNTIME_HAVE_CUDA)
  const bool have_device = gpu::cuda_device_available(device);
#else
  const bool have_device = false;
  device = "this fmpc was built without CUDA";
#endif
  switch (scene.backend) {
    case SceneBackend::Cpu:
      return BackendChoice{"cpu", ""};
    case SceneBackend::Auto:
      if (have_device) return BackendChoice{"cuda", "backend auto: running on CUDA (" + device + ")"};
      return BackendChoice{"cpu", "backend auto: no GPU (" + device + "); running on the CPU"};
    case SceneBackend::Cuda:
      if (have_device) return BackendChoice{"cuda", ""};
      diagnostics.error(scene.range_of("backend"),
                        "backend: 'cuda' cannot run here: " + device + "; use backend cpu or auto");
      return std::nullopt;
  }
  return std::nullopt;
}

std::string default_output_directory(const Scene& scene) {
  return !scene.outputs.directory.empty() ? scene.outputs.directory : scene.name + "_output";
}

std::optional<SceneRunResult> run_scene(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options,
                                        DiagnosticList& diagnostics) {
  const SimulationSetup& setup = built.setup;
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point from) {
    return std::chrono::duration<double>(Clock::now() - from).count();
  };
  SceneRunTiming timing;
  const auto created = Clock::now();
  const auto simulation = create_stepper(setup, options.backend, diagnostics);
  if (!simulation) return std::nullopt;
  timing.simulator = seconds_since(created);
  if (!ensure_directory(options.output_directory, diagnostics)) return std::nullopt;
  const auto planned = planned_step_count(scene, simulation->stability().time_step, diagnostics);
  if (!planned) return std::nullopt;
  const std::size_t total = *planned;
  SceneRecorder recorder(scene, built, options, total);
  const auto record = [&](bool frame, bool sample) {
    const auto from = Clock::now();
    recorder.record(*simulation, frame, sample, diagnostics);
    timing.recording += seconds_since(from);
  };
  const auto start = Clock::now();
  if (recorder.is_frame(0) || recorder.is_sample(0)) record(recorder.is_frame(0), recorder.is_sample(0));
  bool running = true;
  bool first = true;
  for (const std::size_t event : recorder.events()) {
    if (event == 0) continue;
    const auto from = Clock::now();
    running = simulation->advance(event - simulation->steps_taken(), diagnostics);
    const double advanced = seconds_since(from);
    timing.stepping += advanced;
    if (first) timing.first_advance = advanced;
    first = false;
    if (!running) break;
    // The largest displacement is followed at every event (about 100 per run).
    record(recorder.is_frame(event), recorder.is_sample(event));
    if (options.progress) options.progress(event, total);
  }
  if (!running) record(recorder.records_at_end(), recorder.samples_at_end());
  const double wall = seconds_since(start);
  recorder.set_timing(timing);
  return recorder.finish(
      *simulation, running, wall,
      [&](const SceneRunResult& run) { return check_precision(scene, built, options, run, diagnostics); },
      diagnostics);
}

std::optional<double> prepare_cohort(const std::vector<BuiltScene*>& patients, const std::vector<std::string>& labels,
                                     std::optional<double> smallest_elsewhere, DiagnosticList& diagnostics) {
  if (patients.empty()) {
    diagnostics.error(SourceRange{}, "a cohort needs at least one patient");
    return std::nullopt;
  }
  std::vector<CohortPatient> named(patients.size());
  for (std::size_t p = 0; p < patients.size() && p < labels.size(); ++p) named[p].label = labels[p];
  std::optional<double> smallest = smallest_elsewhere;
  const bool automatic = !patients.front()->setup.time_step.has_value();
  for (std::size_t p = 0; p < patients.size(); ++p) {
    DiagnosticList patient_diagnostics;
    const auto report = check_stability(patients[p]->setup, patient_diagnostics);
    // Only the errors: the run's own check repeats the warnings.
    DiagnosticList errors;
    for (const Diagnostic& diagnostic : patient_diagnostics.items())
      if (diagnostic.severity == Severity::Error) errors.add(diagnostic);
    append_for_patients(errors, named, p, diagnostics);
    if (!report) continue;
    smallest = smallest ? std::min(*smallest, report->time_step) : report->time_step;
  }
  if (diagnostics.has_errors() || !smallest) return std::nullopt;
  for (BuiltScene* patient : patients) {
    if (automatic) patient->setup.time_step = *smallest;
    patient->setup.threads = 1;
  }
  return smallest;
}

std::optional<CohortRunResult> run_cohort(const std::vector<CohortPatient>& patients, const CohortRunOptions& options,
                                          DiagnosticList& diagnostics) {
  if (patients.empty()) {
    diagnostics.error(SourceRange{}, "a cohort needs at least one patient");
    return std::nullopt;
  }
  for (const CohortPatient& patient : patients)
    if (!ensure_directory(patient.output_directory, diagnostics)) return std::nullopt;
  if (options.backend == "cuda") {
#if defined(FMPC_RUNTIME_HAVE_CUDA)
    return run_cohort_on_gpu(patients, options, diagnostics);
#else
    diagnostics.error(SourceRange{}, "this fmpc was built without CUDA; run the cohort with backend cpu or auto");
    return std::nullopt;
#endif
  }
  return run_cohort_on_cpu(patients, options, diagnostics);
}

}  // namespace fmpc::sim
