#include "runtime/scene/scene_file_parser.h"

#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "diagnostics/number_format.h"
#include "runtime/io/input_file.h"
#include "runtime/scene/scene_file_yaml.h"

namespace fmpc::sim {

SourceRange SceneParser::range(const YAML::Node& node) const { return mark_range(path_, node.Mark()); }

void SceneParser::error(const YAML::Node& node, const std::string& field, const std::string& message,
                        std::vector<std::string> notes) {
  diagnostics_.error(range(node), field + ": " + message, std::move(notes));
}

void SceneParser::remember(const YAML::Node& node, const std::string& field) { scene_.ranges[field] = range(node); }

bool SceneParser::check_map(const YAML::Node& node, const std::string& field, const std::vector<std::string>& allowed) {
  if (!node.IsMap()) {
    error(node, field, "expected a map with " + join_names(quoted(allowed)));
    return false;
  }
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = it->first.Scalar();
    bool known = false;
    for (const auto& name : allowed) known = known || name == key;
    if (known) continue;
    std::vector<std::string> notes;
    if (auto suggestion = closest_name(key, allowed)) notes.push_back("did you mean '" + *suggestion + "'?");
    const std::string where = field.empty() ? "" : " in " + field;
    // A hostile key can be megabytes long: the message shows its start.
    const std::string shown = key.size() > 60 ? key.substr(0, 60) + "..." : key;
    diagnostics_.error(range(it->first), (field.empty() ? shown : field + "." + shown) + ": unknown key" + where +
                                             "; allowed: " + join_names(quoted(allowed)),
                       notes);
  }
  return true;
}

std::vector<std::string> SceneParser::quoted(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (const auto& n : names) out.push_back("'" + n + "'");
  return out;
}

int SceneParser::one_of(const YAML::Node& node, const std::string& field, const std::vector<std::string>& keys) {
  int found = -1;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (!node[keys[i]]) continue;
    if (found >= 0) {
      error(node[keys[i]], field, "give only one of " + join_names(quoted(keys)));
      return -1;
    }
    found = static_cast<int>(i);
  }
  if (found < 0) error(node, field, "give one of " + join_names(quoted(keys)));
  return found;
}

std::optional<double> SceneParser::number(const YAML::Node& node, const std::string& field,
                                          const std::string& allowed) {
  remember(node, field);
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
    error(node, field, "expected " + allowed + ", got " + describe(node));
    return std::nullopt;
  }
  return value;
}

std::optional<double> SceneParser::positive(const YAML::Node& node, const std::string& field, const std::string& unit) {
  const auto value = number(node, field, "a positive number" + unit);
  if (value && !(*value > 0.0)) {
    error(node, field, "expected a positive number" + unit + ", got " + format_number(*value));
    return std::nullopt;
  }
  return value;
}

std::optional<double> SceneParser::non_negative(const YAML::Node& node, const std::string& field,
                                                const std::string& unit) {
  const auto value = number(node, field, "a non-negative number" + unit);
  if (value && !(*value >= 0.0)) {
    error(node, field, "expected a non-negative number" + unit + ", got " + format_number(*value));
    return std::nullopt;
  }
  return value;
}

std::optional<long long> SceneParser::integer(const YAML::Node& node, const std::string& field, long long min,
                                              long long max) {
  remember(node, field);
  const std::string allowed = "an integer from " + std::to_string(min) + " to " + std::to_string(max);
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value) ||
      value != std::floor(value) || value < static_cast<double>(min) || value > static_cast<double>(max)) {
    error(node, field, "expected " + allowed + ", got " + describe(node));
    return std::nullopt;
  }
  return static_cast<long long>(value);
}

std::optional<bool> SceneParser::boolean(const YAML::Node& node, const std::string& field) {
  remember(node, field);
  bool value = false;
  if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) {
    error(node, field, "expected true or false, got " + describe(node));
    return std::nullopt;
  }
  return value;
}

std::optional<std::string> SceneParser::text(const YAML::Node& node, const std::string& field) {
  remember(node, field);
  if (!node.IsScalar() || node.Scalar().empty()) {
    error(node, field, "expected a non-empty text, got " + describe(node));
    return std::nullopt;
  }
  if (node.Scalar().find('\0') != std::string::npos) {
    error(node, field, "the text contains a NUL byte (\\0), which no file name or label may hold; remove it");
    return std::nullopt;
  }
  return node.Scalar();
}

std::optional<std::size_t> SceneParser::keyword(const YAML::Node& node, const std::string& field,
                                                const std::vector<std::string>& names, const std::string& what) {
  remember(node, field);
  if (node.IsScalar()) {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (node.Scalar() == names[i]) return i;
  }
  std::vector<std::string> notes;
  if (node.IsScalar())
    if (auto suggestion = closest_name(node.Scalar(), names)) notes.push_back("did you mean '" + *suggestion + "'?");
  error(node, field, describe(node) + " is not " + what + "; use " + join_names(names), notes);
  return std::nullopt;
}

std::optional<Point3> SceneParser::vector3(const YAML::Node& node, const std::string& field, const std::string& unit) {
  remember(node, field);
  Point3 p{};
  if (!node.IsSequence() || node.size() != 3) {
    error(node, field, "expected three numbers [x, y, z]" + unit + ", got " + describe(node));
    return std::nullopt;
  }
  for (std::size_t i = 0; i < 3; ++i) {
    double value = 0.0;
    if (!node[i].IsScalar() || !YAML::convert<double>::decode(node[i], value) || !std::isfinite(value)) {
      error(node[i], field, "expected three numbers [x, y, z]" + unit + ", got " + describe(node[i]));
      return std::nullopt;
    }
    p[i] = value;
  }
  return p;
}

std::optional<std::vector<std::int32_t>> SceneParser::indices(const YAML::Node& node, const std::string& field) {
  remember(node, field);
  if (!node.IsSequence() || node.size() == 0) {
    error(node, field, "expected a list of vertex indices (integers >= 0), got " + describe(node));
    return std::nullopt;
  }
  std::vector<std::int32_t> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const auto value = integer(node[i], field, 0, std::numeric_limits<std::int32_t>::max());
    if (!value) return std::nullopt;
    out.push_back(static_cast<std::int32_t>(*value));
  }
  remember(node, field);
  return out;
}

std::optional<SceneBox> SceneParser::box(const YAML::Node& node, const std::string& field) {
  remember(node, field);
  if (!check_map(node, field, {"min", "max"})) return std::nullopt;
  if (!node["min"] || !node["max"]) {
    error(node, field, "a box needs 'min' and 'max' corners [x, y, z] (mesh units)");
    return std::nullopt;
  }
  const auto lo = vector3(node["min"], field + ".min", " (mesh units)");
  const auto hi = vector3(node["max"], field + ".max", " (mesh units)");
  if (!lo || !hi) return std::nullopt;
  for (std::size_t i = 0; i < 3; ++i) {
    if ((*lo)[i] > (*hi)[i]) {
      error(node, field, "'min' must not exceed 'max' on any axis");
      return std::nullopt;
    }
  }
  return SceneBox{*lo, *hi};
}

std::string SceneParser::describe(const YAML::Node& node) {
  if (!node || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list of " + std::to_string(node.size());
  return "a map";
}

std::string SceneParser::resolve(const std::string& file) const {
  namespace fs = std::filesystem;
  const fs::path given(file);
  if (given.is_absolute()) return given.lexically_normal().string();
  return (fs::path(path_).parent_path() / given).lexically_normal().string();
}

// A file named by the scene must be a regular file within its reader's limit (docs/limits.md). Checked here so
// that the error points at the field; a missing file is left to the reader, which says where it looked.
void SceneParser::check_input_file(const YAML::Node& node, const std::string& field, const std::string& file,
                                   std::size_t limit, const std::string& what) {
  struct stat info {};
  if (::stat(file.c_str(), &info) != 0) return;
  if (!S_ISREG(info.st_mode)) {
    error(node, field, "'" + file + "' is " + (S_ISDIR(info.st_mode) ? "a directory" : "not a regular file") +
                           " (a device, FIFO or socket), not a " + what + "; give the path of a regular file");
  } else if (static_cast<unsigned long long>(info.st_size) > limit) {
    error(node, field, "'" + file + "' is larger than " + byte_size_text(limit) + ", the limit for a " + what);
  }
}

}  // namespace fmpc::sim
