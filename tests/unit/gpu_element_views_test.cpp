// The GPU's compact element views without a GPU (runtime/gpu/batch_concatenation.h): an array whose entries all have
// the same bits travels as that one value (per_element_of), the corner slots as a byte per node (corner_ranks) and
// Dm^-1 as a byte per element into a table of the mesh's shapes (rest_shapes); the element pass, run here on the host
// as the CUDA kernel runs it, writes the same bits through either view.
#include <catch2/catch.hpp>
#include <cstring>
#include <random>
#include <type_traits>
#include <vector>

#include "kernels/element_laws.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/gpu/batch_concatenation.h"
#include "tests/support/viscoelastic_box.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

template <typename Real>
std::vector<Real> in(const std::vector<double>& values) {
  return std::vector<Real>(values.begin(), values.end());
}

template <typename Real>
bool same_bits(const std::vector<kernels::CornerForce<Real>>& a, const std::vector<kernels::CornerForce<Real>>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
}

// Every element's node forces through `arrays` (per-element arrays, int slots) and through the GPU's packed view of
// the same values, at seeded positions, velocities and nodal pressures: the same bits.
template <typename Real>
void check_packed_view(const SimulationSetup& setup, const ElementTerm& term, bool expect_uniform_damping) {
  const ElementGeometry& geometry = setup.elements.geometry;
  const std::vector<SimulationSetup> scenes{setup};
  const gpu::ConcatenatedScenes c = gpu::concatenate(scenes);
  const gpu::HostArray<unsigned char> ranks = gpu::corner_ranks(c);
  REQUIRE(ranks.size() == geometry.nodes.size());
  const std::vector<Real> rest_inverse = in<Real>(geometry.rest_inverse);
  // One rest volume for every element (a regular grid's): the packed view holds it as one value.
  const std::vector<Real> rest_volume(geometry.size(), static_cast<Real>(geometry.rest_volume.front()));
  std::vector<Real> parameter[kernels::kMostLawParameters];
  for (int p = 0; p < kernels::kMostLawParameters; ++p) parameter[p] = in<Real>(term.parameter[p]);
  const std::vector<Real> damping = in<Real>(term.stiffness_damping);

  // The view as the CPU engine builds it (per-element arrays, int slots), over this test's arrays in Real.
  kernels::ElementTermView<Real> arrays{};
  for (int p = 0; p < kernels::kMostLawParameters; ++p)
    arrays.parameter[p] = parameter[p].empty() ? nullptr : parameter[p].data();
  arrays.stiffness_damping = damping.empty() ? nullptr : damping.data();
  arrays.rest_inverse = rest_inverse.data();
  arrays.rest_volume = rest_volume.data();
  arrays.law = term.law;
  arrays.element = geometry.kind;
  arrays.count = static_cast<int>(geometry.size());
  arrays.corners = geometry.nodes.data();
  arrays.corner_slot = geometry.corner_slot.data();

  kernels::ElementTermView<Real> packed = arrays;
  packed.corner_slot = nullptr;  // the slots come from the ranks alone
  packed.corner_rank = ranks.data();
  packed.corner_offset = c.corner_offset.data();
  // Dm^-1 from the table of the box's shapes (rest_inverse_of), the same bits as each element's own.
  gpu::HostArray<Real> table;
  gpu::HostArray<unsigned char> shape;
  REQUIRE(gpu::rest_shapes(rest_inverse, table, shape));
  REQUIRE(shape.size() == geometry.size());
  // In float the box's 162 elements share few shapes; in double their last bits may differ (a longer table, as exact).
  if (std::is_same_v<Real, float>) CHECK(table.size() < rest_inverse.size() / 2);
  packed.rest_inverse = table.data();
  packed.rest_shape = shape.data();
  packed.rest_volume = gpu::per_element_of(rest_volume, rest_volume.data(), true);
  CHECK(packed.rest_volume.values == nullptr);
  for (int p = 0; p < kernels::kMostLawParameters; ++p) {
    if (parameter[p].empty()) continue;
    packed.parameter[p] = gpu::per_element_of(parameter[p], parameter[p].data(), true);
    CHECK(packed.parameter[p].values == nullptr);  // one material: one value
  }
  packed.stiffness_damping = gpu::per_element_of(damping, damping.data(), true);
  CHECK((packed.stiffness_damping.values == nullptr) == expect_uniform_damping);

  const std::size_t vertices = setup.rest_positions.size();
  std::mt19937 random(2611);
  std::uniform_real_distribution<double> jitter(-2e-3, 2e-3), speed(-0.5, 0.5), pressure(-300.0, 300.0);
  std::vector<Real> state[6], nodal_pressure(vertices), nodal_dilatation(vertices);
  for (auto& values : state) values.resize(vertices);
  for (std::size_t v = 0; v < vertices; ++v) {
    for (std::size_t i = 0; i < 3; ++i) {
      state[i][v] = static_cast<Real>(setup.rest_positions[v][i] + jitter(random));
      state[3 + i][v] = static_cast<Real>(speed(random));
    }
    nodal_pressure[v] = static_cast<Real>(pressure(random));
    nodal_dilatation[v] = static_cast<Real>(pressure(random) * 1e-4);
  }
  arrays.nodal_pressure = packed.nodal_pressure = nodal_pressure.data();
  arrays.nodal_dilatation = packed.nodal_dilatation = nodal_dilatation.data();
  const kernels::StateView<Real> s{state[0].data(), state[1].data(), state[2].data(),
                                   state[3].data(), state[4].data(), state[5].data()};

  std::vector<kernels::CornerForce<Real>> through_arrays(geometry.nodes.size()), through_packed(geometry.nodes.size());
  kernels::visit_element_term(geometry.kind, term.law, [&](auto kind, auto law) {
    using Element = decltype(kind);
    using Law = decltype(law);
    for (int e = 0; e < arrays.count; ++e) {
      kernels::element_node_forces<Element, Law, false>(e, arrays, s, through_arrays.data());
      kernels::element_node_forces<Element, Law, false>(e, packed, s, through_packed.data());
    }
    // A second term adds to the slots (Accumulate), through the same slots.
    for (int e = 0; e < arrays.count; ++e) {
      kernels::element_node_forces<Element, Law, true>(e, arrays, s, through_arrays.data());
      kernels::element_node_forces<Element, Law, true>(e, packed, s, through_packed.data());
    }
  });
  CHECK(same_bits(through_arrays, through_packed));
  bool moves = false;
  for (const auto& f : through_arrays) moves = moves || f.x != Real(0);
  CHECK(moves);
}

}  // namespace

TEST_CASE("the GPU's element views: one value for equal entries, byte ranks for the slots, shapes for Dm^-1, same bits",
          "[fem][gpu]") {
  for (const ElementKindRow& kind : element_kind_rows()) {
    // A 3^3-cell box, damped (elastic: no Prony terms).
    DiagnosticList built;
    const std::optional<SimulationSetup> box = viscoelastic_box(3, 3, 3, {}, built, kind.kind);
    REQUIRE(box);
    const SimulationSetup& setup = *box;
    for (const ElementLawRow& row : element_law_rows()) {
      ElementMaterial material;
      material.youngs_modulus.assign(setup.elements.geometry.size(), 5000.0);
      material.poisson_ratio.assign(setup.elements.geometry.size(), 0.3);
      DiagnosticList diagnostics;
      auto build = row.build(material, diagnostics);
      REQUIRE(build);
      ElementTerm term = build->term;
      // A value per element (the box's own, varied: in float its congruent elements' values coincide), one value, and
      // zero everywhere.
      std::vector<double> varying = setup.elements.terms.front().stiffness_damping;
      REQUIRE(varying.size() == setup.elements.geometry.size());
      for (std::size_t e = 0; e < varying.size(); ++e) varying[e] *= 1.0 + 0.01 * static_cast<double>(e % 7);
      for (const int damping : {0, 1, 2}) {
        INFO("element kind " << kind.keyword << ", law " << row.keyword << ", damping " << damping);
        if (damping == 0) term.stiffness_damping = varying;
        if (damping == 1) term.stiffness_damping.assign(varying.size(), 0.013);
        if (damping == 2) term.stiffness_damping.assign(varying.size(), 0.0);
        check_packed_view<double>(setup, term, damping != 0);
        check_packed_view<float>(setup, term, damping != 0);
      }
    }
  }
}

TEST_CASE(
    "per_element_of holds one value only where every entry has the same bits; rest_shapes and corner_ranks "
    "only within a byte",
    "[fem][gpu]") {
  const std::vector<float> same(5, 2.5f), different = {2.5f, 2.5f, 2.5000002f}, signs = {0.0f, -0.0f}, zeros(4, 0.0f),
                                          none;
  const float held[1] = {0.0f};
  const float* device = held;  // where the values would be on the device: only handed back
  const kernels::PerElement<float> one = gpu::per_element_of(same, device, true);
  CHECK(one.values == nullptr);
  CHECK(one[3] == 2.5f);
  CHECK(static_cast<bool>(one));
  CHECK(gpu::per_element_of(different, device, true).values == device);
  CHECK(gpu::per_element_of(signs, device, true).values == device);  // -0 is not +0's bits
  CHECK(gpu::per_element_of(same, device, false).values == device);  // GpuOptions::compact_element_views off
  const kernels::PerElement<float> zero = gpu::per_element_of(zeros, device, true),
                                   absent = gpu::per_element_of(none, device, true);
  CHECK(zero.values == nullptr);
  CHECK_FALSE(static_cast<bool>(zero));  // zero damping everywhere: undamped, velocities not read
  CHECK(absent.values == nullptr);
  CHECK_FALSE(static_cast<bool>(absent));
  CHECK(absent[7] == 0.0f);

  // 256 distinct Dm^-1 are a table; 257 are not (the views keep Dm^-1 per element).
  for (const std::size_t count : {256u, 257u}) {
    std::vector<double> rest_inverse(9 * count, 1.0);
    for (std::size_t e = 0; e < count; ++e) rest_inverse[9 * e + 4] = 1.0 + static_cast<double>(e);
    rest_inverse.insert(rest_inverse.end(), rest_inverse.begin(), rest_inverse.begin() + 9);  // element 0's again
    gpu::HostArray<double> table;
    gpu::HostArray<unsigned char> shape;
    const bool shared = gpu::rest_shapes(rest_inverse, table, shape);
    CHECK(shared == (count == 256));
    if (shared) {
      CHECK(table.size() == 9 * count);
      CHECK(shape.back() == 0);
      CHECK(shape[255] == 255);
    } else {
      CHECK(table.empty());
      CHECK(shape.empty());
    }
  }

  // One vertex with `corners` entries: ranks 0 .. corners - 1.
  for (const int corners : {256, 257}) {
    gpu::ConcatenatedScenes c;
    c.nodes.assign(static_cast<std::size_t>(corners), 0);
    c.corner_offset = {0, corners};
    c.corner_slot.resize(static_cast<std::size_t>(corners));
    for (int k = 0; k < corners; ++k) c.corner_slot[static_cast<std::size_t>(k)] = k;
    const gpu::HostArray<unsigned char> ranks = gpu::corner_ranks(c);
    if (corners == 256) {
      REQUIRE(ranks.size() == 256);
      CHECK(ranks.back() == 255);
    } else {
      CHECK(ranks.empty());  // the element pass reads corner_slot
    }
  }
}
