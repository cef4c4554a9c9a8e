#include "runtime/scene/scene_meshing.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "runtime/mesh/mesh_reader.h"

namespace fmpc::sim {

std::vector<SizeSegment> probe_size_sources(const Scene& scene, const Mesh& surface) {
  std::vector<SizeSegment> sources;
  if (!scene.probe) return sources;
  const SceneProbe& probe = *scene.probe;
  Point3 travel{0.0, 0.0, 0.0};
  if (probe.mode == ProbeLoad::Mode::Displacement)
    for (std::size_t a = 0; a < 3; ++a) travel[a] = probe.target[a] / scene.mesh.unit;
  std::vector<Point3> starts;
  if (probe.by_ray) {
    double best = std::numeric_limits<double>::infinity();
    for (const Triangle& t : surface.triangles) {
      const auto hit = ray_triangle_hit(
          probe.ray_origin, probe.ray_direction, surface.points[static_cast<std::size_t>(t[0])],
          surface.points[static_cast<std::size_t>(t[1])], surface.points[static_cast<std::size_t>(t[2])]);
      if (hit && *hit < best) best = *hit;
    }
    if (best < std::numeric_limits<double>::infinity())
      starts.push_back({probe.ray_origin[0] + best * probe.ray_direction[0],
                        probe.ray_origin[1] + best * probe.ray_direction[1],
                        probe.ray_origin[2] + best * probe.ray_direction[2]});
  } else {
    for (const auto index : probe.indices)
      if (index >= 0 && static_cast<std::size_t>(index) < surface.points.size())
        starts.push_back(surface.points[static_cast<std::size_t>(index)]);
  }
  for (const Point3& start : starts)
    sources.push_back({start, {start[0] + travel[0], start[1] + travel[1], start[2] + travel[2]}});
  return sources;
}

std::vector<SizeSegment> tool_size_sources(const Scene& scene) {
  std::vector<SizeSegment> sources;
  for (const SceneTool& tool : scene.tools) {
    for (std::size_t k = 0; k < tool.path.size(); ++k) {
      const ToolPose& pose = tool.path[k].pose;
      const Point3& from = pose.position;
      const Point3& to = tool.path[std::min(k + 1, tool.path.size() - 1)].pose.position;
      if (k + 1 < tool.path.size() || tool.path.size() == 1) sources.push_back({from, to});
      if (tool.shape != RigidTool::Shape::Capsule) continue;
      // The capsule's axis runs from its position along the tool's z axis: the rotation's third column.
      auto [w, x, y, z] = pose.orientation;
      const double norm = std::sqrt(w * w + x * x + y * y + z * z);
      if (!(norm > 0.0)) continue;
      w /= norm, x /= norm, y /= norm, z /= norm;
      const Point3 axis{2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)};
      sources.push_back(
          {from, {from[0] + tool.length * axis[0], from[1] + tool.length * axis[1], from[2] + tool.length * axis[2]}});
    }
  }
  return sources;
}

std::optional<Mesh> mesh_scene_surface(const Scene& scene, BuiltScene& built, DiagnosticList& diagnostics) {
  std::string contents;
  DiagnosticList read_diagnostics;
  auto surface = read_mesh_file(scene.mesh.file, read_diagnostics, &contents);
  diagnostics.append(read_diagnostics);
  if (!surface) {
    if (read_diagnostics.empty())
      diagnostics.error(scene.range_of("mesh.surface"), "mesh.surface: cannot read '" + scene.mesh.file + "'");
    return std::nullopt;
  }
  // Binary STL and PLY bodies have no lines to quote; ASCII files do.
  built.sources.emplace_back(scene.mesh.file, std::move(contents));
  MeshingRun run;
  run.options = scene.mesh.surface.options;
  SizeField& size = run.options.size;
  // Defaults: far, the surface's mean edge (or the near size given, if coarser); near, the far size.
  if (!scene.mesh.surface.size_far_given)
    size.size_far = std::max(mean_edge_length(*surface), scene.mesh.surface.size_near_given ? size.size_near : 0.0);
  if (!scene.mesh.surface.size_near_given) size.size_near = size.size_far;
  std::vector<SizeSegment> acting = probe_size_sources(scene, *surface);
  const std::vector<SizeSegment> tools = tool_size_sources(scene);
  acting.insert(acting.end(), tools.begin(), tools.end());
  size.sources.insert(size.sources.begin(), acting.begin(), acting.end());
  if (scene.mesh.surface.size_near_given && size.sources.empty())
    diagnostics.warning(scene.range_of("mesh.size_near"), "mesh-size-field",
                        "mesh.size_near: the scene has no probe, no tools and no refine_near, so nothing is near: the "
                        "mesh is size_far everywhere");
  const auto start = std::chrono::steady_clock::now();
  auto meshed = mesh_volume(std::move(*surface), run.options, diagnostics);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!meshed) {
    diagnostics.error(scene.range_of("mesh.surface"),
                      "mesh.surface: '" + scene.mesh.file + "' could not be meshed (above)");
    return std::nullopt;
  }
  Mesh mesh = std::move(meshed->mesh);
  meshed->mesh = Mesh{};
  meshed->mesh.source = mesh.source;
  run.result = std::move(*meshed);
  built.meshing = std::move(run);
  return mesh;
}

}  // namespace fmpc::sim
