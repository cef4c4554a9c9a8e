#include "runtime/scene/scene_recorder.h"

#include <cmath>
#include <cstdio>
#include <regex>
#include <sstream>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/io/atomic_file.h"
#include "runtime/io/input_file.h"
#include "runtime/io/json_text.h"

namespace fmpc::sim {

namespace {

std::string frame_name(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05zu.vtu", index);
  return name;
}

}  // namespace

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

SceneRecorder::SceneRecorder(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options,
                             std::size_t total)
    : scene_(scene), built_(built), options_(options), directory_(options.output_directory) {
  const SimulationSetup& setup = built.setup;
  result_.steps_planned = total;
  frame_steps_ = scene.outputs.frames > 0 ? spread(scene.outputs.frames, total) : std::vector<std::size_t>{};
  write_csv_ = scene.outputs.csv && scene.outputs.samples > 0;
  with_probe_ = setup.probe.has_value();
  with_solver_ = setup.integrator == Integrator::ImplicitEuler;
  for (const RigidTool& tool : setup.tools) tool_names_.push_back(tool.name);
  tool_peaks_.assign(setup.tools.size(), 0.0);
  sample_steps_ = write_csv_ || with_probe_ || !tool_names_.empty() ? spread(std::max(scene.outputs.samples, 2), total)
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
    const auto columns = time_series_columns(with_probe_, with_solver_, tool_names_);
    for (std::size_t i = 0; i < columns.size(); ++i) csv_ += (i ? "," : "") + columns[i];
    csv_ += "\n";
  }
  vtu_options_.format = scene.outputs.vtu;
}

void SceneRecorder::record(const SceneState& state, bool frame, bool sample, DiagnosticList& diagnostics) {
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
    if (!vtu_cells_) {
      // Elements whose kind has more nodes than the tetrahedron's corners are written with all of them, as the
      // kind's VTK cell (its edge nodes are points of the frame).
      const ElementGeometry& geometry = setup.elements.geometry;
      vtu_cells_ = !setup.elements.empty() && geometry.nodes_per_element != 4
                       ? encode_vtu_cells(geometry.nodes.data(), geometry.size(),
                                          static_cast<std::size_t>(geometry.nodes_per_element),
                                          static_cast<std::uint8_t>(element_kind_row(geometry.kind).vtk_cell_type),
                                          built_.mesh.source, vtu_options_, diagnostics)
                       : encode_vtu_cells(built_.mesh, vtu_options_, diagnostics);
    }
    // Element stresses as cell data where the cells are the elements: each element term's stress output (its law's:
    // a von Mises stress, or the volume term's pressure magnitude; springs carry no continuum stress).
    // The arrays point into the stresses' values, which must outlive the document's encoding.
    std::vector<ElementStressOutput> stresses;
    std::vector<VtuArray> cell_data;
    if (!setup.elements.empty() && vtu_cells_ && vtu_cells_->size() == setup.tetrahedra.size())
      stresses = element_stress_outputs(setup, positions);
    for (const ElementStressOutput& stress : stresses) cell_data.push_back(vtu_scalars(stress.name, stress.values));
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


void SceneRecorder::add_solver_steps(const std::vector<ImplicitStepRecord>& steps) {
  for (const ImplicitStepRecord& step : steps) {
    interval_iterations_ = std::max(interval_iterations_, step.iterations);
    interval_residual_ = std::max(interval_residual_, step.relative_residual);
    if (step_iterations_.size() < kMostSummarySolverSteps) {
      step_iterations_.push_back(step.iterations);
      step_residuals_.push_back(step.relative_residual);
    }
  }
}

void SceneRecorder::record_sample(const SceneState& state, double largest, const std::vector<Point3>& positions,
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
  if (with_solver_) {
    row.insert(row.end(), {static_cast<double>(interval_iterations_), interval_residual_});
    interval_iterations_ = 0;
    interval_residual_ = 0.0;
  }
  if (!tool_names_.empty()) {
    tool_readings_ = state.tool_readings(diagnostics);
    if (tool_readings_.size() != tool_names_.size()) {  // a device error, already reported
      outputs_ok_ = false;
      return;
    }
    for (std::size_t t = 0; t < tool_readings_.size(); ++t) {
      const ToolReading& reading = tool_readings_[t];
      tool_peaks_[t] = std::max(tool_peaks_[t], std::sqrt(dot(reading.force, reading.force)));
      row.insert(row.end(), {reading.force[0], reading.force[1], reading.force[2], reading.torque[0],
                             reading.torque[1], reading.torque[2], static_cast<double>(reading.contacts)});
    }
  }
  if (write_csv_) {
    for (std::size_t i = 0; i < row.size(); ++i) csv_ += (i ? "," : "") + format_number(row[i]);
    csv_ += "\n";
  }
}

std::optional<SceneRunResult> SceneRecorder::finish(const SceneState& state, bool completed, double wall_seconds,
                                                    const std::function<PrecisionCheckResult(const SceneRunResult&)>& check,
                                                    DiagnosticList& diagnostics) {
  SceneRunResult& result = result_;
  result.stability = state.stability();
  result.wall_seconds = wall_seconds;
  result.completed = completed;
  result.steps_taken = state.steps_taken();
  result.steps_per_second =
      result.wall_seconds > 0.0 ? static_cast<double>(result.steps_taken) / result.wall_seconds : 0.0;
  result.inversions = state.inversions();
  if (with_solver_) result.solver = state.implicit_solver();
  result.final_positions = state.positions(diagnostics);
  result.final_max_displacement = largest_displacement(result.final_positions, start_positions());
  result.precision_check = check(result);
  const Scene& scene = scene_;
  const std::filesystem::path& directory = directory_;
  const std::vector<PvdFrame>& frames = frames_;
  const bool write_csv = write_csv_;
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
  result.summary_json = summary_json(state, diagnostics);
  if (outputs_ok && scene.outputs.summary) {
    const std::string summary = (directory / "summary.json").string();
    outputs_ok = write_file_atomically(summary, result.summary_json, diagnostics);
    result.files.push_back(summary);
  }
  if (!outputs_ok) return std::nullopt;
  return result;
}

namespace {

// `mesh: {surface}`: how the surface was meshed (docs/meshing.md), with the quality distributions.
void add_meshing(JsonDocument& out, const MeshingRun& run) {
  const VolumeMesh& meshed = run.result;
  const SizeField& size = run.options.size;
  out["surface_vertices"] = meshed.surface_vertices;
  out["surface_triangles"] = meshed.surface_triangles;
  out["enclosed_volume"] = meshed.surface.volume;
  out["estimated_tetrahedra"] = meshed.estimate.tetrahedra;
  out["size_far"] = size.size_far;
  out["size_near"] = size.size_near;
  out["near_distance"] = size.near_distance;
  out["grading"] = size.grading;
  out["size_sources"] = size.sources.size();
  out["keep_surface"] = run.options.keep_surface;
  out["split_surface"] = run.options.split_surface;
  if (meshed.split) {
    out["split_surface_triangles"] = meshed.split->triangles_after;
    out["split_surface_vertices_added"] = meshed.split->parents.size();
    out["flat_surface_elements_removed"] = meshed.flat_removed;
  }
  out["seconds"] = run.seconds;
  out["above_size_field"] = meshed.above_size;
  if (meshed.untangling) {
    out["smoothed_vertices"] = meshed.untangling->moved_vertices;
    out["smoothing_largest_move"] = meshed.untangling->largest_move;
  }
  const auto distribution = [](JsonDocument& d, const Distribution& values) {
    d["min"] = values.min;
    d["p1"] = values.p1;
    d["p5"] = values.p5;
    d["p50"] = values.p50;
    d["p95"] = values.p95;
    d["p99"] = values.p99;
    d["max"] = values.max;
  };
  const TetrahedronQuality& q = meshed.quality;
  JsonDocument& ratio = out["radius_edge_ratio"];
  ratio["bound"] = run.options.max_radius_edge_ratio;
  ratio["above_bound"] = q.above_ratio_bound;
  ratio["above_bound_off_surface"] = q.above_ratio_bound_inside;
  distribution(ratio, q.radius_edge_ratio);
  JsonDocument& dihedral = out["min_dihedral_degrees"];
  dihedral["sought"] = run.options.min_dihedral_degrees;
  dihedral["below"] = q.below_dihedral_bound;
  distribution(dihedral, q.min_dihedral_degrees);
  distribution(out["longest_edge"], q.longest_edge);
}

}  // namespace

std::string SceneRecorder::summary_json(const SceneState& state, DiagnosticList& diagnostics) const {
  const Scene& scene = scene_;
  const BuiltScene& built = built_;
  const SceneRunOptions& options = options_;
  const SimulationSetup& setup = built_.setup;
  const SceneRunResult& result = result_;
  const std::vector<PvdFrame>& frames = frames_;
  const bool write_csv = write_csv_, with_probe = with_probe_;
  const double dt = result.stability.time_step;
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
  json["model"] = model_name(setup);
  if (setup.springs.size() == 0 && !setup.elements.empty()) {
    json["fem"]["law"] = element_law_row(setup.elements.terms.front().law).keyword;
    json["fem"]["element"] = element_kind_row(setup.elements.geometry.kind).keyword;
  }
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
  mesh["volume_term"] = setup.springs.size() > 0 && !setup.elements.empty();
  mesh["fixed_vertices"] = setup.fixed_vertices.size();
  mesh["metres_per_unit"] = scene.mesh.unit;
  if (built.meshing) add_meshing(mesh["meshing"], *built.meshing);
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
  if (!setup.tools.empty()) {
    JsonDocument& tools = json["tools"] = JsonDocument::array();
    for (std::size_t t = 0; t < setup.tools.size(); ++t) {
      const RigidTool& tool = setup.tools[t];
      JsonDocument entry = JsonDocument::object();
      entry["name"] = tool.name;
      entry["shape"] = tool.shape == RigidTool::Shape::Sphere ? "sphere" : "capsule";
      entry["radius_m"] = tool.radius;
      entry["length_m"] = tool.length;
      const ToolReading last = t < tool_readings_.size() ? tool_readings_[t] : ToolReading{};
      entry["final_force_N"] = {last.force[0], last.force[1], last.force[2]};
      entry["final_torque_Nm"] = {last.torque[0], last.torque[1], last.torque[2]};
      entry["final_contacts"] = last.contacts;
      entry["max_force_N"] = tool_peaks_[t];
      tools.push_back(entry);
    }
    json["contact_stiffness_ratio"] = setup.contact_stiffness_ratio;
    json["contact_damping_ratio"] = setup.contact_damping_ratio;
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
  if (result.solver) {
    const ImplicitSolverReport& solver = *result.solver;
    JsonDocument& out = json["solver"];
    out["method"] = to_string(solver.method);
    out["requested_method"] = to_string(setup.implicit.method);
    const bool cpu = options.backend != "cuda";
    out["preconditioner"] = solver.method == ImplicitMethod::Direct ? "none" : cpu ? "block_jacobi" : "jacobi";
    out["warm_start"] = cpu && solver.method == ImplicitMethod::ConjugateGradient && setup.implicit.warm_start;
    out["tolerance"] = solver.tolerance;
    out["max_iterations"] = static_cast<std::size_t>(solver.max_iterations);
    out["steps"] = solver.steps;
    out["iterations_min"] = static_cast<std::size_t>(solver.iterations_min);
    out["iterations_mean"] =
        solver.steps == 0 ? 0.0 : static_cast<double>(solver.iterations_total) / static_cast<double>(solver.steps);
    out["iterations_max"] = static_cast<std::size_t>(solver.iterations_max);
    out["iterations_total"] = static_cast<std::size_t>(solver.iterations_total);
    out["relative_residual_max"] = solver.residual_max;
    out["relative_residual_max_step"] = solver.residual_max_step;
    out["relative_residual_last"] = solver.last.relative_residual;
    out["capped_steps"] = solver.capped_steps;
    out["first_capped_step"] = solver.first_capped_step;
    out["first_capped_relative_residual"] = solver.first_capped_residual;
    out["direct_fallbacks"] = solver.direct_fallbacks;
    if (!setup.tools.empty()) {
      out["contact_rounds"] = static_cast<std::size_t>(setup.implicit.contact_rounds);
      out["contact_unsettled_steps"] = solver.contact_unsettled_steps;
      out["first_contact_unsettled_step"] = solver.first_contact_unsettled_step;
    }
    // Every step's numbers, in step order, while they fit (kMostSummarySolverSteps); null past it.
    if (solver.steps <= kMostSummarySolverSteps && step_iterations_.size() == solver.steps) {
      JsonDocument iterations = JsonDocument::array(), residuals = JsonDocument::array();
      for (std::size_t k = 0; k < step_iterations_.size(); ++k) {
        iterations.push_back(static_cast<std::size_t>(step_iterations_[k]));
        residuals.push_back(step_residuals_[k]);
      }
      JsonDocument& per_step = out["per_step"];
      per_step["iterations"] = std::move(iterations);
      per_step["relative_residual"] = std::move(residuals);
    } else {
      out["per_step"] = nullptr;
    }
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
  return json_text(json);
}

std::vector<std::string> time_series_columns(bool with_probe, bool with_solver, const std::vector<std::string>& tools) {
  std::vector<std::string> columns = {"time_s"};
  if (with_probe)
    columns.insert(columns.end(), {"probe_displacement_m", "probe_force_N", "probe_dx_m", "probe_dy_m", "probe_dz_m",
                                   "probe_fx_N", "probe_fy_N", "probe_fz_N"});
  columns.insert(columns.end(), {"kinetic_energy_J", "elastic_energy_J", "max_displacement_m"});
  // The worst implicit step since the row before: its iterations and its relative residual.
  if (with_solver) columns.insert(columns.end(), {"solver_iterations", "solver_relative_residual"});
  for (const std::string& tool : tools)
    for (const char* column : {"_fx_N", "_fy_N", "_fz_N", "_tx_Nm", "_ty_Nm", "_tz_Nm", "_contacts"})
      columns.push_back(tool + column);
  return columns;
}

std::optional<std::string> capped_steps_message(const ImplicitSolverReport& report) {
  if (report.capped_steps == 0) return std::nullopt;
  const bool direct = report.method == ImplicitMethod::Direct;
  return "implicit Euler: " + std::to_string(report.capped_steps) + " of " + std::to_string(report.steps) +
         " steps stopped at the cap of " + std::to_string(report.max_iterations) +
         (direct ? " direct solves" : " conjugate-gradient iterations") + " above the tolerance " +
         format_number(report.tolerance) + " (the first at step " + std::to_string(report.first_capped_step) +
         " with relative residual " + format_number(report.first_capped_residual) +
         "); the largest relative residual reached was " + format_number(report.residual_max) + " at step " +
         std::to_string(report.residual_max_step) +
         "; raise solver.max_iterations, loosen solver.tolerance or use a smaller dt";
}

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

}  // namespace fmpc::sim
