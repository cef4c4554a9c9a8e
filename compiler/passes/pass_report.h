#pragma once
// What one IR pass did, for `fmpc compile --report` and for the tests that check each pass against its bound.
#include <string>
#include <vector>

namespace fmpc {

struct PassReport {
  std::string pass;                  // "specialize", "prune_rules", ...
  std::string summary;               // one line: "removed 12 rules"
  std::vector<std::string> details;  // one line per removed or changed item: "r5: cannot fire on the inputs' ranges"
  // Bound on |output of the transformed system - output of the system before the pass|, in output units, over the
  // varying inputs' declared ranges, for every output. 0 = exact; +inf = no bound is known.
  double error_bound = 0.0;
  std::string error_note;  // how the bound follows ("exact", "exact up to floating-point reassociation", ...)
};

}  // namespace fmpc
