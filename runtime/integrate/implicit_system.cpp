#include "runtime/integrate/implicit_system.h"

#include <algorithm>
#include <cmath>

#include "kernels/implicit_math.h"

namespace fmpc::sim {

namespace {

// The element terms' assembly runs over runs of kElementRun consecutive elements, each run scattered by one worker
// in element order. Runs that share no vertex run side by side; a greedy colouring of the runs (each, in order,
// takes the smallest colour no earlier run sharing a vertex has) gives the groups, taken in colour order, so that
// every block's sum has one order. Runs rather than single elements: consecutive elements are near each other in a
// generated or a well-numbered mesh, and a run then writes a compact set of rows, where single elements of a colour
// lie all over the matrix (each colour's pass swept the whole matrix: the 20^3 box's assembly was a third of its
// step).
constexpr std::size_t kElementRun = 64;

// `nodes`: N per element.
void colour_element_runs(const std::vector<std::int32_t>& nodes, std::size_t N, std::size_t vertex_count,
                         std::vector<std::int32_t>& order, std::vector<std::int32_t>& offsets) {
  const std::size_t elements = nodes.size() / N;
  const std::size_t runs = (elements + kElementRun - 1) / kElementRun;
  // The runs at each vertex, increasing.
  std::vector<std::vector<std::int32_t>> at(vertex_count);
  for (std::size_t e = 0; e < elements; ++e)
    for (std::size_t a = 0; a < N; ++a) {
      std::vector<std::int32_t>& list = at[static_cast<std::size_t>(nodes[N * e + a])];
      const auto run = static_cast<std::int32_t>(e / kElementRun);
      if (list.empty() || list.back() != run) list.push_back(run);
    }
  std::vector<std::int32_t> colour(runs, -1);
  std::vector<char> taken;
  for (std::size_t run = 0; run < runs; ++run) {
    taken.assign(taken.size(), 0);
    const std::size_t end = std::min(elements, (run + 1) * kElementRun);
    for (std::size_t k = N * run * kElementRun; k < N * end; ++k)
      for (const std::int32_t other : at[static_cast<std::size_t>(nodes[k])]) {
        const std::int32_t c = colour[static_cast<std::size_t>(other)];
        if (c < 0) continue;
        if (static_cast<std::size_t>(c) >= taken.size()) taken.resize(static_cast<std::size_t>(c) + 1, 0);
        taken[static_cast<std::size_t>(c)] = 1;
      }
    std::size_t chosen = 0;
    while (chosen < taken.size() && taken[chosen] != 0) ++chosen;
    colour[run] = static_cast<std::int32_t>(chosen);
  }
  const std::int32_t count = runs == 0 ? 0 : *std::max_element(colour.begin(), colour.end()) + 1;
  offsets.assign(static_cast<std::size_t>(count) + 1, 0);
  for (const std::int32_t c : colour) ++offsets[static_cast<std::size_t>(c) + 1];
  for (std::size_t c = 0; c < static_cast<std::size_t>(count); ++c) offsets[c + 1] += offsets[c];
  order.assign(runs, 0);
  std::vector<std::int32_t> next(offsets.begin(), offsets.end() - 1);
  for (std::size_t run = 0; run < runs; ++run)
    order[static_cast<std::size_t>(next[static_cast<std::size_t>(colour[run])]++)] = static_cast<std::int32_t>(run);
}

// The block of row `row` at `column` (rows list their columns in increasing order).
std::int32_t find_block(const std::vector<std::int32_t>& row_offset, const std::vector<std::int32_t>& column,
                        std::size_t row, std::int32_t wanted) {
  const auto first = column.begin() + row_offset[row], last = column.begin() + row_offset[row + 1];
  return static_cast<std::int32_t>(std::lower_bound(first, last, wanted) - column.begin());
}

}  // namespace

ImplicitSystem::ImplicitSystem(const SimulationSetup& setup, const std::vector<unsigned char>& held)
    : setup_(setup), held_(held), n_(setup.rest_positions.size()), tangents_(setup), nodal_(setup) {
  const SpringNetwork& net = setup.springs;
  const bool elements = !setup.elements.empty();
  const ElementGeometry& geometry = setup.elements.geometry;
  // Each row's columns: itself, its springs' other ends and (with element terms) its elements' other nodes.
  const auto N = static_cast<std::size_t>(tangents_.nodes());
  row_offset_.assign(n_ + 1, 0);
  std::vector<std::int32_t> scratch;
  std::vector<std::vector<std::int32_t>> rows(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    scratch.clear();
    scratch.push_back(static_cast<std::int32_t>(i));
    if (net.size() > 0)
      for (auto k = net.adjacency_offset[i]; k < net.adjacency_offset[i + 1]; ++k)
        scratch.push_back(adjacency_neighbour(net, i, static_cast<std::size_t>(k)));
    if (elements)
      for (auto k = geometry.corner_offset[i]; k < geometry.corner_offset[i + 1]; ++k) {
        const std::size_t e = static_cast<std::size_t>(geometry.corner_index[static_cast<std::size_t>(k)]) / N;
        scratch.insert(scratch.end(), geometry.nodes.begin() + static_cast<std::ptrdiff_t>(N * e),
                       geometry.nodes.begin() + static_cast<std::ptrdiff_t>(N * e + N));
      }
    // A nodal pass couples row i to the patch of every node in its own patch.
    if (nodal_.active())
      for (std::size_t k = nodal_.patch_begin(i); k < nodal_.patch_end(i); ++k) {
        const auto node = static_cast<std::size_t>(nodal_.patch_vertex(k));
        for (std::size_t m = nodal_.patch_begin(node); m < nodal_.patch_end(node); ++m)
          scratch.push_back(nodal_.patch_vertex(m));
      }
    std::sort(scratch.begin(), scratch.end());
    scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
    rows[i] = scratch;
    row_offset_[i + 1] = row_offset_[i] + static_cast<std::int32_t>(scratch.size());
  }
  column_.reserve(static_cast<std::size_t>(row_offset_[n_]));
  diagonal_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    column_.insert(column_.end(), rows[i].begin(), rows[i].end());
    diagonal_[i] = find_block(row_offset_, column_, i, static_cast<std::int32_t>(i));
  }
  rows.clear();
  rows.shrink_to_fit();
  values_.assign(9 * column_.size(), 0.0);
  if (net.size() > 0) {
    neighbour_ = adjacency_neighbours(net);
    spring_block_.resize(neighbour_.size());
    for (std::size_t i = 0; i < n_; ++i)
      for (auto k = net.adjacency_offset[i]; k < net.adjacency_offset[i + 1]; ++k)
        spring_block_[static_cast<std::size_t>(k)] =
            find_block(row_offset_, column_, i, neighbour_[static_cast<std::size_t>(k)]);
  }
  if (elements) {
    element_count_ = geometry.size();
    element_block_.resize(N * N * element_count_);
    for (std::size_t e = 0; e < element_count_; ++e) {
      const std::int32_t* node = tangents_.element_nodes(e);
      for (std::size_t a = 0; a < N; ++a)
        for (std::size_t b = 0; b < N; ++b)
          element_block_[N * N * e + N * a + b] =
              find_block(row_offset_, column_, static_cast<std::size_t>(node[a]), node[b]);
    }
    colour_element_runs(geometry.nodes, N, n_, colour_order_, colour_offset_);
  }
  if (nodal_.active()) {
    nodal_own_entry_.resize(nodal_.patch_end(n_ - 1));
    for (std::size_t i = 0; i < n_; ++i)
      for (std::size_t k = nodal_.patch_begin(i); k < nodal_.patch_end(i); ++k)
        nodal_own_entry_[k] = static_cast<std::int32_t>(
            nodal_.patch_entry(static_cast<std::size_t>(nodal_.patch_vertex(k)), static_cast<std::int32_t>(i)));
    nodal_rate_.assign(n_, 0.0);
  }
  row_touches_held_.assign(n_, 0);
  for (std::size_t i = 0; i < n_; ++i) {
    for (std::size_t axis = 0; axis < 3; ++axis) free_dofs_ += dof_held(3 * i + axis) ? 0 : 1;
    for (auto k = row_offset_[i]; k < row_offset_[i + 1]; ++k)
      if (held_[static_cast<std::size_t>(column_[static_cast<std::size_t>(k)])] != 0) row_touches_held_[i] = 1;
  }
}

void ImplicitSystem::assemble(const std::vector<double>& x, const std::vector<double>& v, const std::vector<double>& a,
                              const std::vector<double>& spring_stiffness, double h, WorkerPool& pool,
                              std::vector<double>& rhs, const ElementLinearisations* linearisations) {
  rhs.resize(dofs());
  const std::size_t chunk_count = chunks();
  const auto rows_of = [this](std::size_t chunk) {
    return std::pair<std::size_t, std::size_t>{chunk * kSystemChunkVertices,
                                               std::min(n_, (chunk + 1) * kSystemChunkVertices)};
  };
  pool.run(
      chunk_count,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t chunk = begin; chunk < end; ++chunk) {
          const auto [first, last] = rows_of(chunk);
          assemble_rows(first, last, x, v, a, spring_stiffness, h, rhs);
        }
      },
      kSystemChunksPerThread);
  for (std::size_t colour = 0; colour < colours(); ++colour) {
    const auto first = static_cast<std::size_t>(colour_offset_[colour]);
    pool.run(
        static_cast<std::size_t>(colour_offset_[colour + 1]) - first,
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t k = begin; k < end; ++k) {
            const auto run = static_cast<std::size_t>(colour_order_[first + k]);
            const std::size_t last = std::min(element_count_, (run + 1) * kElementRun);
            for (std::size_t e = run * kElementRun; e < last; ++e) assemble_element(e, x, v, h, rhs, linearisations);
          }
        },
        1);
  }
  if (nodal_.active()) {
    nodal_.evaluate(x.data(), &pool);
    pool.run(n_, [&](std::size_t begin, std::size_t end) {
      for (std::size_t node = begin; node < end; ++node) {
        double rate = 0.0;
        for (std::size_t k = nodal_.patch_begin(node); k < nodal_.patch_end(node); ++k) {
          const double* g = nodal_.gradient(k);
          const double* velocity = &v[3 * static_cast<std::size_t>(nodal_.patch_vertex(k))];
          rate += g[0] * velocity[0] + g[1] * velocity[1] + g[2] * velocity[2];
        }
        nodal_rate_[node] = nodal_.modulus(node) * rate;
      }
    });
    pool.run(
        chunk_count,
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t chunk = begin; chunk < end; ++chunk) {
            const auto [first, last] = rows_of(chunk);
            assemble_nodal_rows(first, last, h, rhs);
          }
        },
        kSystemChunksPerThread);
  }
  if (free_dofs_ == dofs()) return;
  pool.run(
      chunk_count,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t chunk = begin; chunk < end; ++chunk) {
          const auto [first, last] = rows_of(chunk);
          apply_holds(first, last, rhs);
        }
      },
      kSystemChunksPerThread);
}

void ImplicitSystem::assemble_rows(std::size_t begin, std::size_t end, const std::vector<double>& x,
                                   const std::vector<double>& v, const std::vector<double>& a,
                                   const std::vector<double>& spring_stiffness, double h, std::vector<double>& rhs) {
  const SpringNetwork& net = setup_.springs;
  const kernels::SpringLawParameters<double> law{setup_.law, setup_.basafa_k2_over_k1, setup_.basafa_xc};
  for (std::size_t i = begin; i < end; ++i) {
    std::fill(values_.begin() + 9 * row_offset_[i], values_.begin() + 9 * row_offset_[i + 1], 0.0);
    double* diagonal = &values_[9 * static_cast<std::size_t>(diagonal_[i])];
    const Point3& rest = setup_.rest_positions[i];
    const double dx0 = x[3 * i] - rest[0], dy0 = x[3 * i + 1] - rest[1], dz0 = x[3 * i + 2] - rest[2];
    const double mass = setup_.mass[i];
    const double vertex_term =
        kernels::implicit_vertex_diagonal(mass, h, setup_.nodal_damping_gamma0, setup_.nodal_damping_gamma1,
                                          std::sqrt(dx0 * dx0 + dy0 * dy0 + dz0 * dz0), setup_.mass_damping);
    double r[3];
    for (std::size_t axis = 0; axis < 3; ++axis) {
      diagonal[4 * axis] = vertex_term;
      r[axis] = h * (mass * a[3 * i + axis]);
    }
    if (net.size() > 0) {
      for (auto entry = net.adjacency_offset[i]; entry < net.adjacency_offset[i + 1]; ++entry) {
        const auto k = static_cast<std::size_t>(entry);
        const auto s = static_cast<std::size_t>(net.adjacency_spring[k]);
        const auto j = static_cast<std::size_t>(neighbour_[k]);
        double stiffness[6], system[6];
        if (!kernels::implicit_spring_blocks(x[3 * j] - x[3 * i], x[3 * j + 1] - x[3 * i + 1],
                                             x[3 * j + 2] - x[3 * i + 2], net.rest_length[s], spring_stiffness[s],
                                             net.damping.empty() ? 0.0 : net.damping[s], law, h, stiffness, system))
          continue;
        double* off = &values_[9 * static_cast<std::size_t>(spring_block_[k])];
        const double relative[3] = {v[3 * i] - v[3 * j], v[3 * i + 1] - v[3 * j + 1], v[3 * i + 2] - v[3 * j + 2]};
        double kv[3];
        kernels::symmetric_multiply(stiffness, relative, kv);
        for (int row = 0; row < 3; ++row) {
          for (int col = 0; col < 3; ++col) {
            const double entry_value = system[kernels::symmetric_index(row, col)];
            diagonal[3 * row + col] += entry_value;
            off[3 * row + col] -= entry_value;
          }
          r[row] -= h * (h * kv[row]);
        }
      }
    }
    for (std::size_t axis = 0; axis < 3; ++axis) rhs[3 * i + axis] = r[axis];
  }
}

void ImplicitSystem::assemble_element(std::size_t e, const std::vector<double>& x, const std::vector<double>& v,
                                      double h, std::vector<double>& rhs,
                                      const ElementLinearisations* linearisations) {
  constexpr std::size_t kMost = static_cast<std::size_t>(kMostElementNodes);
  const auto N = static_cast<std::size_t>(tangents_.nodes());
  const std::int32_t* node = tangents_.element_nodes(e);
  double corners[3 * kMost], velocity[3 * kMost];
  for (std::size_t c = 0; c < N; ++c)
    for (std::size_t axis = 0; axis < 3; ++axis) {
      corners[3 * c + axis] = x[3 * static_cast<std::size_t>(node[c]) + axis];
      velocity[3 * c + axis] = v[3 * static_cast<std::size_t>(node[c]) + axis];
    }
  const std::size_t size = 3 * N;
  for (std::size_t term = 0; term < tangents_.term_count(); ++term) {
    double K[9 * kMost * kMost], kv[3 * kMost];
    const double beta = tangents_.stiffness(term, e, corners, K, linearisations);
    const double scale = h * h + h * beta;
    // K v row by row, then each block's nine values (three runs of three in K's rows): the loops the compiler
    // vectorises, where one loop doing both over scattered blocks did not.
    for (std::size_t row = 0; row < size; ++row) {
      double sum = 0.0;
      for (std::size_t column = 0; column < size; ++column) sum += K[size * row + column] * velocity[column];
      kv[row] = sum;
    }
    for (std::size_t a = 0; a < N; ++a) {
      for (std::size_t b = 0; b < N; ++b) {
        double* block = &values_[9 * static_cast<std::size_t>(element_block_[N * N * e + N * a + b])];
        const double* from = &K[size * 3 * a + 3 * b];
        for (std::size_t i = 0; i < 3; ++i)
          for (std::size_t j = 0; j < 3; ++j) block[3 * i + j] += scale * from[size * i + j];
      }
      double* r = &rhs[3 * static_cast<std::size_t>(node[a])];
      for (std::size_t i = 0; i < 3; ++i) r[i] -= h * (h * kv[3 * a + i]);
    }
  }
}

void ImplicitSystem::assemble_nodal_rows(std::size_t begin, std::size_t end, double h, std::vector<double>& rhs) {
  for (std::size_t i = begin; i < end; ++i) {
    double* r = &rhs[3 * i];
    for (std::size_t k = nodal_.patch_begin(i); k < nodal_.patch_end(i); ++k) {
      const auto node = static_cast<std::size_t>(nodal_.patch_vertex(k));
      const double* own = nodal_.gradient(static_cast<std::size_t>(nodal_own_entry_[k]));
      const double weight = h * h * nodal_.modulus(node);
      for (std::size_t m = nodal_.patch_begin(node); m < nodal_.patch_end(node); ++m) {
        const double* other = nodal_.gradient(m);
        double* block = &values_[9 * static_cast<std::size_t>(find_block(row_offset_, column_, i, nodal_.patch_vertex(m)))];
        for (std::size_t a = 0; a < 3; ++a)
          for (std::size_t b = 0; b < 3; ++b) block[3 * a + b] += weight * own[a] * other[b];
      }
      for (std::size_t a = 0; a < 3; ++a) r[a] -= h * (h * own[a] * nodal_rate_[node]);
    }
  }
}

void ImplicitSystem::apply_holds(std::size_t begin, std::size_t end, std::vector<double>& rhs) {
  for (std::size_t i = begin; i < end; ++i) {
    if (row_touches_held_[i] == 0) continue;
    for (auto k = static_cast<std::size_t>(row_offset_[i]); k < static_cast<std::size_t>(row_offset_[i + 1]); ++k) {
      const auto j = static_cast<std::size_t>(column_[k]);
      double* block = &values_[9 * k];
      for (std::size_t r = 0; r < 3; ++r)
        for (std::size_t c = 0; c < 3; ++c)
          if (dof_held(3 * i + r) || dof_held(3 * j + c)) block[3 * r + c] = (i == j && r == c) ? 1.0 : 0.0;
    }
    for (std::size_t axis = 0; axis < 3; ++axis)
      if (dof_held(3 * i + axis)) rhs[3 * i + axis] = 0.0;
  }
}

void ImplicitSystem::multiply_chunks(const double* p, double* y, std::size_t begin, std::size_t end) const {
  const std::size_t first = begin * kSystemChunkVertices, last = std::min(n_, end * kSystemChunkVertices);
  for (std::size_t i = first; i < last; ++i) {
    double y0 = 0.0, y1 = 0.0, y2 = 0.0;
    for (auto k = static_cast<std::size_t>(row_offset_[i]); k < static_cast<std::size_t>(row_offset_[i + 1]); ++k) {
      const double* block = &values_[9 * k];
      const double* q = p + 3 * static_cast<std::size_t>(column_[k]);
      y0 += block[0] * q[0] + block[1] * q[1] + block[2] * q[2];
      y1 += block[3] * q[0] + block[4] * q[1] + block[5] * q[2];
      y2 += block[6] * q[0] + block[7] * q[1] + block[8] * q[2];
    }
    y[3 * i] = y0;
    y[3 * i + 1] = y1;
    y[3 * i + 2] = y2;
  }
}

void ImplicitSystem::multiply(const double* p, double* y, WorkerPool& pool) const {
  pool.run(
      chunks(), [&](std::size_t begin, std::size_t end) { multiply_chunks(p, y, begin, end); },
      kSystemChunksPerThread);
}

}  // namespace fmpc::sim
