#include "tools/lsp/language_server.h"

#include <stdexcept>

#include "tools/lsp/lsp_transport.h"

namespace fmpc::lsp {

namespace {

// JSON-RPC 2.0 and LSP 3.17 error codes.
constexpr int kParseError = -32700;
constexpr int kInvalidRequest = -32600;
constexpr int kMethodNotFound = -32601;
constexpr int kInvalidParams = -32602;
constexpr int kInternalError = -32603;
constexpr int kServerNotInitialized = -32002;
constexpr int kRequestFailed = -32803;

// A request whose params lack what the method needs: answered with kInvalidParams, naming the field.
struct InvalidParams : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A request for a method the server does not have: kMethodNotFound.
struct MethodNotFound : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A request the server understood but cannot answer (formatting a file with syntax errors): kRequestFailed.
struct RequestFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

Json error_response(const Json& id, int code, const std::string& message) {
  return Json{{"jsonrpc", "2.0"}, {"id", id}, {"error", {{"code", code}, {"message", message}}}};
}

const Json& field(const Json& object, const char* name, const std::string& where) {
  if (!object.is_object() || !object.contains(name)) throw InvalidParams(where + " has no '" + name + "'");
  return object[name];
}

std::string string_field(const Json& object, const char* name, const std::string& where) {
  const Json& value = field(object, name, where);
  if (!value.is_string()) throw InvalidParams(where + "." + name + " is not a string");
  return value.get<std::string>();
}

Position position_of(const Json& params) {
  const Json& position = field(params, "position", "params");
  const Json& line = field(position, "line", "params.position");
  const Json& character = field(position, "character", "params.position");
  if (!line.is_number_integer() || !character.is_number_integer() || line.get<long long>() < 0 ||
      character.get<long long>() < 0 || line.get<long long>() > 1 << 30 || character.get<long long>() > 1 << 30)
    throw InvalidParams("params.position needs line and character as whole numbers from 0");
  return Position{line.get<int>(), character.get<int>()};
}

Position position_in(const Json& range, const char* end) {
  Json params{{"position", field(range, end, "range")}};
  return position_of(params);
}

bool offers_utf8(const Json& params) {
  const Json* encodings = nullptr;
  if (params.is_object() && params.contains("capabilities")) {
    const Json& capabilities = params["capabilities"];
    if (capabilities.is_object() && capabilities.contains("general") && capabilities["general"].is_object() &&
        capabilities["general"].contains("positionEncodings"))
      encodings = &capabilities["general"]["positionEncodings"];
  }
  if (!encodings || !encodings->is_array()) return false;
  for (const Json& encoding : *encodings)
    if (encoding == "utf-8") return true;
  return false;
}

bool supports_snippets(const Json& params) {
  const Json::json_pointer pointer("/capabilities/textDocument/completion/completionItem/snippetSupport");
  return params.is_object() && params.contains(pointer) && params[pointer] == true;
}

Json publish(const std::string& uri, const Json& version, Json diagnostics) {
  Json params{{"uri", uri}, {"diagnostics", std::move(diagnostics)}};
  if (version.is_number_integer()) params["version"] = version;
  return Json{{"jsonrpc", "2.0"}, {"method", "textDocument/publishDiagnostics"}, {"params", std::move(params)}};
}

}  // namespace

Json LanguageServer::transport_error(const std::string& why) { return error_response(nullptr, kInvalidRequest, why); }

std::vector<Json> LanguageServer::handle_content(const std::string& content) {
  Json message = Json::parse(content, nullptr, false);
  if (message.is_discarded()) return {error_response(nullptr, kParseError, "the message is not JSON")};
  return handle(message);
}

std::vector<Json> LanguageServer::handle(const Json& message) {
  std::vector<Json> out;
  if (message.is_array()) {
    out.push_back(error_response(nullptr, kInvalidRequest, "batches are not part of the Language Server Protocol"));
    return out;
  }
  const bool has_id = message.is_object() && message.contains("id") &&
                      (message["id"].is_number_integer() || message["id"].is_string());
  const Json id = has_id ? message["id"] : Json(nullptr);
  if (!message.is_object() || message.value("jsonrpc", Json()) != "2.0") {
    out.push_back(error_response(id, kInvalidRequest, "not a JSON-RPC 2.0 message (\"jsonrpc\": \"2.0\")"));
    return out;
  }
  if (!message.contains("method")) return out;  // a response to a request of ours: the server sends none
  if (!message["method"].is_string()) {
    out.push_back(error_response(id, kInvalidRequest, "\"method\" is not a string"));
    return out;
  }
  const std::string method = message["method"].get<std::string>();
  const Json params = message.contains("params") ? message["params"] : Json::object();
  if (message.contains("id") && !has_id) {
    out.push_back(error_response(nullptr, kInvalidRequest, "\"id\" is neither a number nor a string"));
    return out;
  }
  try {
    if (!has_id) {
      dispatch_notification(method, params, out);
      return out;
    }
    if (!initialized_ && method != "initialize") {
      out.push_back(error_response(id, kServerNotInitialized, "the first request must be 'initialize'"));
      return out;
    }
    if (initialized_ && method == "initialize") {
      out.push_back(error_response(id, kInvalidRequest, "'initialize' was already sent"));
      return out;
    }
    if (shutdown_) {
      out.push_back(error_response(id, kInvalidRequest, "the server is shutting down: only 'exit' is accepted"));
      return out;
    }
    Json result = dispatch_request(method, params, out);
    out.insert(out.begin(), Json{{"jsonrpc", "2.0"}, {"id", id}, {"result", std::move(result)}});
  } catch (const InvalidParams& e) {
    if (has_id) out.push_back(error_response(id, kInvalidParams, e.what()));
    else out.push_back(Json{{"jsonrpc", "2.0"},
                            {"method", "window/logMessage"},
                            {"params", {{"type", 1}, {"message", method + ": " + e.what()}}}});
  } catch (const RequestFailed& e) {
    if (has_id) out.push_back(error_response(id, kRequestFailed, e.what()));
  } catch (const MethodNotFound& e) {
    if (has_id) out.push_back(error_response(id, kMethodNotFound, e.what()));
  } catch (const std::exception& e) {
    // A bug in fmpc: the client gets an error for this request and the server goes on.
    if (has_id) out.push_back(error_response(id, kInternalError, std::string("internal error in fmpc: ") + e.what()));
  }
  return out;
}

const Document& LanguageServer::document(const Json& params) const {
  const std::string uri = string_field(field(params, "textDocument", "params"), "uri", "params.textDocument");
  const auto it = documents_.find(uri);
  if (it == documents_.end()) throw InvalidParams("document " + uri + " is not open (send textDocument/didOpen first)");
  return *it->second;
}

Json LanguageServer::dispatch_request(const std::string& method, const Json& params, std::vector<Json>&) {
  if (method == "initialize") {
    initialized_ = true;
    encoding_ = offers_utf8(params) ? PositionEncoding::Utf8 : PositionEncoding::Utf16;
    snippets_ = supports_snippets(params);
    return Json{
        {"capabilities",
         {{"positionEncoding", encoding_ == PositionEncoding::Utf8 ? "utf-8" : "utf-16"},
          {"textDocumentSync", {{"openClose", true}, {"change", 1}}},
          {"hoverProvider", true},
          {"completionProvider", {{"triggerCharacters", Json::array({" ", "(", ","})}}},
          {"definitionProvider", true},
          {"documentSymbolProvider", true},
          {"documentFormattingProvider", true},
          {"codeActionProvider", {{"codeActionKinds", Json::array({"quickfix"})}}}}},
        {"serverInfo", {{"name", "fmpc"}, {"version", "0.1.0"}}}};
  }
  if (method == "shutdown") {
    shutdown_ = true;
    return nullptr;
  }
  if (method == "textDocument/hover") return document(params).hover(position_of(params));
  if (method == "textDocument/completion") return document(params).completion(position_of(params), snippets_);
  if (method == "textDocument/definition") return document(params).definition(position_of(params));
  if (method == "textDocument/documentSymbol") return document(params).symbols();
  if (method == "textDocument/formatting") {
    std::string why;
    std::optional<Json> edits = document(params).formatting(why);
    if (!edits) throw RequestFailed(why);
    return *edits;
  }
  if (method == "textDocument/codeAction") {
    const Json& range = field(params, "range", "params");
    return document(params).code_actions(position_in(range, "start"), position_in(range, "end"));
  }
  throw MethodNotFound("method '" + method + "' is not supported by fmpc lsp");
}

void LanguageServer::open(const std::string& uri, std::string text, const Json& version, std::vector<Json>& out) {
  if (documents_.size() >= kMaxOpenDocuments && documents_.find(uri) == documents_.end()) {
    Json diagnostic{{"range", {{"start", {{"line", 0}, {"character", 0}}}, {"end", {{"line", 0}, {"character", 0}}}}},
                    {"severity", 1},
                    {"source", "fmpc"},
                    {"message", "fmpc lsp holds at most " + std::to_string(kMaxOpenDocuments) +
                                    " open documents (docs/limits.md); close some to check this one"}};
    out.push_back(publish(uri, version, Json::array({diagnostic})));
    return;
  }
  auto document = std::make_unique<Document>(uri, path_of_uri(uri), std::move(text), encoding_);
  out.push_back(publish(uri, version, document->diagnostics()));
  documents_[uri] = std::move(document);
}

void LanguageServer::dispatch_notification(const std::string& method, const Json& params, std::vector<Json>& out) {
  if (method == "exit") {
    exited_ = true;
    return;
  }
  if (!initialized_) return;  // LSP 3.17: notifications before initialize are dropped
  if (method == "textDocument/didOpen") {
    const Json& item = field(params, "textDocument", "params");
    open(string_field(item, "uri", "params.textDocument"), string_field(item, "text", "params.textDocument"),
         item.value("version", Json()), out);
  } else if (method == "textDocument/didChange") {
    const Json& item = field(params, "textDocument", "params");
    const std::string uri = string_field(item, "uri", "params.textDocument");
    const Json& changes = field(params, "contentChanges", "params");
    const auto it = documents_.find(uri);
    if (!changes.is_array() || it == documents_.end()) return;
    std::string text = it->second->text();
    for (const Json& change : changes) {
      const std::string replacement = string_field(change, "text", "params.contentChanges[]");
      if (!change.contains("range")) {
        text = replacement;
        continue;
      }
      // An incremental change (the server asks for full ones, but a client may send these).
      const TextPositions positions(text, encoding_);
      const std::size_t from = positions.offset(position_in(change["range"], "start"));
      const std::size_t to = std::max(from, positions.offset(position_in(change["range"], "end")));
      text.replace(from, to - from, replacement);
      if (text.size() > kMaxLspMessageBytes)
        throw InvalidParams("the document would grow past " + std::to_string(kMaxLspMessageBytes) +
                            " bytes (docs/limits.md); the change is not applied");
    }
    open(uri, std::move(text), item.value("version", Json()), out);
  } else if (method == "textDocument/didClose") {
    const std::string uri = string_field(field(params, "textDocument", "params"), "uri", "params.textDocument");
    if (documents_.erase(uri) > 0) out.push_back(publish(uri, Json(), Json::array()));
  }
  // Everything else ($/cancelRequest, initialized, didSave, configuration ...) needs nothing from this server.
}

}  // namespace fmpc::lsp
