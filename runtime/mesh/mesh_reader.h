#pragma once
// Mesh file readers. Each returns the mesh, or nullopt after appending at least one error naming file:line and
// what to do. Warnings (ignored element types, ignored attributes) are appended too. Points keep file units.
#include <optional>
#include <string>
#include <string_view>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// Gmsh ASCII: v1 ($NOD/$ELM, as SOFA's liver.msh), v2.x and v4.1 ($MeshFormat). Tetrahedra (type 4) and
// triangles (type 2) are kept; points and lines are skipped; other element types are skipped with a warning.
std::optional<Mesh> read_gmsh(std::string_view text, const std::string& file, DiagnosticList& diagnostics);
// Wavefront OBJ: `v` and `f` records (v, v/vt, v//vn, v/vt/vn, negative indices); polygons are fanned into
// triangles; other records are ignored.
std::optional<Mesh> read_obj(std::string_view text, const std::string& file, DiagnosticList& diagnostics);
// Legacy VTK (versions 2-4 layout), ASCII or BINARY (big-endian), DATASET POLYDATA (POLYGONS) or
// UNSTRUCTURED_GRID (CELLS/CELL_TYPES: tetra 10, triangle 5). Attribute data (POINT_DATA, CELL_DATA) is ignored.
std::optional<Mesh> read_vtk(std::string_view bytes, const std::string& file, DiagnosticList& diagnostics);

// STL, ASCII or binary (told apart by the size a binary file must have): corners with equal coordinates become one
// vertex (numbered by first appearance); facet normals are ignored (the corners' order orients a facet).
std::optional<Mesh> read_stl(std::string_view bytes, const std::string& file, DiagnosticList& diagnostics);
// PLY, ASCII or binary little-endian: `vertex` x, y, z and `face` vertex_indices (or vertex_index) lists, polygons
// fanned into triangles; other elements and properties are read past.
std::optional<Mesh> read_ply(std::string_view bytes, const std::string& file, DiagnosticList& diagnostics);

// Reads `path` and picks the reader from its extension (.msh, .obj, .vtk, .stl, .ply). `contents`, when given,
// receives the file's bytes (for diagnostics that quote a line).
std::optional<Mesh> read_mesh_file(const std::string& path, DiagnosticList& diagnostics,
                                   std::string* contents = nullptr);

}  // namespace fmpc::sim
