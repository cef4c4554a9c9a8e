// What the command line does for a user, through the real binary: eval on a terminal says what it needs instead of
// waiting, --summary prints one row per point, and re-running simulate into a folder leaves one run there.
#include <catch2/catch.hpp>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/fmpc_process.h"

namespace {

namespace fs = std::filesystem;

using fmpc::testing::read_file_text;
using Run = fmpc::testing::FmpcRun;
using fmpc::testing::run_fmpc;

const fs::path kSource = FMPC_SOURCE_DIR;

}  // namespace

TEST_CASE("eval with no points on a terminal says what it expects, with the file's own inputs", "[cli]") {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  REQUIRE(master >= 0);
  REQUIRE(::grantpt(master) == 0);
  REQUIRE(::unlockpt(master) == 0);
  const std::string terminal = ::ptsname(master);
  const fs::path tipper = kSource / "tests" / "golden" / "cli_eval_explain" / "tipper.fis";
  // `timeout` turns a wait on the terminal into status 124 after 60 s: the test fails instead of hanging.
  const Run eval = run_fmpc("eval " + tipper.string(), terminal);
  ::close(master);
  CHECK(eval.status == 2);
  CHECK(eval.out.find("no points to evaluate") != std::string::npos);
  CHECK(eval.out.find("service=") != std::string::npos);
  CHECK(eval.out.find("food=") != std::string::npos);
  CHECK(eval.out.find("header row: service,food") != std::string::npos);
  CHECK(eval.out.find("HCV") == std::string::npos);  // not the liver's inputs
}

TEST_CASE("eval --summary prints one aligned row per point with 4 significant digits", "[cli]") {
  const fs::path liver = kSource / "rulesets" / "liver_fibrosis";
  const Run summary = run_fmpc("eval " + (liver / "mamdani.fis").string() + " --csv " +
                          (liver / "example_patients.csv").string() + " --summary");
  REQUIRE(summary.status == 0);
  std::istringstream lines(summary.out);
  std::string header;
  std::getline(lines, header);
  CHECK(header.find("stiffness (kPa)") != std::string::npos);
  CHECK(header.find("strongest rule") != std::string::npos);
  std::size_t rows = 0;
  for (std::string line; std::getline(lines, line);) {
    ++rows;
    CHECK(line.size() <= header.size() + 24);
    CHECK(line.find("0000000") == std::string::npos);  // no 17-digit residues
  }
  const std::string csv = read_file_text(liver / "example_patients.csv");
  CHECK(rows + 1 == static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')));
  CHECK(run_fmpc("eval " + (liver / "mamdani.fis").string() + " --csv " + (liver / "example_patients.csv").string() +
            " --summary --explain")
            .status == 2);  // one or the other
}

TEST_CASE("re-running simulate into a folder removes the earlier run's extra frames, and nothing else", "[cli]") {
  const fs::path folder = fs::temp_directory_path() / "fmpc_cli_behaviour_simulate";
  fs::remove_all(folder);
  fs::create_directories(folder / "out");
  fs::copy_file(kSource / "rulesets" / "scenes" / "strain_stiffening.fis", folder / "strain_stiffening.fis");
  const std::string scene = read_file_text(kSource / "rulesets" / "scenes" / "strain_stiffening_block.yaml");
  const auto write_scene = [&](int frames) {
    std::string text = scene;
    const std::string from = "outputs: {frames: 9, samples: 81}";
    REQUIRE(text.find(from) != std::string::npos);
    text.replace(text.find(from), from.size(), "outputs: {frames: " + std::to_string(frames) + ", samples: 10}");
    std::ofstream(folder / "block.yaml") << text;
  };
  // Files fmpc did not write: a frame no .pvd lists, and a .pvd that is not fmpc's.
  std::ofstream(folder / "out" / "frame_99999.vtu") << "mine";
  std::ofstream(folder / "out" / "notes.pvd") << "<?xml version=\"1.0\"?>\n<mine/>\n";
  write_scene(6);
  const std::string command = "simulate " + (folder / "block.yaml").string() + " -o " + (folder / "out").string() +
                              " --steps 40";
  const Run first = run_fmpc(command);
  INFO(first.out);
  REQUIRE(first.status == 0);
  CHECK(fs::exists(folder / "out" / "frame_00005.vtu"));
  write_scene(3);
  const Run second = run_fmpc(command);
  INFO(second.out);
  REQUIRE(second.status == 0);
  CHECK(second.out.find("removed 3 stale files of an earlier run") != std::string::npos);
  for (int k = 0; k < 3; ++k) CHECK(fs::exists(folder / "out" / ("frame_0000" + std::to_string(k) + ".vtu")));
  for (int k = 3; k < 6; ++k) CHECK_FALSE(fs::exists(folder / "out" / ("frame_0000" + std::to_string(k) + ".vtu")));
  CHECK(fs::exists(folder / "out" / "frame_99999.vtu"));
  CHECK(fs::exists(folder / "out" / "notes.pvd"));
  CHECK(fs::exists(folder / "out" / "strain_stiffening_block.pvd"));
  fs::remove_all(folder);
}

TEST_CASE("every command that can run long reports progress and the time left on a pipe", "[cli][heavy]") {
  // Issue 30: trade --points 10000000 and plot of a 100,000-rule system ran silently when stderr was not a
  // terminal. FMPC_PROGRESS_SECONDS shortens the period of the plain lines (10 s by default) so that runs of a
  // fraction of a second show them.
  const fs::path folder = fs::temp_directory_path() / ("fmpc_progress_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const std::string mamdani = (kSource / "rulesets" / "liver_fibrosis" / "mamdani.fis").string();
  {
    std::ofstream points(folder / "points.csv");
    points << "HCV,HBV,ALD,CLD,NAFLD\n";
    for (int k = 0; k < 3000; ++k) points << k % 60 << ",10,12,11,11.2\n";
  }
  REQUIRE(::setenv("FMPC_PROGRESS_SECONDS", "0.01", 1) == 0);
  const std::string out = (folder / "out").string();
  const std::vector<std::pair<std::string, std::string>> commands = {
      {"eval", "eval " + mamdani + " --csv " + (folder / "points.csv").string() + " -o " + out + ".csv"},
      {"plot", "plot " + mamdani + " --x HCV --y HBV --resolution 61 -o " + out + ".png"},
      {"convert", "convert " + mamdani + " --to fll -o " + out + ".fll"},
      {"trade", "trade " + (kSource / "tests" / "golden" / "fll_eval" / "tipper.fll").string() +
                    " --points 200000 --min-seconds 0.01 --resolutions 3 --cxx false"},
      {"simulate", "simulate " + (kSource / "rulesets" / "scenes" / "liver_indentation.yaml").string() +
                       " --steps 3000 -o " + out + "_run"},
      {"compile", "compile " + mamdani + " --target table --fix ALD=12 --fix CLD=11 --fix NAFLD=11.2 "
                                         "--max-error 5 -o " + out + ".fzt"},
      {"thesis-benchmark", "thesis-benchmark " + mamdani + " --patients " +
                               (kSource / "rulesets" / "liver_fibrosis" / "example_patients.csv").string()}};
  for (const auto& [name, arguments] : commands) {
    const Run run = run_fmpc(arguments);
    INFO(arguments << "\n" << run.out.substr(0, 3000));
    CHECK(run.status == 0);
    CHECK(run.out.find("fmpc " + name + ": progress: ") != std::string::npos);
    CHECK(run.out.find(" left") != std::string::npos);
  }
  ::unsetenv("FMPC_PROGRESS_SECONDS");
  fs::remove_all(folder);
}
