#pragma once
// `fmpc diff A B --csv PATIENTS.csv` and the studio's comparison panel: what differs between two versions of a rule
// system (compiler/eval/system_diff.h) in words a clinician reads, and what the difference does to every patient's
// outputs and stages, as markdown, CSV and a histogram of the changes.
#include <optional>
#include <string>
#include <vector>

#include "compiler/eval/agreement.h"
#include "compiler/eval/system_diff.h"
#include "tools/fmpc/patient_data.h"
#include "tools/plot/canvas.h"

namespace fmpc::cli {

// An MF as the fmpc language writes it, with the family's parameter names: "gauss(mean 7.64, sd 0.91)".
std::string term_shape_text(const Term& term, const FuzzySystem& system);

// One line per difference: settings, variables, terms ("term 'F2' of input 'HCV': gauss(mean 7.64, sd 0.91) ->
// gauss(mean 7.9, sd 0.91)") and rules ("r7: if ... then ... -> if ... then ..."), in that order.
std::vector<std::string> describe_differences(const FuzzySystem& a, const FuzzySystem& b,
                                              const SystemDifferences& differences);

struct VersionDiffReport {
  std::string path_a, path_b, data_path;
  std::vector<std::string> differences;  // describe_differences
  std::vector<std::string> labels;       // per patient
  std::vector<int> lines;
  std::vector<OutputComparisonOverPoints> outputs;
  std::vector<Histogram> histograms;  // per output, of the finite differences b - a; empty counts when none
  std::vector<std::string> units;     // per output, the first version's unit
  std::vector<std::string> notes;     // from reading the data; outputs only one version has
};

// Evaluates both versions for every patient. Evaluation warnings are appended (at most 20 per version); errors (no
// rule fired under the policy `error`) too, and then nullopt.
std::optional<VersionDiffReport> compare_versions(const FuzzySystem& a, const FuzzySystem& b, const PatientData& data,
                                                  const EvaluationOptions& options, DiagnosticList& diagnostics);

std::string version_diff_markdown(const VersionDiffReport& report, const FuzzySystem& a, const FuzzySystem& b);
// label, line, then per output: OUTPUT.a, OUTPUT.b, OUTPUT.difference, OUTPUT.stage_a, OUTPUT.stage_b.
std::string version_diff_csv(const VersionDiffReport& report, const FuzzySystem& a, const FuzzySystem& b);
// The histogram of output `index` of report.outputs.
std::string difference_histogram_plot(const VersionDiffReport& report, std::size_t index, plot::ImageFormat format);

// The stage's term name, or "" for -1.
std::string stage_name(const FuzzySystem& system, int output, int stage);

}  // namespace fmpc::cli
