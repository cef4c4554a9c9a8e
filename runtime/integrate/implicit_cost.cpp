#include "runtime/integrate/implicit_cost.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/OrderingMethods>
#include <Eigen/Sparse>
#pragma GCC diagnostic pop
#include <vector>

namespace fmpc::sim {

ImplicitCost implicit_cost(const ImplicitSystem& system) {
  const std::size_t n = system.vertices();
  ImplicitCost cost;
  cost.cg_iteration = 18.0 * static_cast<double>(system.blocks()) + 14.0 * static_cast<double>(system.dofs());
  if (n == 0) return cost;
  // The vertex graph (both triangles, as the system stores it), ordered by AMD as the direct solver orders its scalar
  // system (Eigen's orderings give the inverse permutation).
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(system.blocks());
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = system.row_offset(i); k < system.row_offset(i + 1); ++k)
      entries.emplace_back(static_cast<int>(i), system.column(k), 1.0);
  Eigen::SparseMatrix<double> pattern(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  pattern.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse;
  Eigen::AMDOrdering<int>()(pattern, inverse);
  const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> permutation = inverse.inverse();
  const int* position = permutation.indices().data();
  // Each permuted column's rows above the diagonal.
  std::vector<std::vector<int>> above(n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = system.row_offset(i); k < system.row_offset(i + 1); ++k) {
      const int row = position[i], column = position[static_cast<std::size_t>(system.column(k))];
      if (row < column) above[static_cast<std::size_t>(column)].push_back(row);
    }
  // L's column counts by the elimination tree (Liu 1986; Eigen's SimplicialCholesky symbolic step): row k of L is the
  // union of the tree paths from A's entries in column k up to k.
  std::vector<int> parent(n, -1), flag(n, -1);
  std::vector<double> count(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    flag[k] = static_cast<int>(k);
    for (int i : above[k])
      for (; flag[static_cast<std::size_t>(i)] != static_cast<int>(k); i = parent[static_cast<std::size_t>(i)]) {
        if (parent[static_cast<std::size_t>(i)] == -1) parent[static_cast<std::size_t>(i)] = static_cast<int>(k);
        count[static_cast<std::size_t>(i)] += 1.0;
        flag[static_cast<std::size_t>(i)] = static_cast<int>(k);
      }
  }
  // A vertex's three scalar columns hold 3 c + 2, 3 c + 1 and 3 c entries below the diagonal, c its block count.
  for (std::size_t v = 0; v < n; ++v)
    for (int s = 0; s < 3; ++s) {
      const double length = 3.0 * count[v] + s;
      cost.factor_nonzeros += length;
      cost.direct_step += length * length;
    }
  cost.direct_step += 4.0 * cost.factor_nonzeros;
  return cost;
}

}  // namespace fmpc::sim
