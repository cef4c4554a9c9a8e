#pragma once
// Surfaces the meshing tests share: the unit cube as 12 outward triangles, and a face set compared whatever each
// face's starting corner and orientation.
#include <algorithm>
#include <set>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace fmpc::testing {

inline sim::Mesh unit_cube_surface() {
  sim::Mesh cube;
  cube.source = "cube";
  cube.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  cube.triangles = {{0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                    {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  return cube;
}

inline std::set<sim::Triangle> sorted_faces(const std::vector<sim::Triangle>& faces) {
  std::set<sim::Triangle> out;
  for (sim::Triangle f : faces) {
    std::sort(f.begin(), f.end());
    out.insert(f);
  }
  return out;
}

}  // namespace fmpc::testing
