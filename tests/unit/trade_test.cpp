// fmpc trade (tools/fmpc/trade_command.cpp) end to end on a small MATLAB system, and the Pareto front of its plot.
#include <catch2/catch.hpp>

#include <sys/wait.h>

#include <algorithm>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "tools/plot/pareto_plot.h"

namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("the Pareto front keeps the points nothing beats on both speed and error", "[trade]") {
  using fmpc::plot::TradePoint;
  const std::vector<TradePoint> points{{"exact", 100, 0.0, "interpreter"},
                                       {"sampled", 1e4, 0.05, "interpreter"},
                                       {"slow and bad", 50, 0.5, ""},
                                       {"compiled", 4e6, 0.05, "compiled C++"},
                                       {"table", 1e7, 0.2, "table"},
                                       {"same as compiled", 4e6, 0.05, "compiled C++"}};
  const std::vector<std::size_t> front = fmpc::plot::pareto_front(points);
  // "sampled" is beaten by "compiled" (faster, same error); ties do not dominate each other.
  CHECK(front == std::vector<std::size_t>{0, 3, 5, 4});
  CHECK(fmpc::plot::pareto_front({}).empty());
  const std::string png = fmpc::plot::render_trade_plot({points, "kPa", {"title"}}, fmpc::plot::ImageFormat::Png);
  CHECK(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
}

TEST_CASE("fmpc trade measures every variant and writes markdown, CSV and a PNG", "[trade]") {
  const fs::path tipper = fs::path(FMPC_SOURCE_DIR) / "tests" / "golden" / "cli_eval_csv" / "tipper.fis";
  std::random_device device;
  const fs::path folder = fs::temp_directory_path() / ("fmpc_trade_test_" + std::to_string(device()));
  fs::create_directories(folder);
  const std::string command = std::string(FMPC_BINARY) + " trade " + tipper.string() +
                              " --points 60 --min-seconds 0.01 --resolutions 3,9 -o " + (folder / "t.md").string() +
                              " --csv " + (folder / "t.csv").string() + " --plot " + (folder / "t.png").string() + " > " +
                              (folder / "out.md").string() + " 2> " + (folder / "err.txt").string();
  const int status = std::system(command.c_str());
  INFO(read_text(folder / "err.txt"));
  REQUIRE(status == 0);
  const std::string markdown = read_text(folder / "out.md");
  const std::string csv = read_text(folder / "t.csv");
  CHECK(read_text(folder / "t.md") == markdown);  // -o writes what is printed, as in validate and diff
  CHECK(markdown.find("| interpreter | samples exact (reference) | 0 | 0 |") != std::string::npos);
  CHECK(markdown.find("| compiled C++ | double") != std::string::npos);
  CHECK(markdown.find("| compiled C++ | float") != std::string::npos);
  CHECK(markdown.find("| table | 3x3 uniform") != std::string::npos);
  CHECK(markdown.find("| table | 9x9 uniform") != std::string::npos);
  CHECK(csv.rfind("variant,detail,max_error,rms_error,evaluations_per_second,memory_bytes,memory_note\n", 0) == 0);
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 7);  // header + exact, sampled, double, float, two tables
  const std::string png = read_text(folder / "t.png");
  CHECK(png.substr(1, 3) == "PNG");

  // An unknown input is a located error, exit status 2.
  const std::string bad = std::string(FMPC_BINARY) + " trade " + tipper.string() + " --fix nosuch=1 > " +
                          (folder / "bad.txt").string() + " 2>&1";
  CHECK(WEXITSTATUS(std::system(bad.c_str())) == 2);
  CHECK(read_text(folder / "bad.txt").find("nosuch") != std::string::npos);
  std::error_code ignored;
  fs::remove_all(folder, ignored);
}
