// The contact of a rigid sphere with a thick block against Hertz (tests/support/hertz_contact.h), mesh by mesh: the
// cells at the contact from a/2 down to a/8 and the penalty's stiffness ratio, each with its force, Hertz's, the
// relative error, the mesh's size and the time it took (one CPU thread, implicit Euler steps of 1 s as Newton steps).
//   fmpc_hertz_bench [depth=D] [extent=E] [growth=G] [ratios=R,R,...] [element=KEYWORD] [solver=auto|direct|cg]
//                    [first_cell ...]
// (first cells in contact radii, default 0.5 0.35 0.25 0.18 0.125; the depth D in m; the block's side E contact radii,
// default HertzCase's; cells growing by G away from the contact; penalty stiffness ratios, default 2, 8, 32; the
// implicit step's linear solve, default auto).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "runtime/fem/element_law_registry.h"
#include "tests/support/hertz_contact.h"

int main(int argc, char** argv) {
  fmpc::test_support::HertzCase base;
  std::vector<double> cells, ratios = {2.0, 8.0, 32.0};
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    const auto value = [&](const char* key) {
      return argument.rfind(key, 0) == 0 ? argument.c_str() + std::strlen(key) : nullptr;
    };
    if (const char* e = value("extent=")) {
      base.extent = std::atof(e);
    } else if (const char* d = value("depth=")) {
      base.depth = std::atof(d);
    } else if (const char* k = value("element=")) {
      const auto kind = fmpc::sim::element_kind_by_keyword(k);
      if (!kind) return std::fprintf(stderr, "element=%s: no such element kind\n", k), 2;
      base.element = kind->kind;
    } else if (const char* m = value("solver=")) {
      // The scene's spellings (fmpc::sim::to_string).
      bool known = false;
      for (const auto method : {fmpc::sim::ImplicitMethod::Automatic, fmpc::sim::ImplicitMethod::Direct,
                                fmpc::sim::ImplicitMethod::ConjugateGradient})
        if (std::strcmp(fmpc::sim::to_string(method), m) == 0) {
          base.method = method;
          known = true;
        }
      if (!known) return std::fprintf(stderr, "solver=%s: use auto, direct or cg\n", m), 2;
    } else if (const char* g = value("growth=")) {
      base.growth = std::atof(g);
    } else if (const char* r = value("ratios=")) {
      ratios.clear();
      for (const char* p = r; *p != '\0'; p = std::strchr(p, ',') ? std::strchr(p, ',') + 1 : p + std::strlen(p))
        ratios.push_back(std::atof(p));
    } else {
      cells.push_back(std::atof(argument.c_str()));
    }
  }
  if (cells.empty()) cells = {0.5, 0.35, 0.25, 0.18, 0.125};
  std::printf("R %g mm, d %g mm (d/R %g), E 10 kPa, nu 0.3, block %g a, growth %g, element %s\n", 1e3 * base.radius,
              1e3 * base.depth, base.depth / base.radius, base.extent, base.growth,
              fmpc::sim::element_kind_rows()[static_cast<std::size_t>(base.element)].keyword);
  std::printf("%-10s %-6s %-6s %-9s %-9s %-12s %-12s %-9s %-6s %-8s\n", "cell/a", "ratio", "cells", "vertices",
              "contacts", "force_N", "hertz_N", "error", "steps", "seconds");
  for (const double cell : cells) {
    for (const double ratio : ratios) {
      fmpc::test_support::HertzCase c = base;
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
