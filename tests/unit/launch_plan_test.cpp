// The CUDA backend's launch plan (runtime/gpu/launch_plan.h) and batch admission (runtime/gpu/
// batch_concatenation.h), on machines without a GPU: the device's answers are given by fake DeviceLaunchLimits.
#include "runtime/gpu/launch_plan.h"

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "kernels/element_laws.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/gpu/batch_concatenation.h"
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/mesh/generated_mesh.h"

using namespace fmpc;
using namespace fmpc::gpu;

namespace {

// The springs' CSR of a grid of nx x ny x nz vertices joined to their axis neighbours, scenes after one another.
struct GridBatch {
  std::vector<int> offset{0}, neighbour;
  BatchShape shape;

  GridBatch(int nx, int ny, int nz) : GridBatch(std::vector<std::array<int, 3>>{{nx, ny, nz}}) {}
  explicit GridBatch(const std::vector<std::array<int, 3>>& scenes) {
    shape.vertex_begin = {0};
    shape.element_begin = {0};
    int base = 0;
    for (const std::array<int, 3>& cells : scenes) {
      // Copies, not structured bindings: a lambda may not capture those before C++20 (clang refuses).
      const int nx = cells[0], ny = cells[1], nz = cells[2];
      for (int z = 0; z < nz; ++z)
        for (int y = 0; y < ny; ++y)
          for (int x = 0; x < nx; ++x) {
            // Copies: C++17 lambdas cannot capture structured bindings (clang refuses; GCC allows it).
            const auto add = [&, sx = nx, sy = ny, sz = nz](int i, int j, int k) {
              if (i >= 0 && i < sx && j >= 0 && j < sy && k >= 0 && k < sz)
                neighbour.push_back(base + (k * sy + j) * sx + i);
            };
            add(x - 1, y, z);
            add(x + 1, y, z);
            add(x, y - 1, z);
            add(x, y + 1, z);
            add(x, y, z - 1);
            add(x, y, z + 1);
            offset.push_back(static_cast<int>(neighbour.size()));
          }
      base += nx * ny * nz;
      shape.vertex_begin.push_back(base);
      shape.element_begin.push_back(0);
    }
    shape.vertex_count = base;
    shape.scene_count = scenes.size();
    shape.fused_scheme = true;
    shape.offset = offset.data();
    shape.neighbour = neighbour.data();
  }
};

// A device that keeps `resident` persistent blocks whose shared memory fits `shared_limit` bytes (none beyond), and
// clusters of up to `most_cluster_blocks` blocks within the same limit. Counts its queries.
struct FakeDevice {
  int resident = 264;
  int cg_resident = 264;
  long long cg_block_limit = 227 * 1024;
  long long shared_limit = 227 * 1024;
  int most_cluster_blocks = 16;
  bool fail = false;
  int queries = 0;

  DeviceLaunchLimits limits() {
    DeviceLaunchLimits limits;
    limits.persistent_blocks = [this](GatherKind, long long bytes) -> std::optional<int> {
      ++queries;
      if (fail) return std::nullopt;
      return bytes <= shared_limit ? resident : 0;
    };
    limits.cluster_fits = [this](int blocks, int rows, long long bytes) -> std::optional<bool> {
      ++queries;
      if (fail) return std::nullopt;
      return blocks <= most_cluster_blocks && rows <= kClusterRows && bytes <= shared_limit;
    };
    limits.cg_persistent_blocks = [this]() -> std::optional<int> {
      ++queries;
      if (fail) return std::nullopt;
      return cg_resident;
    };
    limits.cg_block_shared_limit = [this]() -> std::optional<long long> {
      ++queries;
      if (fail) return std::nullopt;
      return cg_block_limit;
    };
    return limits;
  }
};

// SOFA's liver under implicit Euler (181 vertices, 596 linear tetrahedra), no springs (offsets: 182 zeros).
BatchShape sofa_liver_implicit(std::vector<int>& offset) {
  BatchShape shape;
  shape.implicit_scheme = true;
  shape.vertex_count = 181;
  shape.element_count = 596;
  shape.element_nodes = 4 * 596;
  shape.vertex_begin = {0, 181};
  shape.element_begin = {0, 596};
  offset.assign(182, 0);
  shape.offset = offset.data();
  return shape;
}

sim::GpuOptions options_with(sim::GpuOptions::PersistentKind kind) {
  sim::GpuOptions options;
  options.persistent_kind = kind;
  return options;
}

}  // namespace

TEST_CASE("Launch plan: the fused kernel's lanes follow the mesh's size, the model and a valid setting",
          "[gpu][plan]") {
  FakeDevice device;
  sim::GpuOptions options;
  options.persistent = false;
  GridBatch box(21, 21, 21);  // the 20^3 box's 9,261 vertices
  CHECK(plan_launches(box.shape, options, device.limits())->gather_lanes == 8);
  box.shape.vertex_count = 1 << 16;  // 2^16 x 4 = 2^18: the most lanes that keep within 2^18 threads
  CHECK(plan_launches(box.shape, options, device.limits())->gather_lanes == 4);
  box.shape.vertex_count = (1 << 18) + 1;
  CHECK(plan_launches(box.shape, options, device.limits())->gather_lanes == 1);
  box.shape.vertex_count = 9261;
  box.shape.kind = GatherKind::Elements;
  CHECK(plan_launches(box.shape, options, device.limits())->gather_lanes == 4);
  for (const int lanes : {1, 2, 16, 32}) {
    options.gather_lanes = lanes;
    CHECK(plan_launches(box.shape, options, device.limits())->gather_lanes == lanes);
  }
  for (const int invalid : {3, 64, -2}) {  // not a power of two up to a warp: automatic
    options.gather_lanes = invalid;
    CHECK(plan_launches(box.shape, options, device.limits())->gather_lanes == 4);
  }
  // Even a setting keeps vertices x lanes within 2^30.
  options.gather_lanes = 32;
  box.shape.vertex_count = 1 << 26;
  CHECK(plan_launches(box.shape, options, device.limits())->gather_lanes == 16);
  CHECK(device.queries == 0);  // nothing persistent was asked for: the device is never queried
}

TEST_CASE("Launch plan: no persistent launch where a step needs its own launches", "[gpu][plan]") {
  FakeDevice device;
  GridBatch box(21, 21, 21);
  const auto not_persistent = [&](const BatchShape& shape, const sim::GpuOptions& options) {
    const std::optional<LaunchPlan> plan = plan_launches(shape, options, device.limits());
    REQUIRE(plan);
    CHECK_FALSE(plan->persistent());
    CHECK(plan->persistent_checks == 1);
    CHECK(plan->neighbour_offset.empty());
  };
  sim::GpuOptions off;
  off.persistent = false;
  not_persistent(box.shape, off);
  BatchShape shape = box.shape;
  shape.strain_table = true;
  not_persistent(shape, {});
  shape = box.shape;
  shape.point_state = true;  // a viscoelastic term's update between steps
  not_persistent(shape, {});
  shape = box.shape;
  shape.nodal_pass = true;  // the nodal pressure kind's shares and gather before each element pass
  not_persistent(shape, {});
  shape = box.shape;
  shape.element_kind_not_persistent = true;  // the quadratic kind: its element pass outside the persistent kernel
  not_persistent(shape, {});
  shape = box.shape;
  shape.probe_vertices_unique = false;
  not_persistent(shape, {});
  shape = box.shape;
  shape.fused_scheme = false;  // Verlet, RK4, implicit Euler
  not_persistent(shape, {});
  shape = box.shape;
  shape.vertex_count = 0;
  not_persistent(shape, {});
  CHECK(device.queries == 0);
}

TEST_CASE("Launch plan: the persistent kernel holds the linear tetrahedron, not the quadratic or nodal kinds",
          "[gpu][plan]") {
  CHECK(kernels::element_kind_runs_persistent(sim::element_kind_by_keyword("linear")->kind));
  CHECK_FALSE(kernels::element_kind_runs_persistent(sim::element_kind_by_keyword("quadratic")->kind));
  CHECK_FALSE(kernels::element_kind_runs_persistent(sim::element_kind_by_keyword("linear_nodal_pressure")->kind));
}

TEST_CASE("Launch plan: the cooperative grid takes the fewest rows whose blocks are all resident", "[gpu][plan]") {
  FakeDevice device;
  device.resident = 258;  // the 20^3 box on an H100: 36 rows, 258 blocks (sim::GpuOptions)
  GridBatch box(21, 21, 21);
  const std::optional<LaunchPlan> plan = plan_launches(box.shape, {}, device.limits());
  REQUIRE(plan);
  CHECK(plan->grid_rows == 36);
  CHECK(plan->grid_blocks == 258);
  CHECK(plan->cluster_blocks.empty());
  // Each block waits for exactly the other blocks owning a neighbour of its vertices.
  REQUIRE(plan->neighbour_offset.size() == 259);
  int most = 0;
  for (int b = 0; b < 258; ++b) {
    std::set<int> owners;
    const auto at = [](int i) { return static_cast<std::size_t>(i); };
    for (int v = b * 36; v < std::min(9261, (b + 1) * 36); ++v)
      for (int e = box.offset[at(v)]; e < box.offset[at(v) + 1]; ++e)
        if (box.neighbour[at(e)] / 36 != b) owners.insert(box.neighbour[at(e)] / 36);
    const auto first = plan->neighbour_block.begin();
    const std::vector<int> planned(first + plan->neighbour_offset[at(b)], first + plan->neighbour_offset[at(b) + 1]);
    CHECK(planned == std::vector<int>(owners.begin(), owners.end()));
    most = std::max(most, static_cast<int>(owners.size()));
  }
  CHECK(plan->grid_most_waited == most);
  // 64 MiB of float checkpoints fit 301 states of 9,261 vertices: the most checks, 64.
  CHECK(plan->persistent_checks == kMostPersistentChecks);
  CHECK(plan->check_slot_stride == 1);
}

TEST_CASE("Launch plan: a rows setting that does not fit takes the nearest that does, more rows first", "[gpu][plan]") {
  FakeDevice device;
  device.resident = 258;
  GridBatch box(21, 21, 21);
  sim::GpuOptions options;
  options.persistent_rows = 100;  // fits: 93 blocks
  CHECK(plan_launches(box.shape, options, device.limits())->grid_rows == 100);
  options.persistent_rows = 10;  // 927 blocks are not resident: the fewest that are
  CHECK(plan_launches(box.shape, options, device.limits())->grid_rows == 36);
  options.persistent_rows = 4096;  // more than a block's threads
  CHECK(plan_launches(box.shape, options, device.limits())->grid_rows == kPersistentThreads);
  // Shared memory bounds the rows from above: about 40 rows' state and records fit, so a setting of 200 comes down
  // to the most rows whose block fits.
  device.shared_limit = persistent_euler_shared_bytes<float>(40, 40 * 6, 0);
  options.persistent_rows = 200;
  const std::optional<LaunchPlan> plan = plan_launches(box.shape, options, device.limits());
  REQUIRE(plan->grid_blocks > 0);
  CHECK(plan->grid_rows >= 36);
  CHECK(plan->grid_rows < 200);
  CHECK(persistent_euler_shared_bytes<float>(plan->grid_rows, plan->grid_block_records, plan->grid_most_waited) <=
        device.shared_limit);
  options.persistent_rows = plan->grid_rows + 1;
  CHECK(plan_launches(box.shape, options, device.limits())->grid_rows == plan->grid_rows);
}

TEST_CASE("Launch plan: clusters where the grid does not fit, and as preferred", "[gpu][plan]") {
  FakeDevice device;
  device.resident = 258;
  SECTION("one scene spreads over 16 blocks of at least 256 rows") {
    GridBatch box(21, 21, 21);
    const auto plan =
        plan_launches(box.shape, options_with(sim::GpuOptions::PersistentKind::Clusters), device.limits());
    REQUIRE(plan);
    CHECK(plan->grid_blocks == 0);
    CHECK(plan->cluster_size == 16);
    CHECK(plan->cluster_rows == 608);  // the 20^3 box: 16 blocks of 608 (docs/simulator.md)
    CHECK(plan->persistent_checks == 1);
  }
  SECTION("a thousand small scenes: one block each, scenes never split") {
    GridBatch cohort(std::vector<std::array<int, 3>>(1000, {8, 10, 5}));  // 400 vertices each
    const auto plan = plan_launches(cohort.shape, {}, device.limits());   // automatic: too many for the grid
    REQUIRE(plan);
    CHECK(plan->grid_blocks == 0);
    CHECK(plan->cluster_size == 1);
    CHECK(plan->cluster_rows == 416);
    REQUIRE(plan->cluster_blocks.size() == 1000);
    for (std::size_t s = 0; s < 1000; ++s) {
      CHECK(plan->cluster_blocks[s].first_vertex == cohort.shape.vertex_begin[s]);
      CHECK(plan->cluster_blocks[s].end_vertex == cohort.shape.vertex_begin[s + 1]);
    }
  }
  SECTION("a scene beyond 16 x 1,024 vertices has no cluster; nor has anything where no shape fits") {
    GridBatch large(40, 40, 11);  // 17,600 vertices
    device.resident = 1;
    auto plan = plan_launches(large.shape, options_with(sim::GpuOptions::PersistentKind::Clusters), device.limits());
    REQUIRE(plan);
    CHECK_FALSE(plan->persistent());
    GridBatch box(21, 21, 21);
    device.shared_limit = 1024;
    plan = plan_launches(box.shape, options_with(sim::GpuOptions::PersistentKind::Clusters), device.limits());
    REQUIRE(plan);
    CHECK_FALSE(plan->persistent());
  }
  SECTION("elements never run in clusters") {
    GridBatch box(21, 21, 21);
    box.shape.kind = GatherKind::SpringsAndElements;
    device.resident = 0;
    const auto plan =
        plan_launches(box.shape, options_with(sim::GpuOptions::PersistentKind::Clusters), device.limits());
    REQUIRE(plan);
    CHECK_FALSE(plan->persistent());
  }
}

TEST_CASE("Launch plan: cluster blocks cover every vertex once and their windows hold every neighbour (seeded)",
          "[gpu][plan]") {
  std::mt19937 random(20261127);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<std::array<int, 3>> scenes(1 + random() % 30);
    for (auto& scene : scenes)
      scene = {1 + static_cast<int>(random() % 12), 1 + static_cast<int>(random() % 12),
               1 + static_cast<int>(random() % 12)};
    GridBatch batch(scenes);
    FakeDevice device;
    device.resident = 0;
    const auto plan = plan_launches(batch.shape, {}, device.limits());
    REQUIRE(plan);
    REQUIRE_FALSE(plan->cluster_blocks.empty());
    const auto at = [](int i) { return static_cast<std::size_t>(i); };
    std::vector<int> owner(at(batch.shape.vertex_count), -1);
    for (std::size_t b = 0; b < plan->cluster_blocks.size(); ++b) {
      const ClusterBlock& block = plan->cluster_blocks[b];
      REQUIRE(block.end_vertex - block.first_vertex <= plan->cluster_rows);
      if (plan->cluster_size > 1) REQUIRE(block.window_count <= plan->cluster_window_capacity);
      for (int v = block.first_vertex; v < block.end_vertex; ++v) {
        REQUIRE(owner[at(v)] == -1);
        owner[at(v)] = static_cast<int>(b);
        for (int e = batch.offset[at(v)]; e < batch.offset[at(v) + 1]; ++e) {
          REQUIRE(batch.neighbour[at(e)] >= block.window_first);
          REQUIRE(batch.neighbour[at(e)] < block.window_first + block.window_count);
        }
      }
    }
    REQUIRE(std::count(owner.begin(), owner.end(), -1) == 0);
    // A vertex and its neighbours are in one cluster: clusters never split a scene.
    for (int v = 0; v < batch.shape.vertex_count; ++v)
      for (int e = batch.offset[at(v)]; e < batch.offset[at(v) + 1]; ++e)
        REQUIRE(owner[at(v)] / plan->cluster_size == owner[at(batch.neighbour[at(e)])] / plan->cluster_size);
  }
}

TEST_CASE("Launch plan: checks per persistent launch, their result slots, and a failed device query", "[gpu][plan]") {
  FakeDevice device;
  device.resident = 1 << 20;
  GridBatch box(64, 64, 64);  // 262,144 vertices: 6 MiB of float state, 10 checkpoints in 64 MiB
  auto plan = plan_launches(box.shape, {}, device.limits());
  REQUIRE(plan->grid_blocks > 0);
  CHECK(plan->persistent_checks == 10);
  box.shape.double_precision = true;
  CHECK(plan_launches(box.shape, {}, device.limits())->persistent_checks == 5);
  box.shape.element_count = 7;
  box.shape.scene_count = 3;
  CHECK(plan_launches(box.shape, {}, device.limits())->check_slot_stride == 7);  // non-finite + 2 per scene
  device.fail = true;
  CHECK_FALSE(plan_launches(box.shape, {}, device.limits()));
}

// SOFA's liver (181 vertices, 596 tetrahedra: 3 blocks) and the 20^3 FEM box (9,261 vertices, 48,000 tetrahedra:
// 188 blocks, the elements' count) fit an H100's cooperative grid; a mesh with more entries than resident threads
// keeps the per-iteration kernels, as do explicit schemes and the persistent option off. (The liver's solve also
// fits one block, which the plan prefers: the cases here turn that off.)
TEST_CASE("Launch plan: implicit Euler's conjugate gradient in one cooperative launch where it fits", "[gpu][plan]") {
  FakeDevice device;
  device.cg_block_limit = 0;
  std::vector<int> offset;
  BatchShape shape = sofa_liver_implicit(offset);
  auto plan = plan_launches(shape, {}, device.limits());
  REQUIRE(plan);
  CHECK(plan->cg_grid_blocks == 3);  // 596 elements against 543 degrees of freedom
  CHECK(plan->cg_block_bytes == 0);
  CHECK_FALSE(plan->persistent());   // the explicit launches are not planned
  sim::GpuOptions grid;
  grid.cg_single_block = false;
  device.cg_block_limit = 227 * 1024;
  CHECK(plan_launches(shape, grid, device.limits())->cg_grid_blocks == 3);
  device.cg_block_limit = 0;
  shape.element_nodes = 0;
  shape.vertex_count = 9261;
  shape.element_count = 48000;
  CHECK(plan_launches(shape, {}, device.limits())->cg_grid_blocks == 188);
  shape.element_count = 0;
  CHECK(plan_launches(shape, {}, device.limits())->cg_grid_blocks == 109);  // 27,783 degrees of freedom
  shape.vertex_count = 1;
  CHECK(plan_launches(shape, {}, device.limits())->cg_grid_blocks == 1);
  // More blocks than resident: per-iteration kernels. Exactly resident: cooperative.
  shape.vertex_count = 9261;
  shape.element_count = 48000;
  device.cg_resident = 187;
  CHECK(plan_launches(shape, {}, device.limits())->cg_grid_blocks == 0);
  device.cg_resident = 188;
  CHECK(plan_launches(shape, {}, device.limits())->cg_grid_blocks == 188);
  device.cg_resident = 0;  // no cooperative launches
  CHECK(plan_launches(shape, {}, device.limits())->cg_grid_blocks == 0);
  device.cg_resident = 264;
  sim::GpuOptions off;
  off.persistent = false;
  const int queries = device.queries;
  CHECK(plan_launches(shape, off, device.limits())->cg_grid_blocks == 0);
  shape.implicit_scheme = false;
  CHECK(plan_launches(shape, {}, device.limits())->cg_grid_blocks == 0);
  CHECK(device.queries == queries);  // neither asks the device
  shape.implicit_scheme = true;
  shape.vertex_count = 0;
  CHECK(plan_launches(shape, {}, device.limits())->cg_grid_blocks == 0);
  shape.vertex_count = 181;
  device.fail = true;
  CHECK_FALSE(plan_launches(shape, {}, device.limits()));
}

TEST_CASE("Launch plan: implicit Euler's stages fused up to one stride of the dot products", "[gpu][plan]") {
  FakeDevice device;
  std::vector<int> offset;
  BatchShape shape = sofa_liver_implicit(offset);
  CHECK(plan_launches(shape, {}, device.limits())->cg_fused_stages);
  shape.element_nodes = 0;
  shape.element_count = 48000;
  shape.vertex_count = 10922;  // 32,766 degrees of freedom
  CHECK(plan_launches(shape, {}, device.limits())->cg_fused_stages);
  shape.vertex_count = 10923;  // 32,769: a thread would take two entries
  CHECK_FALSE(plan_launches(shape, {}, device.limits())->cg_fused_stages);
  shape.vertex_count = 9261;
  sim::GpuOptions off;
  off.cg_fused_stages = false;
  CHECK_FALSE(plan_launches(shape, off, device.limits())->cg_fused_stages);
  sim::GpuOptions per_iteration;
  per_iteration.persistent = false;
  CHECK(plan_launches(shape, per_iteration, device.limits())->cg_fused_stages);
  shape.implicit_scheme = false;
  CHECK_FALSE(plan_launches(shape, {}, device.limits())->cg_fused_stages);
  shape.implicit_scheme = true;
  shape.vertex_count = 0;
  CHECK_FALSE(plan_launches(shape, {}, device.limits())->cg_fused_stages);
}

TEST_CASE("Launch plan: conjugate gradient iterations between two reads of its scalars", "[gpu][plan]") {
  // The previous step's count first, then doubling, at least 4, never beyond the cap.
  CHECK(cg_iterations_before_read(25, 0, 25) == 25);
  CHECK(cg_iterations_before_read(0, 0, 25) == kCgLeastIterationsPerRead);
  CHECK(cg_iterations_before_read(1, 0, 25) == kCgLeastIterationsPerRead);
  CHECK(cg_iterations_before_read(10, 10, 1000) == 10);
  CHECK(cg_iterations_before_read(10, 20, 1000) == 20);
  CHECK(cg_iterations_before_read(10, 2, 1000) == kCgLeastIterationsPerRead);
  CHECK(cg_iterations_before_read(40, 0, 25) == 25);
  CHECK(cg_iterations_before_read(25, 20, 25) == 5);
  CHECK(cg_iterations_before_read(25, 25, 25) == 0);
  CHECK(cg_iterations_before_read(25, 30, 25) == 0);
  CHECK(cg_iterations_before_read(5, 0, 0) == 0);
  CHECK(cg_iterations_before_read(5, 0, -3) == 0);
  // Reads per solve of n iterations: at most 1 + log2(n / 4), never one per iteration.
  for (const int n : {1, 3, 4, 5, 17, 138, 1000}) {
    int enqueued = 0, reads = 0;
    while (enqueued < n) {
      const int chunk = cg_iterations_before_read(0, enqueued, 5000);
      REQUIRE(chunk >= kCgLeastIterationsPerRead);
      enqueued += chunk;
      ++reads;
    }
    CHECK(reads <= 1 + std::max(0, static_cast<int>(std::ceil(std::log2(n / 4.0)))));
  }
}

TEST_CASE("GPU batch admission: what scenes must share is named, on machines without a GPU", "[gpu][batch]") {
  DiagnosticList diagnostics;
  sim::BoxSpec spec;
  spec.cells_x = spec.cells_y = spec.cells_z = 2;
  const sim::Mesh box = sim::generate_box(spec, diagnostics);
  sim::SimulationSetup setup;
  setup.rest_positions = box.points;
  setup.springs = sim::springs_from_tetrahedra(box, diagnostics);
  std::vector<sim::SimulationSetup> scenes(2, setup);
  CHECK(batch_accepts(scenes, 1, diagnostics));
  scenes[1].integrator = sim::Integrator::RungeKutta4;
  CHECK_FALSE(batch_accepts(scenes, 1, diagnostics));
  CHECK(
      diagnostics.items().back().message ==
      "scene 1 differs from scene 0 in its integrator; the scenes of one GPU batch share it: run it in another batch");
  scenes[1] = setup;
  scenes[1].gravity[2] = -9.81;
  CHECK_FALSE(batch_accepts(scenes, 1, diagnostics));
  CHECK(diagnostics.items().back().message.find("in its gravity;") != std::string::npos);
  scenes[1] = setup;
  scenes[1].integrator = sim::Integrator::ImplicitEuler;
  scenes[0].integrator = sim::Integrator::ImplicitEuler;
  CHECK_FALSE(batch_accepts(scenes, 1, diagnostics));
  CHECK(diagnostics.items().back().message.rfind("scene 1: implicit Euler runs one scene at a time", 0) == 0);
  scenes.resize(1);
  CHECK(batch_accepts(scenes, 0, diagnostics));  // alone, implicit Euler is accepted
  CHECK(gather_kind(setup) == GatherKind::Springs);
}

// The whole solve in one block where its vectors and element products fit the block's shared memory: SOFA's liver
// (181 vertices, 596 linear tetrahedra: 12,511 doubles, 100,088 bytes); not the 20^3 box; not where the device gives
// the kernel less than it needs, nor with the option or the persistent launches off; the layout's arrays follow one
// another without overlap.
TEST_CASE("Launch plan: implicit Euler's solve in one block where it fits its shared memory", "[gpu][plan]") {
  const CgBlockLayout liver = cg_block_layout(181, 4 * 596);
  CHECK(liver.x == 0);
  CHECK(liver.r == 543);
  CHECK(liver.inverse_jacobi == 5 * 543);
  CHECK(liver.diagonal == 6 * 543);
  CHECK(liver.product == 6 * 543 + 181);
  CHECK(liver.terms == 6 * 543 + 181 + 3 * 4 * 596);
  CHECK(liver.alpha_partial == liver.terms + 2 * 768);  // 543 rounded up to 3 x 256
  CHECK(liver.residual_partial == liver.alpha_partial + kEnergyBlocks);
  CHECK(liver.doubles == 12511);
  FakeDevice device;
  std::vector<int> offset;
  BatchShape shape = sofa_liver_implicit(offset);
  auto plan = plan_launches(shape, {}, device.limits());
  REQUIRE(plan);
  CHECK(plan->cg_block_bytes == 100088);
  CHECK(plan->cg_block.residual_partial == liver.residual_partial);
  CHECK(plan->cg_grid_blocks == 0);
  device.cg_block_limit = 100088;  // exactly enough
  CHECK(plan_launches(shape, {}, device.limits())->cg_block_bytes == 100088);
  device.cg_block_limit = 100087;  // one byte short: the cooperative grid
  plan = plan_launches(shape, {}, device.limits());
  CHECK(plan->cg_block_bytes == 0);
  CHECK(plan->cg_grid_blocks == 3);
  device.cg_block_limit = 227 * 1024;
  sim::GpuOptions off;
  off.cg_single_block = false;
  CHECK(plan_launches(shape, off, device.limits())->cg_block_bytes == 0);
  off = {};
  off.persistent = false;
  plan = plan_launches(shape, off, device.limits());
  CHECK(plan->cg_block_bytes == 0);
  CHECK(plan->cg_grid_blocks == 0);
  shape.vertex_count = 9261;  // the 20^3 box
  shape.element_count = 48000;
  shape.element_nodes = 4 * 48000;
  plan = plan_launches(shape, {}, device.limits());
  CHECK(plan->cg_block_bytes == 0);
  CHECK(plan->cg_grid_blocks == 188);
  shape.vertex_count = 181;
  shape.element_count = 596;
  shape.element_nodes = 4 * 596;
  device.fail = true;
  CHECK_FALSE(plan_launches(shape, {}, device.limits()));
}
