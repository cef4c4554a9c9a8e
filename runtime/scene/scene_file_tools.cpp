// Rigid tools in a scene (docs/scenes.md, "Rigid tools"): `tools:` (a list of spheres and capsules, each with a
// fixed `pose` or a `path` of timed poses, in mesh units) and `contact: {stiffness_ratio}`.
#include <cctype>
#include <cmath>

#include "diagnostics/number_format.h"
#include "runtime/scene/scene_file_parser.h"

namespace fmpc::sim {

namespace {

// A tool's name becomes CSV column names and JSON keys: letters, digits and '_', starting with a letter.
bool column_name(const std::string& name) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name.front()))) return false;
  for (const char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return name.size() <= 64;
}

}  // namespace

// One point of a path, or a fixed pose: `position` [x, y, z] (mesh units), `orientation` [w, x, y, z] (a quaternion,
// normalised; omitted: the previous point's, or none), `time` (s; a path's points only).
std::optional<ToolKeyframe> SceneParser::parse_keyframe(const YAML::Node& node, const std::string& field, bool timed,
                                                        const ToolKeyframe* previous) {
  if (!check_map(node, field, timed ? std::vector<std::string>{"time", "position", "orientation"}
                                    : std::vector<std::string>{"position", "orientation"}))
    return std::nullopt;
  remember(node, field);
  ToolKeyframe keyframe;
  if (previous != nullptr) keyframe.pose.orientation = previous->pose.orientation;
  if (timed) {
    if (!node["time"]) {
      error(node, field, "a path point needs 'time' (s) and 'position' [x, y, z]");
      return std::nullopt;
    }
    const auto time = non_negative(node["time"], field + ".time", " of seconds");
    if (!time) return std::nullopt;
    if (previous != nullptr && !(*time > previous->time)) {
      error(node["time"], field + ".time",
            "the path's times must increase; the point before is at " + format_number(previous->time) + " s");
      return std::nullopt;
    }
    keyframe.time = *time;
  }
  if (!node["position"]) {
    error(node, field, "give 'position' [x, y, z] (mesh units)");
    return std::nullopt;
  }
  const auto position = vector3(node["position"], field + ".position", " (mesh units)");
  if (!position) return std::nullopt;
  keyframe.pose.position = *position;
  if (node["orientation"]) {
    const YAML::Node q = node["orientation"];
    remember(q, field + ".orientation");
    std::array<double, 4> orientation{};
    bool ok = q.IsSequence() && q.size() == 4;
    for (std::size_t i = 0; ok && i < 4; ++i)
      ok = q[i].IsScalar() && YAML::convert<double>::decode(q[i], orientation[i]) && std::isfinite(orientation[i]);
    if (!ok || !normalise_orientation(orientation)) {
      error(q, field + ".orientation",
            "expected a rotation as a quaternion [w, x, y, z] of four finite numbers, not all zero (e.g. [1, 0, 0, 0]), "
            "got " + describe(q));
      return std::nullopt;
    }
    keyframe.pose.orientation = orientation;
  }
  return keyframe;
}

void SceneParser::parse_tools(const YAML::Node& node) {
  remember(node, "tools");
  if (!node.IsSequence() || node.size() == 0) {
    error(node, "tools", "expected a list of tools, each a map with 'shape', 'radius' and a 'pose' or 'path'");
    return;
  }
  if (node.size() > static_cast<std::size_t>(kernels::kMostTools)) {
    error(node, "tools", std::to_string(node.size()) + " tools given; a scene takes at most " +
                             std::to_string(kernels::kMostTools));
    return;
  }
  for (std::size_t i = 0; i < node.size(); ++i) {
    const YAML::Node entry = node[i];
    const std::string field = "tools[" + std::to_string(i) + "]";
    if (!check_map(entry, field, {"name", "shape", "radius", "length", "pose", "path"})) continue;
    remember(entry, field);
    SceneTool tool;
    tool.field = field;
    tool.name = "tool" + std::to_string(i);
    bool ok = true;
    if (entry["name"]) {
      const auto name = text(entry["name"], field + ".name");
      if (name && !column_name(*name)) {
        error(entry["name"], field + ".name",
              "'" + *name + "' cannot name a tool: use up to 64 letters, digits and '_', starting with a letter (it "
              "names the tool's columns in time_series.csv)");
        ok = false;
      } else if (name) {
        for (const SceneTool& other : scene_.tools)
          if (other.name == *name) {
            error(entry["name"], field + ".name", "two tools are named '" + *name + "'; give each its own name");
            ok = false;
          }
        tool.name = *name;
      } else {
        ok = false;
      }
    }
    if (!entry["shape"] || !entry["radius"]) {
      error(entry, field, "a tool needs 'shape' (sphere or capsule) and 'radius' (mesh units)");
      continue;
    }
    static const std::vector<std::string> shapes = {"sphere", "capsule"};
    const auto shape = keyword(entry["shape"], field + ".shape", shapes, "a tool shape");
    if (!shape) continue;
    tool.shape = *shape == 0 ? RigidTool::Shape::Sphere : RigidTool::Shape::Capsule;
    if (const auto radius = positive(entry["radius"], field + ".radius", " (mesh units)")) tool.radius = *radius;
    else ok = false;
    if (tool.shape == RigidTool::Shape::Capsule) {
      if (!entry["length"]) {
        error(entry, field, "a capsule needs 'length' (mesh units): its axis runs from its pose's position along the "
                            "tool's z axis");
        ok = false;
      } else if (const auto length = positive(entry["length"], field + ".length", " (mesh units)")) {
        tool.length = *length;
      } else {
        ok = false;
      }
    } else if (entry["length"]) {
      error(entry["length"], field + ".length", "a sphere has no length; use shape: capsule for a shaft");
      ok = false;
    }
    switch (one_of(entry, field, {"pose", "path"})) {
      case 0:
        if (const auto keyframe = parse_keyframe(entry["pose"], field + ".pose", false, nullptr)) tool.path.push_back(*keyframe);
        else ok = false;
        break;
      case 1: {
        const YAML::Node path = entry["path"];
        remember(path, field + ".path");
        if (!path.IsSequence() || path.size() == 0) {
          error(path, field + ".path", "expected a list of points {time, position, orientation}");
          ok = false;
          break;
        }
        for (std::size_t k = 0; ok && k < path.size(); ++k) {
          const auto keyframe = parse_keyframe(path[k], field + ".path[" + std::to_string(k) + "]", true,
                                               tool.path.empty() ? nullptr : &tool.path.back());
          if (keyframe) tool.path.push_back(*keyframe);
          else ok = false;
        }
        break;
      }
      default:  // one_of said what is missing
        ok = false;
    }
    if (ok) scene_.tools.push_back(std::move(tool));
  }
}

void SceneParser::parse_contact(const YAML::Node& node) {
  remember(node, "contact");
  if (!check_map(node, "contact", {"stiffness_ratio", "damping_ratio"})) return;
  if (node["damping_ratio"])
    if (const auto ratio = non_negative(node["damping_ratio"], "contact.damping_ratio", "")) {
      if (*ratio > kMostContactDampingRatio) {
        error(node["damping_ratio"], "contact.damping_ratio",
              format_number(*ratio) + " is above the limit of " + format_number(kMostContactDampingRatio) +
                  " (1 is critical damping of a vertex on its contact spring)");
        return;
      }
      scene_.contact_damping_ratio = *ratio;
    }
  if (node["stiffness_ratio"])
    if (const auto ratio = positive(node["stiffness_ratio"], "contact.stiffness_ratio", "")) {
      if (*ratio > 1e6) {
        error(node["stiffness_ratio"], "contact.stiffness_ratio",
              format_number(*ratio) + " is above the limit of 1e6 (the explicit step shrinks by 1 / sqrt(1 + ratio))");
        return;
      }
      scene_.contact_stiffness_ratio = *ratio;
    }
}

}  // namespace fmpc::sim
