// Cohorts (fmpc simulate --patients, docs/cohorts.md): shards, labels, one time step for every patient, and each
// patient of a CPU cohort run side by side bitwise equal to its run alone. The patients file's checks run through
// the binary (tests/unit/cli_behaviour_test.cpp style) at the end.
#include <catch2/catch.hpp>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "runtime/scene/cohort.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"
#include "tests/support/fmpc_process.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::filesystem::path temporary_directory(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("fmpc_cohort_test_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

const std::string kDemo = std::string(FMPC_SOURCE_DIR) + "/rulesets/scenes/liver_indentation.yaml";
const std::vector<std::string> kInputs = {"HCV", "HBV", "ALD", "CLD", "NAFLD"};

Scene demo_scene(std::size_t steps) {
  DiagnosticList diagnostics;
  auto scene = parse_scene(kDemo, read_text(kDemo), diagnostics);
  REQUIRE(scene);
  scene->steps = steps;
  scene->outputs.frames = 2;
  scene->outputs.samples = 20;
  return *scene;
}

}  // namespace

TEST_CASE("shards: every patient in exactly one shard, every N-th from the I-th", "[cohort]") {
  CHECK(shard_patients(7, {0, 3}) == std::vector<std::size_t>{0, 3, 6});
  CHECK(shard_patients(7, {2, 3}) == std::vector<std::size_t>{2, 5});
  CHECK(shard_patients(3, {0, 1}) == std::vector<std::size_t>{0, 1, 2});
  CHECK(shard_patients(3, {5, 8}).empty());  // more shards than patients: some hold none
  CHECK(shard_patients(0, {0, 1}).empty());
  for (std::size_t patients = 0; patients <= 40; ++patients) {
    for (std::size_t count = 1; count <= 12; ++count) {
      std::vector<int> seen(patients, 0);
      for (std::size_t index = 0; index < count; ++index) {
        const auto members = shard_patients(patients, {index, count});
        CHECK(std::is_sorted(members.begin(), members.end()));
        // Shards differ in size by at most one patient.
        CHECK(members.size() * count + count >= patients);
        CHECK(members.size() * count <= patients + count);
        for (const std::size_t p : members) {
          REQUIRE(p < patients);
          CHECK(p % count == index);
          ++seen[p];
        }
      }
      for (const int times : seen) CHECK(times == 1);
    }
  }
}

TEST_CASE("shards parse as I/N with 0 <= I < N; everything else is refused", "[cohort]") {
  std::string error;
  const auto shard = parse_cohort_shard("2/5", error);
  REQUIRE(shard);
  CHECK(shard->index == 2);
  CHECK(shard->count == 5);
  CHECK(parse_cohort_shard("0/1", error));
  for (const char* bad : {"", "3", "/3", "3/", "1/0", "0/0", "3/3", "4/3", "-1/3", "1/-3", "1.5/3", " 1/3", "1/3 ",
                          "1/3/4", "a/b", "0x1/3", "1234567890/1234567891"}) {
    error.clear();
    INFO(bad);
    CHECK_FALSE(parse_cohort_shard(bad, error));
    CHECK_FALSE(error.empty());
  }
  parse_cohort_shard("3/3", error);
  CHECK(error.find("below N") != std::string::npos);
  parse_cohort_shard("1/0", error);
  CHECK(error.find("at least 1") != std::string::npos);
}

TEST_CASE("labels must name a folder on every file system", "[cohort]") {
  for (const char* good : {"P1", "patient_07", "a.b-c", "F4", "x"}) CHECK_FALSE(unsafe_patient_label(good));
  const std::string long_label(kMaxPatientLabelBytes + 1, 'a');
  for (const std::string& bad : {std::string(), std::string(".."), std::string("."), std::string(".hidden"),
                                 std::string("-rf"), std::string("a/b"), std::string("a\\b"), std::string("a b"),
                                 std::string("caf\xc3\xa9"), std::string("a\nb"), std::string("a:b"), long_label,
                                 std::string("cohort.csv"), std::string("COHORT.CSV"),
                                 std::string("cohort_force_displacement.png"), std::string(1, '\0')}) {
    INFO(bad);
    CHECK(unsafe_patient_label(bad));
  }
  CHECK_FALSE(unsafe_patient_label(std::string(kMaxPatientLabelBytes, 'a')));
  CHECK(folded_label("Patient-A") == folded_label("PATIENT-a"));
}

TEST_CASE("a patient's scene replaces the constant bindings it names and nothing else", "[cohort]") {
  const Scene scene = demo_scene(10);
  const Scene patient = patient_scene(scene, "P9", {"HCV", "NAFLD"}, {1.5, 2.5});
  CHECK(patient.material.patient == "P9");
  REQUIRE(patient.material.bindings.size() == scene.material.bindings.size());
  for (std::size_t b = 0; b < patient.material.bindings.size(); ++b) {
    const InputBinding& binding = patient.material.bindings[b];
    const double expected = binding.input == "HCV"     ? 1.5
                            : binding.input == "NAFLD" ? 2.5
                                                       : scene.material.bindings[b].value;
    CHECK(binding.value == expected);
  }
  // A patient writes its numbers (summary.json, time_series.csv) by default; frames and the picture when asked.
  CHECK(patient.outputs.frames == 0);
  CHECK_FALSE(patient.outputs.plot);
  CHECK(patient.outputs.samples == scene.outputs.samples);
  CHECK(patient.outputs.csv);
  CHECK(patient.outputs.summary);
  Scene asking = scene;
  asking.outputs.cohort_frames = true;
  asking.outputs.cohort_plot = true;
  const Scene full = patient_scene(asking, "P9", {"HCV"}, {1.5});
  CHECK(full.outputs.frames == scene.outputs.frames);
  CHECK(full.outputs.plot);
  // outputs.cohort.plot draws nothing where the scene draws nothing.
  asking.outputs.plot = false;
  CHECK_FALSE(patient_scene(asking, "P9", {"HCV"}, {1.5}).outputs.plot);
}

TEST_CASE("a CPU cohort gives every patient its single run's bits, at the smallest automatic step", "[cohort]") {
  // Five patients of the demo with different fibrosis inputs (hence different E and automatic steps), 100 steps.
  const std::vector<std::vector<double>> values = {
      {9.7, 9.5, 12, 11, 11.2}, {5, 5, 5, 5, 5}, {20, 18, 25, 22, 19}, {7.2, 6.1, 8.8, 9.4, 5.5}, {14, 3, 17, 6, 21}};
  Scene scene = demo_scene(100);
  scene.outputs.cohort_frames = true;  // the frames are compared too
  std::vector<Scene> scenes;
  std::vector<BuiltScene> built;
  std::vector<std::string> labels;
  for (std::size_t p = 0; p < values.size(); ++p) {
    labels.push_back("P" + std::to_string(p));
    scenes.push_back(patient_scene(scene, labels.back(), kInputs, values[p]));
    DiagnosticList diagnostics;
    auto one = build_scene(scenes.back(), diagnostics);
    REQUIRE(one);
    built.push_back(std::move(*one));
  }
  // The automatic steps differ; the cohort takes the smallest, also when a patient of another shard has it.
  std::vector<double> automatic;
  for (const BuiltScene& b : built) {
    DiagnosticList diagnostics;
    const auto report = check_stability(b.setup, diagnostics);
    REQUIRE(report);
    automatic.push_back(report->time_step);
  }
  const double smallest = *std::min_element(automatic.begin(), automatic.end());
  CHECK(*std::max_element(automatic.begin(), automatic.end()) > smallest);
  {
    std::vector<BuiltScene> copies = {built[0], built[1]};
    std::vector<BuiltScene*> pointers = {&copies[0], &copies[1]};
    DiagnosticList diagnostics;
    const auto dt = prepare_cohort(pointers, {"a", "b"}, smallest / 2, diagnostics);
    REQUIRE(dt);
    CHECK(*dt == smallest / 2);
    CHECK(*copies[1].setup.time_step == smallest / 2);
  }
  std::vector<BuiltScene*> pointers;
  for (BuiltScene& b : built) pointers.push_back(&b);
  DiagnosticList diagnostics;
  const auto dt = prepare_cohort(pointers, labels, std::nullopt, diagnostics);
  REQUIRE(dt);
  CHECK(*dt == smallest);
  for (const BuiltScene& b : built) {
    CHECK(*b.setup.time_step == smallest);
    CHECK(b.setup.threads == 1);
  }

  const auto dir = temporary_directory("cpu");
  std::vector<CohortPatient> patients;
  for (std::size_t p = 0; p < built.size(); ++p)
    patients.push_back(CohortPatient{labels[p], &scenes[p], &built[p], (dir / "cohort" / labels[p]).string()});
  // One batch on 1, 2 and 3 workers, then spread over "devices" (on the CPU: batches side by side, the code path
  // that runs one batch per GPU): 2 slots (patients 0-2 and 3-4) and 3 slots named in any order (0-1, 2-3, 4).
  struct Spread {
    unsigned threads;
    std::vector<int> devices;
  };
  for (const Spread& spread : {Spread{1u, {}}, Spread{2u, {}}, Spread{3u, {}}, Spread{2u, {0, 1}}, Spread{1u, {4, 0, 2}}}) {
    const unsigned threads = spread.threads;
    CohortRunOptions options;
    options.threads = threads;
    options.devices = spread.devices;
    // Progress in steps (the batch's events), on the CPU as on CUDA: increasing, ending at the planned count.
    std::size_t calls = 0, last_done = 0, last_total = 0;
    options.progress = [&](std::size_t done, std::size_t total) {
      ++calls;
      CHECK(done <= total);
      CHECK(done > last_done);
      last_done = done;
      last_total = total;
    };
    const auto run = run_cohort(patients, options, diagnostics);
    REQUIRE(run);
    CHECK_FALSE(diagnostics.has_errors());
    CHECK(calls > 1);
    CHECK(last_done == last_total);
    CHECK(last_total == 100);
    REQUIRE(run->patients.size() == patients.size());
    CHECK(run->spring_steps == Approx(100.0 * static_cast<double>(built[0].setup.springs.size()) * 5));
    for (std::size_t p = 0; p < patients.size(); ++p) {
      INFO("patient " << p << ", " << threads << " threads, " << spread.devices.size() << " devices");
      REQUIRE(run->patients[p]);
      const SceneRunResult& cohort = *run->patients[p];
      SceneRunOptions alone_options;
      alone_options.output_directory = (dir / "alone" / labels[p]).string();
      const auto alone = run_scene(scenes[p], built[p], alone_options, diagnostics);
      REQUIRE(alone);
      CHECK(cohort.completed);
      CHECK(cohort.steps_taken == 100);
      REQUIRE(cohort.probe_curve.size() == alone->probe_curve.size());
      for (std::size_t i = 0; i < cohort.probe_curve.size(); ++i) {
        CHECK(cohort.probe_curve[i].force == alone->probe_curve[i].force);
        CHECK(cohort.probe_curve[i].displacement == alone->probe_curve[i].displacement);
      }
      CHECK(cohort.max_displacement == alone->max_displacement);
      CHECK(cohort.final_max_displacement == alone->final_max_displacement);
      // Every digit of the time series and the frames.
      for (const char* file : {"time_series.csv", "frame_00000.vtu", "frame_00001.vtu", "liver_indentation.pvd"})
        CHECK(read_text(dir / "cohort" / labels[p] / file) == read_text(dir / "alone" / labels[p] / file));
    }
    // The patients' answers differ (different E): the cohort did not run one patient five times.
    CHECK(run->patients[1]->probe_curve.back().force != run->patients[2]->probe_curve.back().force);
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("a cohort over devices: the device list and the patients' split", "[cohort]") {
  std::string error;
  CHECK(*parse_device_list("all", 2, error) == std::vector<int>{0, 1});
  CHECK(*parse_device_list("1,0", 2, error) == std::vector<int>{1, 0});
  CHECK(*parse_device_list("3", 8, error) == std::vector<int>{3});
  const auto refused = [&](const std::string& text, int count, const std::string& reason) {
    INFO(text << " with " << count << " devices");
    error.clear();
    CHECK_FALSE(parse_device_list(text, count, error));
    CHECK(error == reason);
  };
  refused("all", 0, "'all': no CUDA device is present");
  refused("0", 0, "'0': device 0 is not present; no CUDA device is present");
  refused("0,2", 2, "'0,2': device 2 is not present; the devices present are 0 to 1");
  refused("1", 1, "'1': device 1 is not present; the one device present is 0");
  refused("0,1,0", 2, "'0,1,0': device 0 is named twice (each device runs one batch)");
  // {text, the entry refused}
  for (const auto& [bad, entry] : std::vector<std::pair<std::string, std::string>>{
           {"", ""}, {",", ""}, {"0,", ""}, {",1", ""}, {"-1", "-1"}, {"x", "x"}, {"0;1", "0;1"}, {"1.0", "1.0"},
           {" 0", " 0"}, {"99999", "99999"}, {"ALL", "ALL"}})
    refused(bad, 4, "'" + bad + "': '" + entry + "' is not a device number (give 'all' or numbers separated by commas, "
                    "e.g. 0,1)");

  CHECK(split_patients(0, 2).empty());
  CHECK(split_patients(5, 0).empty());
  const auto sizes = [](std::size_t patients, std::size_t parts) {
    std::vector<std::size_t> out;
    for (const PatientRange& range : split_patients(patients, parts)) out.push_back(range.end - range.begin);
    return out;
  };
  CHECK(sizes(1000, 2) == std::vector<std::size_t>{500, 500});
  CHECK(sizes(7, 3) == std::vector<std::size_t>{3, 2, 2});
  CHECK(sizes(2, 4) == std::vector<std::size_t>{1, 1});  // never an empty batch
  // Every patient exactly once, in order, the sizes within one of each other.
  for (std::size_t patients = 1; patients <= 40; ++patients)
    for (std::size_t parts = 1; parts <= 9; ++parts) {
      const auto ranges = split_patients(patients, parts);
      REQUIRE(ranges.size() == std::min(patients, parts));
      std::size_t next = 0, smallest = patients, largest = 0;
      for (const PatientRange& range : ranges) {
        CHECK(range.begin == next);
        CHECK(range.end > range.begin);
        next = range.end;
        smallest = std::min(smallest, range.end - range.begin);
        largest = std::max(largest, range.end - range.begin);
      }
      CHECK(next == patients);
      CHECK(largest - smallest <= 1);
    }
}

TEST_CASE("fmpc simulate --patients checks the whole patients file before running anything", "[cohort][cli]") {
  const auto dir = temporary_directory("cli");
  const auto run_with = [&](const std::string& csv, const std::string& extra = "") {
    {
      std::ofstream out(dir / "patients.csv", std::ios::binary);
      out << csv;
    }
    return fmpc::testing::run_fmpc("simulate " + kDemo + " --backend cpu --steps 20 -o " + (dir / "out").string() +
                                   " --patients " + (dir / "patients.csv").string() + extra);
  };
  const std::string header = "label,HCV,HBV,ALD,CLD,NAFLD\n";
  struct Case {
    std::string csv;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"", "no header row: the CSV is empty"},
      {header, "has a header but no patients"},
      {"\n\n", "no header row: the CSV is empty"},
      {header + "P1,1,2,3,4,5\nP1,1,2,3,4,5\n", "label 'P1' is given twice"},
      {header + "p1,1,2,3,4,5\nP1,1,2,3,4,5\n", "label 'P1' is given twice"},
      {header + "P1,nan,2,3,4,5\n", "input 'HCV' is NaN"},
      {header + "P1,1,inf,3,4,5\n", "input 'HBV' is inf"},
      {header + "P1,1,2,-inf,4,5\n", "input 'ALD' is -inf"},
      {header + "P1,1,2,x,4,5\n", "'x' is not a number (input 'ALD')"},
      {header + "P1,1,2,3,4\n", "this row has 5 fields, the header 6"},
      {header + "../escape,1,2,3,4,5\n", "label '../escape'"},
      {header + ",1,2,3,4,5\n", "the label is empty"},
      {header + "cohort.csv,1,2,3,4,5\n", "is the name of a file the cohort writes"},
      {"HCV,HBV,ALD,CLD,NAFLD\n1,2,3,4,5\n", "the header has no 'label' column"},
      {"label,HCV,HBV,ALD,CLD\nP1,1,2,3,4\n", "the header has no column for input 'NAFLD'"},
      {"label,HCV,HBV,ALD,CLD,NAFLD,HCVV\nP1,1,2,3,4,5,6\n", "'HCVV' is not an input of system"},
      {"label,HCV,HBV,ALD,CLD,NAFLD,HCV\nP1,1,2,3,4,5,6\n", "column 'HCV' appears twice"},
      {"label,label,HCV,HBV,ALD,CLD,NAFLD\nP1,P2,1,2,3,4,5\n", "column 'label' appears twice"},
  };
  for (const Case& c : cases) {
    INFO(c.csv);
    const auto run = run_with(c.csv);
    CHECK(run.status == 2);
    CHECK(run.out.find(c.message) != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir / "out"));  // nothing written
  }
  // Every bad row is reported, with its line and column, not just the first.
  const auto many = run_with(header + "P1,nan,2,3,4,5\nP2,1,2,3,4,5\nP1,1,2,3,4,x\n");
  CHECK(many.out.find("patients.csv:2:4: error: input 'HCV' is NaN") != std::string::npos);
  CHECK(many.out.find("patients.csv:4:1: error: label 'P1' is given twice") != std::string::npos);
  CHECK(many.out.find("patients.csv:4:12: error: 'x' is not a number") != std::string::npos);
  // Out of range is a warning, evaluated as given (as fmpc eval); bad shards are refused before the file is read.
  const auto shard = run_with(header + "P1,1,2,3,4,5\n", " --shard 2/2");
  CHECK(shard.status == 2);
  CHECK(shard.out.find("--shard: '2/2': I counts from 0") != std::string::npos);
  const auto empty_shard = run_with(header + "P1,1,2,3,4,5\n", " --shard 1/2");
  CHECK(empty_shard.status == 0);
  CHECK(empty_shard.out.find("holds none") != std::string::npos);
  const auto no_patients = fmpc::testing::run_fmpc("simulate " + kDemo + " --shard 0/2");
  CHECK(no_patients.status == 2);
  CHECK(no_patients.out.find("--shard: a shard is a share of a cohort") != std::string::npos);
  // --devices: a cohort's, on CUDA only. Here (backend cpu) refused whatever this build and machine have: no CUDA in
  // the build, no device 0 present, or a cohort that runs on the CPU; nothing written.
  for (const char* devices : {" --devices 0", " --devices 0,0"}) {
    const auto refused = run_with(header + "P1,1,2,3,4,5\n", devices);
    CHECK(refused.status == 2);
    CHECK(refused.out.find("argument --devices: error: --devices") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir / "out"));
  }
  const auto alone_devices = fmpc::testing::run_fmpc("simulate " + kDemo + " --devices all");
  CHECK(alone_devices.status == 2);
  CHECK(alone_devices.out.find("--devices: a scene alone runs on one device") != std::string::npos);

  // A good cohort with a value out of range: two folders of numbers, cohort.csv and the overlay; no frames and no
  // patient's picture unless outputs.cohort asks.
  const auto good = run_with(header + "A,9.7,9.5,12,11,11.2\nB,200,5,5,5,5\n");
  CHECK(good.status == 0);
  CHECK(good.out.find("warning: input 'HCV' = 200 is outside its range") != std::string::npos);
  for (const char* file : {"A/time_series.csv", "A/summary.json", "B/time_series.csv", "B/summary.json",
                           "cohort.csv", "cohort_force_displacement.png"})
    CHECK(std::filesystem::exists(dir / "out" / file));
  for (const char* file : {"A/force_displacement.png", "A/frame_00000.vtu", "A/liver_indentation.pvd"})
    CHECK_FALSE(std::filesystem::exists(dir / "out" / file));
  CHECK(good.out.find("wrote 4 files in 2 patient folders") != std::string::npos);
  // The rates, each labelled with what it is over.
  CHECK(good.out.find("  stepping (the simulator's advance calls, checks included): ") != std::string::npos);
  CHECK(good.out.find(" batch steps/s, ") != std::string::npos);
  CHECK(good.out.find(" patient-steps/s, ") != std::string::npos);
  CHECK(good.out.find("  whole command: ") != std::string::npos);
  CHECK(good.out.find(" spring-steps/s\n") != std::string::npos);
  {
    // outputs.cohort asks for both: every patient's frames and picture, and a second run into the same folder.
    std::string text = read_text(kDemo);
    const auto replace = [&](const std::string& from, const std::string& to) {
      const auto at = text.find(from);
      REQUIRE(at != std::string::npos);
      text.replace(at, from.size(), to);
    };
    replace("../liver_fibrosis/mamdani.fis", std::string(FMPC_SOURCE_DIR) + "/rulesets/liver_fibrosis/mamdani.fis");
    replace("outputs: {frames: 25, samples: 240}", "outputs: {frames: 3, samples: 20, cohort: {frames: true, plot: true}}");
    {
      std::ofstream out(dir / "asking.yaml", std::ios::binary);
      out << text;
    }
    const auto asking = fmpc::testing::run_fmpc("simulate " + (dir / "asking.yaml").string() +
                                                " --backend cpu --steps 20 -o " + (dir / "out").string() +
                                                " --patients " + (dir / "patients.csv").string());
    CHECK(asking.status == 0);
    for (const char* file : {"A/force_displacement.png", "A/frame_00000.vtu", "A/frame_00002.vtu", "A/liver_indentation.pvd",
                             "B/force_displacement.png", "B/frame_00002.vtu"})
      CHECK(std::filesystem::exists(dir / "out" / file));
    CHECK(asking.out.find("wrote 14 files in 2 patient folders") != std::string::npos);
  }
  const std::string table = read_text(dir / "out" / "cohort.csv");
  CHECK(table.rfind("label,HCV,HBV,ALD,CLD,NAFLD,E_kPa,E_max_kPa,completed,final_probe_displacement_m,"
                    "final_probe_force_N,max_displacement_m,inverted_elements,steps,dt_s,steps_per_second\nA,9.7,9.5,"
                    "12,11,11.2,",
                    0) == 0);
  CHECK(table.find("\nB,200,5,5,5,5,") != std::string::npos);
  std::filesystem::remove_all(dir);
}
