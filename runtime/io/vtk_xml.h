#pragma once
// VTK XML files for ParaView: one UnstructuredGrid (.vtu, ASCII) per frame and a .pvd collection that lists the
// frames with their times (VTK file formats, "XML File Formats": UnstructuredGrid and Collection).
#include <string>
#include <utility>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

struct VtuPointVectors {
  std::string name;             // e.g. "displacement" (m)
  std::vector<Point3> values;   // one per point
};

// A frame: the points (m), the tetrahedra (VTK_TETRA 10) or, without them, the triangles (VTK_TRIANGLE 5), and
// per-point vector arrays. Numbers are written with format_number (shortest text that reads back exactly).
std::string vtu_document(const std::vector<Point3>& points, const Mesh& cells, const std::vector<VtuPointVectors>& data);

struct PvdFrame {
  double time = 0.0;  // s
  std::string file;   // relative to the .pvd
};
std::string pvd_document(const std::vector<PvdFrame>& frames);

}  // namespace fmpc::sim
