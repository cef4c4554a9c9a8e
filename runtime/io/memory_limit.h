#pragma once
// The memory this process may use, for the checks made before large allocations (docs/limits.md): the smallest of
// the machine's physical memory, the process's address-space and data-segment limits (RLIMIT_AS, RLIMIT_DATA:
// `ulimit -v`, `ulimit -d`) and its cgroup's limit (cgroup v2 memory.max, v1 memory.limit_in_bytes), each with the
// name of what set it. An ellipsoid of resolution 110 once passed the physical-memory check and died of
// std::bad_alloc under a process limit.
#include <cstdint>
#include <string>

namespace fmpc::sim {

struct MemoryLimit {
  std::uint64_t bytes = 0;  // 0 when nothing could be read (then no check refuses anything)
  std::string source;       // "physical memory", "the process limit RLIMIT_AS (ulimit -v)", "the cgroup limit ..."
};

MemoryLimit memory_limit();

// "1.25 GiB": a size for messages, three significant digits.
std::string gibibytes_text(double bytes);

}  // namespace fmpc::sim
