#pragma once
// The units fmpc converts (docs/language.md, "Units"): SI prefixes of Pa, m, s, N and g, plus % and dimensionless.
// Every conversion is a power of ten, applied as one correctly rounded multiplication or division.
#include <optional>
#include <string>

namespace fmpc {

struct UnitMeaning {
  const char* dimension;  // "pressure", "length", "time", "force", "mass", "dimensionless"
  int exponent;           // value in the base unit = value * 10^exponent
};

// nullopt for a unit fmpc does not know.
std::optional<UnitMeaning> unit_meaning(const std::string& unit);

// value * 10^exponent, as one multiplication or division by an exact power of ten (|exponent| <= 22).
double scale_by_power_of_ten(double value, int exponent);

// `value` given in `from`, in `to`: the same value when the spellings are equal, nullopt when either unit is unknown
// or they measure different things.
std::optional<double> convert_unit(double value, const std::string& from, const std::string& to);

}  // namespace fmpc
