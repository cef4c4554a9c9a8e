#include "runtime/integrate/model_tangent.h"

#include "kernels/implicit_math.h"
#include "kernels/element_laws.h"
#include "runtime/integrate/nodal_pressure_tangent.h"

namespace fmpc::sim {

namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

// A spring's symmetric block at its two ends: +block on (a, a) and (b, b), -block on (a, b) and (b, a).
void add_spring_block(Triplets& out, std::size_t a, std::size_t b, const double* block) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      const double entry = block[kernels::symmetric_index(r, c)];
      const auto ra = static_cast<int>(3 * a) + r, rb = static_cast<int>(3 * b) + r;
      const auto ca = static_cast<int>(3 * a) + c, cb = static_cast<int>(3 * b) + c;
      out.emplace_back(ra, ca, entry);
      out.emplace_back(rb, cb, entry);
      out.emplace_back(ra, cb, -entry);
      out.emplace_back(rb, ca, -entry);
    }
  }
}

// The nodal pass's volumetric tangent (nodal_pressure_tangent.h) as a matrix: B^T D B, B's row n the gradient g_n
// of node n's volume, D = diag(D_n). Zero for a kind without a nodal pass.
Eigen::SparseMatrix<double> nodal_pressure_tangent(const SimulationSetup& setup, const std::vector<Point3>& positions) {
  const std::size_t n = positions.size();
  Eigen::SparseMatrix<double> out(static_cast<Eigen::Index>(3 * n), static_cast<Eigen::Index>(3 * n));
  NodalPressureTangent nodal(setup);
  if (!nodal.active()) return out;
  std::vector<double> x(3 * n);
  for (std::size_t v = 0; v < n; ++v)
    for (std::size_t i = 0; i < 3; ++i) x[3 * v + i] = positions[v][i];
  nodal.evaluate(x.data(), nullptr);
  Triplets gradient;
  Eigen::VectorXd D(static_cast<Eigen::Index>(n));
  for (std::size_t v = 0; v < n; ++v) {
    D[static_cast<Eigen::Index>(v)] = nodal.modulus(v);
    for (std::size_t k = nodal.patch_begin(v); k < nodal.patch_end(v); ++k)
      for (int i = 0; i < 3; ++i)
        gradient.emplace_back(static_cast<int>(v), 3 * nodal.patch_vertex(k) + i, nodal.gradient(k)[i]);
  }
  Eigen::SparseMatrix<double> B(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(3 * n));
  B.setFromTriplets(gradient.begin(), gradient.end());
  out = B.transpose() * D.asDiagonal() * B;
  return out;
}

}  // namespace

ModelTangent model_tangent(const SimulationSetup& setup, const std::vector<Point3>& positions,
                           const std::vector<double>& spring_stiffness) {
  const auto dofs = static_cast<Eigen::Index>(3 * positions.size());
  Triplets stiffness, damping;
  const SpringNetwork& net = setup.springs;
  const std::size_t elements = setup.elements.empty() ? 0 : setup.elements.geometry.size();
  const std::size_t element_entries =
      setup.elements.empty() ? 0 : 9 * setup.elements.geometry.nodes.size() * setup.elements.geometry.nodes_per_element;
  stiffness.reserve(36 * net.size() + element_entries * setup.elements.terms.size());
  damping.reserve(36 * net.size() + element_entries * setup.elements.terms.size());
  const kernels::SpringLawParameters<double> law{setup.law, setup.basafa_k2_over_k1, setup.basafa_xc};
  for (std::size_t s = 0; s < net.size(); ++s) {
    const auto a = static_cast<std::size_t>(net.first[s]), b = static_cast<std::size_t>(net.second[s]);
    const double c = net.damping.empty() ? 0.0 : net.damping[s];
    // h = 1 and c = 0 make implicit_spring_blocks' system block the stiffness block; the dashpot is c u u^T.
    double k_block[6], unused[6], d_block[6];
    const double dx = positions[b][0] - positions[a][0], dy = positions[b][1] - positions[a][1],
                 dz = positions[b][2] - positions[a][2];
    if (!kernels::implicit_spring_blocks(dx, dy, dz, net.rest_length[s], spring_stiffness[s], 0.0, law, 1.0, k_block,
                                         unused))
      continue;
    add_spring_block(stiffness, a, b, k_block);
    if (c == 0.0) continue;
    const double length = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double u[3] = {dx / length, dy / length, dz / length};
    for (int r = 0; r < 3; ++r)
      for (int col = r; col < 3; ++col) d_block[kernels::symmetric_index(r, col)] = c * u[r] * u[col];
    add_spring_block(damping, a, b, d_block);
  }
  const ElementTangents tangents(setup);
  const auto nodes = static_cast<std::size_t>(tangents.nodes()), size = 3 * nodes;
  std::vector<double> x(3 * nodes), K(size * size);
  for (std::size_t term = 0; term < tangents.term_count(); ++term) {
    for (std::size_t e = 0; e < elements; ++e) {
      const std::int32_t* node = tangents.element_nodes(e);
      for (std::size_t a = 0; a < nodes; ++a)
        for (std::size_t i = 0; i < 3; ++i) x[3 * a + i] = positions[static_cast<std::size_t>(node[a])][i];
      const double beta = tangents.stiffness(term, e, x.data(), K.data());
      for (std::size_t row = 0; row < size; ++row) {
        for (std::size_t column = 0; column < size; ++column) {
          const auto global_row = static_cast<int>(3 * static_cast<std::size_t>(node[row / 3]) + row % 3);
          const auto global_column = static_cast<int>(3 * static_cast<std::size_t>(node[column / 3]) + column % 3);
          const double entry = K[size * row + column];
          stiffness.emplace_back(global_row, global_column, entry);
          if (beta != 0.0) damping.emplace_back(global_row, global_column, beta * entry);
        }
      }
    }
  }
  ModelTangent tangent;
  tangent.stiffness.resize(dofs, dofs);
  tangent.damping.resize(dofs, dofs);
  tangent.stiffness.setFromTriplets(stiffness.begin(), stiffness.end());
  if (!setup.elements.empty() && kernels::element_kind_has_nodal_pass(setup.elements.geometry.kind))
    tangent.stiffness += nodal_pressure_tangent(setup, positions);
  tangent.damping.setFromTriplets(damping.begin(), damping.end());
  return tangent;
}

ElementTangents::ElementTangents(const SimulationSetup& setup) : geometry_(setup.elements.geometry) {
  if (setup.strain_stiffness) table_ = strain_table_view(*setup.strain_stiffness);
  for (std::size_t term = 0; term < setup.elements.terms.size(); ++term)
    views_.push_back(element_term_view(setup.elements, term, &table_));
}

double ElementTangents::stiffness(std::size_t term, std::size_t e, const double* x, double* K,
                                  const ElementLinearisations* held) const {
  const kernels::ElementTermView<double>& view = views_[term];
  kernels::visit_element_term(view.element, view.law, [&](auto kind, auto element_law) {
    using Element = decltype(kind);
    using Law = decltype(element_law);
    using Lin = typename Element::template Linearisation<Law>;
    constexpr int N = Element::kNodes;
    Lin lin{};
    if (held != nullptr && held->holds<Lin>(term)) {
      held->load(term, e, lin);
    } else {
      double nodes[N][3];
      for (int a = 0; a < N; ++a)
        for (int i = 0; i < 3; ++i) nodes[a][i] = x[3 * a + i];
      Element::template linearise<Law>(view, static_cast<int>(e), nodes, lin);
    }
    Element::template stiffness_matrix<Law>(view, static_cast<int>(e), lin, K);
  });
  return view.stiffness_damping[e];
}

}  // namespace fmpc::sim
