// The contact of a rigid sphere with a thick block against Hertz (tests/support/hertz_contact.h), mesh by mesh: the
// cells at the contact from a/2 down to a/8 and the penalty's stiffness ratio, each with its force, Hertz's, the
// relative error, the mesh's size and the time it took (one CPU thread, implicit Euler steps of 1 s as Newton steps).
//   fmpc_hertz_bench [first_cell ...]   (in contact radii; default 0.5 0.35 0.25 0.18 0.125)
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "tests/support/hertz_contact.h"

int main(int argc, char** argv) {
  std::vector<double> cells;
  for (int i = 1; i < argc; ++i) cells.push_back(std::atof(argv[i]));
  if (cells.empty()) cells = {0.5, 0.35, 0.25, 0.18, 0.125};
  std::printf("R 10 mm, d 0.5 mm (d/R 0.05), E 10 kPa, nu 0.3, block 40 a, growth 1.3\n");
  std::printf("%-10s %-6s %-6s %-9s %-9s %-12s %-12s %-9s %-6s %-8s\n", "cell/a", "ratio", "cells", "vertices",
              "contacts", "force_N", "hertz_N", "error", "steps", "seconds");
  for (const double cell : cells) {
    for (const double ratio : {2.0, 8.0, 32.0}) {
      fmpc::test_support::HertzCase c;
      c.first_cell = cell;
      c.contact_stiffness_ratio = ratio;
      const fmpc::test_support::HertzResult r = fmpc::test_support::run_hertz(c);
      if (!r.ok) {
        std::printf("%-10g %-6g failed: %s\n", cell, ratio, r.error.c_str());
        continue;
      }
      std::printf("%-10g %-6g %-6d %-9zu %-9zu %-12.6g %-12.6g %-+9.4f %-6d %-8.2f\n", cell, ratio, r.cells, r.vertices,
                  r.contacts, r.force, r.hertz, r.relative_error, r.steps, r.seconds);
      std::fflush(stdout);
    }
  }
  return 0;
}
