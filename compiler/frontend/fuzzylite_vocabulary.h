#pragma once
// The words fuzzylite's two text formats share (FLL, fuzzylite's own language, and FCL, IEC 61131-7 as fuzzylite
// writes it): membership-function families with their parameter orders, norms, defuzzifiers and hedges, mapped to
// fmpc's IR. Parameters in the IR are in MATLAB's order (kernels/fuzzy_kinds.h); fuzzylite orders some differently
// (Gaussian: mean, sd; Bell: centre, width, slope; Sigmoid: inflection, slope).
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "compiler/ir/system_names.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

// fuzzylite's class name for a family ("Triangle", "Gaussian", "Ramp", ...). LinearS and LinearZ are both "Ramp"
// (rising or falling by the order of its ends).
const char* fuzzylite_term_name(MfKind kind);

// A fuzzylite term ("Gaussian" and its numbers in fuzzylite's order) as an IR membership function; nullopt with
// `error` set when the family is unknown to fmpc or the count is wrong. Linear takes any count (checked by sema).
std::optional<MembershipFunction> term_from_fuzzylite(const std::string& name, const std::vector<double>& numbers,
                                                      std::string& error);
// The numbers of `mf` in fuzzylite's order.
std::vector<double> fuzzylite_term_numbers(const MembershipFunction& mf);

std::optional<TNorm> tnorm_from_fuzzylite(const std::string& name);  // "Minimum", "AlgebraicProduct", ...
std::optional<SNorm> snorm_from_fuzzylite(const std::string& name);  // "Maximum", "AlgebraicSum", ...
const char* fuzzylite_name(TNorm norm);
const char* fuzzylite_name(SNorm norm);

// fuzzylite's hedges with the same meaning as fmpc's: "somewhat" (x^0.5) and "very" (x^2); "very very" is two
// words. fuzzylite's "extremely" is an S-curve, not MATLAB's x^3, so it has no fmpc counterpart and is refused.
std::optional<Hedge> hedge_from_fuzzylite(const std::vector<std::string>& words);
std::vector<std::string> fuzzylite_hedge_words(Hedge hedge);  // empty for a hedge fuzzylite cannot say

// A rule in fuzzylite's syntax ("if A is very x and B is not y then Z is w with 0.5"), its variables and terms
// resolved against `system`'s inputs and outputs. `at` locates the text's first character; errors point into it.
// One connective per rule (fmpc's), no parentheses, no `any`.
// `names` indexes `system`'s names (built once for all its rules: compiler/ir/system_names.h).
std::optional<Rule> parse_fuzzylite_rule(const std::string& text, const SourceRange& at, const FuzzySystem& system,
                                         const SystemNames& names, DiagnosticList& diagnostics);
// `rule` in that syntax; empty with an error when fuzzylite cannot say it (a hedge it means differently).
std::string fuzzylite_rule_text(const FuzzySystem& system, const Rule& rule, const SourceRange& where,
                                DiagnosticList& diagnostics);

// The blanks of both formats: space, tab, carriage return, vertical tab, form feed and newline (std::isspace's set
// in the C locale). Every reader of the two formats trims and splits lines with this one set, so that a line that
// is not blank always has a first word (a form feed alone on a line once passed the trim and crashed the FCL reader
// on a line of no words).
inline constexpr const char* kFuzzyliteBlanks = " \t\r\v\f\n";
bool is_fuzzylite_blank(char c);
// `text` without its leading and trailing blanks.
std::string fuzzylite_trimmed(const std::string& text);
// The words of `text`, split at blanks.
std::vector<std::string> fuzzylite_words(const std::string& text);
// A number as fuzzylite writes them ("0.250", "nan", "inf", "-inf"); nullopt for anything else.
std::optional<double> fuzzylite_number(const std::string& text);

// Sugeno when the outputs' terms are Constant or Linear, Mamdani when they are membership functions; an error at
// `where` when an engine mixes both.
SystemType fuzzylite_system_type(const FuzzySystem& system, const SourceRange& where, DiagnosticList& diagnostics);

// The no-fire policy from each output's default (NaN where none was given): all NaN (fuzzylite's default) is
// `error`, as fmpc never prints a silent NaN; every output at its own mid-range (within 1e-12 of the range, as
// fuzzylite prints fixed decimals) is `midrange`, which is how fmpc writes it; one value for all is `value`.
// Anything else is an error at `where`.
void set_no_fire_from_defaults(FuzzySystem& system, const std::vector<double>& defaults, const SourceRange& where,
                               DiagnosticList& diagnostics);

// Keys an FLL or FCL section gives at most once ("range", "METHOD"), and settings the whole file gives one value
// (fmpc sets norms and the defuzzifier once per system, FLL and FCL per rule block or output): a repeat is an error
// naming the first, never "the last one wins" (a second `range:` or `ACCU` once replaced the first silently).
class FuzzyliteKeys {
 public:
  // A new section (variable, block): its keys may be given again.
  void open_section() { section_.clear(); }
  // False, after an error at `at` naming the first, when `key` was given before in this section (`section` names
  // it: "input variable 'x'").
  bool once_in_section(const std::string& key, const SourceRange& at, const std::string& section,
                       DiagnosticList& diagnostics);
  // False, after an error at `at` naming the first, when the file gave `setting` another value before.
  bool one_value(const std::string& setting, const std::string& value, const SourceRange& at,
                 DiagnosticList& diagnostics);

 private:
  std::map<std::string, SourceRange> section_;
  std::map<std::string, std::pair<std::string, SourceRange>> file_;
};

// The formats of rule files fmpc can be handed, told apart by content (rule_file_loader.h uses these).
bool looks_like_fll(const std::string& first_line);  // "Engine:" or another FLL section keyword first
bool looks_like_fcl(const std::string& first_line);  // "FUNCTION_BLOCK" first

}  // namespace fmpc
