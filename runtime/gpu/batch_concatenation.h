#pragma once
// The host side of a GPU batch, without CUDA: which scenes can share a batch (batch_accepts, gpu_simulation.h) and
// their concatenation into one network (scene s owns a contiguous range of vertices, springs and elements; its CSR
// entries point at its own vertices), in double, converted to the engine's real type on upload.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <unordered_map>
#include <utility>
#include <vector>

#include "kernels/element_term.h"
#include "runtime/gpu/launch_shapes.h"
#include "runtime/integrate/simulation.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::gpu {

// Host arrays whose resize leaves trivial values uninitialised, so that the pool's workers touch their pages first:
// std::vector's zero fill ran on one thread, page faults included (creating the simulation of a 97M-spring box took
// 29.8 s on the H100 machine's 16 cores, most of it copying on one thread).
template <typename T>
struct UninitialisedAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = UninitialisedAllocator<U>;
  };
  UninitialisedAllocator() = default;
  template <typename U>
  UninitialisedAllocator(const UninitialisedAllocator<U>&) {}
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0)
      ::new (static_cast<void*>(p)) U;
    else
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
template <typename T>
using HostArray = std::vector<T, UninitialisedAllocator<T>>;

// The host-side concatenation of a batch (see gpu_launch.h): everything in double, converted on upload.
struct ConcatenatedScenes {
  std::vector<int> vertex_begin{0}, spring_begin{0}, element_begin{0};  // scene_count + 1 entries each
  HostArray<int> offset, spring, neighbour, first, second, vertex_scene;
  HostArray<double> rest_length, stiffness, damping, mass;
  HostArray<unsigned char> fixed;
  HostArray<double> rest[3], position[3], velocity[3], force[3];
  bool has_forces = false;
  bool has_damping = false;  // false: no scene has dashpots, and no damping array is uploaded
  // Tetrahedra (every scene's, for inversion counts) and, when the scenes have element terms, their geometry, the
  // corner CSR (each scene's corners point at its own elements) and each term's parameters and damping (the scenes
  // of a batch have the same terms: create() refuses others).
  HostArray<int> corners, element_scene, corner_offset, corner_index, corner_slot;
  int element_kind = 0;       // the element kind's index in kernels::ElementKinds (the scenes share it)
  int nodes_per_element = 4;  // its kNodes
  HostArray<int> nodes;       // nodes_per_element per element, batch vertex indices
  HostArray<double> rest_inverse, rest_volume;
  struct Term {
    int law = 0;
    HostArray<double> parameter[kernels::kMostLawParameters];
    HostArray<double> stiffness_damping;  // empty: no scene damps this term
    std::vector<sim::PronyTerm> prony;    // scene 0's (a viscoelastic scene runs alone: single_scene_feature)
  };
  std::vector<Term> terms;
  bool has_elements = false;
  // The staging's threads, which also convert the arrays on upload (one pool, not one per array).
  std::unique_ptr<sim::WorkerPool> pool;
};

// The batch's arrays, each scene's after the previous one's, filled on the struct's own pool.
ConcatenatedScenes concatenate(const std::vector<sim::SimulationSetup>& scenes);

// Whether the scene's probe pushes with a force (the batch then carries external forces).
bool force_probe(const sim::SimulationSetup& setup);

// The gather a batch's scenes share (create() refuses batches that differ in it).
GatherKind gather_kind(const sim::SimulationSetup& setup);

// Whether two setups have the same element kind and terms, law for law (their parameters may differ).
bool same_element_laws(const sim::SimulationSetup& a, const sim::SimulationSetup& b);

// The first field in which `scene` differs from scene 0 among those a batch shares, or nullptr.
const char* shared_field_mismatch(const sim::SimulationSetup& scene, const sim::SimulationSetup& reference);

// What a scene uses that only a batch of one can run (implicit Euler, a strain table), as the sentence saying so;
// nullptr when it can join a larger batch.
const char* single_scene_feature(const sim::SimulationSetup& setup);

// out[at + i] = value(i) for i in [0, count), on the pool.
template <typename T, typename Value>
void fill_on_pool(sim::WorkerPool& pool, HostArray<T>& out, std::size_t at, std::size_t count, const Value& value) {
  T* to = out.data() + at;
  pool.run(
      count,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) to[i] = value(i);
      },
      1 << 16);
}

// The per-element view (kernels::PerElement) of `values`, held on the device at `device`: where `one_value` and every
// entry has the same bits, that value alone, which the element pass reads from its kernel parameters instead of an
// array per element; otherwise the array; an empty array: absent (zero).
template <typename Real, typename Allocator>
kernels::PerElement<Real> per_element_of(const std::vector<Real, Allocator>& values, const Real* device,
                                         bool one_value) {
  if (values.empty()) return {};
  if (!one_value) return {device};
  for (const Real& value : values)
    if (std::memcmp(&value, &values.front(), sizeof(Real)) != 0) return {device};
  return {nullptr, values.front()};
}

// The distinct Dm^-1 of `rest_inverse` (9 values per element, compared bitwise in Real) into `table`, 9 per shape in
// order of first appearance, and each element's index among them into `shape` (ElementTermView::rest_shape), where
// there are at most 256 (a regular grid's: the 120^3 box has 48 in float); false, both empty, otherwise.
template <typename Real, typename Allocator>
bool rest_shapes(const std::vector<Real, Allocator>& rest_inverse, HostArray<Real>& table,
                 HostArray<unsigned char>& shape) {
  constexpr std::size_t kMostShapes = 256, kBytes = 9 * sizeof(Real);
  const std::size_t elements = rest_inverse.size() / 9;
  table.clear();
  shape.resize(elements);
  std::unordered_multimap<std::uint64_t, std::size_t> found;  // FNV-1a of the bytes -> shape
  for (std::size_t e = 0; e < elements; ++e) {
    const Real* own = rest_inverse.data() + 9 * e;
    const auto* bytes = reinterpret_cast<const unsigned char*>(own);
    std::uint64_t hash = 1469598103934665603ull;
    for (std::size_t i = 0; i < kBytes; ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
    std::size_t index = kMostShapes;
    const auto range = found.equal_range(hash);
    for (auto it = range.first; it != range.second && index == kMostShapes; ++it)
      if (std::memcmp(table.data() + 9 * it->second, own, kBytes) == 0) index = it->second;
    if (index == kMostShapes) {
      index = table.size() / 9;
      if (index == kMostShapes) {
        table.clear();
        shape.clear();
        return false;
      }
      table.insert(table.end(), own, own + 9);
      found.emplace(hash, index);
    }
    shape[e] = static_cast<unsigned char>(index);
  }
  return true;
}

// Each node's rank among its vertex's corners, corner_slot[k] - corner_offset[nodes[k]] (ElementTermView::
// corner_rank), one byte per node; empty where some rank exceeds 255 (the element pass then reads corner_slot).
HostArray<unsigned char> corner_ranks(const ConcatenatedScenes& c);

// The values converted to Real, on the pool.
template <typename Real, typename Allocator>
HostArray<Real> convert(const std::vector<double, Allocator>& values, sim::WorkerPool& pool) {
  HostArray<Real> out(values.size());
  fill_on_pool(pool, out, 0, values.size(), [&](std::size_t i) { return static_cast<Real>(values[i]); });
  return out;
}

}  // namespace fmpc::gpu
