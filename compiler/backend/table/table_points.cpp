#include "compiler/backend/table/table_points.h"

#include <cmath>
#include <limits>
#include <random>

#include "diagnostics/number_format.h"

namespace fmpc::table_build {

Evaluators::Evaluators(const FuzzySystem& source, const CompileResult& compiled, const EvaluationOptions& options,
                       int threads)
    : compiled_(compiled), source_inputs_(source.inputs.size(), 0.0) {
  for (int t = 0; t < std::max(1, threads); ++t) {
    specialised_.emplace_back(compiled.system, options);
    reference_.emplace_back(source, options);
  }
  for (const auto& [index, value] : compiled.fixed) source_inputs_[static_cast<std::size_t>(index)] = value;
}

std::vector<double> Evaluators::grid(int thread, const double* point) {
  const std::vector<double> inputs(point, point + compiled_.system.inputs.size());
  return specialised_[static_cast<std::size_t>(thread)].evaluate(inputs).outputs;
}

std::vector<double> Evaluators::reference(int thread, const double* point) {
  std::vector<double> inputs = source_inputs_;
  for (std::size_t a = 0; a < compiled_.source_inputs.size(); ++a)
    inputs[static_cast<std::size_t>(compiled_.source_inputs[a])] = point[a];
  return reference_[static_cast<std::size_t>(thread)].evaluate(inputs).outputs;
}

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

std::string point_text(const LookupTable& table, const double* point) {
  std::string text;
  for (std::size_t a = 0; a < table.axes.size(); ++a)
    text += (a ? ", " : "") + table.axes[a].input_name + " = " + format_number(point[a]);
  return text;
}

}  // namespace fmpc::table_build
