// CheapestFirstSchedule (runtime/scene/trade_schedule.h): the order `fmpc trade --max-error` runs its variants in
// on the CPU and which it skips. Hand-made cases (ties, an estimate exactly at the bound, NaN, a bound given at the
// start) and a seeded property test in which two workers finish runs out of order, with measured costs off their
// estimates: nothing cheaper than the bound is ever skipped, and every skipped estimate is above the final choice.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "runtime/scene/trade_schedule.h"

using fmpc::sim::CheapestFirstSchedule;

namespace {

std::vector<std::size_t> skipped_ids(const CheapestFirstSchedule& schedule) {
  std::vector<std::size_t> ids;
  for (const CheapestFirstSchedule::Skip& skip : schedule.skipped()) ids.push_back(skip.id);
  return ids;
}

}  // namespace

TEST_CASE("cheapest first: ascending estimates, ties in the order added, NaN last", "[trade][schedule]") {
  CheapestFirstSchedule schedule;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> estimates{3.0, 1.0, nan, 2.0, 1.0, 0.0};
  for (std::size_t i = 0; i < estimates.size(); ++i) schedule.add(i, estimates[i]);
  std::vector<std::size_t> order;
  while (const auto next = schedule.next()) order.push_back(*next);
  CHECK(order == std::vector<std::size_t>{5, 1, 4, 3, 0, 2});
  CHECK(schedule.skipped().empty());  // no run met E: nothing bounds them
  CHECK(schedule.bound() == HUGE_VAL);
  CHECK_FALSE(schedule.next());
}

TEST_CASE("cheapest first: a run meeting E bounds the rest, exactly at the bound runs, above it is skipped",
          "[trade][schedule]") {
  CheapestFirstSchedule schedule;
  // 0.5 (misses E), 1.0 (meets, costs 1.0), then 1.0 exactly at the bound, 1.0 + 1 ulp, 4.0.
  const std::vector<double> estimates{4.0, std::nextafter(1.0, 2.0), 1.0, 0.5, 1.0};
  for (std::size_t i = 0; i < estimates.size(); ++i) schedule.add(i, estimates[i]);
  REQUIRE(schedule.next() == std::optional<std::size_t>(3));
  schedule.finished(0.5, false);  // cheap but not within E: no bound
  CHECK(schedule.bound() == HUGE_VAL);
  REQUIRE(schedule.next() == std::optional<std::size_t>(2));
  schedule.finished(1.0, true);
  CHECK(schedule.bound() == 1.0);
  CHECK(schedule.beyond_bound(std::nextafter(1.0, 2.0)));
  CHECK_FALSE(schedule.beyond_bound(1.0));
  // The tie at the bound runs (it may cost less than its estimate); the next ulp and 4.0 do not.
  REQUIRE(schedule.next() == std::optional<std::size_t>(4));
  schedule.finished(1.25, true);  // meets, but dearer: the bound stays
  CHECK(schedule.bound() == 1.0);
  CHECK_FALSE(schedule.next());
  CHECK(skipped_ids(schedule) == std::vector<std::size_t>{1, 0});
  for (const CheapestFirstSchedule::Skip& skip : schedule.skipped()) {
    CHECK(skip.bound == 1.0);
    CHECK(skip.estimate > skip.bound);
  }
}

TEST_CASE("cheapest first: a bound given at the start (an earlier level's) skips before anything runs, a NaN "
          "estimate is never skipped, a run ended before it was scheduled lowers the bound",
          "[trade][schedule]") {
  CheapestFirstSchedule schedule(0.25);
  schedule.add(7, 0.3);
  schedule.add(8, std::numeric_limits<double>::quiet_NaN());
  schedule.add(9, 0.25);
  REQUIRE(schedule.next() == std::optional<std::size_t>(9));
  REQUIRE(schedule.next() == std::optional<std::size_t>(8));  // 7 passed over on the way
  CHECK(skipped_ids(schedule) == std::vector<std::size_t>{7});
  schedule.finished(0.0, true);  // zero seconds (a clock too coarse for it) is a cost like any other
  CHECK(schedule.bound() == 0.0);
  CHECK_FALSE(schedule.next());
  // Before any next(): a prefix that was the whole run.
  CheapestFirstSchedule early;
  early.finished(0.1, true);
  early.add(0, 0.2);
  CHECK_FALSE(early.next());
  CHECK(skipped_ids(early) == std::vector<std::size_t>{0});
}

TEST_CASE("cheapest first, seeded: two workers finishing out of order never skip a run the choice could not beat",
          "[trade][schedule]") {
  std::mt19937_64 random(20261127);
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t count = 1 + random() % 40;
    std::uniform_real_distribution<double> estimate_of(0.0, 10.0);
    std::uniform_real_distribution<double> error_of(0.8, 1.25);  // what a measured run is off its estimate
    std::vector<double> estimates(count), costs(count);
    std::vector<bool> meets(count);
    for (std::size_t i = 0; i < count; ++i) {
      // Round to tenths: many ties.
      estimates[i] = std::round(estimate_of(random) * 10.0) / 10.0;
      costs[i] = estimates[i] * error_of(random);
      meets[i] = random() % 3 == 0;
    }
    CheapestFirstSchedule schedule;
    for (std::size_t i = 0; i < count; ++i) schedule.add(i, estimates[i]);
    // Two workers: each holds at most one run; the one that finishes next is drawn at random.
    std::vector<std::size_t> started, running;
    std::vector<double> bound_when_started;
    double chosen = HUGE_VAL;
    for (;;) {
      while (running.size() < 2) {
        const auto next = schedule.next();
        if (!next) break;
        bound_when_started.push_back(schedule.bound());
        started.push_back(*next);
        running.push_back(*next);
      }
      if (running.empty()) break;
      const std::size_t which = random() % running.size();
      const std::size_t done = running[which];
      running.erase(running.begin() + static_cast<std::ptrdiff_t>(which));
      schedule.finished(costs[done], meets[done]);
      if (meets[done]) chosen = std::min(chosen, costs[done]);
    }
    INFO("trial " << trial);
    // Every run is started or skipped, once.
    std::vector<std::size_t> all = started;
    for (const std::size_t id : skipped_ids(schedule)) all.push_back(id);
    std::sort(all.begin(), all.end());
    std::vector<std::size_t> expected(count);
    for (std::size_t i = 0; i < count; ++i) expected[i] = i;
    CHECK(all == expected);
    // Started in ascending estimate, ties by id, each within the bound of its time.
    for (std::size_t n = 0; n < started.size(); ++n) {
      CHECK(estimates[started[n]] <= bound_when_started[n]);
      if (n > 0) {
        const std::size_t a = started[n - 1], b = started[n];
        CHECK((estimates[a] < estimates[b] || (estimates[a] == estimates[b] && a < b)));
      }
    }
    // The final bound is the cheapest run that met E; every skip's estimate is above it and above its own bound.
    CHECK(schedule.bound() == chosen);
    for (const CheapestFirstSchedule::Skip& skip : schedule.skipped()) {
      CHECK(skip.estimate == estimates[skip.id]);
      CHECK(skip.estimate > skip.bound);
      CHECK(skip.bound >= chosen);
      // Nothing the chosen run could not beat by its estimate: not cheaper than it.
      CHECK(skip.estimate > chosen);
    }
  }
}
