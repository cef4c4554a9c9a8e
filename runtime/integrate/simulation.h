#pragma once
// The simulator's library interface: a plain SimulationSetup in, a SimulationResult out. A scene loader builds the
// setup from a mesh, a material mapping and its options; nothing here reads files, prints or exits.
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "kernels/spring_math.h"
#include "kernels/strain_table_math.h"
#include "runtime/mesh/mesh.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

enum class Integrator { ForwardEuler, SemiImplicitEuler, VelocityVerlet, RungeKutta4, ImplicitEuler };
enum class Precision { Float, Double };

const char* to_string(Integrator integrator);

struct ImplicitSolverOptions {
  // Conjugate-gradient iterations per step; 0: twice the unknowns (3 per vertex), Eigen's default. A fixed small
  // cap stopped SOFA's liver with fuzzy stiffness short of the tolerance (stiff springs, Jacobi preconditioning).
  int max_iterations = 0;
  double tolerance = 1e-10;  // relative residual |r| / |b|
};

// A probe on picked vertices (DESIGN section 7: prescribed displacement or force, reaction force recorded).
// The load ramps linearly from zero at t = 0 to `target` at t = ramp_time and is then held (ramp_time 0: at once).
struct ProbeLoad {
  enum class Mode { Displacement, Force } mode = Mode::Displacement;
  std::vector<std::int32_t> vertices;  // distinct, not fixed
  // Displacement: m, every probe vertex is moved kinematically to its initial position + ramp(t) target.
  // Force: N, the total, shared equally by the probe vertices (added to any external force).
  Point3 target{0.0, 0.0, 0.0};
  double ramp_time = 0.0;  // s
};

// What a probe measures at the current state.
struct ProbeReading {
  Point3 displacement{0.0, 0.0, 0.0};  // m, mean over the probe vertices from their initial positions
  // N, the force the probe exerts on the tissue: the applied total (Force), or minus the sum of the spring forces
  // (with their dashpots) on the probe vertices (Displacement: the reaction force).
  Point3 force{0.0, 0.0, 0.0};
};

// Table-driven stiffness k(strain) (DESIGN section 7): every step, each spring's strain X = (l - l0) / l0 is looked
// up in modulus(X) (kernels/table_math.h, clamped to the table's ends) and k = modulus(X) * stiffness_per_modulus.
struct StrainStiffnessTable {
  std::vector<double> strain;                 // breakpoints, strictly increasing, at least 2
  std::vector<double> modulus;                // Pa, one per breakpoint
  std::vector<double> stiffness_per_modulus;  // per spring (m): the material mapping's k for a modulus of 1 Pa
};

struct SimulationSetup {
  std::vector<Point3> rest_positions;      // also x0 of the nodal damping gamma0 + gamma1 |x - x0|
  std::vector<Point3> initial_positions;   // empty: the rest positions
  std::vector<Point3> initial_velocities;  // empty: at rest
  std::vector<double> mass;                // kg per vertex (lumped_masses)
  SpringNetwork springs;                   // rest_length, stiffness, damping and adjacency filled in
  kernels::SpringLaw law = kernels::SpringLaw::LinearDashpot;
  double basafa_k2_over_k1 = 200.0;   // Basafa-Farahmand K2 / K1
  double basafa_xc = 0.2;             // Basafa-Farahmand Xc (strain)
  double nodal_damping_gamma0 = 0.0;  // N s/m
  double nodal_damping_gamma1 = 0.0;  // N s/m^2
  std::vector<std::int32_t> fixed_vertices;
  Point3 gravity{0.0, 0.0, 0.0};        // m/s^2
  std::vector<Point3> external_forces;  // N per vertex, constant; empty: none

  Integrator integrator = Integrator::SemiImplicitEuler;
  Precision precision = Precision::Double;
  std::optional<double> time_step;  // s; nullopt: automatic (stability_margin x the critical step)
  double stability_margin = 0.8;
  // A given time_step above the critical step is an error; false turns it into a warning (for studying an
  // unstable scheme, e.g. the thesis's forward Euler). NaN/Inf detection stays on either way.
  bool refuse_unstable_time_step = true;
  std::size_t step_count = 0;
  unsigned threads = 1;  // CPU worker threads; results do not depend on it
  ImplicitSolverOptions implicit;

  std::size_t record_every = 0;  // 0: no samples; otherwise every N steps (and step 0)
  std::vector<std::int32_t> recorded_vertices;

  std::optional<ProbeLoad> probe;
  std::optional<StrainStiffnessTable> strain_stiffness;  // replaces springs.stiffness every step
};

// Where vertex v starts: its initial position, or its rest position.
const Point3& start_position(const SimulationSetup& setup, std::size_t v);

// The table as the shared lookup (kernels/strain_table_math.h) reads it; it points into `table`.
kernels::StrainTableView strain_table_view(const StrainStiffnessTable& table);

// The probe's reading at a state, computed in double by both backends: the mean displacement of the probe vertices
// from their start, and the applied force (Force) or minus the spring and dashpot forces on the probe vertices with
// the springs' current `stiffness` (Displacement). Zeros without a probe or with mismatched sizes.
ProbeReading read_probe(const SimulationSetup& setup, double time, const std::vector<Point3>& positions,
                        const std::vector<Point3>& velocities, const std::vector<double>& stiffness);

// The CG iteration cap of one implicit step: options.max_iterations, or twice the unknowns when it is 0.
int implicit_iteration_limit(const SimulationSetup& setup);

// Probe and strain-table checks (validate_setup calls it); errors name the vertex or the entry.
bool validate_loads(const SimulationSetup& setup, DiagnosticList& diagnostics);

// Elastic energy of the springs at `positions` (J): 1/2 k (l - l0)^2 for the linear law, the integral of F_s for
// Basafa-Farahmand. With a strain table, k is the table's value at the current strain (an approximation: the
// integral of the varying k is not taken).
double elastic_energy(const SimulationSetup& setup, const std::vector<Point3>& positions);
// Kinetic energy 1/2 m |v|^2 summed over the vertices (J).
double kinetic_energy(const SimulationSetup& setup, const std::vector<Point3>& velocities);

// The critical time step from the Gershgorin bound w_max^2 <= max_i 2 sum_j k_ij / m_i (k_ij: the spring's largest
// tangent stiffness) and the damping rate beta_max = max_i (2 sum_j c_ij + gamma0) / m_i, through each scheme's
// stability limit on the test equation x'' + beta x' + w^2 x = 0 (docs/simulator.md derives them).
struct StabilityReport {
  double omega_max = 0.0;                                               // rad/s
  std::int32_t limiting_vertex = -1;                                    // the vertex that sets omega_max
  double damping_rate_max = 0.0;                                        // 1/s
  double critical_time_step = std::numeric_limits<double>::infinity();  // s; infinity: unconditionally stable
  double time_step = 0.0;                                               // s, the step used
  bool automatic = false;
  std::string limit;  // the formula applied, e.g. "h <= 2 / (beta/2 + sqrt(w^2 + beta^2/4))"
};

// Sizes, indices, masses, rest lengths, parameters, the probe and the strain table; appends one error per problem,
// naming the vertex or spring. springs.damping may be empty (no dashpots).
bool validate_setup(const SimulationSetup& setup, DiagnosticList& diagnostics);

// Validates the setup, then computes the bounds and the critical step (with a strain table, at the stiffest value
// the table can give); appends an error and returns nullopt when the setup is invalid, the scheme is unstable at any step (forward Euler without damping) or a given step exceeds
// the critical one.
std::optional<StabilityReport> check_stability(const SimulationSetup& setup, DiagnosticList& diagnostics);

struct NonFiniteReport {
  std::size_t step = 0;  // the step that produced the first non-finite value (1-based)
  double time = 0.0;
  std::int32_t vertex = -1;  // the first vertex with a non-finite position or velocity
  std::int32_t spring = -1;  // the spring at that vertex that is non-finite or the most strained
};

struct Sample {
  std::size_t step = 0;
  double time = 0.0;
  std::vector<Point3> positions;  // of the recorded vertices, in their order
  double kinetic_energy = 0.0;
  double potential_energy = 0.0;  // springs + gravity + external forces
};

struct SimulationResult {
  bool completed = false;
  StabilityReport stability;
  std::size_t steps_taken = 0;
  std::vector<Point3> positions;
  std::vector<Point3> velocities;
  std::vector<Sample> samples;
  std::optional<NonFiniteReport> non_finite;
  int implicit_max_iterations_used = 0;
};

// A running simulation on the CPU (float or double state, multi-threaded, deterministic).
class CpuSimulation {
 public:
  // Checks the setup (sizes, indices, masses, rest lengths, stability); returns null after appending errors.
  // The simulation keeps its own copy of the setup.
  static std::unique_ptr<CpuSimulation> create(const SimulationSetup& setup, DiagnosticList& diagnostics);
  virtual ~CpuSimulation() = default;

  // Advances `steps` steps; stops early (returning false, with an error naming step, vertex and spring) when a
  // position or velocity becomes NaN or infinite.
  virtual bool advance(std::size_t steps, DiagnosticList& diagnostics) = 0;
  virtual std::size_t steps_taken() const = 0;
  virtual double time() const = 0;
  virtual std::vector<Point3> positions() const = 0;
  virtual std::vector<Point3> velocities() const = 0;
  virtual double kinetic_energy() const = 0;
  virtual double potential_energy() const = 0;
  virtual const StabilityReport& stability() const = 0;
  virtual const std::optional<NonFiniteReport>& non_finite() const = 0;
  virtual int implicit_max_iterations_used() const = 0;
  // The probe's displacement and force now; zeros without a probe.
  virtual ProbeReading probe_reading() const = 0;
  // The stiffness of every spring now (N/m): springs.stiffness, or the last table lookup with a strain table.
  virtual std::vector<double> current_stiffness() const = 0;
};

// create + advance(step_count) with samples every record_every steps.
SimulationResult simulate(const SimulationSetup& setup, DiagnosticList& diagnostics);

}  // namespace fmpc::sim
