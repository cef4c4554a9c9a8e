#include "runtime/io/memory_limit.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>

namespace fmpc::sim {

namespace {

// The cgroup this process is in, as /proc/self/cgroup names it: "0::/PATH" (v2), or the memory controller's line.
std::uint64_t cgroup_limit(std::string& file) {
  std::ifstream groups("/proc/self/cgroup");
  std::uint64_t smallest = 0;
  for (std::string line; std::getline(groups, line);) {
    const std::size_t first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1);
    const std::string path = line.substr(second + 1);
    std::string candidate;
    if (controllers.empty()) candidate = "/sys/fs/cgroup" + path + "/memory.max";  // v2
    else if (controllers.find("memory") != std::string::npos)
      candidate = "/sys/fs/cgroup/memory" + path + "/memory.limit_in_bytes";  // v1
    else
      continue;
    std::ifstream limit(candidate);
    std::string text;
    if (!(limit >> text) || text == "max") continue;
    std::istringstream number(text);
    std::uint64_t bytes = 0;
    // v1 writes a number near 2^63 for "no limit".
    if (!(number >> bytes) || bytes == 0 || bytes >= (std::uint64_t{1} << 62)) continue;
    if (smallest == 0 || bytes < smallest) {
      smallest = bytes;
      file = candidate;
    }
  }
  return smallest;
}

}  // namespace

MemoryLimit memory_limit() {
  MemoryLimit limit;
  const auto consider = [&](std::uint64_t bytes, const std::string& source) {
    if (bytes > 0 && (limit.bytes == 0 || bytes < limit.bytes)) limit = MemoryLimit{bytes, source};
  };
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page > 0)
    consider(static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page), "this machine's memory");
  for (const auto& [resource, name] : {std::pair<int, const char*>{RLIMIT_AS, "RLIMIT_AS (ulimit -v)"},
                                       std::pair<int, const char*>{RLIMIT_DATA, "RLIMIT_DATA (ulimit -d)"}}) {
    rlimit value{};
    if (::getrlimit(resource, &value) == 0 && value.rlim_cur != RLIM_INFINITY)
      consider(static_cast<std::uint64_t>(value.rlim_cur), std::string("this process's limit ") + name);
  }
  std::string file;
  const std::uint64_t cgroup = cgroup_limit(file);
  consider(cgroup, "this process's cgroup limit (" + file + ")");
  return limit;
}

std::string gibibytes_text(double bytes) {
  char text[64];
  std::snprintf(text, sizeof text, "%.3g GiB", bytes / static_cast<double>(std::uint64_t{1} << 30));
  return text;
}

}  // namespace fmpc::sim
