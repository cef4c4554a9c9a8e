// Runs the registered GPU tests: all of them, or those whose name contains one of the arguments. Device tests are
// skipped (visibly) when no CUDA device can be used; the program then still exits 0 unless a host test failed.
#include <cstdio>
#include <iostream>
#include <string>

#include "runtime/gpu/gpu_simulation.h"
#include "tests/gpu/gpu_test_harness.h"

namespace fmpc::gpu_test {

namespace {
int failures_in_current_test = 0;
}  // namespace

std::vector<TestCase>& registry() {
  static std::vector<TestCase> tests;
  return tests;
}

void record_failure(const char* file, int line, const std::string& what) {
  ++failures_in_current_test;
  std::cout << "    " << file << ":" << line << ": FAILED: " << what << "\n";
}

void note(const std::string& text) { std::cout << "    " << text << "\n"; }

}  // namespace fmpc::gpu_test

int main(int argc, char** argv) {
  using namespace fmpc::gpu_test;
  // bench/run_gpu.sh runs each sanitizer smoke under each tool in a process of its own.
  if (argc == 2 && std::string(argv[1]) == "--list") {
    for (const TestCase& test : registry()) std::cout << test.id << "\n";
    return 0;
  }
  std::string device;
  const bool have_device = fmpc::gpu::cuda_device_available(device);
  std::cout << (have_device ? "CUDA device: " + device : "no CUDA device (" + device + ")") << "\n";
  int passed = 0, failed = 0, skipped = 0;
  for (const TestCase& test : registry()) {
    bool selected = argc < 2;
    // An argument selects the tests whose id or sentence contains it.
    for (int i = 1; i < argc; ++i)
      selected = selected || std::string(test.id).find(argv[i]) != std::string::npos ||
                 std::string(test.name).find(argv[i]) != std::string::npos;
    if (!selected) continue;
    if (test.needs_device && !have_device) {
      std::cout << "[ SKIP ] " << test.name << "\n";
      ++skipped;
      continue;
    }
    std::cout << "[ RUN  ] " << test.name << "\n" << std::flush;
    failures_in_current_test = 0;
    test.run();
    std::cout << (failures_in_current_test == 0 ? "[ PASS ] " : "[ FAIL ] ") << test.name << "\n" << std::flush;
    (failures_in_current_test == 0 ? passed : failed) += 1;
  }
  std::cout << passed << " passed, " << failed << " failed, " << skipped << " skipped\n";
  // ctest's SKIP_REGULAR_EXPRESSION matches this line; it is printed only when nothing failed.
  if (failed == 0 && skipped > 0) std::cout << "SKIPPED: " << skipped << " device tests need a CUDA device\n";
  if (passed + failed + skipped == 0) {
    std::cout << "no test matches the arguments\n";
    return 1;
  }
  return failed == 0 ? 0 : 1;
}
