#pragma once
// `fmpc studio`'s web server (cpp-httplib, Debian libcpp-httplib-dev): the page (tools/studio/web, embedded at build
// time), Debian's browser libraries (CodeMirror, d3, three.js from /usr/share/javascript, a fixed list of files),
// and a JSON API over the library the CLI calls. It binds 127.0.0.1 only, at a given or a free port, and answers
// only requests that carry the session token (the `token` query parameter or the X-Fmpc-Token header) and a Host
// header naming 127.0.0.1 or localhost at that port; files are named relative to the opened folder and refused
// outside it (studio_security.h). docs/studio.md describes the API.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace fmpc::studio {

struct StudioOptions {
  std::filesystem::path root;  // the opened folder (made canonical by start)
  std::string opened;          // the file to show first, relative to root; empty: the first rule file there
  int port = 0;                // 0: a free port the system picks
  std::filesystem::path javascript = "/usr/share/javascript";  // Debian's libjs-* packages
  std::string token;           // empty: a fresh one from /dev/urandom
};

// Most bytes a request may carry: a rule file (8 MiB) or a CSV of patients as JSON text.
inline constexpr std::size_t kMaxRequestBytes = 16 * (std::size_t{1} << 20);

class StudioServer {
 public:
  StudioServer();
  ~StudioServer();
  StudioServer(const StudioServer&) = delete;
  StudioServer& operator=(const StudioServer&) = delete;

  // Checks the options and binds the socket; false with `error` (a folder that does not exist, a port in use).
  bool start(const StudioOptions& options, std::string& error);
  // Serves until stop() (from another thread or a signal handler's thread); returns false when listening failed.
  bool serve();
  void stop();

  int port() const;
  const std::string& token() const;
  // http://127.0.0.1:PORT/?token=TOKEN
  std::string url() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace fmpc::studio
