// libFuzzer target: the language server (tools/lsp) on hostile text. The input is opened as a document and every
// feature is asked for at positions spread over it (hover, completion, definition, code actions), then symbols and
// formatting; the same bytes are also handed to the server as a message's content. Nothing may crash, leak or
// answer with anything but JSON-RPC.
#include <cstdint>
#include <string>

#include "tools/lsp/language_server.h"

namespace {

using fmpc::lsp::Json;

Json request(int id, const std::string& method, Json params) {
  return Json{{"jsonrpc", "2.0"}, {"id", id}, {"method", method}, {"params", std::move(params)}};
}

void expect_response(const std::vector<Json>& out) {
  if (out.empty() || !out.front().contains("jsonrpc")) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fmpc::lsp::LanguageServer server;
  expect_response(server.handle(request(1, "initialize", Json{{"capabilities", Json::object()}})));
  server.handle_content(text);  // the bytes as a message
  // The bytes as a document (JSON needs valid UTF-8: invalid bytes become U+FFFD, as a client would send them).
  const std::string document = Json(text).dump(-1, ' ', false, Json::error_handler_t::replace);
  const std::string uri = "file:///fuzz.fis";
  server.handle(Json{{"jsonrpc", "2.0"},
                     {"method", "textDocument/didOpen"},
                     {"params", {{"textDocument", {{"uri", uri}, {"version", 1}, {"text", Json::parse(document)}}}}}});
  const Json document_id{{"uri", uri}};
  int lines = 1;
  for (char c : text) lines += c == '\n';
  int id = 2;
  for (int line = 0; line <= lines && id < 40; line += 1 + lines / 8) {
    for (int character : {0, 3, 11, 40}) {
      const Json at{{"textDocument", document_id}, {"position", {{"line", line}, {"character", character}}}};
      expect_response(server.handle(request(id++, "textDocument/hover", at)));
      expect_response(server.handle(request(id++, "textDocument/completion", at)));
      expect_response(server.handle(request(id++, "textDocument/definition", at)));
    }
  }
  expect_response(server.handle(request(id++, "textDocument/documentSymbol", Json{{"textDocument", document_id}})));
  expect_response(server.handle(request(id++, "textDocument/formatting", Json{{"textDocument", document_id}})));
  expect_response(server.handle(
      request(id++, "textDocument/codeAction",
              Json{{"textDocument", document_id},
                   {"range", {{"start", {{"line", 0}, {"character", 0}}}, {"end", {{"line", lines}, {"character", 0}}}}}})));
  return 0;
}
