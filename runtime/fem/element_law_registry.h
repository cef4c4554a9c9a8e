#pragma once
// The element laws' registry (docs/simulator.md, "Adding a law"): one row per law of kernels/element_laws.h, in the
// same order, with what the rest of fmpc needs to know about it: its scene keywords, how its per-element parameters
// are built from a scene's material, its name in `fmpc trade`, its frames' cell data and its documentation. Scene
// parsing, the model builders, the trade and the outputs go through these rows; nothing outside a law's kernels
// header and this registry names a law (tests/unit/law_unit_test.cpp checks it).
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/fem/element_terms.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

// What a law's builder gets: the scene's material per element.
struct ElementMaterial {
  std::vector<double> youngs_modulus;                                 // Pa, one per element
  std::vector<double> poisson_ratio;                                  // one per element
  StiffnessMapping spring_mapping = StiffnessMapping::VanGelder1998;  // beside springs: their Young's modulus mapping
  SourceRange where;                                                  // the material's place in the scene, for errors
};

// A material parameter a law's builder reads from ElementMaterial, and so one that a rule file's output can give per
// element (`material.bind: {KEYWORD: OUTPUT}`, docs/scenes.md): its name, the quantity its unit must measure, the
// range a valid value lies in (SI), and where the builder reads it. A law lists its own in its registry row.
struct MaterialParameterRow {
  const char* keyword;      // material.bind's key (the scene's own field of the same name sets it otherwise)
  const char* description;  // "Young's modulus", for messages
  enum class Quantity {
    Pressure,       // Pa, kPa or MPa; an output without a unit is read as kPa (with a warning), as material.rules is
    Dimensionless,  // no unit, `dimensionless` or `%`
  } quantity;
  double lowest, highest;                    // the valid range (SI)
  bool lowest_included, highest_included;    // whether each end is a valid value
  std::vector<double> ElementMaterial::*values;  // where the builder reads it, one value per element
};

struct ElementLawBuild {
  ElementTerm term;  // its law and parameters (no damping yet)
  // Beside springs: the factor the springs' stiffness (from the mapping at E) is scaled by so that the springs and
  // the term together have the material's E and nu.
  double spring_modulus_scale = 1.0;
  std::string description;  // appended to the run's stiffness description
};

struct ElementLawRow {
  const char* keyword;        // the law's own name (fem: {law: KEYWORD} in scene files)
  const char* model_keyword;  // the scene's `model:` value that selects this law alone on linear tetrahedra; null: none
  // Beside a spring network (springs: {volume_term: true}) rather than a model of its own.
  bool beside_springs;
  const char* trade_name;     // fmpc trade --models
  const char* trade_label;    // the trade's short variant label
  const char* description;    // one line for docs and --help, with its source
  int law;                    // index in kernels::ElementLaws
  const char* stress_output;  // the frames' cell array (the law's kStressOutput)
  // The term's parameters from the material, checked (an error names the element and the field); nullopt after
  // appending errors.
  std::optional<ElementLawBuild> (*build)(const ElementMaterial& material, DiagnosticList& diagnostics);
  // The material parameters the builder reads, each bindable to a rule output.
  std::vector<MaterialParameterRow> parameters;
};

// Every row, in kernels::ElementLaws' order.
const std::vector<ElementLawRow>& element_law_rows();
// The parameter of `row` with keyword `name`; null when it has none.
const MaterialParameterRow* material_parameter(const ElementLawRow& row, const std::string& name);
// SI units per unit `unit` of a rule output that gives `parameter` (kPa -> 1000 for a pressure, % -> 0.01); nullopt
// when the unit does not measure the parameter's quantity. An empty unit: kPa for a pressure (the caller warns), 1
// for a ratio.
std::optional<double> si_per_unit(const MaterialParameterRow& parameter, const std::string& unit);
// Whether `value` (SI) lies in the parameter's valid range; and the range as text ("(0, inf) Pa", "[0, 0.4999]").
bool in_valid_range(const MaterialParameterRow& parameter, double value);
std::string valid_range_text(const MaterialParameterRow& parameter);
const ElementLawRow& element_law_row(int law);
// The row whose model_keyword (or trade_name) is `name`; null when none is.
const ElementLawRow* element_law_by_model_keyword(const std::string& name);
// The law `fem: {law: NAME}` selects: a row with that keyword that is a model of its own (not beside springs); null
// when none is.
const ElementLawRow* fem_law_by_keyword(const std::string& name);
// The keywords fem_law_by_keyword accepts, in the registry's order (for errors and docs).
std::vector<std::string> fem_law_keywords();
const ElementLawRow* element_law_by_trade_name(const std::string& name);
// The law a spring network takes beside it (beside_springs).
const ElementLawRow& element_law_beside_springs();
// The finite-element model messages recommend and a model built without a law takes: the first row with a
// model_keyword.
const ElementLawRow& default_fem_law();

// The element kinds' registry: one row per kernels::ElementKinds entry, in the same order. `fem: {element: KEYWORD}`
// in scene files selects a kind by its keyword; nothing outside a kind's kernels header, kernels/element_laws.h and
// runtime/fem's registry and geometry builders names it.
struct ElementKindRow {
  const char* keyword;      // fem: {element: KEYWORD}
  const char* description;  // one line for docs and errors, with its source
  int kind;                 // index in kernels::ElementKinds
  int vtk_cell_type;        // frames write the elements' nodes as this VTK cell (10: VTK_TETRA, 24: quadratic)
  double largest_poisson_ratio;  // a larger material.poisson_ratio is an error on this kind
  // Above this ratio the kind locks (too stiff): build_fem_model warns with `locking_note`; 1: it does not.
  double locking_poisson_ratio;
  const char* locking_note;  // the measured error the warning quotes (docs/validation.md)
};

// Every row, in kernels::ElementKinds' order.
const std::vector<ElementKindRow>& element_kind_rows();
const ElementKindRow& element_kind_row(int kind);
// The row with keyword `name`; null when none has it.
const ElementKindRow* element_kind_by_keyword(const std::string& name);
// The kind `model: corotational_fem` and a `fem` map without `element` take: the first row.
const ElementKindRow& default_element_kind();
std::vector<std::string> element_kind_keywords();

// What the engines do not run yet for an element kind (docs/simulator.md, "Element kinds"): each a reason that
// completes "fem.element KEYWORD ...", null where they run it. It follows from the kind's kernels (a kind with a
// nodal pass, kernels::element_kind_has_nodal_pass, runs every integrator on the CPU and the explicit ones on CUDA,
// whose matrix-free conjugate gradient has no nodal term yet), so that the engines' refusals, the scene's backend
// choice, fmpc trade's skipped variants and the tests that visit every kind read one answer.
struct ElementKindLimits {
  const char* cuda = nullptr;                 // the CUDA backend, any integrator (no kind today)
  const char* cuda_implicit_euler = nullptr;  // integrator: implicit_euler on the CUDA backend
  const char* implicit_euler = nullptr;       // integrator: implicit_euler on either backend (no kind today)
  const char* strain_table = nullptr;         // a Young's modulus bound to strain (a strain table)
};
ElementKindLimits element_kind_limits(int kind);
// The reason the CUDA backend does not run `limits`' kind with implicit Euler (implicit_euler true) or an explicit
// integrator: cuda, else for implicit Euler cuda_implicit_euler or implicit_euler; null where it runs it.
const char* cuda_refusal(const ElementKindLimits& limits, bool implicit_euler);

// Springs plus the volume term reaching a Young's modulus E and Poisson ratio nu (docs/simulator.md): a central
// spring network obeys the Cauchy relation lambda = mu, with mu = 2 E_s / 5 for the Van Gelder mapping at E_s (the
// bulk modulus 2 E_s / 3 is exact for every tetrahedron, docs/simulator.md) and 24/25 of it for Lloyd's. The springs
// take E_s so that their mu is the target's, the volume term the rest of lambda: kappa = lambda - mu =
// E (4 nu - 1) / (2 (1 + nu)(1 - 2 nu)). nu below 1/4 would need a negative kappa: an error naming the field.
struct VolumeTermCalibration {
  double spring_modulus = 0.0;  // E_s, Pa, for the spring mapping
  double bulk_modulus = 0.0;    // kappa, Pa
};
std::optional<VolumeTermCalibration> calibrate_volume_term(double youngs_modulus, double poisson_ratio,
                                                           StiffnessMapping mapping, const SourceRange& where,
                                                           DiagnosticList& diagnostics);

}  // namespace fmpc::sim
