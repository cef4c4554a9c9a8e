#include "runtime/mesh/mesh.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace fmpc::sim {

double signed_volume(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  return ((uy * vz - uz * vy) * wx + (uz * vx - ux * vz) * wy + (ux * vy - uy * vx) * wz) / 6.0;
}

double signed_volume(const Mesh& mesh, const Tetrahedron& t) {
  return signed_volume(mesh.points[static_cast<std::size_t>(t[0])], mesh.points[static_cast<std::size_t>(t[1])],
                       mesh.points[static_cast<std::size_t>(t[2])], mesh.points[static_cast<std::size_t>(t[3])]);
}

double triangle_area(const Point3& a, const Point3& b, const Point3& c) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  return 0.5 * std::sqrt(nx * nx + ny * ny + nz * nz);
}

double triangle_area(const Mesh& mesh, const Triangle& t) {
  return triangle_area(mesh.points[static_cast<std::size_t>(t[0])], mesh.points[static_cast<std::size_t>(t[1])],
                       mesh.points[static_cast<std::size_t>(t[2])]);
}

double distance(const Point3& a, const Point3& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

std::vector<Triangle> boundary_triangles(const Mesh& mesh) {
  // Faces of a positively oriented tetrahedron (a,b,c,d) with outward normals.
  std::map<std::array<std::int32_t, 3>, std::pair<Triangle, int>> faces;
  for (const Tetrahedron& t : mesh.tetrahedra) {
    const Triangle oriented[4] = {{t[0], t[2], t[1]}, {t[0], t[1], t[3]}, {t[1], t[2], t[3]}, {t[0], t[3], t[2]}};
    for (const Triangle& face : oriented) {
      std::array<std::int32_t, 3> key = face;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, face, 0);
      ++it->second.second;
      (void)inserted;
    }
  }
  std::vector<Triangle> boundary;
  for (const auto& entry : faces) {
    if (entry.second.second == 1) boundary.push_back(entry.second.first);
  }
  return boundary;
}

}  // namespace fmpc::sim
