#pragma once
// The two clocks of the setup and frame benchmarks: wall time, and the process's CPU time (every thread), which on a
// machine shared with other sessions measures the code where the wall time measures their load.
#include <chrono>
#include <ctime>

namespace fmpc::bench {

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

inline double cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

}  // namespace fmpc::bench
