#include "runtime/meshing/surface_untangle.h"

#include <algorithm>

#include "runtime/meshing/surface_check.h"
#include "runtime/meshing/tetgen_mesher.h"

namespace fmpc::sim {

void report_self_intersections(const Mesh& surface, const std::vector<std::size_t>& triangles,
                               DiagnosticList& diagnostics) {
  std::string list;
  for (std::size_t i = 0; i < triangles.size() && i < kMaxSurfaceDefectsListed; ++i)
    list += (i == 0 ? "" : ", ") + std::to_string(triangles[i]);
  if (triangles.size() > kMaxSurfaceDefectsListed) list += ", ...";
  for (std::size_t i = 0; i < triangles.size() && i < kMaxSurfaceDefectsListed; ++i)
    diagnostics.error(
        triangle_range(surface, triangles[i]),
        triangle_name(surface, triangles[i]) + " intersects another part of the surface" +
            (i > 0 ? std::string() : " (" + std::to_string(triangles.size()) + " triangles do: " + list + ")"),
        i > 0 ? std::vector<std::string>{}
              : std::vector<std::string>{
                    "fix the surface, or set mesh.smooth_intersections: true (fmpc mesh --smooth-intersections) "
                    "to move their vertices toward their neighbours until the surface is free of them"});
  if (triangles.size() > kMaxSurfaceDefectsListed)
    diagnostics.error(
        SourceRange{surface.source, 0, 0, 0, 0},
        std::to_string(triangles.size() - kMaxSurfaceDefectsListed) + " more intersecting triangles are not listed");
}

std::optional<SurfaceUntangling> untangle_surface(Mesh& surface, std::vector<std::size_t> intersecting,
                                                  DiagnosticList& diagnostics) {
  SurfaceUntangling result;
  result.intersecting_triangles = intersecting.size();
  std::vector<std::vector<std::int32_t>> neighbours(surface.points.size());
  for (const Triangle& t : surface.triangles)
    for (std::size_t k = 0; k < 3; ++k) {
      neighbours[static_cast<std::size_t>(t[k])].push_back(t[(k + 1) % 3]);
      neighbours[static_cast<std::size_t>(t[(k + 1) % 3])].push_back(t[k]);
    }
  for (auto& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  const std::vector<Point3> original = surface.points;
  std::vector<unsigned char> moved(surface.points.size(), 0);
  while (!intersecting.empty()) {
    if (result.rounds == kMaxUntangleRounds) {
      diagnostics.error(SourceRange{surface.source, 0, 0, 0, 0},
                        "smoothing did not free the surface of self-intersections in " +
                            std::to_string(kMaxUntangleRounds) + " rounds; these remain:");
      report_self_intersections(surface, intersecting, diagnostics);
      return std::nullopt;
    }
    ++result.rounds;
    // The intersecting triangles' vertices, widened by one ring per round after the first.
    std::vector<unsigned char> chosen(surface.points.size(), 0);
    for (const std::size_t t : intersecting)
      for (const auto v : surface.triangles[t]) chosen[static_cast<std::size_t>(v)] = 1;
    for (std::size_t ring = 1; ring < result.rounds; ++ring) {
      std::vector<unsigned char> wider = chosen;
      for (std::size_t v = 0; v < chosen.size(); ++v)
        if (chosen[v])
          for (const auto u : neighbours[v]) wider[static_cast<std::size_t>(u)] = 1;
      chosen.swap(wider);
    }
    const std::vector<Point3> before = surface.points;
    for (std::size_t v = 0; v < chosen.size(); ++v) {
      if (!chosen[v] || neighbours[v].empty()) continue;
      Point3 mean{0.0, 0.0, 0.0};
      for (const auto u : neighbours[v])
        for (std::size_t a = 0; a < 3; ++a) mean[a] += before[static_cast<std::size_t>(u)][a];
      for (std::size_t a = 0; a < 3; ++a) mean[a] /= static_cast<double>(neighbours[v].size());
      surface.points[v] = mean;
      moved[v] = 1;
    }
    auto again = tetgen_self_intersections(surface, diagnostics);
    if (!again) return std::nullopt;
    intersecting = std::move(*again);
  }
  for (std::size_t v = 0; v < moved.size(); ++v) {
    if (!moved[v]) continue;
    ++result.moved_vertices;
    result.largest_move = std::max(result.largest_move, distance(original[v], surface.points[v]));
  }
  return result;
}

}  // namespace fmpc::sim
