#include "compiler/backend/table/table_builder.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <map>
#include <random>
#include <set>
#include <thread>

#include "compiler/backend/table/cell_bound.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

constexpr double kTrainingMargin = 0.8;  // train below 0.8 of the target before measuring held-out points
constexpr std::size_t kWorstPointsPerRound = 64;
constexpr int kMaxHeldOutSets = 6;
constexpr std::size_t kLocalSearches = 32;  // estimate: compass searches from the worst held-out points and centres

// Runs work(thread, index) for index in [0, count) on `threads` std::threads, in chunks taken in turn. An exception
// in any worker (the interpreter's internal errors) stops the others and is rethrown here, once all have joined.
template <typename Work>
void run_parallel(std::size_t count, int threads, const Work& work) {
  const std::size_t workers = std::max<std::size_t>(1, std::min<std::size_t>(static_cast<std::size_t>(threads), count));
  constexpr std::size_t kChunk = 64;
  std::atomic<std::size_t> next{0};
  std::vector<std::exception_ptr> failures(workers);
  const auto worker = [&](int thread) {
    try {
      for (;;) {
        const std::size_t begin = next.fetch_add(kChunk);
        if (begin >= count) return;
        const std::size_t end = std::min(count, begin + kChunk);
        for (std::size_t i = begin; i < end; ++i) work(thread, i);
      }
    } catch (...) {
      failures[static_cast<std::size_t>(thread)] = std::current_exception();
      next = count;
    }
  };
  if (workers == 1) {
    worker(0);
  } else {
    std::vector<std::thread> pool;
    for (std::size_t t = 1; t < workers; ++t) pool.emplace_back(worker, static_cast<int>(t));
    worker(0);
    for (std::thread& thread : pool) thread.join();
  }
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
}

// One interpreter per thread for the specialised system (grid values) and for the source (the reference).
class Evaluators {
 public:
  Evaluators(const FuzzySystem& source, const CompileResult& compiled, const EvaluationOptions& options, int threads)
      : compiled_(compiled), source_inputs_(source.inputs.size(), 0.0) {
    for (int t = 0; t < std::max(1, threads); ++t) {
      specialised_.emplace_back(compiled.system, options);
      reference_.emplace_back(source, options);
    }
    for (const auto& [index, value] : compiled.fixed) source_inputs_[static_cast<std::size_t>(index)] = value;
  }

  std::vector<double> grid(int thread, const double* point) {
    const std::vector<double> inputs(point, point + compiled_.system.inputs.size());
    return specialised_[static_cast<std::size_t>(thread)].evaluate(inputs).outputs;
  }

  std::vector<double> reference(int thread, const double* point) {
    std::vector<double> inputs = source_inputs_;
    for (std::size_t a = 0; a < compiled_.source_inputs.size(); ++a)
      inputs[static_cast<std::size_t>(compiled_.source_inputs[a])] = point[a];
    return reference_[static_cast<std::size_t>(thread)].evaluate(inputs).outputs;
  }

 private:
  const CompileResult& compiled_;
  std::vector<double> source_inputs_;
  std::vector<Interpreter> specialised_;
  std::vector<Interpreter> reference_;
};

// Points uniform over the axes' ranges with their reference outputs, row-major (point, coordinate / output).
struct PointSet {
  std::size_t dimensions = 0;
  std::size_t outputs = 0;
  std::vector<double> points;
  std::vector<double> reference;
  std::size_t size() const { return dimensions == 0 ? 0 : points.size() / dimensions; }
  const double* point(std::size_t i) const { return points.data() + i * dimensions; }
};

// `points` (row-major, one coordinate per axis) with their reference outputs.
PointSet with_reference(const LookupTable& table, std::vector<double> points, Evaluators& evaluators, int threads) {
  PointSet set;
  set.dimensions = table.axes.size();
  set.outputs = table.output_names.size();
  set.points = std::move(points);
  const std::size_t count = set.size();
  set.reference.resize(count * set.outputs);
  run_parallel(count, threads, [&](int thread, std::size_t i) {
    const std::vector<double> outputs = evaluators.reference(thread, set.point(i));
    std::copy(outputs.begin(), outputs.end(), set.reference.begin() + static_cast<std::ptrdiff_t>(i * set.outputs));
  });
  return set;
}

// Draws from std::mt19937_64 and maps the bits itself, so a seed gives the same points on every platform.
PointSet draw_points(const LookupTable& table, std::uint64_t seed, std::size_t count, Evaluators& evaluators,
                     int threads) {
  const std::size_t dimensions = table.axes.size();
  std::mt19937_64 generator(seed);
  std::vector<double> points(count * dimensions);
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t a = 0; a < dimensions; ++a) {
      const double unit = static_cast<double>(generator() >> 11) * 0x1.0p-53;
      const double lo = table.axes[a].breakpoints.front(), hi = table.axes[a].breakpoints.back();
      points[i * dimensions + a] = lo + unit * (hi - lo);
    }
  return with_reference(table, std::move(points), evaluators, threads);
}

struct Measurement {
  std::vector<double> errors;  // per point: the largest |table - reference| over the outputs
  double max_error = 0.0;
  std::size_t worst = 0;  // the first point with max_error
};

Measurement measure(const LookupTable& table, const PointSet& set, int threads) {
  std::vector<const double*> pointers;
  std::vector<int> counts;
  const TableView<double> view = view_of(table, pointers, counts);
  Measurement result;
  result.errors.assign(set.size(), 0.0);
  run_parallel(set.size(), threads, [&](int, std::size_t i) {
    std::vector<double> out(set.outputs);
    interpolate_table(view, set.point(i), out.data());
    double error = 0.0;
    for (std::size_t o = 0; o < set.outputs; ++o) {
      const double difference = std::fabs(out[o] - set.reference[i * set.outputs + o]);
      error = std::isnan(difference) ? std::numeric_limits<double>::infinity() : std::max(error, difference);
    }
    result.errors[i] = error;
  });
  for (std::size_t i = 0; i < result.errors.size(); ++i)
    if (result.errors[i] > result.max_error) {
      result.max_error = result.errors[i];
      result.worst = i;
    }
  return result;
}

double stored(double value, TableValueType type) {
  return type == TableValueType::Float32 ? static_cast<double>(static_cast<float>(value)) : value;
}

std::string point_text(const LookupTable& table, const double* point) {
  std::string text;
  for (std::size_t a = 0; a < table.axes.size(); ++a)
    text += (a ? ", " : "") + table.axes[a].input_name + " = " + format_number(point[a]);
  return text;
}

std::string counts_text(const std::vector<std::vector<double>>& axes) {
  std::string text;
  std::uint64_t total = 1;
  for (const auto& axis : axes) {
    text += (text.empty() ? "" : " x ") + std::to_string(axis.size());
    total *= axis.size();
  }
  return text + " = " + std::to_string(total) + " points";
}

std::uint64_t grid_size(const std::vector<std::vector<double>>& axes) {
  std::uint64_t total = 1;
  for (const auto& axis : axes) {
    total *= axis.size();
    if (total > (1ULL << 62)) return total;
  }
  return total;
}

std::vector<double> uniform_axis(double lo, double hi, int count) {
  std::vector<double> axis(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) axis[static_cast<std::size_t>(k)] = lo + (hi - lo) * k / (count - 1);
  axis.back() = hi;
  return axis;
}

// The ends of the input's range and the tops, shoulders and centres of its terms inside it.
std::vector<double> feature_axis(const Variable& input) {
  std::vector<double> points = {input.min, input.max};
  for (const Term& term : input.terms) {
    const std::vector<double>& p = term.mf.params;
    std::vector<double> features;
    switch (term.mf.kind) {
      case MfKind::Triangle: features = {p[0], p[1], p[2]}; break;
      case MfKind::Trapezoid:
      case MfKind::PiShape: features = {p[0], p[1], p[2], p[3]}; break;
      case MfKind::Gaussian: features = {p[1] - p[0], p[1], p[1] + p[0]}; break;
      case MfKind::Gaussian2: features = {p[1], p[3]}; break;
      case MfKind::GeneralizedBell: features = {p[2] - p[0], p[2], p[2] + p[0]}; break;
      case MfKind::Sigmoid: features = {p[1]}; break;
      case MfKind::DifferenceSigmoid:
      case MfKind::ProductSigmoid: features = {p[1], p[3]}; break;
      case MfKind::ZShape:
      case MfKind::SShape:
      case MfKind::LinearS:
      case MfKind::LinearZ: features = {p[0], p[1]}; break;
      case MfKind::Constant:
      case MfKind::Linear: break;
    }
    for (double x : features)
      if (x > input.min && x < input.max) points.push_back(x);
  }
  std::sort(points.begin(), points.end());
  const double tolerance = (input.max - input.min) * 1e-6;
  std::vector<double> axis;
  for (double x : points)
    if (axis.empty() || x - axis.back() > tolerance) axis.push_back(x);
  axis.back() = input.max;
  if (axis.size() < 3) axis = uniform_axis(input.min, input.max, 3);
  return axis;
}

class GridBuilder {
 public:
  GridBuilder(LookupTable& table, Evaluators& evaluators, const TableBuildOptions& options, TableBuildStatistics& stats)
      : table_(table), evaluators_(evaluators), options_(options), stats_(stats) {}

  // Replaces the grid's axes by `axes` (each a superset of the current one), evaluating only the new points.
  bool set_axes(const std::vector<std::vector<double>>& axes, DiagnosticList& diagnostics) {
    const std::size_t dimensions = axes.size(), outputs = table_.output_names.size();
    std::vector<std::vector<long long>> old_index(dimensions);
    std::vector<long long> old_counts(dimensions, 0);
    const bool had_values = !table_.values.empty();
    for (std::size_t a = 0; a < dimensions; ++a) {
      const std::vector<double>& previous = table_.axes[a].breakpoints;
      old_counts[a] = static_cast<long long>(previous.size());
      for (double x : axes[a]) {
        const auto found = std::lower_bound(previous.begin(), previous.end(), x);
        old_index[a].push_back(had_values && found != previous.end() && *found == x ? found - previous.begin() : -1);
      }
    }
    const std::uint64_t total = grid_size(axes);
    std::vector<double> values(static_cast<std::size_t>(total) * outputs, 0.0);
    std::vector<double> rounding(values.size(), 0.0);
    std::vector<std::size_t> missing;
    std::vector<std::size_t> multi(dimensions, 0);
    for (std::uint64_t flat = 0; flat < total; ++flat) {
      long long previous_flat = 0;
      bool present = had_values;
      for (std::size_t a = 0; a < dimensions && present; ++a) {
        const long long i = old_index[a][multi[a]];
        present = i >= 0;
        previous_flat = previous_flat * old_counts[a] + i;
      }
      if (present) {
        std::copy_n(table_.values.begin() + previous_flat * static_cast<long long>(outputs), outputs,
                    values.begin() + static_cast<std::ptrdiff_t>(flat * outputs));
        std::copy_n(rounding_.begin() + previous_flat * static_cast<long long>(outputs), outputs,
                    rounding.begin() + static_cast<std::ptrdiff_t>(flat * outputs));
      } else
        missing.push_back(static_cast<std::size_t>(flat));
      for (std::size_t a = dimensions; a-- > 0;) {
        if (++multi[a] < axes[a].size()) break;
        multi[a] = 0;
      }
    }
    std::atomic<bool> not_finite{false};
    std::vector<std::size_t> counts(dimensions);
    for (std::size_t a = 0; a < dimensions; ++a) counts[a] = axes[a].size();
    run_parallel(missing.size(), options_.threads, [&](int thread, std::size_t m) {
      std::size_t flat = missing[m];
      std::vector<double> point(dimensions);
      for (std::size_t a = dimensions; a-- > 0;) {
        point[a] = axes[a][flat % counts[a]];
        flat /= counts[a];
      }
      const std::vector<double> out = evaluators_.grid(thread, point.data());
      for (std::size_t o = 0; o < outputs; ++o) {
        if (!std::isfinite(out[o])) not_finite = true;
        values[missing[m] * outputs + o] = stored(out[o], options_.value_type);
        rounding[missing[m] * outputs + o] = std::fabs(values[missing[m] * outputs + o] - out[o]);
      }
    });
    stats_.grid_evaluations += missing.size();
    if (not_finite) {
      diagnostics.error(SourceRange{options_.source_path, 0, 0, 0, 0},
                        "an output is not finite at a grid point (no rule fires there and the policy is 'error')",
                        {"a table needs a value everywhere: choose another 'when no rule fires' policy, or narrow "
                         "the inputs' ranges"});
      return false;
    }
    for (std::size_t a = 0; a < dimensions; ++a) table_.axes[a].breakpoints = axes[a];
    table_.values = std::move(values);
    rounding_ = std::move(rounding);
    return true;
  }

  // |stored value - computed value| per value of the table (non-zero for float32 tables).
  const std::vector<double>& rounding() const { return rounding_; }

 private:
  LookupTable& table_;
  Evaluators& evaluators_;
  const TableBuildOptions& options_;
  TableBuildStatistics& stats_;
  std::vector<double> rounding_;
};

struct Refinement {
  std::size_t axis = 0;
  std::size_t cell = 0;
  double error = 0.0;  // how far linear interpolation along the axis misses at the point
};

// For each of the worst training points, the axis along which interpolating between its cell's ends misses most.
std::vector<Refinement> worst_axes(const LookupTable& table, const PointSet& training, const Measurement& measured,
                                   const std::vector<bool>& refinable, double threshold, Evaluators& evaluators,
                                   const TableBuildOptions& options, TableBuildStatistics& stats) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < measured.errors.size(); ++i)
    if (measured.errors[i] > threshold) order.push_back(i);
  const std::size_t take = std::min(order.size(), kWorstPointsPerRound);
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(take), order.end(),
                    [&](std::size_t a, std::size_t b) {
                      return measured.errors[a] != measured.errors[b] ? measured.errors[a] > measured.errors[b] : a < b;
                    });
  order.resize(take);
  const std::size_t dimensions = table.axes.size(), outputs = table.output_names.size();
  std::vector<Refinement> result(take);
  std::vector<char> valid(take, 0);
  run_parallel(take, options.threads, [&](int thread, std::size_t k) {
    const double* p = training.point(order[k]);
    const double* reference = training.reference.data() + order[k] * outputs;
    Refinement best;
    bool found = false;
    for (std::size_t a = 0; a < dimensions; ++a) {
      const std::vector<double>& axis = table.axes[a].breakpoints;
      int cell = 0;
      double fraction = 0.0;
      locate_on_axis(axis.data(), static_cast<int>(axis.size()), p[a], cell, fraction);
      const double lo = axis[static_cast<std::size_t>(cell)], hi = axis[static_cast<std::size_t>(cell) + 1];
      if (hi - lo <= (axis.back() - axis.front()) * 1e-9) continue;
      std::vector<double> q(p, p + dimensions);
      q[a] = lo;
      const std::vector<double> at_lo = evaluators.grid(thread, q.data());
      q[a] = hi;
      const std::vector<double> at_hi = evaluators.grid(thread, q.data());
      double miss = 0.0;
      for (std::size_t o = 0; o < outputs; ++o)
        miss = std::max(miss, std::fabs(reference[o] - (at_lo[o] + fraction * (at_hi[o] - at_lo[o]))));
      if (!found || miss > best.error) best = Refinement{a, static_cast<std::size_t>(cell), miss};
      found = true;
    }
    // A point whose worst axis has a fixed count (--vary NAME:points) is left alone: refining another axis
    // would not help it.
    if (found && refinable[best.axis]) {
      result[k] = best;
      valid[k] = 1;
    }
  });
  stats.probe_evaluations += take * 2 * dimensions;
  std::vector<Refinement> chosen;
  for (std::size_t k = 0; k < take; ++k)
    if (valid[k]) chosen.push_back(result[k]);
  return chosen;
}

// ---- the derived bound ----------------------------------------------------------------------------------

// Per cell of the current grid: its bound and, for refinement, the refinable axis to split it along.
struct CellBounds {
  std::vector<double> bound;
  std::vector<int> split;  // -1 where no refinable axis would help
  std::size_t worst = 0;
  std::vector<std::size_t> counts;  // cells per axis
  std::size_t size() const { return bound.size(); }
};

// The cell with flat index `cell` (last axis fastest): its lower breakpoint index per axis.
void cell_origin(std::size_t cell, const std::vector<std::size_t>& counts, std::vector<std::size_t>& origin) {
  for (std::size_t a = counts.size(); a-- > 0;) {
    origin[a] = cell % counts[a];
    cell /= counts[a];
  }
}

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

// The centre of cell `cell`.
std::vector<double> cell_centre(const LookupTable& table, const CellBounds& cells, std::size_t cell) {
  std::vector<std::size_t> origin(table.axes.size());
  cell_origin(cell, cells.counts, origin);
  std::vector<double> centre;
  for (std::size_t a = 0; a < table.axes.size(); ++a)
    centre.push_back(0.5 * (table.axes[a].breakpoints[origin[a]] + table.axes[a].breakpoints[origin[a] + 1]));
  return centre;
}

// ---- the estimate: every cell and a local search --------------------------------------------------------

// The largest |table - reference| at `start` and around it: a compass search (each axis in turn, +- a step that
// starts at a quarter of the point's cell and halves when no move improves), inside the axes' box.
std::pair<double, std::vector<double>> local_search(const LookupTable& table, const TableView<double>& view,
                                                    std::vector<double> point, Evaluators& evaluators, int thread,
                                                    std::uint64_t& evaluations) {
  const std::size_t d = table.axes.size(), m = table.output_names.size();
  std::vector<double> out(m);
  const auto error_at = [&](const std::vector<double>& x) {
    interpolate_table(view, x.data(), out.data());
    const std::vector<double> reference = evaluators.reference(thread, x.data());
    ++evaluations;
    double error = 0.0;
    for (std::size_t o = 0; o < m; ++o) {
      const double difference = std::fabs(out[o] - reference[o]);
      error = std::isnan(difference) ? std::numeric_limits<double>::infinity() : std::max(error, difference);
    }
    return error;
  };
  std::vector<double> step(d);
  for (std::size_t a = 0; a < d; ++a) {
    const std::vector<double>& axis = table.axes[a].breakpoints;
    int cell = 0;
    double fraction = 0.0;
    locate_on_axis(axis.data(), static_cast<int>(axis.size()), point[a], cell, fraction);
    step[a] = 0.25 * (axis[static_cast<std::size_t>(cell) + 1] - axis[static_cast<std::size_t>(cell)]);
  }
  double best = error_at(point);
  for (int round = 0; round < 40; ++round) {
    bool moved = false;
    for (std::size_t a = 0; a < d; ++a)
      for (const double sign : {1.0, -1.0}) {
        std::vector<double> candidate = point;
        candidate[a] = std::clamp(point[a] + sign * step[a], table.axes[a].breakpoints.front(),
                                  table.axes[a].breakpoints.back());
        if (candidate[a] == point[a]) continue;
        const double error = error_at(candidate);
        if (error > best) {
          best = error;
          point = std::move(candidate);
          moved = true;
        }
      }
    if (!moved)
      for (double& s : step) s /= 2.0;
  }
  return {best, point};
}

struct Training {
  PointSet points;
  Measurement measured;
  bool grid_final = false;       // the budget (or fixed counts) allow no further refinement
  bool only_fixed_axes = false;  // ... because only axes with a fixed count could reduce the error
};

// The next axes for the cells asking to be split, (axis, cell index along it) with a weight each. Uniform: the
// axis with the largest total weight is doubled (n -> 2n - 1, nested, so no grid point is evaluated twice);
// refined: each cell is split at its midpoint on its axis, as long as the grid stays within the budget.
void refine_axes(const std::vector<std::vector<double>>& axes,
                 const std::vector<std::pair<std::size_t, std::size_t>>& splits, const std::vector<double>& weights,
                 const TableBuildOptions& options, std::vector<std::vector<double>>& next) {
  if (splits.empty()) return;
  if (options.spacing == BreakpointSpacing::Uniform) {
    std::vector<double> total(axes.size(), 0.0);
    for (std::size_t k = 0; k < splits.size(); ++k) total[splits[k].first] = std::max(total[splits[k].first], weights[k]);
    const auto axis = static_cast<std::size_t>(std::max_element(total.begin(), total.end()) - total.begin());
    const std::vector<double>& current = axes[axis];
    next[axis] = uniform_axis(current.front(), current.back(), static_cast<int>(2 * current.size() - 1));
    // Nested doubling: the old breakpoints are exactly the even ones (set them so, not recomputed).
    for (std::size_t k = 0; k < current.size(); ++k) next[axis][2 * k] = current[k];
    return;
  }
  std::set<std::pair<std::size_t, std::size_t>> done;
  for (const auto& [axis_index, cell] : splits) {
    if (!done.insert({axis_index, cell}).second) continue;
    // The grid with one more breakpoint on this axis, against the budget (without building it).
    std::uint64_t size = 1;
    for (std::size_t a = 0; a < next.size() && size <= options.max_grid_points; ++a)
      size *= next[a].size() + (a == axis_index ? 1 : 0);
    if (size > options.max_grid_points) continue;
    const double mid = 0.5 * (axes[axis_index][cell] + axes[axis_index][cell + 1]);
    auto& axis = next[axis_index];
    axis.insert(std::upper_bound(axis.begin(), axis.end(), mid), mid);
  }
}

struct Estimate {
  double error = 0.0;
  std::vector<double> location;
  std::vector<double> above_target;  // points found above --max-error (row-major)
};

// The largest error found on the held-out set, at every cell's centre, and by compass searches from the worst
// points of both.
Estimate estimate_error(const LookupTable& table, const PointSet& held_out, Evaluators& evaluators,
                        const TableBuildOptions& options, int threads, TableBuildStatistics& stats) {
  const std::size_t d = table.axes.size();
  const Measurement at_held_out = measure(table, held_out, threads);
  std::vector<double> centres;
  CellBounds shape;
  for (const TableAxis& axis : table.axes) shape.counts.push_back(axis.breakpoints.size() - 1);
  std::size_t cells = 1;
  for (std::size_t c : shape.counts) cells *= c;
  for (std::size_t c = 0; c < cells; ++c) {
    const std::vector<double> centre = cell_centre(table, shape, c);
    centres.insert(centres.end(), centre.begin(), centre.end());
  }
  const PointSet centre_set = with_reference(table, std::move(centres), evaluators, threads);
  const Measurement at_centres = measure(table, centre_set, threads);
  stats.probe_evaluations += centre_set.size();
  stats.cells = centre_set.size();
  std::vector<std::vector<double>> starts;
  for (const PointSet* set : {&held_out, &centre_set}) {
    const Measurement& measured = set == &centre_set ? at_centres : at_held_out;
    std::vector<std::size_t> order(measured.errors.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    const std::size_t take = std::min<std::size_t>(order.size(), kLocalSearches / 2);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(take), order.end(),
                      [&](std::size_t a, std::size_t b) {
                        return measured.errors[a] != measured.errors[b] ? measured.errors[a] > measured.errors[b]
                                                                        : a < b;
                      });
    for (std::size_t k = 0; k < take; ++k) starts.emplace_back(set->point(order[k]), set->point(order[k]) + d);
  }
  std::vector<const double*> pointers;
  std::vector<int> counts;
  const TableView<double> view = view_of(table, pointers, counts);
  std::vector<std::pair<double, std::vector<double>>> searched(starts.size());
  std::vector<std::uint64_t> evaluations(starts.size(), 0);
  run_parallel(starts.size(), threads, [&](int thread, std::size_t k) {
    searched[k] = local_search(table, view, starts[k], evaluators, thread, evaluations[k]);
  });
  for (std::uint64_t e : evaluations) stats.probe_evaluations += e;
  stats.local_searches = searched.size();

  Estimate estimate;
  estimate.error = at_held_out.max_error;
  estimate.location.assign(held_out.point(at_held_out.worst), held_out.point(at_held_out.worst) + d);
  if (at_centres.max_error > estimate.error) {
    estimate.error = at_centres.max_error;
    estimate.location.assign(centre_set.point(at_centres.worst), centre_set.point(at_centres.worst) + d);
  }
  for (const auto& [error, point] : searched) {
    if (error > estimate.error) {
      estimate.error = error;
      estimate.location = point;
    }
    if (error > options.max_error) estimate.above_target.insert(estimate.above_target.end(), point.begin(), point.end());
  }
  for (const PointSet* set : {&held_out, &centre_set}) {
    const Measurement& measured = set == &centre_set ? at_centres : at_held_out;
    for (std::size_t i = 0; i < set->size(); ++i)
      if (measured.errors[i] > options.max_error)
        estimate.above_target.insert(estimate.above_target.end(), set->point(i), set->point(i) + d);
  }
  return estimate;
}

}  // namespace

double reachable_error_floor(const CompileResult& compiled, TableValueType value_type) {
  double largest = 0.0, range = 0.0;
  for (const Variable& output : compiled.system.outputs) {
    largest = std::max({largest, std::fabs(output.min), std::fabs(output.max)});
    range = std::max(range, output.max - output.min);
  }
  const double unit_roundoff = value_type == TableValueType::Float32 ? 0x1.0p-24 : 0x1.0p-53;
  const double passes = std::isfinite(compiled.error_bound()) ? compiled.error_bound() : 0.0;
  return unit_roundoff * largest + 1e-12 * range + passes;
}

std::optional<LookupTable> build_table(const FuzzySystem& source, const CompileResult& compiled,
                                       const TableBuildOptions& options, DiagnosticList& diagnostics,
                                       TableBuildStatistics* statistics) {
  TableBuildStatistics local;
  TableBuildStatistics& stats = statistics ? *statistics : local;
  const FuzzySystem& system = compiled.system;
  const SourceRange where{options.source_path, 0, 0, 0, 0};
  const SourceRange command_line{"command line", 0, 0, 0, 0};
  if (!(options.max_error > 0.0) || !std::isfinite(options.max_error)) {
    diagnostics.error(command_line, "--max-error must be a positive number, not " + format_number(options.max_error));
    return std::nullopt;
  }
  if (const double floor = reachable_error_floor(compiled, options.value_type); options.max_error <= floor) {
    diagnostics.error(command_line,
                      "--max-error " + format_number(options.max_error) + " is below what a table of '" +
                          system.name + "' can reach: its floor is " + format_number(floor),
                      {"the floor is the rounding of the stored " +
                           std::string(options.value_type == TableValueType::Float32 ? "float" : "double") +
                           " values plus the interpreter's own rounding (1e-12 of the output range)" +
                           (std::isfinite(compiled.error_bound()) && compiled.error_bound() > 0.0
                                ? " and the passes' error bound"
                                : "") +
                           "; give --max-error above it, or use --target cpp for an evaluator without "
                           "interpolation error"});
    return std::nullopt;
  }
  if (system.inputs.empty() || system.inputs.size() > static_cast<std::size_t>(kMaxTableAxes)) {
    diagnostics.error(where, "a table has 1 to " + std::to_string(kMaxTableAxes) + " axes; " +
                                 std::to_string(system.inputs.size()) + " inputs vary",
                      {"fix more inputs with --fix NAME=VALUE"});
    return std::nullopt;
  }
  const int threads = std::max(1, options.threads);
  LookupTable table;
  table.system_name = system.name;
  table.source_path = options.source_path;
  table.source_hash = options.source_hash;
  table.value_type = options.value_type;
  for (const Variable& output : system.outputs) {
    table.output_names.push_back(output.name);
    table.output_units.push_back(output.unit);
  }
  for (const auto& [index, value] : compiled.fixed) {
    const Variable& input = source.inputs[static_cast<std::size_t>(index)];
    table.fixed_inputs.push_back(TableFixedInput{input.name, input.unit, value});
  }

  std::vector<std::vector<double>> axes;
  std::vector<bool> refinable;
  for (std::size_t a = 0; a < system.inputs.size(); ++a) {
    const Variable& input = system.inputs[a];
    TableAxis axis;
    axis.input_name = input.name;
    axis.input_unit = input.unit;
    axis.input_index = static_cast<std::uint32_t>(compiled.source_inputs[a]);
    axis.breakpoints = {input.min, input.max};
    table.axes.push_back(axis);
    const int points = a < compiled.axis_points.size() ? compiled.axis_points[a] : 0;
    refinable.push_back(points == 0);
    if (points > 0) axes.push_back(uniform_axis(input.min, input.max, points));
    else if (options.spacing == BreakpointSpacing::Uniform) axes.push_back(uniform_axis(input.min, input.max, 2));
    else axes.push_back(feature_axis(input));
  }
  if (grid_size(axes) > options.max_grid_points) {
    diagnostics.error(where, "the starting grid, " + counts_text(axes) + ", exceeds the budget of " +
                                 std::to_string(options.max_grid_points) + " points",
                      {"raise --max-grid-points, give fewer points with --vary NAME:points, or fix more inputs"});
    return std::nullopt;
  }

  Evaluators evaluators(source, compiled, options.evaluation, threads);
  GridBuilder grid(table, evaluators, options, stats);
  if (!grid.set_axes(axes, diagnostics)) return std::nullopt;

  // Refinement driven by measured errors at seeded training points: cheap, and where both statements start.
  Training training;
  training.points = draw_points(table, options.seed, options.training_points, evaluators, threads);
  stats.probe_evaluations += training.points.size();
  const double threshold = kTrainingMargin * options.max_error;
  const auto refine_by_training = [&]() -> bool {
    for (;;) {
      ++stats.rounds;
      training.measured = measure(table, training.points, threads);
      stats.training_error = training.measured.max_error;
      if (options.progress || options.early_refusal_factor > 0) {
        TableBuildProgress progress;
        progress.round = stats.rounds;
        progress.grid_points = grid_size(axes);
        progress.budget = options.max_grid_points;
        progress.training_error = training.measured.max_error;
        progress.target = options.max_error;
        // Optimistic: the interpolation error falls as h^2 on every axis at once.
        const double ratio = std::max(1.0, training.measured.max_error / options.max_error);
        progress.estimated_grid_points =
            static_cast<double>(progress.grid_points) * std::pow(ratio, 0.5 * static_cast<double>(axes.size()));
        if (options.progress) options.progress(progress);
        const bool refinable_axis = std::find(refinable.begin(), refinable.end(), true) != refinable.end();
        if (options.early_refusal_factor > 0 && refinable_axis && stats.rounds >= kEarlyRefusalRounds &&
            progress.estimated_grid_points >
                options.early_refusal_factor * static_cast<double>(options.max_grid_points)) {
          diagnostics.error(where,
                            "cannot reach --max-error " + format_number(options.max_error) + " within " +
                                std::to_string(options.max_grid_points) + " grid points: after " +
                                std::to_string(stats.rounds) + " rounds the grid, " + counts_text(axes) +
                                ", has a maximum error of " + format_number(training.measured.max_error) +
                                ", and even if the error falls as h^2 the target needs about " +
                                format_number(std::round(progress.estimated_grid_points)) +
                                " grid points (an estimate; refused now instead of refining on)",
                            {"raise --max-error or --max-grid-points, or fix more inputs (--fix NAME=VALUE), or use "
                             "--target cpp for an evaluator without interpolation error"});
          return false;
        }
      }
      if (training.measured.max_error <= threshold || training.grid_final) return true;
      const std::vector<Refinement> refinements =
          worst_axes(table, training.points, training.measured, refinable, threshold, evaluators, options, stats);
      std::vector<std::vector<double>> next = axes;
      std::vector<std::pair<std::size_t, std::size_t>> splits;
      for (const Refinement& r : refinements) splits.emplace_back(r.axis, r.cell);
      std::vector<double> weights;
      for (const Refinement& r : refinements) weights.push_back(r.error);
      refine_axes(axes, splits, weights, options, next);
      training.grid_final = next == axes || grid_size(next) > options.max_grid_points;
      training.only_fixed_axes = refinements.empty();
      if (training.grid_final) return true;
      if (!grid.set_axes(next, diagnostics)) return false;
      axes = std::move(next);
    }
  };

  // The statement is a bound where the rule base admits one (cell_bound.h) and the passes' own error is known.
  std::optional<std::string> limitation = cell_bound_limitation(system, options.evaluation);
  if (!limitation && !std::isfinite(compiled.error_bound()))
    limitation = std::string("the passes' error has no known bound");
  stats.bound_limitation = limitation.value_or("");
  // The training points' error is a lower bound of any bound: where refinement stopped above the target, say so.
  const auto unreachable = [&]() {
    diagnostics.error(where,
                      std::string(training.only_fixed_axes ? "cannot refine the grid to reach" : "cannot reach") +
                          " --max-error " + format_number(options.max_error) + " within " +
                          std::to_string(options.max_grid_points) + " grid points: the grid reached " +
                          counts_text(axes) + " with a maximum error of " +
                          format_number(training.measured.max_error) + " at " +
                          point_text(table, training.points.point(training.measured.worst)),
                      {training.only_fixed_axes
                           ? "the error lies along axes whose point count is fixed (--vary NAME:points): give "
                             "them more points or leave the count out"
                           : "raise --max-grid-points or --max-error, fix more inputs (--fix NAME=VALUE), or use "
                             "--target cpp for an evaluator without interpolation error"});
  };
  if (!limitation) {
    if (!refine_by_training()) return std::nullopt;
    if (training.measured.max_error > options.max_error) {
      unreachable();
      return std::nullopt;
    }
    // The interpreter's own rounding, against which the table is stated: far below any target that matters.
    double range = 0.0;
    for (const Variable& output : system.outputs) range = std::max(range, output.max - output.min);
    const double slack = compiled.error_bound() + 1e-12 * range;
    std::vector<CellBounder> bounders;
    for (int t = 0; t < threads; ++t) bounders.emplace_back(system, options.evaluation);
    for (;;) {
      ++stats.rounds;
      CellBounding bounding(table, grid.rounding(), bounders, evaluators, refinable, options.max_error - slack);
      bounding.run(threads, stats);
      const CellBounds& cells = bounding.cells;
      const double stated = cells.bound[cells.worst] + slack;
      if (stated <= options.max_error) {
        table.max_error = stated;
        table.error_kind = TableErrorKind::Bound;
        table.max_error_location = cell_centre(table, cells, cells.worst);
        stats.cells = cells.size();
        return table;
      }
      // Refine the cells whose bound exceeds the target, each along its own axis (uniform: the axis most of
      // that excess asks for, doubled).
      std::vector<std::size_t> over;
      for (std::size_t c = 0; c < cells.size(); ++c)
        if (cells.bound[c] + slack > options.max_error && cells.split[c] >= 0) over.push_back(c);
      std::stable_sort(over.begin(), over.end(),
                       [&](std::size_t a, std::size_t b) { return cells.bound[a] > cells.bound[b]; });
      std::vector<std::pair<std::size_t, std::size_t>> splits;
      std::vector<double> weights;
      std::vector<std::size_t> origin(axes.size());
      for (std::size_t c : over) {
        cell_origin(c, cells.counts, origin);
        const auto a = static_cast<std::size_t>(cells.split[c]);
        splits.emplace_back(a, origin[a]);
        weights.push_back(std::min(cells.bound[c], 1e300));
      }
      std::vector<std::vector<double>> next = axes;
      refine_axes(axes, splits, weights, options, next);
      if (next == axes || grid_size(next) > options.max_grid_points) {
        const std::vector<double> centre = cell_centre(table, cells, cells.worst);
        const bool fixed_axes_only = over.empty();
        diagnostics.error(where,
                          "cannot bound the table's error below --max-error " + format_number(options.max_error) +
                              (fixed_axes_only ? " by refining the automatic axes"
                                               : " within " + std::to_string(options.max_grid_points) + " grid points") +
                              ": the grid reached " + counts_text(axes) + " and its error bound is " +
                              format_number(stated) + ", largest in the cell around " +
                              point_text(table, centre.data()),
                          {fixed_axes_only
                               ? "the error lies along axes whose point count is fixed (--vary NAME:points): give "
                                 "them more points or leave the count out"
                               : "raise --max-grid-points or --max-error, fix more inputs (--fix NAME=VALUE), or use "
                                 "--target cpp for an evaluator without interpolation error; where the rules jump "
                                 "(a step in a membership function, a region where no rule fires), no grid "
                                 "interpolates them within less than half the jump"});
        return std::nullopt;
      }
      if (!grid.set_axes(next, diagnostics)) return std::nullopt;
      axes = std::move(next);
    }
  }

  // The estimate: training refinement, then a held-out set, every cell's centre and local searches from the worst
  // points found; where they exceed the target, they join the training points and refinement goes on.
  std::uint64_t held_out_seed = options.seed ^ 0x9E3779B97F4A7C15ULL;
  for (;;) {
    if (!refine_by_training()) return std::nullopt;
    if (training.measured.max_error > options.max_error) {  // the budget (or fixed counts) stopped refinement
      unreachable();
      return std::nullopt;
    }
    const PointSet held_out = draw_points(table, held_out_seed++, options.held_out_points, evaluators, threads);
    stats.probe_evaluations += held_out.size();
    ++stats.held_out_sets;
    const Estimate estimate = estimate_error(table, held_out, evaluators, options, threads, stats);
    if (estimate.error <= options.max_error) {
      table.max_error = estimate.error;
      table.error_kind = TableErrorKind::Estimate;
      table.max_error_location = estimate.location;
      stats.held_out_points = held_out.size();
      return table;
    }
    if (stats.held_out_sets >= kMaxHeldOutSets) {
      diagnostics.error(where, "held-out points, cell centres and local searches keep finding errors above "
                               "--max-error " +
                                   format_number(options.max_error) + " (" + format_number(estimate.error) +
                                   " at " + point_text(table, estimate.location.data()) + ")",
                        {"the function has features narrower than the training points resolve: raise "
                         "--max-error or fix more inputs"});
      return std::nullopt;
    }
    // The held-out set and the points found above the target join the training set.
    training.points.points.insert(training.points.points.end(), held_out.points.begin(), held_out.points.end());
    training.points.reference.insert(training.points.reference.end(), held_out.reference.begin(),
                                     held_out.reference.end());
    if (!estimate.above_target.empty()) {
      const PointSet extra = with_reference(table, estimate.above_target, evaluators, threads);
      training.points.points.insert(training.points.points.end(), extra.points.begin(), extra.points.end());
      training.points.reference.insert(training.points.reference.end(), extra.reference.begin(),
                                       extra.reference.end());
    }
    training.grid_final = false;
  }
}

double default_table_max_error(const FuzzySystem& source) {
  double narrowest = std::numeric_limits<double>::infinity();
  for (const Variable& output : source.outputs) narrowest = std::min(narrowest, output.max - output.min);
  return 0.01 * narrowest;
}

}  // namespace fmpc
