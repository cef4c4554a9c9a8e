#include "runtime/meshing/mesh_quality.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fmpc::sim {

namespace {

Point3 sub(const Point3& p, const Point3& q) { return {p[0] - q[0], p[1] - q[1], p[2] - q[2]}; }
Point3 cross(const Point3& p, const Point3& q) {
  return {p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
}
double dot(const Point3& p, const Point3& q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; }

}  // namespace

Distribution distribution_of(std::vector<double> values) {
  Distribution d;
  if (values.empty()) return d;
  std::sort(values.begin(), values.end());
  const auto rank = [&](double percent) {
    const auto r = static_cast<std::size_t>(std::ceil(percent / 100.0 * static_cast<double>(values.size())));
    return values[std::min(values.size() - 1, r == 0 ? 0 : r - 1)];
  };
  d.min = values.front();
  d.p1 = rank(1);
  d.p5 = rank(5);
  d.p50 = rank(50);
  d.p95 = rank(95);
  d.p99 = rank(99);
  d.max = values.back();
  return d;
}

// The circumcentre relative to a is (|u|^2 (v x w) + |v|^2 (w x u) + |w|^2 (u x v)) / (2 u . (v x w)) with
// u = b - a, v = c - a, w = d - a.
double circumradius(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  const Point3 u = sub(b, a), v = sub(c, a), w = sub(d, a);
  const double denominator = 2.0 * dot(u, cross(v, w));
  if (denominator == 0.0) return std::numeric_limits<double>::infinity();
  const Point3 vw = cross(v, w), wu = cross(w, u), uv = cross(u, v);
  const double uu = dot(u, u), vv = dot(v, v), ww = dot(w, w);
  const Point3 centre{(uu * vw[0] + vv * wu[0] + ww * uv[0]) / denominator,
                      (uu * vw[1] + vv * wu[1] + ww * uv[1]) / denominator,
                      (uu * vw[2] + vv * wu[2] + ww * uv[2]) / denominator};
  return std::sqrt(dot(centre, centre));
}

// The dihedral angle at the edge shared by the faces opposite vertices k and l is pi minus the angle between those
// faces' outward normals.
double min_dihedral_degrees(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  const Point3* p[4] = {&a, &b, &c, &d};
  Point3 normal[4];
  for (std::size_t k = 0; k < 4; ++k) {
    const Point3& x = *p[(k + 1) % 4];
    const Point3& y = *p[(k + 2) % 4];
    const Point3& z = *p[(k + 3) % 4];
    Point3 n = cross(sub(y, x), sub(z, x));
    if (dot(n, sub(*p[k], x)) > 0.0) n = {-n[0], -n[1], -n[2]};  // away from the opposite vertex
    normal[k] = n;
  }
  double smallest = 180.0;
  for (std::size_t k = 0; k < 4; ++k) {
    for (std::size_t l = k + 1; l < 4; ++l) {
      const double lengths = std::sqrt(dot(normal[k], normal[k]) * dot(normal[l], normal[l]));
      if (!(lengths > 0.0)) return 0.0;
      const double cosine = std::clamp(dot(normal[k], normal[l]) / lengths, -1.0, 1.0);
      smallest = std::min(smallest, 180.0 - std::acos(cosine) * 180.0 / M_PI);
    }
  }
  return smallest;
}

ElementShape element_shape(const Mesh& mesh, const Tetrahedron& t) {
  const Point3& a = mesh.points[static_cast<std::size_t>(t[0])];
  const Point3& b = mesh.points[static_cast<std::size_t>(t[1])];
  const Point3& c = mesh.points[static_cast<std::size_t>(t[2])];
  const Point3& d = mesh.points[static_cast<std::size_t>(t[3])];
  const double edges[6] = {distance(a, b), distance(a, c), distance(a, d),
                           distance(b, c), distance(b, d), distance(c, d)};
  ElementShape shape;
  shape.radius_edge_ratio = circumradius(a, b, c, d) / *std::min_element(edges, edges + 6);
  shape.min_dihedral_degrees = min_dihedral_degrees(a, b, c, d);
  shape.longest_edge = *std::max_element(edges, edges + 6);
  shape.volume = signed_volume(a, b, c, d);
  return shape;
}

TetrahedronQuality measure_quality(const Mesh& mesh, double ratio_bound, double dihedral_bound) {
  TetrahedronQuality quality;
  quality.tetrahedra = mesh.tetrahedra.size();
  std::vector<double> ratio, dihedral, longest;
  ratio.reserve(mesh.tetrahedra.size());
  dihedral.reserve(mesh.tetrahedra.size());
  longest.reserve(mesh.tetrahedra.size());
  std::vector<unsigned char> on_boundary(mesh.points.size(), 0);
  for (const Triangle& face : boundary_triangles(mesh))
    for (const auto v : face) on_boundary[static_cast<std::size_t>(v)] = 1;
  for (const Tetrahedron& t : mesh.tetrahedra) {
    const ElementShape shape = element_shape(mesh, t);
    quality.volume += shape.volume;
    quality.non_positive += shape.volume <= 0.0;
    quality.above_ratio_bound += shape.radius_edge_ratio > ratio_bound;
    quality.above_ratio_bound_inside +=
        shape.radius_edge_ratio > ratio_bound && !on_boundary[static_cast<std::size_t>(t[0])] &&
        !on_boundary[static_cast<std::size_t>(t[1])] && !on_boundary[static_cast<std::size_t>(t[2])] &&
        !on_boundary[static_cast<std::size_t>(t[3])];
    quality.below_dihedral_bound += shape.min_dihedral_degrees < dihedral_bound;
    ratio.push_back(shape.radius_edge_ratio);
    dihedral.push_back(shape.min_dihedral_degrees);
    longest.push_back(shape.longest_edge);
  }
  quality.radius_edge_ratio = distribution_of(std::move(ratio));
  quality.min_dihedral_degrees = distribution_of(std::move(dihedral));
  quality.longest_edge = distribution_of(std::move(longest));
  return quality;
}

}  // namespace fmpc::sim
