#pragma once
// The simulator's library interface: a plain SimulationSetup in, a SimulationResult out. A scene loader builds the
// setup from a mesh, a material mapping and its options; nothing here reads files, prints or exits.
#include <cstddef>
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
#include "runtime/integrate/rigid_tools.h"
#include "runtime/integrate/simulation_options.h"
#include "runtime/mesh/mesh.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

enum class Integrator { ForwardEuler, SemiImplicitEuler, VelocityVerlet, RungeKutta4, ImplicitEuler };
enum class Precision { Float, Double };

// What happens when a tetrahedron turns inside out during a run: it is always counted and reported.
enum class InversionPolicy { Warn, Stop };

const char* to_string(Integrator integrator);

// How implicit Euler solves its linear system (M + h D + h^2 K) dv = h (f0 - h K v0) each step.
enum class ImplicitMethod {
  Automatic,  // the CPU: whichever costs less by an estimate and a trial at the start (implicit_solver.h); CUDA: the CG
  Direct,     // a sparse LDL^T factorisation every step (CPU only), refined while above the tolerance
  ConjugateGradient,  // preconditioned CG (CPU: block Jacobi, started from the last step's solution; CUDA: Jacobi)
};

const char* to_string(ImplicitMethod method);  // "auto", "direct", "cg": the scene's spelling

struct ImplicitSolverOptions {
  ImplicitMethod method = ImplicitMethod::Automatic;
  // Conjugate-gradient iterations (or direct solves) per step; 0: twice the unknowns (3 per vertex), Eigen's default.
  // A step that reaches it above the tolerance is counted and warned about (code `cg-not-converged`), never silent.
  int max_iterations = 0;
  double tolerance = 1e-10;  // relative residual |b - A dv| / |b|
  // The CPU's CG starts from the previous step's dv (false: from zero, Eigen's start; for measuring).
  bool warm_start = true;
  // With tools: solves per step, 1 to kernels::kMostContactRounds. The contact is an active set: the vertices inside a
  // tool at the step's start, then after each solve those its solution predicts inside, solved again while that
  // changes the set, at most this many solves (then a `contact-not-settled` warning). 1: the set at the step's start,
  // solved once and never warned about, as SOFA detects its penalty contact once per step (a haptic loop's budget);
  // either way the steps whose set still changed are counted (ImplicitSolverReport::contact_unsettled_steps).
  int contact_rounds = kernels::kMostContactRounds;
};

// One implicit step's solve, as the run's log keeps it (Simulation::take_implicit_steps).
struct ImplicitStepRecord {
  std::size_t step = 0;            // 1-based: the step this solve advanced to
  int iterations = 0;              // CG iterations (matrix products), or direct solves
  double relative_residual = 0.0;  // |b - A dv| / |b| reached (0 when b = 0: the system at rest)
  bool capped = false;             // stopped at max_iterations above the tolerance
};

// Every implicit step's solve so far, summed (Simulation::implicit_solver); zeros for the explicit schemes.
struct ImplicitSolverReport {
  ImplicitMethod method = ImplicitMethod::ConjugateGradient;  // the one used (never Automatic)
  double tolerance = 0.0;
  int max_iterations = 0;  // the cap in force (implicit_iteration_limit)
  std::size_t steps = 0;
  std::uint64_t iterations_total = 0;
  int iterations_min = 0;
  int iterations_max = 0;
  double residual_max = 0.0;          // the largest relative residual a step reached
  std::size_t residual_max_step = 0;  // its step
  std::size_t capped_steps = 0;       // steps that stopped at the cap above the tolerance
  std::size_t first_capped_step = 0;  // 0: none
  double first_capped_residual = 0.0;
  std::size_t direct_fallbacks = 0;   // direct factorisations that failed (a zero pivot): those steps used the CG
  // With tools: steps whose contact set still changed after their last solve (ImplicitSolverOptions::contact_rounds).
  std::size_t contact_unsettled_steps = 0;
  std::size_t first_contact_unsettled_step = 0;  // 0: none
  ImplicitStepRecord last;            // the latest step's
  // Records take_implicit_steps never saw: more than kMostPendingImplicitSteps were waiting (the sums above count
  // them).
  std::size_t unlogged_steps = 0;
};

// Records a Simulation keeps for take_implicit_steps (16 MiB); later steps are only summed until they are taken.
inline constexpr std::size_t kMostPendingImplicitSteps = std::size_t{1} << 20;

// A probe on picked vertices (DESIGN section 7: prescribed displacement or force, reaction force recorded).
// The load ramps linearly from zero at t = 0 to `target` at t = ramp_time and is then held (ramp_time 0: at once).
struct ProbeLoad {
  enum class Mode { Displacement, Force } mode = Mode::Displacement;
  std::vector<std::int32_t> vertices;  // distinct, not fixed
  // Displacement: m, every probe vertex is moved kinematically to its initial position + ramp(t) target.
  // Force: N, the total, shared equally by the probe vertices (added to any external force).
  Point3 target{0.0, 0.0, 0.0};
  double ramp_time = 0.0;  // s
  // > 0: cyclic loading instead, a triangle wave up to target at ramp_time and back to zero at twice it, `cycles`
  // times, then held at zero (kernels::probe_ramp_share).
  int cycles = 0;
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

  // Rigid tools in frictionless penalty contact with the surface (runtime/integrate/rigid_tools.h), at most
  // kernels::kMostTools; the penalty stiffness per surface vertex is contact_stiffness_ratio x its stiffness bound.
  std::vector<RigidTool> tools;
  double contact_stiffness_ratio = kDefaultContactStiffnessRatio;
  // The contact's damping as a fraction of critical for each surface vertex against its contact spring alone:
  // c = 2 ratio sqrt(k_c m) (rigid_tools.h's contact_damping). 0 (the default): none. Explicit integrators only.
  double contact_damping_ratio = 0.0;
};

// The model's name as scenes spell it: "springs" for a spring network (with or without a term beside it), the scene
// `model:` keyword of its element law where it has one (the registry's model_keyword) on the default element kind,
// else "fem" (the summary's "fem" field then names the law and the element kind).
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
// Per element term, its per-point state now in double (kernels/prony_viscoelasticity.h; empty for a term without
// state): what the host's force sums need to include a viscoelastic term's history (the engines' probe readings).
using ElementTermStates = std::vector<std::vector<double>>;
ProbeReading read_probe(const SimulationSetup& setup, double time, const std::vector<Point3>& positions,
                        const std::vector<Point3>& velocities, const std::vector<double>& stiffness,
                        const ElementTermStates* states = nullptr);

// The internal force (N, in double) of the model on each of `vertices` at a state: springs (with `stiffness`, one per
// spring, and their dashpots) and tetrahedron-field elements (their damping included; a strain table's modulus at
// each element's strain; with `states`, a stateful term's stress at the state's time: its history included).
std::vector<Point3> internal_forces(const SimulationSetup& setup, const std::vector<Point3>& positions,
                                    const std::vector<Point3>& velocities, const std::vector<double>& stiffness,
                                    const std::vector<std::int32_t>& vertices,
                                    const ElementTermStates* states = nullptr);

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

// Per vertex, the bounds x^T K x <= sum_i s_i |x_i|^2 and x^T C x <= sum_i c_i |x_i|^2 of the springs and elements
// that check_stability applies (a strain table's largest modulus, Basafa-Farahmand's largest slope; the tools'
// contact not included), and the smallest damping-to-stiffness ratios of the springs (c / k) and the elements
// (beta_e) that forward Euler's bound reads.
struct VertexBounds {
  std::vector<double> stiffness;  // s_i, N/m
  std::vector<double> damping;    // c_i, N s/m (dashpots and element damping)
  double spring_ratio_min = std::numeric_limits<double>::infinity();
  double element_ratio_min = std::numeric_limits<double>::infinity();
};
VertexBounds vertex_bounds(const SimulationSetup& setup);

// Sizes, indices, masses, rest lengths, parameters, the probe and the strain table; appends one error per problem,
// naming the vertex or spring. springs.damping may be empty (no dashpots).
bool validate_setup(const SimulationSetup& setup, DiagnosticList& diagnostics);

// Validates the setup, then computes the bounds and the critical step (with a strain table, at the stiffest value
// the table can give); appends an error and returns nullopt when the setup is invalid, the scheme is unstable at any step (forward Euler without damping) or a given step exceeds
// the critical one.
std::optional<StabilityReport> check_stability(const SimulationSetup& setup, DiagnosticList& diagnostics);

struct NonFiniteReport {
  std::size_t scene = 0;  // index in the batch
  std::size_t step = 0;   // the step that produced the first non-finite value (1-based)
  double time = 0.0;
  std::int32_t vertex = -1;  // the first vertex with a non-finite position or velocity
  std::int32_t spring = -1;  // the spring at that vertex that is non-finite or the most strained
};

// Elements turned inside out during a run, in every model and on both backends: the element kind's own test
// (kernels::element_inverted: a tetrahedron's signed volume <= 0, a quadratic element's Jacobian <= 0 at one of its
// quadrature points), the tetrahedra's signed volumes where the model has no element terms. Counted at every check
// (every `inversion_check_every` steps and at the end of every advance); the first step is exact: when a check first
// finds one, the run replays from the previous check one step at a time (the steps are deterministic).
struct InversionReport {
  std::size_t first_step = 0;    // the first step after which an element was inverted (0: at the start)
  double first_time = 0.0;       // s
  std::int32_t first_element = -1;  // the smallest inverted element at that step
  std::size_t largest_count = 0;    // the most elements inverted at one check; 0: none was, and first_* are unset
  std::size_t current_count = 0;    // at the last check
};

// Steps between two NaN/Inf and inversion checks (Simulation::advance's default; the CPU backend also finds NaN/Inf at
// the step that makes it).
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
  ImplicitSolverReport implicit_solver;
};

class SteppingEngine;

// Which persistent launches a CUDA run uses (GpuOptions): for tests and benchmarks that measure them.
struct SimulationLaunches {
  bool persistent = false;  // chunks of steps in one launch (a cooperative grid or clusters)
  bool clusters = false;    // in thread-block clusters
};

// Where a scene's positions live on the CUDA device: three arrays (x, y, z) of `count` floats or doubles, the
// simulation's own state, read-only, valid until its next advance, pose or material change (an explicit Euler step
// writes the other of two buffers). The stream that wrote them has finished when device_positions returns.
struct DevicePositions {
  const void* x = nullptr;
  const void* y = nullptr;
  const void* z = nullptr;
  std::size_t count = 0;
  bool double_precision = false;
};

// A running simulation: a batch of one or more scenes advanced together on one backend (the CPU: each scene's
// vertices on worker threads, the scenes of a batch side by side; CUDA: one launch per kernel for the whole batch,
// runtime/gpu/gpu_simulation.h), float or double state, deterministic. Both backends are written under one run
// supervisor (runtime/integrate/run_supervisor.cpp): NaN/Inf and inversion checks every `check_every` steps and at
// the end of each advance, the first non-finite step and the first inversion located exactly by replay from the
// last checkpoint (the steps are deterministic), the inversion policy, and the messages. A NaN/Inf in any scene
// stops the whole batch.
class Simulation {
 public:
  // Checks every scene (sizes, indices, masses, rest lengths, stability; errors of a batch name the scene) and what
  // the backend cannot run together (the CUDA backend's batches share their integrator, precision, laws and loads:
  // an error names the first scene that differs), then builds the backend's state. Null after appending errors.
  static std::unique_ptr<Simulation> create(std::vector<SimulationSetup> scenes, const SimulationOptions& options,
                                            DiagnosticList& diagnostics);
  // One scene.
  static std::unique_ptr<Simulation> create(const SimulationSetup& setup, DiagnosticList& diagnostics,
                                            const SimulationOptions& options = {});
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // Advances `steps` steps, checking for NaN/Inf, inversions and the nodal damping's displacement bound every
  // `check_every` steps counted from the run's start (0: only at the end) and at the end. Stops early (returning
  // false, with an error naming the exact step, scene, vertex and spring) at a non-finite position or velocity, a
  // vertex beyond the displacement the nodal damping's bound assumed, or (on_inversion: stop) a tetrahedron turned
  // inside out; a first inversion under on_inversion: warn appends a warning (code `inverted-elements`) and the
  // run goes on. After a false return every advance returns false.
  bool advance(std::size_t steps, DiagnosticList& diagnostics, std::size_t check_every = kCheckEvery);

  std::size_t scene_count() const;
  std::size_t steps_taken() const;
  double time(std::size_t scene = 0) const;
  const SimulationSetup& setup(std::size_t scene = 0) const;
  const StabilityReport& stability(std::size_t scene = 0) const;
  Backend backend() const;
  SimulationLaunches launches() const;
  const std::optional<NonFiniteReport>& non_finite() const;
  // Inverted tetrahedra of a scene (InversionReport): at every check, the first step exact by replay.
  const InversionReport& inversions(std::size_t scene = 0) const;
  // The most conjugate-gradient iterations (or direct solves) one implicit step needed (0 for the explicit schemes).
  int implicit_max_iterations_used() const;
  // Implicit Euler's solves in a scene so far: the method, iterations and residuals reached, the steps stopped at
  // the cap. Checkpoint replays count each step once.
  ImplicitSolverReport implicit_solver(std::size_t scene = 0) const;
  // Each implicit step's record since the last call (at most kMostPendingImplicitSteps; the report counts the
  // others), in step order: what a caller logs per step (the scene runner fills summary.json and the time series).
  std::vector<ImplicitStepRecord> take_implicit_steps(std::size_t scene = 0);

  // The state, read back (from the device on CUDA). After a device error (appended) the vectors are empty and the
  // optionals nullopt. Energies: kinetic 1/2 m |v|^2, elastic (springs and element
  // terms), potential (elastic and the loads' -(m g + f) . x); on CUDA reduced on the device in double with a fixed
  // summation tree (the same bits on every run, the last bits may differ from the host's sums).
  std::vector<Point3> positions(std::size_t scene, DiagnosticList& diagnostics) const;
  std::vector<Point3> positions(DiagnosticList& diagnostics) const { return positions(0, diagnostics); }
  std::vector<Point3> velocities(std::size_t scene, DiagnosticList& diagnostics) const;
  std::vector<Point3> velocities(DiagnosticList& diagnostics) const { return velocities(0, diagnostics); }
  // CUDA: the scene's positions where they live, without a copy (DevicePositions); on the CPU backend an error saying
  // to read positions().
  std::optional<DevicePositions> device_positions(std::size_t scene, DiagnosticList& diagnostics) const;
  // Every scene's positions (and, given, velocities) now, in one download per array on CUDA (what a cohort reads at
  // every output event); false after a device error.
  bool scene_states(std::vector<std::vector<Point3>>& positions, std::vector<std::vector<Point3>>* velocities,
                    DiagnosticList& diagnostics) const;
  std::optional<double> kinetic_energy(std::size_t scene, DiagnosticList& diagnostics) const;
  std::optional<double> kinetic_energy(DiagnosticList& diagnostics) const { return kinetic_energy(0, diagnostics); }
  std::optional<double> potential_energy(std::size_t scene, DiagnosticList& diagnostics) const;
  std::optional<double> potential_energy(DiagnosticList& diagnostics) const { return potential_energy(0, diagnostics); }
  std::optional<double> elastic_energy(std::size_t scene, DiagnosticList& diagnostics) const;
  std::optional<double> elastic_energy(DiagnosticList& diagnostics) const { return elastic_energy(0, diagnostics); }
  // The largest distance of a vertex from its start (initial or rest positions): on CUDA reduced on the device, the
  // same bits as the host's computation on positions(), without moving the state to the host.
  std::optional<double> largest_displacement(std::size_t scene, DiagnosticList& diagnostics) const;
  std::optional<double> largest_displacement(DiagnosticList& diagnostics) const {
    return largest_displacement(0, diagnostics);
  }
  // Whether energies and the largest displacement are reduced where the state lives (CUDA) rather than from
  // positions() and velocities() on the host.
  bool reduces_in_place() const;
  // The probe's displacement and force now (read_probe on the state); zeros without a probe.
  ProbeReading probe_reading(std::size_t scene, DiagnosticList& diagnostics) const;
  ProbeReading probe_reading(DiagnosticList& diagnostics) const { return probe_reading(0, diagnostics); }
  // Every spring's stiffness now (N/m): the setup's, or a strain table's last lookup.
  std::vector<double> current_stiffness(std::size_t scene, DiagnosticList& diagnostics) const;
  std::vector<double> current_stiffness(DiagnosticList& diagnostics) const { return current_stiffness(0, diagnostics); }

  // ---- rigid tools (runtime/integrate/rigid_tools.h) ---------------------------------------------------------------
  // Poses tool `tool` of `scene` at `pose` for the steps from now on (its path, if any, is dropped); the readings see
  // it at once. A pose that is not finite or whose quaternion has no length, a tool or scene that does not exist, are
  // errors naming the argument, and nothing changes. The quaternion is normalised.
  bool set_tool_pose(std::size_t scene, std::size_t tool, ToolPose pose, DiagnosticList& diagnostics);
  // Where each tool of the scene is now (its path's pose at the current time, or the pose last set).
  const std::vector<ToolPose>& tool_poses(std::size_t scene = 0) const;
  // What each tool of the scene feels now: read_tools at the current state and poses, in double on both backends
  // (on CUDA from the positions downloaded). Empty after a device error; one zero reading per tool before any
  // contact.
  std::vector<ToolReading> tool_readings(std::size_t scene, DiagnosticList& diagnostics) const;
  // The contact stiffness per vertex (N/m; empty without tools).
  const std::vector<double>& contact_stiffness(std::size_t scene = 0) const;
  // Its contact damping per vertex (N s/m; empty without contact damping: SimulationSetup::contact_damping_ratio).
  const std::vector<double>& contact_damping(std::size_t scene = 0) const;

  // ---- the material ------------------------------------------------------------------------------------------------
  // Replaces scene `scene`'s material between two steps, keeping its state, time and checks: the springs' stiffness
  // and damping, the element terms' parameters and damping and the strain table are taken from `material`, a setup
  // built from the same mesh and model with another material (a recompiled rule file or table: runtime/session/).
  // The stability check runs again at the scene's time step, and the contact stiffness follows the new bounds.
  // Arrays of other sizes, another model (other element laws, a strain table where there was none or the reverse),
  // values the setup checks refuse, or a time step the new material makes unstable are errors, and nothing changes.
  bool replace_material(std::size_t scene, const SimulationSetup& material, DiagnosticList& diagnostics);

 private:
  Simulation(std::vector<SimulationSetup> scenes, std::vector<StabilityReport> stability, Backend backend);
  bool locate_non_finite(int vertex, DiagnosticList& diagnostics);
  bool check_displacement_bound(DiagnosticList& diagnostics);
  bool check_inversions(DiagnosticList& diagnostics);
  bool needs_checkpoints() const;
  bool displacement_bound_checked(std::size_t scene) const;
  std::size_t scene_of(int vertex) const;
  std::int32_t culprit_spring(std::size_t scene, std::size_t vertex, DiagnosticList& diagnostics) const;
  bool fail();
  // The engine's run to `ends` with the tools at their poses: where a tool follows a path that still moves, one step
  // at a time, each with the poses at its start time.
  bool run_engine(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics);
  bool tools_move() const;
  // Poses every scene's tools at `step`'s time along their paths; gives the engine the shapes that changed.
  bool pose_tools(std::size_t step, DiagnosticList& diagnostics);
  bool start_tools(DiagnosticList& diagnostics);

  std::vector<SimulationSetup> scenes_;
  std::vector<StabilityReport> stability_;
  std::unique_ptr<SteppingEngine> engine_;
  Backend backend_;
  std::vector<int> vertex_begin_;  // scene s owns batch vertices [vertex_begin_[s], vertex_begin_[s + 1])
  std::vector<InversionReport> inversions_;
  std::vector<std::vector<ToolPose>> tool_poses_;  // per scene, per tool: the pose the engine holds
  std::vector<std::vector<double>> contact_stiffness_;  // per scene (empty without tools)
  std::vector<std::vector<double>> contact_damping_;    // per scene (empty without tools or contact damping)
  std::optional<NonFiniteReport> non_finite_;
  std::size_t restores_ = 0;
  bool failed_ = false;
};

// create + advance(step_count) with samples every record_every steps.
SimulationResult simulate(const SimulationSetup& setup, DiagnosticList& diagnostics);

// The steps of `dt` that cover `span` seconds, ceil(span / dt), as a double to be checked against a limit before it
// becomes a count: the division's result is shrunk by 1e-12 of itself first, so that a span that is an exact
// multiple of dt does not gain a step to rounding.
double steps_covering(double span, double dt);

}  // namespace fmpc::sim
