#pragma once
// N-D stiffness lookup tables (DESIGN section 6) and their file format, .fzt. The table is plain data; the
// interpolation is kernels/table_math.h, shared with the CUDA kernels and generated code.
//
// .fzt layout, version 2, all integers and floats little-endian:
//   magic "FMPCFZT" 0x1A | u32 version | u32 byte-order mark 0x01020304 | u64 source hash (FNV-1a of the rule file)
//   u32 value type (1 float32, 2 float64) | u32 interpolation (1 multilinear) | u32 axes | u32 outputs
//   f64 maximum error | u32 error kind (1 bound, 2 estimate) | str system | str source path
//   per axis: str input name | str input unit | u32 input index | u32 breakpoint count | f64 breakpoints[count]
//   per output: str output name | str output unit
//   u32 fixed inputs | per fixed input: str name | str unit | f64 value
//   f64 location of the maximum error[axes]
//   values[product of counts x outputs] in the value type, layout of kernels/table_math.h
//   u64 checksum: FNV-1a of every byte before it
// (str = u32 length + that many bytes, at most kMaxFztString.) A unit is the rule file's text ("kPa"), empty where
// the rule file gives none (MATLAB files). Version 1 (no units, no error kind: its error was a held-out sample) is
// refused with a message saying to rebuild the table.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"
#include "kernels/table_math.h"

namespace fmpc {

inline constexpr std::uint32_t kFztVersion = 2;
inline constexpr std::uint32_t kMaxFztString = 4096;
inline constexpr std::uint32_t kMaxFztOutputs = 64;
inline constexpr std::uint64_t kMaxFztValues = 1ULL << 31;  // 16 GiB of doubles: beyond any scene's need

enum class TableValueType : std::uint32_t { Float32 = 1, Float64 = 2 };

// What the stated maximum error is (docs/compiler.md, "Error statement"):
//   Bound     |table - interpreter| <= max_error everywhere in the axes' box, derived cell by cell;
//   Estimate  the largest |table - interpreter| found by evaluating every cell and searching locally around the
//             worst points: a measurement, not a guarantee.
enum class TableErrorKind : std::uint32_t { Bound = 1, Estimate = 2 };
const char* to_string(TableErrorKind kind);  // "bound", "estimate"

struct TableAxis {
  std::string input_name;
  std::string input_unit;           // the rule file's unit of the input; empty where it gives none
  std::uint32_t input_index = 0;    // in the source system
  std::vector<double> breakpoints;  // strictly increasing, at least 2
};

// An input folded in at compile time (--fix NAME=VALUE).
struct TableFixedInput {
  std::string name;
  std::string unit;
  double value = 0.0;
  bool operator==(const TableFixedInput& other) const {
    return name == other.name && unit == other.unit && value == other.value;
  }
};

struct LookupTable {
  std::string system_name;
  std::string source_path;
  std::uint64_t source_hash = 0;
  TableValueType value_type = TableValueType::Float64;
  std::vector<TableAxis> axes;
  std::vector<std::string> output_names;
  std::vector<std::string> output_units;   // one per output, the rule file's; empty where it gives none
  std::vector<TableFixedInput> fixed_inputs;
  std::vector<double> values;  // layout of kernels/table_math.h; rounded to the value type when serialized
  double max_error = 0.0;                   // against the interpreter, output units, over every output
  TableErrorKind error_kind = TableErrorKind::Estimate;
  std::vector<double> max_error_location;   // one coordinate per axis: where the bound or the estimate is largest

  std::uint64_t grid_points() const;
};

// Views the table for kernels/table_math.h; `breakpoint_pointers` and `counts` must outlive the view.
TableView<double> view_of(const LookupTable& table, std::vector<const double*>& breakpoint_pointers,
                          std::vector<int>& counts);

// Checks the invariants a table must hold (also what the loader checks after parsing): axes 1..kMaxTableAxes,
// counts >= 2, finite strictly increasing breakpoints, values.size() == grid_points() * outputs, finite values,
// one unit per output, a known error kind. Errors name the field.
bool validate_table(const LookupTable& table, const std::string& origin, DiagnosticList& diagnostics);

// The table as a system's interface, for reading and checking points: its axes are the inputs (range: the axis),
// its outputs the outputs (names and units; no terms, no rules).
FuzzySystem table_interface(const LookupTable& table);

std::string serialize_fzt(const LookupTable& table);

// Whether `bytes` start with the .fzt signature (a table, not a rule file: the CLI tells them apart by this).
bool has_fzt_signature(const std::string& bytes);
// The signature itself: the first 8 bytes of every .fzt file.
std::string fzt_signature();

// Parses and validates `bytes` (the contents of `path`). Every read is bounds-checked; a truncated, corrupted,
// wrong-version, wrong-endian or hostile file gives nullopt and an error naming the field and what to do.
std::optional<LookupTable> parse_fzt(const std::string& path, const std::string& bytes, DiagnosticList& diagnostics);

}  // namespace fmpc
