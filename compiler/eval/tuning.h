#pragma once
// Tuning a rule system's membership-function parameters against measured data (MATLAB's tunefis; docs/cli.md, `fmpc tune`):
// only the parameters named, each within bounds that keep its term in its variable's range and its kind of value
// (a width positive, a slope's sign), every candidate valid (check_system) and with its variables' terms in their
// order; the RMSE of one output against the measured values minimised by the bounded Nelder-Mead search of
// nelder_mead.h from the file's own values; k-fold held-out RMSE before and after. Rules, weights and settings
// are never changed, and no rule is added or removed.
#include <cstdint>
#include <string>
#include <vector>

#include "compiler/eval/nelder_mead.h"
#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

struct TunableParameter {
  std::string name;  // VARIABLE.TERM.PARAMETER in the language's names: "HCV.F2.mean", "y.model.offset"
  bool output = false;
  std::size_t variable = 0;
  std::size_t term = 0;
  std::size_t index = 0;  // into the term's MATLAB-ordered params
  double value = 0.0;     // the file's value
  double lower = 0.0;
  double upper = 0.0;
  std::string bound;  // why these bounds, for the report ("inside the range", "a width", ...)
};

// The parameters of `system` that match a pattern VARIABLE.TERM.PARAMETER, each part a glob (`*`, `?`):
// "HCV.F2.mean", "HCV.*.mean", "*.*.sd", "stiffness.*.*". A pattern of two parts (VARIABLE.TERM) takes every
// parameter of the terms it matches. Errors (located at `where`): a pattern that matches nothing (with the closest
// parameter name), an interval type-2 system. In the system's order; each parameter once.
std::vector<TunableParameter> select_parameters(const FuzzySystem& system, const std::vector<std::string>& patterns,
                                                const SourceRange& where, DiagnosticList& diagnostics);

// The system with `values` (one per parameter, in order) in place of the parameters' values.
FuzzySystem with_parameters(const FuzzySystem& system, const std::vector<TunableParameter>& parameters,
                            const std::vector<double>& values);

struct TuningData {
  std::vector<std::vector<double>> inputs;  // per patient, in the system's input order and units
  std::vector<double> measured;             // per patient, in the fitted output's unit
  std::size_t output = 0;                   // index of the fitted output
};

// Root mean square of predicted - measured over the patients `rows` of `data`; infinite when the system predicts
// no finite value for one of them (no rule fires under the `error` policy).
double prediction_rmse(const FuzzySystem& system, const TuningData& data, const std::vector<std::size_t>& rows);

struct TuningOptions {
  int folds = 5;           // k of the k-fold cross-validation; 0 skips it
  std::uint64_t seed = 1;  // which patients go into which fold
  NelderMeadOptions search;
};

struct FoldResult {
  std::size_t patients = 0;  // held out
  double rmse_before = 0.0;  // the file's system on the held-out patients
  double rmse_after = 0.0;   // the system tuned on the other folds, on the held-out patients
  int evaluations = 0;
  bool converged = false;
};

struct TuningResult {
  std::vector<double> values;  // tuned on every patient
  double rmse_before = 0.0;    // on every patient
  double rmse_after = 0.0;
  NelderMeadResult search;  // the search on every patient
  std::vector<FoldResult> folds;
  double held_out_rmse_before = 0.0;  // pooled over every held-out prediction
  double held_out_rmse_after = 0.0;
};

// The patients of each fold: a Fisher-Yates shuffle driven by std::mt19937_64(seed) (whose output the C++ standard
// fixes), cut into `folds` parts of sizes differing by at most one.
std::vector<std::vector<std::size_t>> fold_assignment(std::size_t patients, int folds, std::uint64_t seed);

// Tunes `parameters` of `system`. Preconditions: the system passed check_system, data holds at least 2 patients
// (and at least `folds` when folds > 0), every parameter from select_parameters on this system.
TuningResult tune_system(const FuzzySystem& system, const std::vector<TunableParameter>& parameters,
                         const TuningData& data, const TuningOptions& options);

}  // namespace fmpc
