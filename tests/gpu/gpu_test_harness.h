#pragma once
// A small test registry for the GPU tests. The GPU machine has none of the Debian packages (no Catch2), so the
// GPU test program carries its own runner (gpu_test_main.cpp): tests register themselves, say whether they need a
// device, and record failures with file and line. Without a device the device tests are reported as skipped and
// the program still passes.
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace fmpc::gpu_test {

struct TestCase {
  const char* id;    // the function's name: what the runner's arguments and --list name
  const char* name;  // a sentence for the log
  bool needs_device;
  void (*run)();
};

std::vector<TestCase>& registry();
void record_failure(const char* file, int line, const std::string& what);
// An informative line in the test's output (measured differences, reports).
void note(const std::string& text);

struct Registration {
  Registration(const char* id, const char* name, bool needs_device, void (*run)()) {
    registry().push_back({id, name, needs_device, run});
  }
};

}  // namespace fmpc::gpu_test

#define FMPC_GPU_TEST_CONCAT_(a, b) a##b
#define FMPC_GPU_TEST_CONCAT(a, b) FMPC_GPU_TEST_CONCAT_(a, b)
// FMPC_GPU_TEST(function, "name", needs_device) { body }
#define FMPC_GPU_TEST(function, name, needs_device)                                                             \
  static void function();                                                                                       \
  static const ::fmpc::gpu_test::Registration FMPC_GPU_TEST_CONCAT(function, _registration)(#function, name,   \
                                                                                            needs_device, function); \
  static void function()

#define FMPC_EXPECT(condition)                                                                      \
  do {                                                                                              \
    if (!(condition)) ::fmpc::gpu_test::record_failure(__FILE__, __LINE__, "expected " #condition); \
  } while (false)

// Stops the test (returns) when the condition does not hold.
#define FMPC_REQUIRE(condition)                                                     \
  do {                                                                              \
    if (!(condition)) {                                                             \
      ::fmpc::gpu_test::record_failure(__FILE__, __LINE__, "required " #condition); \
      return;                                                                       \
    }                                                                               \
  } while (false)

#define FMPC_EXPECT_WITHIN(value, expected, tolerance)                                                          \
  do {                                                                                                          \
    const double fmpc_value = (value), fmpc_expected = (expected), fmpc_tolerance = (tolerance);                \
    if (!(std::abs(fmpc_value - fmpc_expected) <= fmpc_tolerance)) {                                            \
      std::ostringstream fmpc_message;                                                                          \
      fmpc_message.precision(17);                                                                               \
      fmpc_message << #value " = " << fmpc_value << ", expected " << fmpc_expected << " +- " << fmpc_tolerance; \
      ::fmpc::gpu_test::record_failure(__FILE__, __LINE__, fmpc_message.str());                                 \
    }                                                                                                           \
  } while (false)
