// fmpc::runtime::Session (runtime/session/session.h): a scene from YAML text and from a setup, stepped by steps and to
// a time, a tool posed every tick and read back, the state read, and the material swapped for other rules between
// two steps, implicit Euler's contact rounds taken from the scene; bad input (other inputs, a rule file with errors,
// an unstable step, a session from a setup) is an error and changes nothing.
#include "runtime/session/session.h"

#include <catch2/catch.hpp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "runtime/fem/fem_model_builder.h"
#include "runtime/io/json_text.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"
#include "tests/support/error_messages.h"

using namespace fmpc;
using fmpc::runtime::Session;

namespace {

std::filesystem::path scratch_folder() {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "fmpc_session_test";
  std::filesystem::create_directories(folder);
  return folder;
}

// A one-input MATLAB rule file: Young's modulus (kPa, the FIS default unit) from a fibrosis score F in [0, 4],
// between `soft` and `hard` kPa.
std::string rules_text(const std::string& input, double soft, double hard) {
  char text[1024];
  std::snprintf(text, sizeof text,
                "[System]\nName='stiffness'\nType='mamdani'\nVersion=2.0\nNumInputs=1\nNumOutputs=1\nNumRules=2\n"
                "AndMethod='min'\nOrMethod='max'\nImpMethod='min'\nAggMethod='max'\nDefuzzMethod='centroid'\n\n"
                "[Input1]\nName='%s'\nRange=[0 4]\nNumMFs=2\nMF1='low':'trimf',[-4 0 4]\nMF2='high':'trimf',[0 4 8]\n\n"
                "[Output1]\nName='E'\nRange=[%g %g]\nNumMFs=2\nMF1='soft':'trimf',[%g %g %g]\n"
                "MF2='hard':'trimf',[%g %g %g]\n\n[Rules]\n1, 1 (1) : 1\n2, 2 (1) : 1\n",
                input.c_str(), soft, hard, 2 * soft - hard, soft, hard, soft, hard, 2 * hard - soft);
  return text;
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::filesystem::path path = scratch_folder() / name;
  std::ofstream(path) << text;
  return path.string();
}

// A 2 x 2 x 1 cm FEM block whose modulus comes from `rules` at F = 2, fixed at its base, with a sphere above it.
std::string scene_text(const std::string& rules, const std::string& extra = "") {
  return "name: session_block\nmodel: corotational_fem\n"
         "mesh:\n  box: {size: [0.02, 0.02, 0.01], cells: [6, 6, 3]}\n  units: m\n"
         "material:\n  rules: " +
         rules +
         "\n  inputs: {F: 2}\n  poisson_ratio: 0.4\n"
         "mass: {density: 1000}\ndamping: {ratio: 0.5}\n"
         "fixed:\n  plane: {point: [0, 0, 0], normal: [0, 0, 1]}\n"
         "tools:\n  - name: tip\n    shape: sphere\n    radius: 0.003\n    pose: {position: [0.01, 0.01, 0.0131]}\n"
         "integrator: semi_implicit_euler\nprecision: double\n" +
         extra;
}

using fmpc::testing::errors_of;

}  // namespace

TEST_CASE("session: a scene from YAML, stepped, a tool posed and read, the state read", "[session]") {
  const std::string rules = write_file("soft.fis", rules_text("F", 5, 15));
  DiagnosticList diagnostics;
  const auto session = Session::from_yaml(scene_text(rules), (scratch_folder() / "block.yaml").string(), diagnostics);
  REQUIRE(session);
  INFO(session->render(diagnostics));
  CHECK(session->backend() == sim::Backend::Cpu);
  CHECK(session->tool_count() == 1);
  CHECK(session->find_tool("tip") == std::optional<std::size_t>(0));
  CHECK_FALSE(session->find_tool("shaft"));
  CHECK(session->vertex_count() == 7 * 7 * 4);
  REQUIRE(session->step(3, diagnostics));
  CHECK(session->steps_taken() == 3);
  // step_to takes the steps that reach the time (none when it is there already).
  const double dt = session->time_step();
  REQUIRE(session->step_to(10.5 * dt, diagnostics));
  CHECK(session->steps_taken() == 11);
  REQUIRE(session->step_to(2.0 * dt, diagnostics));
  CHECK(session->steps_taken() == 11);
  CHECK_FALSE(session->step_to(std::nan(""), diagnostics));
  CHECK(errors_of(diagnostics) == "the time nan s is not finite");
  diagnostics = DiagnosticList{};
  // A haptic loop: the tip pressed 1 mm in over 100 ticks of 1 ms, then held.
  for (int tick = 1; tick <= 150; ++tick) {
    runtime::ToolPose pose;
    pose.position = {0.01, 0.01, 0.0131 - 0.001 * std::min(1.0, tick / 100.0)};
    REQUIRE(session->set_tool_pose(0, pose, diagnostics));
    REQUIRE(session->step_to(tick * 1e-3, diagnostics));
  }
  const std::vector<runtime::ToolReading> readings = session->tool_readings(diagnostics);
  REQUIRE(readings.size() == 1);
  CHECK(readings[0].force[2] > 0.0);  // the tissue pushes the tip up
  CHECK(readings[0].contacts > 0);
  CHECK(session->positions(diagnostics).size() == session->vertex_count());
  CHECK(session->velocities(diagnostics).size() == session->vertex_count());
  const auto energies = session->energies(diagnostics);
  REQUIRE(energies);
  CHECK(energies->elastic > 0.0);
  CHECK(session->inversions().largest_count == 0);
  CHECK_FALSE(session->device_positions(diagnostics));
  CHECK(errors_of(diagnostics) ==
        "the positions live on the host with the CPU backend; read positions() instead of a device pointer");
}

TEST_CASE("session: the material swapped between two steps, keeping the state", "[session]") {
  const std::string soft = write_file("soft.fis", rules_text("F", 5, 15));
  const std::string hard = write_file("hard.fis", rules_text("F", 10, 30));
  const std::string other_inputs = write_file("other.fis", rules_text("HBV", 10, 30));
  const std::string broken = write_file("broken.fis", "[System]\nName='x'\nNumInputs=one\n");
  DiagnosticList diagnostics;
  // An explicit step small enough for the harder material too (its critical step is 1 / sqrt(2) of the soft one's).
  auto session =
      Session::from_yaml(scene_text(soft, "dt: 5e-5\n"), (scratch_folder() / "block.yaml").string(), diagnostics);
  REQUIRE(session);
  REQUIRE(session->stability().critical_time_step > 2.0 * 5e-5);
  runtime::ToolPose pressed;
  pressed.position = {0.01, 0.01, 0.0121};
  REQUIRE(session->set_tool_pose(0, pressed, diagnostics));
  REQUIRE(session->step_to(0.03, diagnostics));
  const std::vector<double> before = session->simulation().setup().elements.terms.at(0).parameter[0];
  const std::vector<runtime::Point3> positions = session->positions(diagnostics);
  const std::size_t steps = session->steps_taken();

  SECTION("a rule file with other inputs, or with errors: an error, and nothing changes") {
    CHECK_FALSE(session->swap_material(other_inputs, diagnostics));
    CHECK(errors_of(diagnostics) == "'" + other_inputs +
                                        "' takes the inputs HBV, but the scene binds F; the material was not "
                                        "replaced (a new rule file must keep the inputs the scene's material.inputs "
                                        "bind)");
    diagnostics = DiagnosticList{};
    CHECK_FALSE(session->swap_material(broken, diagnostics));
    CHECK(errors_of(diagnostics).find("' cannot be read as rules (above); fix it with fmpc check") !=
          std::string::npos);
    CHECK_FALSE(session->swap_material((scratch_folder() / "missing.fis").string(), diagnostics));
    CHECK(session->simulation().setup().elements.terms.at(0).parameter[0] == before);
    CHECK(session->steps_taken() == steps);
    const std::vector<runtime::Point3> now = session->positions(diagnostics);
    CHECK(std::memcmp(now.data(), positions.data(), now.size() * sizeof(runtime::Point3)) == 0);
    diagnostics = DiagnosticList{};
    CHECK(session->step(10, diagnostics));  // the run goes on
  }
  SECTION("harder rules: the elements stiffen, the state and time go on, the tip feels more") {
    const double force_before = session->tool_readings(diagnostics).at(0).force[2];
    REQUIRE(session->swap_material(hard, diagnostics));
    INFO(session->render(diagnostics));
    const std::vector<double> after = session->simulation().setup().elements.terms.at(0).parameter[0];
    REQUIRE(after.size() == before.size());
    CHECK(after[0] > 1.5 * before[0]);
    CHECK(session->steps_taken() == steps);
    const std::vector<runtime::Point3> now = session->positions(diagnostics);
    CHECK(std::memcmp(now.data(), positions.data(), now.size() * sizeof(runtime::Point3)) == 0);
    REQUIRE(session->step_to(0.06, diagnostics));
    CHECK(session->tool_readings(diagnostics).at(0).force[2] > 1.5 * force_before);
  }
  SECTION("a material too stiff for the time step in use: an error, and nothing changes") {
    diagnostics = DiagnosticList{};
    session = Session::from_yaml(
        scene_text(soft, "dt: " + std::to_string(0.9 * session->stability().critical_time_step) + "\n"),
        (scratch_folder() / "block.yaml").string(), diagnostics);
    REQUIRE(session);
    REQUIRE(session->step(5, diagnostics));
    CHECK_FALSE(session->swap_material(hard, diagnostics));
    const std::string text = errors_of(diagnostics);
    CHECK(text.rfind("the new material: dt: time step ", 0) == 0);
    CHECK(text.find("the material was not replaced; the simulation goes on with the old one") != std::string::npos);
    CHECK(session->simulation().setup().elements.terms.at(0).parameter[0] == before);
  }
}

TEST_CASE("session: a setup built in code, bad scenes and tools", "[session]") {
  DiagnosticList diagnostics;
  sim::BoxSpec box;
  box.size = {0.01, 0.01, 0.01};
  box.cells_x = box.cells_y = box.cells_z = 2;
  sim::FemModelSpec spec;
  spec.youngs_modulus = {5e3};
  spec.poisson_ratio = {0.3};
  spec.mass.value = 1000.0;
  auto setup = sim::build_fem_model(sim::generate_box(box, diagnostics), spec, diagnostics);
  REQUIRE(setup);
  setup->fixed_vertices = {0};
  const auto session = Session::from_setup(*setup, diagnostics);
  REQUIRE(session);
  CHECK(session->step(5, diagnostics));
  CHECK(session->tool_count() == 0);
  CHECK(session->tool_readings(diagnostics).empty());
  CHECK_FALSE(session->swap_material("rules.fis", diagnostics));
  CHECK(errors_of(diagnostics) ==
        "this session was made from a setup, which has no scene to build with 'rules.fis'; "
        "pass a setup built with the new material instead");
  // Another material built in code: taken; another mesh: refused.
  sim::FemModelSpec harder = spec;
  harder.youngs_modulus = {5.5e3};  // stable at the automatic step (0.8 of the critical one) of 5 kPa
  auto material = sim::build_fem_model(sim::generate_box(box, diagnostics), harder, diagnostics);
  REQUIRE(material);
  diagnostics = DiagnosticList{};
  CHECK(session->swap_material(*material, diagnostics));
  box.cells_z = 3;
  auto other_mesh = sim::build_fem_model(sim::generate_box(box, diagnostics), harder, diagnostics);
  REQUIRE(other_mesh);
  CHECK_FALSE(session->swap_material(*other_mesh, diagnostics));
  CHECK(errors_of(diagnostics) ==
        "the new material does not fit this simulation: it has 36 vertices where the "
        "simulation has 27; build it from the same mesh and model");

  diagnostics = DiagnosticList{};
  const std::string rules = write_file("soft.fis", rules_text("F", 5, 15));
  std::string text = scene_text(rules);
  text.replace(text.find("0.0131"), 6, "0.0121");  // 1 mm into the top face
  CHECK_FALSE(Session::from_yaml(text, "inside.yaml", diagnostics));
  CHECK(errors_of(diagnostics).rfind("tool 0 'tip' starts inside the tissue: vertex ", 0) == 0);
  diagnostics = DiagnosticList{};
  text = scene_text(rules);
  text.replace(text.find("shape: sphere"), 13, "shape: cylinder");
  CHECK_FALSE(Session::from_yaml(text, "bad.yaml", diagnostics));
  CHECK(errors_of(diagnostics).rfind("tools[0].shape: ", 0) == 0);
  CHECK_FALSE(Session::open((scratch_folder() / "no_such_scene.yaml").string(), diagnostics));
}

TEST_CASE("session: tools in a scene file: a path, the CSV's columns and the summary", "[session][tools]") {
  const std::string text =
      "name: tool_path\nmesh:\n  box: {size: [0.02, 0.02, 0.01], cells: [4, 4, 2]}\n  units: m\n"
      "material: {youngs_modulus: 10}\nmass: {density: 1000}\ndamping: {ratio: 0.9}\n"
      "fixed:\n  plane: {point: [0, 0, 0], normal: [0, 0, 1]}\n"
      "tools:\n"
      "  - name: tip\n    shape: sphere\n    radius: 0.003\n"
      "    path:\n      - {time: 0, position: [0.01, 0.01, 0.0131]}\n      - {time: 0.05, position: [0.01, 0.01, "
      "0.012]}\n"
      "  - name: shaft\n    shape: capsule\n    radius: 0.001\n    length: 0.01\n"
      "    pose: {position: [0.0, 0.005, 0.0115], orientation: [0.7071067811865476, 0, 0.7071067811865476, 0]}\n"
      "contact: {stiffness_ratio: 2}\nduration: 0.06\nprecision: double\n"
      "outputs: {frames: 0, samples: 4, precision_check: off}\n";
  DiagnosticList diagnostics;
  const std::string path = (scratch_folder() / "tool_path.yaml").string();
  const auto scene = sim::parse_scene(path, text, diagnostics);
  REQUIRE(scene);
  REQUIRE(scene->tools.size() == 2);
  CHECK(scene->tools[0].path.size() == 2);
  CHECK(scene->contact_stiffness_ratio == 2.0);
  const auto built = sim::build_scene(*scene, diagnostics);
  REQUIRE(built);
  CHECK(built->setup.tools[1].length == 0.01);
  sim::SceneRunOptions options;
  options.output_directory = (scratch_folder() / "tool_path.out").string();
  const auto result = sim::run_scene(*scene, *built, options, diagnostics);
  REQUIRE(result);
  INFO(errors_of(diagnostics));
  CHECK(result->completed);
  std::ifstream csv(result->csv_path);
  std::string header;
  std::getline(csv, header);
  CHECK(header ==
        "time_s,kinetic_energy_J,elastic_energy_J,max_displacement_m,tip_fx_N,tip_fy_N,tip_fz_N,tip_tx_Nm,tip_ty_Nm,"
        "tip_tz_Nm,tip_contacts,shaft_fx_N,shaft_fy_N,shaft_fz_N,shaft_tx_Nm,shaft_ty_Nm,shaft_tz_Nm,shaft_contacts");
  CHECK(result->summary_json.find("\"tools\": [") != std::string::npos);
  CHECK(result->summary_json.find("\"name\": \"shaft\"") != std::string::npos);

  // Errors name the field.
  const auto fails = [&](const std::string& from, const std::string& to) {
    std::string changed = text;
    changed.replace(changed.find(from), from.size(), to);
    DiagnosticList errors;
    CHECK_FALSE(sim::parse_scene(path, changed, errors));
    return errors_of(errors);
  };
  CHECK(fails("- {time: 0.05,", "- {time: 0,") ==
        "tools[0].path[1].time: the path's times must increase; the point before is at 0 s");
  CHECK(fails("radius: 0.001\n    length: 0.01", "radius: 0.001") ==
        "tools[1]: a capsule needs 'length' (mesh units): its axis runs from its pose's position along the tool's z "
        "axis");
  CHECK(fails("orientation: [0.7071067811865476, 0, 0.7071067811865476, 0]", "orientation: [0, 0, 0, 0]") ==
        "tools[1].pose.orientation: expected a rotation as a quaternion [w, x, y, z] of four finite numbers, not all "
        "zero (e.g. [1, 0, 0, 0]), got a list of 4");
  CHECK(fails("name: shaft", "name: tip") == "tools[1].name: two tools are named 'tip'; give each its own name");
  CHECK(fails("name: shaft", "name: 'shaft,1'") ==
        "tools[1].name: 'shaft,1' cannot name a tool: use up to 64 letters, digits and '_', starting with a letter (it "
        "names the tool's columns in time_series.csv)");
  CHECK(fails("contact: {stiffness_ratio: 2}", "contact: {stiffness_ratio: 0}") ==
        "contact.stiffness_ratio: expected a positive number, got 0");
  // contact.damping_ratio: from 0 to 100, explicit integrators only; the setup and summary.json carry it.
  CHECK(fails("contact: {stiffness_ratio: 2}", "contact: {damping_ratio: -1}") ==
        "contact.damping_ratio: expected a non-negative number, got -1");
  CHECK(fails("contact: {stiffness_ratio: 2}", "contact: {damping_ratio: 101}") ==
        "contact.damping_ratio: 101 is above the limit of 100 (1 is critical damping of a vertex on its contact spring)");
  CHECK(fails("contact: {stiffness_ratio: 2}", "contact: {damping_ratio: 1}\nintegrator: implicit_euler") ==
        "contact.damping_ratio: contact damping is for the explicit integrators (a pressed vertex bouncing off the "
        "tool between substeps); implicit Euler's step damps that itself: leave it out");
  std::string damped_text = text;
  damped_text.replace(damped_text.find("contact: {stiffness_ratio: 2}"), 29, "contact: {damping_ratio: 0.7}");
  const auto damped = sim::parse_scene(path, damped_text, diagnostics);
  REQUIRE(damped);
  CHECK(damped->contact_damping_ratio == 0.7);
  const auto damped_built = sim::build_scene(*damped, diagnostics);
  REQUIRE(damped_built);
  CHECK(damped_built->setup.contact_damping_ratio == 0.7);
  CHECK(damped_built->setup.contact_stiffness_ratio == sim::kDefaultContactStiffnessRatio);
}

TEST_CASE("session: a tick's mean tool force is its impulse over its duration", "[session][tools][heavy]") {
  const std::string rules = write_file("mean.fis", rules_text("F", 5, 15));
  const auto open = [&](bool implicit) {
    std::string text = scene_text(rules);
    if (implicit) {
      const std::string explicit_line = "integrator: semi_implicit_euler\n";
      text.replace(text.find(explicit_line), explicit_line.size(), "integrator: implicit_euler\ndt: 0.001\n");
    }
    DiagnosticList diagnostics;
    auto session = Session::from_yaml(text, (scratch_folder() / "mean.yaml").string(), diagnostics);
    INFO(render_all(diagnostics, SourceFiles{}));
    REQUIRE(session);
    return session;
  };
  DiagnosticList diagnostics;
  // The tip pressed 1.5 mm in over 40 ticks of 1 ms, then held.
  const auto press = [&](Session& session, int tick) {
    runtime::ToolPose pose;
    pose.position = {0.01, 0.01, 0.0131 - 0.0015 * std::min(1.0, tick / 40.0)};
    REQUIRE(session.set_tool_pose(0, pose, diagnostics));
  };
  // Semi-implicit Euler: a step applies the force read at its start. The same ticks stepped one step at a time by
  // hand give every step's reading: the mean is their sum over the steps; the tick-end reading and the state are
  // step_to's, bit for bit.
  const auto averaged = open(false), by_hand = open(false), plain = open(false);
  double largest_gap = 0.0, largest_mean = 0.0;
  for (int tick = 1; tick <= 60; ++tick) {
    INFO("tick " << tick);
    const double t = tick * 1e-3;
    for (Session* session : {averaged.get(), by_hand.get(), plain.get()}) press(*session, tick);
    std::vector<runtime::ToolReading> mean, end;
    REQUIRE(averaged->step_to_averaging(t, mean, diagnostics, &end));
    REQUIRE(plain->step_to(t, diagnostics));
    sim::Point3 force{0, 0, 0}, torque{0, 0, 0};
    std::size_t steps = 0;
    while (by_hand->steps_taken() < averaged->steps_taken()) {
      const runtime::ToolReading start = by_hand->tool_readings(diagnostics).at(0);
      for (int i = 0; i < 3; ++i) {
        force[i] += start.force[i];
        torque[i] += start.torque[i];
      }
      REQUIRE(by_hand->step(1, diagnostics));
      ++steps;
    }
    REQUIRE(steps > 1);  // substeps
    REQUIRE(mean.size() == 1);
    for (int i = 0; i < 3; ++i) {
      CHECK(mean[0].force[i] == Approx(force[i] / static_cast<double>(steps)).margin(1e-15));
      CHECK(mean[0].torque[i] == Approx(torque[i] / static_cast<double>(steps)).margin(1e-17));
    }
    CHECK(end.at(0).force == plain->tool_readings(diagnostics).at(0).force);
    CHECK(end.at(0).force == averaged->tool_readings(diagnostics).at(0).force);
    CHECK(averaged->positions(diagnostics) == plain->positions(diagnostics));
    largest_gap = std::max(largest_gap, std::abs(end[0].force[2] - mean[0].force[2]));
    largest_mean = std::max(largest_mean, std::abs(mean[0].force[2]));
  }
  CHECK(averaged->tool_readings(diagnostics).at(0).contacts > 0);
  CHECK(largest_mean > 0.0);
  CHECK(largest_gap > 1e-3 * largest_mean);  // with substeps the tick-end reading is not the tick's mean
  // Implicit Euler, one step per tick: its step applies the force at its end, so the mean is the tick-end reading,
  // bit for bit (the haptic bench's implicit numbers do not change).
  const auto implicit = open(true), implicit_plain = open(true);
  for (int tick = 1; tick <= 30; ++tick) {
    INFO("implicit tick " << tick);
    press(*implicit, tick);
    press(*implicit_plain, tick);
    std::vector<runtime::ToolReading> mean, end;
    REQUIRE(implicit->step_to_averaging(tick * 1e-3, mean, diagnostics, &end));
    REQUIRE(implicit_plain->step_to(tick * 1e-3, diagnostics));
    CHECK(mean.at(0).force == end.at(0).force);
    CHECK(mean.at(0).torque == end.at(0).torque);
    CHECK(end.at(0).force == implicit_plain->tool_readings(diagnostics).at(0).force);
  }
  CHECK(implicit->tool_readings(diagnostics).at(0).force[2] > 0.0);
  // Nothing to step: the mean is the reading now; a time that is not finite is step_to's error.
  std::vector<runtime::ToolReading> now;
  REQUIRE(averaged->step_to_averaging(averaged->time(), now, diagnostics));
  CHECK(now.at(0).force == averaged->tool_readings(diagnostics).at(0).force);
  CHECK_FALSE(averaged->step_to_averaging(std::nan(""), now, diagnostics));
  CHECK(errors_of(diagnostics) == "the time nan s is not finite");
}

TEST_CASE("session: a swapped material's Prony weights and times take effect", "[session][prony]") {
  // A viscoelastic block sagging under gravity from rest: swapped to other weights and times before its first step,
  // it steps as a block built with them (to round-off: the history of the jump to the start state is the weights
  // times a stress of order 1e-16 Pa) and not as the old one.
  DiagnosticList diagnostics;
  sim::BoxSpec box;
  box.size = {0.01, 0.01, 0.01};
  box.cells_x = box.cells_y = box.cells_z = 2;
  const auto build = [&](std::vector<sim::PronyTerm> prony, sim::Integrator integrator) {
    sim::FemModelSpec spec;
    spec.youngs_modulus = {5e3};
    spec.poisson_ratio = {0.3};
    spec.mass.value = 1000.0;
    spec.prony = std::move(prony);
    auto setup = sim::build_fem_model(sim::generate_box(box, diagnostics), spec, diagnostics);
    REQUIRE(setup);
    for (std::size_t v = 0; v < setup->rest_positions.size(); ++v)
      if (setup->rest_positions[v][2] == 0.0) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
    setup->gravity = {0.0, 0.0, -9.81};
    setup->integrator = integrator;
    return *setup;
  };
  const std::vector<sim::PronyTerm> old_series{{0.2, 0.005}, {0.1, 0.05}}, new_series{{0.6, 0.002}, {0.3, 0.02}};
  for (const sim::Integrator integrator : {sim::Integrator::SemiImplicitEuler, sim::Integrator::ImplicitEuler}) {
    CAPTURE(static_cast<int>(integrator));
    const sim::SimulationSetup old_material = build(old_series, integrator);
    const auto old_session = Session::from_setup(old_material, diagnostics);
    const auto new_session = Session::from_setup(build(new_series, integrator), diagnostics);
    const auto swapped = Session::from_setup(old_material, diagnostics);
    REQUIRE((old_session && new_session && swapped));
    REQUIRE(swapped->swap_material(build(new_series, integrator), diagnostics));
    std::vector<std::vector<sim::Point3>> positions;
    for (Session* session : {old_session.get(), new_session.get(), swapped.get()}) {
      REQUIRE(session->step(200, diagnostics));
      positions.push_back(session->positions(diagnostics));
    }
    // The largest distance between two sessions' vertices, over the largest sag.
    double sag = 0.0, to_new = 0.0, old_to_new = 0.0;
    for (std::size_t v = 0; v < old_material.rest_positions.size(); ++v) {
      sag = std::max(sag, sim::distance(positions[1][v], old_material.rest_positions[v]));
      to_new = std::max(to_new, sim::distance(positions[2][v], positions[1][v]));
      old_to_new = std::max(old_to_new, sim::distance(positions[0][v], positions[1][v]));
    }
    CHECK(sag > 1e-4);
    CHECK(to_new < 1e-12 * sag);
    CHECK(old_to_new > 1e-2 * sag);
  }
  // Another number of terms changes the state each point keeps: refused, nothing changed.
  const auto session = Session::from_setup(build(old_series, sim::Integrator::SemiImplicitEuler), diagnostics);
  REQUIRE(session);
  diagnostics = DiagnosticList{};
  CHECK_FALSE(session->swap_material(build({{0.5, 0.01}}, sim::Integrator::SemiImplicitEuler), diagnostics));
  CHECK(errors_of(diagnostics) ==
        "the new material does not fit this simulation: its element term 0 has 1 Prony terms where the simulation "
        "has 2 (the series' length sets the state each point keeps); build it from the same mesh and model");
}

TEST_CASE("session: solver.contact_rounds comes from the scene; the summary counts the steps left unsettled",
          "[session][tools][implicit]") {
  // The session's setup carries the scene's bound: one solve per step, the steps whose contact then changed counted
  // and never warned about.
  const std::string rules = write_file("rounds.fis", rules_text("F", 5, 15));
  std::string text = scene_text(rules, "solver: {contact_rounds: 1}\n");
  const std::string explicit_line = "integrator: semi_implicit_euler\n";
  text.replace(text.find(explicit_line), explicit_line.size(), "integrator: implicit_euler\ndt: 0.005\n");
  DiagnosticList diagnostics;
  const auto session = Session::from_yaml(text, (scratch_folder() / "rounds.yaml").string(), diagnostics);
  REQUIRE(session);
  CHECK(session->simulation().setup().implicit.contact_rounds == 1);
  for (int tick = 1; tick <= 6; ++tick) {
    runtime::ToolPose pose;
    pose.position = {0.01 + 0.0008 * tick, 0.01, 0.0131 - 0.0015 * std::min(1.0, tick / 2.0)};
    REQUIRE(session->set_tool_pose(0, pose, diagnostics));
    REQUIRE(session->step(5, diagnostics));
  }
  const sim::ImplicitSolverReport report = session->simulation().implicit_solver();
  CHECK(report.contact_unsettled_steps > 0);
  for (const Diagnostic& d : diagnostics.items()) CHECK(d.code != "contact-not-settled");

  // A run of the scene: summary.json's solver section gives the bound and the count; a scene without tools has
  // neither.
  const std::string path = (scratch_folder() / "rounds_run.yaml").string();
  const auto scene = sim::parse_scene(path, text + "duration: 0.05\noutputs: {frames: 0, precision_check: off}\n",
                                      diagnostics);
  REQUIRE(scene);
  const auto built = sim::build_scene(*scene, diagnostics);
  REQUIRE(built);
  sim::SceneRunOptions options;
  options.output_directory = (scratch_folder() / "rounds_run.out").string();
  const auto result = sim::run_scene(*scene, *built, options, diagnostics);
  REQUIRE(result);
  REQUIRE(result->solver);
  const sim::JsonDocument summary = sim::JsonDocument::parse(result->summary_json);
  CHECK(summary["solver"]["contact_rounds"] == 1);
  CHECK(summary["solver"]["contact_unsettled_steps"] == result->solver->contact_unsettled_steps);
  CHECK(summary["solver"]["first_contact_unsettled_step"] == result->solver->first_contact_unsettled_step);
}
