#include "compiler/ir/units.h"

#include <cstdlib>
#include <utility>
#include <vector>

namespace fmpc {

std::optional<UnitMeaning> unit_meaning(const std::string& unit) {
  if (unit == "dimensionless") return UnitMeaning{"dimensionless", 0};
  if (unit == "%") return UnitMeaning{"dimensionless", -2};
  static const std::vector<std::pair<std::string, const char*>> bases = {
      {"Pa", "pressure"}, {"m", "length"}, {"s", "time"}, {"N", "force"}, {"g", "mass"}};
  static const std::vector<std::pair<std::string, int>> prefixes = {
      {"", 0},   {"da", 1}, {"h", 2},  {"k", 3},  {"M", 6},       {"G", 9},       {"T", 12},  {"d", -1},
      {"c", -2}, {"m", -3}, {"u", -6}, {"\xC2\xB5", -6} /* micro sign */, {"\xCE\xBC", -6} /* Greek mu */,
      {"n", -9}, {"p", -12}, {"f", -15}};
  for (const auto& [base, dimension] : bases) {
    if (unit.size() < base.size() || unit.compare(unit.size() - base.size(), base.size(), base) != 0) continue;
    const std::string prefix = unit.substr(0, unit.size() - base.size());
    for (const auto& [spelling, exponent] : prefixes)
      if (prefix == spelling) return UnitMeaning{dimension, exponent};
  }
  return std::nullopt;
}

double scale_by_power_of_ten(double value, int exponent) {
  double power = 1.0;
  for (int i = 0; i < std::abs(exponent); ++i) power *= 10.0;  // exact up to 1e22
  return exponent >= 0 ? value * power : value / power;
}

std::optional<double> convert_unit(double value, const std::string& from, const std::string& to) {
  if (from == to) return value;
  const std::optional<UnitMeaning> a = unit_meaning(from), b = unit_meaning(to);
  if (!a || !b || std::string(a->dimension) != b->dimension) return std::nullopt;
  return scale_by_power_of_ten(value, a->exponent - b->exponent);
}

}  // namespace fmpc
