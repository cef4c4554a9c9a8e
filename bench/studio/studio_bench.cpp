// The studio's patient panel on the thesis's 247-rule Mamdani liver: explain() alone (outputs, firing strengths,
// the aggregated set), rule_contributions() (the same plus 247 leave-one-rule-out evaluations), and
// evaluation_json() (all of it as the JSON the page receives, text included), at the example patients in turn.
#include <benchmark/benchmark.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "compiler/eval/rule_contributions.h"
#include "compiler/frontend/rule_file_loader.h"
#include "tools/studio/studio_evaluation.h"

namespace {

const fmpc::FuzzySystem& liver() {
  static const fmpc::FuzzySystem system = [] {
    std::ifstream in(std::string(FMPC_SOURCE_DIR) + "/rulesets/liver_fibrosis/mamdani.fis");
    std::stringstream text;
    text << in.rdbuf();
    fmpc::DiagnosticList diagnostics;
    fmpc::RuleFile file = fmpc::load_rule_file("mamdani.fis", text.str(), diagnostics);
    if (diagnostics.has_errors() || file.systems.empty()) throw std::runtime_error("the liver rules did not load");
    return file.systems.front();
  }();
  return system;
}

// rulesets/liver_fibrosis/example_patients.csv
const std::vector<std::vector<double>> kPatients = {
    {5, 5, 5, 5, 5}, {7.6, 7.2, 9.5, 11, 7.7}, {9.7, 9.5, 12, 11, 11.2}, {13.8, 12, 22.4, 8.3, 21.6}};

void BM_Explain(benchmark::State& state) {
  std::size_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(fmpc::explain(liver(), kPatients[k++ % kPatients.size()]));
}
BENCHMARK(BM_Explain)->Unit(benchmark::kMillisecond);

void BM_RuleContributions(benchmark::State& state) {
  std::size_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(fmpc::rule_contributions(liver(), kPatients[k++ % kPatients.size()]));
}
BENCHMARK(BM_RuleContributions)->Unit(benchmark::kMillisecond);

void BM_PatientPanelAnswer(benchmark::State& state) {
  std::size_t k = 0;
  for (auto _ : state) {
    const std::string text = fmpc::sim::json_text(fmpc::studio::evaluation_json(liver(), kPatients[k++ % kPatients.size()]));
    benchmark::DoNotOptimize(text.data());
  }
}
BENCHMARK(BM_PatientPanelAnswer)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
