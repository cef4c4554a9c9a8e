#pragma once
// The thesis's experiment (Tan Sing Yee 2014, sections 3.5 and 4.4.3-4.5.2), reproduced: the liver controllers'
// stiffness drives one mass point under a step force, and its displacement and velocity curves are compared with
// those of the Basafa & Farahmand (2011) benchmark (curve_similarity.h), as Table 4-1 compared them.
//
// What the thesis simulated (Simulink, Fig. 3.5, "position_array and time_array"): one mass point, Eq. (3.5)
// m x'' + gamma x' + k x = F_ext with k the controller's output and gamma = 2 zeta k / w, zeta = 0.9, w = sqrt(k/m)
// (Eq. 3.6), against the benchmark Eq. (3.15) for one node: m x'' + (gamma0 + gamma1 |x - x0|) x' + F_s(X) = F_ext,
// F_s(X) = K1 X + K2 X^3 up to Xc and linear beyond (kernels/spring_math.h). Here both are run by the simulator
// itself (a Simulation on the CPU, RK4, double): vertex 0 fixed at the origin, vertex 1 at (0, 0, l0), held in x and y, one
// spring between them, a constant force F along z on vertex 1 from t = 0 (a step), starting at rest.
//
// What the thesis did not state, and what is assumed (docs/liver_fibrosis.md, "The thesis's experiment"):
// - F_ext and the time span: Simulink's Step block defaults (final value 1, so F = 1 N) and Simulink's default
//   stop time (10 s); the mass: 1.5 kg, the upper bound the thesis names for Fig. 4.6.
// - units: the controller's output (kPa) was substituted for k; here the spring is a bar with A / L = 1 mm, so
//   k = E A / L in N/m equals E in kPa. The benchmark's X is the strain (l - l0) / l0 with l0 = 1 m, so X is the
//   displacement in metres (as in kernels/spring_math.h: K1 = k l0).
// - the pairing: "thesis MSM" (ControllerRun::thesis_*) compares the thesis's linear mass point (Eq. 3.5) driven by
//   the controller with the benchmark; "benchmark law" (ControllerRun::benchmark_*) runs the benchmark's own law and
//   nodal damping with K1 = k l0 (K2 / K1 and Xc kept) driven by the controller, as issue 10 item 7 asks. The
//   reference is the benchmark with its own K1.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"
#include "runtime/analysis/curve_similarity.h"

namespace fmpc::sim {

// Basafa & Farahmand (2011) as the thesis's Table 3-3 gives it.
struct BasafaFarahmandParameters {
  double k1 = 0.05;      // N
  double k2 = 10.0;      // N
  double xc = 0.2;       // strain
  double gamma0 = 2.0;   // N s/m
  double gamma1 = 1000.0;  // N s/m^2
};

struct MassPointResponse {
  Curve displacement;  // m along the force, from rest
  Curve velocity;      // m/s along the force
};

struct LiverBenchmarkOptions {
  BasafaFarahmandParameters benchmark;
  double mass = 1.5;               // kg, the moving mass point
  double force = 1.0;              // N, the step's final value
  double duration = 10.0;          // s
  double time_step = 1e-3;         // s (RK4; docs/liver_fibrosis.md gives the step's convergence)
  std::size_t samples = 1001;      // evenly spaced, t = 0 and t = duration included
  double damping_ratio = 0.9;      // zeta of the thesis's linear mass point, gamma = 2 zeta sqrt(k m)
  double area_over_length = 1e-3;  // m: k (N/m) = E (Pa) x area_over_length
  double rest_length = 1.0;        // m, l0 of the benchmark's spring
  SourceRange time_step_range;     // where the time step came from (a step the simulator refuses points there)
  // Called before each run with (runs done, runs in all): thousands of patients take minutes.
  std::function<void(std::size_t, std::size_t)> progress;
  // When set, each modulus (Pa) also drives an organ under the same step force (organ_step_response.h), and its
  // curves are compared with the reference as the mass point's are (ControllerRun::organ_*).
  std::function<std::optional<MassPointResponse>(double modulus, DiagnosticList& diagnostics)> organ;
};

// Limits on the options (checked before anything is allocated).
constexpr std::size_t kLiverBenchmarkStepsMax = 100'000'000;
constexpr std::size_t kLiverBenchmarkSamplesMax = 100'000;
// Runs x samples a report may hold: every run keeps 4 curves (64 bytes a sample), so at most 256 MiB (6 curves with
// an organ: 384 MiB).
constexpr std::size_t kLiverBenchmarkRunSamplesMax = std::size_t(1) << 22;

// The sample steps: `samples` (at least 2) evenly spread over [0, steps], first and last included, strictly
// increasing (fewer than `samples` when steps < samples - 1).
std::vector<std::size_t> evenly_spaced_steps(std::size_t samples, std::size_t steps);

enum class MassPointLaw {
  BasafaFarahmand,  // F_s(X), K1 = k l0, K2 = (K2/K1 of the benchmark) K1, nodal damping gamma0 + gamma1 |x - x0|
  ThesisLinear,     // k x with a dashpot gamma = 2 zeta sqrt(k m) (Eq. 3.5 and 3.6)
};

// One run of the mass point with spring constant `stiffness` (N/m; for BasafaFarahmand, K1 = stiffness x l0).
// Errors (invalid options, a step the simulator refuses as unstable, a non-finite state) are appended; nullopt then.
std::optional<MassPointResponse> simulate_mass_point(MassPointLaw law, double stiffness,
                                                     const LiverBenchmarkOptions& options,
                                                     DiagnosticList& diagnostics);

struct LiverController {
  std::string name;                   // "Mamdani", "Sugeno", "IT2"
  const FuzzySystem* system = nullptr;  // its first output is the stiffness (Young's modulus, in its own unit)
};

struct LiverPatient {
  std::string label;
  std::vector<double> readings;  // FibroScan kPa, one per input of the controllers, in their input order
};

struct ControllerRun {
  std::string controller;
  std::string patient;
  double modulus = 0.0;    // Pa, the controller's output
  double stiffness = 0.0;  // N/m
  CurveComparison benchmark_displacement, benchmark_velocity;  // benchmark_pairing against the reference
  CurveComparison thesis_displacement, thesis_velocity;        // thesis_pairing against the reference
  MassPointResponse benchmark_response, thesis_response;
  // With LiverBenchmarkOptions::organ: the organ's probe curves, and their comparison with the reference.
  std::optional<MassPointResponse> organ_response;
  CurveComparison organ_displacement, organ_velocity;
};

struct LiverBenchmarkReport {
  MassPointResponse reference;  // the benchmark with its own K1
  std::vector<ControllerRun> runs;  // controller-major, patients in order
};

// The reference: the benchmark with its own K1 (curves named "benchmark displacement" and "benchmark velocity").
std::optional<MassPointResponse> simulate_benchmark_reference(const LiverBenchmarkOptions& options,
                                                              DiagnosticList& diagnostics);

// Both pairings for one Young's modulus (Pa) against the reference; `controller` and `patient` label the run.
std::optional<ControllerRun> compare_modulus_with_benchmark(const std::string& controller, const std::string& patient,
                                                            double modulus, const MassPointResponse& reference,
                                                            const LiverBenchmarkOptions& options,
                                                            DiagnosticList& diagnostics);

// Evaluates every controller for every patient with the reference interpreter (an output that is NaN, not
// positive, or in a unit other than Pa, kPa or MPa is an error; a reading outside an input's range, or no rule
// firing, is a warning), then takes each of `moduli` (Pa) as given (controller "constant", patient
// "E = ... kPa"), runs both pairings and compares their curves with the reference. More than
// kLiverBenchmarkRunSamplesMax runs x samples is refused before anything runs.
std::optional<LiverBenchmarkReport> run_liver_benchmark(const std::vector<LiverController>& controllers,
                                                        const std::vector<LiverPatient>& patients,
                                                        const std::vector<double>& moduli,
                                                        const LiverBenchmarkOptions& options,
                                                        DiagnosticList& diagnostics);

}  // namespace fmpc::sim
