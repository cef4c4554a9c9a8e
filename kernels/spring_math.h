#pragma once
// Spring laws and the per-vertex force gather, shared by the CPU loops (runtime/integrate) and the CUDA kernels
// (kernels/*.cu). Everything is FMPC_HD, templated on the real type (float or double), and sums in the
// CSR order of the adjacency, so every backend adds the same terms in the same order.
#include "kernels/fmpc_hd.h"

#if !defined(__CUDACC__)
#include <cmath>
#endif

namespace fmpc::kernels {

// sqrt in the argument's own precision on both sides (a float must not be promoted to double).
FMPC_HD float square_root(float value) {
#if defined(__CUDACC__)
  return sqrtf(value);
#else
  return std::sqrt(value);
#endif
}
FMPC_HD double square_root(double value) {
#if defined(__CUDACC__)
  return sqrt(value);
#else
  return std::sqrt(value);
#endif
}

// value = fraction 2^exponent with |fraction| in [0.5, 1) (frexp), and its exact inverse scaling (ldexp): powers of
// two rescale without rounding, so the host and the device agree bit for bit.
FMPC_HD float fraction_and_exponent(float value, int& exponent) {
#if defined(__CUDACC__)
  return frexpf(value, &exponent);
#else
  return std::frexp(value, &exponent);
#endif
}
FMPC_HD double fraction_and_exponent(double value, int& exponent) {
#if defined(__CUDACC__)
  return frexp(value, &exponent);
#else
  return std::frexp(value, &exponent);
#endif
}
FMPC_HD float scale_by_power_of_two(float value, int exponent) {
#if defined(__CUDACC__)
  return ldexpf(value, exponent);
#else
  return std::ldexp(value, exponent);
#endif
}
FMPC_HD double scale_by_power_of_two(double value, int exponent) {
#if defined(__CUDACC__)
  return ldexp(value, exponent);
#else
  return std::ldexp(value, exponent);
#endif
}

enum class SpringLaw : int {
  LinearDashpot = 0,    // f = k (l - l0), plus dashpot c (dv . u)
  BasafaFarahmand = 1,  // f = F_s(X), X = (l - l0) / l0, plus dashpot c (dv . u); see basafa_farahmand_force
};

// Basafa & Farahmand (2011), as summarised in ../shared/data/README.md:
//   F_s(X) = K1 X + K2 X^3                     for |X| <= Xc
//          = (A + B (|X| - Xc)) sign(X)        above, A = K1 Xc + K2 Xc^3, B = K1 + 3 K2 Xc^2
// (continuous with a continuous slope at Xc). Here X is the strain (l - l0) / l0, K1 = k l0 (so that small
// strains behave like the linear spring of stiffness k) and K2 = ratio K1; the benchmark (K1 0.05 N, K2 10 N,
// Xc 0.2) is a spring with l0 = 1 m, k = 0.05 N/m, ratio 200.
template <typename Real>
FMPC_HD Real basafa_farahmand_force(Real strain, Real k1, Real k2, Real xc) {
  const Real magnitude = strain < Real(0) ? -strain : strain;
  if (magnitude <= xc) return k1 * strain + k2 * strain * strain * strain;
  const Real a = k1 * xc + k2 * xc * xc * xc;
  const Real b = k1 + Real(3) * k2 * xc * xc;
  const Real value = a + b * (magnitude - xc);
  return strain < Real(0) ? -value : value;
}

// dF_s/dX.
template <typename Real>
FMPC_HD Real basafa_farahmand_slope(Real strain, Real k1, Real k2, Real xc) {
  const Real magnitude = strain < Real(0) ? -strain : strain;
  if (magnitude <= xc) return k1 + Real(3) * k2 * strain * strain;
  return k1 + Real(3) * k2 * xc * xc;
}

template <typename Real>
struct SpringLawParameters {
  SpringLaw law = SpringLaw::LinearDashpot;
  Real k2_over_k1 = Real(200);  // Basafa-Farahmand only
  Real xc = Real(0.2);          // Basafa-Farahmand only
};

// Tension (positive when stretched, N) along the spring for its current length.
template <typename Real>
FMPC_HD Real spring_tension(Real length, Real rest, Real k, const SpringLawParameters<Real>& p) {
  if (p.law == SpringLaw::BasafaFarahmand) {
    const Real k1 = k * rest;
    return basafa_farahmand_force((length - rest) / rest, k1, p.k2_over_k1 * k1, p.xc);
  }
  return k * (length - rest);
}

// d(tension)/d(length) (N/m).
template <typename Real>
FMPC_HD Real spring_tension_slope(Real length, Real rest, Real k, const SpringLawParameters<Real>& p) {
  if (p.law == SpringLaw::BasafaFarahmand) {
    const Real k1 = k * rest;
    return basafa_farahmand_slope((length - rest) / rest, k1, p.k2_over_k1 * k1, p.xc) / rest;
  }
  return k;
}

// Energy stored in one spring at length l: the integral of its tension from l0 to l (evaluated in double by the
// energy reductions of both backends). Linear: k (l - l0)^2 / 2. Basafa-Farahmand with X = |l - l0| / l0,
// r = K2/K1: k l0^2 (X^2/2 + r X^4/4) up to Xc, and beyond it the linear growth of F_s:
// k l0^2 (Xc^2/2 + r Xc^4/4 + (Xc + r Xc^3)(X - Xc) + (1 + 3 r Xc^2)(X - Xc)^2 / 2).
template <typename Real>
FMPC_HD Real spring_potential_energy(Real length, Real rest, Real k, const SpringLawParameters<Real>& p) {
  if (p.law == SpringLaw::BasafaFarahmand) {
    const Real r = p.k2_over_k1, xc = p.xc;
    const Real difference = length - rest;
    const Real strain = (difference < Real(0) ? -difference : difference) / rest;
    const Real scale = k * rest * rest;
    if (strain <= xc) return scale * (strain * strain / Real(2) + r * strain * strain * strain * strain / Real(4));
    const Real a = xc + r * xc * xc * xc, b = Real(1) + Real(3) * r * xc * xc;
    const Real beyond = strain - xc;
    return scale * (xc * xc / Real(2) + r * xc * xc * xc * xc / Real(4) + a * beyond + b * beyond * beyond / Real(2));
  }
  return Real(0.5) * k * (length - rest) * (length - rest);
}

// Force on the vertex "self" from one spring: d = x_other - x_self, dv = v_other - v_self.
// A spring shorter than 1e-9 l0 has no direction: it exerts no force (the thesis's code divided by the length
// unguarded); the nodes around it still move it apart.
template <typename Real>
FMPC_HD void spring_force_on_vertex(Real dx, Real dy, Real dz, Real dvx, Real dvy, Real dvz, Real rest, Real k, Real c,
                                    const SpringLawParameters<Real>& p, Real& fx, Real& fy, Real& fz) {
  const Real length_squared = dx * dx + dy * dy + dz * dz;
  const Real minimum = Real(1e-9) * rest;
  if (!(length_squared > minimum * minimum)) {
    fx = fy = fz = Real(0);
    return;
  }
  const Real length = square_root(length_squared);
  // One IEEE division per spring, then three products: each division is about ten instructions in the GPU's
  // gather, and the three of them cost the 240^3 box 8% of its step (H100, docs/performance.md). The CPU and the
  // GPU still round alike.
  const Real inverse_length = Real(1) / length;
  const Real ux = dx * inverse_length, uy = dy * inverse_length, uz = dz * inverse_length;
  const Real along = spring_tension(length, rest, k, p) + c * (dvx * ux + dvy * uy + dvz * uz);
  fx = along * ux;
  fy = along * uy;
  fz = along * uz;
}

// One spring as seen from one of its ends, at that end's CSR entry: the other end and the spring's parameters
// (damping 0 without dashpots). The GPU backend derives these from the arrays below when the stiffness stays fixed
// (no strain table), so a vertex's gather reads one aligned record per spring (16 bytes in float) instead of two
// indices and three values scattered by spring index: same values, same arithmetic, same bits.
template <typename Real>
struct alignas(4 * sizeof(Real)) SpringIncidence {
  int neighbour;
  Real rest_length;
  Real stiffness;
  Real damping;
};

// The CSR entries in sliced ELLPACK order (SELL-C-sigma, C = 32: Kreutzer, Hager, Wellein, Fehske & Bishop 2014,
// "A unified sparse matrix data format for efficient general sparse matrix-vector multiplication on modern
// processors with wide SIMD units"), for the GPU's per-vertex kernels with one thread per vertex. Threads take the
// vertices in `vertex_order` (runtime/springs/sliced_springs.h: vertices sorted by their number of springs within
// small windows, so a warp's vertices have nearly the same count), 32 rows per warp; entry j of a row lies at
// first + 32 j, so the j-th loads of a warp read 32 consecutive records (512 bytes in float, one vector load per
// thread) instead of 32 records scattered by the CSR offsets. Each vertex still adds its entries in CSR order: the
// same terms in the same order, the same bits. Rows are indexed by thread, like vertex_order, so a thread's two
// loads (its vertex and its row) do not wait on each other.
constexpr int kSliceRows = 32;

struct alignas(8) SlicedRow {
  int first;  // index of entry 0; entry j at first + kSliceRows j
  int count;  // the vertex's CSR entries; -1: no sliced row (the gather reads the CSR order)
};

template <typename Real>
struct SlicedSpringsView {
  const SlicedRow* row = nullptr;  // per thread (row r is vertex_order[r]'s); null: no sliced layout
  const SpringIncidence<Real>* record = nullptr;
};

// The spring network and state as raw arrays (structure of arrays), for the gather below.
template <typename Real>
struct SpringNetworkView {
  const int* adjacency_offset;  // vertex_count + 1
  const int* adjacency_spring;
  const int* adjacency_neighbour;
  const Real* rest_length;
  const Real* stiffness;
  const Real* damping;  // null: no dashpots (a scene without damping allocates no array)
  SpringLawParameters<Real> law;
  const SpringIncidence<Real>* incidence = nullptr;  // per CSR entry; null: read through the arrays above
  SlicedSpringsView<Real> sliced;  // the GPU's sliced layout where it has one (then `incidence` is null)
};

template <typename Real>
struct StateView {
  const Real* x;
  const Real* y;
  const Real* z;
  const Real* vx;
  const Real* vy;
  const Real* vz;
};

// CSR entry e read through the spring indices (what the incidence records hold, for networks without them).
template <typename Real>
FMPC_HD SpringIncidence<Real> incidence_from_arrays(const SpringNetworkView<Real>& net, int e) {
  const int spring = net.adjacency_spring[e];
  return {net.adjacency_neighbour[e], net.rest_length[spring], net.stiffness[spring],
          net.damping ? net.damping[spring] : Real(0)};
}

// CSR entry e as a record: the GPU's incidence records where there are some, else read through the spring indices.
template <typename Real>
FMPC_HD SpringIncidence<Real> spring_incidence(const SpringNetworkView<Real>& net, int e) {
  return net.incidence != nullptr ? net.incidence[e] : incidence_from_arrays(net, e);
}

// One vertex's position and velocity: the other end of a spring as a gather reads it.
template <typename Real>
struct VertexState {
  Real x, y, z, vx, vy, vz;
};

// The force of record r's spring on a vertex at (x, v) = (x, y, z, vx, vy, vz) whose other end is at `other`: one
// term of the gathers below.
template <typename Real>
FMPC_HD void entry_spring_force(const SpringLawParameters<Real>& law, const SpringIncidence<Real>& r,
                                const VertexState<Real>& other, Real x, Real y, Real z, Real vx, Real vy, Real vz,
                                Real& fx, Real& fy, Real& fz) {
  spring_force_on_vertex(other.x - x, other.y - y, other.z - z, other.vx - vx, other.vy - vy, other.vz - vz,
                         r.rest_length, r.stiffness, r.damping, law, fx, fy, fz);
}

// Vertex v's state in `s`.
template <typename Real>
FMPC_HD VertexState<Real> vertex_state(const StateView<Real>& s, int v) {
  return {s.x[v], s.y[v], s.z[v], s.vx[v], s.vy[v], s.vz[v]};
}

// Sum of the spring forces on a vertex at (x, v) over its `count` CSR entries, in order (deterministic; no atomics):
// entry(j) gives its j-th entry as a SpringIncidence, other(record) the state of that spring's other end. Every
// gather of both backends adds its terms here or in this order (the persistent CUDA kernel computes them on several
// threads and adds them in this order on one, kernels/persistent_step.cu), so they all have these bits. Batch > 1
// reads the records, then the other ends, of `Batch` entries before computing any of their terms: a term's branch
// (spring_force_on_vertex's guard) otherwise holds the next entry's loads back (kSlicedGatherBatch). The terms are
// still added one by one in CSR order.
template <int Batch = 1, typename Real, typename Entry, typename Other>
FMPC_HD void sum_spring_terms(int count, const SpringLawParameters<Real>& law, const VertexState<Real>& self,
                              Entry entry, Other other, Real& fx, Real& fy, Real& fz) {
  Real sx = Real(0), sy = Real(0), sz = Real(0);
  const auto add = [&](const SpringIncidence<Real>& r, const VertexState<Real>& o) {
    Real f0, f1, f2;
    entry_spring_force(law, r, o, self.x, self.y, self.z, self.vx, self.vy, self.vz, f0, f1, f2);
    sx += f0;
    sy += f1;
    sz += f2;
  };
  if constexpr (Batch == 1) {
    FMPC_UNROLL_GATHER
    for (int j = 0; j < count; ++j) {
      const SpringIncidence<Real> r = entry(j);
      add(r, other(r));
    }
  } else {
    for (int first = 0; first < count; first += Batch) {
      SpringIncidence<Real> r[Batch]{};
      VertexState<Real> o[Batch]{};
      FMPC_UNROLL_ALL
      for (int b = 0; b < Batch; ++b)
        if (first + b < count) r[b] = entry(first + b);
      FMPC_UNROLL_ALL
      for (int b = 0; b < Batch; ++b)
        if (first + b < count) o[b] = other(r[b]);
      FMPC_UNROLL_ALL
      for (int b = 0; b < Batch; ++b)
        if (first + b < count) add(r[b], o[b]);
    }
  }
  fx = sx;
  fy = sy;
  fz = sz;
}

// sum_spring_terms for vertex v of the state `s`.
template <int Batch = 1, typename Real, typename Entry>
FMPC_HD void sum_spring_forces(int v, int count, const SpringNetworkView<Real>& net, const StateView<Real>& s,
                               Entry entry, Real& fx, Real& fy, Real& fz) {
  sum_spring_terms<Batch>(
      count, net.law, vertex_state(s, v), entry,
      [&](const SpringIncidence<Real>& r) { return vertex_state(s, r.neighbour); }, fx, fy, fz);
}

// Entry j of a sliced row: what incidence_from_arrays gives for the vertex's CSR entry j.
template <typename Real>
FMPC_HD SpringIncidence<Real> sliced_incidence(const SlicedSpringsView<Real>& sliced, SlicedRow row, int j) {
#if defined(__CUDA_ARCH__)
  // Streamed (evict-first, __ldcs): each record is read once per step, and kept from evicting the neighbours' state
  // that the same and nearby warps read again; the 240^3 box ran 636.3 steps/s against 606.9 (H100, 3,000 steps).
  const SpringIncidence<Real>* const at = sliced.record + row.first + kSliceRows * j;
  SpringIncidence<Real> r;
  if constexpr (sizeof(Real) == sizeof(float)) {
    const float4 q = __ldcs(reinterpret_cast<const float4*>(at));
    r.neighbour = __float_as_int(q.x);
    r.rest_length = q.y;
    r.stiffness = q.z;
    r.damping = q.w;
  } else {
    const double2 first = __ldcs(reinterpret_cast<const double2*>(at));
    const double2 second = __ldcs(reinterpret_cast<const double2*>(at) + 1);
    r.neighbour = __double2loint(first.x);
    r.rest_length = first.y;
    r.stiffness = second.x;
    r.damping = second.y;
  }
  return r;
#else
  return sliced.record[row.first + kSliceRows * j];
#endif
}

// Writes vertex v's CSR entries into its sliced row (the GPU fills the layout with this, one thread per row).
template <typename Real>
FMPC_HD void write_sliced_row(int v, const SpringNetworkView<Real>& net, SlicedRow row, SpringIncidence<Real>* record) {
  const int begin = net.adjacency_offset[v];
  for (int j = 0; j < row.count; ++j) record[row.first + kSliceRows * j] = incidence_from_arrays(net, begin + j);
}

// Entries a sliced row's gather reads together (sum_spring_terms' Batch): the GPU's one-thread-per-vertex kernels on
// large meshes are bound by memory latency, and four records and neighbours in flight per thread ran the 240^3 box
// at 559.7 steps/s against 506.7 one at a time (2: 552.3; 6: 530.9; 8: 484.8; H100, fmpc simulate --steps 1000).
constexpr int kSlicedGatherBatch = 4;

// Sum of the spring forces on vertex v, in CSR order: from v's sliced row where it has one (row.count >= 0), else
// from the incidence records where there are some, else read through the spring indices (the same values, so the
// same bits).
template <typename Real>
FMPC_HD void gather_spring_force(int v, SlicedRow row, const SpringNetworkView<Real>& net, const StateView<Real>& s,
                                 Real& fx, Real& fy, Real& fz) {
  if (row.count >= 0) {
    sum_spring_forces<kSlicedGatherBatch>(
        v, row.count, net, s, [&](int j) { return sliced_incidence(net.sliced, row, j); }, fx, fy, fz);
    return;
  }
  const int begin = net.adjacency_offset[v], count = net.adjacency_offset[v + 1] - begin;
  if (net.incidence != nullptr) {
    sum_spring_forces(
        v, count, net, s, [&](int j) { return net.incidence[begin + j]; }, fx, fy, fz);
    return;
  }
  sum_spring_forces(
      v, count, net, s, [&](int j) { return incidence_from_arrays(net, begin + j); }, fx, fy, fz);
}

}  // namespace fmpc::kernels
