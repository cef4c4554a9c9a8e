#pragma once
// The fmpc language server (docs/lsp.md): JSON-RPC 2.0 messages of the Language Server Protocol 3.17 in, the
// messages to send back out. Full-document sync; diagnostics on open and on every change; hover, completion, go to
// definition, document symbols, formatting (fmpc fmt's layout) and quick fixes from fix-its. Transport-free, so
// that `fmpc lsp` (tools/fmpc/lsp_command.cpp) only moves frames: every request gets a response, malformed ones
// an error response, and nothing a client sends ends the server but `exit`.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "tools/lsp/lsp_document.h"

namespace fmpc::lsp {

// Open documents held at once (docs/limits.md); one more is answered with a diagnostic instead of being read.
inline constexpr std::size_t kMaxOpenDocuments = 256;

class LanguageServer {
 public:
  // One message's content (JSON text); the messages to send, in order. Text that is not JSON is a parse error.
  std::vector<Json> handle_content(const std::string& content);
  std::vector<Json> handle(const Json& message);
  // The response to a frame the transport refused (`why`: malformed header, oversized content).
  static Json transport_error(const std::string& why);

  bool exited() const { return exited_; }
  // 0 after shutdown then exit, 1 after exit without shutdown (LSP 3.17, "exit").
  int exit_code() const { return shutdown_ ? 0 : 1; }

 private:
  Json dispatch_request(const std::string& method, const Json& params, std::vector<Json>& out);
  void dispatch_notification(const std::string& method, const Json& params, std::vector<Json>& out);
  void open(const std::string& uri, std::string text, const Json& version, std::vector<Json>& out);
  const Document& document(const Json& params) const;

  std::map<std::string, std::unique_ptr<Document>> documents_;
  bool initialized_ = false;
  bool shutdown_ = false;
  bool exited_ = false;
  bool snippets_ = false;
  PositionEncoding encoding_ = PositionEncoding::Utf16;
};

}  // namespace fmpc::lsp
