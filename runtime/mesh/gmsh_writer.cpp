#include "runtime/mesh/mesh_writer.h"

#include "diagnostics/number_format.h"

namespace fmpc::sim {

std::string gmsh_document(const Mesh& mesh) {
  std::string text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" + std::to_string(mesh.points.size()) + "\n";
  text.reserve(mesh.points.size() * 64 + mesh.tetrahedra.size() * 48);
  for (std::size_t v = 0; v < mesh.points.size(); ++v) {
    const Point3& p = mesh.points[v];
    text += std::to_string(v + 1) + " " + format_number(p[0]) + " " + format_number(p[1]) + " " + format_number(p[2]) +
            "\n";
  }
  text += "$EndNodes\n$Elements\n" + std::to_string(mesh.tetrahedra.size() + mesh.triangles.size()) + "\n";
  std::size_t number = 0;
  for (const Tetrahedron& t : mesh.tetrahedra)
    text += std::to_string(++number) + " 4 2 1 1 " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
            std::to_string(t[2] + 1) + " " + std::to_string(t[3] + 1) + "\n";
  for (const Triangle& t : mesh.triangles)
    text += std::to_string(++number) + " 2 2 1 1 " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
            std::to_string(t[2] + 1) + "\n";
  text += "$EndElements\n";
  return text;
}

}  // namespace fmpc::sim
