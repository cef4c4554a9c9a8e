#include "compiler/frontend/fuzzylite_vocabulary.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <utility>

#include "diagnostics/number_format.h"

namespace fmpc {

const char* fuzzylite_term_name(MfKind kind) {
  switch (kind) {
    case MfKind::Triangle: return "Triangle";
    case MfKind::Trapezoid: return "Trapezoid";
    case MfKind::Gaussian: return "Gaussian";
    case MfKind::Gaussian2: return "GaussianProduct";
    case MfKind::GeneralizedBell: return "Bell";
    case MfKind::Sigmoid: return "Sigmoid";
    case MfKind::DifferenceSigmoid: return "SigmoidDifference";
    case MfKind::ProductSigmoid: return "SigmoidProduct";
    case MfKind::ZShape: return "ZShape";
    case MfKind::SShape: return "SShape";
    case MfKind::PiShape: return "PiShape";
    case MfKind::LinearS: return "Ramp";
    case MfKind::LinearZ: return "Ramp";
    case MfKind::Constant: return "Constant";
    case MfKind::Linear: return "Linear";
  }
  return "?";
}

std::optional<MembershipFunction> term_from_fuzzylite(const std::string& name, const std::vector<double>& n,
                                                      std::string& error) {
  struct Family {
    const char* name;
    MfKind kind;
    std::size_t count;
  };
  static const Family families[] = {
      {"Triangle", MfKind::Triangle, 3},   {"Trapezoid", MfKind::Trapezoid, 4},
      {"Gaussian", MfKind::Gaussian, 2},   {"GaussianProduct", MfKind::Gaussian2, 4},
      {"Bell", MfKind::GeneralizedBell, 3}, {"Sigmoid", MfKind::Sigmoid, 2},
      {"SigmoidDifference", MfKind::DifferenceSigmoid, 4}, {"SigmoidProduct", MfKind::ProductSigmoid, 4},
      {"ZShape", MfKind::ZShape, 2},       {"SShape", MfKind::SShape, 2},
      {"PiShape", MfKind::PiShape, 4},     {"Ramp", MfKind::LinearS, 2},
      {"Constant", MfKind::Constant, 1},   {"Linear", MfKind::Linear, 0}};
  for (const Family& f : families) {
    if (name != f.name) continue;
    if (f.count > 0 && n.size() != f.count) {
      // fuzzylite allows a trailing height; fmpc's terms all reach 1.
      error = n.size() == f.count + 1
                  ? "term '" + name + "' has a height (" + std::to_string(n.back()) +
                        "); fmpc's membership functions all reach 1: remove it or scale the term another way"
                  : "'" + name + "' takes " + std::to_string(f.count) + " numbers, not " + std::to_string(n.size());
      return std::nullopt;
    }
    MembershipFunction mf;
    mf.kind = f.kind;
    switch (f.kind) {
      case MfKind::Gaussian: mf.params = {n[1], n[0]}; break;                    // mean sd -> sd mean
      case MfKind::Gaussian2: mf.params = {n[1], n[0], n[3], n[2]}; break;       // m1 s1 m2 s2 -> s1 m1 s2 m2
      case MfKind::GeneralizedBell: mf.params = {n[1], n[2], n[0]}; break;       // c w s -> w s c
      case MfKind::Sigmoid: mf.params = {n[1], n[0]}; break;                     // inflection slope -> a c
      case MfKind::DifferenceSigmoid:                                            // left rising falling right
      case MfKind::ProductSigmoid: mf.params = {n[1], n[0], n[2], n[3]}; break;  // -> a1 c1 a2 c2
      case MfKind::LinearS:
        // A Ramp rises from its start to its end, or falls when the end comes first.
        if (n[0] > n[1]) {
          mf.kind = MfKind::LinearZ;
          mf.params = {n[1], n[0]};
        } else {
          mf.params = n;
        }
        break;
      default: mf.params = n;
    }
    return mf;
  }
  error = "'" + name + "' is not a membership function fmpc has (Triangle, Trapezoid, Gaussian, GaussianProduct, "
          "Bell, Sigmoid, SigmoidDifference, SigmoidProduct, ZShape, SShape, PiShape, Ramp, Constant, Linear)";
  return std::nullopt;
}

std::vector<double> fuzzylite_term_numbers(const MembershipFunction& mf) {
  const std::vector<double>& p = mf.params;
  switch (mf.kind) {
    case MfKind::Gaussian: return {p[1], p[0]};
    case MfKind::Gaussian2: return {p[1], p[0], p[3], p[2]};
    case MfKind::GeneralizedBell: return {p[2], p[0], p[1]};
    case MfKind::Sigmoid: return {p[1], p[0]};
    case MfKind::DifferenceSigmoid:
    case MfKind::ProductSigmoid: return {p[1], p[0], p[2], p[3]};
    case MfKind::LinearZ: return {p[1], p[0]};
    default: return p;
  }
}

namespace {

const std::pair<const char*, TNorm> kTNorms[] = {
    {"Minimum", TNorm::Minimum}, {"AlgebraicProduct", TNorm::Product}, {"EinsteinProduct", TNorm::EinsteinProduct}};
const std::pair<const char*, SNorm> kSNorms[] = {{"Maximum", SNorm::Maximum},
                                                 {"AlgebraicSum", SNorm::ProbabilisticSum},
                                                 {"UnboundedSum", SNorm::Sum},
                                                 {"EinsteinSum", SNorm::EinsteinSum}};

}  // namespace

std::optional<TNorm> tnorm_from_fuzzylite(const std::string& name) {
  for (const auto& [text, norm] : kTNorms)
    if (name == text) return norm;
  return std::nullopt;
}

std::optional<SNorm> snorm_from_fuzzylite(const std::string& name) {
  for (const auto& [text, norm] : kSNorms)
    if (name == text) return norm;
  return std::nullopt;
}

const char* fuzzylite_name(TNorm norm) {
  for (const auto& [text, n] : kTNorms)
    if (n == norm) return text;
  return "?";
}

const char* fuzzylite_name(SNorm norm) {
  for (const auto& [text, n] : kSNorms)
    if (n == norm) return text;
  return "?";
}

std::optional<Hedge> hedge_from_fuzzylite(const std::vector<std::string>& words) {
  if (words.empty()) return Hedge::None;
  if (words.size() == 1 && words[0] == "somewhat") return Hedge::Somewhat;
  if (words.size() == 1 && words[0] == "very") return Hedge::Very;
  if (words.size() == 2 && words[0] == "very" && words[1] == "very") return Hedge::VeryVery;
  return std::nullopt;
}

std::vector<std::string> fuzzylite_hedge_words(Hedge hedge) {
  switch (hedge) {
    case Hedge::None: return {};
    case Hedge::Somewhat: return {"somewhat"};
    case Hedge::Very: return {"very"};
    case Hedge::VeryVery: return {"very", "very"};
    case Hedge::Extremely: return {};
  }
  return {};
}

namespace {

struct Word {
  std::string text;
  int offset = 0;  // from the rule text's start
};

std::vector<Word> words_of(const std::string& text) {
  std::vector<Word> words;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && is_fuzzylite_blank(text[i])) ++i;
    if (i >= text.size()) break;
    const std::size_t start = i;
    while (i < text.size() && !is_fuzzylite_blank(text[i])) ++i;
    words.push_back(Word{text.substr(start, i - start), static_cast<int>(start)});
  }
  return words;
}

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return text;
}

}  // namespace

std::optional<Rule> parse_fuzzylite_rule(const std::string& text, const SourceRange& at, const FuzzySystem& system,
                                         const SystemNames& names, DiagnosticList& diagnostics) {
  const std::vector<Word> words = words_of(text);
  const auto range_of = [&](const Word& w) {
    return SourceRange{at.file, at.line, at.column + w.offset, at.line,
                       at.column + w.offset + static_cast<int>(w.text.size())};
  };
  const auto fail = [&](const SourceRange& where, const std::string& message) {
    diagnostics.error(where, message);
    return std::nullopt;
  };
  Rule rule;
  rule.range = SourceRange{at.file, at.line, at.column, at.line, at.column + static_cast<int>(text.size())};
  for (const Word& w : words)
    if (w.text.find('(') != std::string::npos || w.text.find(')') != std::string::npos)
      return fail(range_of(w), "parentheses in a rule: fmpc rules join their conditions with one connective; split "
                               "the rule into several");
  if (words.empty() || lower(words[0].text) != "if") return fail(rule.range, "a rule starts with 'if'");
  std::size_t k = 1;
  bool in_consequent = false;
  std::optional<Connective> connective;
  while (k < words.size()) {
    // VARIABLE is [not] [hedge...] TERM
    const Word& variable_word = words[k];
    const std::vector<Variable>& variables = in_consequent ? system.outputs : system.inputs;
    const int variable = names.variable(in_consequent, variable_word.text);
    if (variable < 0) {
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(variable_word.text, names.variable_names(in_consequent)))
        notes.push_back("did you mean '" + *suggestion + "'?");
      diagnostics.error(range_of(variable_word),
                        "'" + variable_word.text + "' is not an " + (in_consequent ? "output" : "input") + " variable",
                        notes);
      return std::nullopt;
    }
    if (k + 1 >= words.size() || words[k + 1].text != "is")
      return fail(range_of(variable_word), "expected 'is' after '" + variable_word.text + "'");
    k += 2;
    Clause clause;
    clause.variable = variable;
    std::vector<std::string> hedges;
    std::size_t term_at = k;
    // Everything up to the last word before a connective, 'then', 'with' or the end is not/hedges, then the term.
    std::size_t end = k;
    while (end < words.size() && words[end].text != "and" && words[end].text != "or" && words[end].text != "then" &&
           words[end].text != "with")
      ++end;
    if (end == k) return fail(range_of(words[k - 1]), "expected a term after 'is'");
    term_at = end - 1;
    for (std::size_t h = k; h < term_at; ++h) {
      if (words[h].text == "not" && h == k) {
        clause.negated = true;
        continue;
      }
      hedges.push_back(words[h].text);
    }
    if (words[term_at].text == "any")
      return fail(range_of(words[term_at]), "'any' (a condition always true) has no fmpc form: leave the clause out");
    const std::optional<Hedge> hedge = hedge_from_fuzzylite(hedges);
    if (!hedge) {
      const Word& first = words[k + (clause.negated ? 1 : 0)];
      std::string message = "hedge '";
      for (std::size_t h = 0; h < hedges.size(); ++h) message += (h ? " " : "") + hedges[h];
      message += "' has no fmpc counterpart: fmpc's hedges are somewhat (x^0.5), very (x^2), extremely (x^3) and very "
                 "very (x^4); fuzzylite's 'extremely' is an S-curve and 'seldom' another";
      return fail(range_of(first), message);
    }
    clause.hedge = *hedge;
    const Variable& var = variables[static_cast<std::size_t>(variable)];
    clause.term = names.term(in_consequent, variable, words[term_at].text);
    if (clause.term < 0) {
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(words[term_at].text, names.term_names(in_consequent, variable)))
        notes.push_back("did you mean '" + *suggestion + "'?");
      diagnostics.error(range_of(words[term_at]),
                        "'" + words[term_at].text + "' is not a term of '" + var.name + "'", notes);
      return std::nullopt;
    }
    clause.range = range_of(variable_word);
    clause.range.end_column = range_of(words[term_at]).end_column;
    (in_consequent ? rule.consequent : rule.antecedent).push_back(clause);
    k = end;
    if (k >= words.size()) break;
    const std::string& joiner = words[k].text;
    if (joiner == "then") {
      if (in_consequent) return fail(range_of(words[k]), "a second 'then'");
      in_consequent = true;
      ++k;
      continue;
    }
    if (joiner == "with") {
      if (!in_consequent || k + 2 != words.size())
        return fail(range_of(words[k]), "'with WEIGHT' ends a rule, after its conclusion");
      char* stop = nullptr;
      const std::string& number = words[k + 1].text;
      rule.weight = std::strtod(number.c_str(), &stop);
      if (number.empty() || *stop != '\0') return fail(range_of(words[k + 1]), "'" + number + "' is not a weight");
      k = words.size();
      break;
    }
    if (in_consequent) {
      if (joiner != "and") return fail(range_of(words[k]), "conclusions are joined with 'and'");
    } else {
      const Connective c = joiner == "and" ? Connective::And : Connective::Or;
      if (connective && *connective != c)
        return fail(range_of(words[k]), "the rule mixes 'and' and 'or'; fmpc rules take one connective: split it");
      connective = c;
    }
    ++k;
  }
  if (rule.consequent.empty()) return fail(rule.range, "a rule needs 'then' and a conclusion");
  rule.connective = connective.value_or(Connective::And);
  return rule;
}

std::string fuzzylite_rule_text(const FuzzySystem& system, const Rule& rule, const SourceRange& where,
                                DiagnosticList& diagnostics) {
  const auto clause_text = [&](const Clause& clause, const std::vector<Variable>& variables) -> std::optional<std::string> {
    const Variable& v = variables[static_cast<std::size_t>(clause.variable)];
    std::string text = v.name + " is ";
    if (clause.negated) text += "not ";
    if (clause.hedge != Hedge::None) {
      const std::vector<std::string> words = fuzzylite_hedge_words(clause.hedge);
      if (words.empty()) {
        diagnostics.error(where, system.rule_display_name(static_cast<std::size_t>(&rule - system.rules.data())) +
                                     ": hedge '" + to_string(clause.hedge) +
                                     "' (x^3) means an S-curve in fuzzylite; write the term's shape instead");
        return std::nullopt;
      }
      for (const std::string& w : words) text += w + " ";
    }
    return text + v.terms[static_cast<std::size_t>(clause.term)].name;
  };
  std::string text = "if ";
  for (std::size_t c = 0; c < rule.antecedent.size(); ++c) {
    const auto part = clause_text(rule.antecedent[c], system.inputs);
    if (!part) return {};
    text += (c ? (rule.connective == Connective::And ? " and " : " or ") : "") + *part;
  }
  text += " then ";
  for (std::size_t c = 0; c < rule.consequent.size(); ++c) {
    const auto part = clause_text(rule.consequent[c], system.outputs);
    if (!part) return {};
    text += (c ? " and " : "") + *part;
  }
  if (rule.weight != 1.0) text += " with " + format_number(rule.weight);
  return text;
}

bool is_fuzzylite_blank(char c) { return c != '\0' && std::strchr(kFuzzyliteBlanks, c) != nullptr; }

std::string fuzzylite_trimmed(const std::string& text) {
  const std::size_t first = text.find_first_not_of(kFuzzyliteBlanks);
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(kFuzzyliteBlanks) - first + 1);
}

std::vector<std::string> fuzzylite_words(const std::string& text) {
  std::vector<std::string> words;
  for (const Word& word : words_of(text)) words.push_back(word.text);
  return words;
}

std::optional<double> fuzzylite_number(const std::string& text) {
  if (text == "nan" || text == "NaN") return std::nan("");
  if (text == "inf") return HUGE_VAL;
  if (text == "-inf") return -HUGE_VAL;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') return std::nullopt;
  return value;
}

SystemType fuzzylite_system_type(const FuzzySystem& system, const SourceRange& where, DiagnosticList& diagnostics) {
  bool sugeno = false, mamdani = false;
  for (const Variable& output : system.outputs)
    for (const Term& term : output.terms)
      (term.mf.kind == MfKind::Constant || term.mf.kind == MfKind::Linear ? sugeno : mamdani) = true;
  if (sugeno && mamdani)
    diagnostics.error(where, "the outputs mix Constant/Linear terms (Takagi-Sugeno) with membership functions "
                             "(Mamdani); fmpc systems are one or the other");
  return sugeno ? SystemType::Sugeno : SystemType::Mamdani;
}

void set_no_fire_from_defaults(FuzzySystem& system, const std::vector<double>& defaults, const SourceRange& where,
                               DiagnosticList& diagnostics) {
  system.no_fire = NoFirePolicy::Error;
  if (defaults.empty()) return;
  bool all_nan = true, all_midrange = defaults.size() == system.outputs.size(), all_equal = true;
  for (std::size_t o = 0; o < defaults.size(); ++o) {
    const double v = defaults[o];
    all_nan = all_nan && std::isnan(v);
    if (all_midrange) {
      const Variable& output = system.outputs[o];
      all_midrange = std::fabs(v - (output.min + output.max) / 2) <= 1e-12 * std::max(1.0, output.max - output.min);
    }
    all_equal = all_equal && (v == defaults[0] || (std::isnan(v) && std::isnan(defaults[0])));
  }
  if (all_nan) return;
  if (all_midrange) {
    system.no_fire = NoFirePolicy::Midrange;
  } else if (all_equal) {
    system.no_fire = NoFirePolicy::Value;
    system.no_fire_value = defaults[0];
  } else {
    diagnostics.error(where, "the outputs' defaults differ and are not each output's mid-range; fmpc systems have "
                             "one no-fire value (or mid-range, or an error) for all outputs");
  }
}

namespace {

std::string position_of(const SourceRange& at) { return std::to_string(at.line) + ":" + std::to_string(at.column); }

}  // namespace

bool FuzzyliteKeys::once_in_section(const std::string& key, const SourceRange& at, const std::string& section,
                                    DiagnosticList& diagnostics) {
  const auto [first, inserted] = section_.emplace(key, at);
  if (inserted) return true;
  diagnostics.error(at, "'" + key + "' is given twice in " + section + "; keep one",
                    {"first given here: " + position_of(first->second)});
  return false;
}

bool FuzzyliteKeys::one_value(const std::string& setting, const std::string& value, const SourceRange& at,
                              DiagnosticList& diagnostics) {
  const auto [first, inserted] = file_.emplace(setting, std::make_pair(value, at));
  if (inserted || first->second.first == value) return true;
  diagnostics.error(at, "'" + setting + "' is '" + value + "' here and '" + first->second.first +
                            "' before; an fmpc system has one " + setting + " for all its rules and outputs: make "
                            "them equal, or split the file",
                    {"first given here: " + position_of(first->second.second)});
  return false;
}

bool looks_like_fll(const std::string& line) {
  for (const char* key : {"Engine:", "InputVariable:", "OutputVariable:", "RuleBlock:"})
    if (line.compare(0, std::string(key).size(), key) == 0) return true;
  return false;
}

bool looks_like_fcl(const std::string& line) { return line.compare(0, 14, "FUNCTION_BLOCK") == 0; }

}  // namespace fmpc
