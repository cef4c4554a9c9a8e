// The generated CUDA evaluator (`fmpc compile --target cuda`) on the device. The headers are generated at build
// time by fmpc_add_ruleset (tests/gpu/evaluator/CMakeLists.txt) from the liver rule base and golden rule files;
// evaluate_batch_cuda<double> and <float> run batches of 1, 37 and 1,000,003 points (seeded uniform points, with
// the range ends, out-of-range values, +-inf and NaN first), and every result is compared with the same header's
// host path in double (every point) and with the interpreter (a sample): double to 1e-12 of the output range and
// the same flags, float to 1e-5 of the range (or of the value, for Sugeno outputs beyond their range). In the
// FMPC_GPU_ONLY build (no interpreter there) the host path alone is the reference. Interval type-2 systems (the
// liver's it2.fis, valve_it2.fis) compare float where the CPU's own float carries the computation (see
// float_comparable); two of them (tests/golden/it2_*_end_of_range) are the issue-11 systems where Karnik-Mendel
// and EKM used to cycle to their cap. Also the lookup tables' launchers (`--target table`): both layouts of
// kernels/table_math.h and Automatic, against the header's host loop. Every output and flag must be written and
// nothing past the n-th point: the buffers carry a guard filled beforehand. And kernels/type_reduction_math.h
// itself on the device: KM, EKM and EIASC over 30,000 seeded adversarial interval sets (ties, zeros, subnormals,
// equal grades, all mass at one end, lower grades of 1e-25) against an exhaustive search in long double.
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "ekm_end_of_range.cuh"
#include "km_end_of_range.cuh"
#include "liver_it2.cuh"
#include "liver_mamdani.cuh"
#include "liver_sugeno.cuh"
#include "liver_table3.h"
#include "liver_table5.h"
#include "narrow.cuh"
#include "strain_stiffening.cuh"
#include "sugeno_tip.cuh"
#include "tipper.cuh"
#include "valve_it2.cuh"
#include "kernels/type_reduction_math.h"
#include "tests/gpu/gpu_test_harness.h"
#include "tests/support/type_reduction_reference.h"
#if defined(FMPC_GPU_TEST_HAVE_INTERPRETER)
#include "tests/gpu/evaluator/evaluator_reference.h"
#endif

namespace {

using fmpc::gpu_test::note;
using fmpc::gpu_test::record_failure;

// Records the failing call and leaves the test.
#define CHECK_CUDA_OR_RETURN(call)                                                                 \
  do {                                                                                             \
    const cudaError_t status_ = (call);                                                            \
    if (status_ != cudaSuccess) {                                                                  \
      record_failure(__FILE__, __LINE__, std::string(#call) + ": " + cudaGetErrorString(status_)); \
      return false;                                                                                \
    }                                                                                              \
  } while (false)

template <typename T>
using DeviceBatch = cudaError_t (*)(const T*, T*, std::size_t, unsigned*, cudaStream_t);
using HostEvaluate = unsigned (*)(const double*, double*);
using HostEvaluateFloat = unsigned (*)(const float*, float*);

struct GeneratedEvaluator {
  const char* label;
  const char* rule_file;  // relative to the source tree
  std::size_t inputs, outputs;
  const double* input_min;
  const double* input_max;
  const double* output_min;
  const double* output_max;
  bool interval_type2;
  HostEvaluate host;
  HostEvaluateFloat host_float;
  DeviceBatch<double> device_double;
  DeviceBatch<float> device_float;
};

#define FMPC_GENERATED_EVALUATOR(ns, file, type2)                                                                \
  GeneratedEvaluator {                                                                                           \
    #ns, file, ns::kInputCount, ns::kOutputCount, ns::kInputMin, ns::kInputMax, ns::kOutputMin, ns::kOutputMax, \
        type2, &ns::evaluate<double>, &ns::evaluate<float>, &ns::evaluate_batch_cuda<double>,                    \
        &ns::evaluate_batch_cuda<float>                                                                          \
  }

const std::vector<GeneratedEvaluator>& evaluators() {
  static const std::vector<GeneratedEvaluator> list = {
      FMPC_GENERATED_EVALUATOR(liver_mamdani, "rulesets/liver_fibrosis/mamdani.fis", false),
      FMPC_GENERATED_EVALUATOR(liver_sugeno, "rulesets/liver_fibrosis/sugeno.fis", false),
      FMPC_GENERATED_EVALUATOR(tipper, "tests/golden/cli_eval_csv/tipper.fis", false),
      FMPC_GENERATED_EVALUATOR(sugeno_tip, "tests/golden/cli_convert_to_fmpc/sugeno_tip.fis", false),
      FMPC_GENERATED_EVALUATOR(narrow, "tests/golden/cli_no_rule_fired/narrow.fis", false),
      FMPC_GENERATED_EVALUATOR(strain_stiffening, "rulesets/scenes/strain_stiffening.fis", false),
      FMPC_GENERATED_EVALUATOR(liver_it2, "rulesets/liver_fibrosis/it2.fis", true),
      FMPC_GENERATED_EVALUATOR(valve_it2, "tests/golden/compile_type2_cpp/valve_it2.fis", true),
      FMPC_GENERATED_EVALUATOR(km_end_of_range, "tests/golden/it2_km_end_of_range/end_of_range.fis", true),
      FMPC_GENERATED_EVALUATOR(ekm_end_of_range, "tests/golden/it2_ekm_end_of_range/end_of_range.fis", true),
  };
  return list;
}

constexpr std::size_t kBatchSizes[] = {1, 37, 1000003};
constexpr std::size_t kGuard = 64;                // values past the n-th point that must stay untouched

// The edges first (so that the small batches hold them), then seeded uniform points inside the ranges.
std::vector<double> test_points(const GeneratedEvaluator& e, std::size_t count, std::uint64_t seed) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const std::size_t d = e.inputs;
  std::vector<double> points;
  auto edge = [&](auto value_of) {
    for (std::size_t i = 0; i < d; ++i) points.push_back(value_of(i));
  };
  edge([&](std::size_t i) { return e.input_min[i]; });
  edge([&](std::size_t i) { return e.input_max[i]; });
  edge([&](std::size_t i) { return e.input_min[i] - (e.input_max[i] - e.input_min[i]) / 3.0; });
  edge([&](std::size_t i) { return e.input_max[i] + (e.input_max[i] - e.input_min[i]) / 7.0; });
  edge([&](std::size_t i) { return i % 2 ? kInf : -kInf; });
  for (std::size_t nan_at = 0; nan_at < d; ++nan_at)
    edge([&](std::size_t i) { return i == nan_at ? std::numeric_limits<double>::quiet_NaN() : e.input_max[i]; });
  std::mt19937_64 random(seed);
  while (points.size() < count * d) {
    for (std::size_t i = 0; i < d; ++i)
      points.push_back(std::uniform_real_distribution<double>(e.input_min[i], e.input_max[i])(random));
  }
  points.resize(count * d);
  return points;
}

bool same_or_both_nan(double a, double b, double tolerance) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::fabs(a - b) <= tolerance;
}

// Device results for the first n points, in precision T: outputs (as double) and flags. Fails the test when a
// CUDA call fails or when the kernel wrote past the n-th point or left a point unwritten.
template <typename T>
bool run_on_device(DeviceBatch<T> batch, const std::vector<double>& points, std::size_t n, std::size_t d,
                   std::size_t m, std::vector<double>& outputs, std::vector<unsigned>& flags) {
  std::vector<T> inputs(n * d);
  for (std::size_t k = 0; k < n * d; ++k) inputs[k] = static_cast<T>(points[k]);
  T* device_inputs = nullptr;
  T* device_outputs = nullptr;
  unsigned* device_flags = nullptr;
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_inputs, n * d * sizeof(T)));
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_outputs, (n + kGuard) * m * sizeof(T)));
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_flags, (n + kGuard) * sizeof(unsigned)));
  CHECK_CUDA_OR_RETURN(cudaMemcpy(device_inputs, inputs.data(), n * d * sizeof(T), cudaMemcpyHostToDevice));
  // 0xFF bytes: a NaN in either precision and a flag word no evaluation returns (the flags are 4 bits).
  CHECK_CUDA_OR_RETURN(cudaMemset(device_outputs, 0xFF, (n + kGuard) * m * sizeof(T)));
  CHECK_CUDA_OR_RETURN(cudaMemset(device_flags, 0xFF, (n + kGuard) * sizeof(unsigned)));
  CHECK_CUDA_OR_RETURN(batch(device_inputs, device_outputs, n, device_flags, 0));
  CHECK_CUDA_OR_RETURN(cudaDeviceSynchronize());
  std::vector<T> out((n + kGuard) * m);
  std::vector<unsigned> all_flags(n + kGuard);
  CHECK_CUDA_OR_RETURN(cudaMemcpy(out.data(), device_outputs, out.size() * sizeof(T), cudaMemcpyDeviceToHost));
  CHECK_CUDA_OR_RETURN(
      cudaMemcpy(all_flags.data(), device_flags, all_flags.size() * sizeof(unsigned), cudaMemcpyDeviceToHost));
  CHECK_CUDA_OR_RETURN(cudaFree(device_inputs));
  CHECK_CUDA_OR_RETURN(cudaFree(device_outputs));
  CHECK_CUDA_OR_RETURN(cudaFree(device_flags));

  std::size_t unwritten = 0, overwritten = 0;
  for (std::size_t p = 0; p < n + kGuard; ++p) {
    const bool untouched = all_flags[p] == 0xFFFFFFFFu;
    if (p < n && untouched) ++unwritten;
    if (p >= n && !untouched) ++overwritten;
  }
  const unsigned char* guard = reinterpret_cast<const unsigned char*>(out.data() + n * m);
  for (std::size_t b = 0; b < kGuard * m * sizeof(T); ++b) overwritten += guard[b] != 0xFF ? 1 : 0;
  if (unwritten != 0 || overwritten != 0) {
    record_failure(__FILE__, __LINE__,
                   std::to_string(unwritten) + " points without flags, " + std::to_string(overwritten) +
                       " guard values written past point " + std::to_string(n));
    return false;
  }
  outputs.resize(n * m);
  for (std::size_t k = 0; k < n * m; ++k) outputs[k] = static_cast<double>(out[k]);
  flags.assign(all_flags.begin(), all_flags.begin() + static_cast<std::ptrdiff_t>(n));
  return true;
}

#if defined(FMPC_GPU_TEST_HAVE_INTERPRETER)
constexpr std::size_t kInterpretedPoints = 1500;

// Which points the interpreter evaluates: the first ones (the edges among them), then a stride through the rest.
std::vector<std::size_t> interpreted_points(std::size_t n) {
  std::vector<std::size_t> chosen;
  const std::size_t stride = std::max<std::size_t>(1, n / kInterpretedPoints);
  for (std::size_t p = 0; p < n; p += p < kInterpretedPoints / 2 ? 1 : stride) chosen.push_back(p);
  return chosen;
}
#endif

void check_evaluator(const GeneratedEvaluator& e) {
  const std::size_t d = e.inputs, m = e.outputs;
  const std::size_t largest = *std::max_element(std::begin(kBatchSizes), std::end(kBatchSizes));
  const std::vector<double> points = test_points(e, largest, 20240601);
  // Host path of the same header, every point.
  std::vector<double> host(largest * m);
  std::vector<unsigned> host_flags(largest);
  for (std::size_t p = 0; p < largest; ++p) host_flags[p] = e.host(&points[p * d], &host[p * m]);
  // Type-2 only: the host path in float at the float-rounded inputs, which says where float can carry the
  // computation at all (Karnik-Mendel's switch point in float may settle elsewhere where a centroid denominator
  // nearly cancels: docs/codegen.md). Where the CPU's float agrees with double, the GPU's float must too.
  std::vector<char> float_carries(largest, 1);
  if (e.interval_type2) {
    std::vector<float> in(d), out(m);
    for (std::size_t p = 0; p < largest; ++p) {
      for (std::size_t i = 0; i < d; ++i) in[i] = static_cast<float>(points[p * d + i]);
      const unsigned flags = e.host_float(in.data(), out.data());
      bool agrees = flags == host_flags[p];
      for (std::size_t o = 0; o < m; ++o) {
        const double expected = host[p * m + o], range = e.output_max[o] - e.output_min[o];
        agrees = agrees && same_or_both_nan(static_cast<double>(out[o]), expected,
                                            1e-5 * std::max(range, std::fabs(expected)));
      }
      float_carries[p] = agrees ? 1 : 0;
    }
  }

  for (std::size_t n : kBatchSizes) {
    std::vector<double> device_double, device_float;
    std::vector<unsigned> flags_double, flags_float;
    if (!run_on_device<double>(e.device_double, points, n, d, m, device_double, flags_double)) return;
    if (!run_on_device<float>(e.device_float, points, n, d, m, device_float, flags_float)) return;

    double worst_double = 0.0, worst_float = 0.0;
    std::size_t double_failures = 0, float_failures = 0, flag_failures = 0, float_compared = 0;
    for (std::size_t p = 0; p < n; ++p) {
      flag_failures += flags_double[p] != host_flags[p] ? 1 : 0;
      // Float carries the computation where it reaches the same decisions as double (a firing below float's
      // range turns "fired weakly" into "no rule fired"; tests/unit/emit_cpp_test.cpp skips the same points).
      const bool float_comparable = flags_float[p] == host_flags[p] && float_carries[p];
      float_compared += float_comparable ? 1 : 0;
      for (std::size_t o = 0; o < m; ++o) {
        const double range = e.output_max[o] - e.output_min[o], expected = host[p * m + o];
        const double got_double = device_double[p * m + o], got_float = device_float[p * m + o];
        if (!same_or_both_nan(got_double, expected, 1e-12 * range)) ++double_failures;
        if (std::isfinite(expected)) worst_double = std::max(worst_double, std::fabs(got_double - expected));
        if (!float_comparable) continue;
        const double float_scale = std::max(range, std::fabs(expected));
        if (!same_or_both_nan(got_float, expected, 1e-5 * float_scale)) ++float_failures;
        if (std::isfinite(expected)) worst_float = std::max(worst_float, std::fabs(got_float - expected));
      }
    }
    std::ostringstream summary;
    summary.precision(3);
    summary << e.label << ", n = " << n << ": max |GPU - CPU| double " << worst_double << ", float " << worst_float
            << " (float compared on " << float_compared << " of " << n << " points)";
    note(summary.str());
    if (double_failures || float_failures || flag_failures) {
      record_failure(__FILE__, __LINE__,
                     std::string(e.label) + ", n = " + std::to_string(n) + ": " + std::to_string(double_failures) +
                         " double outputs beyond 1e-12 of the range, " + std::to_string(float_failures) +
                         " float outputs beyond 1e-5, " + std::to_string(flag_failures) + " flags differ");
    }
    // Float must be comparable almost everywhere, or the float check above proves little (type-2: on 90% of
    // random points, as in tests/unit/emit_type2_test.cpp).
    if (n >= 1000) FMPC_EXPECT(float_compared * 100 >= n * (e.interval_type2 ? 90 : 99));

#if defined(FMPC_GPU_TEST_HAVE_INTERPRETER)
    // The interpreter on a sample, against the device's double results.
    const std::vector<std::size_t> chosen = interpreted_points(n);
    std::vector<double> sample;
    for (std::size_t p : chosen) sample.insert(sample.end(), &points[p * d], &points[p * d] + d);
    const std::string rule_file = std::string(FMPC_SOURCE_DIR) + "/" + e.rule_file;
    const fmpc::gpu_test::ReferenceEvaluation reference =
        fmpc::gpu_test::interpret_rule_file(rule_file, sample.data(), chosen.size(), d);
    if (!reference.error.empty()) {
      record_failure(__FILE__, __LINE__, reference.error);
      return;
    }
    std::size_t interpreter_failures = 0;
    for (std::size_t k = 0; k < chosen.size(); ++k) {
      const std::size_t p = chosen[k];
      if (flags_double[p] != reference.flags[k]) ++interpreter_failures;
      for (std::size_t o = 0; o < m; ++o)
        if (!same_or_both_nan(device_double[p * m + o], reference.outputs[k * m + o],
                              1e-12 * (e.output_max[o] - e.output_min[o])))
          ++interpreter_failures;
    }
    if (interpreter_failures)
      record_failure(__FILE__, __LINE__,
                     std::string(e.label) + ", n = " + std::to_string(n) + ": " +
                         std::to_string(interpreter_failures) + " of " + std::to_string(chosen.size()) +
                         " sampled points differ from the interpreter (outputs beyond 1e-12 of the range or flags)");
#endif
  }
}

// ---- Lookup tables ----

struct GeneratedTable {
  const char* label;
  int axes;
  bool packed_by_default;
  void (*host)(const double*, double*, std::size_t);
  cudaError_t (*device)(const double*, double*, std::size_t, cudaStream_t, fmpc::TableLayout);
  const int* counts;
  const double* const* breakpoints;
};

#define FMPC_LOOKUP_TABLE(ns)                                                                        \
  GeneratedTable {                                                                                      \
    #ns, ns::kAxes, ns::kPackedByDefault, &ns::interpolate_batch, &ns::interpolate_batch_cuda,          \
        ns::host_table::counts, ns::host_table::breakpoints                                             \
  }

// Queries: every kind of coordinate on every axis independently (a breakpoint, either end, beyond either end,
// +-inf, uniform inside), with one NaN query first so that the smallest batch holds it.
std::vector<double> table_queries(const GeneratedTable& t, std::size_t count, std::uint64_t seed) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::mt19937_64 random(seed);
  std::vector<double> queries;
  for (std::size_t q = 0; q < count; ++q) {
    for (int a = 0; a < t.axes; ++a) {
      const double* axis = t.breakpoints[a];
      const int n = t.counts[a];
      const double lo = axis[0], hi = axis[n - 1];
      double x = std::uniform_real_distribution<double>(lo, hi)(random);
      switch (std::uniform_int_distribution<int>(0, 11)(random)) {
        case 0: x = axis[std::uniform_int_distribution<int>(0, n - 1)(random)]; break;
        case 1: x = hi; break;
        case 2: x = lo; break;
        case 3: x = hi + 3.0; break;
        case 4: x = lo - 3.0; break;
        case 5: x = q % 2 ? kInf : -kInf; break;
        default: break;
      }
      queries.push_back(q == 0 && a == t.axes - 1 ? std::numeric_limits<double>::quiet_NaN() : x);
    }
  }
  return queries;
}

void check_table(const GeneratedTable& t) {
  const std::size_t d = static_cast<std::size_t>(t.axes);
  const std::size_t largest = *std::max_element(std::begin(kBatchSizes), std::end(kBatchSizes));
  const std::vector<double> queries = table_queries(t, largest, 20261122);
  std::vector<double> host(largest);
  t.host(queries.data(), host.data(), largest);
  double* device_queries = nullptr;
  double* device_out = nullptr;
  const auto release = [&] {
    cudaFree(device_queries);
    cudaFree(device_out);
  };
  if (cudaMalloc(&device_queries, largest * d * sizeof(double)) != cudaSuccess ||
      cudaMalloc(&device_out, (largest + kGuard) * sizeof(double)) != cudaSuccess ||
      cudaMemcpy(device_queries, queries.data(), largest * d * sizeof(double), cudaMemcpyHostToDevice) !=
          cudaSuccess) {
    record_failure(__FILE__, __LINE__, std::string(t.label) + ": cudaMalloc/cudaMemcpy failed");
    release();
    return;
  }
  for (const fmpc::TableLayout layout :
       {fmpc::TableLayout::Grid, fmpc::TableLayout::SectorPacked, fmpc::TableLayout::Automatic}) {
    const char* layout_name = layout == fmpc::TableLayout::Grid           ? "grid"
                              : layout == fmpc::TableLayout::SectorPacked ? "packed"
                              : t.packed_by_default                       ? "automatic (packed)"
                                                                          : "automatic (grid)";
    for (std::size_t n : kBatchSizes) {
      std::vector<double> out(n + kGuard);
      const bool ran = cudaMemset(device_out, 0xFF, (n + kGuard) * sizeof(double)) == cudaSuccess &&
                       t.device(device_queries, device_out, n, 0, layout) == cudaSuccess &&
                       cudaDeviceSynchronize() == cudaSuccess &&
                       cudaMemcpy(out.data(), device_out, out.size() * sizeof(double), cudaMemcpyDeviceToHost) ==
                           cudaSuccess;
      if (!ran) {
        record_failure(__FILE__, __LINE__, std::string(t.label) + ", " + layout_name + ": a CUDA call failed: " +
                                               cudaGetErrorString(cudaGetLastError()));
        release();
        return;
      }
      // The same arithmetic as the host loop, up to FMA contraction on the device: within 1e-12 of the 75 kPa range.
      std::size_t failures = 0, guard_written = 0;
      double worst = 0.0;
      for (std::size_t p = 0; p < n; ++p) {
        failures += same_or_both_nan(out[p], host[p], 1e-12 * 75.0) ? 0 : 1;
        if (std::isfinite(host[p]) && std::isfinite(out[p])) worst = std::max(worst, std::fabs(out[p] - host[p]));
      }
      const unsigned char* guard = reinterpret_cast<const unsigned char*>(out.data() + n);
      for (std::size_t b = 0; b < kGuard * sizeof(double); ++b) guard_written += guard[b] != 0xFF ? 1 : 0;
      std::ostringstream summary;
      summary.precision(3);
      summary << t.label << ", " << layout_name << " layout, n = " << n << ": max |GPU - CPU| " << worst;
      note(summary.str());
      if (failures || guard_written)
        record_failure(__FILE__, __LINE__,
                       std::string(t.label) + ", " + layout_name + ", n = " + std::to_string(n) + ": " +
                           std::to_string(failures) + " lookups beyond 1e-12 of the range, " +
                           std::to_string(guard_written) + " guard bytes written");
    }
  }
  release();
}

// ---- Type reduction on the device ----

// One thread per set: sets[s] occupies points [offsets[s], offsets[s + 1]). Writes yl, yr and (fired, cap hit).
template <typename T>
__global__ void reduce_sets_kernel(fmpc::TypeReduction method, const T* x, const T* lower, const T* upper,
                                   const int* offsets, int sets, T* ends, int* status) {
  for (int s = blockIdx.x * blockDim.x + threadIdx.x; s < sets; s += gridDim.x * blockDim.x) {
    const int first = offsets[s], n = offsets[s + 1] - offsets[s];
    const fmpc::TypeReducedInterval<T> r = fmpc::reduce_type(method, x + first, lower + first, upper + first, n);
    ends[2 * s] = r.left;
    ends[2 * s + 1] = r.right;
    status[2 * s] = r.fired ? 1 : 0;
    status[2 * s + 1] = r.iteration_cap_hit ? 1 : 0;
  }
}

// The sets' ends on the device in precision T; false (with a failure recorded) when a CUDA call fails.
template <typename T>
bool reduce_on_device(fmpc::TypeReduction method, const std::vector<fmpc::testing::IntervalSet>& sets,
                      std::vector<double>& ends, std::vector<int>& status) {
  std::vector<T> x, lower, upper;
  std::vector<int> offsets{0};
  for (const auto& s : sets) {
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      x.push_back(static_cast<T>(s.x[i]));
      lower.push_back(static_cast<T>(s.lower[i]));
      upper.push_back(static_cast<T>(s.upper[i]));
    }
    offsets.push_back(static_cast<int>(x.size()));
  }
  const int count = static_cast<int>(sets.size());
  T *device_x = nullptr, *device_lower = nullptr, *device_upper = nullptr, *device_ends = nullptr;
  int *device_offsets = nullptr, *device_status = nullptr;
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_x, x.size() * sizeof(T)));
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_lower, x.size() * sizeof(T)));
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_upper, x.size() * sizeof(T)));
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_offsets, offsets.size() * sizeof(int)));
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_ends, 2 * sets.size() * sizeof(T)));
  CHECK_CUDA_OR_RETURN(cudaMalloc(&device_status, 2 * sets.size() * sizeof(int)));
  CHECK_CUDA_OR_RETURN(cudaMemcpy(device_x, x.data(), x.size() * sizeof(T), cudaMemcpyHostToDevice));
  CHECK_CUDA_OR_RETURN(cudaMemcpy(device_lower, lower.data(), x.size() * sizeof(T), cudaMemcpyHostToDevice));
  CHECK_CUDA_OR_RETURN(cudaMemcpy(device_upper, upper.data(), x.size() * sizeof(T), cudaMemcpyHostToDevice));
  CHECK_CUDA_OR_RETURN(
      cudaMemcpy(device_offsets, offsets.data(), offsets.size() * sizeof(int), cudaMemcpyHostToDevice));
  reduce_sets_kernel<T><<<(count + 127) / 128, 128>>>(method, device_x, device_lower, device_upper, device_offsets,
                                                      count, device_ends, device_status);
  CHECK_CUDA_OR_RETURN(cudaGetLastError());
  CHECK_CUDA_OR_RETURN(cudaDeviceSynchronize());
  std::vector<T> got(2 * sets.size());
  status.resize(2 * sets.size());
  CHECK_CUDA_OR_RETURN(cudaMemcpy(got.data(), device_ends, got.size() * sizeof(T), cudaMemcpyDeviceToHost));
  CHECK_CUDA_OR_RETURN(
      cudaMemcpy(status.data(), device_status, status.size() * sizeof(int), cudaMemcpyDeviceToHost));
  for (void* buffer : {static_cast<void*>(device_x), static_cast<void*>(device_lower),
                       static_cast<void*>(device_upper), static_cast<void*>(device_offsets),
                       static_cast<void*>(device_ends), static_cast<void*>(device_status)})
    CHECK_CUDA_OR_RETURN(cudaFree(buffer));
  ends.assign(got.begin(), got.end());
  return true;
}

}  // namespace

FMPC_GPU_TEST(type_reduction_on_the_device, "KM, EKM, EIASC on the device vs exhaustive search (30,000 sets)",
              true) {
  using fmpc::testing::AdversarialKind;
  std::mt19937_64 random(20260517);
  std::vector<fmpc::testing::IntervalSet> sets;
  const int kinds = static_cast<int>(AdversarialKind::Count);
  for (int trial = 0; trial < 30000; ++trial)
    sets.push_back(fmpc::testing::adversarial_interval_set(random, static_cast<AdversarialKind>(trial % kinds)));
  std::vector<fmpc::testing::ExactInterval> exact;
  for (const auto& s : sets) exact.push_back(fmpc::testing::exact_type_reduction(s.x, s.lower, s.upper));
  for (const fmpc::TypeReduction method : {fmpc::TypeReduction::KarnikMendel,
                                           fmpc::TypeReduction::EnhancedKarnikMendel, fmpc::TypeReduction::Eiasc}) {
    std::vector<double> ends, ends_float;
    std::vector<int> status, status_float;
    if (!reduce_on_device<double>(method, sets, ends, status)) return;
    if (!reduce_on_device<float>(method, sets, ends_float, status_float)) return;
    std::size_t failures = 0, caps = 0;
    double worst = 0.0;  // largest error / tolerance
    for (std::size_t s = 0; s < sets.size(); ++s) {
      caps += static_cast<std::size_t>(status[2 * s + 1] + status_float[2 * s + 1]);
      if ((status[2 * s] == 1) != exact[s].fired) {
        ++failures;
        continue;
      }
      if (!exact[s].fired) continue;
      const double tolerance = fmpc::testing::type_reduction_tolerance(sets[s].x);
      const double error = std::max(std::fabs(static_cast<double>(ends[2 * s] - exact[s].left)),
                                    std::fabs(static_cast<double>(ends[2 * s + 1] - exact[s].right)));
      if (!(error <= tolerance)) ++failures;
      if (tolerance > 0.0) worst = std::max(worst, error / tolerance);
    }
    std::ostringstream summary;
    summary.precision(3);
    summary << "type reduction " << static_cast<int>(method) << " on the device: worst error " << worst
            << " of the tolerance (1e-12 of the range) over " << sets.size() << " sets";
    note(summary.str());
    if (failures || caps)
      record_failure(__FILE__, __LINE__,
                     "type reduction " + std::to_string(static_cast<int>(method)) + ": " + std::to_string(failures) +
                         " sets beyond 1e-12 of the range of the exhaustive search, " + std::to_string(caps) +
                         " iteration caps reached (double and float)");
  }
}

FMPC_GPU_TEST(generated_evaluators_on_the_device, "generated CUDA evaluators: batches of 1, 37, 1000003 vs CPU",
              true) {
  for (const GeneratedEvaluator& e : evaluators()) check_evaluator(e);
}

FMPC_GPU_TEST(generated_tables_on_the_device, "generated table launchers: grid, packed, automatic vs CPU", true) {
  // Automatic takes each layout once (tests/gpu/evaluator/CMakeLists.txt).
  FMPC_EXPECT(!liver_table3::kPackedByDefault);
  FMPC_EXPECT(liver_table5::kPackedByDefault);
  check_table(FMPC_LOOKUP_TABLE(liver_table3));
  check_table(FMPC_LOOKUP_TABLE(liver_table5));
}

#if defined(FMPC_GPU_TEST_HAVE_INTERPRETER)
// Without a device this is what runs: the headers generated at build time compile under nvcc and their host path
// agrees with the interpreter.
FMPC_GPU_TEST(generated_evaluators_host_path, "generated CUDA evaluators: host path vs interpreter", false) {
  for (const GeneratedEvaluator& e : evaluators()) {
    const std::size_t count = 2000, d = e.inputs, m = e.outputs;
    const std::vector<double> points = test_points(e, count, 7);
    const fmpc::gpu_test::ReferenceEvaluation reference = fmpc::gpu_test::interpret_rule_file(
        std::string(FMPC_SOURCE_DIR) + "/" + e.rule_file, points.data(), count, d);
    FMPC_REQUIRE(reference.error.empty());
    std::size_t failures = 0;
    std::vector<double> out(m);
    for (std::size_t p = 0; p < count; ++p) {
      const unsigned flags = e.host(&points[p * d], out.data());
      if (flags != reference.flags[p]) ++failures;
      for (std::size_t o = 0; o < m; ++o)
        if (!same_or_both_nan(out[o], reference.outputs[p * m + o], 1e-12 * (e.output_max[o] - e.output_min[o])))
          ++failures;
    }
    if (failures)
      record_failure(__FILE__, __LINE__, std::string(e.label) + ": " + std::to_string(failures) +
                                             " host results differ from the interpreter");
  }
}
#else
// FMPC_GPU_ONLY: no interpreter in this build; the headers' host path (checked against the interpreter by
// tests/unit/emit_cpp_test.cpp on the build machine) is the reference.
#endif
