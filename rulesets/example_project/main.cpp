// Liver stiffness for a few (HBV, CLD, NAFLD) readings with HCV = 10 kPa and ALD = 22 kPa fixed, from the
// generated evaluator, and for (HBV, CLD) with NAFLD = 6 kPa also fixed, from the generated table.
#include <cstdio>

#include "liver_evaluator.h"
#include "liver_table.h"

int main() {
  static_assert(liver_evaluator::kInputCount == 3, "HBV, CLD and NAFLD vary");
  const double readings[][3] = {{5.0, 8.0, 6.0}, {7.5, 11.0, 6.0}, {12.0, 30.0, 6.0}};
  for (const auto& x : readings) {
    double stiffness = 0.0;
    const unsigned flags = liver_evaluator::evaluate(x, &stiffness);
    const double query[2] = {x[0], x[1]};
    liver_table::Value tabulated = 0;
    fmpc::interpolate_table(liver_table::view(), query, &tabulated);
    std::printf("HBV %5.2f CLD %5.2f NAFLD %5.2f kPa: stiffness %.6f kPa (flags %u), table %.6f kPa\n", x[0], x[1],
                x[2], stiffness, flags, static_cast<double>(tabulated));
  }
  return 0;
}
