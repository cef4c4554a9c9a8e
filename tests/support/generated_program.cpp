#include "tests/support/generated_program.h"

#include <cstdlib>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <system_error>

#include <catch2/catch.hpp>

#include "tests/support/random_system.h"

namespace fmpc::testing {

namespace fs = std::filesystem;

std::string read_text_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

ScratchFolder::ScratchFolder(const std::string& tag) {
  std::random_device device;
  path_ = fs::temp_directory_path() / ("fmpc_emit_" + tag + "_" + std::to_string(device()));
  fs::create_directories(path_);
}

ScratchFolder::~ScratchFolder() {
  std::error_code ignored;
  fs::remove_all(path_, ignored);
}

bool compile_generated_program(const fs::path& source, const fs::path& program, std::string& log) {
  const fs::path log_path = program.string() + ".log";
  const std::string command = std::string(FMPC_CXX_COMPILER) +
                              " -std=c++17 -O1 -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wdouble-promotion "
                              "-Wold-style-cast -Werror -o " +
                              program.string() + " " + source.string() + " > " + log_path.string() + " 2>&1";
  const int status = std::system(command.c_str());
  log = read_text_file(log_path);
  return status == 0;
}

std::vector<std::vector<double>> evaluator_test_points(const FuzzySystem& system, std::uint64_t seed,
                                                       std::size_t count) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<std::vector<double>> points = random_inputs(system, seed, count);
  const std::size_t d = system.inputs.size();
  std::vector<double> low(d), high(d), below(d), above(d), infinite(d), nan(d);
  for (std::size_t i = 0; i < d; ++i) {
    const Variable& v = system.inputs[i];
    low[i] = v.min;
    high[i] = v.max;
    below[i] = v.min - (v.max - v.min) / 3.0;
    above[i] = v.max + (v.max - v.min) / 7.0;
    infinite[i] = i % 2 ? kInf : -kInf;
    nan[i] = i == d / 2 ? std::numeric_limits<double>::quiet_NaN() : v.min;
  }
  for (auto* edge : {&low, &high, &below, &above, &infinite, &nan}) points.push_back(*edge);
  return points;
}

void check_line_directives(const std::string& header, const std::string& header_name, const std::string& rule_file,
                           const FuzzySystem& system) {
  std::istringstream lines(header);
  std::string line;
  int physical = 0, rule_directives = 0, return_directives = 0;
  std::size_t next_rule = 0;
  while (std::getline(lines, line)) {
    ++physical;
    if (line.rfind("#line ", 0) != 0) continue;
    std::istringstream directive(line.substr(6));
    int number = 0;
    std::string file;
    directive >> number >> file;
    if (file == "\"" + header_name + "\"") {
      CHECK(number == physical + 1);
      ++return_directives;
    } else {
      CHECK(file == "\"" + rule_file + "\"");
      REQUIRE(next_rule < system.rules.size());
      CHECK(number == system.rules[next_rule++].range.line);
      ++rule_directives;
    }
  }
  CHECK(rule_directives == static_cast<int>(system.rules.size()));
  CHECK(return_directives == rule_directives);
}

}  // namespace fmpc::testing
