// Implicit Euler on the GPU (gpu_launch.h): the system's assembly from the springs' blocks and the elements'
// linearisation, and the Jacobi-preconditioned conjugate gradient's kernels with their fixed-shape dot products.
#include "kernels/step_device.cuh"

namespace fmpc::gpu {

namespace {

template <typename Real>
__global__ void implicit_spring_blocks_kernel(ImplicitArguments<Real> a) {
  const int s = vertex_index();
  if (s >= a.spring_count) return;
  const int p = a.first[s], q = a.second[s];
  const kernels::SpringNetworkView<Real>& springs = a.model.springs;
  const kernels::SpringLawParameters<double> law{springs.law.law, static_cast<double>(springs.law.k2_over_k1),
                                                 static_cast<double>(springs.law.xc)};
  kernels::implicit_spring_blocks(static_cast<double>(a.state.x[q]) - static_cast<double>(a.state.x[p]),
                                  static_cast<double>(a.state.y[q]) - static_cast<double>(a.state.y[p]),
                                  static_cast<double>(a.state.z[q]) - static_cast<double>(a.state.z[p]),
                                  a.rest_length[s], static_cast<double>(springs.stiffness[s]),
                                  springs.damping ? static_cast<double>(springs.damping[s]) : 0.0, law, a.h,
                                  a.blocks + 12 * s, a.blocks + 12 * s + 6);
}

// Element e's share of one term of the implicit system: its linearisation at the step's start (into
// `linearisation`), h^2 K v0 for the right-hand side and the diagonal of (h^2 + h beta) K_aa for the preconditioner;
// the first term writes them, each later one adds (Accumulate). Arrays of 3 values per node are indexed 3 (N e + a),
// N nodes per element, as the node CSR's entries.
template <typename Real, typename Element, typename Law, bool Accumulate>
__global__ void implicit_element_kernel(ImplicitArguments<Real> a, kernels::ElementTermView<double> term,
                                        typename Element::template Linearisation<Law>* linearisation) {
  constexpr int N = Element::kNodes;
  const int e = vertex_index();
  const ImplicitElements& f = a.elements;
  if (e >= f.count) return;
  double x[N][3], v[N][3], kv[N][3], diagonal[N][3];
  for (int c = 0; c < N; ++c) {
    const int vertex = term.corners[N * e + c];
    x[c][0] = static_cast<double>(a.state.x[vertex]);
    x[c][1] = static_cast<double>(a.state.y[vertex]);
    x[c][2] = static_cast<double>(a.state.z[vertex]);
    v[c][0] = static_cast<double>(a.state.vx[vertex]);
    v[c][1] = static_cast<double>(a.state.vy[vertex]);
    v[c][2] = static_cast<double>(a.state.vz[vertex]);
  }
  typename Element::template Linearisation<Law> lin;
  Element::template linearise<Law>(term, e, x, lin);
  linearisation[e] = lin;
  Element::template stiffness_action<Law>(term, e, lin, v, kv);
  Element::template stiffness_diagonal<Law>(term, e, lin, diagonal);
  const double beta = term.stiffness_damping ? term.stiffness_damping[e] : 0.0;
  const double scale = a.h * a.h + a.h * beta;
  for (int c = 0; c < N; ++c) {
    for (int i = 0; i < 3; ++i) {
      double& rhs = f.rhs_part[3 * (N * e + c) + i];
      double& out = f.diagonal_part[3 * (N * e + c) + i];
      rhs = Accumulate ? rhs + a.h * a.h * kv[c][i] : a.h * a.h * kv[c][i];
      out = Accumulate ? out + scale * diagonal[c][i] : scale * diagonal[c][i];
    }
  }
}

// (h^2 + h beta) K p of element e for one term, with the nodes at fixed vertices taken as zero (their rows are
// identity); the first term writes, each later one adds.
template <typename Real, typename Element, typename Law, bool Accumulate>
__global__ void implicit_element_apply_kernel(ImplicitArguments<Real> a, kernels::ElementTermView<double> term,
                                              const typename Element::template Linearisation<Law>* linearisation) {
  constexpr int N = Element::kNodes;
  const int e = vertex_index();
  const ImplicitElements& f = a.elements;
  if (e >= f.count) return;
  double p[N][3], kp[N][3];
  for (int c = 0; c < N; ++c) {
    const int vertex = term.corners[N * e + c];
    const unsigned char held = a.loads.fixed[vertex];
    for (int i = 0; i < 3; ++i) p[c][i] = kernels::axis_fixed(held, i) ? 0.0 : a.p[3 * vertex + i];
  }
  Element::template stiffness_action<Law>(term, e, linearisation[e], p, kp);
  const double beta = term.stiffness_damping ? term.stiffness_damping[e] : 0.0;
  const double scale = a.h * a.h + a.h * beta;
  for (int c = 0; c < N; ++c)
    for (int i = 0; i < 3; ++i) {
      double& product = f.product[3 * (N * e + c) + i];
      product = Accumulate ? product + scale * kp[c][i] : scale * kp[c][i];
    }
}

// launch(Element, Law, term index) for each element term, its element kind and law template arguments; the first
// error stops.
template <typename Launch>
cudaError_t for_each_term(const ImplicitElements& elements, Launch&& launch) {
  for (int t = 0; t < elements.term_count; ++t) {
    const kernels::ElementTermView<double>& term = elements.terms[t];
    const cudaError_t status = kernels::visit_element_term(term.element, term.law, [&](auto kind, auto element_law) {
      launch(kind, element_law, t);
      return cudaGetLastError();
    });
    if (status != cudaSuccess) return status;
  }
  return cudaSuccess;
}

// Sum over the corners at v of an element-major array of 3 values per corner (double).
__device__ void gather_corner_values(int v, const kernels::CornerForceView<double>& corners, const double* values,
                                     double* out) {
  for (int k = corners.offset[v]; k < corners.offset[v + 1]; ++k) {
    const double* value = values + 3 * corners.corner[k];
    for (int i = 0; i < 3; ++i) out[i] += value[i];
  }
}

template <typename Real, GatherKind K>
__global__ void implicit_vertex_kernel(ImplicitArguments<Real> a) {
  const int row = vertex_index();
  if (row >= a.vertex_count) return;
  const int v = vertex_of_row(a.model, row);
  double* b = a.rhs + 3 * v;
  const unsigned char held = a.loads.fixed[v];
  if (held == kernels::kAllAxesFixed) {
    a.diagonal[v] = 1.0;
    for (int c = 0; c < 3; ++c) {
      b[c] = 0.0;
      a.inverse_jacobi[3 * v + c] = 1.0;
    }
    return;
  }
  Real acceleration[3];
  const kernels::StateView<Real> state{a.state.x, a.state.y, a.state.z, a.state.vx, a.state.vy, a.state.vz};
  kernels::vertex_acceleration(v, forces_of<Real, K>(a.model, row), state, a.loads, acceleration[0], acceleration[1],
                               acceleration[2]);
  for (int c = 0; c < 3; ++c) b[c] = a.h * a.mass[v] * static_cast<double>(acceleration[c]);
  const double own_velocity[3] = {static_cast<double>(a.state.vx[v]), static_cast<double>(a.state.vy[v]),
                                  static_cast<double>(a.state.vz[v])};
  const double dx = static_cast<double>(a.state.x[v]) - a.rest_position[3 * v];
  const double dy = static_cast<double>(a.state.y[v]) - a.rest_position[3 * v + 1];
  const double dz = static_cast<double>(a.state.z[v]) - a.rest_position[3 * v + 2];
  const double diagonal = kernels::implicit_vertex_diagonal(
      a.mass[v], a.h, static_cast<double>(a.loads.gamma0), static_cast<double>(a.loads.gamma1),
      sqrt(dx * dx + dy * dy + dz * dz), static_cast<double>(a.loads.mass_damping));
  double jacobi[3] = {diagonal, diagonal, diagonal};
  const kernels::SpringNetworkView<Real>& springs = a.model.springs;
  for (int e = springs.adjacency_offset[v]; e < springs.adjacency_offset[v + 1]; ++e) {
    const int s = springs.adjacency_spring[e], o = springs.adjacency_neighbour[e];
    const double* stiffness = a.blocks + 12 * s;
    const double* system = stiffness + 6;
    const double relative[3] = {own_velocity[0] - static_cast<double>(a.state.vx[o]),
                                own_velocity[1] - static_cast<double>(a.state.vy[o]),
                                own_velocity[2] - static_cast<double>(a.state.vz[o])};
    double kv[3];
    kernels::symmetric_multiply(stiffness, relative, kv);
    for (int c = 0; c < 3; ++c) {
      b[c] -= a.h * a.h * kv[c];
      jacobi[c] += system[kernels::symmetric_index(c, c)];
    }
  }
  if (a.contact_blocks != nullptr) {
    // The tools' contact in the step's active set (kernels::contact_linear_model), as the CPU's contact_part: h^2 K_c
    // on the free axes' block, h (the model's force at x0 - f0's) - h^2 K_c v0 into b.
    double* block = a.contact_blocks + 6 * v;
    double change[3] = {0.0, 0.0, 0.0};
    const double k = static_cast<double>(a.loads.contact.stiffness[v]);
    for (int i = 0; i < 6; ++i) block[i] = 0.0;
    if (k > 0.0)
      kernels::contact_linear_model(a.loads.contact, a.contact_active[v], k, static_cast<double>(a.state.x[v]),
                                    static_cast<double>(a.state.y[v]), static_cast<double>(a.state.z[v]), block,
                                    change);
    for (int i = 0; i < 6; ++i) block[i] *= a.h * a.h;
    double free_velocity[3];
    for (int c = 0; c < 3; ++c) free_velocity[c] = kernels::axis_fixed(held, c) ? 0.0 : own_velocity[c];
    double kv[3];
    kernels::symmetric_multiply(block, free_velocity, kv);
    for (int c = 0; c < 3; ++c) {
      b[c] += a.h * change[c] - kv[c];
      jacobi[c] += block[kernels::symmetric_index(c, c)];
    }
  }
  if (a.elements.count > 0) {
    const kernels::CornerForceView<double> corners{a.model.corners.offset, a.model.corners.corner, nullptr};
    double kv[3] = {0.0, 0.0, 0.0}, element_diagonal[3] = {0.0, 0.0, 0.0};
    gather_corner_values(v, corners, a.elements.rhs_part, kv);
    gather_corner_values(v, corners, a.elements.diagonal_part, element_diagonal);
    for (int c = 0; c < 3; ++c) {
      b[c] -= kv[c];
      jacobi[c] += element_diagonal[c];
    }
  }
  a.diagonal[v] = diagonal;
  for (int c = 0; c < 3; ++c) {
    // A held axis is an identity row with a zero right-hand side.
    if (kernels::axis_fixed(held, c)) {
      b[c] = 0.0;
      jacobi[c] = 1.0;
    }
    a.inverse_jacobi[3 * v + c] = jacobi[c] != 0.0 ? 1.0 / jacobi[c] : 1.0;
  }
}

template <typename Real>
__global__ void implicit_apply_kernel(ImplicitArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  const double* own = a.p + 3 * v;
  double* out = a.ap + 3 * v;
  const unsigned char held = a.loads.fixed[v];
  if (held == kernels::kAllAxesFixed) {
    for (int c = 0; c < 3; ++c) out[c] = own[c];
    return;
  }
  double sum[3] = {a.diagonal[v] * own[0], a.diagonal[v] * own[1], a.diagonal[v] * own[2]};
  const kernels::SpringNetworkView<Real>& springs = a.model.springs;
  for (int e = springs.adjacency_offset[v]; e < springs.adjacency_offset[v + 1]; ++e) {
    const int s = springs.adjacency_spring[e], o = springs.adjacency_neighbour[e];
    const unsigned char other = a.loads.fixed[o];
    double relative[3];
    for (int c = 0; c < 3; ++c) relative[c] = own[c] - (kernels::axis_fixed(other, c) ? 0.0 : a.p[3 * o + c]);
    double product[3];
    kernels::symmetric_multiply(a.blocks + 12 * s + 6, relative, product);
    for (int c = 0; c < 3; ++c) sum[c] += product[c];
  }
  if (a.contact_blocks != nullptr) {
    double free_own[3], product[3];
    for (int c = 0; c < 3; ++c) free_own[c] = kernels::axis_fixed(held, c) ? 0.0 : own[c];
    kernels::symmetric_multiply(a.contact_blocks + 6 * v, free_own, product);
    for (int c = 0; c < 3; ++c) sum[c] += product[c];
  }
  if (a.elements.count > 0) {
    const kernels::CornerForceView<double> corners{a.model.corners.offset, a.model.corners.corner, nullptr};
    gather_corner_values(v, corners, a.elements.product, sum);
  }
  for (int c = 0; c < 3; ++c) out[c] = kernels::axis_fixed(held, c) ? own[c] : sum[c];
}

// Partial sums of first . second (and of third . fourth when third is not null) over [0, count), in the fixed
// shape of the energy sums; block b writes partial[b] and partial[kEnergyBlocks + b].
__global__ void dot_partial_kernel(const double* first, const double* second, const double* third, const double* fourth,
                                   int count, double* partial) {
  __shared__ double cache[kEnergyThreads];
  double sum = 0.0, other = 0.0;
  const long long stride = static_cast<long long>(kEnergyBlocks) * kEnergyThreads;
  for (long long i = static_cast<long long>(blockIdx.x) * kEnergyThreads + threadIdx.x; i < count; i += stride) {
    sum += first[i] * second[i];
    if (third != nullptr) other += third[i] * fourth[i];
  }
  const double total = block_tree_sum(sum, cache);
  __syncthreads();  // every thread has read cache[0] before the second tree overwrites it
  const double other_total = block_tree_sum(other, cache);
  if (threadIdx.x == 0) {
    partial[blockIdx.x] = total;
    partial[kEnergyBlocks + blockIdx.x] = other_total;
  }
}

enum class CgStage : int { Start = 0, Alpha = 1, Residual = 2 };

__global__ void cg_scalars_kernel(const double* partial, ConjugateGradientScalars* scalars, CgStage stage) {
  __shared__ double cache[kEnergyThreads];
  double sum = 0.0, other = 0.0;
  for (int i = static_cast<int>(threadIdx.x); i < kEnergyBlocks; i += kEnergyThreads) {
    sum += partial[i];
    other += partial[kEnergyBlocks + i];
  }
  const double total = block_tree_sum(sum, cache);
  __syncthreads();
  const double other_total = block_tree_sum(other, cache);
  if (threadIdx.x != 0) return;
  switch (stage) {
    case CgStage::Start:
      scalars->rhs_norm2 = total;
      scalars->rz = other_total;
      break;
    case CgStage::Alpha:
      scalars->p_ap = total;
      scalars->alpha = scalars->rz / total;
      break;
    case CgStage::Residual:
      scalars->rr = total;
      scalars->rz_next = other_total;
      scalars->beta = other_total / scalars->rz;
      break;
  }
}

// Per degree of freedom: x = 0, r = b, z = p = M^-1 r.
template <typename Real>
__global__ void cg_start_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count) return;
  a.x[i] = 0.0;
  a.r[i] = a.rhs[i];
  a.z[i] = a.inverse_jacobi[i] * a.r[i];
  a.p[i] = a.z[i];
}

template <typename Real>
__global__ void cg_update_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count) return;
  const double alpha = a.scalars->alpha;
  a.x[i] += alpha * a.p[i];
  a.r[i] -= alpha * a.ap[i];
  a.z[i] = a.inverse_jacobi[i] * a.r[i];
}

template <typename Real>
__global__ void cg_direction_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count) return;
  a.p[i] = a.z[i] + a.scalars->beta * a.p[i];
  // Nothing in this kernel reads rz: thread 0 may move rz_next into it.
  if (i == 0) a.scalars->rz = a.scalars->rz_next;
}

template <typename Real>
__global__ void implicit_finish_kernel(ImplicitArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count || a.loads.fixed[v] == kernels::kAllAxesFixed) return;
  const Real h = static_cast<Real>(a.h);
  a.state.vx[v] += static_cast<Real>(a.x[3 * v]);
  a.state.vy[v] += static_cast<Real>(a.x[3 * v + 1]);
  a.state.vz[v] += static_cast<Real>(a.x[3 * v + 2]);
  a.state.x[v] += h * a.state.vx[v];
  a.state.y[v] += h * a.state.vy[v];
  a.state.z[v] += h * a.state.vz[v];
}

// The step's contact set (kernels::contact_set) of every vertex a tool can touch: at the state (predicted false),
// or after moving by h (v0 + dv) on its free axes with dv the solution in x; each vertex whose set changes counts
// into *contact_changes.
template <typename Real>
__global__ void contact_set_kernel(ImplicitArguments<Real> a, bool predicted) {
  const int v = vertex_index();
  if (v >= a.vertex_count || !(a.loads.contact.stiffness[v] > Real(0))) return;
  const unsigned char held = a.loads.fixed[v];
  const double velocity[3] = {static_cast<double>(a.state.vx[v]), static_cast<double>(a.state.vy[v]),
                              static_cast<double>(a.state.vz[v])};
  double moved[3];
  for (int c = 0; c < 3; ++c) moved[c] = kernels::axis_fixed(held, c) ? 0.0 : a.h * (velocity[c] + a.x[3 * v + c]);
  const auto set = static_cast<unsigned char>(kernels::contact_set(
      a.loads.contact, static_cast<double>(a.state.x[v]), static_cast<double>(a.state.y[v]),
      static_cast<double>(a.state.z[v]), predicted ? moved : nullptr));
  if (set == a.contact_active[v]) return;
  a.contact_active[v] = set;
  atomicAdd(a.contact_changes, 1u);
}

cudaError_t launch_dots(const double* first, const double* second, const double* third, const double* fourth, int count,
                        double* partial, ConjugateGradientScalars* scalars, CgStage stage, cudaStream_t stream) {
  dot_partial_kernel<<<kEnergyBlocks, kEnergyThreads, 0, stream>>>(first, second, third, fourth, count, partial);
  const cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  cg_scalars_kernel<<<1, kEnergyThreads, 0, stream>>>(partial, scalars, stage);
  return cudaGetLastError();
}

}  // namespace

template <typename Real>
cudaError_t launch_implicit_assemble(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.spring_count > 0) {
    implicit_spring_blocks_kernel<Real><<<blocks_for(a.spring_count), kThreadsPerBlock, 0, stream>>>(a);
    const cudaError_t status = cudaGetLastError();
    if (status != cudaSuccess) return status;
  }
  if (a.elements.count > 0) {
    // The element pass at the state (f0 in b) and the elements' linearisation, before the per-vertex kernel.
    cudaError_t status = launch_element_forces(
        a.model, kernels::StateView<Real>{a.state.x, a.state.y, a.state.z, a.state.vx, a.state.vy, a.state.vz}, stream);
    if (status != cudaSuccess) return status;
    status = for_each_term(a.elements, [&](auto kind, auto element_law, int t) {
      using Element = decltype(kind);
      using Law = decltype(element_law);
      using Linearisation = typename Element::template Linearisation<Law>;
      auto* linearisation = static_cast<Linearisation*>(a.elements.linearisation[t]);
      if (t == 0) {
        implicit_element_kernel<Real, Element, Law, false>
            <<<blocks_for(a.elements.count), kThreadsPerBlock, 0, stream>>>(a, a.elements.terms[t], linearisation);
      } else {
        implicit_element_kernel<Real, Element, Law, true>
            <<<blocks_for(a.elements.count), kThreadsPerBlock, 0, stream>>>(a, a.elements.terms[t], linearisation);
      }
    });
    if (status != cudaSuccess) return status;
  }
  if (a.vertex_count <= 0) return cudaSuccess;
  return with_kind(a.model.kind, [&](auto kind) {
    implicit_vertex_kernel<Real, decltype(kind)::value><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
    return cudaGetLastError();
  });
}

template <typename Real>
cudaError_t launch_cg_start(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  cg_start_kernel<Real><<<blocks_for(3 * a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  const cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  return launch_dots(a.rhs, a.rhs, a.r, a.z, 3 * a.vertex_count, a.partial, a.scalars, CgStage::Start, stream);
}

template <typename Real>
cudaError_t launch_cg_iteration(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  if (a.elements.count > 0) {
    const cudaError_t status = for_each_term(a.elements, [&](auto kind, auto element_law, int t) {
      using Element = decltype(kind);
      using Law = decltype(element_law);
      using Linearisation = typename Element::template Linearisation<Law>;
      const auto* linearisation = static_cast<const Linearisation*>(a.elements.linearisation[t]);
      if (t == 0) {
        implicit_element_apply_kernel<Real, Element, Law, false>
            <<<blocks_for(a.elements.count), kThreadsPerBlock, 0, stream>>>(a, a.elements.terms[t], linearisation);
      } else {
        implicit_element_apply_kernel<Real, Element, Law, true>
            <<<blocks_for(a.elements.count), kThreadsPerBlock, 0, stream>>>(a, a.elements.terms[t], linearisation);
      }
    });
    if (status != cudaSuccess) return status;
  }
  implicit_apply_kernel<Real><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  status = launch_dots(a.p, a.ap, nullptr, nullptr, 3 * a.vertex_count, a.partial, a.scalars, CgStage::Alpha, stream);
  if (status != cudaSuccess) return status;
  cg_update_kernel<Real><<<blocks_for(3 * a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  return launch_dots(a.r, a.r, a.r, a.z, 3 * a.vertex_count, a.partial, a.scalars, CgStage::Residual, stream);
}

template <typename Real>
cudaError_t launch_cg_direction(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  cg_direction_kernel<Real><<<blocks_for(3 * a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_contact_set(const ImplicitArguments<Real>& a, bool predicted, cudaStream_t stream) {
  if (a.vertex_count <= 0 || a.contact_blocks == nullptr) return cudaSuccess;
  contact_set_kernel<Real><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a, predicted);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_implicit_finish(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  implicit_finish_kernel<Real><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  return cudaGetLastError();
}

#define FMPC_IMPLICIT_STEP_LAUNCHERS(Real)                                                           \
  template cudaError_t launch_implicit_assemble<Real>(const ImplicitArguments<Real>&, cudaStream_t); \
  template cudaError_t launch_cg_start<Real>(const ImplicitArguments<Real>&, cudaStream_t);          \
  template cudaError_t launch_contact_set<Real>(const ImplicitArguments<Real>&, bool, cudaStream_t); \
  template cudaError_t launch_cg_iteration<Real>(const ImplicitArguments<Real>&, cudaStream_t);      \
  template cudaError_t launch_cg_direction<Real>(const ImplicitArguments<Real>&, cudaStream_t);      \
  template cudaError_t launch_implicit_finish<Real>(const ImplicitArguments<Real>&, cudaStream_t);
FMPC_IMPLICIT_STEP_LAUNCHERS(float)
FMPC_IMPLICIT_STEP_LAUNCHERS(double)

}  // namespace fmpc::gpu
