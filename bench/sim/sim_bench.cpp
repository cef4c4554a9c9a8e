// Simulation benchmark: steps per second of the CPU backend (1 and N threads) and the CUDA backend (float/double,
// one launch per kernel, CUDA graphs, or one persistent launch per chunk (column `graphs`: no, yes, persistent),
// every GPU integrator), on hanging boxes from ~1k to ~1M springs, plus a batch of
// small scenes in one launch against the same scenes run one by one, a cohort of demo-scene patients with their
// probes in one launch; then the co-rotational FEM (tetrahedron-steps/s)
// from ~8k to ~10M tetrahedra and springs with the volume term. Writes a CSV and prints a table.
//
//   fmpc_sim_bench [--out DIR] [--quick] [--threads N] [--min-seconds S] [--fem-cells N] [--fem-only]
//                  [--cohort PATIENTS] [--liver PATH] [--implicit-only] [--fem-law LAW] [--fem-element ELEMENT]
//
// --fem-law / --fem-element: the FEM rows of that law (fem: {law}) on that element kind (fem: {element}); the
// springs-with-the-volume-term rows only with the defaults.
//
// --cohort N: the cohort row's patients (default 1,000; 64 with --quick unless --cohort is given): the demo scene's
// block with its probe, one batch (fmpc simulate --patients), aggregate spring-steps/s.
// --fem-only: the element rows alone; with --fem-cells N > 52, only the N^3 box on the GPU (for profilers).
// --liver PATH: SOFA's liver.msh (../shared/data/sofa-liver), for the implicit Euler rows at SOFA's settings.
// --implicit-only: the implicit Euler rows alone (issue 27 item 3): SOFA's liver FEM scene (rulesets/scenes/
// sofa_liver_fem.yaml: 596 tetrahedra, dt 0.02, the CG capped at 25 iterations) and the 20^3-cell FEM box at dt
// 1 ms (bench/scenes/box20_fem_implicit.yaml), on the CPU and on CUDA (the conjugate gradient as planned: in one
// block where the solve fits its shared memory; in one cooperative launch per step; in per-iteration launches), with
// the iterations and residuals reached in column `solver`.
//
// Every run checks for NaN/Inf every 64 steps (the default of advance), and the time includes that check's
// synchronisation. Scene creation and upload are not timed; one warm-up chunk (graph capture) is excluded.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "runtime/fem/fem_model_builder.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/scene/spring_model_builder.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

#if FMPC_RUNTIME_HAVE_CUDA
// A simulation on the CUDA backend: one scene, or a batch.
std::unique_ptr<Simulation> gpu_simulation(const SimulationSetup& setup, DiagnosticList& diagnostics,
                                           const GpuOptions& options = {}) {
  SimulationOptions cuda;
  cuda.backend = Backend::Cuda;
  cuda.gpu = options;
  return Simulation::create(setup, diagnostics, cuda);
}
std::unique_ptr<Simulation> gpu_batch(std::vector<SimulationSetup> scenes, const GpuOptions& options,
                                      DiagnosticList& diagnostics) {
  SimulationOptions cuda;
  cuda.backend = Backend::Cuda;
  cuda.gpu = options;
  return Simulation::create(std::move(scenes), cuda, diagnostics);
}
#endif

struct Options {
  std::string out_dir;
  bool quick = false;
  unsigned threads = 0;  // 0: hardware concurrency
  double min_seconds = 0.5;
  int fem_cells = 120;  // the largest FEM box, GPU only: 120^3 cells = 10,368,000 tetrahedra
  bool fem_only = false;
  std::size_t cohort = 1000;   // patients of the demo scene in the cohort row
  bool cohort_given = false;   // --cohort N also holds with --quick
  int spring_cells = 0;        // > 0: only the large springs box of this many cells per side (GPU rows)
  bool cohort_only = false;    // only the cohort rows (with --spring-cells: both)
  std::string liver;           // SOFA's liver.msh for the implicit rows (empty: the liver row is skipped)
  bool implicit_only = false;  // only the implicit Euler rows
  // The element rows' law and element kind (fem: {law, element} keywords; empty: the registries' defaults).
  std::string fem_law;
  std::string fem_element;
};

struct Row {
  std::string model = "springs";
  std::string variant;
  std::string backend;
  std::string precision;
  std::string integrator;
  std::string graphs;
  unsigned threads = 1;
  std::size_t scenes = 1;
  std::size_t vertices = 0;  // all scenes
  std::size_t springs = 0;   // all scenes
  std::size_t elements = 0;  // tetrahedra of the element pass (FEM, volume term), all scenes
  std::size_t steps = 0;
  double seconds = 0.0;
  std::string status = "ok";
  std::string solver = "-";  // implicit Euler: the iterations and the residuals the timed steps reached

  double microseconds_per_step() const { return steps == 0 ? 0.0 : 1e6 * seconds / static_cast<double>(steps); }
  double spring_steps_per_second() const {
    return seconds > 0.0 ? static_cast<double>(springs) * static_cast<double>(steps) / seconds : 0.0;
  }
  double element_steps_per_second() const {
    return seconds > 0.0 ? static_cast<double>(elements) * static_cast<double>(steps) / seconds : 0.0;
  }
};

// A box of cells^3 Kuhn cubes (edges, face and body diagonals), 0.1 m, soft tissue, hanging from its top face.
SimulationSetup benchmark_box(int cells, Precision precision, Integrator integrator, double young_modulus = 5000.0) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = box.cells_y = box.cells_z = cells;
  box.size = {0.1, 0.1, 0.1};
  const Mesh mesh = generate_box(box, diagnostics);
  SpringModelSpec model;
  model.stiffness.mapping = StiffnessMapping::VanGelder1998;
  model.stiffness.value = young_modulus;
  model.mass.value = 1060.0;
  auto setup = build_spring_model(mesh, model, diagnostics);
  if (!setup) return {};
  for (std::size_t v = 0; v < setup->rest_positions.size(); ++v) {
    if (setup->rest_positions[v][1] > 0.0999) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
  }
  setup->gravity = {0.0, -9.81, 0.0};
  setup->precision = precision;
  setup->integrator = integrator;
  return *setup;
}

// The same box as a finite-element model of `law` on `element` (registry indices; nu 0.45, damping ratio 0.9), or,
// with_springs, as springs with the law beside them calibrated for nu 0.45.
SimulationSetup benchmark_element_box(int cells, bool with_springs, int law, int element) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = box.cells_y = box.cells_z = cells;
  box.size = {0.1, 0.1, 0.1};
  const Mesh mesh = generate_box(box, diagnostics);
  std::optional<SimulationSetup> setup;
  if (!with_springs) {
    FemModelSpec spec;
    spec.law = law;
    spec.element = element;
    spec.youngs_modulus = {5000.0};
    spec.poisson_ratio = {0.45};
    spec.mass.value = 1060.0;
    spec.damping_ratio = 0.9;
    setup = build_fem_model(mesh, spec, diagnostics);
  } else {
    ElementMaterial material;
    material.youngs_modulus.assign(mesh.tetrahedra.size(), 5000.0);
    material.poisson_ratio.assign(mesh.tetrahedra.size(), 0.45);
    auto term = element_law_beside_springs().build(material, diagnostics);
    if (!term) return {};
    SpringModelSpec spec;
    spec.stiffness.mapping = StiffnessMapping::VanGelder1998;
    spec.stiffness.value = 5000.0 * term->spring_modulus_scale;
    spec.mass.value = 1060.0;
    spec.damping.ratio = 0.9;
    setup = build_spring_model(mesh, spec, diagnostics);
    if (setup) {
      setup->tetrahedra = mesh.tetrahedra;
      if (!add_element_term(*setup, std::move(term->term), 0.9, 0.0, diagnostics)) return {};
    }
  }
  if (!setup) return {};
  for (std::size_t v = 0; v < setup->rest_positions.size(); ++v) {
    if (setup->rest_positions[v][1] > 0.0999) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
  }
  setup->gravity = {0.0, -9.81, 0.0};
  return *setup;
}

std::size_t element_count(const SimulationSetup& setup) {
  return setup.elements.empty() ? 0 : setup.tetrahedra.size();
}

// "springs", the finite-element law's model keyword, or springs with the law beside them.
std::string model_label(const SimulationSetup& setup) {
  if (setup.springs.size() > 0 && !setup.elements.empty())
    return element_law_row(setup.elements.terms.front().law).trade_label;
  // The default law keeps its model name (the rows of earlier runs in docs/performance.md); another law is named.
  const int law = setup.elements.empty() ? default_fem_law().law : setup.elements.terms.front().law;
  const std::string name = law == default_fem_law().law ? sim::model_name(setup) : element_law_row(law).keyword;
  const int kind = setup.elements.geometry.kind;
  if (kind == default_element_kind().kind) return name;
  return name + " (" + element_kind_rows()[static_cast<std::size_t>(kind)].keyword + ")";
}

// Runs advance(chunk) until at least min_seconds have passed (the chunk doubling from `first`), after one untimed
// warm-up chunk. Returns false when a run failed.
bool time_steps(const std::function<bool(std::size_t)>& advance, std::size_t first, double min_seconds, Row& row) {
  if (!advance(first)) return false;
  std::size_t chunk = first;
  std::size_t steps = 0;
  const auto start = std::chrono::steady_clock::now();
  double elapsed = 0.0;
  while (elapsed < min_seconds) {
    if (!advance(chunk)) return false;
    steps += chunk;
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (elapsed < min_seconds / 4.0) chunk *= 2;
  }
  row.steps = steps;
  row.seconds = elapsed;
  return true;
}

std::string failure_text(const DiagnosticList& diagnostics) {
  return diagnostics.items().empty() ? "failed" : "failed: " + diagnostics.items().front().message;
}

const char* precision_name(Precision precision) { return precision == Precision::Float ? "float" : "double"; }

Row cpu_row(const SimulationSetup& base, unsigned threads, Precision precision, const Options& options) {
  SimulationSetup setup = base;
  setup.threads = threads;
  setup.precision = precision;
  Row row;
  row.model = model_label(setup);
  row.elements = element_count(setup);
  row.variant = "cpu";
  row.backend = "cpu";
  row.precision = precision_name(precision);
  row.integrator = to_string(setup.integrator);
  row.graphs = "-";
  row.threads = threads;
  row.vertices = setup.rest_positions.size();
  row.springs = setup.springs.size();
  DiagnosticList diagnostics;
  const auto simulation = sim::Simulation::create(setup, diagnostics);
  if (!simulation ||
      !time_steps([&](std::size_t n) { return simulation->advance(n, diagnostics); }, 1, options.min_seconds, row)) {
    row.status = failure_text(diagnostics);
  }
  return row;
}

// How the GPU rows launch their steps: one launch per kernel, CUDA graphs, or the persistent cooperative launch
// (GpuOptions::persistent; only where the mesh qualifies, else the row says graphs).
enum class Launch { Kernels, Graphs, Persistent };

const char* launch_name(Launch launch) {
  return launch == Launch::Kernels ? "no" : launch == Launch::Graphs ? "yes" : "persistent";
}

gpu::GpuOptions gpu_options_for(Launch launch) {
  gpu::GpuOptions options;
  options.use_graphs = launch != Launch::Kernels;
  options.persistent = launch == Launch::Persistent;
  return options;
}

// lanes: GpuOptions::persistent_rows (vertices per block) or gather_lanes (0: automatic); check_every: advance's
// NaN/Inf check interval (0: at the end of each timed chunk only, to separate the checks' cost from the steps').
Row gpu_row(const SimulationSetup& base, Precision precision, Integrator integrator, Launch launch,
            const Options& options, int lanes = 0, std::size_t check_every = kCheckEvery, int element_blocks = 0,
            bool sliced_springs = true, int slice_window = 0, bool compact_element_views = true) {
  SimulationSetup setup = base;
  setup.precision = precision;
  setup.integrator = integrator;
  // Forward Euler is refused without mass damping (the sideways vibrations of prestressed springs are otherwise
  // undamped, docs/simulator.md): its rows run with alpha = 20 /s, which changes no kernel's work.
  if (integrator == Integrator::ForwardEuler) setup.mass_damping = 20.0;
  Row row;
  row.model = model_label(setup);
  row.elements = element_count(setup);
  row.variant = "cuda";
  row.backend = "cuda";
  row.precision = precision_name(precision);
  row.integrator = to_string(integrator);
  row.vertices = setup.rest_positions.size();
  row.springs = setup.springs.size();
  DiagnosticList diagnostics;
  gpu::GpuOptions gpu_options = gpu_options_for(launch);
  (launch == Launch::Persistent ? gpu_options.persistent_rows : gpu_options.gather_lanes) = lanes;
  gpu_options.element_blocks_per_sm = element_blocks;
  gpu_options.sliced_springs = sliced_springs;
  gpu_options.slice_window = slice_window;
  gpu_options.compact_element_views = compact_element_views;
  const auto simulation = gpu_simulation(setup, diagnostics, gpu_options);
  row.graphs = launch_name(
      simulation && launch == Launch::Persistent && !simulation->launches().persistent ? Launch::Graphs : launch);
  if (simulation && simulation->launches().clusters) row.graphs += " in clusters";
  if (lanes > 0) row.graphs += (launch == Launch::Persistent ? " rows " : " lanes ") + std::to_string(lanes);
  if (element_blocks > 0) row.graphs += " element pass " + std::to_string(element_blocks) + " blocks/SM";
  if (!sliced_springs) row.graphs += " springs in CSR order";
  if (slice_window > 0) row.graphs += " slice window " + std::to_string(slice_window);
  if (!compact_element_views) row.graphs += " element arrays per element";
  if (check_every != kCheckEvery)
    row.graphs += check_every == 0 ? " checks per chunk" : " checks every " + std::to_string(check_every);
  if (!simulation || !time_steps([&](std::size_t n) { return simulation->advance(n, diagnostics, check_every); }, 64,
                                 options.min_seconds, row)) {
    row.status = failure_text(diagnostics);
  }
  return row;
}

// `count` small scenes (different stiffness, hence different steps) in one batch, against the same scenes as
// separate simulations advanced one after another.
std::vector<Row> batch_rows(int cells, std::size_t count, Precision precision, const Options& options) {
  std::vector<SimulationSetup> scenes;
  for (std::size_t s = 0; s < count; ++s) {
    scenes.push_back(
        benchmark_box(cells, precision, Integrator::SemiImplicitEuler, 4000.0 + 10.0 * static_cast<double>(s)));
  }
  std::size_t vertices = 0, springs = 0;
  for (const auto& scene : scenes) {
    vertices += scene.rest_positions.size();
    springs += scene.springs.size();
  }
  std::vector<Row> rows;
  for (const bool batched : {true, false}) {
    Row row;
    row.variant = batched ? "cuda-batch" : "cuda-one-by-one";
    row.backend = "cuda";
    row.precision = precision_name(precision);
    row.integrator = to_string(Integrator::SemiImplicitEuler);
    row.graphs = "yes";
    row.scenes = count;
    row.vertices = vertices;
    row.springs = springs;
    DiagnosticList diagnostics;
    if (batched) {
      const auto batch = gpu_batch(scenes, gpu_options_for(Launch::Graphs), diagnostics);
      if (!batch ||
          !time_steps([&](std::size_t n) { return batch->advance(n, diagnostics); }, 64, options.min_seconds, row)) {
        row.status = failure_text(diagnostics);
      }
    } else {
      std::vector<std::unique_ptr<Simulation>> singles;
      for (const auto& scene : scenes) {
        singles.push_back(gpu_simulation(scene, diagnostics, gpu_options_for(Launch::Graphs)));
        if (!singles.back()) break;
      }
      const auto advance_all = [&](std::size_t n) {
        for (auto& single : singles) {
          if (!single || !single->advance(n, diagnostics)) return false;
        }
        return true;
      };
      if (!time_steps(advance_all, 64, options.min_seconds, row)) row.status = failure_text(diagnostics);
    }
    rows.push_back(row);
  }
  return rows;
}

// The demo's block (rulesets/scenes/liver_indentation.yaml: 4 x 4 x 2 cm, 8 x 8 x 4 cells, base fixed, damping ratio
// 0.9, float) for `count` patients with Young's modulus spread over 5 to 40 kPa, each pressed 4 mm over 1 s by its
// own displacement probe on the top face's centre vertex and its 4 neighbours, all at the smallest automatic step:
// what `fmpc simulate SCENE --patients FILE` runs in one launch (issue 13: 5e10 spring-steps/s at 1,000 patients).
std::vector<Row> cohort_rows(std::size_t count, const Options& options) {
  std::vector<SimulationSetup> patients;
  BoxSpec box;
  box.cells_x = box.cells_y = 8;
  box.cells_z = 4;
  box.size = {0.04, 0.04, 0.02};
  DiagnosticList diagnostics;
  const Mesh mesh = generate_box(box, diagnostics);
  double smallest = 1.0;
  for (std::size_t p = 0; p < count; ++p) {
    SpringModelSpec model;
    model.stiffness.mapping = StiffnessMapping::VanGelder1998;
    model.stiffness.value =
        5000.0 + 35000.0 * static_cast<double>(p) / static_cast<double>(std::max<std::size_t>(count - 1, 1));
    model.mass.value = 1060.0;
    model.damping.ratio = 0.9;
    auto setup = build_spring_model(mesh, model, diagnostics);
    if (!setup) break;
    ProbeLoad probe;
    for (std::size_t v = 0; v < setup->rest_positions.size(); ++v) {
      const Point3& x = setup->rest_positions[v];
      if (x[2] < 1e-9) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
      if (x[2] > 0.02 - 1e-9 && std::abs(x[0] - 0.02) + std::abs(x[1] - 0.02) < 0.0051)
        probe.vertices.push_back(static_cast<std::int32_t>(v));
    }
    probe.target = {0.0, 0.0, -0.004};
    probe.ramp_time = 1.0;
    setup->probe = probe;
    setup->precision = Precision::Float;
    const auto report = check_stability(*setup, diagnostics);
    if (!report) break;
    smallest = std::min(smallest, report->time_step);
    patients.push_back(std::move(*setup));
  }
  Row row;
  row.variant = "cuda-cohort";
  row.backend = "cuda";
  row.precision = "float";
  row.integrator = to_string(Integrator::SemiImplicitEuler);
  row.graphs = "yes";
  row.scenes = count;
  for (SimulationSetup& patient : patients) {
    patient.time_step = smallest;
    row.vertices += patient.rest_positions.size();
    row.springs += patient.springs.size();
  }
  if (patients.size() != count) {
    row.status = failure_text(diagnostics);
    return {row};
  }
  std::vector<Row> rows;
  // The per-step gather's threads per vertex (0: the automatic choice) on the cohort's many short CSR rows.
  // Lanes -1: one thread per vertex reading the springs in CSR order instead of the sliced layout.
  const std::pair<Launch, int> variants[] = {{Launch::Graphs, 0}, {Launch::Graphs, -1}, {Launch::Graphs, 2},
                                             {Launch::Graphs, 4}, {Launch::Graphs, 8},  {Launch::Persistent, 0}};
  for (const auto& [launch, lanes] : variants) {
    gpu::GpuOptions gpu_options = gpu_options_for(launch);
    gpu_options.gather_lanes = lanes < 0 ? 1 : lanes;
    gpu_options.sliced_springs = lanes >= 0;
    const auto batch = gpu_batch(patients, gpu_options, diagnostics);
    if (launch == Launch::Persistent && batch && !batch->launches().persistent) continue;  // too large for one grid
    Row timed = row;
    timed.graphs = launch_name(launch);
    if (batch && batch->launches().clusters) timed.graphs += " in clusters";
    if (lanes > 0) timed.graphs += " lanes " + std::to_string(lanes);
    if (lanes < 0) timed.graphs += " lanes 1, springs in CSR order";
    if (!batch ||
        !time_steps([&](std::size_t n) { return batch->advance(n, diagnostics); }, 64, options.min_seconds, timed)) {
      timed.status = failure_text(diagnostics);
    }
    rows.push_back(timed);
  }
  return rows;
}

std::string format(double value, int precision) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", precision, value);
  return text;
}

std::string scientific(double value) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.3g", value);
  return text;
}

void write_csv(const std::vector<Row>& rows, std::ostream& out) {
  out << "model,variant,backend,precision,integrator,graphs,threads,scenes,vertices,springs,tetrahedra,steps,seconds,"
         "us_per_step,spring_steps_per_s,tetrahedron_steps_per_s,status,solver\n";
  for (const Row& r : rows) {
    out << r.model << ',' << r.variant << ',' << r.backend << ',' << r.precision << ',' << r.integrator << ','
        << r.graphs << ',' << r.threads << ',' << r.scenes << ',' << r.vertices << ',' << r.springs << ',' << r.elements
        << ',' << r.steps << ',' << format(r.seconds, 6) << ',' << format(r.microseconds_per_step(), 3) << ','
        << scientific(r.spring_steps_per_second()) << ',' << scientific(r.element_steps_per_second()) << ",\""
        << r.status << "\",\"" << r.solver << "\"\n";
  }
}

void print_table(const std::vector<Row>& rows, std::ostream& out) {
  out << "| model | variant | precision | integrator | graphs | threads | scenes | springs | tetrahedra | us/step | "
         "spring-steps/s | tet-steps/s | solver |\n";
  out << "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const Row& r : rows) {
    out << "| " << r.model << " | " << r.variant << " | " << r.precision << " | " << r.integrator << " | " << r.graphs
        << " | " << r.threads << " | " << r.scenes << " | " << r.springs << " | " << r.elements << " | "
        << (r.status == "ok" ? format(r.microseconds_per_step(), 2) : r.status) << " | "
        << (r.status == "ok" && r.springs > 0 ? scientific(r.spring_steps_per_second()) : "-") << " | "
        << (r.status == "ok" && r.elements > 0 ? scientific(r.element_steps_per_second()) : "-") << " | " << r.solver
        << " |\n";
  }
}

// SOFA's liver FEM scene as rulesets/scenes/sofa_liver_fem.yaml sets it (E 3 kPa, nu 0.3, density 1, Rayleigh 0.1
// mass and 0.1 stiffness, nodes 3 39 64 fixed, gravity -9.81 along y, dt 0.02, double), with SOFA's CG cap of 25
// iterations; nullopt (the error printed) where the mesh cannot be read.
std::optional<SimulationSetup> sofa_liver_fem(const std::string& path) {
  DiagnosticList diagnostics;
  const std::optional<Mesh> mesh = read_mesh_file(path, diagnostics);
  std::optional<SimulationSetup> setup;
  if (mesh) {
    FemModelSpec spec;
    spec.youngs_modulus = {3000.0};
    spec.poisson_ratio = {0.3};
    spec.mass.value = 1.0;
    spec.rayleigh_stiffness = 0.1;
    setup = build_fem_model(*mesh, spec, diagnostics);
  }
  if (!setup) {
    std::cerr << path << ": " << failure_text(diagnostics) << "\n";
    return std::nullopt;
  }
  setup->mass_damping = 0.1;
  setup->fixed_vertices = {3, 39, 64};
  setup->gravity = {0.0, -9.81, 0.0};
  setup->time_step = 0.02;
  setup->integrator = Integrator::ImplicitEuler;
  setup->precision = Precision::Double;
  setup->implicit.max_iterations = 25;
  return setup;
}

// The timed steps' solver report: the most and mean iterations, the largest relative residual reached and the
// steps stopped at the cap.
std::string solver_text(const ImplicitSolverReport& report, std::size_t steps_before) {
  if (report.steps == 0) return "-";
  std::ostringstream text;
  text << to_string(report.method) << " tol " << scientific(report.tolerance) << " cap " << report.max_iterations
       << ": iterations " << report.iterations_min << "-" << report.iterations_max << " (mean "
       << format(static_cast<double>(report.iterations_total) / static_cast<double>(report.steps), 1)
       << "), residual max " << scientific(report.residual_max) << ", capped " << report.capped_steps << " of "
       << report.steps << " steps (" << steps_before << " untimed first)";
  return text.str();
}

// How CUDA launches an implicit row's conjugate gradient: the plan's choice (one block where the solve fits its
// shared memory, else the cooperative grid where that fits), the cooperative grid, the per-iteration launches (fused
// stages where the mesh allows), or a launch per kernel (the fused stages off).
enum class CgLaunchRow { Planned, Grid, PerIteration, Separate };

// One implicit Euler row: on the CPU with `threads` workers (cuda false), or on CUDA with `launch`.
Row implicit_row(const SimulationSetup& base, const std::string& model, bool cuda, CgLaunchRow launch, unsigned threads,
                 const Options& options) {
  SimulationSetup setup = base;
  setup.threads = threads;
  Row row;
  row.model = model;
  row.elements = element_count(setup);
  row.variant = cuda ? "cuda" : "cpu";
  row.backend = cuda ? "cuda" : "cpu";
  row.precision = precision_name(setup.precision);
  row.integrator = to_string(setup.integrator);
  row.graphs = !cuda                                ? "-"
               : launch == CgLaunchRow::Planned ? "cg one block or cooperative (planned)"
               : launch == CgLaunchRow::Grid         ? "cg cooperative where it fits"
               : launch == CgLaunchRow::PerIteration ? "cg per iteration"
                                                     : "cg per iteration, a launch per kernel";
  row.threads = cuda ? 1 : threads;
  row.vertices = setup.rest_positions.size();
  row.springs = setup.springs.size();
  DiagnosticList diagnostics;
  SimulationOptions simulation_options;
  if (cuda) {
    simulation_options.backend = Backend::Cuda;
    simulation_options.gpu.persistent = launch == CgLaunchRow::Planned || launch == CgLaunchRow::Grid;
    simulation_options.gpu.cg_single_block = launch == CgLaunchRow::Planned;
    simulation_options.gpu.cg_fused_stages = launch != CgLaunchRow::Separate;
  }
  const std::unique_ptr<Simulation> simulation = Simulation::create(setup, diagnostics, simulation_options);
  constexpr std::size_t kFirst = 8;
  if (!simulation || !time_steps([&](std::size_t n) { return simulation->advance(n, diagnostics); }, kFirst,
                                 options.min_seconds, row)) {
    row.status = failure_text(diagnostics);
    return row;
  }
  row.solver = solver_text(simulation->implicit_solver(), kFirst);
  return row;
}

// Issue 27 item 3's rows (see the header): SOFA's liver (when --liver names its mesh) and the 20^3 FEM box.
std::vector<Row> implicit_rows(const Options& options, bool have_device, unsigned threads) {
  std::vector<std::pair<std::string, SimulationSetup>> scenes;
  if (!options.liver.empty()) {
    if (std::optional<SimulationSetup> liver = sofa_liver_fem(options.liver)) {
      scenes.emplace_back("SOFA liver FEM (cap 25)", std::move(*liver));
    } else {
      Row row;
      row.model = "SOFA liver FEM (cap 25)";
      row.variant = "setup";
      row.status = "failed: " + options.liver + " not read";
      return {row};
    }
  }
  SimulationSetup box = benchmark_element_box(20, false, default_fem_law().law, default_element_kind().kind);
  box.integrator = Integrator::ImplicitEuler;
  box.precision = Precision::Double;
  box.time_step = 0.001;
  scenes.emplace_back("FEM box 20^3 (dt 1 ms)", std::move(box));
  std::vector<Row> rows;
  for (const auto& [name, setup] : scenes) {
    std::cout << "implicit Euler, " << name << ": " << setup.rest_positions.size() << " vertices, "
              << setup.tetrahedra.size() << " tetrahedra\n"
              << std::flush;
    const bool small = setup.rest_positions.size() < 1000;
    if (small) {
      // SOFA's settings on one core: the CG capped at 25 iterations, and the automatic choice (the direct solver).
      SimulationSetup cg = setup;
      cg.implicit.method = ImplicitMethod::ConjugateGradient;
      rows.push_back(implicit_row(cg, name, false, CgLaunchRow::Planned, 1, options));
      rows.push_back(implicit_row(setup, name, false, CgLaunchRow::Planned, 1, options));
    } else {
      rows.push_back(implicit_row(setup, name, false, CgLaunchRow::Planned, threads, options));
    }
    if (!have_device) continue;
    for (const CgLaunchRow launch :
         {CgLaunchRow::Planned, CgLaunchRow::Grid, CgLaunchRow::PerIteration, CgLaunchRow::Separate})
      rows.push_back(implicit_row(setup, name, true, launch, 1, options));
  }
  return rows;
}

bool parse(int argc, char** argv, Options& options) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quick") {
      options.quick = true;
    } else if (arg == "--out" && i + 1 < argc) {
      options.out_dir = argv[++i];
    } else if (arg == "--threads" && i + 1 < argc) {
      options.threads = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else if (arg == "--min-seconds" && i + 1 < argc) {
      options.min_seconds = std::strtod(argv[++i], nullptr);
    } else if (arg == "--cohort" && i + 1 < argc) {
      options.cohort = static_cast<std::size_t>(std::strtoul(argv[++i], nullptr, 10));
      options.cohort_given = true;
    } else if (arg == "--fem-only") {
      options.fem_only = true;
    } else if (arg == "--fem-cells" && i + 1 < argc) {
      options.fem_cells = static_cast<int>(std::strtol(argv[++i], nullptr, 10));
    } else if (arg == "--cohort-only") {
      options.cohort_only = true;
    } else if (arg == "--spring-cells" && i + 1 < argc) {
      options.spring_cells = static_cast<int>(std::strtol(argv[++i], nullptr, 10));
    } else if (arg == "--liver" && i + 1 < argc) {
      options.liver = argv[++i];
    } else if (arg == "--implicit-only") {
      options.implicit_only = true;
    } else if (arg == "--fem-law" && i + 1 < argc) {
      options.fem_law = argv[++i];
    } else if (arg == "--fem-element" && i + 1 < argc) {
      options.fem_element = argv[++i];
    } else {
      std::cerr
          << "usage: fmpc_sim_bench [--out DIR] [--quick] [--threads N] [--min-seconds S] [--fem-cells N] [--fem-only] "
             "[--cohort PATIENTS] [--cohort-only] [--spring-cells N] [--liver PATH] [--implicit-only] [--fem-law LAW] "
             "[--fem-element ELEMENT]\n";
      return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!parse(argc, argv, options)) return 2;
  if (options.quick) options.min_seconds = std::min(options.min_seconds, 0.1);
  const unsigned threads = options.threads != 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  std::string device;
  const bool have_device = gpu::cuda_device_available(device);
  std::cout << "CPU threads: " << threads << "; CUDA: " << (have_device ? device : "skipped (" + device + ")") << "\n";

  // cells^3 boxes, 3n(n+1)^2 + 3n^2(n+1) + n^3 springs: 5 -> 1,115, 11 -> 10,439, 20 -> 59,660 (9,261 vertices, the
  // issue 13 small mesh), 24 -> 102,024, 52 -> 1,008,748.
  std::vector<int> sizes = options.quick ? std::vector<int>{5, 11, 20} : std::vector<int>{5, 11, 20, 24, 52};
  // Parts measured alone: the FEM boxes, the large springs box, the cohort.
  const bool part_alone = options.fem_only || options.spring_cells > 0 || options.cohort_only || options.implicit_only;
  if (part_alone) sizes.clear();
  std::vector<Row> rows;
  // Issue 13's large springs box on the GPU alone (--spring-cells; 240 is the end-to-end scene's): the per-step
  // kernel with one thread per vertex, its springs in the sliced layout (default window 1,024; 32 and 256) and in CSR
  // order.
  if (options.spring_cells > 0 && have_device) {
    const auto start = std::chrono::steady_clock::now();
    const SimulationSetup base = benchmark_box(options.spring_cells, Precision::Float, Integrator::SemiImplicitEuler);
    std::cout << "springs box " << options.spring_cells << "^3: " << base.rest_positions.size() << " vertices, "
              << base.springs.size() << " springs, set up in "
              << format(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2) << " s\n"
              << std::flush;
    rows.push_back(gpu_row(base, Precision::Float, Integrator::SemiImplicitEuler, Launch::Graphs, options));
    for (const int window : {32, 256})
      rows.push_back(gpu_row(base, Precision::Float, Integrator::SemiImplicitEuler, Launch::Graphs, options, 1,
                             kCheckEvery, 0, true, window));
    rows.push_back(gpu_row(base, Precision::Float, Integrator::SemiImplicitEuler, Launch::Graphs, options, 1,
                           kCheckEvery, 0, false));
  }
  for (const int cells : sizes) {
    const SimulationSetup base = benchmark_box(cells, Precision::Double, Integrator::SemiImplicitEuler);
    std::cout << "box " << cells << "^3: " << base.rest_positions.size() << " vertices, " << base.springs.size()
              << " springs\n"
              << std::flush;
    rows.push_back(cpu_row(base, 1, Precision::Double, options));
    if (threads > 1) {
      rows.push_back(cpu_row(base, threads, Precision::Double, options));
      rows.push_back(cpu_row(base, threads, Precision::Float, options));
    }
    if (!have_device) continue;
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const Launch launch : {Launch::Kernels, Launch::Graphs, Launch::Persistent})
        rows.push_back(gpu_row(base, precision, Integrator::SemiImplicitEuler, launch, options));
      // The small mesh of issue 13 (300,000 steps/s): vertices per block, and the checks' share.
      if (cells == 20 && precision == Precision::Float) {
        for (const int block_rows : {12, 48, 96, 256})
          rows.push_back(
              gpu_row(base, precision, Integrator::SemiImplicitEuler, Launch::Persistent, options, block_rows));
        rows.push_back(gpu_row(base, precision, Integrator::SemiImplicitEuler, Launch::Persistent, options, 0, 0));
        rows.push_back(gpu_row(base, precision, Integrator::SemiImplicitEuler, Launch::Graphs, options, 0, 0));
      }
      // The per-step gather's threads per vertex (default 4) where the mesh is large enough to be bandwidth-bound.
      if (cells >= 20 && precision == Precision::Float) {
        for (const int lanes : {1, 2, 8})
          rows.push_back(gpu_row(base, precision, Integrator::SemiImplicitEuler, Launch::Graphs, options, lanes));
        // One thread per vertex reading the springs in CSR order, against the sliced layout (the lanes 1 row).
        rows.push_back(
            gpu_row(base, precision, Integrator::SemiImplicitEuler, Launch::Graphs, options, 1, kCheckEvery, 0, false));
      }
      for (const Integrator integrator :
           {Integrator::ForwardEuler, Integrator::VelocityVerlet, Integrator::RungeKutta4}) {
        rows.push_back(gpu_row(base, precision, integrator, Launch::Graphs, options));
      }
    }
  }
  if (have_device && !part_alone) {
    const std::size_t scenes = options.quick ? 16 : 256;
    std::cout << "batch: " << scenes << " boxes of 5^3 cells\n" << std::flush;
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (Row& row : batch_rows(5, scenes, precision, options)) rows.push_back(row);
    }
  }

  if (have_device && (!part_alone || options.cohort_only || (options.spring_cells > 0 && options.cohort_given))) {
    const std::size_t patients = options.quick && !options.cohort_given ? 64 : options.cohort;
    std::cout << "cohort: " << patients << " patients of the demo scene, each with its own probe\n" << std::flush;
    for (Row& row : cohort_rows(patients, options)) rows.push_back(row);
  }

  // The force models with an element pass. CPU rows up to 52^3 cells (843,648 tetrahedra); the largest box on the
  // GPU only, semi-implicit Euler in float and double (issue 10: 10 G tetrahedron-steps/s at 10M tetrahedra).
  // --fem-law / --fem-element: the FEM rows of that law on that element kind (springs beside the law are left out).
  const ElementLawRow* law_row = options.fem_law.empty() ? &default_fem_law() : fem_law_by_keyword(options.fem_law);
  const ElementKindRow* kind_row =
      options.fem_element.empty() ? &default_element_kind() : element_kind_by_keyword(options.fem_element);
  if (!law_row || !kind_row) {
    std::cerr << "fmpc_sim_bench: unknown " << (law_row ? "--fem-element " + options.fem_element : "--fem-law " + options.fem_law)
              << "\n";
    return 2;
  }
  const int law = law_row->law, element = kind_row->kind;
  const bool default_model = law == default_fem_law().law && element == default_element_kind().kind;
  std::vector<int> fem_sizes = options.quick ? std::vector<int>{5, 11} : std::vector<int>{11, 24, 52};
  if (!options.quick && have_device && options.fem_cells > 52) fem_sizes.push_back(options.fem_cells);
  if (options.spring_cells > 0 || options.cohort_only || options.implicit_only) fem_sizes.clear();
  if (options.fem_only && options.fem_cells > 52) fem_sizes = {options.fem_cells};
  for (const int cells : fem_sizes) {
    for (const bool with_springs : {false, true}) {
      const bool largest = cells > 52;
      if ((largest || !default_model) && with_springs) continue;
      const auto start = std::chrono::steady_clock::now();
      const SimulationSetup base = benchmark_element_box(cells, with_springs, law, element);
      const double setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::cout << model_label(base) << " box " << cells << "^3: " << base.rest_positions.size() << " vertices, "
                << base.tetrahedra.size() << " tetrahedra, set up in " << format(setup_seconds, 2) << " s\n"
                << std::flush;
      if (base.rest_positions.empty()) {
        Row row;
        row.model = model_label(base);
        row.variant = "setup";
        row.status = "failed: the model was not built";
        rows.push_back(row);
        continue;
      }
      if (!largest) {
        rows.push_back(cpu_row(base, 1, Precision::Double, options));
        if (threads > 1) rows.push_back(cpu_row(base, threads, Precision::Float, options));
      }
      if (!have_device) continue;
      if (const char* refusal = cuda_refusal(element_kind_limits(element), false)) {
        std::cout << "GPU rows skipped: fem.element " << kind_row->keyword << " " << refusal << "\n";
        continue;
      }
      for (const Precision precision : {Precision::Float, Precision::Double})
        rows.push_back(gpu_row(base, precision, Integrator::SemiImplicitEuler, Launch::Graphs, options));
      // The element pass's register bound, 2 and 3 blocks per SM, against the element kind's default (the row above).
      if (largest || cells >= 52)
        for (const int element_blocks : {2, 3})
          rows.push_back(gpu_row(base, Precision::Float, Integrator::SemiImplicitEuler, Launch::Graphs, options, 0,
                                 kCheckEvery, element_blocks));
      // The element pass on per-element arrays and int slots (GpuOptions::compact_element_views off): the bytes the
      // compact views save, in the same process (docs/performance.md, "Bytes per element").
      if (largest)
        rows.push_back(gpu_row(base, Precision::Float, Integrator::SemiImplicitEuler, Launch::Graphs, options, 0,
                               kCheckEvery, 0, true, 0, false));
      if (!largest && cells <= 24)
        rows.push_back(gpu_row(base, Precision::Float, Integrator::SemiImplicitEuler, Launch::Persistent, options));
      if (!largest && cells == 24) {
        if (const char* refusal = cuda_refusal(element_kind_limits(element), true)) {
          std::cout << "GPU implicit row skipped: fem.element " << kind_row->keyword << " " << refusal << "\n";
        } else {
          rows.push_back(gpu_row(base, Precision::Float, Integrator::ImplicitEuler, Launch::Graphs, options));
        }
      }
    }
  }

  if (!part_alone || options.implicit_only)
    for (Row& row : implicit_rows(options, have_device, threads)) rows.push_back(row);

  // The table first: a results folder that cannot be written loses nothing of a long run.
  print_table(rows, std::cout);
  if (!options.out_dir.empty()) {
    std::error_code ignored;
    std::filesystem::create_directories(options.out_dir, ignored);
    std::ofstream csv(options.out_dir + "/sim_bench.csv");
    write_csv(rows, csv);
    std::ofstream table(options.out_dir + "/sim_bench.md");
    table << "CPU threads: " << threads << "; CUDA: " << (have_device ? device : "none") << "\n\n";
    print_table(rows, table);
    if (!csv || !table) {
      std::cerr << "cannot write the results under " << options.out_dir << "\n";
      return 1;
    }
  }
  bool all_ok = true;
  for (const Row& r : rows) all_ok = all_ok && r.status == "ok";
  return all_ok ? 0 : 1;
}
