#pragma once
// Cook's membrane (R. D. Cook, "Improved two-dimensional finite element", J. Struct. Div. ASCE 100, 1974): the
// trapezoid with corners (0, 0), (48, 44), (48, 60), (0, 44), clamped on its left edge, a uniform vertical shear on its
// right edge totalling 1, E = 1; the vertical displacement of the top-right corner (48, 60) is the quantity every
// element is measured by (bending with shear on skewed elements). Built in 3D as one layer of thickness 1 and run in
// plane strain (every vertex's z held), against CalculiX's 8-node quadrilaterals on a fine mesh (tests/unit/
// cook_membrane_test.cpp, docs/validation.md).
#include <filesystem>
#include <optional>
#include <string>

#include "tests/support/elastic_problem.h"

namespace fmpc::testing {

struct CookMembrane {
  ElasticProblem problem;
  std::size_t tip = 0;  // the vertex at (48, 60, 0)
};

// per_side x per_side cells in the plane (the unit square mapped bilinearly onto the trapezoid), one layer through
// the thickness, each cell split into 6 tetrahedra (generate_box); plane strain; the shear as a traction of 1/16 on
// the right face (area 16).
CookMembrane cook_membrane(int per_side, double poisson_ratio);

// CalculiX's answer with its own 2D elements: CPE8 (plane strain) or CPS8 (plane stress) 8-node quadrilaterals, with
// reduced integration (CPE8R, CPS8R) when `reduced`, on per_side x per_side cells of the same mapping, thickness 1,
// the shear as the quadratic edge's consistent loads (1/6, 2/3, 1/6 of each edge's share). Returns the top-right
// corner's vertical displacement; nullopt with `error`.
std::optional<double> calculix_cook_2d(int per_side, double poisson_ratio, bool plane_stress, bool reduced,
                                       const std::filesystem::path& folder, std::string& error);

}  // namespace fmpc::testing
