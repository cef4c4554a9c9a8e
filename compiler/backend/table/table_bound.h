#pragma once
// The derived bound over a whole table (docs/compiler.md, "Error statement"): every cell of the grid bounded with
// cell_bound.h's CellBounder, in blocks where the rules are flat and by subdivision where a single cell's bound is
// loose, and for each cell the axis to split it along. Internal to the table builder (table_builder.h).
#include <cstddef>
#include <vector>

#include "compiler/backend/table/cell_bound.h"
#include "compiler/backend/table/table_builder.h"
#include "compiler/backend/table/table_points.h"

namespace fmpc::table_build {

// Per cell of the current grid (flat index, last axis fastest): its bound and, for refinement, the refinable axis
// to split it along.
struct CellBounds {
  std::vector<double> bound;
  std::vector<int> split;  // -1 where no refinable axis would help
  std::size_t worst = 0;
  std::vector<std::size_t> counts;  // cells per axis
  std::size_t size() const { return bound.size(); }
};

// The cell with flat index `cell` (last axis fastest): its lower breakpoint index per axis.
void cell_origin(std::size_t cell, const std::vector<std::size_t>& counts, std::vector<std::size_t>& origin);

// The centre of cell `cell` (only cells.counts is read).
std::vector<double> cell_centre(const LookupTable& table, const CellBounds& cells, std::size_t cell);

// Bounds every cell of the table's grid against `goal` (the target less what the passes and the interpreter's
// rounding take), `rounding` being the stored values' |stored - computed| (GridBuilder::rounding), with one
// CellBounder and one interpreter per thread. Adds the evaluations and bounds it made to `stats`.
CellBounds bound_cells(const LookupTable& table, const std::vector<double>& rounding,
                       std::vector<CellBounder>& bounders, Evaluators& evaluators, const std::vector<bool>& refinable,
                       double goal, int threads, TableBuildStatistics& stats);

}  // namespace fmpc::table_build
