#pragma once
// A 0.1 m box of 5 kPa tissue (1060 kg/m^3, nu 0.45, damping ratio 0.3) with a Prony series, hanging from its top
// face under gravity, on elements of kind `element` (index in kernels::ElementKinds): the viscoelastic scene of the CPU and GPU tests (tests/unit/viscoelastic_test.cpp, tests/gpu/
// gpu_viscoelastic_test.cpp). Header-only, so that the GPU tests (which do not link tests/support) use it too.
#include <cstdint>
#include <optional>
#include <vector>

#include "runtime/fem/fem_model_builder.h"
#include "runtime/mesh/generated_mesh.h"

namespace fmpc::sim {

inline std::optional<SimulationSetup> viscoelastic_box(int nx, int ny, int nz, const std::vector<PronyTerm>& prony,
                                                       DiagnosticList& diagnostics, int element = 0) {
  BoxSpec box;
  box.cells_x = nx;
  box.cells_y = ny;
  box.cells_z = nz;
  box.size = {0.1, 0.1, 0.1};
  const Mesh mesh = generate_box(box, diagnostics);
  FemModelSpec spec;
  spec.youngs_modulus = {5000.0};
  spec.poisson_ratio = {0.45};
  spec.mass.value = 1060.0;
  spec.damping_ratio = 0.3;
  spec.prony = prony;
  spec.element = element;
  auto setup = build_fem_model(mesh, spec, diagnostics);
  if (!setup) return std::nullopt;
  for (std::size_t v = 0; v < setup->rest_positions.size(); ++v)
    if (setup->rest_positions[v][1] > 0.0999) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
  setup->gravity = {0.0, -9.81, 0.0};
  return setup;
}

}  // namespace fmpc::sim
