// Hostile inputs (docs/limits.md): the caps of diagnostics, the bounded "did you mean", the bounded input reader,
// all-or-nothing outputs, the parser depth limit, scene duplicate keys, names and step counts, generated-mesh sizes.
// tests/hostile runs the same classes through the fmpc command line.
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "compiler/frontend/rule_file_loader.h"
#include "compiler/frontend/utf8.h"
#include "diagnostics/diagnostic.h"
#include "runtime/io/atomic_file.h"
#include "runtime/io/input_file.h"
#include "runtime/io/memory_limit.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/scene/scene_file.h"

using namespace fmpc;

namespace {

// The unbounded optimal string alignment distance, case-insensitive: the reference for the banded one.
std::size_t reference_distance(const std::string& a, const std::string& b) {
  auto same = [](char x, char y) { return std::tolower(x) == std::tolower(y); };
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (same(a[i - 1], b[j - 1]) ? 0 : 1)});
      if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// What closest_name returned before the band: the first candidate of smallest distance within the cap.
std::optional<std::string> reference_closest(const std::string& name, const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = std::max<std::size_t>(1, name.size() / 3) + 1;
  for (const std::string& c : candidates) {
    const std::size_t d = reference_distance(name, c);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  return best;
}

std::string temporary_folder(const std::string& name) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() /
                                       ("fmpc_hostile_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder.string();
}

std::vector<std::string> scene_errors(const std::string& text) {
  DiagnosticList diagnostics;
  (void)sim::parse_scene("/nonexistent-scenes/s.yaml", text, diagnostics);
  std::vector<std::string> errors;
  for (const Diagnostic& d : diagnostics.items())
    errors.push_back(std::to_string(d.range.line) + ":" + std::to_string(d.range.column) + ": " + d.message);
  return errors;
}

const char* kScene = "mesh: {box: {size: [1, 1, 1], cells: [2, 2, 2]}}\nmaterial: {youngs_modulus: 5}\n";

}  // namespace

TEST_CASE("the banded edit distance suggests exactly what the full one did", "[hostile]") {
  std::mt19937 random(12);
  const std::string alphabet = "abAB_1";
  auto word = [&](std::size_t max_length) {
    std::string w(random() % (max_length + 1), 'a');
    for (char& c : w) c = alphabet[random() % alphabet.size()];
    return w;
  };
  for (int trial = 0; trial < 3000; ++trial) {
    const std::string name = word(12);
    std::vector<std::string> candidates;
    const std::size_t count = random() % 6;
    for (std::size_t i = 0; i < count; ++i) {
      // Half the candidates are a few edits from the name, so that suggestions happen.
      std::string c = random() % 2 ? word(12) : name;
      for (std::size_t e = random() % 4; e > 0 && !c.empty(); --e) c[random() % c.size()] = alphabet[random() % 6];
      candidates.push_back(c);
    }
    INFO("name '" << name << "'");
    CHECK(closest_name(name, candidates) == reference_closest(name, candidates));
  }
  CHECK(closest_name("HVC", {"HCV", "HBV"}) == std::optional<std::string>("HCV"));
  CHECK(closest_name("", {"a", "bc"}) == std::optional<std::string>("a"));
}

TEST_CASE("did you mean stays cheap on megabyte names", "[hostile]") {
  const std::string long_name(1 << 20, 'a');
  std::string other = long_name;
  other.back() = 'b';
  CHECK_FALSE(closest_name(long_name, {other}).has_value());  // not compared: longer than kMaxSuggestedNameBytes
  CHECK_FALSE(closest_name("F3", {long_name}).has_value());
  std::vector<std::string> many(kMaxSuggestionCandidates + 10, "zzzzzz");
  many.push_back("F3x");  // beyond the candidates examined
  CHECK_FALSE(closest_name("F3", many).has_value());
}

TEST_CASE("diagnostics cap their excerpt, their text and their count", "[hostile]") {
  const std::string line(100000, 'x');
  SourceFiles sources;
  sources.add("long.fis", "first\n" + line + "\n");
  DiagnosticList diagnostics;
  for (int i = 0; i < 250; ++i) diagnostics.error(SourceRange{"long.fis", 2, 50000 + i, 2, 50001 + i}, "bad " + std::to_string(i));
  const std::string text = render_all(diagnostics, sources);
  // 100 rendered, each with a window of at most kMaxExcerptBytes (+ the two "..." marks), then one summary line.
  CHECK(text.size() < 100 * (2 * kMaxExcerptBytes + 100) + 200);
  CHECK(text.find("... and 150 more not shown: 150 errors, 0 warnings") != std::string::npos);
  CHECK(text.find(" 2 | ...xxx") != std::string::npos);
  // The caret sits under the column inside the window.
  const std::size_t source_line = text.find(" 2 | ...");
  const std::size_t caret_line = text.find('\n', source_line) + 1;
  const std::size_t caret = text.find('^', caret_line) - caret_line;
  CHECK(caret - 5 == kMaxExcerptBytes / 2 + 3);  // " 2 | " is 5 bytes, "..." 3

  DiagnosticList long_message;
  long_message.error(SourceRange{"f", 1, 1, 1, 2}, "unknown name '" + std::string(1 << 20, 'q') + "' here",
                     {std::string(5000, 'n')});
  const Diagnostic& d = long_message.items().front();
  CHECK(d.message.size() <= kMaxDiagnosticTextBytes + 40);
  CHECK(d.message.rfind("unknown name 'qq", 0) == 0);
  CHECK(d.message.find("[... ") != std::string::npos);
  CHECK(d.message.substr(d.message.size() - 6) == "' here");
  CHECK(d.notes.front().size() <= kMaxDiagnosticTextBytes + 40);

  DiagnosticList many;
  for (std::size_t i = 0; i < kMaxStoredDiagnostics + 7; ++i) many.warning(SourceRange{}, "w", "warning");
  many.error(SourceRange{}, "one more");
  CHECK(many.items().size() == kMaxStoredDiagnostics);
  CHECK(many.warning_count() == kMaxStoredDiagnostics + 7);
  CHECK(many.error_count() == 1);
  CHECK(many.dropped_count() == 8);
  DiagnosticList copy;
  copy.append(many);
  CHECK(copy.error_count() == 1);
}

TEST_CASE("the input reader refuses what is not a regular file, and files over their limit", "[hostile]") {
  const std::string folder = temporary_folder("input");
  std::string error;
  CHECK_FALSE(sim::read_input_file(folder, 1024, "rule file", error));
  CHECK(error.find("is a directory, not a rule file") != std::string::npos);
  CHECK_FALSE(sim::read_input_file("/dev/zero", 1024, "mesh file", error));
  CHECK(error.find("character device") != std::string::npos);
  const std::string fifo = folder + "/pipe";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK_FALSE(sim::read_input_file(fifo, 1024, "scene file", error));  // returns at once: no writer needed
  CHECK(error.find("FIFO") != std::string::npos);
  const std::string file = folder + "/f.txt";
  std::ofstream(file) << std::string(2000, 'a');
  CHECK_FALSE(sim::read_input_file(file, 1024, "CSV file", error));
  CHECK(error.find("the limit for a CSV file is 1 KiB") != std::string::npos);
  const auto text = sim::read_input_file(file, 2000, "CSV file", error);
  REQUIRE(text);
  CHECK(text->size() == 2000);
  CHECK_FALSE(sim::read_input_file(folder + "/missing", 10, "rule file", error));
  CHECK(error.find("No such file") != std::string::npos);
  CHECK_FALSE(sim::read_input_file(std::string("a\0b", 3), 10, "rule file", error));
  CHECK(error.find("NUL") != std::string::npos);
  std::filesystem::remove_all(folder);
}

TEST_CASE("an input of several kinds is read under the limit of the kind its first bytes name", "[hostile]") {
  // `fmpc eval` and fmpc.load_table: a table (signature, 1 KiB here) or a rule file (anything, 100 bytes here).
  const std::vector<sim::InputKind> kinds = {{"lookup table", 1024, "SIG!"}, {"rule file", 100, ""}};
  const std::string folder = temporary_folder("kinds");
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(folder + "/" + name, std::ios::binary) << text;
    return folder + "/" + name;
  };
  std::string error;
  // Every size on either side of each limit, for both kinds, and files shorter than the signature.
  for (const std::size_t size : {0, 3, 4, 99, 100, 101, 1023, 1024, 1025}) {
    for (const bool table : {true, false}) {
      std::string text = table ? "SIG!" : "rule";
      text.resize(std::max<std::size_t>(size, 0), 'x');
      if (size < 4) text = std::string(size, 'S');  // shorter than the signature: a rule file
      const bool is_table = table && size >= 4;
      const std::size_t limit = is_table ? 1024 : 100;
      INFO(size << (is_table ? " byte table" : " byte rule file"));
      const auto input = sim::read_input_file(write("f", text), kinds, error);
      CHECK(bool(input) == (size <= limit));
      if (input) {
        CHECK(input->kind == (is_table ? 0u : 1u));
        CHECK(input->contents == text);
      } else {
        CHECK(error.find(std::string("the limit for a ") + (is_table ? "lookup table" : "rule file")) !=
              std::string::npos);
      }
    }
  }
  // A gigabyte that is not a table is refused by the rule file's limit, before it is read (sparse: no disk used).
  const std::string big = folder + "/big";
  {
    std::ofstream(big).close();
    std::filesystem::resize_file(big, std::uintmax_t{1} << 30);
  }
  CHECK_FALSE(sim::read_input_file(big, kinds, error));
  CHECK(error.find("is 1 GiB; the limit for a rule file is 100 bytes") != std::string::npos);
  // With only the table kind, anything else is named as not a table after its first bytes.
  CHECK_FALSE(sim::read_input_file(big, {kinds[0]}, error));
  CHECK(error.find("it is not a lookup table") != std::string::npos);
  std::filesystem::remove_all(folder);
}

TEST_CASE("several outputs are written all or none", "[hostile]") {
  const std::string folder = temporary_folder("outputs");
  DiagnosticList diagnostics;
  CHECK_FALSE(sim::write_files_atomically({{folder + "/t.fzt", "table"}, {folder + "/missing/t.h", "header"}},
                                          diagnostics));
  CHECK(diagnostics.items().front().message.find("missing/t.h") != std::string::npos);
  CHECK(std::filesystem::is_empty(folder));  // neither the first output nor a temporary file is left
  DiagnosticList ok;
  CHECK(sim::write_files_atomically({{folder + "/a", "1"}, {folder + "/b", "22"}}, ok));
  CHECK(std::filesystem::file_size(folder + "/a") == 1);
  CHECK(std::filesystem::file_size(folder + "/b") == 2);
  DiagnosticList nul;
  CHECK_FALSE(sim::write_file_atomically(folder + std::string("/x\0y", 4), "z", nul));
  CHECK(nul.items().front().message.find("NUL") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(folder + "/x"));
  std::filesystem::remove_all(folder);
}

TEST_CASE("expressions nested past the parser's limit are located errors", "[hostile]") {
  auto matlab = [](const std::string& range) {
    return "[System]\nName='x'\nType='mamdani'\nNumInputs=1\nNumOutputs=1\nNumRules=0\n\n[Input1]\nName='a'\n"
           "Range=[0 " + range + "]\nNumMFs=1\nMF1='t':'trimf',[0 1 2]\n\n[Output1]\nName='y'\nRange=[0 1]\n"
           "NumMFs=1\nMF1='u':'trimf',[0 1 2]\n";
  };
  for (const std::string& deep : {std::string(30000, '(') + "1" + std::string(30000, ')'),
                                  std::string(30000, '-') + "1", std::string(5000, '+') + "2"}) {
    DiagnosticList diagnostics;
    (void)load_rule_file("deep.fis", matlab(deep), diagnostics);
    REQUIRE(diagnostics.has_errors());
    CHECK(diagnostics.items().front().message.find("nests deeper than the parser's limit") != std::string::npos);
    CHECK(diagnostics.items().front().range.line == 10);
  }
  // 60 parentheses and 60 signs are ordinary expressions.
  DiagnosticList fine;
  (void)load_rule_file("ok.fis", matlab(std::string(60, '(') + std::string(60, '-') + "1" + std::string(60, ')')),
                       fine);
  CHECK_FALSE(fine.has_errors());
}

TEST_CASE("a rule file that defines no system is an error", "[hostile]") {
  for (const std::string& text : {std::string(), std::string("# only\n# comments\n"), std::string("\n\n  \n")}) {
    DiagnosticList diagnostics;
    (void)load_rule_file("empty.fis", text, diagnostics);
    REQUIRE(diagnostics.error_count() == 1);
    CHECK(diagnostics.items().front().message.find("defines no system") != std::string::npos);
  }
}

TEST_CASE("scene files: duplicate keys, one document, nesting", "[hostile][scene]") {
  CHECK(scene_errors(std::string(kScene) + "material: {youngs_modulus: 6}\n") ==
        std::vector<std::string>{"3:1: material: duplicate key; YAML keeps only one of the two, so remove one"});
  CHECK(scene_errors("mesh: {box: {size: [1, 1, 1], size: [2, 2, 2]}}\nmaterial: {youngs_modulus: 5}\n") ==
        std::vector<std::string>{"1:31: mesh.box.size: duplicate key; YAML keeps only one of the two, so remove one"});
  CHECK(scene_errors(std::string(kScene) + "fixed:\n  box:\n    - {min: [0, 0, 0], max: [1, 1, 1], min: [0, 0, 0]}\n") ==
        std::vector<std::string>{
            "5:40: fixed.box[0].min: duplicate key; YAML keeps only one of the two, so remove one"});
  // The same key in two maps is not a duplicate.
  CHECK(scene_errors(std::string(kScene) + "fixed: {box: [{min: [0, 0, 0], max: [1, 1, 1]}, {min: [0, 0, 0], max: "
                                           "[1, 1, 1]}]}\n")
            .empty());
  CHECK(scene_errors(std::string(kScene) + "---\nname: x\n").front().find("more than one YAML document") !=
        std::string::npos);
  CHECK(scene_errors("mesh: " + std::string(100, '[') + std::string(100, ']') + "\n").front() ==
        "1:38: the YAML nests deeper than 32 levels; a scene needs about 6: check the indentation and brackets");
}

TEST_CASE("scene names cannot lead out of the output folder", "[hostile][scene]") {
  for (const std::string& bad : std::vector<std::string>{"../x", "/tmp/x", "a/b", "a\\\\b", "..", ".", "\"a\\0b\"", "\"a\\nb\"",
                                 std::string(201, 'n')}) {
    INFO(bad);
    const auto errors = scene_errors("name: " + bad + "\n" + kScene);
    REQUIRE(errors.size() == 1);
    CHECK(errors.front().rfind("1:7: name: ", 0) == 0);
  }
  CHECK(scene_errors(std::string("name: liver-01_a.b\n") + kScene).empty());
  CHECK(sim::output_name_problem("a.b-c_d") == std::nullopt);
  CHECK(sim::output_name_problem("..").has_value());
}

TEST_CASE("step counts are checked before they become integers", "[hostile][scene]") {
  CHECK(scene_errors(std::string(kScene) + "duration: 1e15\ndt: 1e-3\n").front().rfind("4:5: dt: duration 1e+15 s", 0) == 0);
  CHECK(scene_errors(std::string(kScene) + "dt: 1e-300\n").size() == 1);
  CHECK(scene_errors(std::string(kScene) + "duration: 1\ndt: 1e-9\n").empty());  // exactly 1e9 steps
  DiagnosticList diagnostics;
  auto scene = sim::parse_scene("/nonexistent-scenes/s.yaml", std::string(kScene) + "duration: 1e15\n", diagnostics);
  REQUIRE(scene);
  CHECK_FALSE(sim::planned_step_count(*scene, 1e-4, diagnostics));  // dt auto: the runner's check
  CHECK(diagnostics.items().front().message.find("the limit is") != std::string::npos);
  CHECK(diagnostics.items().front().range.line == 3);
  DiagnosticList fine;
  CHECK(sim::planned_step_count(*scene, 1e7, fine) == std::optional<std::size_t>(100000000));
}

TEST_CASE("generated meshes are sized before they are allocated", "[hostile][scene]") {
  sim::BoxSpec box;
  box.cells_x = box.cells_y = box.cells_z = 1000;
  CHECK(sim::tetrahedron_count(box) == 6000000000ULL);
  DiagnosticList diagnostics;
  const sim::Mesh mesh = sim::generate_box(box, diagnostics);
  CHECK(mesh.points.empty());
  REQUIRE(diagnostics.has_errors());
  CHECK(diagnostics.items().front().message.find("the limit is 268435456 tetrahedra (int32 indices)") != std::string::npos);
  box.cells_x = box.cells_y = 2147483647;
  CHECK(sim::tetrahedron_count(box) == UINT64_MAX);
  sim::EllipsoidSpec ellipsoid;
  ellipsoid.resolution = 10;  // 48,000 tetrahedra, about 12 MiB
  CHECK_FALSE(sim::generated_mesh_too_large(sim::tetrahedron_count(ellipsoid)));
  ellipsoid.resolution = 178;  // 356^3 cells of 6: past 2^28 whatever the memory
  CHECK(sim::generated_mesh_too_large(sim::tetrahedron_count(ellipsoid)));
  const auto errors = scene_errors("mesh: {ellipsoid: {radii: [1, 1, 1], resolution: 200}}\nmaterial: {youngs_modulus: 5}\n");
  REQUIRE(errors.size() == 1);
  CHECK(errors.front().rfind("1:50: mesh.ellipsoid.resolution: 200 makes 384000000 tetrahedra", 0) == 0);
}

TEST_CASE("memory checks use the limit the process has, not only the machine's", "[hostile]") {
  const sim::MemoryLimit machine = sim::memory_limit();
  REQUIRE(machine.bytes > 0);
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FMPC_UNDER_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(FMPC_UNDER_ASAN)
  WARN("not run under AddressSanitizer: its shadow memory needs more address space than any RLIMIT_AS");
#else
  // In a child: RLIMIT_AS of 3 GiB (below this machine's memory) becomes the limit, and an ellipsoid estimated at
  // 15 GiB is refused by it (issue 30: resolution 110 passed the physical-memory check and died of bad_alloc).
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    const rlimit limit{rlim_t{3} << 30, rlim_t{3} << 30};
    if (::setrlimit(RLIMIT_AS, &limit) != 0) ::_exit(3);
    const sim::MemoryLimit process = sim::memory_limit();
    if (process.bytes != (std::uint64_t{3} << 30) || process.source.find("RLIMIT_AS") == std::string::npos) ::_exit(4);
    sim::EllipsoidSpec ellipsoid;
    ellipsoid.resolution = 110;
    const auto refused = sim::generated_mesh_too_large(sim::tetrahedron_count(ellipsoid));
    ::_exit(refused && refused->find("RLIMIT_AS (ulimit -v), 3 GiB") != std::string::npos ? 0 : 5);
  }
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
#endif
}

TEST_CASE("mesh counts claim no more than the bytes left", "[hostile]") {
  DiagnosticList gmsh;
  CHECK_FALSE(sim::read_gmsh("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1073741824\n1 0 0 0\n$EndNodes\n",
                             "m.msh", gmsh));
  CHECK(gmsh.items().front().range.line == 7);
  DiagnosticList vtk;
  CHECK_FALSE(sim::read_vtk("# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 2147483648 float\n0 0 0\n",
                            "m.vtk", vtk));
  CHECK(vtk.items().front().message.find("truncated") != std::string::npos);
  DiagnosticList cells;
  CHECK_FALSE(sim::read_vtk("# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n0 0 0\n"
                            "CELLS 1 2147483647\n4 0 0 0 0\n",
                            "m.vtk", cells));
  CHECK(cells.items().front().message.find("truncated") != std::string::npos);
}

TEST_CASE("UTF-8 is checked to Unicode's table before ANTLR sees the text", "[hostile]") {
  // (text, offset of the first bad byte or npos)
  const std::vector<std::pair<std::string, std::size_t>> cases = {
      {"plain ascii", std::string::npos},
      {"caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80 \xF4\x8F\xBF\xBF", std::string::npos},  // U+10FFFF is the last
      {"x\xF4\x90\x8A\x8B", 1},  // above U+10FFFF: the fuzz finding
      {"x\xED\xA0\x80", 1},       // a surrogate
      {"\xED\x9F\xBF", std::string::npos},  // U+D7FF, just below them
      {"\xE0\x80\xAF", 0},        // overlong '/'
      {"\xE0\xA0\x80", std::string::npos},
      {"\xF0\x8F\xBF\xBF", 0},   // overlong
      {"\xC0\xAF", 0},
      {"\xC1\xBF", 0},
      {"ab\xC3", 2},                // truncated
      {"\xE2\x82", 0},
      {"\xF5\x80\x80\x80", 0},
      {"\x80", 0},
      {"a\xE2\x28\xA1", 1},       // second byte not a continuation
      {"a\xF0\x9F\x98\x28", 1},  // fourth byte not a continuation
  };
  for (const auto& [text, bad] : cases) {
    INFO(text);
    CHECK(first_invalid_utf8(text) == bad);
    if (bad == std::string::npos) continue;
    // Both readers refuse it with a located error instead of letting ANTLR throw.
    for (const std::string& prefix : {std::string("[System]\nName='"), std::string("system ")}) {
      DiagnosticList diagnostics;
      CHECK_NOTHROW(load_rule_file("bad.fis", prefix + text + "\n", diagnostics));
      REQUIRE(diagnostics.has_errors());
      CHECK(diagnostics.items().front().message.find("UTF-8") != std::string::npos);
    }
  }
}
