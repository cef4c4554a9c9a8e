#include "runtime/fem/element_law_registry.h"

#include <cmath>
#include <limits>
#include <string>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

namespace {

// The largest Poisson ratio a law given by E and nu takes (its lambda is infinite at 0.5); the element kind may take
// less (element_kind_rows()).
constexpr double kLargestPoissonRatio = 0.4999;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// What the laws given by Young's modulus and Poisson's ratio read (IsotropicModuli).
std::vector<MaterialParameterRow> youngs_modulus_and_poisson_ratio(double lowest_ratio, double highest_ratio) {
  using Quantity = MaterialParameterRow::Quantity;
  return {
      {"youngs_modulus", "Young's modulus", Quantity::Pressure, 0.0, kInfinity, false, false,
       &ElementMaterial::youngs_modulus},
      {"poisson_ratio", "Poisson ratio", Quantity::Dimensionless, lowest_ratio, highest_ratio, true, true,
       &ElementMaterial::poisson_ratio},
  };
}

// A law whose parameters are Young's modulus and Poisson's ratio per element (kYoungsModulus, kPoissonRatio): both
// checked, nu in [0, 0.4999] (the element kind's own limit is build_fem_model's).
template <typename Law>
std::optional<ElementLawBuild> build_youngs_modulus_and_poisson_ratio(const ElementMaterial& material,
                                                                      DiagnosticList& diagnostics) {
  const std::size_t count = material.youngs_modulus.size();
  for (std::size_t e = 0; e < count; ++e) {
    const double youngs = material.youngs_modulus[e], poisson = material.poisson_ratio[e];
    if (!(youngs > 0.0) || !std::isfinite(youngs)) {
      diagnostics.error(material.where, "tetrahedron " + std::to_string(e) + ": Young's modulus " +
                                            format_number(youngs) +
                                            " Pa is not a positive, finite number; fix the material value");
      return std::nullopt;
    }
    // The law's own range; the element kind's (linear tetrahedra: 0.499) is checked by build_fem_model.
    if (!(poisson >= 0.0 && poisson <= kLargestPoissonRatio)) {
      diagnostics.error(material.where, "tetrahedron " + std::to_string(e) + ": Poisson ratio " +
                                            format_number(poisson) +
                                            " is outside [0, 0.4999] (0.5 is incompressible: the law's lambda is "
                                            "infinite there)");
      return std::nullopt;
    }
  }
  ElementLawBuild build;
  build.term.law = kernels::element_law_index<Law>;
  build.term.parameter[Law::kYoungsModulus] = material.youngs_modulus;
  build.term.parameter[Law::kPoissonRatio] = material.poisson_ratio;
  return build;
}

// One ratio for the whole term (the caller refuses a ratio per region): kappa per element scales with its E.
std::optional<ElementLawBuild> build_volume_preservation(const ElementMaterial& material, DiagnosticList& diagnostics) {
  using Law = kernels::VolumePreservation;
  const double poisson = material.poisson_ratio.empty() ? 0.0 : material.poisson_ratio.front();
  // The calibration is linear in E: its factors at E = 1 Pa scale the springs and give kappa per unit modulus.
  const auto unit = calibrate_volume_term(1.0, poisson, material.spring_mapping, material.where, diagnostics);
  if (!unit) return std::nullopt;
  ElementLawBuild build;
  build.term.law = kernels::element_law_index<Law>;
  std::vector<double>& kappa = build.term.parameter[Law::kBulkModulus];
  kappa.resize(material.youngs_modulus.size());
  for (std::size_t e = 0; e < kappa.size(); ++e) kappa[e] = unit->bulk_modulus * material.youngs_modulus[e];
  build.spring_modulus_scale = unit->spring_modulus;
  build.description = "; volume term (Teschner et al. 2004) for nu = " + format_number(poisson) + ": springs at " +
                      format_number(unit->spring_modulus) + " E, kappa = " + format_number(unit->bulk_modulus) + " E";
  return build;
}

}  // namespace

const std::vector<ElementLawRow>& element_law_rows() {
  static const std::vector<ElementLawRow> rows = {
      {"corotational", "corotational_fem", false, "corotational_fem", "FEM",
       "co-rotational linear elasticity on linear tetrahedra (Mueller & Gross 2004; Nesme, Payan & Faure 2005), "
       "E and nu per element, E optionally from a strain table",
       kernels::element_law_index<kernels::CorotationalLinear>, kernels::CorotationalLinear::kStressOutput,
       build_youngs_modulus_and_poisson_ratio<kernels::CorotationalLinear>,
       youngs_modulus_and_poisson_ratio(0.0, kLargestPoissonRatio)},
      {"volume_preservation", nullptr, true, "springs_volume_term", "springs+volume",
       "the volume term beside springs (Teschner et al. 2004), kappa calibrated with the springs to E and nu",
       kernels::element_law_index<kernels::VolumePreservation>, kernels::VolumePreservation::kStressOutput,
       build_volume_preservation, youngs_modulus_and_poisson_ratio(0.25, 0.499)},
      {"stable_neo_hookean", nullptr, false, "stable_neo_hookean", "SNH",
       "stable neo-Hookean hyperelasticity (Smith, de Goes & Kim 2018, ACM TOG 37(2)) with the paper's Lame "
       "re-parameterisation from E and nu, finite and restoring for inverted elements; E optionally from a strain "
       "table at the principal strain of largest magnitude",
       kernels::element_law_index<kernels::StableNeoHookean>, kernels::StableNeoHookean::kStressOutput,
       build_youngs_modulus_and_poisson_ratio<kernels::StableNeoHookean>,
       youngs_modulus_and_poisson_ratio(0.0, kLargestPoissonRatio)},
  };
  return rows;
}

const MaterialParameterRow* material_parameter(const ElementLawRow& row, const std::string& name) {
  for (const MaterialParameterRow& parameter : row.parameters)
    if (name == parameter.keyword) return &parameter;
  return nullptr;
}

std::optional<double> si_per_unit(const MaterialParameterRow& parameter, const std::string& unit) {
  switch (parameter.quantity) {
    case MaterialParameterRow::Quantity::Pressure:
      if (unit.empty() || unit == "kPa") return 1000.0;
      if (unit == "Pa") return 1.0;
      if (unit == "MPa") return 1e6;
      return std::nullopt;
    case MaterialParameterRow::Quantity::Dimensionless:
      if (unit.empty() || unit == "dimensionless") return 1.0;
      if (unit == "%") return 0.01;
      return std::nullopt;
  }
  return std::nullopt;
}

bool in_valid_range(const MaterialParameterRow& parameter, double value) {
  const bool above = parameter.lowest_included ? value >= parameter.lowest : value > parameter.lowest;
  const bool below = parameter.highest_included ? value <= parameter.highest : value < parameter.highest;
  return above && below;
}

std::string valid_range_text(const MaterialParameterRow& parameter) {
  const auto end = [](double v) { return std::isinf(v) ? std::string("inf") : format_number(v); };
  return std::string(parameter.lowest_included ? "[" : "(") + end(parameter.lowest) + ", " + end(parameter.highest) +
         (parameter.highest_included ? "]" : ")") +
         (parameter.quantity == MaterialParameterRow::Quantity::Pressure ? " Pa" : "");
}

const ElementLawRow& element_law_row(int law) { return element_law_rows().at(static_cast<std::size_t>(law)); }

const ElementLawRow* element_law_by_model_keyword(const std::string& name) {
  for (const ElementLawRow& row : element_law_rows())
    if (row.model_keyword != nullptr && name == row.model_keyword) return &row;
  return nullptr;
}

const ElementLawRow* element_law_by_trade_name(const std::string& name) {
  for (const ElementLawRow& row : element_law_rows())
    if (name == row.trade_name) return &row;
  return nullptr;
}

const ElementLawRow* fem_law_by_keyword(const std::string& name) {
  for (const ElementLawRow& row : element_law_rows())
    if (!row.beside_springs && name == row.keyword) return &row;
  return nullptr;
}

std::vector<std::string> fem_law_keywords() {
  std::vector<std::string> out;
  for (const ElementLawRow& row : element_law_rows())
    if (!row.beside_springs) out.emplace_back(row.keyword);
  return out;
}

const std::vector<ElementKindRow>& element_kind_rows() {
  static const std::vector<ElementKindRow> rows = {
      {"linear",
       "4-node linear tetrahedra, one point per element (Bonet & Wood, Nonlinear Continuum Mechanics for Finite "
       "Element Analysis, 2nd ed., 9.4)",
       kernels::element_kind_index<kernels::LinearTetrahedron>, 10, 0.499, 0.45,
       "docs/validation.md measures linear tetrahedra 6.4% too stiff at nu 0.45 on an 8^3-cell cube and 3.3 times too "
       "stiff on SOFA's liver at nu 0.49, against CalculiX C3D10"},
      {"quadratic",
       "10-node quadratic tetrahedra (CalculiX / Abaqus C3D10), built from the linear mesh by adding each edge's "
       "midpoint, 4-point (degree-2) quadrature, HRZ-lumped masses (1/36 at corners, 4/27 on edges; Hinton, Rock & "
       "Zienkiewicz 1976)",
       kernels::element_kind_index<kernels::QuadraticTetrahedron>, 24, 0.4999, 1.0, ""},
      {"linear_nodal_pressure",
       "4-node linear tetrahedra with the average nodal pressure of Bonet & Burton 1998: the law's shear part per "
       "element, its volumetric part lambda/2 (J - 1)^2 with J averaged over each node's elements, so that "
       "nearly incompressible materials do not lock on a linear mesh",
       kernels::element_kind_index<kernels::LinearNodalPressure>, 10, 0.4999, 1.0, ""},
  };
  return rows;
}

const ElementKindRow& element_kind_row(int kind) { return element_kind_rows().at(static_cast<std::size_t>(kind)); }

const ElementKindRow* element_kind_by_keyword(const std::string& name) {
  for (const ElementKindRow& row : element_kind_rows())
    if (name == row.keyword) return &row;
  return nullptr;
}

const ElementKindRow& default_element_kind() { return element_kind_rows().front(); }

std::vector<std::string> element_kind_keywords() {
  std::vector<std::string> out;
  for (const ElementKindRow& row : element_kind_rows()) out.emplace_back(row.keyword);
  return out;
}

ElementKindLimits element_kind_limits(int kind) {
  ElementKindLimits limits;
  if (kernels::element_kind_has_nodal_pass(kind)) {
    limits.cuda_implicit_euler = "runs implicit_euler on the CPU backend only for now (the CUDA engine's matrix-free "
                                 "conjugate gradient has no nodal pressure term yet); the explicit integrators run "
                                 "on both";
    // A modulus that follows the strain would change the split between the shear part and the nodal pressure
    // (kernels/laws/isotropic_moduli.h, shear_part).
    limits.strain_table = "takes a constant or regional Young's modulus, not a strain table";
  }
  return limits;
}

const char* cuda_refusal(const ElementKindLimits& limits, bool implicit_euler) {
  if (limits.cuda || !implicit_euler) return limits.cuda;
  return limits.cuda_implicit_euler ? limits.cuda_implicit_euler : limits.implicit_euler;
}

const ElementLawRow& element_law_beside_springs() {
  for (const ElementLawRow& row : element_law_rows())
    if (row.beside_springs) return row;
  return element_law_rows().front();
}

const ElementLawRow& default_fem_law() {
  for (const ElementLawRow& row : element_law_rows())
    if (row.model_keyword != nullptr) return row;
  return element_law_rows().front();
}

std::optional<VolumeTermCalibration> calibrate_volume_term(double youngs_modulus, double poisson_ratio,
                                                           StiffnessMapping mapping, const SourceRange& where,
                                                           DiagnosticList& diagnostics) {
  if (!(poisson_ratio >= 0.25 && poisson_ratio <= 0.499)) {
    diagnostics.error(where, "material.poisson_ratio: " + format_number(poisson_ratio) +
                                 " cannot be reached by springs with the volume term: central springs have nu = 1/4 "
                                 "(Cauchy relation lambda = mu) and the volume term can only add to lambda; give a "
                                 "ratio in [0.25, 0.499], or use model: corotational_fem for any ratio in [0, 0.499]");
    return std::nullopt;
  }
  if (mapping != StiffnessMapping::VanGelder1998 && mapping != StiffnessMapping::LloydSzekelyHarders2007) {
    diagnostics.error(where,
                      "the volume term needs a Young's modulus mapping (van_gelder_1998 or "
                      "lloyd_szekely_harders_2007) for the springs beside it");
    return std::nullopt;
  }
  double mu = 0.0, lambda = 0.0;
  kernels::lame_parameters(youngs_modulus, poisson_ratio, mu, lambda);
  // mu_springs = (2/5) c E_s with c = 1 (Van Gelder) or 24/25 (Lloyd).
  const double c = mapping == StiffnessMapping::LloydSzekelyHarders2007 ? 24.0 / 25.0 : 1.0;
  VolumeTermCalibration calibration;
  calibration.spring_modulus = 2.5 * mu / c;
  calibration.bulk_modulus = lambda - mu;
  return calibration;
}

}  // namespace fmpc::sim
