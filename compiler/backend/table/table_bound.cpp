#include "compiler/backend/table/table_bound.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace fmpc::table_build {

namespace {

// A cell's bound sharpened by subdivision. The cell's interpolant L (from its stored corner values) and the rule
// base f: on a region R of the cell, |f - L| <= |f - L_R| + |L_R - L|, where L_R interpolates f at R's corners;
// the first term is R's own cell bound (cell_bound.h), the second is multilinear on R and so largest at R's
// corners, where it is |f(c) - L(c)|, computed. Halving R along the axis with the largest term until the sum is
// below the goal makes the bound approach the true error where the single-cell bound is loose (a kink in a cell
// is bounded by h |slope change| / 4 wherever it lies; the error is that large only where it lies in the middle).
class Subdivision {
 public:
  Subdivision(const LookupTable& table, Evaluators& evaluators, CellBounder& bounder, int thread, const double* lo,
              const double* hi, const std::vector<double>& corners)
      : evaluators_(evaluators), bounder_(bounder), thread_(thread), d_(table.axes.size()),
        m_(table.output_names.size()), lo_(lo, lo + d_), hi_(hi, hi + d_), corners_(corners) {}

  // The bound over the region [lo, hi] of the cell; stops splitting once below `goal` or after `depth` halvings.
  double bound(std::vector<double> lo, std::vector<double> hi, double goal, int depth) {
    std::vector<double> f_min(m_, std::numeric_limits<double>::infinity());
    std::vector<double> f_max(m_, -std::numeric_limits<double>::infinity());
    double corner_miss = 0.0;
    std::vector<double> point(d_);
    for (std::size_t corner = 0; corner < (std::size_t{1} << d_); ++corner) {
      for (std::size_t a = 0; a < d_; ++a) point[a] = corner >> (d_ - 1 - a) & 1 ? hi[a] : lo[a];
      const std::vector<double> f = evaluators_.grid(thread_, point.data());
      ++evaluations;
      for (std::size_t o = 0; o < m_; ++o) {
        f_min[o] = std::min(f_min[o], f[o]);
        f_max[o] = std::max(f_max[o], f[o]);
        const double miss = std::fabs(f[o] - interpolant(point.data(), o));
        corner_miss = std::isnan(miss) ? std::numeric_limits<double>::infinity() : std::max(corner_miss, miss);
      }
    }
    const CellBound own = bounder_.bound(lo.data(), hi.data(), f_min.data(), f_max.data(), 0.0);
    ++bounds;
    const double total = own.bound + corner_miss;
    if (total <= goal || depth == 0 || !std::isfinite(own.bound)) return total;
    std::size_t axis = 0;
    double best = -1.0;
    for (std::size_t a = 0; a < d_; ++a) {
      const double score = own.has_terms ? own.terms[a] : (hi[a] - lo[a]) / (hi_[a] - lo_[a]);
      if (score > best) {
        best = score;
        axis = a;
      }
    }
    const double mid = 0.5 * (lo[axis] + hi[axis]);
    std::vector<double> upper_lo = lo, lower_hi = hi;
    upper_lo[axis] = mid;
    lower_hi[axis] = mid;
    const double first = bound(lo, lower_hi, goal, depth - 1);
    if (!(first <= goal)) return first;  // the cell fails either way: no need to look further
    return std::max(first, bound(upper_lo, hi, goal, depth - 1));
  }

  std::uint64_t evaluations = 0, bounds = 0;

 private:
  // The cell's stored multilinear interpolant of output o at `x` (inside the cell).
  double interpolant(const double* x, std::size_t o) const {
    double value = 0.0;
    for (std::size_t corner = 0; corner < (std::size_t{1} << d_); ++corner) {
      double weight = 1.0;
      for (std::size_t a = 0; a < d_; ++a) {
        const double t = (x[a] - lo_[a]) / (hi_[a] - lo_[a]);
        weight *= corner >> (d_ - 1 - a) & 1 ? t : 1.0 - t;
      }
      value += weight * corners_[corner * m_ + o];
    }
    return value;
  }

  Evaluators& evaluators_;
  CellBounder& bounder_;
  int thread_;
  std::size_t d_, m_;
  std::vector<double> lo_, hi_;
  const std::vector<double>& corners_;  // stored values, corner-major (corner bit d-1-a for axis a)
};

constexpr double kSubdivideWithin = 4.0;  // subdivide cells whose bound is at most this many times the goal
constexpr int kSubdivisionDepth = 10;     // halvings of one cell

// Bounds every cell of the grid. Blocks of cells first: the rule base's derivative intervals over a block hold
// in each of its cells, so one evaluation over a block whose bound (with the largest cell widths) is below the goal
// bounds all of its cells; other blocks are halved along their longest side down to single cells, which get the
// cell bound (with the value-range fallback) and, where that is within kSubdivideWithin of the goal, subdivision.
// Where the rules are flat (most of a table's range) this evaluates a few blocks instead of every cell.
class CellBounding {
 public:
  CellBounding(const LookupTable& table, const std::vector<double>& rounding, std::vector<CellBounder>& bounders,
               Evaluators& evaluators, const std::vector<bool>& refinable, double goal)
      : table_(table), rounding_(rounding), bounders_(bounders), evaluators_(evaluators), refinable_(refinable),
        goal_(goal), d_(table.axes.size()), m_(table.output_names.size()), stride_(d_, 1) {
    std::size_t total = 1;
    for (const TableAxis& axis : table.axes) {
      cells.counts.push_back(axis.breakpoints.size() - 1);
      total *= axis.breakpoints.size() - 1;
    }
    cells.bound.assign(total, 0.0);
    cells.split.assign(total, -1);
    for (std::size_t a = d_ - 1; a-- > 0;) stride_[a] = stride_[a + 1] * table.axes[a + 1].breakpoints.size();
    for (double r : rounding) largest_rounding_ = std::max(largest_rounding_, r);
  }

  void run(int threads, TableBuildStatistics& stats) {
    // Top-level blocks: about 64 per thread, so that the threads share the work.
    std::vector<std::size_t> pieces(d_, 1);
    std::size_t blocks = 1;
    while (blocks < 64 * static_cast<std::size_t>(threads)) {
      std::size_t axis = 0;
      for (std::size_t a = 1; a < d_; ++a)
        if (cells.counts[a] / pieces[a] > cells.counts[axis] / pieces[axis]) axis = a;
      if (cells.counts[axis] / pieces[axis] < 2) break;
      blocks = blocks / pieces[axis] * (pieces[axis] * 2);
      pieces[axis] *= 2;
    }
    std::vector<std::uint64_t> evaluations(static_cast<std::size_t>(threads), 0), bounds(evaluations);
    run_parallel(blocks, threads, [&](int thread, std::size_t block) {
      std::vector<std::size_t> first(d_), last(d_);
      std::size_t rest = block;
      for (std::size_t a = d_; a-- > 0;) {
        const std::size_t piece = rest % pieces[a];
        rest /= pieces[a];
        first[a] = cells.counts[a] * piece / pieces[a];
        last[a] = cells.counts[a] * (piece + 1) / pieces[a];
      }
      Counters counters;
      bound_block(thread, first, last, counters);
      evaluations[static_cast<std::size_t>(thread)] += counters.evaluations;
      bounds[static_cast<std::size_t>(thread)] += counters.bounds;
    });
    for (std::size_t c = 0; c < cells.size(); ++c)
      if (cells.bound[c] > cells.bound[cells.worst]) cells.worst = c;
    for (int t = 0; t < threads; ++t) {
      stats.probe_evaluations += evaluations[static_cast<std::size_t>(t)];
      stats.cells_bounded += bounds[static_cast<std::size_t>(t)];
    }
  }

  CellBounds cells;

 private:
  struct Counters {
    std::uint64_t evaluations = 0, bounds = 0;
  };

  std::size_t flat_cell(const std::vector<std::size_t>& origin) const {
    std::size_t flat = 0;
    for (std::size_t a = 0; a < d_; ++a) flat = flat * cells.counts[a] + origin[a];
    return flat;
  }

  // Cells [first_a, last_a) per axis.
  void bound_block(int thread, const std::vector<std::size_t>& first, const std::vector<std::size_t>& last,
                   Counters& counters) {
    std::size_t count = 1, longest = 0;
    for (std::size_t a = 0; a < d_; ++a) {
      count *= last[a] - first[a];
      if (last[a] - first[a] > last[longest] - first[longest]) longest = a;
    }
    if (count == 0) return;
    if (count == 1) {
      bound_cell(thread, first, counters);
      return;
    }
    std::array<double, kMaxTableAxes> lo{}, hi{}, widths{};
    for (std::size_t a = 0; a < d_; ++a) {
      const std::vector<double>& b = table_.axes[a].breakpoints;
      lo[a] = b[first[a]];
      hi[a] = b[last[a]];
      for (std::size_t i = first[a]; i < last[a]; ++i) widths[a] = std::max(widths[a], b[i + 1] - b[i]);
    }
    const std::vector<double> no_min(m_, -std::numeric_limits<double>::infinity());
    const std::vector<double> no_max(m_, std::numeric_limits<double>::infinity());
    const CellBound b = bounders_[static_cast<std::size_t>(thread)].bound(
        lo.data(), hi.data(), no_min.data(), no_max.data(), largest_rounding_, widths.data());
    ++counters.bounds;
    if (b.bound <= goal_) {
      std::vector<std::size_t> origin = first;
      for (;;) {
        cells.bound[flat_cell(origin)] = b.bound;
        std::size_t a = d_;
        while (a-- > 0) {
          if (++origin[a] < last[a]) break;
          origin[a] = first[a];
        }
        if (a == static_cast<std::size_t>(-1)) break;
      }
      return;
    }
    const std::size_t mid = (first[longest] + last[longest]) / 2;
    std::vector<std::size_t> lower_last = last, upper_first = first;
    lower_last[longest] = mid;
    upper_first[longest] = mid;
    bound_block(thread, first, lower_last, counters);
    bound_block(thread, upper_first, last, counters);
  }

  void bound_cell(int thread, const std::vector<std::size_t>& origin, Counters& counters) {
    const std::size_t cell = flat_cell(origin);
    std::array<double, kMaxTableAxes> lo{}, hi{};
    std::size_t base = 0;
    for (std::size_t a = 0; a < d_; ++a) {
      lo[a] = table_.axes[a].breakpoints[origin[a]];
      hi[a] = table_.axes[a].breakpoints[origin[a] + 1];
      base += origin[a] * stride_[a];
    }
    std::vector<double> corner_min(m_, std::numeric_limits<double>::infinity());
    std::vector<double> corner_max(m_, -std::numeric_limits<double>::infinity());
    std::vector<double> corners((std::size_t{1} << d_) * m_);
    double corner_rounding = 0.0;
    for (std::size_t corner = 0; corner < (std::size_t{1} << d_); ++corner) {
      std::size_t flat = base;
      for (std::size_t a = 0; a < d_; ++a)
        if (corner >> (d_ - 1 - a) & 1) flat += stride_[a];
      for (std::size_t o = 0; o < m_; ++o) {
        const double v = table_.values[flat * m_ + o];
        corners[corner * m_ + o] = v;
        corner_min[o] = std::min(corner_min[o], v);
        corner_max[o] = std::max(corner_max[o], v);
        corner_rounding = std::max(corner_rounding, rounding_[flat * m_ + o]);
      }
    }
    CellBounder& bounder = bounders_[static_cast<std::size_t>(thread)];
    const CellBound b = bounder.bound(lo.data(), hi.data(), corner_min.data(), corner_max.data(), corner_rounding);
    ++counters.bounds;
    cells.bound[cell] = b.bound;
    if (b.bound > goal_ && b.bound <= kSubdivideWithin * goal_) {
      Subdivision subdivision(table_, evaluators_, bounder, thread, lo.data(), hi.data(), corners);
      const double sharper =
          subdivision.bound(std::vector<double>(lo.begin(), lo.begin() + static_cast<std::ptrdiff_t>(d_)),
                            std::vector<double>(hi.begin(), hi.begin() + static_cast<std::ptrdiff_t>(d_)), goal_,
                            kSubdivisionDepth);
      cells.bound[cell] = std::min(cells.bound[cell], sharper);
      counters.evaluations += subdivision.evaluations;
      counters.bounds += subdivision.bounds;
    }
    // Split along the refinable axis with the largest term; where the value range bounded the cell, along its
    // widest refinable side relative to the axis's range. Where the terms of the axes with a fixed count
    // (--vary NAME:points) alone exceed the goal, no split helps: -1.
    if (b.has_terms) {
      double fixed_terms = 0.0;
      for (std::size_t a = 0; a < d_; ++a)
        if (!refinable_[a]) fixed_terms += b.terms[a];
      if (!(fixed_terms < goal_)) return;
    }
    double best = -1.0;
    for (std::size_t a = 0; a < d_; ++a) {
      if (!refinable_[a]) continue;
      const std::vector<double>& axis = table_.axes[a].breakpoints;
      const double score = b.has_terms ? b.terms[a] : (hi[a] - lo[a]) / (axis.back() - axis.front());
      if (score > best) {
        best = score;
        cells.split[cell] = static_cast<int>(a);
      }
    }
  }

  const LookupTable& table_;
  const std::vector<double>& rounding_;
  std::vector<CellBounder>& bounders_;
  Evaluators& evaluators_;
  const std::vector<bool>& refinable_;
  double goal_;
  std::size_t d_, m_;
  std::vector<std::size_t> stride_;  // of the grid's points
  double largest_rounding_ = 0.0;
};

}  // namespace

void cell_origin(std::size_t cell, const std::vector<std::size_t>& counts, std::vector<std::size_t>& origin) {
  for (std::size_t a = counts.size(); a-- > 0;) {
    origin[a] = cell % counts[a];
    cell /= counts[a];
  }
}

std::vector<double> cell_centre(const LookupTable& table, const CellBounds& cells, std::size_t cell) {
  std::vector<std::size_t> origin(table.axes.size());
  cell_origin(cell, cells.counts, origin);
  std::vector<double> centre;
  for (std::size_t a = 0; a < table.axes.size(); ++a)
    centre.push_back(0.5 * (table.axes[a].breakpoints[origin[a]] + table.axes[a].breakpoints[origin[a] + 1]));
  return centre;
}

CellBounds bound_cells(const LookupTable& table, const std::vector<double>& rounding,
                       std::vector<CellBounder>& bounders, Evaluators& evaluators, const std::vector<bool>& refinable,
                       double goal, int threads, TableBuildStatistics& stats) {
  CellBounding bounding(table, rounding, bounders, evaluators, refinable, goal);
  bounding.run(threads, stats);
  return std::move(bounding.cells);
}

}  // namespace fmpc::table_build
