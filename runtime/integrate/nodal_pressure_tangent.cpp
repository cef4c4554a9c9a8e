#include "runtime/integrate/nodal_pressure_tangent.h"

#include <algorithm>

#include "kernels/element_laws.h"
#include "runtime/fem/element_terms.h"

namespace fmpc::sim {

namespace {

// Runs task(begin, end) over [0, count) on the pool, or on this thread.
void run_on(WorkerPool* pool, std::size_t count, const std::function<void(std::size_t, std::size_t)>& task) {
  if (pool != nullptr) {
    pool->run(count, task);
  } else {
    task(0, count);
  }
}

}  // namespace

NodalPressureTangent::NodalPressureTangent(const SimulationSetup& setup) : setup_(setup) {
  if (setup.elements.empty() || !kernels::element_kind_has_nodal_pass(setup.elements.geometry.kind)) return;
  const ElementGeometry& geometry = setup.elements.geometry;
  const std::size_t n = setup.rest_positions.size(), N = static_cast<std::size_t>(geometry.nodes_per_element);
  // Each node's patch: the nodes of its elements, sorted and unique.
  patch_offset_.assign(n + 1, 0);
  std::vector<std::int32_t> patch;
  for (std::size_t v = 0; v < n; ++v) {
    patch.clear();
    for (auto k = geometry.corner_offset[v]; k < geometry.corner_offset[v + 1]; ++k) {
      const std::size_t e = static_cast<std::size_t>(geometry.corner_index[static_cast<std::size_t>(k)]) / N;
      patch.insert(patch.end(), geometry.nodes.begin() + static_cast<std::ptrdiff_t>(N * e),
                   geometry.nodes.begin() + static_cast<std::ptrdiff_t>(N * e + N));
    }
    std::sort(patch.begin(), patch.end());
    patch.erase(std::unique(patch.begin(), patch.end()), patch.end());
    patch_vertex_.insert(patch_vertex_.end(), patch.begin(), patch.end());
    patch_offset_[v + 1] = static_cast<std::int32_t>(patch_vertex_.size());
  }
  corner_patch_entry_.resize(N * geometry.corner_index.size());
  for (std::size_t v = 0; v < n; ++v)
    for (auto k = static_cast<std::size_t>(geometry.corner_offset[v]);
         k < static_cast<std::size_t>(geometry.corner_offset[v + 1]); ++k) {
      const std::size_t e = static_cast<std::size_t>(geometry.corner_index[k]) / N;
      for (std::size_t b = 0; b < N; ++b)
        corner_patch_entry_[N * k + b] = static_cast<std::int32_t>(patch_entry(v, geometry.nodes[N * e + b]));
    }
  element_gradient_.assign(3 * N * geometry.size(), 0.0);
  element_modulus_.assign(geometry.size(), 0.0);
  modulus_.assign(n, 0.0);
  gradient_.assign(3 * patch_vertex_.size(), 0.0);
}

std::size_t NodalPressureTangent::patch_entry(std::size_t n, std::int32_t v) const {
  const auto first = patch_vertex_.begin() + patch_offset_[n], last = patch_vertex_.begin() + patch_offset_[n + 1];
  return static_cast<std::size_t>(std::lower_bound(first, last, v) - patch_vertex_.begin());
}

void NodalPressureTangent::evaluate(const double* x, WorkerPool* pool) {
  if (!active()) return;
  const ElementGeometry& geometry = setup_.elements.geometry;
  const auto N = static_cast<std::size_t>(geometry.nodes_per_element);
  const kernels::StrainTableView no_table{nullptr, nullptr, 0};
  std::vector<kernels::ElementTermView<double>> views;
  for (std::size_t term = 0; term < setup_.elements.terms.size(); ++term)
    views.push_back(element_term_view(setup_.elements, term, &no_table));
  run_on(pool, geometry.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t e = begin; e < end; ++e) {
      element_modulus_[e] = 0.0;
      for (const kernels::ElementTermView<double>& view : views)
        kernels::visit_element_term(view.element, view.law, [&](auto kind, auto element_law) {
          using Element = decltype(kind);
          if constexpr (Element::kNodalPressure) {
            constexpr int M = Element::kNodes;
            double nodes[M][3], share[3];
            for (std::size_t b = 0; b < N; ++b)
              for (std::size_t i = 0; i < 3; ++i)
                nodes[b][i] = x[3 * static_cast<std::size_t>(geometry.nodes[N * e + b]) + i];
            Element::template nodal_shares<decltype(element_law)>(view, static_cast<int>(e), nodes, share);
            element_modulus_[e] += share[2];
            if (&view == &views.front()) {
              double dV[M][3];
              Element::volume_gradient(view, static_cast<int>(e), nodes, dV);
              for (std::size_t b = 0; b < N; ++b)
                for (std::size_t i = 0; i < 3; ++i) element_gradient_[3 * (N * e + b) + i] = dV[b][i];
            }
          }
        });
    }
  });
  run_on(pool, modulus_.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      std::fill(gradient_.begin() + 3 * static_cast<std::ptrdiff_t>(patch_begin(v)),
                gradient_.begin() + 3 * static_cast<std::ptrdiff_t>(patch_end(v)), 0.0);
      double volume = 0.0, modulus_volume = 0.0;
      for (auto k = static_cast<std::size_t>(geometry.corner_offset[v]);
           k < static_cast<std::size_t>(geometry.corner_offset[v + 1]); ++k) {
        const std::size_t e = static_cast<std::size_t>(geometry.corner_index[k]) / N;
        volume += geometry.rest_volume[e] / 4.0;
        modulus_volume += element_modulus_[e];
        for (std::size_t b = 0; b < N; ++b) {
          double* g = &gradient_[3 * static_cast<std::size_t>(corner_patch_entry_[N * k + b])];
          for (std::size_t i = 0; i < 3; ++i) g[i] += element_gradient_[3 * (N * e + b) + i] / 4.0;
        }
      }
      // D_n = K_n / V0_n with K_n = sum lambda V0 / sum V0: the shares' z over the square of their y.
      modulus_[v] = volume > 0.0 ? modulus_volume / (volume * volume) : 0.0;
    }
  });
}

}  // namespace fmpc::sim
