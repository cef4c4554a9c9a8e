// GPU throughput of the generated CUDA evaluator and of table lookups, checked against the CPU first.
// Built and run by bench/run_gpu.sh (section "evaluator") with nvcc -arch=sm_90; the headers it includes are
// generated on the build machine by `bench/run_gpu.sh --prepare` (build-gpu-carry/evaluator/):
//   liver_evaluator.cuh  fmpc compile rulesets/liver_fibrosis/mamdani.fis --target cuda (all five inputs vary)
//   liver_it2_evaluator.cuh  the same for rulesets/liver_fibrosis/it2.fis (interval type-2, Karnik-Mendel)
//   liver_table2.h       --target table, HCV ALD NAFLD fixed, HBV:65 CLD:65 (a 2-D table, 65 x 65)
//   liver_table2f.h      the same with --precision float (its packed groups are 16 bytes: read one lane each)
//   liver_table5.h       --target table, all five inputs :9 (a 5-D table, 9^5 points), double values
//   liver_table5f.h      the same with --precision float
//   liver_table5r7.h     all five inputs :7 (7^5 points, double: 131 KiB, fits an SM's L1)
//   liver_table5r5.h     all five inputs :5 (5^5 points, double: 24 KiB)
// (Coarser tables are less accurate: docs/performance.md, "The trade, measured", gives each resolution's error.)
// Every table is timed in both layouts of kernels/table_math.h (grid and sector-packed) through the header's
// launcher; the row says which one the launcher's Automatic picks.
// Usage: evaluator_gpu_bench OUT_DIR [points]   (default 2^24 points). Writes OUT_DIR/evaluator_gpu.{csv,md} and
// prints the markdown table last. Exit status 1 when a correctness check fails.
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "liver_evaluator.cuh"
#include "liver_it2_evaluator.cuh"
#include "liver_table2.h"
#include "liver_table2f.h"
#include "liver_table5.h"
#include "liver_table5f.h"
#include "liver_table5r5.h"
#include "liver_table5r7.h"

namespace {

#define CHECK_CUDA(call)                                                                             \
  do {                                                                                               \
    const cudaError_t status_ = (call);                                                              \
    if (status_ != cudaSuccess) {                                                                    \
      std::fprintf(stderr, "%s:%d: %s: %s\n", __FILE__, __LINE__, #call, cudaGetErrorString(status_)); \
      std::exit(2);                                                                                  \
    }                                                                                                \
  } while (0)

constexpr int kRepetitions = 10;
constexpr std::size_t kCheckedPoints = 1 << 16;
constexpr double kNotChecked = HUGE_VAL;  // a row's tolerance when the row is timed only

struct Row {
  std::string variant;
  double per_second = 0;
  double max_difference = 0;
  double tolerance = 0;
  bool ok = true;
};

// Best of kRepetitions launches, in seconds.
template <typename Launch>
double best_seconds(Launch launch) {
  cudaEvent_t start, stop;
  CHECK_CUDA(cudaEventCreate(&start));
  CHECK_CUDA(cudaEventCreate(&stop));
  launch();  // warm-up
  CHECK_CUDA(cudaDeviceSynchronize());
  float best = 1e30f;
  for (int r = 0; r < kRepetitions; ++r) {
    CHECK_CUDA(cudaEventRecord(start));
    launch();
    CHECK_CUDA(cudaEventRecord(stop));
    CHECK_CUDA(cudaEventSynchronize(stop));
    float ms = 0;
    CHECK_CUDA(cudaEventElapsedTime(&ms, start, stop));
    best = std::min(best, ms);
  }
  CHECK_CUDA(cudaEventDestroy(start));
  CHECK_CUDA(cudaEventDestroy(stop));
  return static_cast<double>(best) * 1e-3;
}

// The liver evaluators: type-1 Mamdani and interval type-2, the same five inputs.
#define FMPC_BENCH_EVALUATOR(Name, header, label)                                                          \
  struct Name {                                                                                           \
    static constexpr const char* kLabel = label;                                                          \
    static constexpr std::size_t kInputs = header::kInputCount;                                           \
    static double range() { return header::kOutputMax[0] - header::kOutputMin[0]; }                      \
    template <typename T>                                                                                 \
    static cudaError_t device_batch(const T* in, T* out, std::size_t n) {                                 \
      return header::evaluate_batch_cuda<T>(in, out, n);                                                  \
    }                                                                                                     \
    static void host(const double* in, double* out) { header::evaluate(in, out); }                        \
  };
FMPC_BENCH_EVALUATOR(LiverMamdani, liver_evaluator, "CUDA evaluator")
FMPC_BENCH_EVALUATOR(LiverIt2, liver_it2_evaluator, "CUDA evaluator, interval type-2 (it2.fis)")
#undef FMPC_BENCH_EVALUATOR

template <typename Evaluator, typename T>
Row evaluator_row(const std::vector<double>& points, std::size_t n, double tolerance) {
  const std::size_t d = Evaluator::kInputs;
  std::vector<T> host_inputs(points.begin(), points.begin() + static_cast<std::ptrdiff_t>(n * d));
  T* inputs = nullptr;
  T* outputs = nullptr;
  CHECK_CUDA(cudaMalloc(&inputs, n * d * sizeof(T)));
  CHECK_CUDA(cudaMalloc(&outputs, n * sizeof(T)));
  CHECK_CUDA(cudaMemcpy(inputs, host_inputs.data(), n * d * sizeof(T), cudaMemcpyHostToDevice));
  const double seconds = best_seconds([&] { CHECK_CUDA(Evaluator::template device_batch<T>(inputs, outputs, n)); });
  std::vector<T> device_outputs(kCheckedPoints);
  CHECK_CUDA(cudaMemcpy(device_outputs.data(), outputs, kCheckedPoints * sizeof(T), cudaMemcpyDeviceToHost));
  CHECK_CUDA(cudaFree(inputs));
  CHECK_CUDA(cudaFree(outputs));

  // The CPU reference: the same header's host path in double, which tests/unit/emit_cpp_test.cpp checks against
  // the interpreter to 1e-12 of the range.
  Row row;
  row.variant = std::string(Evaluator::kLabel) + ", " + (sizeof(T) == 8 ? "double" : "float");
  row.per_second = static_cast<double>(n) / seconds;
  row.tolerance = tolerance;
  for (std::size_t p = 0; p < kCheckedPoints; ++p) {
    double expected = 0;
    Evaluator::host(&points[p * d], &expected);
    row.max_difference = std::max(row.max_difference, std::fabs(static_cast<double>(device_outputs[p]) - expected));
  }
  row.ok = row.max_difference <= tolerance;
  return row;
}

// Each generated table header's view() returns its host arrays in host code and its __device__ arrays in device
// code, and interpolate_batch / interpolate_batch_cuda are its host loop and its kernel launcher (the product's
// batch path); a struct per header lets one function template serve every table.
#define FMPC_BENCH_TABLE(Name, header)                                                                        \
  struct Name {                                                                                              \
    using Value = header::Value;                                                                              \
    static FMPC_HD fmpc::TableView<Value> view() { return header::view(); }                                  \
    static void host_batch(const double* q, Value* out, std::size_t n) { header::interpolate_batch(q, out, n); } \
    static constexpr bool kPackedByDefault = header::kPackedByDefault;                                       \
    static cudaError_t device_batch(const double* q, Value* out, std::size_t n, fmpc::TableLayout layout) {  \
      return header::interpolate_batch_cuda(q, out, n, 0, layout);                                           \
    }                                                                                                        \
  };
FMPC_BENCH_TABLE(Table2, liver_table2)
FMPC_BENCH_TABLE(Table2Float, liver_table2f)
FMPC_BENCH_TABLE(Table5, liver_table5)
FMPC_BENCH_TABLE(Table5Float, liver_table5f)
FMPC_BENCH_TABLE(Table5Res7, liver_table5r7)
FMPC_BENCH_TABLE(Table5Res5, liver_table5r5)
#undef FMPC_BENCH_TABLE

// A lookup kernel as user code would write it: the run-time-dimension interpolate_table on view().
template <typename Table>
__global__ void user_lookup_kernel(const double* __restrict__ queries, typename Table::Value* __restrict__ out,
                                   std::size_t n) {
  const fmpc::TableView<typename Table::Value> table = Table::view();
  const std::size_t stride = static_cast<std::size_t>(gridDim.x) * blockDim.x;
  for (std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += stride)
    fmpc::interpolate_table(table, queries + i * static_cast<std::size_t>(table.axes), out + i);
}

enum class LookupPath { GridLayout, PackedLayout, UserKernel };

// Every query is read from device memory (d doubles) and every result written back (one Value: the liver table
// has one output); the 2^d corner values per lookup are gathered from the table, which stays in L1/L2. The row
// names both, so that lookups/s can be read as bandwidth.
template <typename Table>
Row table_row(const char* name, const std::vector<double>& points, std::size_t n, LookupPath path) {
  using Value = typename Table::Value;
  const fmpc::TableView<Value> host = Table::view();
  const std::size_t d = static_cast<std::size_t>(host.axes);
  std::size_t grid_points = 1;
  for (std::size_t a = 0; a < d; ++a) grid_points *= static_cast<std::size_t>(host.counts[a]);
  double* queries = nullptr;
  Value* out = nullptr;
  CHECK_CUDA(cudaMalloc(&queries, n * d * sizeof(double)));
  CHECK_CUDA(cudaMalloc(&out, n * sizeof(Value)));
  // Queries: the first d coordinates of each evaluator point (every input spans [0, 75] kPa), uniform, so the
  // lookups gather from the whole table in no particular order.
  std::vector<double> host_queries(n * d);
  for (std::size_t p = 0; p < n; ++p)
    for (std::size_t i = 0; i < d; ++i) host_queries[p * d + i] = points[p * 5 + i];
  CHECK_CUDA(cudaMemcpy(queries, host_queries.data(), n * d * sizeof(double), cudaMemcpyHostToDevice));
  const double seconds = best_seconds([&] {
    if (path != LookupPath::UserKernel) {
      CHECK_CUDA(Table::device_batch(queries, out, n,
                                     path == LookupPath::GridLayout ? fmpc::TableLayout::Grid
                                                                    : fmpc::TableLayout::SectorPacked));
    } else {
      constexpr unsigned threads = 256;
      const unsigned blocks = static_cast<unsigned>(std::min<std::size_t>((n + threads - 1) / threads, 65535u * 32u));
      user_lookup_kernel<Table><<<blocks, threads>>>(queries, out, n);
      CHECK_CUDA(cudaGetLastError());
    }
  });
  std::vector<Value> device_out(kCheckedPoints);
  CHECK_CUDA(cudaMemcpy(device_out.data(), out, kCheckedPoints * sizeof(Value), cudaMemcpyDeviceToHost));
  CHECK_CUDA(cudaFree(queries));
  CHECK_CUDA(cudaFree(out));
  std::vector<Value> expected(kCheckedPoints);
  Table::host_batch(host_queries.data(), expected.data(), kCheckedPoints);

  const bool packed = path == LookupPath::PackedLayout;
  const int packed_axes = fmpc::packed_lookup_axes<Value>(static_cast<int>(d));
  const std::size_t sectors = packed ? std::size_t{1} << (d - static_cast<std::size_t>(packed_axes)) : std::size_t{1} << (d - 1);
  const bool automatic = packed == Table::kPackedByDefault && path != LookupPath::UserKernel;
  char variant[320];
  std::snprintf(variant, sizeof variant,
                "%s, %s, %s layout%s (%s; %zu KiB grid; per lookup %zu B read + %zu B written, %zu places gathered)",
                name, sizeof(Value) == 8 ? "double" : "float", packed ? "packed" : "grid",
                automatic ? " [Automatic]" : "",
                path == LookupPath::UserKernel ? "interpolate_table in a user kernel" : "interpolate_batch_cuda",
                grid_points * sizeof(Value) / 1024, d * sizeof(double), sizeof(Value), sectors);
  Row row;
  row.variant = variant;
  row.per_second = static_cast<double>(n) / seconds;
  // The same arithmetic on both sides (the header's host loop is the reference), up to FMA contraction on the
  // device: double to 1e-9 kPa, float to 1e-5 of the 75 kPa range, as for the float evaluator.
  row.tolerance = sizeof(Value) == 8 ? 1e-9 : 1e-5 * 75.0;
  for (std::size_t p = 0; p < kCheckedPoints; ++p)
    row.max_difference = std::max(row.max_difference, std::fabs(static_cast<double>(device_out[p]) -
                                                                 static_cast<double>(expected[p])));
  row.ok = row.max_difference <= row.tolerance;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: evaluator_gpu_bench OUT_DIR [points]\n");
    return 2;
  }
  const std::string out_dir = argv[1];
  const std::size_t n = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : (std::size_t{1} << 24);
  if (n < kCheckedPoints) {
    std::fprintf(stderr, "points must be at least %zu\n", kCheckedPoints);
    return 2;
  }
  cudaDeviceProp properties{};
  CHECK_CUDA(cudaGetDeviceProperties(&properties, 0));

  std::mt19937_64 random(20240601);
  std::vector<double> points(n * 5);
  for (double& x : points) x = 75.0 * static_cast<double>(random() >> 11) * 0x1.0p-53;

  std::vector<Row> rows;
  const double range = LiverMamdani::range();
  // Device code contracts a * b + c into FMA (nvcc's default), so double differs from the host by rounding.
  rows.push_back(evaluator_row<LiverMamdani, double>(points, n, 1e-12 * range));
  rows.push_back(evaluator_row<LiverMamdani, float>(points, n, 1e-5 * range));
  // Type-2 in float can be compared only where float carries the computation (docs/codegen.md)
  // (ctest gpu.generated_evaluator checks it, against the CPU's own float): the bench checks double and times float.
  const std::size_t type2_points = std::max(n / 4, kCheckedPoints);
  rows.push_back(evaluator_row<LiverIt2, double>(points, type2_points, 1e-12 * LiverIt2::range()));
  rows.push_back(evaluator_row<LiverIt2, float>(points, type2_points, kNotChecked));
  // Every table in both layouts (the order of the rows in docs/performance.md), and the 9^5 double table in a user
  // kernel as well.
  const auto both_layouts = [&](auto table, const char* name) {
    using Table = decltype(table);
    rows.push_back(table_row<Table>(name, points, n, LookupPath::GridLayout));
    rows.push_back(table_row<Table>(name, points, n, LookupPath::PackedLayout));
  };
  both_layouts(Table2{}, "table lookup, 2-D 65x65");
  both_layouts(Table2Float{}, "table lookup, 2-D 65x65");
  both_layouts(Table5{}, "table lookup, 5-D 9^5");
  rows.push_back(table_row<Table5>("table lookup, 5-D 9^5", points, n, LookupPath::UserKernel));
  both_layouts(Table5Float{}, "table lookup, 5-D 9^5");
  both_layouts(Table5Res7{}, "table lookup, 5-D 7^5");
  both_layouts(Table5Res5{}, "table lookup, 5-D 5^5");

  std::string csv = "variant,per_second,max_difference_vs_cpu,tolerance,ok\n";
  std::string md = "| variant (" + std::string(properties.name) + ", " + std::to_string(n) +
                   " points) | per second | max diff vs CPU | tolerance | check |\n| --- | ---: | ---: | ---: | --- |\n";
  bool all_ok = true;
  for (const Row& row : rows) {
    char line[512];
    const char* check = row.tolerance == kNotChecked ? "timed only" : row.ok ? "ok" : "FAILED";
    std::snprintf(line, sizeof line, "%s,%.6g,%.3g,%.3g,%s\n", row.variant.c_str(), row.per_second,
                  row.max_difference, row.tolerance, check);
    csv += line;
    std::snprintf(line, sizeof line, "| %s | %.3g | %.3g | %.3g | %s |\n", row.variant.c_str(), row.per_second,
                  row.max_difference, row.tolerance, check);
    md += line;
    all_ok = all_ok && row.ok;
  }
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"evaluator_gpu.csv", csv},
                                   std::pair<std::string, std::string>{"evaluator_gpu.md", md}}) {
    if (std::FILE* file = std::fopen((out_dir + "/" + name).c_str(), "w")) {
      std::fputs(text.c_str(), file);
      std::fclose(file);
    }
  }
  std::fputs(md.c_str(), stdout);
  return all_ok ? 0 : 1;
}
