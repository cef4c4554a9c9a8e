// FLL (fuzzylite language) reader and writer. The format is line based: "Key: value", sections opened by Engine:,
// InputVariable:, OutputVariable: and RuleBlock:, '#' comments (fuzzylite's FllImporter, fl/imex/FllImporter.cpp).
#include "compiler/frontend/fll.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "compiler/frontend/fuzzylite_vocabulary.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

// Per-output settings FLL gives each output and fmpc gives the system: read per output, then reconciled.
struct OutputSettings {
  std::string aggregation, defuzzifier, default_value;
  SourceRange aggregation_at, defuzzifier_at, default_at;
};

struct RuleLine {
  std::string text;
  SourceRange at;
};

class FllReader {
 public:
  FllReader(const std::string& path, DiagnosticList& diagnostics) : path_(path), diagnostics_(diagnostics) {}

  RuleFile read(const std::string& text) {
    RuleFile file;
    file.path = path_;
    system_.range = SourceRange{path_, 1, 1, 1, 1};
    std::istringstream lines(text);
    int number = 0;
    for (std::string line; std::getline(lines, line);) {
      ++number;
      const std::size_t comment = line.find('#');
      if (comment != std::string::npos) line.resize(comment);
      const std::size_t first = line.find_first_not_of(kFuzzyliteBlanks);
      if (first == std::string::npos) continue;
      const std::size_t colon = line.find(':', first);
      const auto at = [&](std::size_t column, std::size_t length) {
        return SourceRange{path_, number, static_cast<int>(column) + 1, number, static_cast<int>(column + length) + 1};
      };
      if (colon == std::string::npos) {
        diagnostics_.error(at(first, line.size() - first), "expected 'key: value' (FLL)");
        continue;
      }
      const std::string key = fuzzylite_trimmed(line.substr(first, colon - first));
      const std::size_t value_start = line.find_first_not_of(kFuzzyliteBlanks, colon + 1);
      const std::string value = value_start == std::string::npos ? "" : fuzzylite_trimmed(line.substr(value_start));
      const SourceRange key_at = at(first, key.size());
      const SourceRange value_at =
          value_start == std::string::npos ? at(colon + 1, 0) : at(value_start, value.size());
      line_key(key, value, key_at, value_at);
    }
    finish();
    if (!diagnostics_.has_errors() || !system_.inputs.empty() || !system_.outputs.empty())
      file.systems.push_back(std::move(system_));
    return file;
  }

 private:
  enum class Section { None, Engine, Input, Output, RuleBlock };

  void line_key(const std::string& key, const std::string& value, const SourceRange& key_at,
                const SourceRange& value_at) {
    if (key == "Engine") {
      section_ = Section::Engine;
      keys_.open_section();
      if (engine_at_.valid()) {
        diagnostics_.error(key_at, "a second 'Engine:'; an FLL file holds one engine, and fmpc reads it as one system",
                           {"the first engine starts here: " + std::to_string(engine_at_.line) + ":" +
                                std::to_string(engine_at_.column) + "; put each engine in a file of its own"});
        return;
      }
      engine_at_ = key_at;
      system_.name = value.empty() ? "fll" : value;
      system_.range = key_at;
      return;
    }
    if (key == "InputVariable" || key == "OutputVariable") {
      const bool input = key == "InputVariable";
      section_ = input ? Section::Input : Section::Output;
      keys_.open_section();
      Variable variable;
      variable.name = value;
      variable.range = key_at;
      variable.name_range = value_at;
      (input ? system_.inputs : system_.outputs).push_back(variable);
      if (!input) outputs_.emplace_back();
      if (value.empty()) diagnostics_.error(value_at, "the variable needs a name");
      return;
    }
    if (key == "RuleBlock") {
      section_ = Section::RuleBlock;
      keys_.open_section();
      return;
    }
    // Every other key but `term` and `rule` once per section.
    if (key != "term" && key != "rule" && !keys_.once_in_section(key, key_at, section_title(), diagnostics_)) return;
    if (key == "description") {
      if (section_ == Section::Engine) system_.description = value;
      else if (Variable* v = current_variable()) v->description = value;
      return;
    }
    if (key == "enabled") {
      if (value == "false")
        diagnostics_.error(value_at, "a disabled " + section_name() +
                                         " has no fmpc counterpart: remove it from the file, or enable it");
      return;
    }
    switch (section_) {
      case Section::Input:
      case Section::Output: variable_key(key, value, key_at, value_at); return;
      case Section::RuleBlock: rule_block_key(key, value, key_at, value_at); return;
      case Section::Engine:
      case Section::None: break;
    }
    unknown_key(key, key_at, {"Engine", "description", "InputVariable", "OutputVariable", "RuleBlock"});
  }

  std::string section_name() const {
    switch (section_) {
      case Section::Input: return "input variable";
      case Section::Output: return "output variable";
      case Section::RuleBlock: return "rule block";
      default: return "engine";
    }
  }

  // "input variable 'x'", "the engine": where a key was given twice.
  std::string section_title() {
    if (const Variable* v = current_variable()) return section_name() + " '" + v->name + "'";
    return section_ == Section::RuleBlock ? "the rule block" : "the engine";
  }

  Variable* current_variable() {
    if (section_ == Section::Input && !system_.inputs.empty()) return &system_.inputs.back();
    if (section_ == Section::Output && !system_.outputs.empty()) return &system_.outputs.back();
    return nullptr;
  }

  void unknown_key(const std::string& key, const SourceRange& at, const std::vector<std::string>& known) {
    std::vector<std::string> notes;
    if (auto suggestion = closest_name(key, known)) notes.push_back("did you mean '" + *suggestion + "'?");
    diagnostics_.error(at, "'" + key + "' is not a key of an FLL " + section_name(), notes);
  }

  void variable_key(const std::string& key, const std::string& value, const SourceRange& key_at,
                    const SourceRange& value_at) {
    Variable& variable = *current_variable();
    const bool output = section_ == Section::Output;
    if (key == "range") {
      const std::vector<std::string> words = fuzzylite_words(value);
      const auto lo = words.size() == 2 ? fuzzylite_number(words[0]) : std::nullopt;
      const auto hi = words.size() == 2 ? fuzzylite_number(words[1]) : std::nullopt;
      if (!lo || !hi) {
        diagnostics_.error(value_at, "expected 'range: MIN MAX'");
        return;
      }
      variable.min = *lo;
      variable.max = *hi;
    } else if (key == "lock-range") {
      if (value == "true")
        diagnostics_.warning(value_at, "format-difference",
                             std::string("lock-range: true clamps ") + (output ? "the output" : "inputs") +
                                 " to the range in fuzzylite; fmpc evaluates " +
                                 (output ? "outputs unclamped" : "inputs outside the range as given, with a warning"));
    } else if (key == "term") {
      read_term(variable, value, value_at);
    } else if (output && key == "aggregation") {
      outputs_.back().aggregation = value;
      outputs_.back().aggregation_at = value_at;
    } else if (output && key == "defuzzifier") {
      outputs_.back().defuzzifier = value;
      outputs_.back().defuzzifier_at = value_at;
    } else if (output && key == "default") {
      outputs_.back().default_value = value;
      outputs_.back().default_at = value_at;
    } else if (output && key == "lock-previous") {
      if (value == "true")
        diagnostics_.error(value_at, "lock-previous: true keeps the last output when no rule fires, a state fmpc's "
                                     "evaluators do not keep: use 'default: VALUE'");
    } else {
      unknown_key(key, key_at,
                  output ? std::vector<std::string>{"description", "enabled", "range", "lock-range", "aggregation",
                                                    "defuzzifier", "default", "lock-previous", "term"}
                         : std::vector<std::string>{"description", "enabled", "range", "lock-range", "term"});
    }
  }

  void read_term(Variable& variable, const std::string& value, const SourceRange& at) {
    const std::vector<std::string> words = fuzzylite_words(value);
    if (words.size() < 2) {
      diagnostics_.error(at, "expected 'term: NAME FAMILY NUMBERS...'");
      return;
    }
    Term term;
    term.name = words[0];
    term.range = at;
    term.name_range = SourceRange{at.file, at.line, at.column, at.line, at.column + static_cast<int>(words[0].size())};
    std::vector<double> numbers;
    for (std::size_t k = 2; k < words.size(); ++k) {
      const auto n = fuzzylite_number(words[k]);
      if (!n) {
        diagnostics_.error(at, "'" + words[k] + "' is not a number (term '" + term.name + "')");
        return;
      }
      numbers.push_back(*n);
    }
    std::string error;
    const auto mf = term_from_fuzzylite(words[1], numbers, error);
    if (!mf) {
      diagnostics_.error(at, error);
      return;
    }
    term.mf = *mf;
    variable.terms.push_back(term);
  }

  void rule_block_key(const std::string& key, const std::string& value, const SourceRange& key_at,
                      const SourceRange& value_at) {
    if (key == "rule") {
      rules_.push_back(RuleLine{value, value_at});
      return;
    }
    if (key == "conjunction" || key == "implication" || key == "disjunction" || key == "activation")
      if (!keys_.one_value(key, value, value_at, diagnostics_)) return;
    if (key == "conjunction" || key == "implication") {
      if (value == "none") return;
      const auto norm = tnorm_from_fuzzylite(value);
      if (!norm) {
        diagnostics_.error(value_at, "'" + value + "' is not a T-norm fmpc has (Minimum, AlgebraicProduct, "
                                                   "EinsteinProduct)");
        return;
      }
      (key == "conjunction" ? system_.and_method : system_.implication) = *norm;
      return;
    }
    if (key == "disjunction") {
      if (value == "none") return;
      const auto norm = snorm_from_fuzzylite(value);
      if (!norm)
        diagnostics_.error(value_at, "'" + value + "' is not an S-norm fmpc has (Maximum, AlgebraicSum, "
                                                   "UnboundedSum, EinsteinSum)");
      else
        system_.or_method = *norm;
      return;
    }
    if (key == "activation") {
      if (value != "General" && !value.empty())
        diagnostics_.error(value_at, "activation '" + value + "' has no fmpc counterpart: fmpc fires every rule "
                                     "(fuzzylite's General)");
      return;
    }
    unknown_key(key, key_at, {"description", "enabled", "conjunction", "disjunction", "implication", "activation",
                              "rule"});
  }

  // Per-output settings into the system's; rules once every variable is known.
  void finish() {
    if (system_.name.empty()) system_.name = "fll";
    system_.type = fuzzylite_system_type(system_, system_.range, diagnostics_);
    for (std::size_t o = 0; o < outputs_.size(); ++o) {
      const OutputSettings& s = outputs_[o];
      if (o > 0) {
        const OutputSettings& first = outputs_.front();
        if (s.aggregation != first.aggregation || s.defuzzifier != first.defuzzifier)
          diagnostics_.error(s.defuzzifier_at.valid() ? s.defuzzifier_at : system_.outputs[o].range,
                             "output '" + system_.outputs[o].name + "' differs from '" + system_.outputs[0].name +
                                 "' in aggregation or defuzzifier; fmpc systems set these once for all outputs: "
                                 "split the engine, or make them equal");
        continue;
      }
      if (!s.aggregation.empty() && s.aggregation != "none") {
        const auto norm = snorm_from_fuzzylite(s.aggregation);
        if (!norm) diagnostics_.error(s.aggregation_at, "'" + s.aggregation + "' is not an S-norm fmpc has");
        else system_.aggregation = *norm;
      }
      read_defuzzifier(s);
    }
    read_defaults();
    const SystemNames names(system_);
    for (const RuleLine& line : rules_)
      if (auto rule = parse_fuzzylite_rule(line.text, line.at, system_, names, diagnostics_))
        system_.rules.push_back(*rule);
  }

  // Each output's default as a number (NaN where none was given), into the system's one policy.
  void read_defaults() {
    std::vector<double> values;
    for (const OutputSettings& s : outputs_) {
      const auto value = s.default_value.empty() ? std::optional<double>(std::nan("")) : fuzzylite_number(s.default_value);
      if (!value) {
        diagnostics_.error(s.default_at, "'" + s.default_value + "' is not a number");
        return;
      }
      values.push_back(*value);
    }
    set_no_fire_from_defaults(system_, values,
                              !outputs_.empty() && outputs_.back().default_at.valid() ? outputs_.back().default_at
                                                                                      : system_.range,
                              diagnostics_);
  }

  void read_defuzzifier(const OutputSettings& s) {
    const std::vector<std::string> words = fuzzylite_words(s.defuzzifier);
    if (words.empty()) return;
    const std::string& name = words[0];
    struct Named {
      const char* name;
      Defuzzifier defuzzifier;
      bool integral;
    };
    static const Named named[] = {{"Centroid", Defuzzifier::Centroid, true},
                                  {"Bisector", Defuzzifier::Bisector, true},
                                  {"MeanOfMaximum", Defuzzifier::MeanOfMaximum, true},
                                  {"SmallestOfMaximum", Defuzzifier::SmallestOfMaximum, true},
                                  {"LargestOfMaximum", Defuzzifier::LargestOfMaximum, true},
                                  {"WeightedAverage", Defuzzifier::WeightedAverage, false},
                                  {"WeightedSum", Defuzzifier::WeightedSum, false}};
    for (const Named& n : named) {
      if (name != n.name) continue;
      system_.defuzzifier = n.defuzzifier;
      if (n.integral && words.size() >= 2) {
        const auto resolution = fuzzylite_number(words[1]);
        if (!resolution || *resolution < 2 || *resolution > 1e6 || *resolution != std::floor(*resolution))
          diagnostics_.error(s.defuzzifier_at, "resolution '" + words[1] + "' is not a whole number from 2 to 10^6");
        else
          system_.samples = static_cast<int>(*resolution);
      }
      if (!n.integral && words.size() >= 2 && words[1] != "Automatic" && words[1] != "TakagiSugeno")
        diagnostics_.error(s.defuzzifier_at, "'" + words[1] + "' weighting (fuzzylite's Tsukamoto) has no fmpc "
                                                              "counterpart; use Automatic or TakagiSugeno");
      return;
    }
    diagnostics_.error(s.defuzzifier_at, "'" + name + "' is not a defuzzifier fmpc has (Centroid, Bisector, "
                                                      "MeanOfMaximum, SmallestOfMaximum, LargestOfMaximum, "
                                                      "WeightedAverage, WeightedSum)");
  }

  std::string path_;
  DiagnosticList& diagnostics_;
  FuzzySystem system_;
  Section section_ = Section::None;
  std::vector<OutputSettings> outputs_;
  std::vector<RuleLine> rules_;
  SourceRange engine_at_;
  FuzzyliteKeys keys_;
};

std::string defuzzifier_text(const FuzzySystem& system) {
  const std::string resolution = " " + std::to_string(system.samples);
  switch (system.defuzzifier) {
    case Defuzzifier::Centroid: return "Centroid" + resolution;
    case Defuzzifier::Bisector: return "Bisector" + resolution;
    case Defuzzifier::MeanOfMaximum: return "MeanOfMaximum" + resolution;
    case Defuzzifier::SmallestOfMaximum: return "SmallestOfMaximum" + resolution;
    case Defuzzifier::LargestOfMaximum: return "LargestOfMaximum" + resolution;
    case Defuzzifier::WeightedAverage: return "WeightedAverage TakagiSugeno";
    case Defuzzifier::WeightedSum: return "WeightedSum TakagiSugeno";
  }
  return "Centroid" + resolution;
}

}  // namespace

RuleFile read_fll(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  return FllReader(path, diagnostics).read(text);
}

std::string write_fll(const FuzzySystem& system, DiagnosticList& diagnostics) {
  if (system.interval_type2)
    diagnostics.error(system.range, "FLL holds type-1 systems; '" + system.name + "' is interval type-2");
  if (system.samples == 0 && system.type == SystemType::Mamdani)
    diagnostics.warning(system.range, "format-difference",
                        "FLL has no exact defuzzification ('samples exact'); written with resolution 1001");
  std::ostringstream out;
  out << "# " << system.name << ", written by fmpc (fuzzylite language, FLL)\n";
  out << "Engine: " << system.name << '\n';
  if (!system.description.empty()) out << "description: " << system.description << '\n';
  const auto write_terms = [&](const Variable& v) {
    if (!v.unit.empty() && v.unit != "dimensionless")
      diagnostics.warning(v.range, "format-difference", "FLL has no units: '" + v.name + "' (" + v.unit +
                                                            ") is written without its unit");
    for (const Term& term : v.terms) {
      out << "  term: " << term.name << ' ' << fuzzylite_term_name(term.mf.kind);
      for (double n : fuzzylite_term_numbers(term.mf)) out << ' ' << format_number(n);
      out << '\n';
    }
  };
  for (const Variable& v : system.inputs) {
    out << "InputVariable: " << v.name << '\n';
    if (!v.description.empty()) out << "  description: " << v.description << '\n';
    out << "  enabled: true\n  range: " << format_number(v.min) << ' ' << format_number(v.max)
        << "\n  lock-range: false\n";
    write_terms(v);
  }
  FuzzySystem written = system;
  if (system.samples == 0) written.samples = 1001;
  for (const Variable& v : system.outputs) {
    out << "OutputVariable: " << v.name << '\n';
    if (!v.description.empty()) out << "  description: " << v.description << '\n';
    out << "  enabled: true\n  range: " << format_number(v.min) << ' ' << format_number(v.max)
        << "\n  lock-range: false\n";
    // Written for Sugeno systems too: fuzzylite's weighted average ignores it, and the file keeps the system's field.
    out << "  aggregation: " << fuzzylite_name(system.aggregation) << '\n';
    out << "  defuzzifier: " << defuzzifier_text(written) << '\n';
    switch (system.no_fire) {
      case NoFirePolicy::Error: out << "  default: nan\n"; break;
      case NoFirePolicy::Value: out << "  default: " << format_number(system.no_fire_value) << '\n'; break;
      case NoFirePolicy::Midrange: out << "  default: " << format_number((v.min + v.max) / 2) << '\n'; break;
    }
    out << "  lock-previous: false\n";
    write_terms(v);
  }
  out << "RuleBlock: rules\n  enabled: true\n";
  out << "  conjunction: " << fuzzylite_name(system.and_method) << '\n';
  out << "  disjunction: " << fuzzylite_name(system.or_method) << '\n';
  out << "  implication: " << fuzzylite_name(system.implication) << '\n';
  out << "  activation: General\n";
  for (const Rule& rule : system.rules) {
    const std::string text = fuzzylite_rule_text(system, rule, rule.range, diagnostics);
    if (!text.empty()) out << "  rule: " << text << '\n';
  }
  return out.str();
}

}  // namespace fmpc
