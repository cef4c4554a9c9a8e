#include "runtime/scene/scene_file_parser.h"

namespace fmpc::sim {

void SceneParser::parse_fixed(const YAML::Node& node) {
  remember(node, "fixed");
  if (!check_map(node, "fixed", {"indices", "box", "plane"})) return;
  parse_selection(node, "fixed", scene_.fixed);
}

// `hold`: one map or a list of maps, each with the selectors of `fixed` and `axes: [x, y, z]` (the axes held).
void SceneParser::parse_hold(const YAML::Node& node) {
  remember(node, "hold");
  one_or_list(node, "hold", [&](const YAML::Node& entry, const std::string& field) {
    if (!check_map(entry, field, {"indices", "box", "plane", "axes"})) return;
    SceneHold hold;
    hold.field = field;
    remember(entry, field);
    const YAML::Node axes = entry["axes"];
    if (!axes || !axes.IsSequence() || axes.size() == 0) {
      error(axes ? axes : entry, field + ".axes", "expected the held axes, a list of x, y and z (e.g. [z])");
      return;
    }
    for (std::size_t i = 0; i < axes.size(); ++i) {
      static const std::vector<std::string> names = {"x", "y", "z"};
      if (auto axis = keyword(axes[i], field + ".axes", names, "an axis"))
        hold.axes = static_cast<std::uint8_t>(hold.axes | (1u << *axis));
    }
    if (!entry["indices"] && !entry["box"] && !entry["plane"]) {
      error(entry, field, "give the vertices to hold: 'indices', 'box' or 'plane'");
      return;
    }
    parse_selection(entry, field, hold.selection);
    scene_.holds.push_back(std::move(hold));
  });
}

// The vertex selectors of `fixed` and `hold` entries: indices, boxes, planes.
void SceneParser::parse_selection(const YAML::Node& node, const std::string& prefix, SceneFixed& out) {
  if (node["indices"])
    if (auto v = indices(node["indices"], prefix + ".indices")) out.indices = *v;
  if (node["box"]) {
    remember(node["box"], prefix + ".box");
    one_or_list(node["box"], prefix + ".box", [&](const YAML::Node& b, const std::string& field) {
      if (auto parsed = box(b, field)) out.boxes.push_back(*parsed);
    });
  }
  if (node["plane"]) {
    remember(node["plane"], prefix + ".plane");
    one_or_list(node["plane"], prefix + ".plane", [&](const YAML::Node& p, const std::string& field) {
      if (!check_map(p, field, {"point", "normal", "tolerance"})) return;
      if (!p["point"] || !p["normal"]) {
        error(p, field, "a plane needs 'point' and 'normal' [x, y, z] (mesh units)");
        return;
      }
      SceneFixed::Plane plane;
      plane.field = field;
      const auto point = vector3(p["point"], field + ".point", " (mesh units)");
      const auto normal = vector3(p["normal"], field + ".normal", "");
      if (!point || !normal) return;
      if ((*normal)[0] == 0.0 && (*normal)[1] == 0.0 && (*normal)[2] == 0.0) {
        error(p["normal"], field + ".normal", "the normal must not be zero");
        return;
      }
      plane.point = *point;
      plane.normal = *normal;
      if (p["tolerance"]) {
        const auto tolerance = non_negative(p["tolerance"], field + ".tolerance", " (mesh units)");
        if (!tolerance) return;
        plane.tolerance = *tolerance;
      }
      out.planes.push_back(plane);
    });
  }
}

void SceneParser::parse_loads(const YAML::Node& node) {
  remember(node, "loads");
  if (!check_map(node, "loads", {"gravity", "probe"})) return;
  if (node["gravity"])
    if (auto g = vector3(node["gravity"], "loads.gravity", " (m/s^2)")) scene_.gravity = *g;
  if (!node["probe"]) return;
  const YAML::Node p = node["probe"];
  remember(p, "loads.probe");
  if (!check_map(p, "loads.probe", {"indices", "ray", "radius", "displacement", "force", "ramp", "cycles"})) return;
  SceneProbe probe;
  bool ok = true;
  switch (one_of(p, "loads.probe", {"indices", "ray"})) {
    case 0:
      if (auto v = indices(p["indices"], "loads.probe.indices")) probe.indices = *v;
      else ok = false;
      break;
    case 1: {
      probe.by_ray = true;
      const YAML::Node ray = p["ray"];
      remember(ray, "loads.probe.ray");
      if (!check_map(ray, "loads.probe.ray", {"origin", "direction"}) || !ray["origin"] || !ray["direction"]) {
        if (ray.IsMap()) error(ray, "loads.probe.ray", "a ray needs 'origin' and 'direction' [x, y, z] (mesh units)");
        ok = false;
        break;
      }
      const auto origin = vector3(ray["origin"], "loads.probe.ray.origin", " (mesh units)");
      const auto direction = vector3(ray["direction"], "loads.probe.ray.direction", "");
      if (!origin || !direction) {
        ok = false;
        break;
      }
      if ((*direction)[0] == 0.0 && (*direction)[1] == 0.0 && (*direction)[2] == 0.0) {
        error(ray["direction"], "loads.probe.ray.direction", "the direction must not be zero");
        ok = false;
        break;
      }
      probe.ray_origin = *origin;
      probe.ray_direction = *direction;
      break;
    }
    default:
      ok = false;
  }
  if (p["radius"]) {
    if (!probe.by_ray) error(p["radius"], "loads.probe.radius", "only allowed with 'ray'");
    if (auto v = non_negative(p["radius"], "loads.probe.radius", " (mesh units)")) probe.radius = *v;
  }
  switch (one_of(p, "loads.probe", {"displacement", "force"})) {
    case 0:
      probe.mode = ProbeLoad::Mode::Displacement;
      if (auto v = vector3(p["displacement"], "loads.probe.displacement", " (m)")) probe.target = *v;
      else ok = false;
      break;
    case 1:
      probe.mode = ProbeLoad::Mode::Force;
      if (auto v = vector3(p["force"], "loads.probe.force", " (N)")) probe.target = *v;
      else ok = false;
      break;
    default:
      ok = false;
  }
  if (p["ramp"]) {
    if (auto v = non_negative(p["ramp"], "loads.probe.ramp", " of seconds")) probe.ramp = *v;
  }
  if (p["cycles"]) {
    if (auto v = integer(p["cycles"], "loads.probe.cycles", 1, 1000)) probe.cycles = static_cast<int>(*v);
    if (!(probe.ramp > 0.0))
      error(p["cycles"], "loads.probe.cycles", "needs a positive 'ramp' (the time from zero to the target)");
  }
  if (ok) scene_.probe = probe;
}

}  // namespace fmpc::sim
