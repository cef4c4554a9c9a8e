#pragma once
// The validation and comparison panels as JSON: a CSV the page sends as text, read by the same reader as
// `fmpc validate` and `fmpc diff` (tools/fmpc/patient_data.h), and the same reports (validation_report.h,
// version_diff_report.h), so that every number equals the command's.
#include <map>
#include <string>

#include "compiler/ir/fuzzy_system.h"
#include "tools/studio/studio_rule_model.h"

namespace fmpc::studio {

struct CohortTable {
  std::string name;  // as diagnostics name it ("measured.csv")
  std::string text;
  std::map<std::string, std::string> input_columns;  // --column INPUT=COLUMN
};

// {"ok": true, "agreement": ..., "patients": [...], "worst": [...], "notes": [...], "warnings": [...]} or
// {"ok": false, "errors": [...]} with every diagnostic as `fmpc validate` prints it.
Json validation_json(const FuzzySystem& system, const std::string& output, const std::string& measured_column,
                     const CohortTable& table);

// `a` is the reference (the file on disk, or the first file), `b` the other version.
Json comparison_json(const FuzzySystem& a, const std::string& name_a, const FuzzySystem& b, const std::string& name_b,
                     const CohortTable& table);

// Just the differences in the definitions, without patients.
Json differences_json(const FuzzySystem& a, const FuzzySystem& b);

}  // namespace fmpc::studio
