// rulesets/liver_fibrosis/mamdani.fis with all five inputs varying, on the same 4096 seeded points:
//   BM_Interpreter      fmpc's reference interpreter (fmpc::Interpreter, double)
//   BM_Compiled<T>      the generated evaluator's batch function, evaluate_batch<T> over the 4096 points in one
//                       call (fmpc compile --target cpp, built into this program with the build's flags: Release
//                       is -O3, no -march; with GCC on glibc x86-64 the CPU picks among its clones for the
//                       baseline, x86-64-v3 and x86-64-v4, docs/codegen.md)
//   BM_CompiledSingle<T> the generated evaluate<T>, one point per call
//   BM_CompiledBaseline<T> evaluate_batch<T> built with FMPC_NO_TARGET_CLONES: the baseline target only (x86-64:
//                       SSE2), x86-64 with GCC or Clang only
//   BM_CompiledX86_64_v3<T> evaluate_batch<T> compiled with -march=x86-64-v3 (AVX2, FMA) and no clones, x86-64
//                       only, run only on CPUs that have AVX2 and FMA
//   BM_Fuzzylite        fuzzylite 6.0 (Debian libfuzzylite-dev), the same system imported from MATLAB .fis text
// One core, one run:  fmpc_evaluator_bench --benchmark_repetitions=1  (docs/performance.md has the figures).
// Before timing, it checks that the compiled evaluator (evaluate and evaluate_batch) agrees with the interpreter
// (1e-12 of the range in double, 1e-5 in float) and reports how far fuzzylite's centroid (its own integration)
// lies from MATLAB's 101 samples.
#include <benchmark/benchmark.h>
#include <fl/Headers.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/frontend/rule_file_loader.h"
#include "liver_evaluator.h"
#if defined(FMPC_BENCH_X86_64_V3)
#include "evaluator_baseline.h"
#include "evaluator_x86_64_v3.h"
#endif

namespace {

constexpr std::size_t kPoints = 4096;
constexpr std::size_t kInputs = 5;

struct Fixture {
  fmpc::FuzzySystem system;
  std::vector<double> points;  // kPoints x kInputs
  std::vector<float> points_float;
  std::unique_ptr<fl::Engine> fuzzylite;
  bool ready = false;
};

Fixture& fixture() {
  static Fixture f = [] {
    Fixture made;
    const std::string path = std::string(FMPC_SOURCE_DIR) + "/rulesets/liver_fibrosis/mamdani.fis";
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    fmpc::DiagnosticList diagnostics;
    fmpc::RuleFile file = fmpc::load_rule_file(path, text.str(), diagnostics);
    if (diagnostics.has_errors() || file.systems.size() != 1 || file.systems[0].inputs.size() != kInputs) {
      std::fprintf(stderr, "cannot load %s\n", path.c_str());
      return made;
    }
    made.system = file.systems[0];
    std::mt19937_64 random(20240601);
    made.points.resize(kPoints * kInputs);
    for (std::size_t k = 0; k < made.points.size(); ++k) {
      const fmpc::Variable& v = made.system.inputs[k % kInputs];
      made.points[k] = v.min + static_cast<double>(random() >> 11) * 0x1.0p-53 * (v.max - v.min);
    }
    made.points_float.assign(made.points.begin(), made.points.end());
    fmpc::DiagnosticList write_diagnostics;
    const std::string matlab = fmpc::write_matlab_fis(made.system, write_diagnostics);
    made.fuzzylite.reset(fl::FisImporter().fromString(matlab));
    std::string status;
    if (!made.fuzzylite || !made.fuzzylite->isReady(&status)) {
      std::fprintf(stderr, "fuzzylite cannot run the system: %s\n", status.c_str());
      return made;
    }

    // Agreement before speed.
    fmpc::Interpreter interpreter(made.system);
    std::vector<double> batch_double(kPoints);
    std::vector<float> batch_float(kPoints);
    liver_evaluator::evaluate_batch(made.points.data(), batch_double.data(), kPoints);
    liver_evaluator::evaluate_batch(made.points_float.data(), batch_float.data(), kPoints);
    double worst_double = 0, worst_float = 0, worst_fuzzylite = 0;
    for (std::size_t p = 0; p < kPoints; ++p) {
      const double* x = &made.points[p * kInputs];
      const double expected = interpreter.evaluate(std::vector<double>(x, x + kInputs)).outputs[0];
      double compiled = 0;
      liver_evaluator::evaluate(x, &compiled);
      float compiled_float = 0;
      liver_evaluator::evaluate(&made.points_float[p * kInputs], &compiled_float);
      for (std::size_t i = 0; i < kInputs; ++i) made.fuzzylite->getInputVariable(i)->setValue(x[i]);
      made.fuzzylite->process();
      const double theirs = made.fuzzylite->getOutputVariable(0)->getValue();
      worst_double = std::max({worst_double, std::fabs(compiled - expected), std::fabs(batch_double[p] - expected)});
      worst_float = std::max({worst_float, std::fabs(static_cast<double>(compiled_float) - expected),
                              std::fabs(static_cast<double>(batch_float[p]) - expected)});
      worst_fuzzylite = std::max(worst_fuzzylite, std::fabs(theirs - expected));
    }
    const double range = made.system.outputs[0].max - made.system.outputs[0].min;
    std::fprintf(stderr,
                 "agreement with the interpreter over %zu points (evaluate and evaluate_batch): compiled double "
                 "%.3g, compiled float %.3g, "
                 "fuzzylite %.3g (kPa; fuzzylite integrates the centroid its own way)\n",
                 kPoints, worst_double, worst_float, worst_fuzzylite);
#if defined(FMPC_BENCH_X86_64_V3)
    const auto check_build = [&](const char* name, auto batch_double_function, auto batch_float_function) {
      batch_double_function(made.points.data(), batch_double.data(), kPoints);
      batch_float_function(made.points_float.data(), batch_float.data(), kPoints);
      double worst_build_double = 0, worst_build_float = 0;
      for (std::size_t p = 0; p < kPoints; ++p) {
        const double* x = &made.points[p * kInputs];
        const double expected = interpreter.evaluate(std::vector<double>(x, x + kInputs)).outputs[0];
        worst_build_double = std::max(worst_build_double, std::fabs(batch_double[p] - expected));
        worst_build_float = std::max(worst_build_float, std::fabs(static_cast<double>(batch_float[p]) - expected));
      }
      std::fprintf(stderr, "%s build: double %.3g, float %.3g\n", name, worst_build_double, worst_build_float);
      worst_double = std::max(worst_double, worst_build_double);
      worst_float = std::max(worst_float, worst_build_float);
    };
    using DoubleBatch = void (*)(const double*, double*, std::size_t);
    using FloatBatch = void (*)(const float*, float*, std::size_t);
    check_build("baseline", static_cast<DoubleBatch>(&liver_batch_baseline),
                static_cast<FloatBatch>(&liver_batch_baseline));
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
      check_build("x86-64-v3", static_cast<DoubleBatch>(&liver_batch_x86_64_v3),
                  static_cast<FloatBatch>(&liver_batch_x86_64_v3));
#endif
    if (!(worst_double <= 1e-12 * range) || !(worst_float <= 1e-5 * range)) {
      std::fprintf(stderr, "the compiled evaluator disagrees with the interpreter: not timing it\n");
      return made;
    }
    made.ready = true;
    return made;
  }();
  return f;
}

void BM_Interpreter(benchmark::State& state) {
  Fixture& f = fixture();
  if (!f.ready) return state.SkipWithError("setup failed (see stderr)");
  fmpc::Interpreter interpreter(f.system);
  std::vector<double> x(kInputs);
  std::size_t p = 0;
  for (auto _ : state) {
    std::copy_n(&f.points[p * kInputs], kInputs, x.begin());
    benchmark::DoNotOptimize(interpreter.evaluate(x));
    p = (p + 1) % kPoints;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Interpreter);

// Times `batch(points, outputs, kPoints)` over the fixture's points in precision T.
template <typename T, typename Batch>
void time_batch(benchmark::State& state, Batch batch) {
  Fixture& f = fixture();
  if (!f.ready) return state.SkipWithError("setup failed (see stderr)");
  const T* points = nullptr;
  if constexpr (sizeof(T) == sizeof(double)) points = f.points.data();
  else points = f.points_float.data();
  std::vector<T> outputs(kPoints);
  for (auto _ : state) {
    batch(points, outputs.data(), kPoints);
    benchmark::DoNotOptimize(outputs.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(kPoints));
}

template <typename T>
void BM_Compiled(benchmark::State& state) {
  time_batch<T>(state, [](const T* in, T* out, std::size_t n) { liver_evaluator::evaluate_batch(in, out, n); });
}
BENCHMARK_TEMPLATE(BM_Compiled, double);
BENCHMARK_TEMPLATE(BM_Compiled, float);

template <typename T>
void BM_CompiledSingle(benchmark::State& state) {
  time_batch<T>(state, [](const T* in, T* out, std::size_t n) {
    for (std::size_t p = 0; p < n; ++p) liver_evaluator::evaluate(in + p * kInputs, &out[p]);
  });
}
BENCHMARK_TEMPLATE(BM_CompiledSingle, double);
BENCHMARK_TEMPLATE(BM_CompiledSingle, float);

#if defined(FMPC_BENCH_X86_64_V3)
template <typename T>
void BM_CompiledBaseline(benchmark::State& state) {
  time_batch<T>(state, [](const T* in, T* out, std::size_t n) { liver_batch_baseline(in, out, n); });
}
BENCHMARK_TEMPLATE(BM_CompiledBaseline, double);
BENCHMARK_TEMPLATE(BM_CompiledBaseline, float);

template <typename T>
void BM_CompiledX86_64_v3(benchmark::State& state) {
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma"))
    return state.SkipWithError("this CPU has no AVX2 or FMA");
  time_batch<T>(state, [](const T* in, T* out, std::size_t n) { liver_batch_x86_64_v3(in, out, n); });
}
BENCHMARK_TEMPLATE(BM_CompiledX86_64_v3, double);
BENCHMARK_TEMPLATE(BM_CompiledX86_64_v3, float);
#endif

void BM_Fuzzylite(benchmark::State& state) {
  Fixture& f = fixture();
  if (!f.ready) return state.SkipWithError("setup failed (see stderr)");
  fl::Engine& engine = *f.fuzzylite;
  std::size_t p = 0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < kInputs; ++i) engine.getInputVariable(i)->setValue(f.points[p * kInputs + i]);
    engine.process();
    benchmark::DoNotOptimize(engine.getOutputVariable(0)->getValue());
    p = (p + 1) % kPoints;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Fuzzylite);

}  // namespace

BENCHMARK_MAIN();
