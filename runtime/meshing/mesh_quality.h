#pragma once
// Shape measures of a tetrahedral mesh: the radius-edge ratio (circumradius / shortest edge; sqrt(6)/4 = 0.612 for
// the regular tetrahedron, the measure Delaunay refinement bounds: Shewchuk 1998, Si 2015) and the smallest dihedral
// angle (70.53 degrees for the regular tetrahedron; slivers have a small one at a fair radius-edge ratio), each as
// a distribution over the elements.
#include <cstddef>
#include <limits>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// Nearest-rank percentiles of a sample.
struct Distribution {
  double min = 0.0, p1 = 0.0, p5 = 0.0, p50 = 0.0, p95 = 0.0, p99 = 0.0, max = 0.0;
};
Distribution distribution_of(std::vector<double> values);

struct TetrahedronQuality {
  std::size_t tetrahedra = 0;
  Distribution radius_edge_ratio;
  Distribution min_dihedral_degrees;         // each element's smallest of its six dihedral angles
  Distribution longest_edge;                 // mesh units
  double volume = 0.0;                       // the sum of the elements' signed volumes (mesh units^3)
  std::size_t non_positive = 0;              // elements with signed volume <= 0
  std::size_t above_ratio_bound = 0;         // elements with a radius-edge ratio above the bound given
  std::size_t above_ratio_bound_inside = 0;  // of those, the ones with no vertex on the boundary
  std::size_t below_dihedral_bound = 0;      // elements with a smallest dihedral angle below the bound given
};

double circumradius(const Point3& a, const Point3& b, const Point3& c, const Point3& d);
// The six dihedral angles' smallest (degrees).
double min_dihedral_degrees(const Point3& a, const Point3& b, const Point3& c, const Point3& d);

struct ElementShape {
  double radius_edge_ratio = 0.0;
  double min_dihedral_degrees = 0.0;
  double longest_edge = 0.0;
  double volume = 0.0;  // signed
};
ElementShape element_shape(const Mesh& mesh, const Tetrahedron& tetrahedron);
// The distributions, and the elements outside the bounds (infinite and 0 bounds count none).
TetrahedronQuality measure_quality(const Mesh& mesh, double ratio_bound = std::numeric_limits<double>::infinity(),
                                   double dihedral_bound = 0.0);

}  // namespace fmpc::sim
