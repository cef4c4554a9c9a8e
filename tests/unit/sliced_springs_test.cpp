// The sliced ELLPACK layout of the springs' CSR entries (runtime/springs/sliced_springs.h, kernels/spring_math.h):
// its order and rows on seeded random networks of every awkward size, and the gather through it bitwise equal to
// the gather in CSR order (the GPU's kernels with one thread per vertex read this layout; tests/gpu compares the
// runs).
#include "runtime/springs/sliced_springs.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/integrator_math.h"
#include "kernels/internal_force_math.h"
#include "kernels/spring_math.h"
#include "runtime/integrate/worker_pool.h"

using namespace fmpc;

namespace {

// A random CSR over n vertices: entry counts mostly from a few values (ties), some zero, some long rows; every entry
// its own spring with random parameters, neighbours anywhere.
template <typename Real>
struct SlicedCase {
  std::vector<int> offset{0}, spring, neighbour;
  std::vector<unsigned char> fixed;  // loads' masks: some vertices held on every axis, some on one
  std::vector<Real> rest_length, stiffness, damping;
  std::vector<Real> state[6];

  SlicedCase(int n, bool damped, std::mt19937& random) {
    std::uniform_int_distribution<int> pick(0, 9);
    for (int v = 0; v < n; ++v) {
      const int kind = pick(random);
      const int count = kind == 0 ? 0 : kind < 4 ? 10 : kind < 8 ? 26 : kind == 8 ? 1 : 40 + pick(random);
      offset.push_back(offset.back() + count);
      const int held = pick(random);
      fixed.push_back(held < 2 ? kernels::kAllAxesFixed : held == 2 ? 2 : 0);
    }
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_int_distribution<int> vertex(0, n > 0 ? n - 1 : 0);
    for (int e = 0; e < offset.back(); ++e) {
      spring.push_back(e);
      neighbour.push_back(vertex(random));
      rest_length.push_back(static_cast<Real>(0.5 + 0.4 * unit(random)));
      stiffness.push_back(static_cast<Real>(1000.0 * (1.5 + unit(random))));
      if (damped) damping.push_back(static_cast<Real>(2.0 + unit(random)));
    }
    for (auto& axis : state)
      for (int v = 0; v < n; ++v) axis.push_back(static_cast<Real>(unit(random)));
  }

  kernels::SpringNetworkView<Real> view() const {
    kernels::SpringNetworkView<Real> net{};
    net.adjacency_offset = offset.data();
    net.adjacency_spring = spring.data();
    net.adjacency_neighbour = neighbour.data();
    net.rest_length = rest_length.data();
    net.stiffness = stiffness.data();
    net.damping = damping.empty() ? nullptr : damping.data();
    return net;
  }
  kernels::StateView<Real> state_view() const {
    return {state[0].data(), state[1].data(), state[2].data(), state[3].data(), state[4].data(), state[5].data()};
  }
};

template <typename Real>
bool bitwise_same(Real a, Real b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// The layout's invariants, then every vertex's gather through it against the CSR order (bitwise). The checks of
// one network are counted and asserted once (a REQUIRE per entry made the test 20 s under the sanitizers); the
// first failure is named.
template <typename Real>
void check_sliced(int n, int window, bool damped, std::mt19937& random, sim::WorkerPool& pool) {
  const SlicedCase<Real> c(n, damped, random);
  sim::SlicedSpringLayout layout;
  const bool with_fixed = n % 2 == 0;
  REQUIRE(sim::slice_spring_entries(c.offset.data(), with_fixed ? c.fixed.data() : nullptr, n, window, pool, layout));
  const int width = sim::valid_slice_window(window) ? window : sim::kDefaultSliceWindow;
  REQUIRE(layout.vertex_order.size() == static_cast<std::size_t>(n));
  REQUIRE(layout.row.size() == static_cast<std::size_t>(n));
  const auto count = [&](int v) { return c.offset[v + 1] - c.offset[v]; };
  // What a vertex's gather walks: nothing where every axis is held.
  const auto walked = [&](int v) { return with_fixed && c.fixed[v] == kernels::kAllAxesFixed ? 0 : count(v); };
  std::string failure;
  const auto expect = [&](bool holds, const char* what, int r) {
    if (!holds && failure.empty()) failure = std::string(what) + " at row " + std::to_string(r);
  };
  std::int64_t widths = 0;
  int slice_width = 0;
  std::vector<char> seen(static_cast<std::size_t>(n), 0);
  for (int r = 0; r < n; ++r) {
    const int v = layout.vertex_order[r];
    const bool in_window = v >= 0 && v < n && v / width == r / width;
    expect(in_window, "a vertex outside its row's window", r);
    if (!in_window) break;
    expect(!seen[v], "a vertex taken twice", r);
    seen[v] = 1;
    if (r % width != 0) {
      const int before = layout.vertex_order[r - 1];
      // Most entries walked first, ties by vertex index.
      expect(walked(before) > walked(v) || (walked(before) == walked(v) && before < v), "out of order", r);
    }
    // Every row holds all its vertex's entries; a slice is as wide as its longest.
    expect(layout.row[r].count == count(v), "a row's count differs from its vertex's", r);
    slice_width = r % kernels::kSliceRows == 0 ? count(v) : std::max(slice_width, count(v));
    if (r % kernels::kSliceRows == kernels::kSliceRows - 1 || r == n - 1)
      widths += std::int64_t{kernels::kSliceRows} * slice_width;
  }
  INFO(failure);
  REQUIRE(failure.empty());
  // No padding beyond each slice's longest row.
  REQUIRE(layout.entries == widths);
  std::vector<char> used(static_cast<std::size_t>(layout.entries), 0);
  for (int r = 0; r < n && failure.empty(); ++r)
    for (int j = 0; j < layout.row[r].count; ++j) {
      const std::int64_t at = layout.row[r].first + std::int64_t{kernels::kSliceRows} * j;
      const bool inside = at >= 0 && at < layout.entries;
      expect(inside, "an entry outside the layout", r);
      if (!inside) break;
      expect(!used[static_cast<std::size_t>(at)], "two entries in one place", r);
      used[static_cast<std::size_t>(at)] = 1;
    }
  INFO(failure);
  REQUIRE(failure.empty());

  std::vector<kernels::SpringIncidence<Real>> record(static_cast<std::size_t>(layout.entries));
  const kernels::SpringNetworkView<Real> csr = c.view();
  kernels::SpringNetworkView<Real> sliced = csr;
  sliced.sliced = {layout.row.data(), record.data()};
  for (int r = 0; r < n; ++r) kernels::write_sliced_row(layout.vertex_order[r], csr, layout.row[r], record.data());
  const kernels::StateView<Real> s = c.state_view();
  for (int r = 0; r < n; ++r) {
    const int v = layout.vertex_order[r];
    Real a[3], b[3];
    kernels::SpringForces<Real>{csr}.gather(v, s, a[0], a[1], a[2]);
    kernels::SpringForces<Real>{sliced, layout.row[r]}.gather(v, s, b[0], b[1], b[2]);
    for (int axis = 0; axis < 3; ++axis) expect(bitwise_same(a[axis], b[axis]), "the gather's bits differ", r);
  }
  INFO(failure);
  REQUIRE(failure.empty());
}

}  // namespace

TEST_CASE("sliced springs: order within windows, rows without overlap, the CSR gather's bits", "[sim][sliced]") {
  std::mt19937 random(20261125);
  sim::WorkerPool pool(3, 1);  // several parts even for small networks
  // Empty, one vertex, around a slice (32) and a block (256), and random sizes.
  std::vector<int> sizes{0, 1, 2, 31, 32, 33, 255, 256, 257, 511, 513, 1000};
  std::uniform_int_distribution<int> size(0, 700);
  while (sizes.size() < 1000) sizes.push_back(size(random));
  // Every window, and windows that are not one (0, 48, 2048: the default).
  const int windows[] = {32, 64, 128, 256, 1024, 0, 48, 2048};
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    const bool damped = i % 2 == 0;
    const int window = windows[i % 8];
    if (i % 3 == 0)
      check_sliced<double>(sizes[i], window, damped, random, pool);
    else
      check_sliced<float>(sizes[i], window, damped, random, pool);
  }
}

TEST_CASE("sliced springs: a layout beyond int indices is refused before anything is filled", "[sim][sliced]") {
  sim::WorkerPool pool(2, 1);
  // Vertices 0 and 256 (two windows of 256, so no sort puts them in one slice) have 2^25 entries each: two slices
  // of 32 x 2^25 = 2^31 entries, one more than int holds.
  std::vector<int> offset(258, 0);
  for (int v = 0; v < 257; ++v) offset[v + 1] = offset[v] + (v == 0 || v == 256 ? 1 << 25 : 0);
  sim::SlicedSpringLayout layout;
  CHECK_FALSE(sim::slice_spring_entries(offset.data(), nullptr, 257, 256, pool, layout));
  CHECK(layout.entries == std::int64_t{1} << 31);
  // Within one window, the sort puts both in the first slice: 2^30 entries.
  for (int v = 0; v < 257; ++v) offset[v + 1] = offset[v] + (v == 0 || v == 32 ? 1 << 25 : 0);
  REQUIRE(sim::slice_spring_entries(offset.data(), nullptr, 257, 256, pool, layout));
  CHECK(layout.entries == std::int64_t{1} << 30);
  CHECK(layout.vertex_order[1] == 32);
  CHECK(layout.row[1].first == 1);
  CHECK(layout.row[1].count == 1 << 25);
}
