#include "compiler/frontend/fmpc_ast.h"

#include <array>
#include <optional>

namespace fmpc::ast {

namespace {

// Named parameters in the order a clinician reads them; matlab_index maps each to MATLAB's params vector
// (kernels/fuzzy_kinds.h), e.g. gauss(mean, sd) is gaussmf [sd mean]. The last column is MATLAB's own names for
// its params vector, from the Fuzzy Logic Toolbox reference pages (trimf [a b c], gaussmf [sigma c],
// gauss2mf [sig1 c1 sig2 c2], dsigmf [a1 c1 a2 c2], ...): messages name them when a MATLAB user writes them.
const std::vector<FamilySignature>& families() {
  static const std::vector<FamilySignature> table = {
      {"triangle", MfKind::Triangle, {"start", "peak", "end"}, {0, 1, 2}, {true, true, true}, {"a", "b", "c"}},
      {"trapezoid", MfKind::Trapezoid, {"start", "top_start", "top_end", "end"}, {0, 1, 2, 3},
       {true, true, true, true}, {"a", "b", "c", "d"}},
      {"gauss", MfKind::Gaussian, {"mean", "sd"}, {1, 0}, {true, true}, {"sigma", "c"}},
      {"gauss2", MfKind::Gaussian2, {"mean1", "sd1", "mean2", "sd2"}, {1, 0, 3, 2}, {true, true, true, true},
       {"sig1", "c1", "sig2", "c2"}},
      {"bell", MfKind::GeneralizedBell, {"width", "slope", "center"}, {0, 1, 2}, {true, false, true},
       {"a", "b", "c"}},
      {"sigmoid", MfKind::Sigmoid, {"slope", "center"}, {0, 1}, {false, true}, {"a", "c"}},
      {"dsigmoid", MfKind::DifferenceSigmoid, {"slope1", "center1", "slope2", "center2"}, {0, 1, 2, 3},
       {false, true, false, true}, {"a1", "c1", "a2", "c2"}},
      {"psigmoid", MfKind::ProductSigmoid, {"slope1", "center1", "slope2", "center2"}, {0, 1, 2, 3},
       {false, true, false, true}, {"a1", "c1", "a2", "c2"}},
      {"zshape", MfKind::ZShape, {"start", "end"}, {0, 1}, {true, true}, {"a", "b"}},
      {"sshape", MfKind::SShape, {"start", "end"}, {0, 1}, {true, true}, {"a", "b"}},
      {"pishape", MfKind::PiShape, {"start", "top_start", "top_end", "end"}, {0, 1, 2, 3},
       {true, true, true, true}, {"a", "b", "c", "d"}},
      {"linear_s", MfKind::LinearS, {"start", "end"}, {0, 1}, {true, true}, {"a", "b"}},
      {"linear_z", MfKind::LinearZ, {"start", "end"}, {0, 1}, {true, true}, {"a", "b"}},
      {"constant", MfKind::Constant, {"value"}, {0}, {true}, {"c"}},
      {"linear", MfKind::Linear, {}, {}, {}, {}},
  };
  return table;
}

constexpr std::array<const char*, 14> kReservedWords{{"system", "input", "output", "rule", "if", "then", "is",
                                                      "not", "and", "or", "weight", "somewhat", "very",
                                                      "extremely"}};

}  // namespace

bool is_reserved_word(const std::string& word) {
  for (const char* reserved : kReservedWords)
    if (word == reserved) return true;
  return false;
}

const FamilySignature* find_family(const std::string& name) {
  for (const FamilySignature& family : families())
    if (name == family.name) return &family;
  return nullptr;
}

const FamilySignature* find_matlab_family(const std::string& name) {
  const std::optional<MfKind> kind = mf_kind_from_matlab_name(name);
  if (!kind || name == family_of(*kind).name) return nullptr;
  return &family_of(*kind);
}

const FamilySignature* find_family_or_alias(const std::string& name, bool* alias) {
  const FamilySignature* family = find_family(name);
  const FamilySignature* matlab = family ? nullptr : find_matlab_family(name);
  if (alias) *alias = matlab != nullptr;
  return family ? family : matlab;
}

const FamilySignature& family_of(MfKind kind) {
  for (const FamilySignature& family : families())
    if (family.kind == kind) return family;
  return families().front();
}

std::vector<std::string> family_names() {
  std::vector<std::string> names;
  for (const FamilySignature& family : families()) names.emplace_back(family.name);
  return names;
}

std::vector<std::string> matlab_family_names() {
  std::vector<std::string> names;
  for (const FamilySignature& family : families())
    if (std::string(matlab_name(family.kind)) != family.name) names.emplace_back(matlab_name(family.kind));
  return names;
}

}  // namespace fmpc::ast
