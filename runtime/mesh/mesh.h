#pragma once
// A simulation mesh as plain data: points and the elements that reference them by 0-based index. Readers fill it
// from files, generators build it in code; nothing here prints or touches the file system.
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace fmpc::sim {

using Point3 = std::array<double, 3>;
using Tetrahedron = std::array<std::int32_t, 4>;
using Triangle = std::array<std::int32_t, 3>;

inline bool finite_point(const Point3& p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

struct Mesh {
  std::vector<Point3> points;
  std::vector<Tetrahedron> tetrahedra;  // positive orientation: signed_volume > 0
  std::vector<Triangle> triangles;      // surface or membrane triangles
  // Where an element came from in its file (1-based line), parallel to the element arrays, so that findings can
  // point back at the source. Shorter arrays are allowed: a missing entry reads as 0 (unknown); generated meshes
  // leave them empty.
  std::vector<int> tetrahedron_lines;
  std::vector<int> triangle_lines;
  std::string source;  // file path, or a description such as "generated box 4x4x4"

  std::size_t vertex_count() const { return points.size(); }
};

// (b - a) x (c - a) . (d - a) / 6: positive when d lies on the side of triangle abc its normal points to.
double signed_volume(const Point3& a, const Point3& b, const Point3& c, const Point3& d);
double signed_volume(const Mesh& mesh, const Tetrahedron& tetrahedron);
double triangle_area(const Point3& a, const Point3& b, const Point3& c);
double triangle_area(const Mesh& mesh, const Triangle& triangle);
double distance(const Point3& a, const Point3& b);
// The square of distance(a, b) before its square root: distance(a, b) == std::sqrt(squared_distance(a, b)).
double squared_distance(const Point3& a, const Point3& b);

class WorkerPool;  // runtime/integrate/worker_pool.h

// Triangles that belong to exactly one tetrahedron, oriented outwards (used to draw or export a volume mesh), sorted
// by their sorted vertex triples. Needs fewer than 2^31 faces (4 per tetrahedron); null pool: one of its own.
std::vector<Triangle> boundary_triangles(const Mesh& mesh, WorkerPool* pool = nullptr);

}  // namespace fmpc::sim
