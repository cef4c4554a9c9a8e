// Scene building (fixed nodes, probes, ray picking), the outputs (VTU, PVD, CSV, JSON) and whole runs: the demo,
// the strain-table scene and SOFA's liver scenes (skipped visibly without ../shared/data).
#include "runtime/scene/scene_run.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/io/json_text.h"
#include "runtime/io/vtk_xml.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string scene_path(const std::string& name) { return std::string(FMPC_SOURCE_DIR) + "/rulesets/scenes/" + name + ".yaml"; }

Scene parse_text(const std::string& text, const std::string& path = "/tmp/fmpc_scene_test.yaml") {
  DiagnosticList diagnostics;
  auto scene = parse_scene(path, text, diagnostics);
  INFO((diagnostics.empty() ? std::string() : diagnostics.items().front().message));
  REQUIRE(scene);
  return *scene;
}

// Every diagnostic of parsing `text` as "line:column: message".
std::vector<std::string> errors_of(const std::string& text) {
  DiagnosticList d;
  parse_scene("s.yaml", text, d);
  std::vector<std::string> out;
  for (const Diagnostic& item : d.items())
    out.push_back(std::to_string(item.range.line) + ":" + std::to_string(item.range.column) + ": " + item.message);
  return out;
}

std::vector<std::string> messages(const DiagnosticList& diagnostics) {
  std::vector<std::string> out;
  for (const Diagnostic& d : diagnostics.items()) out.push_back(d.message);
  return out;
}

// Tags open and close in order: enough to call the generated XML well-formed (it has no comments or CDATA).
bool tags_balanced(const std::string& xml) {
  std::vector<std::string> open;
  const std::regex tag(R"(<(/?)([A-Za-z]+)[^>]*?(/?)>)");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), tag); it != std::sregex_iterator(); ++it) {
    const std::smatch& m = *it;
    if (m[1] == "/") {
      if (open.empty() || open.back() != m[2]) return false;
      open.pop_back();
    } else if (m[3] != "/") {
      open.push_back(m[2]);
    }
  }
  return open.empty() && xml.rfind("<?xml version=\"1.0\"?>\n", 0) == 0;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::filesystem::path temporary_directory(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("fmpc_scene_test_" + name);
  std::filesystem::remove_all(dir);
  return dir;
}

}  // namespace

TEST_CASE("VTU frames and the PVD collection are well-formed with the right counts", "[scene]") {
  DiagnosticList diagnostics;
  const Mesh box = generate_box(BoxSpec{{0, 0, 0}, {1, 1, 1}, 2, 1, 1}, diagnostics);
  REQUIRE(box.points.size() == 12);
  REQUIRE(box.tetrahedra.size() == 12);
  std::vector<Point3> displacement(box.points.size(), Point3{0.5, 0, -1e-300});
  VtuOptions ascii;
  ascii.format = VtuFormat::Ascii;
  const auto box_cells = encode_vtu_cells(box, ascii, diagnostics);
  REQUIRE(box_cells);
  const std::string vtu = *vtu_document(box.points, *box_cells, {vtu_vectors("displacement", displacement)}, {}, ascii,
                                        diagnostics);
  CHECK(tags_balanced(vtu));
  CHECK(vtu.find("<Piece NumberOfPoints=\"12\" NumberOfCells=\"12\">") != std::string::npos);
  CHECK(vtu.find("<PointData Vectors=\"displacement\">") != std::string::npos);
  CHECK(count(vtu, "          10\n") == 12);               // VTK_TETRA per cell
  CHECK(vtu.find("          48\n") != std::string::npos);  // the last offset: 12 cells x 4
  CHECK(count(vtu, "0.5 0 -1e-300\n") == 12);              // shortest round-trip numbers

  Mesh triangles;
  triangles.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  triangles.triangles = {{0, 1, 2}};
  const auto triangle_cells = encode_vtu_cells(triangles, ascii, diagnostics);
  REQUIRE(triangle_cells);
  const std::string surface = *vtu_document(triangles.points, *triangle_cells, {}, {}, ascii, diagnostics);
  CHECK(tags_balanced(surface));
  CHECK(surface.find("          5\n") != std::string::npos);  // VTK_TRIANGLE
  CHECK(surface.find("<PointData>") != std::string::npos);

  const std::string pvd = pvd_document({{0.0, "frame_00000.vtu"}, {0.25, "a&b.vtu"}});
  CHECK(tags_balanced(pvd));
  CHECK(pvd.find("<DataSet timestep=\"0.25\" group=\"\" part=\"0\" file=\"a&amp;b.vtu\"/>") != std::string::npos);
}

TEST_CASE("JSON text: the library's layout and escaping, fmpc's numbers, null for non-finite numbers", "[scene]") {
  JsonDocument json;
  json["text"] = "a \"quoted\"\\ line\n\x01";
  json["nan"] = std::nan("");
  json["inf"] = HUGE_VAL;
  json["count"] = std::size_t{3};
  json["flag"] = false;
  json["list"] = {0.1, 2.0};
  json["empty"] = JsonDocument::object();
  const std::string text = json_text(json);
  CHECK(text == "{\n  \"text\": \"a \\\"quoted\\\"\\\\ line\\n\\u0001\",\n  \"nan\": null,\n  \"inf\": null,\n"
                "  \"count\": 3,\n  \"flag\": false,\n  \"list\": [\n    0.1,\n    2\n  ],\n  \"empty\": {}\n}\n");
  // Valid JSON, read back by the library.
  const JsonDocument read = JsonDocument::parse(text);
  CHECK(read["nan"].is_null());
  CHECK(read["list"][1].get<double>() == 2.0);
  // Without floating-point numbers the text is exactly nlohmann's own dump(2).
  JsonDocument plain;
  plain["name"] = "\xce\xbcm \t tab";
  plain["nested"] = {{"a", 1}, {"b", JsonDocument::array()}, {"c", {true, nullptr, -4}}};
  CHECK(json_text(plain) == plain.dump(2) + "\n");
  // Invalid UTF-8 (a file name, say) becomes U+FFFD instead of an invalid document or an exception.
  JsonDocument bad;
  bad["path"] = std::string("a\xff" "b");
  CHECK(json_text(bad) == "{\n  \"path\": \"a\xef\xbf\xbd" "b\"\n}\n");
}

TEST_CASE("JSON text writes every finite double as format_number does, and it reads back exactly", "[scene]") {
  std::mt19937_64 random(20240611);
  std::uniform_int_distribution<std::uint64_t> bits;
  std::size_t checked = 0;
  for (int i = 0; i < 20000; ++i) {
    double value = 0.0;
    const std::uint64_t b = bits(random);
    std::memcpy(&value, &b, sizeof value);
    if (i % 4 == 1) value = std::ldexp(static_cast<double>(b >> 11), -53) * 1000.0;  // plain magnitudes
    if (i % 4 == 2) value = static_cast<double>(static_cast<std::int64_t>(b >> 20)) - 1e12;  // whole numbers
    if (i % 4 == 3) value = std::nextafter(0.0, 1.0) * static_cast<double>(b >> 40);  // subnormals
    if (!std::isfinite(value)) continue;
    JsonDocument array = JsonDocument::array();
    array.push_back(value);
    const std::string text = json_text(array);
    REQUIRE(text == "[\n  " + format_number(value) + "\n]\n");
    CHECK(JsonDocument::parse(text)[0].get<double>() == (value == 0.0 ? 0.0 : value));
    ++checked;
  }
  CHECK(checked > 15000);
}

TEST_CASE("rays hit triangles (Moller-Trumbore), and probes are picked by ray", "[scene]") {
  const Point3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  CHECK(ray_triangle_hit({0.25, 0.25, 2}, {0, 0, -1}, a, b, c) == Approx(2.0));
  CHECK(ray_triangle_hit({0.25, 0.25, 2}, {0, 0, -4}, a, b, c) == Approx(0.5));  // t in the direction's units
  CHECK_FALSE(ray_triangle_hit({0.25, 0.25, 2}, {0, 0, 1}, a, b, c));            // behind the origin
  CHECK_FALSE(ray_triangle_hit({0.9, 0.9, 2}, {0, 0, -1}, a, b, c));             // outside
  CHECK_FALSE(ray_triangle_hit({0.25, 0.25, 2}, {1, 0, 0}, a, b, c));            // parallel

  const Scene scene = parse_text(R"(mesh: {box: {size: [2, 2, 2], cells: [2, 2, 1]}}
material: {stiffness: 10}
fixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
loads: {probe: {ray: {origin: [1, 1, 5], direction: [0, 0, -1]}, displacement: [0, 0, -0.1]}}
)");
  DiagnosticList diagnostics;
  const auto built = build_scene(scene, diagnostics);
  REQUIRE(built);
  REQUIRE(built->setup.probe);
  REQUIRE(built->setup.probe->vertices.size() == 1);
  CHECK(built->mesh.points[static_cast<std::size_t>(built->setup.probe->vertices[0])] == Point3{1, 1, 2});
  CHECK(built->setup.fixed_vertices.size() == 9);
  CHECK(built->setup.strain_stiffness.has_value() == false);  // nothing built that the scene does not use
  CHECK(built->setup.external_forces.empty());

  Scene wide = scene;
  wide.probe->radius = 1.0;
  const auto built_wide = build_scene(wide, diagnostics);
  INFO((diagnostics.empty() ? std::string() : diagnostics.items().back().message));
  REQUIRE(built_wide);
  CHECK(built_wide->setup.probe->vertices.size() == 5);  // the centre and its 4 edge neighbours on the top face

  Scene miss = scene;
  miss.probe->ray_origin = {5, 5, 5};
  DiagnosticList missed;
  CHECK_FALSE(build_scene(miss, missed));
  CHECK(messages(missed) == std::vector<std::string>{"loads.probe.ray: the ray from (5, 5, 5) along (0, 0, -1) hits no "
                                                     "surface of the mesh; the mesh spans (0, 0, 0) to (2, 2, 2) "
                                                     "(mesh units)"});
}

TEST_CASE("fixed-node and probe errors name the field", "[scene]") {
  const std::string base = "mesh: {box: {size: [1, 1, 1]}}\nmaterial: {stiffness: 10}\n";
  const auto errors_of = [&](const std::string& extra) {
    DiagnosticList diagnostics;
    INFO(extra);
    CHECK_FALSE(build_scene(parse_text(base + extra), diagnostics));
    return messages(diagnostics);
  };
  CHECK(errors_of("fixed: {indices: [0, 8]}\n") ==
        std::vector<std::string>{"fixed.indices: vertex 8 is out of range; the mesh has 8 vertices (0 to 7)"});
  CHECK(errors_of("fixed: {box: {min: [2, 2, 2], max: [3, 3, 3]}}\n") ==
        std::vector<std::string>{"fixed.box: no vertex lies in the box (2, 2, 2) to (3, 3, 3); the mesh spans (0, 0, 0) "
                                 "to (1, 1, 1) (mesh units)"});
  CHECK(errors_of("fixed: {plane: {point: [0, 0, 0.5], normal: [0, 0, 1]}}\n") ==
        std::vector<std::string>{"fixed.plane: no vertex lies within 1e-09 of the plane through (0, 0, 0.5) with normal "
                                 "(0, 0, 1); raise 'tolerance' or move the plane (the mesh spans (0, 0, 0) to (1, 1, 1) "
                                 "(mesh units))"});
  CHECK(errors_of("fixed: {indices: [0]}\nloads: {probe: {indices: [0], displacement: [0, 0, 1]}}\n") ==
        std::vector<std::string>{"loads.probe: vertex 0 is picked by the probe and also fixed; a vertex can be one or "
                                 "the other"});
  CHECK(errors_of("loads: {probe: {indices: [1, 1], force: [0, 0, 1]}}\n") ==
        std::vector<std::string>{"loads.probe.indices: vertex 1 is given twice"});
}

TEST_CASE("a displacement probe records the reaction force, a force probe the displacement", "[scene]") {
  SimulationSetup setup;
  setup.rest_positions = {{0, 0, 0}, {1, 0, 0}};
  setup.mass = {1.0, 1.0};
  setup.fixed_vertices = {0};
  setup.springs.vertex_count = 2;
  setup.springs.first = {0};
  setup.springs.second = {1};
  setup.springs.kind = {SpringKind::TetrahedronEdge};
  setup.springs.element_measure = {0.0};
  setup.springs.rest_length = {1.0};
  setup.springs.stiffness = {100.0};
  setup.springs.damping = {20.0};
  build_adjacency(setup.springs);
  setup.integrator = Integrator::ImplicitEuler;
  setup.time_step = 0.01;

  SimulationSetup pushed = setup;
  pushed.probe = ProbeLoad{ProbeLoad::Mode::Displacement, {1}, {0.1, 0, 0}, 0.5};
  DiagnosticList diagnostics;
  auto simulation = Simulation::create(pushed, diagnostics);
  REQUIRE(simulation);
  REQUIRE(simulation->advance(25, diagnostics));  // half the ramp
  CHECK(simulation->positions(diagnostics)[1][0] == Approx(1.05).epsilon(1e-12));
  ProbeReading reading = simulation->probe_reading(diagnostics);
  CHECK(reading.displacement[0] == Approx(0.05).epsilon(1e-12));
  CHECK(reading.force[0] == Approx(100.0 * 0.05).epsilon(1e-12));  // k d: the probe pulls against the spring
  REQUIRE(simulation->advance(100, diagnostics));
  reading = simulation->probe_reading(diagnostics);
  CHECK(reading.force[0] == Approx(10.0).epsilon(1e-12));

  SimulationSetup pulled = setup;
  pulled.probe = ProbeLoad{ProbeLoad::Mode::Force, {1}, {5.0, 0, 0}, 0.0};
  simulation = Simulation::create(pulled, diagnostics);
  REQUIRE(simulation);
  REQUIRE(simulation->advance(2000, diagnostics));
  reading = simulation->probe_reading(diagnostics);
  CHECK(reading.force[0] == 5.0);
  CHECK(reading.displacement[0] == Approx(5.0 / 100.0).epsilon(1e-6));  // F / k at rest

  SimulationSetup clash = setup;
  clash.probe = ProbeLoad{ProbeLoad::Mode::Force, {0, 2}, {1, 0, 0}, 0.0};
  DiagnosticList refused;
  CHECK_FALSE(Simulation::create(clash, refused));
  CHECK(messages(refused) == std::vector<std::string>{"probe vertex 0 is also fixed; unfix it or pick another",
                                                      "probe vertex 2 is out of range (the mesh has 2 vertices)"});
}

TEST_CASE("the demo scene runs and writes frames, PVD, CSV and summary", "[scene]") {
  const std::string path = scene_path("liver_indentation");
  DiagnosticList diagnostics;
  auto scene = parse_scene(path, read_text(path), diagnostics);
  REQUIRE(scene);
  scene->steps = 1500;  // the full demo is ~18,000 steps; its shape is checked on the first part of the ramp
  scene->outputs.frames = 4;
  scene->outputs.samples = 30;
  const auto built = build_scene(*scene, diagnostics);
  REQUIRE(built);
  CHECK(built->setup.probe->vertices.size() == 5);
  CHECK(built->setup.fixed_vertices.size() == 81);
  const auto dir = temporary_directory("demo");
  SceneRunOptions options;
  options.output_directory = dir.string();
  std::size_t progress_calls = 0;
  options.progress = [&](std::size_t done, std::size_t total) {
    ++progress_calls;
    CHECK(done <= total);
  };
  const auto result = run_scene(*scene, *built, options, diagnostics);
  REQUIRE(result);
  CHECK_FALSE(diagnostics.has_errors());
  CHECK(result->completed);
  CHECK(result->steps_taken == 1500);
  CHECK(progress_calls >= 100);
  CHECK(result->files.size() == 7);  // 4 frames, pvd, csv, summary
  CHECK(std::filesystem::exists(dir / "frame_00003.vtu"));
  CHECK_FALSE(std::filesystem::exists(dir / "frame_00004.vtu"));
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    CHECK(entry.path().filename().string().find(".tmp.") == std::string::npos);  // no temporary left behind

  const std::string pvd = read_text((dir / "liver_indentation.pvd").string());
  CHECK(count(pvd, "<DataSet ") == 4);
  // Binary frames by default: the XML before the appended data is well-formed (tests/unit/vtk_xml_test.cpp decodes
  // the data).
  const std::string frame = read_text((dir / "frame_00002.vtu").string());
  const std::size_t appended = frame.find("  <AppendedData encoding=\"raw\">\n   _");
  REQUIRE(appended != std::string::npos);
  CHECK(tags_balanced(frame.substr(0, appended) + "</VTKFile>\n"));
  CHECK(frame.find("compressor=\"vtkZLibDataCompressor\"") < appended);
  CHECK(frame.find("NumberOfPoints=\"405\" NumberOfCells=\"1536\"") != std::string::npos);

  std::istringstream csv(read_text((dir / "time_series.csv").string()));
  std::string header;
  std::getline(csv, header);
  std::string expected;
  for (const auto& column : time_series_columns(true)) expected += (expected.empty() ? "" : ",") + column;
  CHECK(header == expected);
  std::size_t rows = 0;
  std::string line, last;
  while (std::getline(csv, line)) {
    ++rows;
    last = line;
    CHECK(count(line, ",") == 11);
  }
  CHECK(rows == 30);
  // The probe moves down by ramp(t) x 4 mm and the tissue pushes back: force and displacement both positive along
  // the probe's direction, in the ratio of the block's stiffness (about 300 N/m for this patient early in the ramp).
  REQUIRE(result->probe_curve.size() == 30);
  const ProbeCurvePoint& end = result->probe_curve.back();
  CHECK(end.displacement == Approx(0.004 * end.time / 1.0).epsilon(1e-5));
  CHECK(end.force / end.displacement == Approx(300.0).epsilon(0.15));

  const std::string json = read_text((dir / "summary.json").string());
  for (const char* key : {"\"scene\"", "\"completed\": true", "\"dt_s\"", "\"steps\": 1500", "\"wall_time_s\"",
                          "\"steps_per_second\"", "\"timing\"", "\"stepping_s\"", "\"max_displacement_m\"", "\"k_min_N_per_m\"", "\"k_max_N_per_m\"",
                          "\"youngs_modulus_min_kPa\": 20.8283800234838", "\"patient\"", "\"probe\"", "\"final_force_N\""})
    CHECK(json.find(key) != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("the strain-stiffening scene stiffens its springs as they stretch", "[scene]") {
  const std::string path = scene_path("strain_stiffening_block");
  DiagnosticList diagnostics;
  auto scene = parse_scene(path, read_text(path), diagnostics);
  REQUIRE(scene);
  const auto built = build_scene(*scene, diagnostics);
  REQUIRE(built);
  REQUIRE(built->setup.strain_stiffness);
  CHECK(built->setup.strain_stiffness->strain.size() == 61);
  const auto dir = temporary_directory("strain");
  SceneRunOptions options;
  options.output_directory = dir.string();
  scene->steps = 2000;
  scene->outputs.frames = 0;
  const auto result = run_scene(*scene, *built, options, diagnostics);
  REQUIRE(result);
  CHECK(result->completed);
  CHECK_FALSE(std::filesystem::exists(dir / "strain_stiffening_block.pvd"));  // frames: 0
  CHECK(result->probe_curve.back().force == Approx(2.0 * std::min(1.0, result->probe_curve.back().time / 0.5)));
  CHECK(result->probe_curve.back().displacement > 0.0);
  std::filesystem::remove_all(dir);
}

TEST_CASE("SOFA's liver spring scenes run, springs and fuzzy", "[scene]") {
  if (!std::filesystem::exists(std::string(FMPC_SHARED_DATA_DIR) + "/sofa-liver/liver.msh")) {
    WARN("skipped: " << FMPC_SHARED_DATA_DIR << "/sofa-liver is absent (../shared/data holds SOFA's liver mesh)");
    return;
  }
  double sag[2] = {0.0, 0.0};
  int i = 0;
  for (const char* name : {"sofa_liver_springs", "sofa_liver_fuzzy"}) {
    INFO(name);
    const std::string path = scene_path(name);
    DiagnosticList diagnostics;
    auto scene = parse_scene(path, read_text(path), diagnostics);
    REQUIRE(scene);
    const auto built = build_scene(*scene, diagnostics);
    REQUIRE(built);
    CHECK(built->mesh.points.size() == 181);
    CHECK(built->setup.fixed_vertices.size() == 3);
    const auto dir = temporary_directory(name);
    SceneRunOptions options;
    options.output_directory = dir.string();
    scene->outputs.frames = 2;
    scene->steps = 25;  // 0.5 s of the scene's 2 s: implicit steps on these stiff springs take CG hundreds of iterations
    const auto result = run_scene(*scene, *built, options, diagnostics);
    REQUIRE(result);
    CHECK(result->completed);
    CHECK(result->steps_taken == 25);
    CHECK(result->stability.time_step == 0.02);
    CHECK_FALSE(diagnostics.has_errors());
    sag[i++] = result->max_displacement;
    std::filesystem::remove_all(dir);
  }
  // Hanging from three nodes under gravity, both sag; the fuzzy liver (E = 19.3 kPa) is of the same order.
  CHECK(sag[0] > 0.0);
  CHECK(sag[1] > 0.0);
  CHECK(sag[1] / sag[0] > 0.1);
  CHECK(sag[1] / sag[0] < 10.0);
}

TEST_CASE("SOFA's liver-CUDA scene as co-rotational FEM: runs, no inversion, stresses in the frames", "[scene][fem]") {
  if (!std::filesystem::exists(std::string(FMPC_SHARED_DATA_DIR) + "/sofa-liver/liver.msh")) {
    WARN("skipped: " << FMPC_SHARED_DATA_DIR << "/sofa-liver is absent (../shared/data holds SOFA's liver mesh)");
    return;
  }
  const std::string path = scene_path("sofa_liver_fem");
  DiagnosticList diagnostics;
  auto scene = parse_scene(path, read_text(path), diagnostics);
  REQUIRE(scene);
  const auto built = build_scene(*scene, diagnostics);
  REQUIRE(built);
  CHECK(model_name(built->setup) == "corotational_fem");
  CHECK(built->setup.tetrahedra.size() == 596);
  CHECK(built->setup.mass_damping == 0.1);
  const auto dir = temporary_directory("sofa_liver_fem");
  SceneRunOptions options;
  options.output_directory = dir.string();
  scene->outputs.frames = 2;
  scene->steps = 10;
  scene->outputs.precision_check = SceneOutputs::PrecisionCheck::Off;
  const auto result = run_scene(*scene, *built, options, diagnostics);
  REQUIRE(result);
  CHECK(result->completed);
  CHECK(result->inversions.largest_count == 0);
  CHECK(result->max_displacement > 0.0);
  CHECK_FALSE(diagnostics.has_errors());
  const std::string frame = read_text((dir / "frame_00001.vtu").string());
  CHECK(frame.find("<CellData") != std::string::npos);
  CHECK(frame.find("Name=\"von_mises_stress_Pa\"") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("the precision check: agreeing scenes say so, a chaotic one warns, big ones are skipped", "[scene]") {
  const auto run = [](const std::string& text, DiagnosticList& diagnostics) {
    const Scene scene = parse_text(text);
    const auto built = build_scene(scene, diagnostics);
    REQUIRE(built);
    const auto dir = temporary_directory("precision");
    SceneRunOptions options;
    options.output_directory = dir.string();
    auto result = run_scene(scene, *built, options, diagnostics);
    std::filesystem::remove_all(dir);
    REQUIRE(result);
    return result->precision_check;
  };
  const std::string box = "mesh: {box: {size: [0.01, 0.01, 0.01], cells: [1, 1, 1]}, units: m}\n"
                          "material: {youngs_modulus: 1}\nmass: {density: 1000}\n";
  // An undamped box hanging from one corner tumbles chaotically: float and double part ways.
  DiagnosticList chaotic;
  const PrecisionCheckResult tumbling =
      run(box + "damping: none\nfixed: {indices: [0]}\nloads: {gravity: [0.3, 0.1, -9.81]}\n"
                "integrator: velocity_verlet\nduration: 3.0\noutputs: {frames: 0, samples: 10}\n",
          chaotic);
  CHECK(tumbling.ran);
  CHECK_FALSE(tumbling.agrees);
  CHECK(tumbling.displacement_difference > kPrecisionTolerance);
  bool warned = false;
  for (const Diagnostic& d : chaotic.items()) warned = warned || d.code == "precision-dependent";
  CHECK(warned);
  // A damped box resting on its base settles to the same answer in both.
  DiagnosticList settled;
  const PrecisionCheckResult resting =
      run(box + "damping: {ratio: 0.9}\nfixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\n"
                "loads: {gravity: [0, 0, -9.81]}\nduration: 0.5\noutputs: {frames: 0, samples: 10}\n",
          settled);
  CHECK(resting.ran);
  CHECK(resting.agrees);
  CHECK(resting.displacement_difference < 1e-4);
  // A box that barely moves (gravity 1e-9 m/s^2: displacements near 1e-13 of its size, rounding in both precisions)
  // is not "100% different": issue 30's scene moved 1e-7 mm and was warned about.
  DiagnosticList still;
  const PrecisionCheckResult barely =
      run(box + "damping: {ratio: 0.9}\nfixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\n"
                "loads: {gravity: [0, 0, -1e-9]}\nduration: 0.5\noutputs: {frames: 0, samples: 10}\n",
          still);
  CHECK(barely.ran);
  CHECK(barely.agrees);
  CHECK(barely.reason.find("moves less than 1e-05 of its size") != std::string::npos);
  for (const Diagnostic& d : still.items()) CHECK(d.code != "precision-dependent");
  // Off, and skipped above the automatic limit (the reason says how to force it).
  DiagnosticList off;
  CHECK_FALSE(run(box + "fixed: {indices: [0]}\nduration: 0.01\noutputs: {frames: 0, samples: 0, precision_check: off}\n",
                  off)
                  .ran);
}

TEST_CASE("scenes choose the force model; the FEM refuses spring settings, naming the field", "[scene][fem]") {
  const std::string base =
      "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [2, 2, 2]}, units: m}\nmass: {density: 1000}\n"
      "fixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\nloads: {gravity: [0, 0, -9.81]}\n";
  DiagnosticList diagnostics;
  const Scene fem = parse_text("model: corotational_fem\n" + base +
                               "material: {youngs_modulus: 3, poisson_ratio: 0.3}\n"
                               "damping: {ratio: 0.5, rayleigh: {mass: 2, stiffness: 0.001}}\non_inversion: stop\n");
  CHECK(fem.model == ForceModel::Elements);
  CHECK(fem.element_law == kernels::element_law_index<kernels::CorotationalLinear>);
  CHECK(fem.on_inversion == InversionPolicy::Stop);
  CHECK(fem.rayleigh.mass == 2.0);
  const auto built = build_scene(fem, diagnostics);
  REQUIRE(built);
  const SimulationSetup& setup = built->setup;
  CHECK(model_name(setup) == "corotational_fem");
  CHECK(setup.springs.size() == 0);
  REQUIRE(setup.elements.terms.size() == 1);
  const ElementTerm& term = setup.elements.terms.front();
  CHECK(term.law == kernels::element_law_index<kernels::CorotationalLinear>);
  CHECK(setup.elements.geometry.size() == 48);
  CHECK(term.parameter[kernels::CorotationalLinear::kYoungsModulus].front() == 3000.0);
  CHECK(term.parameter[kernels::CorotationalLinear::kPoissonRatio].front() == 0.3);
  CHECK(setup.mass_damping == 2.0);
  CHECK(setup.on_inversion == InversionPolicy::Stop);
  for (const double beta : term.stiffness_damping) CHECK(beta > 0.001);
  CHECK(built->stiffness_description == "FEM (law corotational, element linear) with E = 3 kPa, nu = 0.3");

  // Springs with the volume term and Rayleigh damping.
  const Scene volume = parse_text(base + "material: {youngs_modulus: 3, poisson_ratio: 0.45}\n"
                                         "springs: {volume_term: true}\ndamping: {rayleigh: {stiffness: 0.01}}\n");
  const auto springs = build_scene(volume, diagnostics);
  REQUIRE(springs);
  REQUIRE(springs->setup.elements.terms.size() == 1);
  CHECK(springs->setup.elements.terms.front().law == kernels::element_law_index<kernels::VolumePreservation>);
  CHECK(springs->setup.springs.damping.size() == springs->setup.springs.size());
  CHECK(springs->setup.springs.damping.front() == Approx(0.01 * springs->setup.springs.stiffness.front()));

  const auto spring_only = errors_of("model: corotational_fem\n" + base +
                                     "material: {stiffness: 100, mapping: lloyd_szekely_harders_2007}\n"
                                     "law: basafa_farahmand\ndamping: {coefficient: 2}\nsprings: {bending: true}\n");
  CHECK(spring_only ==
        std::vector<std::string>{
            "6:37: material.mapping: only allowed with 'youngs_modulus', 'rules' or 'table' (it maps "
            "Young's modulus to spring constants)",
            "6:23: material.stiffness: a finite-element model takes Young's modulus (youngs_modulus, rules "
            "or table), not spring constants",
            "9:10: springs: has no meaning for model: corotational_fem (it is a spring setting)",
            "7:6: law: has no meaning for model: corotational_fem (it is a spring setting); the FEM's "
            "material is its element law (fem: {law: ...})",
            "8:24: damping.coefficient: a per-spring dashpot setting; the FEM is damped by 'ratio' "
            "(each element's fastest mode) and 'rayleigh'"});
  CHECK(errors_of(base + "material: {youngs_modulus: 3, poisson_ratio: 0.3}\n") ==
        std::vector<std::string>{"5:46: material.poisson_ratio: springs alone have nu = 1/4 (central springs obey the "
                                 "Cauchy relation lambda = mu); add the volume term (springs: {volume_term: true}) to "
                                 "reach another ratio, or use model: corotational_fem"});
  CHECK(errors_of("model: corotational_fem\n" + base + "material: {youngs_modulus: 3, poisson_ratio: 0.5}\n") ==
        std::vector<std::string>{"6:46: material.poisson_ratio: expected a number in [0, 0.4999] (0.5 is incompressible, "
                                 "which no element here represents; linear tetrahedra take at most 0.499), got 0.5"});
  CHECK(errors_of(base + "material: {youngs_modulus: 3}\nmodel: finite_elements\n").front() ==
        "6:8: model: 'finite_elements' is not a force model; use springs, fem or corotational_fem");

  // A per-region binding that misses part of the body: the FEM evaluates the material per element, and says so.
  const std::string material = "material: {rules: " + std::string(FMPC_SOURCE_DIR) +
                               "/rulesets/liver_fibrosis/mamdani.fis, inputs: {HCV: {regions: [{box: {min: [0, 0, 0], "
                               "max: [0.01, 0.02, 0.02]}, value: 9}]}, HBV: 9.5, ALD: 12, CLD: 11, NAFLD: 11}}\n";
  for (const bool fem_model : {true, false}) {
    DiagnosticList missed;
    CHECK_FALSE(build_scene(parse_text((fem_model ? "model: corotational_fem\n" : "") + base + material), missed));
    REQUIRE(missed.error_count() == 1);
    const std::string& message = missed.items().front().message;
    INFO(message);
    CHECK(message.rfind(fem_model ? "material.inputs.HCV: element " : "material.inputs.HCV: spring ", 0) == 0);
    CHECK(message.find(fem_model ? " (centroid " : " (midpoint ") != std::string::npos);
  }
}

TEST_CASE("model: fem takes its law and element kind from the registries; corotational_fem is one such pair",
          "[scene][fem]") {
  const std::string base =
      "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [2, 2, 2]}, units: m}\nmass: {density: 1000}\n"
      "fixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\nloads: {gravity: [0, 0, -9.81]}\n"
      "material: {youngs_modulus: 3, poisson_ratio: 0.3}\n";
  // Every law that is a model of its own, on every element kind, by its keywords; model: corotational_fem is the
  // pair {corotational, linear} and builds the same setup.
  const Scene old_keys = parse_text("model: corotational_fem\n" + base);
  DiagnosticList diagnostics;
  const auto old_built = build_scene(old_keys, diagnostics);
  REQUIRE(old_built);
  for (const std::string& law : fem_law_keywords())
    for (const std::string& kind : element_kind_keywords()) {
      INFO(law << " on " << kind);
      const Scene scene = parse_text("model: fem\nfem: {law: " + law + ", element: " + kind + "}\n" + base);
      CHECK(scene.model == ForceModel::Elements);
      CHECK(scene.element_law == fem_law_by_keyword(law)->law);
      CHECK(scene.element_kind == element_kind_by_keyword(kind)->kind);
      const auto built = build_scene(scene, diagnostics);
      REQUIRE(built);
      CHECK(built->setup.elements.terms.front().law == scene.element_law);
      CHECK(built->setup.elements.geometry.kind == scene.element_kind);
      CHECK(built->stiffness_description == "FEM (law " + law + ", element " + kind + ") with E = 3 kPa, nu = 0.3");
      const char* own = element_law_row(scene.element_law).model_keyword;
      const bool named = own != nullptr && scene.element_kind == default_element_kind().kind;
      CHECK(model_name(built->setup) == (named ? std::string(own) : "fem"));
      CHECK(model_keyword(scene) == model_name(built->setup));
      if (scene.element_law == old_keys.element_law && scene.element_kind == default_element_kind().kind) {
        for (int i = 0; i < kernels::kMostLawParameters; ++i)
          CHECK(built->setup.elements.terms.front().parameter[i] ==
                old_built->setup.elements.terms.front().parameter[i]);
        CHECK(built->setup.elements.geometry.nodes == old_built->setup.elements.geometry.nodes);
        CHECK(built->setup.mass == old_built->setup.mass);
      }
    }
  // model: fem alone is the default law on the default element kind.
  const Scene bare = parse_text("model: fem\n" + base);
  CHECK(bare.element_law == default_fem_law().law);
  CHECK(bare.element_kind == default_element_kind().kind);
  CHECK(diagnostics.error_count() == 0);

  const auto joined = [](const std::vector<std::string>& names) {
    std::string out;
    for (std::size_t i = 0; i < names.size(); ++i)
      out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
    return out;
  };
  // Unknown laws and element kinds: located, listing the known ones; the volume term is no model of its own.
  CHECK(
      errors_of("model: fem\nfem: {law: neo_hooke}\n" + base) ==
      std::vector<std::string>{"2:12: fem.law: 'neo_hooke' is not an element law; use " + joined(fem_law_keywords())});
  CHECK(errors_of("model: fem\nfem: {law: " + std::string(element_law_beside_springs().keyword) + "}\n" + base)
            .front()
            .rfind("2:12: fem.law: '" + std::string(element_law_beside_springs().keyword) + "' is not an element law",
                   0) == 0);
  CHECK(errors_of("model: fem\nfem: {element: cubic}\n" + base) ==
        std::vector<std::string>{"2:16: fem.element: 'cubic' is not an element kind; use " +
                                 joined(element_kind_keywords())});
  CHECK(errors_of("model: fem\nfem: {law: corotational, elements: linear}\n" + base).front() ==
        "2:26: fem.elements: unknown key in fem; allowed: 'law' or 'element'");
  // fem belongs to model: fem.
  CHECK(errors_of("model: corotational_fem\nfem: {element: linear}\n" + base) ==
        std::vector<std::string>{"2:6: fem: 'fem' chooses the law and element of model: fem; this scene's model is "
                                 "'corotational_fem': write model: fem (model: corotational_fem is fem: {law: "
                                 "corotational, element: linear})"});
  CHECK(errors_of("fem: {law: corotational}\n" + base).front() ==
        "1:6: fem: 'fem' chooses the law and element of model: fem; this scene's model is springs (the default): "
        "write model: fem (model: corotational_fem is fem: {law: corotational, element: linear})");
}

TEST_CASE("each element kind's Poisson limit and locking warning: linear up to 0.499 warned above 0.45, quadratic and "
          "nodal pressure to 0.4999",
          "[scene][fem][quadratic]") {
  const auto build = [](const std::string& kind, const std::string& nu, DiagnosticList& diagnostics) {
    const Scene scene = parse_text("model: fem\nfem: {element: " + kind +
                                   "}\nmesh: {box: {size: [0.02, 0.02, 0.02], cells: [1, 1, 1]}, units: m}\n"
                                   "mass: {density: 1000}\nmaterial: {youngs_modulus: 3, poisson_ratio: " +
                                   nu + "}\n");
    return build_scene(scene, diagnostics).has_value();
  };
  const auto located = [](const DiagnosticList& diagnostics) {
    std::vector<std::string> out;
    for (const Diagnostic& item : diagnostics.items())
      out.push_back(std::to_string(item.range.line) + ":" + std::to_string(item.range.column) + ": " + item.message);
    return out;
  };
  DiagnosticList quiet;
  CHECK(build("linear", "0.45", quiet));
  CHECK(build("quadratic", "0.4999", quiet));
  CHECK(build("linear_nodal_pressure", "0.4999", quiet));
  CHECK(quiet.empty());
  DiagnosticList locking;
  CHECK(build("linear", "0.49", locking));
  REQUIRE(locking.items().size() == 1);
  CHECK(locking.items().front().severity == Severity::Warning);
  CHECK(locking.items().front().code == "element-locking");
  CHECK(located(locking) ==
        std::vector<std::string>{"5:46: material.poisson_ratio 0.49: fem.element linear locks (is too stiff) above nu = "
                                 "0.45; docs/validation.md measures linear tetrahedra 6.4% too stiff at nu 0.45 on an "
                                 "8^3-cell cube and 3.3 times too stiff on SOFA's liver at nu 0.49, against CalculiX "
                                 "C3D10"});
  DiagnosticList refused;
  CHECK(!build("linear", "0.4995", refused));
  CHECK(located(refused) ==
        std::vector<std::string>{"5:46: material.poisson_ratio: 0.4995 is above 0.499, the most fem.element linear "
                                 "takes; use fem: {element: quadratic} or fem: {element: linear_nodal_pressure} (up to "
                                 "0.4999) for nearly incompressible tissue"});
}

TEST_CASE("implicit Euler's solves in summary.json and the time series; steps at the cap warned once with the count",
          "[scene][implicit]") {
  // A soft FEM block sagging at a large step: the CG capped at 3 iterations cannot reach 1e-12.
  const std::string text = R"yaml(name: implicit_block
mesh: {box: {size: [0.02, 0.02, 0.02], cells: [2, 2, 2]}}
model: corotational_fem
material: {youngs_modulus: 2, poisson_ratio: 0.45}
mass: {density: 1000}
fixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
loads: {gravity: [0, 0, -9.81]}
integrator: implicit_euler
dt: 0.01
duration: 0.2
precision: double
solver: {method: cg, tolerance: 1e-12, max_iterations: 3}
outputs: {frames: 0, samples: 5, precision_check: off}
)yaml";
  const Scene scene = parse_text(text);
  DiagnosticList diagnostics;
  const auto built = build_scene(scene, diagnostics);
  REQUIRE(built);
  CHECK(built->setup.implicit.max_iterations == 3);
  const auto dir = temporary_directory("implicit");
  SceneRunOptions options;
  options.output_directory = dir.string();
  const auto result = run_scene(scene, *built, options, diagnostics);
  REQUIRE(result);
  REQUIRE(result->solver);
  CHECK(result->solver->steps == 20);
  CHECK(result->solver->capped_steps == 20);
  // One warning for the run, located at `solver`, with the count and the residuals reached.
  std::vector<Diagnostic> capped;
  for (const Diagnostic& d : diagnostics.items())
    if (d.code == "cg-not-converged") capped.push_back(d);
  REQUIRE(capped.size() == 1);
  CHECK(capped[0].range.line == 12);
  CHECK(capped[0].range.column == 9);
  CHECK(capped[0].message ==
        "implicit Euler: 20 of 20 steps stopped at the cap of 3 conjugate-gradient iterations above the tolerance "
        "1e-12 (the first at step 1 with relative residual " +
            format_number(result->solver->first_capped_residual) + "); the largest relative residual reached was " +
            format_number(result->solver->residual_max) + " at step " +
            std::to_string(result->solver->residual_max_step) +
            "; raise solver.max_iterations, loosen solver.tolerance or use a smaller dt");

  const JsonDocument summary = JsonDocument::parse(read_text((dir / "summary.json").string()));
  const JsonDocument& solver = summary["solver"];
  CHECK(solver["method"] == "cg");
  CHECK(solver["requested_method"] == "cg");
  CHECK(solver["preconditioner"] == "block_jacobi");
  CHECK(solver["warm_start"] == true);
  CHECK(solver["tolerance"].get<double>() == 1e-12);
  CHECK(solver["max_iterations"] == 3);
  CHECK(solver["steps"] == 20);
  CHECK(solver["iterations_max"] == 3);
  CHECK(solver["capped_steps"] == 20);
  CHECK(solver["first_capped_step"] == 1);
  CHECK_FALSE(solver.contains("contact_rounds"));  // no tools
  REQUIRE(solver["per_step"]["iterations"].size() == 20);
  REQUIRE(solver["per_step"]["relative_residual"].size() == 20);
  double largest = 0.0;
  for (const auto& residual : solver["per_step"]["relative_residual"]) largest = std::max(largest, residual.get<double>());
  CHECK(largest == solver["relative_residual_max"].get<double>());

  // The time series: each row's worst step since the row before.
  std::istringstream csv(read_text((dir / "time_series.csv").string()));
  std::string header, line;
  std::getline(csv, header);
  CHECK(header == "time_s,kinetic_energy_J,elastic_energy_J,max_displacement_m,solver_iterations,"
                  "solver_relative_residual");
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  REQUIRE(rows.size() == 5);
  CHECK(rows.front().substr(rows.front().size() - 4) == ",0,0");  // step 0: no solve yet
  CHECK(rows.back().find(",3,") != std::string::npos);

  // The direct solver on the same scene: one solve a step, no warning.
  Scene direct = scene;
  direct.solver.method = ImplicitMethod::Direct;
  direct.solver.max_iterations = 0;
  const auto direct_built = build_scene(direct, diagnostics);
  REQUIRE(direct_built);
  DiagnosticList direct_diagnostics;
  const auto direct_result = run_scene(direct, *direct_built, options, direct_diagnostics);
  REQUIRE(direct_result);
  CHECK(direct_result->solver->method == ImplicitMethod::Direct);
  CHECK(direct_result->solver->iterations_max == 1);
  CHECK(direct_result->solver->residual_max < 1e-12);
  CHECK(direct_diagnostics.warning_count() == 0);
  const JsonDocument direct_summary = JsonDocument::parse(read_text((dir / "summary.json").string()));
  CHECK(direct_summary["solver"]["preconditioner"] == "none");
  CHECK(direct_summary["solver"]["warm_start"] == false);
  std::filesystem::remove_all(dir);
}

TEST_CASE("backend cuda with an element kind CUDA does not run with the scene's integrator is an error at backend, "
          "with the registry's reason",
          "[scene][fem][nodal]") {
  // The nodal pressure kind: the explicit integrators on both backends, implicit Euler on the CPU only
  // (element_kind_limits, cuda_refusal); decided before any GPU is asked for.
  const std::string text = R"yaml(name: nodal_implicit
mesh: {box: {size: [0.02, 0.02, 0.02], cells: [1, 1, 1]}}
model: fem
fem: {law: stable_neo_hookean, element: linear_nodal_pressure}
material: {youngs_modulus: 2, poisson_ratio: 0.45}
mass: {density: 1000}
integrator: implicit_euler
backend: cuda
)yaml";
  DiagnosticList diagnostics;
  CHECK_FALSE(choose_backend(parse_text(text), diagnostics));
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items().front().range.line == 8);
  CHECK(messages(diagnostics).front() ==
        "backend: fem.element linear_nodal_pressure runs implicit_euler on the CPU backend only for now (the CUDA "
        "engine's matrix-free conjugate gradient has no nodal pressure term yet); the explicit integrators run on "
        "both; use backend cpu or auto");
}
