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
#include "runtime/fem/element_terms.h"
#include "runtime/mesh/mesh.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

enum class Integrator { ForwardEuler, SemiImplicitEuler, VelocityVerlet, RungeKutta4, ImplicitEuler };
enum class Precision { Float, Double };

// What happens when a tetrahedron turns inside out during a run: it is always counted and reported.
enum class InversionPolicy { Warn, Stop };

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
// An element term whose law takes its Young's modulus from a strain table (kStrainTableModulus) looks it up at the
// law's strain measure (kernels/laws/), and stiffness_per_modulus is empty.
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
  // What computes the internal forces (DESIGN section 7): a spring network and element terms, either or both; every
  // integrator runs every combination on both backends, asking for forces (and, for implicit Euler, the stiffness),
  // never for a kind. Springs: rest_length, stiffness, damping and adjacency filled in; a model of elements alone
  // has none (vertex_count and an all-zero adjacency_offset only).
  SpringNetwork springs;
  // The mesh's tetrahedra (positively oriented): inversions are counted on them in every model, and the element
  // terms' arrays are parallel to them. Empty for triangle meshes.
  std::vector<Tetrahedron> tetrahedra;
  // The element terms (runtime/fem/element_terms.h): a finite-element model's law, or a term beside the springs (the
  // volume term); empty: none. At most kernels::kMostElementTerms.
  ElementTerms elements;
  // Rayleigh's mass-proportional damping alpha (1/s): a force -alpha m v on every free vertex (its stiffness-
  // proportional part is in the springs' dashpots and the elements' stiffness_damping).
  double mass_damping = 0.0;
  InversionPolicy on_inversion = InversionPolicy::Warn;
  kernels::SpringLaw law = kernels::SpringLaw::LinearDashpot;
  double basafa_k2_over_k1 = 200.0;   // Basafa-Farahmand K2 / K1
  double basafa_xc = 0.2;             // Basafa-Farahmand Xc (strain)
  double nodal_damping_gamma0 = 0.0;  // N s/m
  double nodal_damping_gamma1 = 0.0;  // N s/m^2
  std::vector<std::int32_t> fixed_vertices;  // held along every axis
  // Per vertex (or empty): the axes held besides those of fixed_vertices, bit a for axis a (a vertex sliding on a
  // plane z = c has bit 2), as SOFA's PartialFixedConstraint.
  std::vector<std::uint8_t> fixed_axes;
  Point3 gravity{0.0, 0.0, 0.0};        // m/s^2
  std::vector<Point3> external_forces;  // N per vertex, constant; empty: none

  Integrator integrator = Integrator::SemiImplicitEuler;
  Precision precision = Precision::Double;
  std::optional<double> time_step;  // s; nullopt: automatic (stability_margin x the critical step)
  double stability_margin = 0.8;
  // Where the run's errors point: the time step's field (a step refused by the stability check) and the scene file
  // (a non-finite state, an inversion under on_inversion: stop). Default: no position.
  SourceRange time_step_range;
  SourceRange source_range;
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

// The model's name as scenes spell it: "springs" for a spring network (with or without a term beside it), else the
// scene `model:` keyword of its element law (the registry's model_keyword).
std::string model_name(const SimulationSetup& setup);

// Where vertex v starts: its initial position, or its rest position.
const Point3& start_position(const SimulationSetup& setup, std::size_t v);

// The held axes of every vertex (kernels::kAllAxesFixed for fixed vertices and a displacement probe's, which are
// moved kinematically; fixed_axes' bits otherwise): what both backends, the stability check and the static solver
// read.
std::vector<unsigned char> held_axes(const SimulationSetup& setup);

// The table as the shared lookup (kernels/strain_table_math.h) reads it; it points into `table`.
kernels::StrainTableView strain_table_view(const StrainStiffnessTable& table);

// The probe's reading at a state, computed in double by both backends: the mean displacement of the probe vertices
// from their start, and the applied force (Force) or minus the internal forces (springs with their dashpots and the
// springs' current `stiffness`, elements with their damping) on the probe vertices (Displacement). Zeros without a
// probe or with mismatched sizes.
ProbeReading read_probe(const SimulationSetup& setup, double time, const std::vector<Point3>& positions,
                        const std::vector<Point3>& velocities, const std::vector<double>& stiffness);

// The internal force (N, in double) of the model on each of `vertices` at a state: springs (with `stiffness`, one per
// spring, and their dashpots) and tetrahedron-field elements (their damping included; a strain table's modulus at
// each element's strain).
std::vector<Point3> internal_forces(const SimulationSetup& setup, const std::vector<Point3>& positions,
                                    const std::vector<Point3>& velocities, const std::vector<double>& stiffness,
                                    const std::vector<std::int32_t>& vertices);

// Per element term, per tetrahedron at `positions` (double): the term's stress output (its law's stress_output, the
// frames' cell array named by the law's kStressOutput: e.g. a von Mises stress, or the volume term's pressure beside
// springs, whose own stresses are not a continuum field); empty without element terms.
struct ElementStressOutput {
  const char* name;            // the cell array's name
  std::vector<double> values;  // one per tetrahedron
};
std::vector<ElementStressOutput> element_stress_outputs(const SimulationSetup& setup,
                                                        const std::vector<Point3>& positions);

// The CG iteration cap of one implicit step: options.max_iterations, or twice the unknowns when it is 0.
int implicit_iteration_limit(const SimulationSetup& setup);

// Probe and strain-table checks (validate_setup calls it); errors name the vertex or the entry.
bool validate_loads(const SimulationSetup& setup, DiagnosticList& diagnostics);

// Elastic energy at `positions` (J): of the springs, 1/2 k (l - l0)^2 for the linear law, the integral of F_s for
// Basafa-Farahmand; of each element term, its law's energy. With a strain table, k (E) is the table's value at the
// current strain (an approximation: the integral of the varying modulus is not taken).
double elastic_energy(const SimulationSetup& setup, const std::vector<Point3>& positions);
// The element terms' share of elastic_energy.
double element_elastic_energy(const SimulationSetup& setup, const std::vector<Point3>& positions);
// Kinetic energy 1/2 m |v|^2 summed over the vertices (J).
double kinetic_energy(const SimulationSetup& setup, const std::vector<Point3>& velocities);

// The critical time step (docs/simulator.md derives every bound). Every force model bounds its stiffness per vertex
// so that x^T K x <= sum_i s_i |x_i|^2: springs s_i = 2 sum_j k_ij (k_ij the largest tangent stiffness), elements
// s_i = sum of lambda_e over the elements at i (lambda_e an upper bound of the element stiffness's largest
// eigenvalue); then w_max^2 <= max_i s_i / m_i. The damping rate beta_max = max_i c_i / m_i bounds x^T C x / x^T M x
// the same way (dashpots, element damping beta_e lambda_e, nodal gamma0 + gamma1 d, Rayleigh alpha m_i). Each scheme's
// limit on x'' + beta x' + w^2 x = 0 follows; forward Euler's also needs the smallest damping-to-stiffness ratio.
struct StabilityReport {
  double omega_max = 0.0;                                               // rad/s
  std::int32_t limiting_vertex = -1;                                    // the vertex that sets omega_max
  double damping_rate_max = 0.0;                                        // 1/s
  // The displacement from rest the bound on the nodal damping gamma1 |x - x0| assumed (m); the run stops with an
  // error naming the vertex if one moves further (its damping, and so the stable step, would be out of the bound).
  double assumed_displacement_max = std::numeric_limits<double>::infinity();
  double critical_time_step = std::numeric_limits<double>::infinity();  // s; infinity: unconditionally stable
  double time_step = 0.0;                                               // s, the step used
  bool automatic = false;
  std::string limit;  // the formula applied, e.g. "h <= 2 / (beta/2 + sqrt(w^2 + beta^2/4))"
  // Forward Euler: modes no damping acts on (sideways vibrations of stretched springs, rotations of loaded
  // elements) grow at any step without mass or nodal damping; a given step then runs with a warning, `auto` is
  // refused.
  bool undamped_modes = false;
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

// Tetrahedra turned inside out (signed volume <= 0) during a run, in every model and on both backends. Counted at
// every check (every `inversion_check_every` steps and at the end of every advance); the first step is exact: when
// a check first finds one, the run replays from the previous check one step at a time (the steps are deterministic).
struct InversionReport {
  std::size_t first_step = 0;    // the first step after which an element was inverted (0: at the start)
  double first_time = 0.0;       // s
  std::int32_t first_element = -1;  // the smallest inverted element at that step
  std::size_t largest_count = 0;    // the most elements inverted at one check; 0: none was, and first_* are unset
  std::size_t current_count = 0;    // at the last check
};

// Steps between two NaN/Inf and inversion checks of the GPU backend, and between two inversion checks of the CPU
// backend (which checks NaN/Inf every step).
constexpr std::size_t kCheckEvery = 64;

// The message of a first inversion ("tetrahedron 12 (vertices ...) turned inside out at step 37 (t = ... s); ...").
std::string inversion_message(const SimulationSetup& setup, const InversionReport& report);

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
  InversionReport inversions;
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
  // position or velocity becomes NaN or infinite, when a vertex moves beyond the displacement the nodal damping's
  // bound assumed, or (on_inversion: stop) when a tetrahedron turns inside out. A first inversion under
  // on_inversion: warn appends a warning (code `inverted-elements`) and the run goes on.
  virtual bool advance(std::size_t steps, DiagnosticList& diagnostics) = 0;
  virtual std::size_t steps_taken() const = 0;
  virtual double time() const = 0;
  virtual std::vector<Point3> positions() const = 0;
  virtual std::vector<Point3> velocities() const = 0;
  virtual double kinetic_energy() const = 0;
  virtual double potential_energy() const = 0;
  virtual const StabilityReport& stability() const = 0;
  virtual const std::optional<NonFiniteReport>& non_finite() const = 0;
  virtual const InversionReport& inversions() const = 0;
  virtual int implicit_max_iterations_used() const = 0;
  // The probe's displacement and force now; zeros without a probe.
  virtual ProbeReading probe_reading() const = 0;
  // The stiffness of every spring now (N/m): springs.stiffness, or the last table lookup with a strain table.
  virtual std::vector<double> current_stiffness() const = 0;
};

// create + advance(step_count) with samples every record_every steps.
SimulationResult simulate(const SimulationSetup& setup, DiagnosticList& diagnostics);

}  // namespace fmpc::sim
