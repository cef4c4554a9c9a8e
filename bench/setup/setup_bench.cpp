// Host setup benchmark: seconds per phase and peak memory per spring for generated boxes of n^3 cells, from the
// mesh to a ready SimulationSetup, as `fmpc simulate` builds it (generate_box, repair_mesh, build_spring_model).
//
//   fmpc_setup_bench [--cells N[,N...]] [--threads T] [--breakdown] [--simulator] [--out DIR]
//
// --cells      box sizes (default 20,40,60,100); a box of n^3 cells has (n+1)^3 vertices, 6 n^3 tetrahedra and
//              about 7 n^3 springs (n = 240: 96.8 million)
// --threads    worker threads (default 0: every hardware thread); the checksum must not change with it
// --breakdown  after the timed build, time build_spring_model's steps one by one (degenerate check, masses,
//              springs with their CSR, rest lengths, stiffness, damping) on the same mesh
// --simulator  then create the simulators from the setup (sim::Simulation on the CPU and, with CUDA, on it) and report the
//              peak they reach: their own copies of the setup and its upload
// --out DIR    also write DIR/setup_bench.csv and DIR/setup_bench.md
//
// Each size runs in a forked child, so that one size's allocations do not raise the next one's peak. Memory is
// the process's resident set (/proc/self/status VmRSS and VmHWM, peak reset through /proc/self/clear_refs) minus
// what the child held when it started; "held" is the resident set once the mesh and the setup are built, "data" the
// capacity of their arrays.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "runtime/integrate/simulation.h"
#include "bench/setup/process_clock.h"
#include "runtime/integrate/worker_pool.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_check.h"
#include "runtime/scene/spring_model_builder.h"
#if FMPC_RUNTIME_HAVE_CUDA
#include "runtime/gpu/gpu_simulation.h"
#endif

using namespace fmpc;
using namespace fmpc::sim;
using fmpc::bench::cpu_seconds;
using fmpc::bench::seconds_since;

namespace {

struct Options {
  std::vector<int> cells{20, 40, 60, 100};
  unsigned threads = 0;
  bool breakdown = false;
  bool simulator = false;
  std::string out_dir;
};

// One size's results, passed from the child to the parent as one line of text.
struct Row {
  int cells = 0;
  unsigned threads = 0;
  std::size_t vertices = 0, tetrahedra = 0, springs = 0;
  double generate = 0, repair = 0, model = 0, cpu = 0;
  double peak_bytes = 0, held_bytes = 0, data_bytes = 0;
  double cpu_simulation_peak = -1, gpu_simulation_peak = -1;
  // breakdown (seconds; -1: not measured)
  double degenerate = -1, masses = -1, network = -1, rest_lengths = -1, stiffness = -1, damping = -1;
  std::uint64_t checksum = 0;
  std::string status = "ok";
};

// VmRSS or VmHWM of this process, bytes.
double status_bytes(const char* field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::size_t length = std::strlen(field);
  while (std::getline(status, line)) {
    if (line.compare(0, length, field) == 0 && line.size() > length && line[length] == ':')
      return 1024.0 * std::strtod(line.c_str() + length + 1, nullptr);
  }
  return 0.0;
}

void reset_peak() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";  // resets VmHWM to the current VmRSS (Linux 4.0+)
}

// FNV-1a over the arrays, eight bytes at a time: equal setups give equal sums, so runs on different thread counts
// can be compared from their output alone.
struct Checksum {
  std::uint64_t value = 1469598103934665603ull;
  template <class T>
  void add(const std::vector<T>& values) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(values.data());
    const std::size_t size = values.size() * sizeof(T);
    std::size_t i = 0;
    for (; i + 8 <= size; i += 8) {
      std::uint64_t word = 0;
      std::memcpy(&word, bytes + i, 8);
      value = (value ^ word) * 1099511628211ull;
    }
    for (; i < size; ++i) value = (value ^ bytes[i]) * 1099511628211ull;
  }
};

template <class T>
double bytes_of(const std::vector<T>& values) {
  return static_cast<double>(values.capacity() * sizeof(T));
}

// What the arrays of the mesh and the setup occupy (their capacities): the floor under the resident set.
double data_bytes_of(const Mesh& mesh, const SimulationSetup& setup) {
  const SpringNetwork& n = setup.springs;
  return bytes_of(mesh.points) + bytes_of(mesh.tetrahedra) + bytes_of(mesh.triangles) + bytes_of(mesh.tetrahedron_lines) +
         bytes_of(mesh.triangle_lines) + bytes_of(setup.rest_positions) + bytes_of(setup.mass) + bytes_of(n.first) +
         bytes_of(n.second) + bytes_of(n.kind) + bytes_of(n.element_measure) + bytes_of(n.rest_length) +
         bytes_of(n.stiffness) + bytes_of(n.damping) + bytes_of(n.adjacency_offset) + bytes_of(n.adjacency_spring);
}

std::uint64_t checksum_of(const Mesh& mesh, const SimulationSetup& setup) {
  Checksum sum;
  sum.add(mesh.points);
  sum.add(mesh.tetrahedra);
  sum.add(setup.rest_positions);
  sum.add(setup.mass);
  const SpringNetwork& n = setup.springs;
  sum.add(n.first);
  sum.add(n.second);
  sum.add(n.kind);
  sum.add(n.rest_length);
  sum.add(n.stiffness);
  sum.add(n.damping);
  sum.add(n.adjacency_offset);
  sum.add(n.adjacency_spring);
  return sum.value;
}

SpringModelSpec benchmark_model(unsigned threads) {
  // bench/sim's soft-tissue box: Van Gelder stiffness from E = 5 kPa, 1060 kg/m^3, damping ratio 0.9.
  SpringModelSpec model;
  model.stiffness.mapping = StiffnessMapping::VanGelder1998;
  model.stiffness.value = 5000.0;
  model.mass.value = 1060.0;
  model.threads = threads;
  return model;
}

Row run_size(int cells, const Options& options) {
  Row row;
  row.cells = cells;
  row.threads = options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  const double baseline = status_bytes("VmRSS");
  reset_peak();
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = box.cells_y = box.cells_z = cells;
  box.size = {0.1, 0.1, 0.1};
  const double cpu_start = cpu_seconds();
  auto start = std::chrono::steady_clock::now();
  Mesh mesh = generate_box(box, diagnostics);
  row.generate = seconds_since(start);
  MeshCheckOptions check;
  check.threads = options.threads;
  start = std::chrono::steady_clock::now();
  const MeshRepairResult repair = repair_mesh(mesh, check);
  row.repair = seconds_since(start);
  if (!repair.findings.empty()) row.status = "the generated box has findings";
  const SpringModelSpec model = benchmark_model(options.threads);
  start = std::chrono::steady_clock::now();
  auto setup = build_spring_model(mesh, model, diagnostics);
  row.model = seconds_since(start);
  row.cpu = cpu_seconds() - cpu_start;
  if (!setup) {
    row.status = "failed: " + (diagnostics.items().empty() ? std::string("?") : diagnostics.items().front().message);
    return row;
  }
  row.vertices = mesh.points.size();
  row.tetrahedra = mesh.tetrahedra.size();
  row.springs = setup->springs.size();
  row.peak_bytes = status_bytes("VmHWM") - baseline;
  row.held_bytes = status_bytes("VmRSS") - baseline;
  row.data_bytes = data_bytes_of(mesh, *setup);
  row.checksum = checksum_of(mesh, *setup);

  if (options.breakdown) {
    WorkerPool pool(resolve_thread_count(options.threads, mesh.points.size() + mesh.tetrahedra.size()));
    DiagnosticList steps;
    start = std::chrono::steady_clock::now();
    const std::vector<MeshFinding> degenerate = degenerate_elements(mesh, {}, &pool);
    row.degenerate = seconds_since(start);
    std::vector<Point3> metres = mesh.points;  // length unit 1
    start = std::chrono::steady_clock::now();
    const std::vector<double> mass = lumped_masses(mesh, metres, model.mass, steps, &pool);
    row.masses = seconds_since(start);
    start = std::chrono::steady_clock::now();
    SpringNetwork network = springs_from_tetrahedra(mesh, metres, steps, &pool);
    row.network = seconds_since(start);
    start = std::chrono::steady_clock::now();
    compute_rest_lengths(network, metres, steps, 1e-9, &pool);
    row.rest_lengths = seconds_since(start);
    start = std::chrono::steady_clock::now();
    assign_stiffness(network, model.stiffness, steps, &pool, ElementMeasures::Release);  // as the builder
    row.stiffness = seconds_since(start);
    start = std::chrono::steady_clock::now();
    assign_damping(network, mass, model.damping, steps, &pool);
    row.damping = seconds_since(start);
    if (steps.has_errors() || !degenerate.empty()) row.status = "breakdown failed";
  }

  if (options.simulator) {
    for (std::size_t v = 0; v < setup->rest_positions.size(); ++v)
      if (setup->rest_positions[v][1] > 0.0999) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
    setup->gravity = {0.0, -9.81, 0.0};
    setup->precision = Precision::Float;
    setup->threads = row.threads;
    DiagnosticList simulator_diagnostics;
    {
      reset_peak();
      auto cpu = sim::Simulation::create(*setup, simulator_diagnostics);
      row.cpu_simulation_peak = cpu ? status_bytes("VmHWM") - baseline : -1;
    }
#if FMPC_RUNTIME_HAVE_CUDA
    std::string device;
    if (gpu::cuda_device_available(device)) {
      reset_peak();
      sim::SimulationOptions cuda;
      cuda.backend = sim::Backend::Cuda;
      auto gpu_run = sim::Simulation::create(*setup, simulator_diagnostics, cuda);
      row.gpu_simulation_peak = gpu_run ? status_bytes("VmHWM") - baseline : -1;
    }
#endif
  }
  return row;
}

std::string encode(const Row& r) {
  std::ostringstream out;
  out.precision(17);
  out << r.cells << ' ' << r.threads << ' ' << r.vertices << ' ' << r.tetrahedra << ' ' << r.springs << ' '
      << r.generate << ' ' << r.repair << ' ' << r.model << ' ' << r.cpu << ' ' << r.peak_bytes << ' ' << r.held_bytes << ' '
      << r.data_bytes << ' '
      << r.cpu_simulation_peak << ' ' << r.gpu_simulation_peak << ' ' << r.degenerate << ' ' << r.masses << ' '
      << r.network << ' ' << r.rest_lengths << ' ' << r.stiffness << ' ' << r.damping << ' ' << r.checksum << ' '
      << r.status;
  return out.str();
}

Row decode(const std::string& text) {
  Row r;
  std::istringstream in(text);
  in >> r.cells >> r.threads >> r.vertices >> r.tetrahedra >> r.springs >> r.generate >> r.repair >> r.model >> r.cpu >>
      r.peak_bytes >> r.held_bytes >> r.data_bytes >> r.cpu_simulation_peak >> r.gpu_simulation_peak >> r.degenerate >> r.masses >>
      r.network >> r.rest_lengths >> r.stiffness >> r.damping >> r.checksum;
  std::getline(in, r.status);
  if (!r.status.empty() && r.status[0] == ' ') r.status.erase(0, 1);
  return r;
}

// Runs one size in a child process; its row comes back through a pipe.
Row run_isolated(int cells, const Options& options) {
  int channel[2];
  if (pipe(channel) != 0) return run_size(cells, options);
  const pid_t child = fork();
  if (child == 0) {
    close(channel[0]);
    const std::string line = encode(run_size(cells, options)) + "\n";
    const ssize_t written = write(channel[1], line.data(), line.size());
    _exit(written == static_cast<ssize_t>(line.size()) ? 0 : 1);
  }
  close(channel[1]);
  std::string text;
  char buffer[4096];
  for (ssize_t got; (got = read(channel[0], buffer, sizeof buffer)) > 0;) text.append(buffer, static_cast<std::size_t>(got));
  close(channel[0]);
  int status = 0;
  waitpid(child, &status, 0);
  if (text.empty()) {
    Row failed;
    failed.cells = cells;
    failed.status = WIFSIGNALED(status) ? "killed by signal " + std::to_string(WTERMSIG(status)) + " (out of memory?)"
                                        : "child failed";
    return failed;
  }
  return decode(text);
}

std::string fixed(double value, int digits) {
  if (value < 0) return "-";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

std::string per_spring(double bytes, std::size_t springs) {
  return bytes < 0 || springs == 0 ? "-" : fixed(bytes / static_cast<double>(springs), 1);
}

bool parse_options(int argc, char** argv, Options& options) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (arg == "--cells") {
      options.cells.clear();
      std::istringstream list(value());
      std::string item;
      while (std::getline(list, item, ',')) {
        const int n = std::atoi(item.c_str());
        if (n < 1 || n > 1000) return false;
        options.cells.push_back(n);
      }
      if (options.cells.empty()) return false;
    } else if (arg == "--threads") {
      options.threads = static_cast<unsigned>(std::atoi(value().c_str()));
    } else if (arg == "--breakdown") {
      options.breakdown = true;
    } else if (arg == "--simulator") {
      options.simulator = true;
    } else if (arg == "--out") {
      options.out_dir = value();
    } else {
      return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!parse_options(argc, argv, options)) {
    std::fprintf(stderr,
                 "usage: fmpc_setup_bench [--cells N[,N...]] [--threads T] [--breakdown] [--simulator] [--out DIR]\n");
    return 2;
  }
  std::vector<Row> rows;
  std::string table =
      "| cells | vertices | tetrahedra | springs | threads | generate s | repair s | model s | setup s | setup CPU s "
      "| peak B/spring | held B/spring | data B/spring | CPU simulation peak B/spring | GPU simulation peak B/spring "
      "| checksum | status |\n"
      "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- "
      "| --- |\n";
  std::string breakdown =
      "| cells | springs | degenerate check s | masses s | springs + CSR s | rest lengths s | stiffness s | damping s |\n"
      "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  std::string csv =
      "cells,vertices,tetrahedra,springs,threads,generate_s,repair_s,model_s,setup_s,setup_cpu_s,peak_bytes,held_bytes,"
      "data_bytes,"
      "cpu_simulation_peak_bytes,gpu_simulation_peak_bytes,degenerate_s,masses_s,springs_csr_s,rest_lengths_s,"
      "stiffness_s,damping_s,checksum,status\n";
  std::printf("%s", table.c_str());
  std::fflush(stdout);
  for (const int cells : options.cells) {
    const Row r = run_isolated(cells, options);
    rows.push_back(r);
    char checksum[32];
    std::snprintf(checksum, sizeof checksum, "%016llx", static_cast<unsigned long long>(r.checksum));
    const std::string line = "| " + std::to_string(r.cells) + " | " + std::to_string(r.vertices) + " | " +
                             std::to_string(r.tetrahedra) + " | " + std::to_string(r.springs) + " | " +
                             std::to_string(r.threads) + " | " + fixed(r.generate, 2) + " | " + fixed(r.repair, 2) +
                             " | " + fixed(r.model, 2) + " | " + fixed(r.generate + r.repair + r.model, 2) + " | " +
                             fixed(r.cpu, 2) + " | " +
                             per_spring(r.peak_bytes, r.springs) + " | " + per_spring(r.held_bytes, r.springs) +
                             " | " + per_spring(r.data_bytes, r.springs) + " | " +
                             per_spring(r.cpu_simulation_peak, r.springs) + " | " +
                             per_spring(r.gpu_simulation_peak, r.springs) + " | " + checksum + " | " + r.status +
                             " |\n";
    table += line;
    std::printf("%s", line.c_str());
    std::fflush(stdout);
    if (options.breakdown)
      breakdown += "| " + std::to_string(r.cells) + " | " + std::to_string(r.springs) + " | " +
                   fixed(r.degenerate, 2) + " | " + fixed(r.masses, 2) + " | " + fixed(r.network, 2) + " | " +
                   fixed(r.rest_lengths, 2) + " | " + fixed(r.stiffness, 2) + " | " + fixed(r.damping, 2) + " |\n";
    std::ostringstream row;
    row.precision(9);
    row << r.cells << ',' << r.vertices << ',' << r.tetrahedra << ',' << r.springs << ',' << r.threads << ','
        << r.generate << ',' << r.repair << ',' << r.model << ',' << r.generate + r.repair + r.model << ',' << r.cpu
        << ','
        << r.peak_bytes << ',' << r.held_bytes << ',' << r.data_bytes << ',' << r.cpu_simulation_peak << ',' << r.gpu_simulation_peak << ','
        << r.degenerate << ',' << r.masses << ',' << r.network << ',' << r.rest_lengths << ',' << r.stiffness << ','
        << r.damping << ',' << checksum << ',' << r.status << '\n';
    csv += row.str();
  }
  if (options.breakdown) std::printf("\n%s", breakdown.c_str());
  if (!options.out_dir.empty()) {
    std::ofstream(options.out_dir + "/setup_bench.csv") << csv;
    std::ofstream(options.out_dir + "/setup_bench.md") << table << (options.breakdown ? "\n" + breakdown : "");
  }
  for (const Row& r : rows)
    if (r.status != "ok") return 1;
  return 0;
}
