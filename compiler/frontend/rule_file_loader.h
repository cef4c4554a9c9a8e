#pragma once
// One entry point for every reader: picks the dialect from the text (a file whose first non-comment line is
// "[System]" is MATLAB's), parses, lowers and checks. Returns what it could build; errors are in `diagnostics`.
#include <optional>
#include <string>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

enum class Dialect { Fmpc, Matlab };

Dialect detect_dialect(const std::string& text);

// Parses `text` (the contents of `path`), resolves names and checks parameters (sema). The result holds every
// system that could be built; when diagnostics.has_errors() it must not be evaluated.
RuleFile load_rule_file(const std::string& path, const std::string& text, DiagnosticList& diagnostics);

}  // namespace fmpc
