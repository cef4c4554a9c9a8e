// compiler/backend/table/cell_bound.h: the bound on multilinear interpolation's error over a cell, derived from the
// rule base, is never below the error measured densely inside the cell, on seeded random systems of every
// membership family, norm, hedge, weight and both system types, over random cells large and small; a block bound
// holds for each cell inside the block; what the bound does not cover is named.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "compiler/backend/table/cell_bound.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "tests/support/random_system.h"

namespace {

using namespace fmpc;

testing::RandomSystemOptions bounded_options() {
  testing::RandomSystemOptions options;
  options.max_inputs = 2;
  options.max_outputs = 2;
  options.max_rules = 8;
  options.mamdani_defuzzifiers = {Defuzzifier::Centroid};
  options.exact_samples = false;
  options.no_fire_policies = false;  // `error` makes an output NaN, which no table holds
  return options;
}

struct Cell {
  std::vector<double> lo, hi;
};

// A random cell inside the inputs' ranges, each side a random fraction (1e-3 to 1/2, log-uniform) of the range.
Cell random_cell(const FuzzySystem& system, std::mt19937_64& random) {
  const auto unit = [&random]() { return static_cast<double>(random() >> 11) * 0x1.0p-53; };
  Cell cell;
  for (const Variable& input : system.inputs) {
    const double range = input.max - input.min;
    const double width = range * std::pow(10.0, -3.0 + 2.7 * unit());
    const double lo = input.min + (range - width) * unit();
    cell.lo.push_back(lo);
    cell.hi.push_back(lo + width);
  }
  return cell;
}

// The values at the cell's 2^d corners (corner bit d-1-a for axis a), per output.
std::vector<std::vector<double>> corner_values(Interpreter& interpreter, const Cell& cell) {
  const std::size_t d = cell.lo.size();
  std::vector<std::vector<double>> values;
  for (std::size_t corner = 0; corner < (std::size_t{1} << d); ++corner) {
    std::vector<double> x(d);
    for (std::size_t a = 0; a < d; ++a) x[a] = corner >> (d - 1 - a) & 1 ? cell.hi[a] : cell.lo[a];
    values.push_back(interpreter.evaluate(x).outputs);
  }
  return values;
}

// max |f - L| over a 33^d grid in the cell and 200 random points, L the corners' multilinear interpolant.
double measured_error(Interpreter& interpreter, const Cell& cell, const std::vector<std::vector<double>>& corners,
                      std::mt19937_64& random) {
  const std::size_t d = cell.lo.size();
  const auto error_at = [&](const std::vector<double>& t) {
    std::vector<double> x(d);
    for (std::size_t a = 0; a < d; ++a) x[a] = cell.lo[a] + t[a] * (cell.hi[a] - cell.lo[a]);
    const std::vector<double> f = interpreter.evaluate(x).outputs;
    double worst = 0.0;
    for (std::size_t o = 0; o < f.size(); ++o) {
      double interpolated = 0.0;
      for (std::size_t corner = 0; corner < corners.size(); ++corner) {
        double weight = 1.0;
        for (std::size_t a = 0; a < d; ++a) weight *= corner >> (d - 1 - a) & 1 ? t[a] : 1.0 - t[a];
        interpolated += weight * corners[corner][o];
      }
      worst = std::max(worst, std::fabs(f[o] - interpolated));
    }
    return worst;
  };
  double worst = 0.0;
  const std::size_t side = 33;
  std::size_t total = 1;
  for (std::size_t a = 0; a < d; ++a) total *= side;
  for (std::size_t k = 0; k < total; ++k) {
    std::vector<double> t(d);
    std::size_t rest = k;
    for (std::size_t a = 0; a < d; ++a) {
      t[a] = static_cast<double>(rest % side) / (side - 1);
      rest /= side;
    }
    worst = std::max(worst, error_at(t));
  }
  for (int k = 0; k < 200; ++k) {
    std::vector<double> t(d);
    for (double& v : t) v = static_cast<double>(random() >> 11) * 0x1.0p-53;
    worst = std::max(worst, error_at(t));
  }
  return worst;
}

}  // namespace

TEST_CASE("the cell bound is never below the error measured densely in the cell", "[heavy][table][bound]") {
  // 400 random systems x 8 cells = 3,200 cells (about 1,100 evaluations each).
  const testing::RandomSystemOptions options = bounded_options();
  std::mt19937_64 random(1106);
  std::size_t cells = 0, skipped_systems = 0, tight = 0, value_bounded = 0;
  double loosest = 0.0;
  for (std::uint64_t seed = 1; seed <= 400; ++seed) {
    const FuzzySystem system = testing::random_system(seed, options);
    if (cell_bound_limitation(system, EvaluationOptions{})) {
      ++skipped_systems;
      continue;
    }
    CellBounder bounder(system, EvaluationOptions{});
    Interpreter interpreter(system);
    double range = 0.0;
    for (const Variable& output : system.outputs) range = std::max(range, output.max - output.min);
    for (int k = 0; k < 8; ++k) {
      const Cell cell = random_cell(system, random);
      const auto corners = corner_values(interpreter, cell);
      std::vector<double> corner_min(system.outputs.size(), 1e300), corner_max(system.outputs.size(), -1e300);
      for (const auto& values : corners)
        for (std::size_t o = 0; o < values.size(); ++o) {
          corner_min[o] = std::min(corner_min[o], values[o]);
          corner_max[o] = std::max(corner_max[o], values[o]);
        }
      const CellBound b = bounder.bound(cell.lo.data(), cell.hi.data(), corner_min.data(), corner_max.data(), 0.0);
      const double error = measured_error(interpreter, cell, corners, random);
      INFO("seed " << seed << " cell " << k << ": bound " << b.bound << ", measured " << error
                   << (b.smooth ? " (derivatives)" : " (value range)"));
      // The interpreter's own rounding is below 1e-12 of the output range.
      CHECK(error <= b.bound + 1e-12 * std::max(range, 1.0));
      ++cells;
      if (!b.smooth) ++value_bounded;
      if (error > 1e-9 * range && b.bound <= 10.0 * error) ++tight;
      if (error > 1e-6 * range) loosest = std::max(loosest, b.bound / error);
    }
  }
  CHECK(cells >= 2000);
  // Not vacuous: most cells with a visible error are bounded within 10 times it.
  CHECK(tight * 2 >= cells - value_bounded);
  WARN(cells << " cells of " << (400 - skipped_systems) << " systems (" << skipped_systems
             << " outside the bound's class): " << tight << " bounded within 10x of the measured error, "
             << value_bounded << " by their value range; loosest bound / error " << loosest);
}

TEST_CASE("a block's bound with the cells' widths holds for every cell inside it", "[heavy][table][bound]") {
  const testing::RandomSystemOptions options = bounded_options();
  std::mt19937_64 random(77);
  std::size_t blocks = 0;
  for (std::uint64_t seed = 500; seed < 560; ++seed) {
    const FuzzySystem system = testing::random_system(seed, options);
    if (cell_bound_limitation(system, EvaluationOptions{})) continue;
    CellBounder bounder(system, EvaluationOptions{});
    Interpreter interpreter(system);
    double range = 0.0;
    for (const Variable& output : system.outputs) range = std::max(range, output.max - output.min);
    for (int k = 0; k < 4; ++k) {
      // A block of 4 cells per axis.
      const Cell block = random_cell(system, random);
      const std::size_t d = block.lo.size();
      std::vector<double> widths(d);
      for (std::size_t a = 0; a < d; ++a) widths[a] = (block.hi[a] - block.lo[a]) / 4.0;
      const std::vector<double> no_min(system.outputs.size(), -1e300 * 1e300), no_max(system.outputs.size(), 1e300 * 1e300);
      const CellBound b = bounder.bound(block.lo.data(), block.hi.data(), no_min.data(), no_max.data(), 0.0,
                                        widths.data());
      if (!std::isfinite(b.bound)) continue;
      ++blocks;
      for (std::size_t c = 0; c < (std::size_t{1} << (2 * d)); ++c) {
        Cell cell;
        for (std::size_t a = 0; a < d; ++a) {
          const std::size_t i = c >> (2 * a) & 3;
          cell.lo.push_back(block.lo[a] + widths[a] * static_cast<double>(i));
          cell.hi.push_back(block.lo[a] + widths[a] * static_cast<double>(i + 1));
        }
        const auto corners = corner_values(interpreter, cell);
        const double error = measured_error(interpreter, cell, corners, random);
        INFO("seed " << seed << " block " << k << " cell " << c << ": block bound " << b.bound << ", measured "
                     << error);
        CHECK(error <= b.bound + 1e-12 * std::max(range, 1.0));
      }
    }
  }
  CHECK(blocks >= 60);
}

TEST_CASE("what the derived bound does not cover is named", "[table][bound]") {
  const auto system_of = [](const std::string& text) {
    DiagnosticList diagnostics;
    RuleFile file = load_rule_file("t.fis", text, diagnostics);
    REQUIRE_FALSE(diagnostics.has_errors());
    return file.systems.front();
  };
  const std::string base = R"(system s
  type mamdani
  defuzzify DEFUZZ
input x in [0, 1] kPa
  a is triangle(start 0, peak 0.5, end 1)
output y in [0, 1] kPa
  b is triangle(start 0, peak 0.5, end 1)
rule r1: if x is a then y is b
)";
  const auto with = [&](const std::string& defuzzify) {
    std::string text = base;
    text.replace(text.find("DEFUZZ"), 6, defuzzify);
    return text;
  };
  CHECK_FALSE(cell_bound_limitation(system_of(with("centroid")), EvaluationOptions{}));
  CHECK(*cell_bound_limitation(system_of(with("mom")), EvaluationOptions{}) ==
        "defuzzifier mom (piecewise constant in the inputs: it jumps between samples)");
  CHECK(*cell_bound_limitation(system_of(with("centroid samples exact")), EvaluationOptions{}) ==
        "'samples exact' (adaptive quadrature)");
  EvaluationOptions octave;
  octave.reference = Reference::Octave;
  CHECK(*cell_bound_limitation(system_of(with("centroid")), octave) == "Octave's semantics (--semantics octave)");
}
