#pragma once
// `mesh: {surface: FILE, ...}` (docs/scenes.md): the surface read and meshed into tetrahedra, the size field fine
// where the scene's probe acts (the point its ray hits, or its picked vertices, and the path its displacement takes
// it along), where its rigid tools go (their paths and a capsule's axis), and at `refine_near`.
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"
#include "runtime/meshing/size_field.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

// Where the probe acts on the surface (mesh units): from each start (the ray's first hit, or each picked vertex) a
// segment along the probe's displacement (its target in metres over mesh.units), or a point for a force probe. Picks
// that miss or name no vertex give nothing here; the scene builder reports them on the meshed volume.
std::vector<SizeSegment> probe_size_sources(const Scene& scene, const Mesh& surface);

// Where the scene's rigid tools act (mesh units): each tool's path (the segments between its keyframes' positions,
// or its one position), and a capsule's axis at every keyframe.
std::vector<SizeSegment> tool_size_sources(const Scene& scene);

// Reads and meshes the scene's surface; the surface's text goes to built.sources and the run to built.meshing.
std::optional<Mesh> mesh_scene_surface(const Scene& scene, BuiltScene& built, DiagnosticList& diagnostics);

}  // namespace fmpc::sim
