#pragma once
// Table-driven stiffness k(strain) (DESIGN section 7), shared by the CPU loop, the CUDA kernel and both backends'
// energy sums: the spring's strain X = (l - l0) / l0 is looked up in the modulus table (linear between breakpoints,
// clamped at the ends, kernels/table_math.h) and k = modulus(X) * stiffness_per_modulus. All in double. Tetrahedra
// look up their own strain measure (kernels/tetrahedron_math.h).
#include "kernels/fmpc_hd.h"
#include "kernels/spring_math.h"
#include "kernels/table_math.h"

namespace fmpc::kernels {

struct StrainTableView {
  const double* strain;   // breakpoints, strictly increasing
  const double* modulus;  // Pa, one per breakpoint
  int count;              // >= 2
};

// The modulus (Pa) at a strain: linear between breakpoints, clamped at the ends. Springs look it up at their strain
// (l - l0) / l0, tetrahedra at their principal strain of largest magnitude (kernels/tetrahedron_math.h).
FMPC_HD double strain_table_modulus(const StrainTableView& table, double strain) {
  int counts[1] = {table.count};
  const double* breakpoints[1] = {table.strain};
  TableView<double> view;
  view.axes = 1;
  view.outputs = 1;
  view.counts = counts;
  view.breakpoints = breakpoints;
  view.values = table.modulus;
  double modulus = 0.0;
  interpolate_table(view, &strain, &modulus);
  return modulus;
}

// d = x_b - x_a of the spring, l0 its rest length.
FMPC_HD double strain_table_stiffness(const StrainTableView& table, double dx, double dy, double dz, double rest,
                                      double stiffness_per_modulus) {
  const double strain = (square_root(dx * dx + dy * dy + dz * dz) - rest) / rest;
  return strain_table_modulus(table, strain) * stiffness_per_modulus;
}

}  // namespace fmpc::kernels
