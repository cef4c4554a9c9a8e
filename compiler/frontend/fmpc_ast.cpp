#include "compiler/frontend/fmpc_ast.h"

#include <array>

namespace fmpc::ast {

namespace {

// Named parameters in the order a clinician reads them; matlab_index maps each to MATLAB's params vector
// (kernels/fuzzy_kinds.h), e.g. gauss(mean, sd) is gaussmf [sd mean].
const std::vector<FamilySignature>& families() {
  static const std::vector<FamilySignature> table = {
      {"triangle", MfKind::Triangle, {"start", "peak", "end"}, {0, 1, 2}, {true, true, true}},
      {"trapezoid", MfKind::Trapezoid, {"start", "top_start", "top_end", "end"}, {0, 1, 2, 3},
       {true, true, true, true}},
      {"gauss", MfKind::Gaussian, {"mean", "sd"}, {1, 0}, {true, true}},
      {"gauss2", MfKind::Gaussian2, {"mean1", "sd1", "mean2", "sd2"}, {1, 0, 3, 2}, {true, true, true, true}},
      {"bell", MfKind::GeneralizedBell, {"width", "slope", "center"}, {0, 1, 2}, {true, false, true}},
      {"sigmoid", MfKind::Sigmoid, {"slope", "center"}, {0, 1}, {false, true}},
      {"dsigmoid", MfKind::DifferenceSigmoid, {"slope1", "center1", "slope2", "center2"}, {0, 1, 2, 3},
       {false, true, false, true}},
      {"psigmoid", MfKind::ProductSigmoid, {"slope1", "center1", "slope2", "center2"}, {0, 1, 2, 3},
       {false, true, false, true}},
      {"zshape", MfKind::ZShape, {"start", "end"}, {0, 1}, {true, true}},
      {"sshape", MfKind::SShape, {"start", "end"}, {0, 1}, {true, true}},
      {"pishape", MfKind::PiShape, {"start", "top_start", "top_end", "end"}, {0, 1, 2, 3},
       {true, true, true, true}},
      {"linear_s", MfKind::LinearS, {"start", "end"}, {0, 1}, {true, true}},
      {"linear_z", MfKind::LinearZ, {"start", "end"}, {0, 1}, {true, true}},
      {"constant", MfKind::Constant, {"value"}, {0}, {true}},
      {"linear", MfKind::Linear, {}, {}, {}},
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

}  // namespace fmpc::ast
