#include "compiler/ir/fuzzy_system.h"

#include <array>
#include <utility>

namespace fmpc {

namespace {

template <typename Enum, std::size_t N>
std::optional<Enum> lookup(const std::array<std::pair<const char*, Enum>, N>& table, const std::string& name) {
  for (const auto& entry : table)
    if (name == entry.first) return entry.second;
  return std::nullopt;
}

template <typename Enum, std::size_t N>
const char* spelling(const std::array<std::pair<const char*, Enum>, N>& table, Enum value) {
  for (const auto& entry : table)
    if (entry.second == value) return entry.first;
  return "?";
}

constexpr std::array<std::pair<const char*, MfKind>, 15> kMfNames{{
    {"trimf", MfKind::Triangle},         {"trapmf", MfKind::Trapezoid},
    {"gaussmf", MfKind::Gaussian},       {"gauss2mf", MfKind::Gaussian2},
    {"gbellmf", MfKind::GeneralizedBell}, {"sigmf", MfKind::Sigmoid},
    {"dsigmf", MfKind::DifferenceSigmoid}, {"psigmf", MfKind::ProductSigmoid},
    {"zmf", MfKind::ZShape},             {"smf", MfKind::SShape},
    {"pimf", MfKind::PiShape},           {"linsmf", MfKind::LinearS},
    {"linzmf", MfKind::LinearZ},         {"constant", MfKind::Constant},
    {"linear", MfKind::Linear},
}};

constexpr std::array<std::pair<const char*, TNorm>, 3> kTNormNames{{
    {"min", TNorm::Minimum}, {"prod", TNorm::Product}, {"einstein_product", TNorm::EinsteinProduct}}};

constexpr std::array<std::pair<const char*, SNorm>, 4> kSNormNames{{
    {"max", SNorm::Maximum}, {"probor", SNorm::ProbabilisticSum}, {"sum", SNorm::Sum},
    {"einstein_sum", SNorm::EinsteinSum}}};

constexpr std::array<std::pair<const char*, Defuzzifier>, 7> kDefuzzifierNames{{
    {"centroid", Defuzzifier::Centroid}, {"bisector", Defuzzifier::Bisector},
    {"mom", Defuzzifier::MeanOfMaximum}, {"som", Defuzzifier::SmallestOfMaximum},
    {"lom", Defuzzifier::LargestOfMaximum}, {"wtaver", Defuzzifier::WeightedAverage},
    {"wtsum", Defuzzifier::WeightedSum}}};

constexpr std::array<std::pair<const char*, TypeReduction>, 4> kTypeReductionNames{{
    {"karnik_mendel", TypeReduction::KarnikMendel},
    {"enhanced_karnik_mendel", TypeReduction::EnhancedKarnikMendel},
    {"eiasc", TypeReduction::Eiasc},
    {"nie_tan", TypeReduction::NieTan}}};

}  // namespace

int Variable::find_term(const std::string& term_name) const {
  for (std::size_t i = 0; i < terms.size(); ++i)
    if (terms[i].name == term_name) return static_cast<int>(i);
  return -1;
}

static int find_variable(const std::vector<Variable>& variables, const std::string& name) {
  for (std::size_t i = 0; i < variables.size(); ++i)
    if (variables[i].name == name) return static_cast<int>(i);
  return -1;
}

int FuzzySystem::find_input(const std::string& variable_name) const { return find_variable(inputs, variable_name); }
int FuzzySystem::find_output(const std::string& variable_name) const { return find_variable(outputs, variable_name); }

std::string FuzzySystem::rule_display_name(std::size_t rule_index) const {
  if (rule_index < rules.size() && !rules[rule_index].label.empty()) return rules[rule_index].label;
  return "rule " + std::to_string(rule_index + 1);
}

const char* to_string(SystemType type) { return type == SystemType::Mamdani ? "mamdani" : "sugeno"; }
const char* to_string(Defuzzifier defuzzifier) { return spelling(kDefuzzifierNames, defuzzifier); }
const char* to_string(TNorm norm) { return spelling(kTNormNames, norm); }
const char* to_string(SNorm norm) { return spelling(kSNormNames, norm); }
const char* matlab_name(MfKind kind) { return spelling(kMfNames, kind); }

const char* to_string(Hedge hedge) {
  switch (hedge) {
    case Hedge::None: return "";
    case Hedge::Somewhat: return "somewhat";
    case Hedge::Very: return "very";
    case Hedge::Extremely: return "extremely";
    case Hedge::VeryVery: return "very very";
  }
  return "";
}

double hedge_exponent(Hedge hedge) {
  switch (hedge) {
    case Hedge::None: return 1.0;
    case Hedge::Somewhat: return 0.5;
    case Hedge::Very: return 2.0;
    case Hedge::Extremely: return 3.0;
    case Hedge::VeryVery: return 4.0;
  }
  return 1.0;
}

std::optional<MfKind> mf_kind_from_matlab_name(const std::string& name) { return lookup(kMfNames, name); }
std::optional<TNorm> tnorm_from_string(const std::string& name) { return lookup(kTNormNames, name); }
std::optional<SNorm> snorm_from_string(const std::string& name) { return lookup(kSNormNames, name); }
std::optional<Defuzzifier> defuzzifier_from_string(const std::string& name) {
  return lookup(kDefuzzifierNames, name);
}

const char* to_string(TypeReduction method) { return spelling(kTypeReductionNames, method); }
std::optional<TypeReduction> type_reduction_from_string(const std::string& name) {
  return lookup(kTypeReductionNames, name);
}

int mf_param_count(MfKind kind) {
  switch (kind) {
    case MfKind::Constant: return 1;
    case MfKind::Gaussian:
    case MfKind::Sigmoid:
    case MfKind::ZShape:
    case MfKind::SShape:
    case MfKind::LinearS:
    case MfKind::LinearZ: return 2;
    case MfKind::Triangle:
    case MfKind::GeneralizedBell: return 3;
    case MfKind::Trapezoid:
    case MfKind::Gaussian2:
    case MfKind::DifferenceSigmoid:
    case MfKind::ProductSigmoid:
    case MfKind::PiShape: return 4;
    case MfKind::Linear: return -1;
  }
  return -1;
}

}  // namespace fmpc
