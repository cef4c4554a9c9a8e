#include "runtime/io/vtk_xml.h"

#include <sstream>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

namespace {

std::string xml_escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

void write_points(std::ostringstream& out, const std::vector<Point3>& points) {
  for (const Point3& p : points)
    out << "          " << format_number(p[0]) << ' ' << format_number(p[1]) << ' ' << format_number(p[2]) << '\n';
}

}  // namespace

std::string vtu_document(const std::vector<Point3>& points, const Mesh& cells, const std::vector<VtuPointVectors>& data) {
  const bool tetrahedra = !cells.tetrahedra.empty();
  const std::size_t cell_count = tetrahedra ? cells.tetrahedra.size() : cells.triangles.size();
  const std::size_t corners = tetrahedra ? 4 : 3;
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      << "  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << points.size() << "\" NumberOfCells=\"" << cell_count << "\">\n"
      << "      <PointData" << (data.empty() ? "" : " Vectors=\"" + xml_escape(data.front().name) + "\"") << ">\n";
  for (const VtuPointVectors& array : data) {
    out << "        <DataArray type=\"Float64\" Name=\"" << xml_escape(array.name)
        << "\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    write_points(out, array.values);
    out << "        </DataArray>\n";
  }
  out << "      </PointData>\n"
      << "      <Points>\n"
      << "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  write_points(out, points);
  out << "        </DataArray>\n"
      << "      </Points>\n"
      << "      <Cells>\n"
      << "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < cell_count; ++c) {
    out << "         ";
    for (std::size_t k = 0; k < corners; ++k)
      out << ' ' << (tetrahedra ? cells.tetrahedra[c][k] : cells.triangles[c][k]);
    out << '\n';
  }
  out << "        </DataArray>\n"
      << "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < cell_count; ++c) out << "          " << (c + 1) * corners << '\n';
  out << "        </DataArray>\n"
      << "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < cell_count; ++c) out << "          " << (tetrahedra ? 10 : 5) << '\n';
  out << "        </DataArray>\n"
      << "      </Cells>\n"
      << "    </Piece>\n"
      << "  </UnstructuredGrid>\n"
      << "</VTKFile>\n";
  return out.str();
}

std::string pvd_document(const std::vector<PvdFrame>& frames) {
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      << "  <Collection>\n";
  for (const PvdFrame& frame : frames)
    out << "    <DataSet timestep=\"" << format_number(frame.time) << "\" group=\"\" part=\"0\" file=\""
        << xml_escape(frame.file) << "\"/>\n";
  out << "  </Collection>\n"
      << "</VTKFile>\n";
  return out.str();
}

}  // namespace fmpc::sim
