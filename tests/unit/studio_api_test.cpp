// The studio's HTTP API (tools/studio/studio_server.h), served in-process on 127.0.0.1 and spoken to over real
// sockets with cpp-httplib's client: requests without the session token, with another Host header, or naming files
// outside the opened folder (.., absolute, a symbolic link leading out) are refused; only the listed Debian library
// files are served; the JSON answers carry the numbers and the diagnostics of the library the CLI uses (equal to
// evaluate() and to `fmpc check`'s rendering); saving writes the canonical layout and refuses a file changed on disk.
#include <catch2/catch.hpp>

#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "compiler/eval/agreement.h"
#include "compiler/eval/control_surface.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/number_format.h"
#include "runtime/io/rule_file_input.h"
#include "tools/studio/studio_files.h"
#include "tools/studio/studio_server.h"

namespace fmpc::studio {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const char* kRules = R"(# tissue stiffness
system tissue
input reading "FibroScan reading" in [0, 40] kPa
  soft is triangle(start 0, peak 5, end 15)
  firm is triangle(start 10, peak 20, end 30)
  hard is trapezoid(start 25, top_start 35, top_end 40, end 40)
input fat in [0, 100] %
  lean is linear_z(start 10, end 40)
  fatty is linear_s(start 20, end 60)
output stiffness in [0, 30] kPa
  low is triangle(start 0, peak 4, end 10)
  mid is triangle(start 6, peak 12, end 18)
  high is triangle(start 14, peak 22, end 30)
rule r1: if reading is soft then stiffness is low
rule r2: if reading is firm then stiffness is mid
rule r3: if reading is hard then stiffness is high
rule r4: if reading is firm and fat is fatty then stiffness is low weight 0.5
)";

const char* kMeasured = "label,reading,fat,stiffness\nA1,4,10,3.9\nA2,12,35,9.1\nA3,21,15,12.5\nA5,33,50,21\n";

void write(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A folder with the rules, a CSV and a link leading out of it, a server on it, and a client.
struct Studio {
  fs::path base;
  fs::path folder;
  StudioServer server;
  std::thread thread;
  std::unique_ptr<httplib::Client> client;

  Studio() {
    base = fs::temp_directory_path() / ("fmpc-studio-test-" + std::to_string(::getpid()));
    fs::remove_all(base);
    folder = base / "rules";
    fs::create_directories(folder / "sub");
    fs::create_directories(base / "javascript" / "d3");
    write(folder / "tissue.fis", kRules);
    write(folder / "measured.csv", kMeasured);
    write(base / "secret.fis", "system secret\n");
    write(base / "javascript" / "d3" / "d3.min.js", "/* d3 */");
    write(base / "javascript" / "d3" / "other.js", "/* not served */");
    fs::create_symlink(base / "secret.fis", folder / "sub" / "escape.fis");
    StudioOptions options;
    options.root = folder;
    options.opened = "tissue.fis";
    options.javascript = base / "javascript";
    options.token = "test-token";
    std::string error;
    REQUIRE(server.start(options, error));
    thread = std::thread([this] { server.serve(); });
    client = std::make_unique<httplib::Client>("127.0.0.1", server.port());
    client->set_connection_timeout(5);
    client->set_read_timeout(30);
  }
  ~Studio() {
    server.stop();
    thread.join();
    fs::remove_all(base);
  }

  httplib::Headers token() const { return {{"X-Fmpc-Token", "test-token"}}; }
  httplib::Result get(const std::string& path) { return client->Get(path.c_str(), token()); }
  httplib::Result post(const std::string& path, const json& body) {
    return client->Post(path.c_str(), token(), body.dump(), "application/json");
  }
};

json body(const httplib::Result& result) { return json::parse(result->body); }

TEST_CASE("studio API: the session token is required on every request", "[studio]") {
  Studio studio;
  for (const char* path : {"/", "/api/session", "/static/studio.js", "/lib/d3/d3.min.js", "/api/file?path=tissue.fis"}) {
    INFO(path);
    const auto none = studio.client->Get(path);
    REQUIRE(none);
    CHECK(none->status == 403);
    CHECK(body(none)["error"] == "missing or wrong session token: open the address `fmpc studio` printed");
    const auto wrong = studio.client->Get(path, httplib::Headers{{"X-Fmpc-Token", "test-tokem"}});
    CHECK(wrong->status == 403);
    const auto in_query = studio.client->Get((std::string(path) + (std::string(path).find('?') == std::string::npos ? "?" : "&") +
                                              "token=test-token").c_str());
    CHECK(in_query->status == 200);
    CHECK(studio.get(path)->status == 200);
  }
  const auto post = studio.client->Post("/api/check", json{{"path", "tissue.fis"}, {"text", kRules}}.dump(),
                                        "application/json");
  CHECK(post->status == 403);
  // The page carries the token into every script and API call it makes.
  const std::string page = studio.get("/")->body;
  CHECK(page.find("content=\"test-token\"") != std::string::npos);
  CHECK(page.find("{{TOKEN}}") == std::string::npos);
  CHECK(studio.server.url() == "http://127.0.0.1:" + std::to_string(studio.server.port()) + "/?token=test-token");
}

TEST_CASE("studio API: a second server cannot share the port", "[studio]") {
  Studio studio;
  StudioServer second;
  StudioOptions options;
  options.root = studio.folder;
  options.port = studio.server.port();
  std::string error;
  CHECK_FALSE(second.start(options, error));
  CHECK(error == "cannot listen on 127.0.0.1:" + std::to_string(options.port) + " (in use?): pick another --port");
}

TEST_CASE("studio API: another Host header is refused (DNS rebinding)", "[studio]") {
  Studio studio;
  const std::string port = std::to_string(studio.server.port());
  for (const std::string& host : std::vector<std::string>{"evil.example:" + port, "127.0.0.1", "127.0.0.1:1",
                                                          "localhost.evil:" + port}) {
    INFO(host);
    const auto answer = studio.client->Get("/api/session", {{"X-Fmpc-Token", "test-token"}, {"Host", host}});
    REQUIRE(answer);
    CHECK(answer->status == 403);
  }
  CHECK(studio.client->Get("/api/session", {{"X-Fmpc-Token", "test-token"}, {"Host", "localhost:" + port}})->status == 200);
}

TEST_CASE("studio API: files outside the opened folder are refused", "[studio]") {
  Studio studio;
  const auto refused = [&](const std::string& path, const std::string& message) {
    INFO(path);
    const auto answer = studio.get("/api/file?path=" + path);
    REQUIRE(answer);
    CHECK(answer->status == 403);
    CHECK(body(answer)["error"] == message);
  };
  refused("../secret.fis", "'../secret.fis' leads out of the opened folder ('..')");
  refused("%2e%2e/secret.fis", "'../secret.fis' leads out of the opened folder ('..')");
  refused("sub/../../secret.fis", "'sub/../../secret.fis' leads out of the opened folder ('..')");
  refused((studio.base / "secret.fis").string(), "'" + (studio.base / "secret.fis").string() +
                                                     "' is absolute; name files relative to the opened folder");
  refused("sub/escape.fis", "'sub/escape.fis' leads out of the opened folder (through a symbolic link)");
  refused("missing.fis", "'missing.fis' does not exist in the opened folder");
  // The same check guards every request that names a file.
  const auto save = studio.post("/api/save", {{"path", "../secret.fis"}, {"text", kRules}, {"version", "0"}});
  CHECK(save->status == 403);
  CHECK(read(studio.base / "secret.fis") == "system secret\n");
  CHECK(studio.post("/api/check", {{"path", "sub/escape.fis"}, {"text", kRules}})->status == 403);
  CHECK(studio.post("/api/compare", {{"path", "tissue.fis"}, {"text", kRules}, {"against", "../secret.fis"}})->status == 403);
  const auto file = studio.get("/api/file?path=tissue.fis");
  CHECK(file->status == 200);
  CHECK(body(file)["text"] == kRules);
  const json session = body(studio.get("/api/session"));
  CHECK(session["files"] == json({"measured.csv", "tissue.fis"}));  // the link leading out is not listed
  CHECK(session["opened"] == "tissue.fis");
}

TEST_CASE("studio API: only the listed library files are served", "[studio]") {
  Studio studio;
  const auto served = studio.get("/lib/d3/d3.min.js");
  CHECK(served->status == 200);
  CHECK(served->body == "/* d3 */");
  CHECK(served->get_header_value("Content-Type") == "text/javascript; charset=utf-8");
  CHECK(studio.get("/lib/d3/other.js")->status == 404);
  CHECK(studio.get("/lib/../secret.fis")->status == 404);
  const auto missing = studio.get("/lib/three/three.min.js");
  CHECK(missing->status == 404);
  CHECK(body(missing)["error"].get<std::string>().find("install Debian's libjs-three") != std::string::npos);
  CHECK(studio.get("/static/nothing.js")->status == 404);
  const auto page = studio.get("/static/studio.js");
  CHECK(page->status == 200);
  CHECK(page->get_header_value("Content-Security-Policy").find("default-src 'self'") == 0);
}

TEST_CASE("studio API: check answers what fmpc check prints", "[studio]") {
  Studio studio;
  const std::string text = std::string(kRules) + "rule r5: if reading is sfot then stiffness is low\n";
  const json check = body(studio.post("/api/check", {{"path", "tissue.fis"}, {"text", text}}));
  sim::LoadedRuleFile expected;
  expected.path = "tissue.fis";
  expected.readable = true;
  expected.sources.add("tissue.fis", text);
  expected.rules = load_rule_file("tissue.fis", text, expected.diagnostics);
  REQUIRE(check["diagnostics"].size() == expected.diagnostics.items().size());
  CHECK(check["errors"] == 1);
  CHECK(check["diagnostics"][0]["text"] == render(expected.diagnostics.items()[0], expected.sources));
  CHECK(check["diagnostics"][0]["line"] == 18);
  CHECK(check["diagnostics"][0]["notes"][0] == "did you mean 'soft'?");
  CHECK(check["systems"].empty());
  const json clean = body(studio.post("/api/check", {{"path", "tissue.fis"}, {"text", kRules}}));
  CHECK(clean["errors"] == 0);
  CHECK(clean["systems"][0]["rules"][3]["sentence"] ==
        "If reading is firm and fat is fatty, then stiffness is low. (weight 0.5)");
  CHECK(clean["systems"][0]["inputs"][0]["terms"][0]["parameters"][1] ==
        json({{"name", "peak"}, {"value", 5}, {"role", "position"}}));
}

TEST_CASE("studio API: evaluate equals the interpreter, digit for digit", "[studio]") {
  Studio studio;
  DiagnosticList diagnostics;
  const FuzzySystem system = load_rule_file("tissue.fis", kRules, diagnostics).systems.front();
  for (const std::vector<double>& inputs : {std::vector<double>{12, 35}, {21.5, 70}, {39, 5}}) {
    const auto answer = studio.post("/api/evaluate", {{"path", "tissue.fis"}, {"text", kRules}, {"inputs", inputs}});
    REQUIRE(answer->status == 200);
    const json result = body(answer);
    const Evaluation expected = evaluate(system, inputs);
    CHECK(result["outputs"][0]["value"].get<double>() == expected.outputs[0]);
    CHECK(result["outputs"][0]["text"] == format_number(expected.outputs[0]));
    CHECK(result["firing"].get<std::vector<double>>() == expected.firing_strengths);
    CHECK(result["outputs"][0]["method"] == "leave_one_out");
  }
  const json warned = body(studio.post("/api/evaluate", {{"path", "tissue.fis"}, {"text", kRules}, {"inputs", {50, 5}}}));
  CHECK(warned["warnings"][0] == "input 'reading' = 50 is outside its range [0, 40]; evaluated as given");
  const auto bad = studio.post("/api/evaluate", {{"path", "tissue.fis"}, {"text", kRules}, {"inputs", {1}}});
  CHECK(bad->status == 400);
  CHECK(body(bad)["error"] == "field 'inputs' must hold 2 numbers");
  const auto broken = studio.post("/api/evaluate", {{"path", "tissue.fis"}, {"text", "system s\n"}, {"inputs", {1, 2}}});
  CHECK(broken->status == 422);
  const auto garbage = studio.client->Post("/api/evaluate", studio.token(), "{not json", "application/json");
  CHECK(garbage->status == 400);
  CHECK(body(garbage)["error"].get<std::string>().rfind("the request is not JSON", 0) == 0);
  CHECK(studio.post("/api/evaluate", {{"text", kRules}})->status == 400);
}

TEST_CASE("studio API: membership curves and the control surface are the library's numbers", "[studio]") {
  Studio studio;
  DiagnosticList diagnostics;
  const FuzzySystem system = load_rule_file("tissue.fis", kRules, diagnostics).systems.front();
  // Every term's grade at every sample is term_membership's, the triangle's peak among the samples.
  const json curves = body(studio.post("/api/memberships", {{"path", "tissue.fis"}, {"text", kRules}, {"variable", "reading"}}));
  const std::vector<double> x = curves["x"].get<std::vector<double>>();
  CHECK(std::find(x.begin(), x.end(), 20.0) != x.end());
  REQUIRE(curves["terms"].size() == 3);
  for (std::size_t t = 0; t < 3; ++t)
    for (std::size_t k = 0; k < x.size(); ++k)
      CHECK(curves["terms"][t]["upper"][k].get<double>() == term_membership(system.inputs[0].terms[t], x[k]).upper);
  CHECK(studio.post("/api/memberships", {{"path", "tissue.fis"}, {"text", kRules}, {"variable", "nosuch"}})->status == 400);
  // The surface is control_surface's (what fmpc plot --x --y draws), with the strongest firing that marks holes.
  const json surface = body(studio.post("/api/surface", {{"path", "tissue.fis"}, {"text", kRules}, {"x", 0}, {"y", 1},
                                                         {"output", 0}, {"point", {12, 35}}, {"resolution", 11}}));
  const ControlSurface expected = control_surface(system, 0, 1, 0, {12, 35}, 11);
  CHECK(surface["x"].get<std::vector<double>>() == expected.x);
  CHECK(surface["y"].get<std::vector<double>>() == expected.y);
  CHECK(surface["z"].get<std::vector<double>>() == expected.z);
  CHECK(surface["strongest_firing"].get<std::vector<double>>() == expected.strongest_firing);
  CHECK(surface["threshold"] == 0.1);
  // reading 0 (soft's foot) fires no rule at 0.1: a coverage hole the page hatches.
  CHECK(expected.strongest_firing[0] < 0.1);
  CHECK(studio.post("/api/surface", {{"path", "tissue.fis"}, {"text", kRules}, {"x", 0}, {"y", 0}, {"output", 0},
                                     {"point", {12, 35}}, {"resolution", 11}})->status == 400);
}

TEST_CASE("studio API: edits, then saving the canonical layout, refused after a change on disk", "[studio]") {
  Studio studio;
  const json file = body(studio.get("/api/file?path=tissue.fis"));
  const json edited = body(studio.post("/api/edit", {{"path", "tissue.fis"}, {"text", kRules}, {"operation", "set_parameter"},
                                                     {"variable", "reading"}, {"term", "soft"}, {"parameter", "peak"},
                                                     {"value", 6}}));
  const std::string text = edited["text"];
  CHECK(text.find("soft is triangle(start 0, peak 6, end 15)") != std::string::npos);
  const auto unknown = studio.post("/api/edit", {{"path", "tissue.fis"}, {"text", kRules}, {"operation", "rename"}});
  CHECK(unknown->status == 400);
  // Saving writes what fmpc fmt writes, the comment kept.
  const auto saved = studio.post("/api/save", {{"path", "tissue.fis"}, {"text", text}, {"version", file["version"]}});
  REQUIRE(saved->status == 200);
  DiagnosticList diagnostics;
  const std::string canonical = *format_fmpc("tissue.fis", text, diagnostics);
  CHECK(read(studio.folder / "tissue.fis") == canonical);
  CHECK(body(saved)["text"] == canonical);
  CHECK(canonical.rfind("# tissue stiffness\n", 0) == 0);
  // The old version no longer matches what is on disk: another save with it is refused, the file untouched.
  const auto stale = studio.post("/api/save", {{"path", "tissue.fis"}, {"text", kRules}, {"version", file["version"]}});
  CHECK(stale->status == 409);
  CHECK(body(stale)["error"].get<std::string>().find("has changed on disk since it was opened") != std::string::npos);
  CHECK(read(studio.folder / "tissue.fis") == canonical);
  // Syntax errors: nothing written.
  const auto broken = studio.post("/api/save", {{"path", "tissue.fis"}, {"text", "system s\ninput x in [0, 1\n"},
                                                {"version", body(saved)["version"]}});
  CHECK(broken->status == 422);
  CHECK(read(studio.folder / "tissue.fis") == canonical);
  // A CSV is not a rule file: refused too.
  const json csv = body(studio.get("/api/file?path=measured.csv"));
  CHECK(studio.post("/api/save", {{"path", "measured.csv"}, {"text", "[System]\nName='x'\n"}, {"version", csv["version"]}})
            ->status == 422);
}

TEST_CASE("studio API: validation and comparison carry the commands' numbers", "[studio]") {
  Studio studio;
  const json request = {{"path", "tissue.fis"}, {"text", kRules}, {"csv", {{"name", "measured.csv"}, {"text", kMeasured}}}};
  const json validation = body(studio.post("/api/validate", request));
  REQUIRE(validation["ok"] == true);
  DiagnosticList diagnostics;
  const FuzzySystem system = load_rule_file("tissue.fis", kRules, diagnostics).systems.front();
  std::vector<double> predicted;
  for (const std::vector<double>& x : {std::vector<double>{4, 10}, {12, 35}, {21, 15}, {33, 50}})
    predicted.push_back(evaluate(system, x).outputs[0]);
  const Agreement expected = measure_agreement(predicted, {3.9, 9.1, 12.5, 21});
  CHECK(validation["agreement"]["mae"]["value"].get<double>() == expected.mean_absolute_error);
  CHECK(validation["agreement"]["rmse"]["value"].get<double>() == expected.root_mean_square_error);
  CHECK(validation["patients"][1]["label"] == "A2");
  const json bad = body(studio.post("/api/validate", {{"path", "tissue.fis"}, {"text", kRules},
                                                      {"csv", {{"name", "m.csv"}, {"text", "label,reading\nA,1\n"}}}}));
  CHECK(bad["ok"] == false);
  CHECK(bad["errors"][0].get<std::string>().rfind("m.csv:1:1: error: the header has no column 'fat' for input 'fat'", 0) == 0);
  // The edit against the file on disk: one term moved, one patient's stage changes.
  std::string edit = kRules;
  edit.replace(edit.find("peak 20"), 7, "peak 26");
  const json comparison = body(studio.post("/api/compare", {{"path", "tissue.fis"}, {"text", edit},
                                                            {"csv", {{"name", "measured.csv"}, {"text", kMeasured}}}}));
  REQUIRE(comparison["ok"] == true);
  CHECK(comparison["differences"] ==
        json({"term 'firm' of input 'reading': triangle(start 10, peak 20, end 30) -> triangle(start 10, peak 26, end 30)"}));
  CHECK(comparison["first"] == "tissue.fis (on disk)");
  CHECK(comparison["outputs"][0]["difference"][0] == 0);
  const json same = body(studio.post("/api/compare", {{"path", "tissue.fis"}, {"text", kRules}}));
  CHECK(same["differences"].empty());
}

TEST_CASE("studio API: the patient's scene runs with the edited rules", "[studio]") {
  Studio studio;
  // A small block (2 x 2 x 1 cells) pressed by a probe for 0.05 s, its material from tissue.fis.
  write(studio.folder / "block.yaml", R"(name: block
mesh:
  box: {size: [0.02, 0.02, 0.01], cells: [2, 2, 1]}
  units: m
material:
  rules: tissue.fis
  inputs: {reading: 12, fat: 35}
mass: {density: 1060}
damping: {ratio: 0.9}
fixed:
  plane: {point: [0, 0, 0], normal: [0, 0, 1]}
loads:
  probe:
    ray: {origin: [0.01, 0.01, 0.05], direction: [0, 0, -1]}
    displacement: [0, 0, -0.001]
    ramp: 0.04
integrator: semi_implicit_euler
dt: auto
duration: 0.05
)");
  std::string edit = kRules;
  edit.replace(edit.find("peak 12"), 7, "peak 15");
  const auto answer = studio.post("/api/scene", {{"path", "tissue.fis"}, {"text", edit}, {"inputs", {21, 35}},
                                                 {"scene", "block.yaml"}});
  REQUIRE(answer->status == 200);
  const json run = body(answer);
  CHECK(run["patient_and_rules_used"] == true);
  CHECK(run["completed"] == true);
  // The modulus is the edited rules' output for the panel's patient, not the scene's own inputs.
  DiagnosticList diagnostics;
  const FuzzySystem edited = load_rule_file("tissue.fis", edit, diagnostics).systems.front();
  CHECK(run["stiffness"].get<std::string>().find(format_number(evaluate(edited, {21, 35}).outputs[0]) + " kPa") !=
        std::string::npos);
  CHECK(run["rest"].size() == 18 * 3);  // 3 x 3 x 2 vertices
  CHECK(run["final"].size() == run["rest"].size());
  CHECK_FALSE(run["triangles"].empty());
  CHECK(run["probe_curve"].size() > 2);
  CHECK(run["probe_curve"].back()[2].get<double>() != 0.0);
  // A scene with a mistake answers the simulator's located message.
  write(studio.folder / "broken.yaml", "name: broken\nmesh: {box: {size: [1, 1, 1], cells: [1, 1, 1]}}\ndurration: 1\n");
  const auto broken = studio.post("/api/scene", {{"path", "tissue.fis"}, {"text", kRules}, {"inputs", {21, 35}},
                                                 {"scene", "broken.yaml"}});
  CHECK(broken->status == 422);
  CHECK(body(broken)["error"].get<std::string>().find("broken.yaml:3:1: error:") != std::string::npos);
  CHECK(studio.post("/api/scene", {{"path", "tissue.fis"}, {"text", kRules}, {"inputs", {21, 35}},
                                   {"scene", "../block.yaml"}})->status == 403);
}

}  // namespace
}  // namespace fmpc::studio
