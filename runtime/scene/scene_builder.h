#pragma once
// From a parsed Scene to what runs: the mesh (read or generated, repaired), the spring model with its material
// (fuzzy rules or a table evaluated for the bindings, Van Gelder or Lloyd-Szekely-Harders mapping), fixed vertices,
// loads and probe, the integrator settings. Only what the scene uses is built: no strain table without a strain
// binding, no force arrays without force loads, no probe without a probe.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/mesh.h"
#include "runtime/meshing/volume_mesher.h"
#include "runtime/scene/material_binding.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

struct BuiltScene {
  Mesh mesh;  // repaired, in mesh units (frames are written in metres from the setup)
  SimulationSetup setup;
  std::optional<MaterialBinding> material;  // rules or table
  std::string stiffness_description;        // for the summary, e.g. "Van Gelder 1998, E = 9.8 kPa"
  std::optional<MeshingRun> meshing;        // `mesh: {surface: FILE}`: how the surface was meshed
  // Files read while building, with their text, so that diagnostics located in them can show the line.
  std::vector<std::pair<std::string, std::string>> sources;
};

// A rule file read and loaded once for many builds (a cohort's patients share it): build_scene then reads and parses
// nothing for a scene whose material.rules is `path`. The caller checked that it loaded without errors.
struct LoadedRules {
  std::string path;
  std::string text;
  RuleFile rules;
};

// Builds everything; returns nullopt after appending errors (located at the scene's fields where they come from
// the scene). Mesh repairs are reported as one warning. `refinements` > 0 subdivides the repaired mesh that many
// times (subdivide_tetrahedra, 8 tetrahedra per tetrahedron each time) before anything is built on it: fixed sets,
// holds, the probe's ray pick and regions are selected on the refined mesh, and the mesh's vertices keep their
// indices (vertex indices in the scene still name them). The caller bounds the size first (each refinement
// multiplies the tetrahedra by 8).
std::optional<BuiltScene> build_scene(const Scene& scene, DiagnosticList& diagnostics, unsigned refinements = 0,
                                      const LoadedRules* rules = nullptr);

// The modulus a strain table gives at strain 0 (Pa): what sets the damping coefficients and the summary's E.
double strain_table_rest_modulus(const StrainStiffnessTable& table);

// Möller-Trumbore: the distance t >= 0 along `direction` (any length; t is in its units) at which the ray from
// `origin` hits triangle abc, or nullopt.
std::optional<double> ray_triangle_hit(const Point3& origin, const Point3& direction, const Point3& a, const Point3& b,
                                       const Point3& c);

}  // namespace fmpc::sim
