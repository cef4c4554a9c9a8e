#pragma once
// What a table build measures with (table_builder.h): work spread over threads, one interpreter per thread for the
// grid values and for the reference, seeded point sets with their reference outputs, and a table's error on them.
// Internal to the table builder (compiler/backend/table/table_*.cpp).
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>
#include <thread>
#include <vector>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/eval/interpreter.h"
#include "compiler/passes/pipeline.h"

namespace fmpc::table_build {

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
  Evaluators(const FuzzySystem& source, const CompileResult& compiled, const EvaluationOptions& options, int threads);

  // The specialised system's outputs at `point` (one coordinate per axis).
  std::vector<double> grid(int thread, const double* point);
  // The source system's outputs at `point`, the fixed inputs plugged in.
  std::vector<double> reference(int thread, const double* point);

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
PointSet with_reference(const LookupTable& table, std::vector<double> points, Evaluators& evaluators, int threads);

// `count` points uniform over the table's axes from `seed`, with their reference outputs. Draws from
// std::mt19937_64 and maps the bits itself, so a seed gives the same points on every platform.
PointSet draw_points(const LookupTable& table, std::uint64_t seed, std::size_t count, Evaluators& evaluators,
                     int threads);

struct Measurement {
  std::vector<double> errors;  // per point: the largest |table - reference| over the outputs
  double max_error = 0.0;
  std::size_t worst = 0;  // the first point with max_error
};

// The table's interpolation error at every point of `set` (infinite where it is NaN).
Measurement measure(const LookupTable& table, const PointSet& set, int threads);

// "HCV = 7.5, HBV = 3": a point of the table's axes, for messages.
std::string point_text(const LookupTable& table, const double* point);

}  // namespace fmpc::table_build
