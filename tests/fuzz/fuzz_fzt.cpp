// libFuzzer target: .fzt lookup tables through their public entry point, parse_fzt
// (compiler/backend/table/lookup_table.h). The file's last 8 bytes are a checksum of the rest, which almost every
// mutation breaks; so each input is parsed twice, as given and with the checksum recomputed, to reach the fields
// behind it. A table that loads is also interpolated at its corners and centre.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/ir/content_hash.h"

namespace {

void parse_and_interpolate(const std::string& bytes) {
  fmpc::DiagnosticList diagnostics;
  const auto table = fmpc::parse_fzt("fuzz.fzt", bytes, diagnostics);
  if (!table) return;
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
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  parse_and_interpolate(bytes);
  if (bytes.size() >= 8) {
    const std::uint64_t checksum = fmpc::fnv1a64(bytes.data(), bytes.size() - 8);
    for (std::size_t i = 0; i < 8; ++i)  // little-endian, as serialize_fzt writes it
      bytes[bytes.size() - 8 + i] = static_cast<char>((checksum >> (8 * i)) & 0xFF);
    parse_and_interpolate(bytes);
  }
  return 0;
}
