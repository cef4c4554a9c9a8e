#pragma once
// The fmpc rule language (docs/language.md): reading (parse -> AST -> IR through sema), canonical formatting
// that keeps comments (`fmpc fmt`), and writing an IR back as fmpc text (`fmpc convert --to fmpc`).
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

// Parses and lowers an fmpc-language file. Syntax errors, unknown names (with "did you mean"), unit mismatches,
// named-argument errors and rules naming variables of another system are reported here; parameter validity and
// duplicates are left to check_system (compiler/sema/check.h), which load_rule_file runs afterwards.
RuleFile read_fmpc(const std::string& path, const std::string& text, DiagnosticList& diagnostics);

// The canonical layout of `text`, comments kept. nullopt when the text has syntax errors (in `diagnostics`).
// Idempotent: format_fmpc(format_fmpc(t)) == format_fmpc(t).
std::optional<std::string> format_fmpc(const std::string& path, const std::string& text,
                                       DiagnosticList& diagnostics);

// One rule of `system` as canonical fmpc text, without the leading "rule LABEL:" (for `fmpc eval --explain`):
// `if HCV is F2 and HBV is "F0-F1" then stiffness is "F0-F1" weight 0.5`.
std::string format_rule_body(const FuzzySystem& system, std::size_t rule_index);

// The systems of `file` as fmpc text in the canonical layout (what format_fmpc would produce).
std::string write_fmpc(const RuleFile& file);

// A parameter value to write into fmpc text (`fmpc tune`): the argument `parameter` (the language's name; a
// `linear` coefficient by its input's name, or `offset`) of term `term` of variable `variable` of system `system`,
// as a number in the variable's unit.
struct ParameterEdit {
  std::string system, variable, term, parameter;
  double value = 0.0;
};

// `text` with each edit's number written where the argument stands, so that comments, layout and every other
// number stay as they were. An argument written with another unit than its variable's is rewritten in the
// variable's unit; a `linear` coefficient the text leaves out (0) is added. nullopt with errors when the text
// does not parse or an edit names nothing in it.
std::optional<std::string> edit_fmpc_parameters(const std::string& path, const std::string& text,
                                                const std::vector<ParameterEdit>& edits,
                                                DiagnosticList& diagnostics);

}  // namespace fmpc
