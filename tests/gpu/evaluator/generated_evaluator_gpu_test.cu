// The generated CUDA evaluator (`fmpc compile --target cuda`) on the device. The headers are generated at build
// time by fmpc_add_ruleset (tests/gpu/evaluator/CMakeLists.txt) from the liver rule base and golden rule files;
// evaluate_batch_cuda<double> and <float> run batches of 1, 37 and 1,000,003 points (seeded uniform points, with
// the range ends, out-of-range values, +-inf and NaN first), and every result is compared with the same header's
// host path in double (every point) and with the interpreter (a sample): double to 1e-12 of the output range and
// the same flags, float to 1e-5 of the range (or of the value, for Sugeno outputs beyond their range). In the
// FMPC_GPU_ONLY build (no interpreter there) the host path alone is the reference. Every
// output and flag must be written and nothing past the n-th point: the buffers carry a guard filled beforehand.
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "liver_mamdani.cuh"
#include "liver_sugeno.cuh"
#include "narrow.cuh"
#include "strain_stiffening.cuh"
#include "sugeno_tip.cuh"
#include "tipper.cuh"
#include "tests/gpu/gpu_test_harness.h"
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

struct GeneratedEvaluator {
  const char* label;
  const char* rule_file;  // relative to the source tree
  std::size_t inputs, outputs;
  const double* input_min;
  const double* input_max;
  const double* output_min;
  const double* output_max;
  HostEvaluate host;
  DeviceBatch<double> device_double;
  DeviceBatch<float> device_float;
};

#define FMPC_GENERATED_EVALUATOR(ns, file)                                                                       \
  GeneratedEvaluator {                                                                                           \
    #ns, file, ns::kInputCount, ns::kOutputCount, ns::kInputMin, ns::kInputMax, ns::kOutputMin, ns::kOutputMax, \
        &ns::evaluate<double>, &ns::evaluate_batch_cuda<double>, &ns::evaluate_batch_cuda<float>                 \
  }

const std::vector<GeneratedEvaluator>& evaluators() {
  static const std::vector<GeneratedEvaluator> list = {
      FMPC_GENERATED_EVALUATOR(liver_mamdani, "rulesets/liver_fibrosis/mamdani.fis"),
      FMPC_GENERATED_EVALUATOR(liver_sugeno, "rulesets/liver_fibrosis/sugeno.fis"),
      FMPC_GENERATED_EVALUATOR(tipper, "tests/golden/cli_eval_csv/tipper.fis"),
      FMPC_GENERATED_EVALUATOR(sugeno_tip, "tests/golden/cli_convert_to_fmpc/sugeno_tip.fis"),
      FMPC_GENERATED_EVALUATOR(narrow, "tests/golden/cli_no_rule_fired/narrow.fis"),
      FMPC_GENERATED_EVALUATOR(strain_stiffening, "rulesets/scenes/strain_stiffening.fis"),
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
      const bool float_comparable = flags_float[p] == host_flags[p];
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
    // Float must be comparable almost everywhere, or the float check above proves little.
    if (n >= 1000) FMPC_EXPECT(float_compared * 100 >= n * 99);

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

}  // namespace

FMPC_GPU_TEST(generated_evaluators_on_the_device, "generated CUDA evaluators: batches of 1, 37, 1000003 vs CPU",
              true) {
  for (const GeneratedEvaluator& e : evaluators()) check_evaluator(e);
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
