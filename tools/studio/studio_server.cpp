#include "tools/studio/studio_server.h"

#include <httplib.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <list>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "compiler/frontend/rule_file_loader.h"
#include "runtime/io/input_file.h"
#include "tools/studio/studio_assets.h"
#include "tools/studio/studio_cohorts.h"
#include "tools/studio/studio_evaluation.h"
#include "tools/studio/studio_files.h"
#include "tools/studio/studio_rule_edits.h"
#include "tools/studio/studio_rule_model.h"
#include "tools/studio/studio_scene.h"
#include "tools/studio/studio_security.h"

namespace fmpc::studio {

namespace fs = std::filesystem;

namespace {

// A request the page got wrong: answered with its status and the message, never a crash.
struct RequestError : std::runtime_error {
  RequestError(int code, const std::string& message) : std::runtime_error(message), status(code) {}
  int status;
};

struct Answer {
  int status = 200;
  Json body;
};

// The files of Debian's libjs-* packages the page loads, exactly these (so nothing else under /usr/share/javascript
// is reachable), with the package that ships each.
struct LibraryFile {
  const char* path;
  const char* package;
};
constexpr LibraryFile kLibraryFiles[] = {
    {"codemirror/lib/codemirror.js", "libjs-codemirror"},  {"codemirror/lib/codemirror.css", "libjs-codemirror"},
    {"codemirror/addon/mode/simple.js", "libjs-codemirror"}, {"codemirror/addon/lint/lint.js", "libjs-codemirror"},
    {"codemirror/addon/lint/lint.css", "libjs-codemirror"}, {"d3/d3.min.js", "libjs-d3"},
    {"three/three.min.js", "libjs-three"},                   {"three/examples/js/controls/OrbitControls.js", "libjs-three"},
};

std::string mime_type(const std::string& name) {
  const auto ends = [&](const char* suffix) {
    const std::string s = suffix;
    return name.size() >= s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".png")) return "image/png";
  return "application/octet-stream";
}

const Json& field(const Json& request, const char* name) {
  if (!request.is_object() || !request.contains(name))
    throw RequestError(400, std::string("the request has no field '") + name + "'");
  return request.at(name);
}

std::string string_field(const Json& request, const char* name) {
  const Json& value = field(request, name);
  if (!value.is_string()) throw RequestError(400, std::string("field '") + name + "' must be a string");
  return value.get<std::string>();
}

std::string optional_string(const Json& request, const char* name) {
  return request.is_object() && request.contains(name) && request.at(name).is_string()
             ? request.at(name).get<std::string>()
             : std::string();
}

double number_field(const Json& request, const char* name) {
  const Json& value = field(request, name);
  if (!value.is_number()) throw RequestError(400, std::string("field '") + name + "' must be a number");
  return value.get<double>();
}

std::vector<double> numbers_field(const Json& request, const char* name, std::size_t count) {
  const Json& value = field(request, name);
  if (!value.is_array() || value.size() != count)
    throw RequestError(400, std::string("field '") + name + "' must hold " + std::to_string(count) + " numbers");
  std::vector<double> numbers;
  for (const Json& item : value) {
    if (!item.is_number() || !std::isfinite(item.get<double>()))
      throw RequestError(400, std::string("field '") + name + "' must hold finite numbers");
    numbers.push_back(item.get<double>());
  }
  return numbers;
}

std::size_t index_field(const Json& request, const char* name, std::size_t size) {
  const Json& value = field(request, name);
  if (!value.is_number_integer() || value.get<long long>() < 0 || static_cast<std::size_t>(value.get<long long>()) >= size)
    throw RequestError(400, std::string("field '") + name + "' must be an index below " + std::to_string(size));
  return static_cast<std::size_t>(value.get<long long>());
}

std::map<std::string, std::string> columns_field(const Json& request) {
  std::map<std::string, std::string> columns;
  if (!request.is_object() || !request.contains("columns")) return columns;
  const Json& value = request.at("columns");
  if (!value.is_object()) throw RequestError(400, "field 'columns' must map input names to column names");
  for (const auto& [input, column] : value.items()) {
    if (!column.is_string()) throw RequestError(400, "field 'columns' must map input names to column names");
    columns[input] = column.get<std::string>();
  }
  return columns;
}

RuleSpec rule_spec_field(const Json& request) {
  const Json& value = field(request, "rule");
  RuleSpec spec;
  const auto clauses = [&](const char* name, std::vector<ClauseSpec>& out) {
    if (!value.contains(name)) return;
    for (const Json& c : value.at(name))
      out.push_back({string_field(c, "variable"), string_field(c, "term"), c.value("negated", false),
                     optional_string(c, "hedge")});
  };
  clauses("antecedent", spec.antecedent);
  clauses("consequent", spec.consequent);
  spec.conjunction = value.value("connective", std::string("and")) != "or";
  spec.weight = value.value("weight", 1.0);
  return spec;
}

}  // namespace

struct StudioServer::State {
  StudioOptions options;
  httplib::Server server;
  int port = 0;
  std::atomic<bool> serving{false};
  std::atomic<bool> stop_requested{false};
  std::atomic<bool> finished{false};

  // A path from the page, checked against the folder: 403 when it leads outside.
  fs::path inside(const std::string& relative) const {
    std::string error;
    const std::optional<fs::path> path = resolve_inside(options.root, relative, error);
    if (!path) throw RequestError(403, error);
    return *path;
  }

  // Rule texts read without errors, most recent first: a patient panel sends the same text with every slider step,
  // and the 247-rule liver takes longer to read than to evaluate.
  mutable std::mutex cache_mutex;
  mutable std::list<std::pair<std::string, std::shared_ptr<const RuleFile>>> cache;
  static constexpr std::size_t kCachedTexts = 4;

  // The rule file the request carries as text, named by its path in the folder; 422 when it has errors.
  struct RequestRules {
    std::string name;
    std::shared_ptr<const RuleFile> file;
    const FuzzySystem* system = nullptr;
  };
  RequestRules request_rules(const Json& request) const {
    RequestRules rules;
    rules.name = relative_name(options.root, inside(string_field(request, "path")));
    const std::string text = string_field(request, "text");
    if (text.size() > sim::kMaxRuleFileBytes)
      throw RequestError(413, "the rule text is larger than a rule file may be (" +
                                  sim::byte_size_text(sim::kMaxRuleFileBytes) + ")");
    const std::string key = rules.name + '\0' + text;
    {
      const std::lock_guard<std::mutex> lock(cache_mutex);
      for (auto it = cache.begin(); it != cache.end(); ++it)
        if (it->first == key) {
          cache.splice(cache.begin(), cache, it);
          rules.file = it->second;
          break;
        }
    }
    if (!rules.file) {
      DiagnosticList diagnostics;
      auto file = std::make_shared<const RuleFile>(load_rule_file(rules.name, text, diagnostics));
      if (diagnostics.has_errors())
        throw RequestError(422, "the rule file has errors: fix them first (they are listed under the editor)");
      const std::lock_guard<std::mutex> lock(cache_mutex);
      cache.emplace_front(key, file);
      if (cache.size() > kCachedTexts) cache.pop_back();
      rules.file = file;
    }
    rules.system = find_system(*rules.file, optional_string(request, "system"));
    if (!rules.system) throw RequestError(422, "there is no system '" + optional_string(request, "system") + "'");
    return rules;
  }

  Answer session() const {
    const std::vector<std::string> files = list_files(options.root);
    std::string opened = options.opened;
    if (opened.empty())
      for (const std::string& file : files)
        if (file.size() > 4 && file.compare(file.size() - 4, 4, ".fis") == 0) {
          opened = file;
          break;
        }
    return {200, Json{{"folder", options.root.filename().string()}, {"files", files}, {"opened", opened}}};
  }

  Answer read_file(const httplib::Request& request) const {
    if (!request.has_param("path")) throw RequestError(400, "the request has no parameter 'path'");
    std::string error;
    inside(request.get_param_value("path"));
    const std::optional<FileText> file =
        read_folder_file(options.root, request.get_param_value("path"), sim::kMaxRuleFileBytes, error);
    if (!file) throw RequestError(404, error);
    return {200, Json{{"path", file->path}, {"text", file->text}, {"version", file->version}}};
  }

  Answer check(const Json& request) const {
    const std::string name = relative_name(options.root, inside(string_field(request, "path")));
    const std::string text = string_field(request, "text");
    if (text.size() > sim::kMaxRuleFileBytes) throw RequestError(413, "the rule text is too large");
    return {200, check_json(load_rule_text(name, text))};
  }

  Answer memberships(const Json& request) const {
    const RequestRules rules = request_rules(request);
    const std::string variable = string_field(request, "variable");
    const int input = rules.system->find_input(variable), output = rules.system->find_output(variable);
    if (input < 0 && output < 0) throw RequestError(400, "there is no variable '" + variable + "'");
    const Variable& v = input >= 0 ? rules.system->inputs[static_cast<std::size_t>(input)]
                                   : rules.system->outputs[static_cast<std::size_t>(output)];
    return {200, membership_curves_json(*rules.system, v, input < 0, 301)};
  }

  Answer edit(const Json& request) const {
    const std::string name = relative_name(options.root, inside(string_field(request, "path")));
    const std::string text = string_field(request, "text");
    const std::string system = optional_string(request, "system");
    const std::string operation = string_field(request, "operation");
    std::string error;
    std::optional<std::string> edited;
    if (operation == "set_parameter") {
      edited = set_term_parameter(name, text, system, string_field(request, "variable"), string_field(request, "term"),
                                  string_field(request, "parameter"), number_field(request, "value"), error);
    } else if (operation == "set_rule") {
      edited = set_rule(name, text, system, index_field(request, "index", std::size_t{1} << 30),
                        rule_spec_field(request), error);
    } else if (operation == "add_rule") {
      edited = add_rule(name, text, system, request.contains("rule") ? rule_spec_field(request) : RuleSpec{}, error);
    } else if (operation == "delete_rule") {
      edited = delete_rule(name, text, system, index_field(request, "index", std::size_t{1} << 30), error);
    } else {
      throw RequestError(400, "unknown operation '" + operation +
                                  "' (set_parameter, set_rule, add_rule, delete_rule)");
    }
    if (!edited) throw RequestError(422, error);
    return {200, Json{{"text", *edited}}};
  }

  Answer save(const Json& request) const {
    const std::string name = relative_name(options.root, inside(string_field(request, "path")));
    const SaveResult result =
        save_rule_file(options.root, name, string_field(request, "text"), string_field(request, "version"));
    if (result.outcome == SaveOutcome::Conflict) throw RequestError(409, result.message);
    if (result.outcome == SaveOutcome::Refused) throw RequestError(422, result.message);
    return {200, Json{{"path", result.file.path}, {"text", result.file.text}, {"version", result.file.version}}};
  }

  Answer evaluate(const Json& request) const {
    const RequestRules rules = request_rules(request);
    return {200, evaluation_json(*rules.system, numbers_field(request, "inputs", rules.system->inputs.size()))};
  }

  Answer surface(const Json& request) const {
    const RequestRules rules = request_rules(request);
    const FuzzySystem& system = *rules.system;
    if (system.inputs.size() < 2) throw RequestError(422, "a surface needs two inputs; this system has one");
    const std::size_t x = index_field(request, "x", system.inputs.size());
    const std::size_t y = index_field(request, "y", system.inputs.size());
    if (x == y) throw RequestError(400, "a surface needs two different inputs");
    const std::size_t output = index_field(request, "output", system.outputs.size());
    const auto resolution = static_cast<std::size_t>(std::clamp(number_field(request, "resolution"), 2.0,
                                                                static_cast<double>(kMaxSurfaceResolution)));
    return {200, surface_json(system, x, y, output, numbers_field(request, "point", system.inputs.size()), resolution)};
  }

  CohortTable table_field(const Json& request) const {
    const Json& csv = field(request, "csv");
    return CohortTable{string_field(csv, "name"), string_field(csv, "text"), columns_field(csv)};
  }

  Answer validate(const Json& request) const {
    const RequestRules rules = request_rules(request);
    return {200, validation_json(*rules.system, optional_string(request, "output"),
                                 optional_string(request, "measured"), table_field(request))};
  }

  // The edit (`text`) against the file on disk (`against` empty or the same path) or another file of the folder.
  Answer compare(const Json& request) const {
    const RequestRules edited = request_rules(request);
    const std::string against = optional_string(request, "against").empty() ? edited.name
                                                                             : optional_string(request, "against");
    std::string error;
    const std::optional<FileText> disk = read_folder_file(options.root, relative_name(options.root, inside(against)),
                                                          sim::kMaxRuleFileBytes, error);
    if (!disk) throw RequestError(404, error);
    const sim::LoadedRuleFile reference = load_rule_text(disk->path, disk->text);
    if (reference.diagnostics.has_errors())
      throw RequestError(422, "'" + disk->path + "' has errors: fmpc check " + disk->path + " lists them");
    const FuzzySystem* system = find_system(reference.rules, edited.system->name);
    if (!system) system = find_system(reference.rules, "");
    const std::string first = disk->path + (against == edited.name ? " (on disk)" : "");
    const std::string second = edited.name + " (this edit)";
    if (!request.contains("csv"))
      return {200, Json{{"ok", true}, {"first", first}, {"second", second},
                        {"differences", differences_json(*system, *edited.system)}}};
    return {200, comparison_json(*system, first, *edited.system, second, table_field(request))};
  }

  Answer scene(const Json& request) const {
    const RequestRules rules = request_rules(request);
    const std::string scene = optional_string(request, "scene");
    const std::optional<fs::path> scene_path = scene.empty() ? std::nullopt : std::optional<fs::path>(inside(scene));
    std::string error;
    std::optional<Json> result =
        run_patient_scene(options.root / rules.name, string_field(request, "text"), *rules.system,
                          numbers_field(request, "inputs", rules.system->inputs.size()), scene_path, error);
    if (!result) throw RequestError(422, error);
    return {200, *result};
  }
};

StudioServer::StudioServer() : state_(std::make_unique<State>()) {}
StudioServer::~StudioServer() = default;

namespace {

void send(httplib::Response& response, const Answer& answer) {
  response.status = answer.status;
  response.set_content(sim::json_text(answer.body), "application/json; charset=utf-8");
}

void send_error(httplib::Response& response, int status, const std::string& message) {
  send(response, Answer{status, Json{{"error", message}}});
}

// Runs a handler on the request's JSON body: malformed JSON and wrong fields become 400, a refused path 403, and
// so on (RequestError); anything else is a bug in fmpc, answered 500 with what happened.
void answer_json(const httplib::Request& request, httplib::Response& response,
                 const std::function<Answer(const Json&)>& handler) {
  try {
    Json body;
    try {
      body = Json::parse(request.body);
    } catch (const nlohmann::json::exception& e) {
      throw RequestError(400, std::string("the request is not JSON: ") + e.what());
    }
    send(response, handler(body));
  } catch (const RequestError& e) {
    send_error(response, e.status, e.what());
  } catch (const nlohmann::json::exception& e) {
    send_error(response, 400, std::string("a field of the request has the wrong type: ") + e.what());
  } catch (const std::exception& e) {
    send_error(response, 500, std::string("internal error in fmpc (please report it): ") + e.what());
  }
}

}  // namespace

bool StudioServer::start(const StudioOptions& options, std::string& error) {
  State& s = *state_;
  s.options = options;
  std::error_code code;
  s.options.root = fs::canonical(options.root, code);
  if (code || !fs::is_directory(s.options.root)) {
    error = "'" + options.root.string() + "' is not a folder that can be opened";
    return false;
  }
  if (s.options.token.empty()) {
    const std::optional<std::string> token = random_token(error);
    if (!token) return false;
    s.options.token = *token;
  }
  httplib::Server& server = s.server;
  server.set_payload_max_length(kMaxRequestBytes);
  // cpp-httplib's default also sets SO_REUSEPORT, with which a second process (of the same user) could bind the
  // studio's port and take a share of its connections; SO_REUSEADDR alone only lets a restart reuse a port in
  // TIME_WAIT, and a port in use is refused.
  server.set_socket_options([](int socket) {
    int yes = 1;
    setsockopt(socket, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  server.set_default_headers({
      {"Cache-Control", "no-store"},
      {"X-Content-Type-Options", "nosniff"},
      {"Referrer-Policy", "no-referrer"},
      {"X-Frame-Options", "DENY"},
      // Only this server's own scripts, styles and connections: nothing is fetched from anywhere else.
      {"Content-Security-Policy",
       "default-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; connect-src 'self'; "
       "frame-ancestors 'none'; base-uri 'none'; form-action 'none'"},
  });
  server.set_pre_routing_handler([this](const httplib::Request& request, httplib::Response& response) {
    const State& state = *state_;
    if (!host_allowed(request.get_header_value("Host"), state.port)) {
      send_error(response, 403,
                 "this studio answers requests for 127.0.0.1:" + std::to_string(state.port) + " only (Host was '" +
                     request.get_header_value("Host") + "')");
      return httplib::Server::HandlerResponse::Handled;
    }
    const std::string token = request.has_param("token") ? request.get_param_value("token")
                                                         : request.get_header_value("X-Fmpc-Token");
    if (!token_matches(token, state.options.token)) {
      send_error(response, 403, "missing or wrong session token: open the address `fmpc studio` printed");
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  server.Get("/", [this](const httplib::Request&, httplib::Response& response) {
    std::string page(studio_asset("index.html"));
    for (std::size_t at = page.find("{{TOKEN}}"); at != std::string::npos; at = page.find("{{TOKEN}}", at))
      page.replace(at, 9, state_->options.token);
    response.set_content(page, "text/html; charset=utf-8");
  });
  server.Get(R"(/static/([a-z_]+\.(js|css)))", [](const httplib::Request& request, httplib::Response& response) {
    const std::string name = request.matches[1];
    const std::string_view asset = studio_asset(name);
    if (asset.empty()) return send_error(response, 404, "no such page file: " + name);
    response.set_content(std::string(asset), mime_type(name).c_str());
  });
  server.Get(R"(/lib/(.+))", [this](const httplib::Request& request, httplib::Response& response) {
    const std::string name = request.matches[1];
    for (const LibraryFile& file : kLibraryFiles) {
      if (name != file.path) continue;
      std::string problem;
      const std::optional<std::string> text =
          sim::read_input_file((state_->options.javascript / file.path).string(), 8 * sim::kMiB, "library", problem);
      if (!text)
        return send_error(response, 404,
                          "'" + name + "' is missing: install Debian's " + file.package + " (" + problem + ")");
      return response.set_content(*text, mime_type(name).c_str());
    }
    send_error(response, 404, "'" + name + "' is not one of the libraries the studio serves");
  });
  server.Get("/api/session", [this](const httplib::Request&, httplib::Response& response) {
    send(response, state_->session());
  });
  server.Get("/api/file", [this](const httplib::Request& request, httplib::Response& response) {
    try {
      send(response, state_->read_file(request));
    } catch (const RequestError& e) {
      send_error(response, e.status, e.what());
    }
  });
  const auto post = [this](const char* path, Answer (State::*handler)(const Json&) const) {
    state_->server.Post(path, [this, handler](const httplib::Request& request, httplib::Response& response) {
      answer_json(request, response, [&](const Json& body) { return (state_.get()->*handler)(body); });
    });
  };
  post("/api/check", &State::check);
  post("/api/memberships", &State::memberships);
  post("/api/edit", &State::edit);
  post("/api/save", &State::save);
  post("/api/evaluate", &State::evaluate);
  post("/api/surface", &State::surface);
  post("/api/validate", &State::validate);
  post("/api/compare", &State::compare);
  post("/api/scene", &State::scene);

  if (options.port > 0) {
    if (!server.bind_to_port("127.0.0.1", options.port)) {
      error = "cannot listen on 127.0.0.1:" + std::to_string(options.port) + " (in use?): pick another --port";
      return false;
    }
    s.port = options.port;
  } else {
    s.port = server.bind_to_any_port("127.0.0.1");
    if (s.port <= 0) {
      error = "cannot listen on 127.0.0.1";
      return false;
    }
  }
  return true;
}

// cpp-httplib's stop() does nothing before its listening loop has started, which would leave a serve() that starts
// just after a stop() running for ever: each side tells the other where it is.
bool StudioServer::serve() {
  State& s = *state_;
  s.serving = true;
  if (s.stop_requested) {
    s.finished = true;
    return true;
  }
  const bool listened = s.server.listen_after_bind();
  s.finished = true;
  return listened;
}

void StudioServer::stop() {
  State& s = *state_;
  s.stop_requested = true;
  if (!s.serving) return;
  while (!s.server.is_running() && !s.finished) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  s.server.stop();
}
int StudioServer::port() const { return state_->port; }
const std::string& StudioServer::token() const { return state_->options.token; }
std::string StudioServer::url() const {
  return "http://127.0.0.1:" + std::to_string(state_->port) + "/?token=" + state_->options.token;
}

}  // namespace fmpc::studio
