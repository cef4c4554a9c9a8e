#pragma once
// The syntax tree of an fmpc-language file (docs/language.md): what the source says, spelled as written, with the
// source range of every token that a diagnostic may point at and the comments that `fmpc fmt` puts back.
// parse_fmpc builds it (fmpc_parser.cpp), lower_fmpc turns it into the IR (compiler/sema/lower_fmpc.cpp) and
// print_fmpc lays it out canonically (fmpc_printer.cpp).
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc::ast {

// The comments around one printed line: own-line comments above it, a comment at the end of its line, and
// whether the source had a blank line above it (kept, at most one, where the layout allows it).
struct Comments {
  std::vector<std::string> leading;  // each with its '#'
  std::string trailing;              // empty when none
  bool blank_line_before = false;
};

struct Name {
  std::string text;  // without the quotes
  SourceRange range;
  bool quoted = false;  // only matters in linear(...), where a bare `offset` is the constant term
};

struct Number {
  double value = 0.0;
  SourceRange range;
};

enum class SettingKind { Type, And, Or, Implication, Aggregation, Defuzzify, NoFire, TypeReduction };

struct Setting {
  SettingKind kind = SettingKind::Type;
  Name value;                  // type / operator / defuzzifier / type reduction name; NoFire "midrange", "value", "error"
  bool interval_type2 = false;  // Type: `type interval_type2 mamdani|sugeno`
  std::optional<Number> samples;  // Defuzzify: `samples N`
  bool samples_exact = false;     // Defuzzify: `samples exact`
  std::optional<Number> no_fire_value;  // NoFire: `value X`
  SourceRange range;  // the whole setting
  Comments comments;
};

struct Argument {
  Name name;  // empty for a positional argument (refused by sema with the named spelling)
  Number value;  // the number, or the low end of an interval `[low, high]`
  std::optional<Name> unit;
  SourceRange range;
  std::optional<Number> high = std::nullopt;  // interval type-2: the high end of `mean [7.1, 8.2]`
};

// The explicit lower MF of `upper gauss(...) lower gauss(...)`.
struct LowerCall {
  Name family;
  std::vector<Argument> arguments;
  SourceRange range;
};

struct Term {
  Name name;
  Name family;  // "gauss", "triangle", ... (the upper MF of an explicit pair)
  std::vector<Argument> arguments;
  bool explicit_upper = false;           // written `is upper FAMILY(...)`
  std::optional<LowerCall> lower;        // `lower FAMILY(...)`
  std::optional<Number> lower_scale;     // `lower scale S [lag L]`
  std::optional<Number> lower_lag;       // `lower [scale S] lag L`
  SourceRange lower_range;               // the `lower ...` part, when present
  SourceRange call_range;                // FAMILY(...) of the upper MF
  SourceRange range;
  Comments comments;
};

struct Variable {
  bool is_output = false;
  Name name;
  std::optional<std::string> description;
  Number min, max;
  std::optional<Name> unit;
  std::vector<Term> terms;
  SourceRange range;  // the header: `input` ... unit
  Comments comments;
};

struct Clause {
  Name variable;
  bool negated = false;
  Hedge hedge = Hedge::None;
  Name term;
  SourceRange range;
};

struct ConnectiveToken {
  Connective connective = Connective::And;
  SourceRange range;
};

struct Rule {
  std::optional<Name> label;
  std::vector<Clause> antecedent;
  std::vector<ConnectiveToken> connectives;  // antecedent.size() - 1 of them, between the clauses
  std::vector<Clause> consequent;
  std::optional<Number> weight;
  SourceRange range;
  Comments comments;
};

using Item = std::variant<Variable, Rule>;

struct System {
  Name name;
  std::optional<std::string> description;
  std::vector<Setting> settings;  // in source order
  std::vector<Item> items;        // variables and rules in source order
  SourceRange range;              // the header: `system` NAME ["description"]
  Comments comments;
};

struct File {
  std::string path;
  std::vector<System> systems;
  Comments end_comments;  // own-line comments after the last item (only `leading` and `blank_line_before`)
};

// Parses `text`; its syntax errors are in `diagnostics` (sorted by position). nullopt when one of them could not be
// repaired; a File when every one was (fmpc_token_repair.h: `.5`, `==`, `mL/min`, a missing ':' ...), read as the
// fix-its say, so that the later steps can report their errors too. A File comes with errors only after repairs.
std::optional<File> parse_fmpc(const std::string& path, const std::string& text, DiagnosticList& diagnostics);

// Resolves names, named MF arguments and units. Systems with errors are left out of the result (their errors are
// in `diagnostics`), so that check_system never reports consequences of a name that did not resolve.
RuleFile lower_fmpc(const File& file, DiagnosticList& diagnostics);

// The canonical text of `file` (docs/language.md, "Canonical layout").
std::string print_fmpc(const File& file);

// Reserved words: names spelled like these are quoted by the printer.
bool is_reserved_word(const std::string& word);

// A name as the language writes it: bare when it is an identifier and not a reserved word, else quoted.
std::string name_as_written(const std::string& name);

// The parameter names of an MF family in the language ("gauss" -> mean, sd) and its IR kind; nullopt for unknown
// families. "linear" has no fixed names (its coefficients are named by input) and reports an empty list.
struct FamilySignature {
  const char* name;
  MfKind kind;
  std::vector<const char*> parameters;  // in the language's canonical order
  std::vector<int> matlab_index;        // position of each parameter in MATLAB's params vector
  std::vector<bool> takes_unit;         // false for slopes
  std::vector<const char*> matlab_parameters;  // MATLAB's documented names, in MATLAB's order: sigma, c
};
const FamilySignature* find_family(const std::string& name);
// The family MATLAB calls `name` ("trimf" -> triangle), accepted as an alias (docs/language.md, "MATLAB's names");
// nullptr when `name` is not one of MATLAB's names that differ from fmpc's.
const FamilySignature* find_matlab_family(const std::string& name);
// The fmpc family or MATLAB alias; `alias` tells which.
const FamilySignature* find_family_or_alias(const std::string& name, bool* alias = nullptr);
const FamilySignature& family_of(MfKind kind);
std::vector<std::string> family_names();
std::vector<std::string> matlab_family_names();  // the aliases: trimf, trapmf, ...

}  // namespace fmpc::ast
