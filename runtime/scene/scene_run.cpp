#include "runtime/scene/scene_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <set>
#include <sstream>

#include "diagnostics/number_format.h"
#include "runtime/io/atomic_file.h"
#include "runtime/io/input_file.h"
#include "runtime/io/json_text.h"
#include "runtime/io/vtk_xml.h"
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

// The run's simulation behind one interface, whichever backend steps it (called per output event, never per
// element).
class SceneStepper {
 public:
  virtual ~SceneStepper() = default;
  virtual bool advance(std::size_t steps, DiagnosticList& diagnostics) = 0;
  virtual std::size_t steps_taken() const = 0;
  virtual double time() const = 0;
  virtual const StabilityReport& stability() const = 0;
  virtual std::vector<Point3> positions(DiagnosticList& diagnostics) const = 0;
  virtual std::vector<Point3> velocities(DiagnosticList& diagnostics) const = 0;
  virtual ProbeReading probe_reading(DiagnosticList& diagnostics) const = 0;
  virtual std::vector<double> current_stiffness(DiagnosticList& diagnostics) const = 0;
  virtual const InversionReport& inversions() const = 0;
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

double relative_difference(double a, double b) {
  const double scale = std::max(std::abs(a), std::abs(b));
  return scale > 0.0 ? std::abs(a - b) / scale : 0.0;
}

// The scene again in the other precision, to its last step, compared with the run's final answers.
PrecisionCheckResult check_precision(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options,
                                     const SceneRunResult& run, DiagnosticList& diagnostics) {
  PrecisionCheckResult check;
  const SimulationSetup& setup = built.setup;
  check.other = setup.precision == Precision::Float ? Precision::Double : Precision::Float;
  const double work = static_cast<double>(setup.rest_positions.size()) * static_cast<double>(run.steps_taken);
  if (scene.outputs.precision_check == SceneOutputs::PrecisionCheck::Off) {
    check.reason = "off (outputs.precision_check)";
    return check;
  }
  if (!run.completed) {
    check.reason = "the run did not complete";
    return check;
  }
  if (scene.outputs.precision_check == SceneOutputs::PrecisionCheck::Auto && work > kPrecisionCheckWork) {
    check.reason = "skipped: " + format_number(work) + " vertex-steps is above the automatic limit of " +
                   format_number(kPrecisionCheckWork) + " (outputs.precision_check: on forces it)";
    return check;
  }
  SimulationSetup other = setup;
  other.precision = check.other;
  other.time_step = run.stability.time_step;  // the same step, not the other precision's automatic one
  DiagnosticList ignored;  // the main run reported everything the scene says
  const auto simulation = create_stepper(other, options.backend, ignored);
  if (!simulation || !simulation->advance(run.steps_taken, ignored)) {
    check.reason = "the rerun in the other precision did not complete";
    check.agrees = false;
  } else {
    check.ran = true;
    const std::vector<Point3>& start = setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;
    check.displacement_difference =
        relative_difference(largest_displacement(simulation->positions(ignored), start), run.final_max_displacement);
    if (setup.probe && !run.probe_curve.empty()) {
      const ProbeReading reading = simulation->probe_reading(ignored);
      const double length = std::sqrt(dot(setup.probe->target, setup.probe->target));
      const double force = length > 0.0 ? dot(reading.force, setup.probe->target) / length : 0.0;
      check.probe_force_difference = relative_difference(force, run.probe_curve.back().force);
    }
    check.other_inverted = simulation->inversions().largest_count;
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

std::string frame_name(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05zu.vtu", index);
  return name;
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
  const auto simulation = create_stepper(setup, options.backend, diagnostics);
  if (!simulation) return std::nullopt;
  if (!ensure_directory(options.output_directory, diagnostics)) return std::nullopt;
  SceneRunResult result;
  result.stability = simulation->stability();
  const double dt = result.stability.time_step;
  const auto planned = planned_step_count(scene, dt, diagnostics);
  if (!planned) return std::nullopt;
  result.steps_planned = *planned;
  const std::size_t total = result.steps_planned;
  const std::vector<std::size_t> frame_steps = scene.outputs.frames > 0 ? spread(scene.outputs.frames, total)
                                                                        : std::vector<std::size_t>{};
  const bool write_csv = scene.outputs.csv && scene.outputs.samples > 0;
  const std::vector<std::size_t> sample_steps =
      write_csv || setup.probe ? spread(std::max(scene.outputs.samples, 2), total) : std::vector<std::size_t>{};
  std::set<std::size_t> events(frame_steps.begin(), frame_steps.end());
  events.insert(sample_steps.begin(), sample_steps.end());
  for (int i = 1; i <= 100; ++i) events.insert(total * static_cast<std::size_t>(i) / 100);
  events.insert(total);

  const std::filesystem::path directory(options.output_directory);
  const bool with_probe = setup.probe.has_value();
  Point3 probe_axis{0.0, 0.0, 0.0};
  if (with_probe) {
    const double length = std::sqrt(dot(setup.probe->target, setup.probe->target));
    if (length > 0.0)
      for (std::size_t i = 0; i < 3; ++i) probe_axis[i] = setup.probe->target[i] / length;
  }
  const std::vector<Point3>& rest = setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;

  std::string csv;
  if (write_csv) {
    const auto columns = time_series_columns(with_probe);
    for (std::size_t i = 0; i < columns.size(); ++i) csv += (i ? "," : "") + columns[i];
    csv += "\n";
  }
  std::vector<PvdFrame> frames;
  VtuOptions vtu_options;
  vtu_options.format = scene.outputs.vtu;
  std::optional<VtuCells> vtu_cells;  // the cells are the same in every frame: encoded once, at the first
  bool outputs_ok = true;
  const auto record = [&](bool frame, bool sample) {
    const std::vector<Point3> positions = simulation->positions(diagnostics);
    if (positions.size() != rest.size()) {  // a device error, already reported
      outputs_ok = false;
      return;
    }
    std::vector<Point3> displacement(positions.size());
    double largest = 0.0;
    for (std::size_t v = 0; v < positions.size(); ++v) {
      for (std::size_t i = 0; i < 3; ++i) displacement[v][i] = positions[v][i] - rest[v][i];
      largest = std::max(largest, std::sqrt(dot(displacement[v], displacement[v])));
    }
    result.max_displacement = std::max(result.max_displacement, largest);
    const double time = simulation->time();
    if (frame && outputs_ok) {
      const std::string name = frame_name(frames.size());
      const std::vector<Point3> velocities = simulation->velocities(diagnostics);
      if (!vtu_cells) vtu_cells = encode_vtu_cells(built.mesh, vtu_options, diagnostics);
      // Element stresses as cell data where the cells are the elements: the FEM's von Mises stress, or the volume
      // term's pressure magnitude (springs carry no continuum stress).
      std::vector<double> stress;
      std::vector<VtuArray> cell_data;
      if (setup.tetrahedron_field && vtu_cells && vtu_cells->size() == setup.tetrahedra.size()) {
        stress = element_von_mises_stress(setup, positions);
        cell_data.push_back(vtu_scalars(
            setup.model == ForceModel::CorotationalFem ? "von_mises_stress_Pa" : "volume_term_pressure_Pa", stress));
      }
      const auto vtu = vtu_cells ? vtu_document(positions, *vtu_cells,
                                                {vtu_vectors("displacement", displacement),
                                                 vtu_vectors("velocity", velocities)},
                                                cell_data, vtu_options, diagnostics)
                                 : std::nullopt;
      outputs_ok = vtu && write_file_atomically((directory / name).string(), *vtu, diagnostics);
      frames.push_back({time, name});
      result.files.push_back((directory / name).string());
    }
    if (!sample) return;
    const std::vector<Point3> velocities = simulation->velocities(diagnostics);
    const double kinetic = kinetic_energy(setup, velocities);
    const double elastic = elastic_energy(setup, positions);
    std::vector<double> row = {time};
    if (with_probe) {
      const ProbeReading reading = simulation->probe_reading(diagnostics);
      const ProbeCurvePoint point{time, dot(reading.displacement, probe_axis), dot(reading.force, probe_axis)};
      result.probe_curve.push_back(point);
      row.insert(row.end(), {point.displacement, point.force, reading.displacement[0], reading.displacement[1],
                             reading.displacement[2], reading.force[0], reading.force[1], reading.force[2]});
    }
    row.insert(row.end(), {kinetic, elastic, largest});
    if (write_csv) {
      for (std::size_t i = 0; i < row.size(); ++i) csv += (i ? "," : "") + format_number(row[i]);
      csv += "\n";
    }
  };

  const auto start = std::chrono::steady_clock::now();
  const auto is_frame = [&](std::size_t step) { return std::binary_search(frame_steps.begin(), frame_steps.end(), step); };
  const auto is_sample = [&](std::size_t step) {
    return std::binary_search(sample_steps.begin(), sample_steps.end(), step);
  };
  if (is_frame(0) || is_sample(0)) record(is_frame(0), is_sample(0));
  bool running = true;
  for (const std::size_t event : events) {
    if (event == 0) continue;
    running = simulation->advance(event - simulation->steps_taken(), diagnostics);
    if (!running) break;
    if (is_frame(event) || is_sample(event)) record(is_frame(event), is_sample(event));
    else record(false, false);  // the largest displacement is followed at every event (about 100 per run)
    if (options.progress) options.progress(event, total);
  }
  if (!running) record(scene.outputs.frames > 0, write_csv || with_probe);  // the last finite state
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.completed = running;
  result.steps_taken = simulation->steps_taken();
  result.steps_per_second =
      result.wall_seconds > 0.0 ? static_cast<double>(result.steps_taken) / result.wall_seconds : 0.0;
  result.inversions = simulation->inversions();
  result.final_positions = simulation->positions(diagnostics);
  result.final_max_displacement = largest_displacement(result.final_positions, rest);
  result.precision_check = check_precision(scene, built, options, result, diagnostics);

  if (outputs_ok && !frames.empty()) {
    const std::string pvd = (directory / (scene.name + ".pvd")).string();
    outputs_ok = write_file_atomically(pvd, pvd_document(frames), diagnostics);
    result.files.push_back(pvd);
  }
  if (outputs_ok && write_csv) {
    result.csv_path = (directory / "time_series.csv").string();
    outputs_ok = write_file_atomically(result.csv_path, csv, diagnostics);
    result.files.push_back(result.csv_path);
  }
  {
    const std::vector<double> stiffness = simulation->current_stiffness(diagnostics);
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
    json["simulated_time_s"] = simulation->time();
    json["wall_time_s"] = result.wall_seconds;
    json["steps_per_second"] = result.steps_per_second;
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
    JsonDocument& check = json["precision_check"];
    check["ran"] = precision.ran;
    check["other_precision"] = precision.other == Precision::Float ? "float" : "double";
    check["result"] = precision.reason;
    check["tolerance"] = kPrecisionTolerance;
    if (precision.ran) {
      check["probe_force_relative_difference"] = precision.probe_force_difference;
      check["max_displacement_relative_difference"] = precision.displacement_difference;
      check["other_inverted_elements"] = precision.other_inverted;
      check["agrees"] = precision.agrees;
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

}  // namespace fmpc::sim
