#pragma once
// The volume term (kernels/laws/volume_preservation.h) with one bulk modulus for every element, added to a setup
// whose tetrahedra are set: what the tests that build spring setups by hand need. Header-only, so that the GPU
// tests (which do not link tests/support) use it too.
#include <utility>

#include "kernels/element_laws.h"
#include "runtime/fem/fem_model_builder.h"

namespace fmpc::sim {

inline bool add_volume_term(SimulationSetup& setup, double bulk_modulus, double damping_ratio,
                            double rayleigh_stiffness, DiagnosticList& diagnostics) {
  ElementTerm term;
  term.law = kernels::element_law_index<kernels::VolumePreservation>;
  term.parameter[kernels::VolumePreservation::kBulkModulus].assign(setup.tetrahedra.size(), bulk_modulus);
  return add_element_term(setup, std::move(term), damping_ratio, rayleigh_stiffness, diagnostics);
}

}  // namespace fmpc::sim
