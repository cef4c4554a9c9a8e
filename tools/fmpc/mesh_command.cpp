// fmpc mesh SURFACE -o OUT.msh|.vtu: a closed triangle surface (OBJ, STL, legacy VTK polydata, PLY) meshed into
// tetrahedra with a graded size field (runtime/meshing, docs/meshing.md), written for reuse as a scene's mesh.file.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

#include "diagnostics/number_format.h"
#include "runtime/io/atomic_file.h"
#include "runtime/io/vtk_xml.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/mesh_writer.h"
#include "runtime/meshing/volume_mesher.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"

namespace fmpc::cli {

namespace {

struct MeshOptions {
  std::string surface;
  std::string output;
  std::optional<double> size_near;
  std::optional<double> size_far;
  double near_distance = 0.0;
  double grading = sim::kDefaultSizeGrading;
  std::vector<std::string> near;
  double radius_edge_ratio = sim::kDefaultRadiusEdgeRatio;
  double min_dihedral = sim::kDefaultMinDihedralDegrees;
  bool smooth_intersections = false;
  bool keep_surface = false;
  bool split_surface = false;
};

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// "x,y,z" (a point) or "x,y,z,x,y,z" (a segment), mesh units.
std::optional<sim::SizeSegment> parse_near(const std::string& text, DiagnosticList& diagnostics) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    char* end = nullptr;
    const double value = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(value)) {
      values.clear();
      break;
    }
    values.push_back(value);
  }
  if (values.size() != 3 && values.size() != 6) {
    diagnostics.error(kCommandLine, "--near: '" + text +
                                        "' is neither a point x,y,z nor a segment x,y,z,x,y,z "
                                        "(finite numbers, mesh units)");
    return std::nullopt;
  }
  sim::SizeSegment segment;
  segment.a = {values[0], values[1], values[2]};
  segment.b = values.size() == 6 ? sim::Point3{values[3], values[4], values[5]} : segment.a;
  return segment;
}

// The mesh as VTK XML in mesh units, each tetrahedron with its radius-edge ratio and smallest dihedral angle.
std::optional<std::string> vtu_with_quality(const sim::Mesh& mesh, DiagnosticList& diagnostics) {
  sim::VtuOptions options;
  const auto cells = sim::encode_vtu_cells(mesh, options, diagnostics);
  if (!cells) return std::nullopt;
  std::vector<double> ratio, dihedral;
  for (const sim::Tetrahedron& t : mesh.tetrahedra) {
    const sim::ElementShape shape = sim::element_shape(mesh, t);
    ratio.push_back(shape.radius_edge_ratio);
    dihedral.push_back(shape.min_dihedral_degrees);
  }
  return sim::vtu_document(
      mesh.points, *cells, {},
      {sim::vtu_scalars("radius_edge_ratio", ratio), sim::vtu_scalars("min_dihedral_degrees", dihedral)}, options,
      diagnostics);
}

int run_mesh(const MeshOptions& options) {
  DiagnosticList diagnostics;
  SourceFiles sources;
  const bool msh = ends_with(options.output, ".msh"), vtu = ends_with(options.output, ".vtu");
  if (!msh && !vtu) diagnostics.error(kCommandLine, "-o: '" + options.output + "' must end in .msh (Gmsh 2.2) or .vtu");
  sim::VolumeMeshOptions mesh_options;
  mesh_options.size.near_distance = options.near_distance;
  mesh_options.size.grading = options.grading;
  mesh_options.max_radius_edge_ratio = options.radius_edge_ratio;
  mesh_options.min_dihedral_degrees = options.min_dihedral;
  mesh_options.smooth_intersections = options.smooth_intersections;
  mesh_options.keep_surface = options.keep_surface;
  mesh_options.split_surface = options.split_surface;
  if (options.split_surface && !options.keep_surface)
    diagnostics.error(kCommandLine, "--split-surface splits a kept surface: add --keep-surface (without it the mesher "
                                    "splits the surface itself)");
  if (!(options.radius_edge_ratio >= 1.0))
    diagnostics.error(kCommandLine,
                      "--radius-edge: " + format_number(options.radius_edge_ratio) +
                          " is below 1; Delaunay refinement needs a bound of at least 1 (1.2 to 2 is usual)");
  if (!(options.min_dihedral >= 0.0 && options.min_dihedral <= 30.0))
    diagnostics.error(kCommandLine, "--min-dihedral: " + format_number(options.min_dihedral) +
                                        " is not from 0 to 30 degrees (TetGen cannot reach more)");
  for (const std::string& text : options.near)
    if (auto segment = parse_near(text, diagnostics)) mesh_options.size.sources.push_back(*segment);
  if (diagnostics.has_errors()) {
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  std::string text;
  auto surface = sim::read_mesh_file(options.surface, diagnostics, &text);
  if (!ends_with(options.surface, ".stl")) sources.add(options.surface, text);
  if (!surface) {
    diagnostics.sort_by_position();
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  mesh_options.size.size_far =
      options.size_far.value_or(std::max(sim::mean_edge_length(*surface), options.size_near.value_or(0.0)));
  mesh_options.size.size_near = options.size_near.value_or(mesh_options.size.size_far);
  sim::SizeOptionNames names{"--size-near", "--size-far", "--near-distance", "--grading"};
  for (const std::string& problem : sim::size_field_problems(mesh_options.size, names))
    diagnostics.error(kCommandLine, problem);
  if (diagnostics.has_errors()) {
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  const auto start = std::chrono::steady_clock::now();
  auto meshed = sim::mesh_volume(std::move(*surface), mesh_options, diagnostics);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (meshed) {
    const auto document = msh ? std::optional<std::string>(sim::gmsh_document(meshed->mesh))
                              : vtu_with_quality(meshed->mesh, diagnostics);
    if (document && !sim::write_file_atomically(options.output, *document, diagnostics)) meshed.reset();
    if (!document) meshed.reset();
  }
  diagnostics.sort_by_position();
  print_diagnostics(diagnostics, sources, std::cerr);
  if (!meshed) return kExitErrors;
  std::cout << sim::quality_text(*meshed, mesh_options) << "  meshing took " << significant_digits(seconds, 3)
            << " s; wrote " << options.output << "\n";
  return kExitOk;
}

}  // namespace

void register_mesh_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<MeshOptions>();
  CLI::App* command =
      app.add_subcommand("mesh",
                         "Mesh a closed surface (OBJ, STL, VTK polydata, PLY) into tetrahedra with a graded size field "
                         "(docs/meshing.md)");
  command->add_option("SURFACE", options->surface, "Closed, consistently oriented triangle surface")->required();
  command
      ->add_option("-o,--output", options->output,
                   "The volume mesh: .msh (Gmsh 2.2, a scene's mesh.file) or "
                   ".vtu (with each element's quality)")
      ->required();
  command->add_option("--size-far", options->size_far,
                      "Longest edge allowed far from every --near (mesh units; default: the surface's mean edge)");
  command->add_option("--size-near", options->size_near,
                      "Longest edge allowed within --near-distance of a --near (mesh units; default: --size-far)");
  command->add_option("--near-distance", options->near_distance, "How far --size-near reaches (mesh units)");
  command->add_option("--grading", options->grading,
                      "Growth of the allowed edge per unit of distance beyond --near-distance");
  command->add_option("--near", options->near,
                      "Where the tissue is worked on: a point x,y,z or a segment x,y,z,x,y,z (mesh units); repeatable");
  command->add_option("--radius-edge", options->radius_edge_ratio,
                      "Largest radius-edge ratio (circumradius / shortest edge) refinement allows");
  command->add_option("--min-dihedral", options->min_dihedral,
                      "Smallest dihedral angle (degrees) TetGen refines and optimises toward (not guaranteed)");
  command->add_flag("--smooth-intersections", options->smooth_intersections,
                    "Smooth the vertices of self-intersecting triangles until none intersect (reported)");
  command->add_flag("--keep-surface", options->keep_surface,
                    "Keep the surface's triangles as the boundary faces, refining only the interior (default: the "
                    "mesher splits them where the size field asks)");
  command->add_flag("--split-surface", options->split_surface,
                    "With --keep-surface: split the surface's triangles coarser than the size field first (at their "
                    "edges' midpoints: the same polyhedron)");
  command->callback([options, &exit_code] { exit_code = run_mesh(*options); });
}

}  // namespace fmpc::cli
