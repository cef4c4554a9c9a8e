#pragma once
// The markdown of a hover, read from the checked system (numbers from the IR, grades from the interpreter's own
// membership functions), shared by fmpc-language text (lsp_hover.cpp) and MATLAB .fis text (lsp_matlab.cpp).
#include <string>

#include <nlohmann/json.hpp>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc::lsp {

// An LSP Hover: `text` as markdown over `range`.
nlohmann::json markdown_hover(const std::string& text, const nlohmann::json& range);

// The input or output called `name`; `is_output` tells which.
const Variable* find_variable(const FuzzySystem& system, const std::string& name, bool* is_output = nullptr);

// "MATLAB's `gaussmf [0.91 7.64]` in kPa", then the exact grades at the range's ends and where the shape turns, and
// the shape sampled over the range.
std::string term_hover_text(const Variable& variable, const Term& term);
// "**HCV = 7.64 kPa**" and the grade of every term of `variable` there.
std::string value_hover_text(const Variable& variable, double value);
// The variable's description, range, terms and how many rules name it.
std::string variable_hover_text(const FuzzySystem& system, const Variable& variable, bool is_output);
// A family, by fmpc's or MATLAB's name: its parameters in both spellings; "" when `written` names none.
std::string family_hover_text(const std::string& written);

}  // namespace fmpc::lsp
