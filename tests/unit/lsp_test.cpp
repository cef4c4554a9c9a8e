// fmpc lsp spoken to as an editor does, over pipes: the handshake, diagnostics as the text changes (UTF-16 and UTF-8
// positions), hover, completion, definitions, symbols, formatting equal to fmpc fmt, quick fixes; and what a broken
// or hostile client sends (malformed headers, non-JSON, oversized Content-Length, requests out of order), each
// answered with an error response while the server goes on, then shutdown and exit.
#include <catch2/catch.hpp>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/frontend/rule_file_loader.h"
#include "tests/support/fmpc_process.h"

namespace {

using Json = nlohmann::json;

const std::filesystem::path kSource = FMPC_SOURCE_DIR;

// `fmpc lsp` as a child process with pipes to its standard input and output.
class LspProcess {
 public:
  LspProcess() {
    int to_child[2], from_child[2];
    REQUIRE(::pipe(to_child) == 0);
    REQUIRE(::pipe(from_child) == 0);
    pid_ = ::fork();
    REQUIRE(pid_ >= 0);
    if (pid_ == 0) {
      ::dup2(to_child[0], STDIN_FILENO);
      ::dup2(from_child[1], STDOUT_FILENO);
      const int null = ::open("/dev/null", O_WRONLY);
      if (null >= 0) ::dup2(null, STDERR_FILENO);
      for (int fd : {to_child[0], to_child[1], from_child[0], from_child[1]}) ::close(fd);
      ::execl(FMPC_BINARY, FMPC_BINARY, "lsp", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(to_child[0]);
    ::close(from_child[1]);
    in_ = to_child[1];
    out_ = from_child[0];
    previous_sigpipe_ = ::signal(SIGPIPE, SIG_IGN);  // a server that died shows as a failed write, not a killed test
  }
  ~LspProcess() {
    if (in_ >= 0) ::close(in_);
    ::close(out_);
    if (pid_ > 0 && !waited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    ::signal(SIGPIPE, previous_sigpipe_);
  }

  void write_raw(const std::string& bytes) {
    std::size_t written = 0;
    while (written < bytes.size()) {
      const ssize_t n = ::write(in_, bytes.data() + written, bytes.size() - written);
      if (n <= 0) FAIL("fmpc lsp stopped reading its input");
      written += static_cast<std::size_t>(n);
    }
  }
  void send(const Json& message) {
    const std::string content = message.dump();
    write_raw("Content-Length: " + std::to_string(content.size()) + "\r\n\r\n" + content);
  }
  Json request(const std::string& method, const Json& params) {
    const int id = ++last_id_;
    send(Json{{"jsonrpc", "2.0"}, {"id", id}, {"method", method}, {"params", params}});
    return response(id);
  }
  void notify(const std::string& method, const Json& params) {
    send(Json{{"jsonrpc", "2.0"}, {"method", method}, {"params", params}});
  }
  // The next message; fails the test after 20 s without one.
  Json receive() {
    std::string header;
    while (header.size() < 4 || header.compare(header.size() - 4, 4, "\r\n\r\n") != 0) header += byte();
    const std::size_t at = header.find("Content-Length: ");
    REQUIRE(at != std::string::npos);
    const std::size_t length = std::stoul(header.substr(at + 16));
    std::string content;
    while (content.size() < length) content += byte();
    return Json::parse(content);
  }
  // The response with `id` (a number, or null for a refused frame), keeping the notifications met on the way.
  Json response(const Json& id) {
    for (;;) {
      Json message = receive();
      if (message.contains("id") && message["id"] == id && !message.contains("method")) return message;
      notifications.push_back(std::move(message));
    }
  }
  Json diagnostics_for(const std::string& uri) {
    for (;;) {
      Json message = receive();
      if (message.value("method", "") == "textDocument/publishDiagnostics" && message["params"]["uri"] == uri)
        return message["params"];
      notifications.push_back(std::move(message));
    }
  }
  void close_input() {
    ::close(in_);
    in_ = -1;
  }
  int wait() {
    int status = 0;
    ::waitpid(pid_, &status, 0);
    waited_ = true;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  std::vector<Json> notifications;

 private:
  char byte() {
    pollfd fd{out_, POLLIN, 0};
    if (::poll(&fd, 1, 20000) != 1) FAIL("fmpc lsp sent nothing for 20 s");
    char c = 0;
    if (::read(out_, &c, 1) != 1) FAIL("fmpc lsp closed its output");
    return c;
  }

  pid_t pid_ = -1;
  int in_ = -1;
  int out_ = -1;
  int last_id_ = 0;
  bool waited_ = false;
  void (*previous_sigpipe_)(int) = nullptr;
};

Json position(int line, int character) { return Json{{"line", line}, {"character", character}}; }

Json at(const std::string& uri, int line, int character) {
  return Json{{"textDocument", {{"uri", uri}}}, {"position", position(line, character)}};
}

// The start of the published diagnostic with `message` (null when there is none).
Json diagnostic_at(const Json& published, const std::string& message) {
  for (const Json& d : published["diagnostics"])
    if (d["message"] == message) return d["range"]["start"];
  return nullptr;
}

Json open_params(const std::string& uri, const std::string& text, int version = 1) {
  return Json{{"textDocument", {{"uri", uri}, {"languageId", "fmpc"}, {"version", version}, {"text", text}}}};
}

const char* const kLiver = R"(system liver
input HCV "FibroScan" in [0, 75] kPa
  F2 is gauss(mean 7.64, sd 0.91)
  F4 is gauss(mean 13.81, sd 2.38)
input HBV in [0, 75] kPa
  "F0-F1" is triangle(start -20, peak 0, end 20)
output stiffness in [0, 75] kPa
  soft is gauss(mean 5.3, sd 1.45)
  hard is gauss(mean 13.81, sd 2.38)
rule r1: if HCV is F2 and HBV is "F0-F1" then stiffness is soft
rule r2: if HCV is F4 then stiffness is hard
)";

}  // namespace

TEST_CASE("fmpc lsp: an editor's session (diagnostics, hover, completion, definition, symbols, formatting, fixes)",
          "[lsp]") {
  LspProcess server;
  const Json init = server.request("initialize", Json{{"processId", nullptr}, {"capabilities", Json::object()}});
  REQUIRE(init.contains("result"));
  const Json& capabilities = init["result"]["capabilities"];
  CHECK(capabilities["positionEncoding"] == "utf-16");  // the client offered nothing else
  CHECK(capabilities["textDocumentSync"]["change"] == 1);
  CHECK(capabilities["hoverProvider"] == true);
  CHECK(capabilities["documentFormattingProvider"] == true);
  server.notify("initialized", Json::object());

  const std::string uri = "file:///tmp/fmpc%20lsp/liver.fis";
  server.notify("textDocument/didOpen", open_params(uri, kLiver));
  Json published = server.diagnostics_for(uri);
  CHECK(published["version"] == 1);
  for (const Json& d : published["diagnostics"]) CHECK(d["severity"] != 1);  // lint warnings only

  // Hover on a term in a rule: its shape as written, MATLAB's vector and exact grades (1 at the mean).
  Json hover = server.request("textDocument/hover", at(uri, 9, 19))["result"];
  const std::string term = hover["contents"]["value"];
  CHECK(term.find("**F2**, a term of input **HCV**") != std::string::npos);
  CHECK(term.find("`gauss(mean 7.64, sd 0.91)` is MATLAB's `gaussmf [0.91 7.64]` in kPa") != std::string::npos);
  CHECK(term.find("| 7.64 kPa | 1 |") != std::string::npos);
  CHECK(hover["range"] == Json{{"start", position(9, 19)}, {"end", position(9, 21)}});
  // Hover on a number: every term of the variable at that value.
  hover = server.request("textDocument/hover", at(uri, 3, 21))["result"];
  const std::string value = hover["contents"]["value"];
  CHECK(value.find("**HCV = 13.81 kPa**") != std::string::npos);
  CHECK(value.find("| F4 | 1 |") != std::string::npos);
  // Hover on a variable.
  hover = server.request("textDocument/hover", at(uri, 10, 13))["result"];
  CHECK(std::string(hover["contents"]["value"]).find("named by 2 of 2 rules") != std::string::npos);

  // Completion: inputs after `if`, a variable's terms after `is`, parameters inside a call.
  server.notify("textDocument/didChange",
                Json{{"textDocument", {{"uri", uri}, {"version", 2}}},
                     {"contentChanges", Json::array({{{"text", std::string(kLiver) + "rule r3: if HBV is "}}})}});
  published = server.diagnostics_for(uri);
  CHECK(published["version"] == 2);
  CHECK(published["diagnostics"][0]["message"] == "expected a term name after 'is', found end of file");
  Json items = server.request("textDocument/completion", at(uri, 11, 19))["result"]["items"];
  std::vector<std::string> labels;
  for (const Json& item : items) labels.push_back(item["label"]);
  CHECK(labels == std::vector<std::string>{"\"F0-F1\"", "not", "somewhat", "very", "extremely"});
  items = server.request("textDocument/completion", at(uri, 11, 12))["result"]["items"];
  labels.clear();
  for (const Json& item : items) labels.push_back(item["label"]);
  CHECK(labels == std::vector<std::string>{"HCV", "HBV"});
  items = server.request("textDocument/completion", at(uri, 2, 25))["result"]["items"];  // after "mean 7.64, "
  REQUIRE(items.size() == 1);
  CHECK(items[0]["label"] == "sd");

  // Go to definition: the term of the rule's clause, the variable.
  Json location = server.request("textDocument/definition", at(uri, 9, 34))["result"];
  CHECK(location == Json{{"uri", uri}, {"range", {{"start", position(5, 2)}, {"end", position(5, 9)}}}});
  location = server.request("textDocument/definition", at(uri, 9, 12))["result"];
  CHECK(location["range"]["start"] == position(1, 6));

  // Symbols: the system, its variables with their terms, its rules (r3 too, though the text does not parse).
  const Json symbols = server.request("textDocument/documentSymbol", Json{{"textDocument", {{"uri", uri}}}})["result"];
  REQUIRE(symbols.size() == 1);
  CHECK(symbols[0]["name"] == "liver");
  std::vector<std::string> children;
  for (const Json& child : symbols[0]["children"]) children.push_back(child["name"]);
  CHECK(children == std::vector<std::string>{"HCV", "HBV", "stiffness", "r1", "r2", "r3"});
  CHECK(symbols[0]["children"][0]["children"][1]["detail"] == "gauss(mean 13.81, sd 2.38)");

  // Formatting refuses text that does not parse, and gives fmpc fmt's layout otherwise.
  Json formatting = server.request("textDocument/formatting",
                                   Json{{"textDocument", {{"uri", uri}}}, {"options", {{"tabSize", 2}, {"insertSpaces", true}}}});
  CHECK(formatting["error"]["code"] == -32803);
  const std::string messy = "system s input x in [0,1.0] a is gauss(sd 1, mean 0)\noutput y in [0, 1]\n"
                            "  k is gauss(mean 0.5,sd 0.1)  # kept\nrule: if x is a then y is k\n";
  server.notify("textDocument/didChange", Json{{"textDocument", {{"uri", uri}, {"version", 3}}},
                                               {"contentChanges", Json::array({{{"text", messy}}})}});
  server.diagnostics_for(uri);
  formatting = server.request("textDocument/formatting",
                              Json{{"textDocument", {{"uri", uri}}}, {"options", {{"tabSize", 4}, {"insertSpaces", true}}}});
  REQUIRE(formatting["result"].size() == 1);
  fmpc::DiagnosticList ignored;
  CHECK(formatting["result"][0]["newText"] == *fmpc::format_fmpc("liver.fis", messy, ignored));
  CHECK(formatting["result"][0]["range"]["end"] == position(4, 0));

  // A repair's fix-it is a quick fix; a position after a non-ASCII character counts UTF-16 code units.
  const std::string repaired = "system s\ninput x \"µ 𝔼\" in [0, 1] mL/min\n  a is gauss(mean .5, sd 1)\n";
  server.notify("textDocument/didChange", Json{{"textDocument", {{"uri", uri}, {"version", 4}}},
                                               {"contentChanges", Json::array({{{"text", repaired}}})}});
  published = server.diagnostics_for(uri);
  // "µ" is one UTF-16 unit (two bytes), "𝔼" two units (four bytes): mL/min starts at byte 28, unit 25.
  CHECK(diagnostic_at(published, "a unit with '/' must be quoted: write \"mL/min\"") == position(1, 25));
  CHECK(diagnostic_at(published, "a number starts with a digit: write 0.5") == position(2, 18));
  const Json actions = server.request("textDocument/codeAction",
                                      Json{{"textDocument", {{"uri", uri}}},
                                           {"range", {{"start", position(2, 18)}, {"end", position(2, 18)}}},
                                           {"context", {{"diagnostics", Json::array()}}}})["result"];
  REQUIRE(actions.size() == 1);
  CHECK(actions[0]["title"] == "Write 0.5");
  CHECK(actions[0]["edit"]["changes"][uri][0] ==
        Json{{"range", {{"start", position(2, 18)}, {"end", position(2, 20)}}}, {"newText", "0.5"}});

  server.notify("textDocument/didClose", Json{{"textDocument", {{"uri", uri}}}});
  CHECK(server.diagnostics_for(uri)["diagnostics"].empty());
  CHECK(server.request("shutdown", nullptr)["result"].is_null());
  server.notify("exit", nullptr);
  CHECK(server.wait() == 0);
}

TEST_CASE("fmpc lsp: positions in UTF-8 when the client offers them", "[lsp]") {
  LspProcess server;
  const Json init = server.request(
      "initialize", Json{{"capabilities", {{"general", {{"positionEncodings", Json::array({"utf-8", "utf-16"})}}}}}});
  CHECK(init["result"]["capabilities"]["positionEncoding"] == "utf-8");
  const std::string uri = "file:///tmp/u.fis";
  server.notify("textDocument/didOpen", open_params(uri, "system s\ninput x \"µ 𝔼\" in [0, 1] mL/min\n"));
  const Json published = server.diagnostics_for(uri);
  CHECK(diagnostic_at(published, "a unit with '/' must be quoted: write \"mL/min\"") == position(1, 28));
  server.close_input();
  CHECK(server.wait() == 1);  // the input ended without shutdown and exit
}

TEST_CASE("fmpc lsp: malformed and oversized frames, bad JSON and bad requests get errors, never a crash", "[lsp]") {
  LspProcess server;
  // A request before initialize.
  CHECK(server.request("textDocument/hover", at("file:///a.fis", 0, 0))["error"]["code"] == -32002);
  server.request("initialize", Json{{"capabilities", Json::object()}});
  CHECK(server.request("initialize", Json{{"capabilities", Json::object()}})["error"]["message"] ==
        "'initialize' was already sent");
  // A header part without Content-Length, then one whose length is not a number: each refused, the stream goes on.
  server.write_raw("Content-Type: application/vscode-jsonrpc; charset=utf-8\r\n\r\n");
  Json error = server.response(nullptr);
  CHECK(error["error"]["code"] == -32600);
  CHECK(error["error"]["message"] == "the header part has no Content-Length");
  server.write_raw("Content-Length: -5\r\n\r\n");
  CHECK(server.response(nullptr)["error"]["message"] == "Content-Length '-5' is not a whole number of bytes");
  server.write_raw("Content-Length: 99999999999999999999999\r\n\r\n");
  CHECK(server.response(nullptr)["error"]["message"] ==
        "Content-Length '99999999999999999999999' is not a whole number of bytes");
  // A header part over its limit.
  server.write_raw("X-Padding: " + std::string(10000, 'x') + "\r\nContent-Length: 2\r\n\r\n");
  CHECK(server.response(nullptr)["error"]["message"] == "the header part is longer than 8192 bytes (the limit)");
  // Content that is not JSON, JSON that is not a request, a batch, an id of the wrong type.
  server.write_raw("Content-Length: 9\r\n\r\n{\"jsonrpc");
  CHECK(server.response(nullptr)["error"]["code"] == -32700);
  server.send(Json::array({1, 2}));
  CHECK(server.response(nullptr)["error"]["code"] == -32600);
  server.send(Json{{"jsonrpc", "2.0"}, {"id", Json::array()}, {"method", "shutdown"}});
  CHECK(server.response(nullptr)["error"]["code"] == -32600);
  server.send(Json{{"jsonrpc", "1.0"}, {"id", 7}, {"method", "shutdown"}});
  CHECK(server.response(7)["error"]["code"] == -32600);
  // An unknown method, params missing what the method needs, a document never opened.
  CHECK(server.request("textDocument/rename", Json::object())["error"]["code"] == -32601);
  CHECK(server.request("textDocument/hover", Json{{"textDocument", {{"uri", 5}}}})["error"]["message"] ==
        "params.textDocument.uri is not a string");
  CHECK(server.request("textDocument/hover", Json{{"textDocument", {{"uri", "file:///x.fis"}}},
                                                  {"position", position(-1, 0)}})["error"]["code"] == -32602);
  CHECK(server.request("textDocument/hover", at("file:///never.fis", 0, 0))["error"]["message"] ==
        "document file:///never.fis is not open (send textDocument/didOpen first)");
  // A malformed notification is logged, not answered; a position far past the text is clamped.
  server.notify("textDocument/didOpen", Json{{"textDocument", {{"uri", "file:///b.fis"}}}});
  const std::string uri = "file:///b.fis";
  server.notify("textDocument/didOpen", open_params(uri, kLiver));
  server.diagnostics_for(uri);
  bool logged = false;
  for (const Json& n : server.notifications) logged = logged || n.value("method", "") == "window/logMessage";
  CHECK(logged);
  CHECK(server.request("textDocument/hover", at(uri, 100000, 100000))["result"].is_null());
  // Content-Length over the limit (32 MiB): refused with the limit named; its content is read and dropped, so the
  // next message is read as one.
  const std::size_t oversized = 32 * 1024 * 1024 + 1;
  server.write_raw("Content-Length: " + std::to_string(oversized) + "\r\n\r\n");
  const std::string chunk(1 << 20, '{');
  for (std::size_t sent = 0; sent < oversized; sent += chunk.size())
    server.write_raw(chunk.substr(0, std::min(chunk.size(), oversized - sent)));
  CHECK(server.response(nullptr)["error"]["message"] ==
        "Content-Length 33554433 is over the limit of 33554432 bytes a message");
  CHECK(server.request("textDocument/hover", at(uri, 2, 3))["result"]["contents"]["kind"] == "markdown");
  // After shutdown, requests are refused until exit; exit after shutdown is status 0.
  CHECK(server.request("shutdown", nullptr)["result"].is_null());
  CHECK(server.request("textDocument/hover", at(uri, 2, 3))["error"]["code"] == -32600);
  server.notify("exit", nullptr);
  CHECK(server.wait() == 0);
}

TEST_CASE("fmpc lsp: the input ending inside a message ends the server with status 1", "[lsp]") {
  LspProcess server;
  server.request("initialize", Json{{"capabilities", Json::object()}});
  server.write_raw("Content-Length: 100\r\n\r\n{\"jsonrpc\"");
  server.close_input();
  CHECK(server.wait() == 1);
}

TEST_CASE("the VS Code extension launches fmpc lsp and its grammar knows the language's words", "[lsp]") {
  const std::filesystem::path folder = kSource / "tools" / "lsp" / "vscode-fmpc";
  const Json package = Json::parse(fmpc::testing::read_file_text(folder / "package.json"));
  CHECK(package["contributes"]["languages"][0]["id"] == "fmpc");
  const std::string grammar_path = package["contributes"]["grammars"][0]["path"];
  const std::string grammar_text = fmpc::testing::read_file_text(folder / grammar_path);
  const Json grammar = Json::parse(grammar_text);
  CHECK(grammar["scopeName"] == package["contributes"]["grammars"][0]["scopeName"]);
  CHECK(std::filesystem::exists(folder / std::string(package["main"])));
  const std::string extension = fmpc::testing::read_file_text(folder / std::string(package["main"]));
  CHECK(extension.find("args: ['lsp']") != std::string::npos);
  for (const char* word : {"system", "input", "output", "rule", "if", "then", "is", "not", "and", "or", "weight",
                           "somewhat", "very", "extremely", "interval_type2", "defuzzify", "triangle", "gauss2",
                           "linear_z", "trimf", "gbellmf", "linzmf", "System", "Rules", "AndMethod", "NumMFs"})
    CHECK(grammar_text.find(word) != std::string::npos);
}

namespace {

const char* const kLspTipper = R"([System]
Name='tipper'
Type='mamdani'
NumInputs=2
NumOutputs=1
NumRules=2
AndMethod='min'

[Input1]
Name='service'
Range=[0 10]
NumMFs=2
MF1='poor':'gaussmf',[1.5 0]
MF2='good':'gaussmf',[1.5 5]

[Input2]
Name='food'
Range=[0 10]
NumMFs=1
MF1='rancid':'trapmf',[0 0 1 3]

[Output1]
Name='tip'
Range=[0 30]
NumMFs=2
MF1='cheap':'trimf',[0 5 10]
MF2='average':'trimf',[10 15 20]

[Rules]
1 1, 1 (1) : 2
2 0, 2 (1) : 1
)";

std::vector<std::string> completion_labels(const Json& completion) {
  std::vector<std::string> labels;
  for (const Json& item : completion["result"]["items"]) labels.push_back(item["label"]);
  return labels;
}

bool has_label(const std::vector<std::string>& labels, const std::string& label) {
  return std::find(labels.begin(), labels.end(), label) != labels.end();
}

}  // namespace

TEST_CASE("fmpc lsp: MATLAB .fis files get hover, completion, definitions and formatting too", "[lsp]") {
  LspProcess server;
  server.request("initialize", Json{{"capabilities", Json::object()}});
  const std::string uri = "file:///tmp/tipper.fis";
  server.notify("textDocument/didOpen", open_params(uri, kLspTipper));
  const Json opened = server.diagnostics_for(uri);
  for (const Json& d : opened["diagnostics"]) CHECK(d["severity"] != 1);
  const auto hover_text = [&](int line, int character) {
    const Json hover = server.request("textDocument/hover", at(uri, line, character))["result"];
    return hover.is_null() ? std::string() : std::string(hover["contents"]["value"]);
  };

  // A term's name, its type, a number of a range, a key of [System].
  std::string text = hover_text(12, 6);
  CHECK(text.find("**poor**, a term of input **service** is MATLAB's `gaussmf [1.5 0]`") != std::string::npos);
  CHECK(text.find("| 0 | 1 |") != std::string::npos);
  CHECK(hover_text(12, 14).find("MATLAB's name for fmpc's `gauss`") != std::string::npos);
  text = hover_text(10, 10);
  CHECK(text.find("**service = 10**") != std::string::npos);
  CHECK(text.find("| good | ") != std::string::npos);
  CHECK(hover_text(6, 2).find("**AndMethod**: how `and` joins") != std::string::npos);
  CHECK(hover_text(9, 2).find("named by 2 of 2 rules") != std::string::npos);
  // A rule line reads as the rule it means; an entry as the term it names, 0 as "takes no part".
  text = hover_text(29, 2);
  CHECK(text.find("`if service is poor or food is rancid then tip is cheap`") != std::string::npos);
  CHECK(text.find("**rancid**, a term of input **food** is MATLAB's `trapmf [0 0 1 3]`") != std::string::npos);
  CHECK(hover_text(30, 2).find("input **food** takes no part in this rule") != std::string::npos);
  CHECK(hover_text(29, 13).find("joined by `or`") != std::string::npos);

  // Go to definition: from a rule's entry to the term's name.
  CHECK(server.request("textDocument/definition", at(uri, 30, 5))["result"] ==
        Json{{"uri", uri}, {"range", {{"start", position(26, 5)}, {"end", position(26, 12)}}}});
  CHECK(server.request("textDocument/definition", at(uri, 30, 2))["result"].is_null());  // 0 names no term

  // Completion: a rule being typed (the file does not load meanwhile) offers the terms by number, with their
  // names; keys not yet given and the next sections; the values of a method; MATLAB's types.
  std::string typed = std::string(kLspTipper) + "2 ";
  server.notify("textDocument/didChange", Json{{"textDocument", {{"uri", uri}, {"version", 2}}},
                                               {"contentChanges", Json::array({{{"text", typed}}})}});
  server.diagnostics_for(uri);
  Json completion = server.request("textDocument/completion", at(uri, 31, 2));
  CHECK(completion_labels(completion) == std::vector<std::string>{"1", "0"});
  CHECK(completion["result"]["items"][0]["detail"] == "food is rancid");
  typed += "1, ";
  server.notify("textDocument/didChange", Json{{"textDocument", {{"uri", uri}, {"version", 3}}},
                                               {"contentChanges", Json::array({{{"text", typed}}})}});
  server.diagnostics_for(uri);
  CHECK(completion_labels(server.request("textDocument/completion", at(uri, 31, 5))) ==
        std::vector<std::string>{"1", "2", "0"});
  std::vector<std::string> labels = completion_labels(server.request("textDocument/completion", at(uri, 20, 0)));
  CHECK(has_label(labels, "MF2"));
  CHECK(has_label(labels, "[Input3]"));
  CHECK(!has_label(labels, "Name"));
  CHECK(!has_label(labels, "[System]"));
  labels = completion_labels(server.request("textDocument/completion", at(uri, 6, 10)));
  CHECK(labels == std::vector<std::string>{"'min'", "'prod'", "'einstein_product'"});
  typed += "\n[Output1]\nMF3='x':";
  server.notify("textDocument/didChange", Json{{"textDocument", {{"uri", uri}, {"version", 4}}},
                                               {"contentChanges", Json::array({{{"text", typed}}})}});
  server.diagnostics_for(uri);
  labels = completion_labels(server.request("textDocument/completion", at(uri, 33, 8)));
  CHECK(has_label(labels, "'trimf'"));
  CHECK(has_label(labels, "'gaussmf'"));

  // Formatting: MATLAB's writefis layout, as fmpc convert --to matlab writes it; refused while a comment would be
  // lost.
  server.notify("textDocument/didChange", Json{{"textDocument", {{"uri", uri}, {"version", 5}}},
                                               {"contentChanges", Json::array({{{"text", kLspTipper}}})}});
  server.diagnostics_for(uri);
  const Json options{{"tabSize", 2}, {"insertSpaces", true}};
  Json formatting = server.request("textDocument/formatting", Json{{"textDocument", {{"uri", uri}}}, {"options", options}});
  REQUIRE(formatting["result"].size() == 1);
  fmpc::DiagnosticList read;
  const fmpc::RuleFile file = fmpc::load_rule_file("tipper.fis", kLspTipper, read);
  fmpc::DiagnosticList written;
  CHECK(formatting["result"][0]["newText"] == fmpc::write_matlab_fis(file.systems.at(0), written));
  server.notify("textDocument/didChange",
                Json{{"textDocument", {{"uri", uri}, {"version", 6}}},
                     {"contentChanges", Json::array({{{"text", "% tips\n" + std::string(kLspTipper)}}})}});
  server.diagnostics_for(uri);
  formatting = server.request("textDocument/formatting", Json{{"textDocument", {{"uri", uri}}}, {"options", options}});
  CHECK(formatting["error"]["code"] == -32803);
  CHECK(std::string(formatting["error"]["message"]).find("line 1 has a comment") != std::string::npos);
  server.request("shutdown", nullptr);
  server.notify("exit", nullptr);
  CHECK(server.wait() == 0);
}
