// libFuzzer target: .fzt lookup tables through their public entry point, parse_fzt
// (compiler/backend/table/lookup_table.h); a table that loads is also interpolated at its corners and centre.
#include <cstdint>
#include <string>
#include <vector>

#include "compiler/backend/table/lookup_table.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  fmpc::DiagnosticList diagnostics;
  const auto table = fmpc::parse_fzt("fuzz.fzt", bytes, diagnostics);
  if (!table) return 0;
  std::vector<const double*> breakpoints;
  std::vector<int> counts;
  const fmpc::TableView<double> view = fmpc::view_of(*table, breakpoints, counts);
  std::vector<double> point(table->axes.size()), out(table->output_names.size() + 1);
  for (int where = 0; where < 3; ++where) {
    for (std::size_t a = 0; a < table->axes.size(); ++a) {
      const std::vector<double>& b = table->axes[a].breakpoints;
      point[a] = where == 0 ? b.front() : where == 1 ? b.back() : 0.5 * (b.front() + b.back());
    }
    fmpc::interpolate_table(view, point.data(), out.data());
  }
  return 0;
}
