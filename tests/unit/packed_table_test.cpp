// The sector-packed table layout (kernels/table_math.h): packed_table_value's order on a small table written out
// by hand, the sizes, the layout policy, and interpolate_packed_table against interpolate_table on seeded random
// tables of 1 to 6 axes, 1 to 3 outputs, float and double, every packing depth: the same bits at random points,
// at breakpoints, at and beyond both ends of every axis, at +-inf, and NaN for a NaN coordinate.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "kernels/table_math.h"

namespace {

using namespace fmpc;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <typename T>
struct RandomTable {
  std::vector<int> counts;
  std::vector<std::vector<double>> axes;
  std::vector<const double*> breakpoints;
  std::vector<T> values;
  int outputs = 1;

  TableView<T> view() const {
    return TableView<T>{static_cast<int>(counts.size()), outputs, counts.data(), breakpoints.data(), values.data()};
  }
};

template <typename T>
RandomTable<T> random_table(int axes, int outputs, std::mt19937_64& random) {
  RandomTable<T> table;
  table.outputs = outputs;
  std::size_t points = 1;
  for (int a = 0; a < axes; ++a) {
    const int count = std::uniform_int_distribution<int>(2, axes > 4 ? 3 : 5)(random);
    std::vector<double> breakpoints{std::uniform_real_distribution<double>(-10.0, 10.0)(random)};
    // Refined (uneven) spacing on odd axes, uniform on even ones.
    const double step = std::uniform_real_distribution<double>(0.1, 3.0)(random);
    for (int k = 1; k < count; ++k)
      breakpoints.push_back(breakpoints.back() +
                            (a % 2 ? step * std::uniform_real_distribution<double>(0.2, 2.0)(random) : step));
    table.counts.push_back(count);
    table.axes.push_back(breakpoints);
    points *= static_cast<std::size_t>(count);
  }
  for (const std::vector<double>& axis : table.axes) table.breakpoints.push_back(axis.data());
  for (std::size_t k = 0; k < points * static_cast<std::size_t>(outputs); ++k)
    table.values.push_back(static_cast<T>(std::uniform_real_distribution<double>(-100.0, 100.0)(random)));
  return table;
}

template <typename T>
std::vector<T> packed_copy(const TableView<T>& view, int packed_axes) {
  std::vector<T> groups(
      static_cast<std::size_t>(packed_table_size(view.axes, view.counts, view.outputs, packed_axes)));
  for (std::size_t i = 0; i < groups.size(); ++i)
    groups[i] = packed_table_value(view, packed_axes, static_cast<long long>(i));
  return groups;
}

// Queries: every breakpoint combination along one random line per axis, the ends and beyond, +-inf, and uniform
// points, each coordinate drawn from those kinds independently.
template <typename T>
std::vector<double> queries_for(const RandomTable<T>& table, std::mt19937_64& random, int count) {
  std::vector<double> queries;
  for (int q = 0; q < count; ++q) {
    for (std::size_t a = 0; a < table.axes.size(); ++a) {
      const std::vector<double>& axis = table.axes[a];
      const double lo = axis.front(), hi = axis.back();
      double x = 0.0;
      switch (std::uniform_int_distribution<int>(0, 7)(random)) {
        case 0: x = axis[std::uniform_int_distribution<std::size_t>(0, axis.size() - 1)(random)]; break;
        case 1: x = hi; break;
        case 2: x = lo; break;
        case 3: x = hi + 1.5; break;
        case 4: x = lo - 0.25; break;
        case 5: x = q % 2 ? kInf : -kInf; break;
        default: x = std::uniform_real_distribution<double>(lo, hi)(random); break;
      }
      queries.push_back(x);
    }
  }
  return queries;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

template <int Axes, int Packed, typename T>
void check_packed_against_grid(std::mt19937_64& random) {
  for (int outputs = 1; outputs <= 3; ++outputs) {
    const RandomTable<T> table = random_table<T>(Axes, outputs, random);
    const TableView<T> grid = table.view();
    const std::vector<T> groups = packed_copy(grid, Packed);
    const PackedTableView<T> packed{Axes, outputs, grid.counts, grid.breakpoints, Packed, groups.data()};
    const std::vector<double> queries = queries_for(table, random, 400);
    std::vector<T> expected(static_cast<std::size_t>(outputs)), got(static_cast<std::size_t>(outputs));
    std::size_t differences = 0;
    for (std::size_t q = 0; q < queries.size(); q += Axes) {
      interpolate_table(grid, &queries[q], expected.data());
      interpolate_packed_table<Axes, Packed>(packed, &queries[q], got.data());
      for (int o = 0; o < outputs; ++o) differences += same_bits(expected[o], got[o]) ? 0 : 1;
    }
    INFO(Axes << " axes, " << Packed << " packed, " << outputs << " outputs, " << sizeof(T) << "-byte values");
    CHECK(differences == 0);

    // A NaN on any axis gives NaN on every output.
    std::vector<double> query(queries.begin(), queries.begin() + Axes);
    for (int a = 0; a < Axes; ++a) {
      std::vector<double> with_nan = query;
      with_nan[static_cast<std::size_t>(a)] = kNaN;
      interpolate_packed_table<Axes, Packed>(packed, with_nan.data(), got.data());
      for (int o = 0; o < outputs; ++o) CHECK(std::isnan(got[o]));
    }
  }
}

template <int Axes, typename T>
void check_every_depth(std::mt19937_64& random) {
  check_packed_against_grid<Axes, 1, T>(random);
  if constexpr (Axes >= 2) check_packed_against_grid<Axes, 2, T>(random);
  if constexpr (Axes >= 3) check_packed_against_grid<Axes, 3, T>(random);
  if constexpr (Axes >= 4) check_packed_against_grid<Axes, Axes, T>(random);
}

}  // namespace

TEST_CASE("packed table: group order, sizes and the layout policy", "[table][packed]") {
  // 3 x 3 grid, values 0..8 row-major (the last axis fastest); packing the last axis pairs each cell's ends.
  const int counts[] = {3, 3};
  const double axis[] = {0.0, 1.0, 2.0};
  const double* const breakpoints[] = {axis, axis};
  const double values[] = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const TableView<double> view{2, 1, counts, breakpoints, values};
  CHECK(packed_copy(view, 1) == std::vector<double>{0, 1, 1, 2, 3, 4, 4, 5, 6, 7, 7, 8});
  // Both axes packed: each of the 4 cells' corners in binary order (first axis most significant).
  CHECK(packed_copy(view, 2) == std::vector<double>{0, 1, 3, 4, 1, 2, 4, 5, 3, 4, 6, 7, 4, 5, 7, 8});
  // Two outputs: each group holds one output's corners, outputs of one cell side by side.
  const double two_outputs[] = {0, 10, 1, 11, 2, 12, 3, 13, 4, 14, 5, 15, 6, 16, 7, 17, 8, 18};
  const TableView<double> view2{2, 2, counts, breakpoints, two_outputs};
  CHECK(packed_copy(view2, 1) ==
        std::vector<double>{0, 1, 10, 11, 1, 2, 11, 12, 3, 4, 13, 14, 4, 5, 14, 15, 6, 7, 16, 17, 7, 8, 17, 18});

  const int liver[] = {9, 9, 9, 9, 9};
  CHECK(packed_table_size(5, liver, 1, 2) == 9LL * 9 * 9 * 8 * 8 * 4);
  CHECK(packed_table_size(5, liver, 1, 3) == 9LL * 9 * 8 * 8 * 8 * 8);
  CHECK(packed_table_size(5, liver, 3, 5) == 3LL * 32768 * 32);
  CHECK(packed_lookup_axes<double>(5) == 2);
  CHECK(packed_lookup_axes<float>(5) == 3);
  CHECK(packed_lookup_axes<float>(2) == 2);
  CHECK(packed_lookup_axes<double>(1) == 1);
  CHECK_FALSE(packed_layout_pays(2, 1ULL << 30, 1ULL << 32));  // two axes: 4 values in 2 sectors either way
  CHECK(packed_layout_pays(5, 59049ULL * 8, 186624ULL * 8));       // 9^5 double: neither fits L1
  CHECK_FALSE(packed_layout_pays(5, 16807ULL * 8, 49392ULL * 8));  // 7^5 double: only the grid fits
  CHECK(packed_layout_pays(5, 3125ULL * 8, 8000ULL * 8));          // 5^5 double: both fit
  CHECK_FALSE(packed_layout_pays(5, kL1TableBytes, kL1TableBytes + 1));
  CHECK(packed_layout_pays(5, kL1TableBytes + 1, kL1TableBytes * 4));
}

TEST_CASE("packed table lookups equal grid lookups bit for bit", "[table][packed]") {
  std::mt19937_64 random(20261122);
  check_every_depth<1, double>(random);
  check_every_depth<2, double>(random);
  check_every_depth<3, double>(random);
  check_every_depth<4, double>(random);
  check_every_depth<5, double>(random);
  check_every_depth<6, double>(random);
  check_every_depth<1, float>(random);
  check_every_depth<3, float>(random);
  check_every_depth<5, float>(random);
}
