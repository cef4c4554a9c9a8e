// .fzt lookup tables: interpolation (kernels/table_math.h), serialization, and a loader that rejects every
// damaged or hostile file with a message and never reads out of bounds (the ASan build runs these too).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/ir/content_hash.h"

using namespace fmpc;

namespace {

// f(x, y) = 2x - 3y + 1 and g = x*y on a refined 2-D grid: multilinear interpolation reproduces both exactly
// (g is bilinear), which makes every lookup checkable by hand.
LookupTable bilinear_table(TableValueType type = TableValueType::Float64) {
  LookupTable t;
  t.system_name = "demo";
  t.source_path = "demo.fis";
  t.source_hash = fnv1a64(std::string("rules"));
  t.value_type = type;
  t.axes = {TableAxis{"x", "kPa", 0, {0.0, 0.5, 2.0, 3.0}}, TableAxis{"y", "", 2, {-1.0, 1.0, 4.0}}};
  t.output_names = {"f", "g"};
  t.output_units = {"Pa", ""};
  t.fixed_inputs = {{"z", "mm", 7.5}};
  t.error_kind = TableErrorKind::Bound;
  for (double x : t.axes[0].breakpoints)
    for (double y : t.axes[1].breakpoints) {
      t.values.push_back(2 * x - 3 * y + 1);
      t.values.push_back(x * y);
    }
  t.max_error = 1e-3;
  t.max_error_location = {1.25, 0.5};
  return t;
}

std::vector<double> lookup(const LookupTable& t, std::vector<double> query) {
  std::vector<const double*> pointers;
  std::vector<int> counts;
  const TableView<double> view = view_of(t, pointers, counts);
  std::vector<double> out(t.output_names.size());
  interpolate_table(view, query.data(), out.data());
  return out;
}

// Rewrites the trailing checksum so that a deliberately hostile body reaches the field checks.
std::string with_valid_checksum(std::string bytes) {
  const std::uint64_t sum = fnv1a64(bytes.data(), bytes.size() - 8);
  for (int i = 0; i < 8; ++i) bytes[bytes.size() - 8 + static_cast<std::size_t>(i)] = static_cast<char>(sum >> (8 * i));
  return bytes;
}

void put_u32(std::string& bytes, std::size_t offset, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[offset + static_cast<std::size_t>(i)] = static_cast<char>(v >> (8 * i));
}

std::string first_error(const std::string& bytes) {
  DiagnosticList diagnostics;
  const auto table = parse_fzt("t.fzt", bytes, diagnostics);
  REQUIRE_FALSE(table);
  REQUIRE(diagnostics.has_errors());
  return diagnostics.items().front().message;
}

}  // namespace

TEST_CASE("multilinear lookup reproduces bilinear functions, at breakpoints, ends and outside", "[table]") {
  const LookupTable t = bilinear_table();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> ux(0.0, 3.0), uy(-1.0, 4.0);
  for (int i = 0; i < 1000; ++i) {
    const double x = ux(rng), y = uy(rng);
    const auto v = lookup(t, {x, y});
    REQUIRE(v[0] == Approx(2 * x - 3 * y + 1).margin(1e-12));
    REQUIRE(v[1] == Approx(x * y).margin(1e-12));
  }
  // Exactly at the upper end of both axes: the last grid value, not a read past it.
  auto corner = lookup(t, {3.0, 4.0});
  REQUIRE(corner[0] == 2 * 3.0 - 3 * 4.0 + 1);
  REQUIRE(corner[1] == 12.0);
  // At interior breakpoints and the lower end.
  REQUIRE(lookup(t, {0.5, 1.0})[1] == 0.5);
  REQUIRE(lookup(t, {0.0, -1.0})[0] == 4.0);
  // Outside: clamped to the nearest edge, never extrapolated.
  REQUIRE(lookup(t, {10.0, 4.0})[1] == 12.0);
  REQUIRE(lookup(t, {-5.0, -7.0})[0] == 4.0);
  REQUIRE(lookup(t, {std::numeric_limits<double>::infinity(), 0.0})[0] == Approx(2 * 3.0 + 1));
  REQUIRE(lookup(t, {-std::numeric_limits<double>::infinity(), 0.0})[0] == Approx(1.0));
  // NaN in, NaN out.
  const auto nan = lookup(t, {std::nan(""), 1.0});
  REQUIRE(std::isnan(nan[0]));
  REQUIRE(std::isnan(nan[1]));
}

TEST_CASE(".fzt round trip keeps every field; float32 tables round values to float", "[table]") {
  for (TableValueType type : {TableValueType::Float64, TableValueType::Float32}) {
    const LookupTable t = bilinear_table(type);
    DiagnosticList diagnostics;
    const auto back = parse_fzt("t.fzt", serialize_fzt(t), diagnostics);
    REQUIRE(back);
    REQUIRE(diagnostics.empty());
    REQUIRE(back->system_name == "demo");
    REQUIRE(back->source_path == "demo.fis");
    REQUIRE(back->source_hash == t.source_hash);
    REQUIRE(back->value_type == type);
    REQUIRE(back->axes.size() == 2);
    REQUIRE(back->axes[1].input_name == "y");
    REQUIRE(back->axes[1].input_index == 2);
    REQUIRE(back->axes[0].input_unit == "kPa");
    REQUIRE(back->axes[1].input_unit.empty());
    REQUIRE(back->axes[0].breakpoints == t.axes[0].breakpoints);
    REQUIRE(back->output_names == t.output_names);
    REQUIRE(back->output_units == t.output_units);
    REQUIRE(back->fixed_inputs == t.fixed_inputs);
    REQUIRE(back->max_error == t.max_error);
    REQUIRE(back->error_kind == TableErrorKind::Bound);
    REQUIRE(back->max_error_location == t.max_error_location);
    REQUIRE(back->values.size() == t.values.size());
    for (std::size_t i = 0; i < t.values.size(); ++i)
      REQUIRE(back->values[i] == (type == TableValueType::Float32
                                      ? static_cast<double>(static_cast<float>(t.values[i]))
                                      : t.values[i]));
  }
}

TEST_CASE(".fzt loader rejects every truncation and every single-byte corruption", "[table]") {
  const std::string good = serialize_fzt(bilinear_table());
  for (std::size_t size = 0; size < good.size(); ++size) {
    DiagnosticList diagnostics;
    REQUIRE_FALSE(parse_fzt("t.fzt", good.substr(0, size), diagnostics));
    REQUIRE(diagnostics.has_errors());
  }
  for (std::size_t i = 0; i < good.size(); ++i) {
    std::string bad = good;
    bad[i] = static_cast<char>(bad[i] ^ 0x5A);
    DiagnosticList diagnostics;
    REQUIRE_FALSE(parse_fzt("t.fzt", bad, diagnostics));
  }
  REQUIRE(first_error(good + "x") == "checksum mismatch: the file is corrupted or truncated");
  REQUIRE(first_error("hello") ==
          "not an .fzt lookup table (the file does not start with the FMPCFZT signature)");
}

TEST_CASE(".fzt loader rejects wrong versions, foreign byte order and hostile headers", "[table]") {
  const std::string good = serialize_fzt(bilinear_table());
  // Offsets from the layout in lookup_table.h.
  constexpr std::size_t kVersion = 8, kByteOrder = 12, kAxes = 32, kOutputs = 36, kErrorKind = 48;

  std::string v3 = good;
  put_u32(v3, kVersion, 3);
  REQUIRE(first_error(v3) == "the table is .fzt version 3; this fmpc reads version 2");
  std::string v1 = good;
  put_u32(v1, kVersion, 1);
  REQUIRE(first_error(v1) == "the table is .fzt version 1, which records neither the units of its inputs and "
                             "outputs nor whether its maximum error is a bound; this fmpc reads version 2");

  std::string big_endian = good;
  put_u32(big_endian, kByteOrder, 0x04030201U);
  REQUIRE(first_error(big_endian) ==
          "the table was written big-endian; fmpc writes and reads little-endian .fzt only");

  std::string many_axes = good;
  put_u32(many_axes, kAxes, 1000);
  REQUIRE(first_error(with_valid_checksum(many_axes)) == "the table has 1000 axes; 1 to 8 are supported");

  std::string no_outputs = good;
  put_u32(no_outputs, kOutputs, 0);
  REQUIRE(first_error(with_valid_checksum(no_outputs)) == "the table has 0 outputs; 1 to 64 are supported");

  std::string unknown_kind = good;
  put_u32(unknown_kind, kErrorKind, 7);
  REQUIRE(first_error(with_valid_checksum(unknown_kind)) == "error kind 7 is not a bound (1) or an estimate (2)");

  // A huge breakpoint count must be refused before anything is allocated. The first axis count sits after the
  // fixed header (52 bytes), two strings ("demo", "demo.fis"), the axis name "x", its unit "kPa" and its index.
  const std::size_t first_count = 52 + (4 + 4) + (4 + 8) + (4 + 1) + (4 + 3) + 4;
  std::string huge = good;
  put_u32(huge, first_count, 0xFFFFFFFFU);
  REQUIRE(first_error(with_valid_checksum(huge)) ==
          "axis 1 'x' claims 4294967295 breakpoints, which the file cannot hold");
}

TEST_CASE("table validation: overflowing grids, NaN and non-monotonic axes, wrong value counts", "[table]") {
  {
    LookupTable t = bilinear_table();
    t.axes[0].breakpoints[2] = std::nan("");
    DiagnosticList d;
    REQUIRE_FALSE(validate_table(t, "t.fzt", d));
    REQUIRE(d.items().front().message == "axis 1 'x': breakpoint 3 is nan; breakpoints must be finite");
    // The same table written and read back is refused by the loader.
    DiagnosticList d2;
    REQUIRE_FALSE(parse_fzt("t.fzt", serialize_fzt(t), d2));
    REQUIRE(d2.items().front().message == d.items().front().message);
  }
  {
    LookupTable t = bilinear_table();
    t.axes[1].breakpoints = {-1.0, 4.0, 1.0};
    DiagnosticList d;
    REQUIRE_FALSE(validate_table(t, "t.fzt", d));
    REQUIRE(d.items().front().message ==
            "axis 2 'y': breakpoints must increase strictly, but breakpoint 3 (1) follows 4");
  }
  {
    LookupTable t = bilinear_table();
    t.values.pop_back();
    DiagnosticList d;
    REQUIRE_FALSE(validate_table(t, "t.fzt", d));
    REQUIRE(d.items().front().message == "the table holds 23 values, but its axes and outputs need 24");
  }
  {
    // Eight axes of 2^4 points each is 2^32 grid points: past the limit, reported without allocating.
    LookupTable t = bilinear_table();
    t.axes.assign(8, TableAxis{"a", "", 0, std::vector<double>(16)});
    for (TableAxis& axis : t.axes)
      for (std::size_t i = 0; i < 16; ++i) axis.breakpoints[i] = static_cast<double>(i);
    DiagnosticList d;
    REQUIRE_FALSE(validate_table(t, "t.fzt", d));
    REQUIRE(d.items().front().message ==
            "the grid has more than 2147483648 points (the product of the breakpoint counts overflows the limit)");
  }
}
