#pragma once
// The CUDA backend's host side. Built only when nvcc is found (FMPC_RUNTIME_HAVE_CUDA); this header itself needs
// no CUDA headers. Every force model (springs, springs with the volume term, co-rotational FEM) runs with every
// integrator. Integrators on the GPU: forward Euler and semi-implicit Euler (one fused kernel per step),
// velocity Verlet (two kernels per step), RK4 (four stage kernels per step) and implicit Euler (a matrix-free,
// Jacobi-preconditioned conjugate gradient in double, kernels/implicit_math.h), all over the same FMPC_HD functions
// as the CPU loop, in float or double. Probes and strain tables run beside every step as on the CPU. Repeated
// explicit steps are replayed from CUDA graphs; many scenes can share one launch (GpuBatchSimulation).
// Every CUDA call and launch is checked and turned into a Diagnostic; nothing exits.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "runtime/integrate/simulation.h"

namespace fmpc::gpu {

// Whether a CUDA device can be used, with its name or the reason it cannot.
bool cuda_device_available(std::string& description);

struct GpuOptions {
  // Capture the steps between two NaN/Inf checks into a CUDA graph once and replay it (saves the launch overhead
  // that dominates small meshes). The results are bitwise the same either way.
  bool use_graphs = true;
  // Forward and semi-implicit Euler on meshes small enough for a group of threads per vertex with every block
  // resident: each chunk of steps in one cooperative launch with a grid barrier between steps
  // (launch_persistent_euler) instead of a few kernels per step. The results are bitwise the same either way;
  // use_graphs then has no effect.
  bool persistent = true;
  // Which persistent launch: the cooperative grid (launch_persistent_euler: every block resident at once, each
  // waiting between steps for the blocks its springs reach) or thread-block clusters (launch_cluster_euler: springs
  // alone, Hopper or newer, each scene within one cluster of at most 16 x 1,024 vertices whose state and records fit
  // its shared memory; clusters run independently, in waves where there are more than the GPU holds). Automatic
  // takes the grid where the batch fits it and clusters where it does not: on an H100 the 20^3 box ran 310,322-
  // 320,840 steps/s end to end on the grid (94,019 in one cluster, measured when the grid ran 124,409-131,427), while
  // 1,000 demo patients, too many for one grid, ran at 6.33e10 spring-steps/s in clusters against 4.23e10 with a
  // launch per step. Grid and Clusters take that one first.
  // Bitwise the same results in every case.
  enum class PersistentKind { Automatic, Grid, Clusters };
  PersistentKind persistent_kind = PersistentKind::Automatic;
  // Vertices per block of the cooperative persistent launch (1 to 256; 0: automatic, the fewest whose grid is
  // resident). A setting whose grid does not fit takes the nearest that does, more rows first. Bitwise the same
  // results for any value.
  int persistent_rows = 0;
  // Threads per vertex in the per-step fused kernel of forward and semi-implicit Euler (1, 2, 4, 8, 16 or 32;
  // 0: automatic, by the mesh's size and model): more loads of a vertex's entries in flight. Bitwise the same
  // results for any value.
  int gather_lanes = 0;
  // The float element pass's register bound, in blocks of 256 threads per multiprocessor: 3 (80 registers, 20 bytes
  // spilled) or 2 (91 registers, no spills); 0: the default, 3. The same bits either way.
  int element_blocks_per_sm = 0;
  // The kernels with one thread per vertex read the springs' records in the sliced layout (kernels::
  // SlicedSpringsView) instead of in CSR order, their threads ordered by entry count within windows of
  // `slice_window` vertices (32 to 1024, a power of two; 0: sim::kDefaultSliceWindow). Bitwise the same results
  // either way; false and the window are for measuring.
  bool sliced_springs = true;
  int slice_window = 0;
};

// Where a GPU run became non-finite. `step` is exact: the run keeps a copy of the state at every check that
// passed and, when a check fails, replays from that copy one step at a time (the kernels are deterministic).
struct GpuNonFiniteReport {
  std::size_t scene = 0;  // index in the batch (0 for GpuSimulation)
  sim::NonFiniteReport report;
};

class GpuSimulation {
 public:
  // Validates the setup like the CPU backend (same stability check), then uploads it.
  static std::unique_ptr<GpuSimulation> create(const sim::SimulationSetup& setup, DiagnosticList& diagnostics);
  static std::unique_ptr<GpuSimulation> create(const sim::SimulationSetup& setup, const GpuOptions& options,
                                               DiagnosticList& diagnostics);
  virtual ~GpuSimulation() = default;

  // Advances `steps` steps, checking for NaN/Inf every `check_every` steps (0: only at the end) and at the end; on
  // a non-finite value the error names the exact step, the vertex and its most strained spring.
  virtual bool advance(std::size_t steps, DiagnosticList& diagnostics, std::size_t check_every = sim::kCheckEvery) = 0;
  virtual std::size_t steps_taken() const = 0;
  virtual std::vector<sim::Point3> positions(DiagnosticList& diagnostics) const = 0;
  virtual std::vector<sim::Point3> velocities(DiagnosticList& diagnostics) const = 0;
  virtual const sim::StabilityReport& stability() const = 0;

  virtual double time() const = 0;
  // Energies as CpuSimulation defines them, reduced on the device in double with a fixed summation tree (the same
  // bits on every run); nullopt after a CUDA error (appended to diagnostics).
  virtual std::optional<double> kinetic_energy(DiagnosticList& diagnostics) const = 0;
  virtual std::optional<double> potential_energy(DiagnosticList& diagnostics) const = 0;
  // The largest distance of a vertex from its start (initial or rest positions), reduced on the device: the same
  // bits as the host's computation on positions(), without moving the state to the host; nullopt after a CUDA error.
  virtual std::optional<double> largest_displacement(DiagnosticList& diagnostics) const = 0;
  // The springs' and the elements' energy (sim::elastic_energy's terms, without the loads'), on the device.
  virtual std::optional<double> elastic_energy(DiagnosticList& diagnostics) const = 0;
  virtual const std::optional<sim::NonFiniteReport>& non_finite() const = 0;
  // Inverted tetrahedra as the CPU backend counts them (sim::InversionReport): at every check (check_every steps and
  // the end of every advance), the first step exact by replay.
  virtual const sim::InversionReport& inversions() const = 0;
  // The probe's displacement and force now (sim::read_probe on the downloaded state); zeros without a probe.
  virtual sim::ProbeReading probe_reading(DiagnosticList& diagnostics) const = 0;
  // Every spring's stiffness now (N/m): the setup's, or the strain table's last lookup.
  virtual std::vector<double> current_stiffness(DiagnosticList& diagnostics) const = 0;
  // The most conjugate-gradient iterations one implicit step needed (0 for the explicit schemes).
  virtual int implicit_max_iterations_used() const = 0;
  // Whether steps run as persistent launches (GpuOptions::persistent and the mesh qualified), and whether those run
  // in one thread-block cluster (GpuOptions::cluster) rather than a cooperative grid.
  virtual bool persistent_launch() const = 0;
  virtual bool cluster_launch() const = 0;
};

// Many scenes advanced together, one launch per kernel for all of them: the scenes' vertices, springs and CSR
// entries are concatenated (offset arrays), each scene keeps its own time step. The scenes must share the
// integrator, the precision, the spring law and its parameters, gravity and the nodal damping (an error names the
// first scene that differs); sizes, materials, fixed vertices, forces, probes and initial states may differ. Each
// scene's probe is applied by its own threads from its own values (no atomics), so a scene's probe and force curve
// are bitwise those it has when run alone. Implicit Euler and strain tables need a batch of one scene. A NaN/Inf in
// any scene stops the whole batch.
class GpuBatchSimulation {
 public:
  static std::unique_ptr<GpuBatchSimulation> create(const std::vector<sim::SimulationSetup>& scenes,
                                                    const GpuOptions& options, DiagnosticList& diagnostics);
  virtual ~GpuBatchSimulation() = default;

  virtual bool advance(std::size_t steps, DiagnosticList& diagnostics, std::size_t check_every = sim::kCheckEvery) = 0;
  virtual std::size_t scene_count() const = 0;
  virtual std::size_t steps_taken() const = 0;
  virtual std::vector<sim::Point3> positions(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::vector<sim::Point3> velocities(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  // Every scene's positions (and, given, velocities) now, in one download per array instead of one per scene (what
  // a cohort reads at every output event); false after a CUDA error (appended to diagnostics).
  virtual bool scene_states(std::vector<std::vector<sim::Point3>>& positions,
                            std::vector<std::vector<sim::Point3>>* velocities, DiagnosticList& diagnostics) const = 0;
  virtual const sim::StabilityReport& stability(std::size_t scene) const = 0;
  virtual std::optional<double> kinetic_energy(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::optional<double> potential_energy(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::optional<double> largest_displacement(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::optional<double> elastic_energy(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual const std::optional<GpuNonFiniteReport>& non_finite() const = 0;
  virtual const sim::InversionReport& inversions(std::size_t scene) const = 0;
  virtual std::vector<double> current_stiffness(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual sim::ProbeReading probe_reading(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual int implicit_max_iterations_used() const = 0;
  virtual bool persistent_launch() const = 0;
  virtual bool cluster_launch() const = 0;
};

}  // namespace fmpc::gpu
