#pragma once
// The rule file as the studio's page sees it, as JSON: the diagnostics `fmpc check` gives (the same functions:
// load_rule_file and lint_rule_file, rendered with the same renderer), and every system's settings, variables,
// terms (with their named parameters and source ranges) and rules (as fmpc text and as a plain sentence), plus the
// membership curves of one variable.
#include <optional>
#include <string>

#include "runtime/io/json_text.h"
#include "runtime/io/rule_file_input.h"

namespace fmpc::studio {

using Json = sim::JsonDocument;

// The rule file read from `text` (named `path`) exactly as `fmpc check` reads it from disk, with lint appended.
sim::LoadedRuleFile load_rule_text(const std::string& path, const std::string& text);

// {line, column, end_line, end_column}: 1-based, columns in bytes as the diagnostics count them.
Json range_json(const SourceRange& range);

// {"diagnostics": [...], "errors": N, "warnings": N, "systems": [...]} for a loaded file. Each diagnostic carries
// `text`, exactly what `fmpc check` prints for it.
Json check_json(const sim::LoadedRuleFile& file);

// One system: settings, inputs (with coverage holes at lint's threshold), outputs, rules.
Json system_json(const FuzzySystem& system);

// The membership functions of a variable sampled for drawing: `x` (`samples` points over the range, plus every MF
// parameter inside it, sorted) and per term its parameters (as in system_json) and `upper` (and `lower` for type-2
// terms) grades, from term_membership.
Json membership_curves_json(const FuzzySystem& system, const Variable& variable, bool output, int samples);

// "If HCV is F2 and HBV is F0-F1, then stiffness is F0-F1." (weights other than 1: "(weight 0.5)").
std::string rule_sentence(const FuzzySystem& system, std::size_t rule);

// The system named `name` (the first when empty) of a file without errors, or nullptr.
const FuzzySystem* find_system(const RuleFile& file, const std::string& name);

}  // namespace fmpc::studio
