#include "runtime/meshing/size_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fmpc::sim {

double mean_edge_length(const Mesh& surface) {
  double sum = 0.0;
  for (const Triangle& t : surface.triangles)
    for (std::size_t k = 0; k < 3; ++k)
      sum += distance(surface.points[static_cast<std::size_t>(t[k])],
                      surface.points[static_cast<std::size_t>(t[(k + 1) % 3])]);
  return surface.triangles.empty() ? 0.0 : sum / (3.0 * static_cast<double>(surface.triangles.size()));
}

double distance_to_segment(const Point3& p, const SizeSegment& segment) {
  const Point3& a = segment.a;
  const Point3& b = segment.b;
  const double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
  const double length2 = dx * dx + dy * dy + dz * dz;
  double t = 0.0;
  if (length2 > 0.0) {
    t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy + (p[2] - a[2]) * dz) / length2;
    t = std::clamp(t, 0.0, 1.0);
  }
  return distance(p, Point3{a[0] + t * dx, a[1] + t * dy, a[2] + t * dz});
}

double size_at(const SizeField& field, const Point3& p) {
  if (field.sources.empty()) return field.size_far;
  double nearest = std::numeric_limits<double>::infinity();
  for (const SizeSegment& source : field.sources) nearest = std::min(nearest, distance_to_segment(p, source));
  const double beyond = std::max(0.0, nearest - field.near_distance);
  return std::min(field.size_far, field.size_near + field.grading * beyond);
}

VolumeEstimate estimate_tetrahedra(const Mesh& surface, const SizeField& field) {
  VolumeEstimate estimate;
  if (surface.points.empty() || surface.triangles.empty()) return estimate;
  Point3 low = surface.points.front(), high = low;
  for (const Point3& p : surface.points)
    for (std::size_t a = 0; a < 3; ++a) low[a] = std::min(low[a], p[a]), high[a] = std::max(high[a], p[a]);
  // A grid of kCells^3 cells; each (y, z) column is a ray along x whose crossings with the surface give the inside
  // intervals (parity). The columns sit off the cell centres by fractions that differ in y and z (so that no column
  // runs along a diagonal y = z either) so that a ray through a generated surface's vertices or edges, which would
  // count a crossing twice or not at all, is unlikely; a column with an odd count is left out.
  constexpr std::size_t kCells = 40;
  constexpr double kOffsetY = 0.5 + 0.0123456789, kOffsetZ = 0.5 + 0.0319753197;
  const double sx = (high[0] - low[0]) / kCells, sy = (high[1] - low[1]) / kCells, sz = (high[2] - low[2]) / kCells;
  if (!(sx > 0.0 && sy > 0.0 && sz > 0.0)) return estimate;
  std::vector<std::vector<double>> crossings(kCells * kCells);
  for (const Triangle& tri : surface.triangles) {
    const Point3& a = surface.points[static_cast<std::size_t>(tri[0])];
    const Point3& b = surface.points[static_cast<std::size_t>(tri[1])];
    const Point3& c = surface.points[static_cast<std::size_t>(tri[2])];
    const auto column_range = [&](std::size_t axis, double step, double offset) {
      const double lo = (std::min({a[axis], b[axis], c[axis]}) - low[axis]) / step - offset;
      const double hi = (std::max({a[axis], b[axis], c[axis]}) - low[axis]) / step - offset;
      const auto first = static_cast<std::size_t>(std::max(0.0, std::ceil(lo)));
      const auto last = static_cast<std::size_t>(std::clamp(std::floor(hi), -1.0, double(kCells) - 1.0) + 1.0);
      return std::pair<std::size_t, std::size_t>{first, last};
    };
    const auto [j0, j1] = column_range(1, sy, kOffsetY);
    const auto [k0, k1] = column_range(2, sz, kOffsetZ);
    // Barycentric coordinates of the column's (y, z) in the triangle's projection on the y-z plane.
    const double det = (b[1] - a[1]) * (c[2] - a[2]) - (c[1] - a[1]) * (b[2] - a[2]);
    if (det == 0.0) continue;  // parallel to the rays
    for (std::size_t j = j0; j < j1; ++j) {
      for (std::size_t k = k0; k < k1; ++k) {
        const double y = low[1] + (static_cast<double>(j) + kOffsetY) * sy;
        const double z = low[2] + (static_cast<double>(k) + kOffsetZ) * sz;
        const double u = ((y - a[1]) * (c[2] - a[2]) - (c[1] - a[1]) * (z - a[2])) / det;
        const double v = ((b[1] - a[1]) * (z - a[2]) - (y - a[1]) * (b[2] - a[2])) / det;
        if (u < 0.0 || v < 0.0 || u + v > 1.0) continue;
        crossings[j * kCells + k].push_back(a[0] + u * (b[0] - a[0]) + v * (c[0] - a[0]));
      }
    }
  }
  const double cell_volume = sx * sy * sz;
  for (std::size_t j = 0; j < kCells; ++j) {
    for (std::size_t k = 0; k < kCells; ++k) {
      std::vector<double>& xs = crossings[j * kCells + k];
      if (xs.size() % 2 != 0) continue;  // a ray through an edge: the column is left out
      std::sort(xs.begin(), xs.end());
      const double y = low[1] + (static_cast<double>(j) + kOffsetY) * sy;
      const double z = low[2] + (static_cast<double>(k) + kOffsetZ) * sz;
      for (std::size_t i = 0; i < kCells; ++i) {
        const double x = low[0] + (static_cast<double>(i) + 0.5) * sx;
        const std::size_t before = static_cast<std::size_t>(std::upper_bound(xs.begin(), xs.end(), x) - xs.begin());
        if (before % 2 == 0) continue;
        const double h = size_at(field, Point3{x, y, z});
        estimate.volume += cell_volume;
        estimate.tetrahedra += kTetrahedraPerSizeCube * cell_volume / (h * h * h);
      }
    }
  }
  return estimate;
}

}  // namespace fmpc::sim
