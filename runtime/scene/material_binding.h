#pragma once
// From fuzzy rules (or a compiled .fzt table) and a scene's input bindings to Young's modulus per spring, or to a
// modulus(strain) table looked up every step. The FIS output is Young's modulus in its own unit, which the rule
// file states and the .fzt table records (kPa for the thesis's liver rules); Pa, kPa and MPa are converted, any
// other unit is refused at the scene's field, and an output without a unit (MATLAB files have none) is read as
// kPa with one warning. Everything returned here is in Pa (SI inside). The material mapping (Van Gelder 1998)
// then turns the modulus into spring constants (runtime/springs/spring_network.h).
#include <optional>
#include <string>
#include <vector>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

// An output of the evaluator besides Young's modulus, evaluated at the same material points (material.bind), in the
// output's own unit: the caller converts and checks it against the parameter it gives.
struct BoundOutput {
  int index = 0;         // the output's index in the system (or table)
  std::string name;      // the output's name
  std::string unit;      // as the rule file (or the table) gives it; empty: none
  bool has_range = false;  // a table records no range
  double range_min = 0.0, range_max = 0.0;  // the output's declared range, in its unit
  std::vector<double> values;               // one per material point
};

struct MaterialBinding {
  std::string system;  // the system (or table) evaluated
  std::string output;  // its output used as Young's modulus
  double pascals_per_output_unit = 1000.0;  // kPa -> Pa by default
  // Every binding constant or per region: the modulus of every spring (Pa).
  std::vector<double> modulus_per_spring;
  // A strain binding: modulus (Pa) at each strain breakpoint (the other inputs at their constants).
  std::vector<double> strain;
  std::vector<double> strain_modulus;
  // material.bind's other outputs, one value per material point each (none with a strain binding).
  std::vector<BoundOutput> bound;
  std::size_t evaluations = 0;  // interpreter (or table) evaluations made
  double modulus_min = 0.0, modulus_max = 0.0;  // Pa, over the springs or the strain table
};

// Where a material is evaluated, and what messages call each point: one point per spring (its midpoint), or one per
// tetrahedron (its centroid: the co-rotational FEM, and the springs' volume term).
enum class MaterialPoint { SpringMidpoint, ElementCentroid };

// Pa per unit of a FIS output: Pa, kPa, MPa. nullopt otherwise (also for no unit: see output_unit_scale).
std::optional<double> pascals_per_unit(const std::string& unit);

// Evaluates `system`'s output `output_index` (Young's modulus), and each output of `bound_outputs` (their values
// in MaterialBinding::bound, in that order), for the bindings. `points` (mesh units, one per spring or element, as
// `kind` says) place the material points in regions; messages name them "spring N (midpoint ...)" or
// "element N (centroid ...)". Every input must be bound exactly once; a strain binding cannot be combined with
// per-region bindings. Errors are located at the scene's fields (scene.range_of("material.inputs.NAME")).
std::optional<MaterialBinding> bind_rules(const FuzzySystem& system, int output_index, const Scene& scene,
                                          const std::vector<Point3>& points, MaterialPoint kind,
                                          DiagnosticList& diagnostics, const std::vector<int>& bound_outputs = {});

// The same for a compiled table: its axes are the inputs to bind; the strain axis uses the table's breakpoints;
// the output's unit is the one the table records (.fzt version 2).
std::optional<MaterialBinding> bind_table(const LookupTable& table, int output_index, const Scene& scene,
                                          const std::vector<Point3>& points, MaterialPoint kind,
                                          DiagnosticList& diagnostics, const std::vector<int>& bound_outputs = {});

}  // namespace fmpc::sim
