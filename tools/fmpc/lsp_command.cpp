// fmpc lsp: the language server (tools/lsp, docs/lsp.md) on standard input and output. This file only moves frames
// between the file descriptors and LanguageServer.
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <unistd.h>

#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/lsp/language_server.h"
#include "tools/lsp/lsp_transport.h"

namespace fmpc::cli {

namespace {

bool write_all(int fd, const std::string& bytes) {
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    written += static_cast<std::size_t>(n);
  }
  return true;
}

bool send(const lsp::Json& message) {
  // Strings are valid UTF-8 (JSON in, fmpc's messages out); `replace` keeps a stray byte from ending the server.
  return write_all(STDOUT_FILENO, lsp::frame_message(message.dump(-1, ' ', false, lsp::Json::error_handler_t::replace)));
}

int run_lsp() {
  // A client that closes its end makes write() fail with EPIPE instead of killing the server mid-message.
  std::signal(SIGPIPE, SIG_IGN);
  lsp::FrameReader reader(STDIN_FILENO);
  lsp::LanguageServer server;
  for (;;) {
    const lsp::Frame frame = reader.next();
    switch (frame.status) {
      case lsp::Frame::Status::Message:
        for (const lsp::Json& message : server.handle_content(frame.content))
          if (!send(message)) return kExitErrors;
        break;
      case lsp::Frame::Status::Malformed:
      case lsp::Frame::Status::Oversized:
        if (!send(lsp::LanguageServer::transport_error(frame.error))) return kExitErrors;
        break;
      case lsp::Frame::Status::End:
        if (!frame.error.empty()) std::cerr << "fmpc lsp: " << frame.error << '\n';
        return server.exit_code();
    }
    if (server.exited()) return server.exit_code();
  }
}

}  // namespace

void register_lsp_command(CLI::App& app, int& exit_code) {
  CLI::App* command = app.add_subcommand(
      "lsp", "Language server for editors (LSP 3.17) on standard input and output: diagnostics, hover, completion, "
             "definitions, symbols, formatting (docs/lsp.md)");
  command->callback([&exit_code] { exit_code = run_lsp(); });
}

}  // namespace fmpc::cli
