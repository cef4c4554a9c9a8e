#include "compiler/backend/table/lookup_table.h"

#include <cmath>
#include <cstring>

#include "compiler/frontend/utf8.h"
#include "compiler/ir/content_hash.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

constexpr char kMagic[8] = {'F', 'M', 'P', 'C', 'F', 'Z', 'T', 0x1A};
constexpr std::uint32_t kByteOrderMark = 0x01020304;

// Bytes are assembled explicitly so the file is little-endian whatever the host.
class ByteWriter {
 public:
  void raw(const void* data, std::size_t size) { bytes_.append(static_cast<const char*>(data), size); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) bytes_.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  }
  void f64(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void f32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    u32(bits);
  }
  void str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    bytes_ += s;
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

// Every read checks the remaining length first; the first failure records what was being read and stops.
class ByteReader {
 public:
  ByteReader(const std::string& bytes, std::size_t end) : bytes_(bytes), end_(end) {}
  bool ok() const { return ok_; }
  const std::string& failure() const { return failure_; }
  std::size_t offset() const { return pos_; }
  std::size_t remaining() const { return end_ - pos_; }

  bool raw(void* out, std::size_t size, const char* what) {
    if (!need(size, what)) return false;
    std::memcpy(out, bytes_.data() + pos_, size);
    pos_ += size;
    return true;
  }
  std::uint32_t u32(const char* what) {
    unsigned char b[4] = {};
    if (!raw(b, 4, what)) return 0;
    return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
           static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24;
  }
  std::uint64_t u64(const char* what) {
    const std::uint64_t lo = u32(what);
    const std::uint64_t hi = u32(what);
    return lo | hi << 32;
  }
  double f64(const char* what) {
    const std::uint64_t bits = u64(what);
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  float f32(const char* what) {
    const std::uint32_t bits = u32(what);
    float v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  std::string str(const char* what) {
    const std::uint32_t size = u32(what);
    if (!ok_) return {};
    if (size > kMaxFztString) {
      fail(std::string(what) + ": length " + std::to_string(size) + " exceeds the limit of " +
           std::to_string(kMaxFztString));
      return {};
    }
    std::string s(size, '\0');
    if (!raw(s.data(), size, what)) return {};
    // Names, units and paths are text everywhere they go (messages, generated headers, Python's str).
    if (first_invalid_utf8(s) != std::string::npos) {
      fail(std::string(what) + ": not valid UTF-8 text");
      return {};
    }
    return s;
  }
  void fail(std::string message) {
    if (ok_) failure_ = std::move(message);
    ok_ = false;
  }

 private:
  bool need(std::size_t size, const char* what) {
    if (!ok_) return false;
    if (size > end_ - pos_) {
      fail(std::string("truncated at byte ") + std::to_string(pos_) + " while reading " + what);
      return false;
    }
    return true;
  }
  const std::string& bytes_;
  std::size_t end_;
  std::size_t pos_ = 0;
  bool ok_ = true;
  std::string failure_;
};

SourceRange file_position(const std::string& path) { return SourceRange{path, 0, 0, 0, 0}; }

}  // namespace

const char* to_string(TableErrorKind kind) {
  switch (kind) {
    case TableErrorKind::Bound: return "bound";
    case TableErrorKind::Estimate: return "estimate";
  }
  return "estimate";
}

std::uint64_t LookupTable::grid_points() const {
  std::uint64_t points = axes.empty() ? 0 : 1;
  for (const TableAxis& axis : axes) points *= axis.breakpoints.size();
  return points;
}

TableView<double> view_of(const LookupTable& table, std::vector<const double*>& breakpoint_pointers,
                          std::vector<int>& counts) {
  breakpoint_pointers.clear();
  counts.clear();
  for (const TableAxis& axis : table.axes) {
    breakpoint_pointers.push_back(axis.breakpoints.data());
    counts.push_back(static_cast<int>(axis.breakpoints.size()));
  }
  TableView<double> view;
  view.axes = static_cast<int>(table.axes.size());
  view.outputs = static_cast<int>(table.output_names.size());
  view.counts = counts.data();
  view.breakpoints = breakpoint_pointers.data();
  view.values = table.values.data();
  return view;
}

bool validate_table(const LookupTable& table, const std::string& origin, DiagnosticList& diagnostics) {
  const std::size_t errors_before = diagnostics.error_count();
  const SourceRange where = file_position(origin);
  if (table.axes.empty() || table.axes.size() > static_cast<std::size_t>(kMaxTableAxes))
    diagnostics.error(where, "the table has " + std::to_string(table.axes.size()) + " axes; 1 to " +
                                 std::to_string(kMaxTableAxes) + " are supported",
                      {"vary fewer inputs, or fix some with --fix NAME=VALUE"});
  if (table.output_names.empty() || table.output_names.size() > kMaxFztOutputs)
    diagnostics.error(where, "the table has " + std::to_string(table.output_names.size()) + " outputs; 1 to " +
                                 std::to_string(kMaxFztOutputs) + " are supported");
  if (table.output_units.size() != table.output_names.size())
    diagnostics.error(where, "the table has " + std::to_string(table.output_names.size()) + " outputs but " +
                                 std::to_string(table.output_units.size()) + " output units");
  if (table.error_kind != TableErrorKind::Bound && table.error_kind != TableErrorKind::Estimate)
    diagnostics.error(where, "error kind " + std::to_string(static_cast<std::uint32_t>(table.error_kind)) +
                                 " is not a bound (1) or an estimate (2)");
  if (!(table.max_error >= 0.0) || std::isinf(table.max_error))
    diagnostics.error(where, "the maximum error is " + format_number(table.max_error) +
                                 "; it must be a finite number, 0 or more");
  std::uint64_t points = 1;
  for (std::size_t a = 0; a < table.axes.size(); ++a) {
    const TableAxis& axis = table.axes[a];
    const std::string field = "axis " + std::to_string(a + 1) + " '" + axis.input_name + "'";
    const std::vector<double>& b = axis.breakpoints;
    if (b.size() < 2) {
      diagnostics.error(where, field + " has " + std::to_string(b.size()) + " breakpoints; at least 2 are needed");
      continue;
    }
    for (std::size_t i = 0; i < b.size(); ++i) {
      if (!std::isfinite(b[i])) {
        diagnostics.error(where, field + ": breakpoint " + std::to_string(i + 1) + " is " + format_number(b[i]) +
                                     "; breakpoints must be finite");
        break;
      }
      if (i > 0 && !(b[i] > b[i - 1])) {
        diagnostics.error(where, field + ": breakpoints must increase strictly, but breakpoint " +
                                     std::to_string(i + 1) + " (" + format_number(b[i]) + ") follows " +
                                     format_number(b[i - 1]));
        break;
      }
    }
    if (points > kMaxFztValues / b.size()) {
      diagnostics.error(where, "the grid has more than " + std::to_string(kMaxFztValues) +
                                   " points (the product of the breakpoint counts overflows the limit)");
      return false;
    }
    points *= b.size();
  }
  if (diagnostics.error_count() > errors_before) return false;
  if (points > kMaxFztValues / table.output_names.size()) {
    diagnostics.error(where, "the table holds more than " + std::to_string(kMaxFztValues) + " values");
    return false;
  }
  const std::uint64_t expected = points * table.output_names.size();
  if (table.values.size() != expected) {
    diagnostics.error(where, "the table holds " + std::to_string(table.values.size()) + " values, but its axes and " +
                                 "outputs need " + std::to_string(expected));
    return false;
  }
  for (std::size_t i = 0; i < table.values.size(); ++i)
    if (!std::isfinite(table.values[i])) {
      diagnostics.error(where, "value " + std::to_string(i) + " is " + format_number(table.values[i]) +
                                   "; table values must be finite");
      return false;
    }
  if (table.max_error_location.size() != table.axes.size()) {
    diagnostics.error(where, "the location of the maximum error has " +
                                 std::to_string(table.max_error_location.size()) + " coordinates, the table " +
                                 std::to_string(table.axes.size()) + " axes");
    return false;
  }
  return true;
}

std::string fzt_signature() { return std::string(kMagic, sizeof kMagic); }

bool has_fzt_signature(const std::string& bytes) {
  return bytes.size() >= sizeof kMagic && std::memcmp(bytes.data(), kMagic, sizeof kMagic) == 0;
}

std::string serialize_fzt(const LookupTable& table) {
  ByteWriter w;
  w.raw(kMagic, sizeof kMagic);
  w.u32(kFztVersion);
  w.u32(kByteOrderMark);
  w.u64(table.source_hash);
  w.u32(static_cast<std::uint32_t>(table.value_type));
  w.u32(1);  // multilinear
  w.u32(static_cast<std::uint32_t>(table.axes.size()));
  w.u32(static_cast<std::uint32_t>(table.output_names.size()));
  w.f64(table.max_error);
  w.u32(static_cast<std::uint32_t>(table.error_kind));
  w.str(table.system_name);
  w.str(table.source_path);
  for (const TableAxis& axis : table.axes) {
    w.str(axis.input_name);
    w.str(axis.input_unit);
    w.u32(axis.input_index);
    w.u32(static_cast<std::uint32_t>(axis.breakpoints.size()));
    for (double b : axis.breakpoints) w.f64(b);
  }
  for (std::size_t o = 0; o < table.output_names.size(); ++o) {
    w.str(table.output_names[o]);
    w.str(o < table.output_units.size() ? table.output_units[o] : std::string());
  }
  w.u32(static_cast<std::uint32_t>(table.fixed_inputs.size()));
  for (const TableFixedInput& fixed : table.fixed_inputs) {
    w.str(fixed.name);
    w.str(fixed.unit);
    w.f64(fixed.value);
  }
  for (double c : table.max_error_location) w.f64(c);
  for (double v : table.values) {
    if (table.value_type == TableValueType::Float32)
      w.f32(static_cast<float>(v));
    else
      w.f64(v);
  }
  std::string bytes = w.bytes();
  ByteWriter checksum;
  checksum.u64(fnv1a64(bytes));
  return bytes + checksum.bytes();
}

std::optional<LookupTable> parse_fzt(const std::string& path, const std::string& bytes, DiagnosticList& diagnostics) {
  const SourceRange where = file_position(path);
  const std::string rebuild = "rebuild it with fmpc compile --target table";
  if (!has_fzt_signature(bytes)) {
    diagnostics.error(where, "not an .fzt lookup table (the file does not start with the FMPCFZT signature)",
                      {"fmpc compile --target table writes .fzt files"});
    return std::nullopt;
  }
  // The checksum covers everything before its own 8 bytes; check it first so that corruption anywhere is named
  // as such rather than as whatever field it happened to hit.
  if (bytes.size() < sizeof kMagic + 8 + 8) {
    diagnostics.error(where, "truncated: " + std::to_string(bytes.size()) + " bytes is shorter than any .fzt header",
                      {rebuild});
    return std::nullopt;
  }
  ByteReader header(bytes, bytes.size());
  char magic[8];
  header.raw(magic, sizeof magic, "the signature");
  const std::uint32_t version = header.u32("the version");
  const std::uint32_t byte_order = header.u32("the byte-order mark");
  // Version and byte order come before the checksum so that an old or foreign file is named as such.
  if (byte_order != kByteOrderMark) {
    diagnostics.error(where, byte_order == 0x04030201U
                                 ? "the table was written big-endian; fmpc writes and reads little-endian .fzt only"
                                 : "the byte-order mark is damaged: the file is corrupted",
                      {rebuild});
    return std::nullopt;
  }
  if (version == 1) {
    diagnostics.error(where, "the table is .fzt version 1, which records neither the units of its inputs and "
                             "outputs nor whether its maximum error is a bound; this fmpc reads version " +
                                 std::to_string(kFztVersion),
                      {rebuild + " from this fmpc"});
    return std::nullopt;
  }
  if (version != kFztVersion) {
    diagnostics.error(where, "the table is .fzt version " + std::to_string(version) + "; this fmpc reads version " +
                                 std::to_string(kFztVersion),
                      {rebuild + " from this fmpc"});
    return std::nullopt;
  }
  const std::size_t body_end = bytes.size() - 8;
  std::uint64_t stored_checksum = 0;
  for (int i = 7; i >= 0; --i)
    stored_checksum = stored_checksum << 8 | static_cast<unsigned char>(bytes[body_end + static_cast<std::size_t>(i)]);
  if (stored_checksum != fnv1a64(bytes.data(), body_end)) {
    diagnostics.error(where, "checksum mismatch: the file is corrupted or truncated", {rebuild});
    return std::nullopt;
  }

  ByteReader r(bytes, body_end);
  r.raw(magic, sizeof magic, "the signature");
  r.u32("the version");
  r.u32("the byte-order mark");
  LookupTable table;
  table.source_hash = r.u64("the source hash");
  const std::uint32_t value_type = r.u32("the value type");
  const std::uint32_t interpolation = r.u32("the interpolation");
  const std::uint32_t axes = r.u32("the number of axes");
  const std::uint32_t outputs = r.u32("the number of outputs");
  table.max_error = r.f64("the maximum error");
  table.error_kind = static_cast<TableErrorKind>(r.u32("the error kind"));
  table.system_name = r.str("the system name");
  table.source_path = r.str("the source path");
  if (r.ok()) {
    if (value_type != static_cast<std::uint32_t>(TableValueType::Float32) &&
        value_type != static_cast<std::uint32_t>(TableValueType::Float64))
      r.fail("value type " + std::to_string(value_type) + " is not float32 (1) or float64 (2)");
    else if (interpolation != 1)
      r.fail("interpolation " + std::to_string(interpolation) + " is not multilinear (1)");
    else if (axes == 0 || axes > static_cast<std::uint32_t>(kMaxTableAxes))
      r.fail("the table has " + std::to_string(axes) + " axes; 1 to " + std::to_string(kMaxTableAxes) +
             " are supported");
    else if (outputs == 0 || outputs > kMaxFztOutputs)
      r.fail("the table has " + std::to_string(outputs) + " outputs; 1 to " + std::to_string(kMaxFztOutputs) +
             " are supported");
  }
  table.value_type = static_cast<TableValueType>(value_type);
  std::uint64_t points = 1;
  for (std::uint32_t a = 0; a < axes && r.ok(); ++a) {
    TableAxis axis;
    axis.input_name = r.str("an axis name");
    axis.input_unit = r.str("an axis unit");
    axis.input_index = r.u32("an axis input index");
    const std::uint32_t count = r.u32("an axis breakpoint count");
    if (!r.ok()) break;
    // Check the count against the bytes left before allocating: a hostile count must not allocate gigabytes.
    if (count < 2 || count > r.remaining() / 8) {
      r.fail("axis " + std::to_string(a + 1) + " '" + axis.input_name + "' claims " + std::to_string(count) +
             " breakpoints, which the file cannot hold");
      break;
    }
    if (points > kMaxFztValues / count) {
      r.fail("the grid has more than " + std::to_string(kMaxFztValues) +
             " points (the product of the breakpoint counts overflows the limit)");
      break;
    }
    points *= count;
    axis.breakpoints.resize(count);
    for (double& b : axis.breakpoints) b = r.f64("the breakpoints");
    table.axes.push_back(std::move(axis));
  }
  for (std::uint32_t o = 0; o < outputs && r.ok(); ++o) {
    table.output_names.push_back(r.str("an output name"));
    table.output_units.push_back(r.str("an output unit"));
  }
  const std::uint32_t fixed = r.ok() ? r.u32("the number of fixed inputs") : 0;
  // Each fixed input takes at least 16 bytes (two empty strings and a value).
  if (r.ok() && fixed > r.remaining() / 16) r.fail("the table claims " + std::to_string(fixed) + " fixed inputs");
  for (std::uint32_t f = 0; f < fixed && r.ok(); ++f) {
    TableFixedInput input;
    input.name = r.str("a fixed input name");
    input.unit = r.str("a fixed input unit");
    input.value = r.f64("a fixed input value");
    table.fixed_inputs.push_back(std::move(input));
  }
  for (std::uint32_t a = 0; a < axes && r.ok(); ++a)
    table.max_error_location.push_back(r.f64("the location of the maximum error"));
  if (r.ok()) {
    const std::uint64_t count = points * outputs;
    const std::uint64_t size = value_type == static_cast<std::uint32_t>(TableValueType::Float32) ? 4 : 8;
    if (count > r.remaining() / size || count * size != r.remaining()) {
      r.fail("the values take " + std::to_string(r.remaining()) + " bytes, but " + std::to_string(count) +
             " values of " + std::to_string(size) + " bytes are declared");
    } else {
      table.values.resize(count);
      for (double& v : table.values)
        v = size == 4 ? static_cast<double>(r.f32("the values")) : r.f64("the values");
    }
  }
  if (!r.ok()) {
    diagnostics.error(where, r.failure(), {rebuild});
    return std::nullopt;
  }
  if (!validate_table(table, path, diagnostics)) return std::nullopt;
  return table;
}

FuzzySystem table_interface(const LookupTable& table) {
  FuzzySystem system;
  system.name = table.system_name;
  for (const TableAxis& axis : table.axes) {
    Variable input;
    input.name = axis.input_name;
    input.unit = axis.input_unit;
    input.min = axis.breakpoints.front();
    input.max = axis.breakpoints.back();
    system.inputs.push_back(std::move(input));
  }
  for (std::size_t o = 0; o < table.output_names.size(); ++o) {
    Variable output;
    output.name = table.output_names[o];
    output.unit = o < table.output_units.size() ? table.output_units[o] : std::string();
    system.outputs.push_back(std::move(output));
  }
  return system;
}

}  // namespace fmpc
