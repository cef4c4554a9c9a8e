#pragma once
// The estimated error of a table (docs/compiler.md, "Error statement"), for rule bases the derived bound does not
// cover: the largest error found on a held-out set, at every cell's centre and by local searches from the worst of
// them. Internal to the table builder (table_builder.h).
#include <vector>

#include "compiler/backend/table/table_builder.h"
#include "compiler/backend/table/table_points.h"

namespace fmpc::table_build {

struct Estimate {
  double error = 0.0;
  std::vector<double> location;
  std::vector<double> above_target;  // points found above --max-error (row-major)
};

// The largest |table - reference| on `held_out`, at every cell's centre, and by compass searches (each axis in
// turn, +- a step that starts at a quarter of the point's cell and halves when no move improves) from the 16 worst
// points of each; every point found above options.max_error. Adds its evaluations to `stats`.
Estimate estimate_error(const LookupTable& table, const PointSet& held_out, Evaluators& evaluators,
                        const TableBuildOptions& options, int threads, TableBuildStatistics& stats);

}  // namespace fmpc::table_build
