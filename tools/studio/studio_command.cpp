// fmpc studio [FILE|FOLDER]: the studio (DESIGN section 9, docs/studio.md) for a folder of rule files, served on
// 127.0.0.1 at a free port with a session token in the printed address, until interrupted.
#include <CLI/CLI.hpp>

#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <iostream>
#include <pthread.h>
#include <spawn.h>
#include <sys/wait.h>
#include <thread>

#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/studio/studio_server.h"

extern char** environ;

namespace fmpc::cli {

namespace {

namespace fs = std::filesystem;

struct StudioCommandOptions {
  std::string path = ".";
  int port = 0;
  bool no_browser = false;
};

// Asks the desktop to open the address (xdg-open), without waiting; nothing happens where there is none.
void open_browser(const std::string& url) {
  if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY")) return;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  std::string program = "xdg-open", argument = url;
  char* argv[] = {program.data(), argument.data(), nullptr};
  pid_t child = 0;
  if (posix_spawnp(&child, "xdg-open", &actions, nullptr, argv, environ) == 0) {
    // Reaped in the background so that it leaves no zombie; xdg-open returns once the browser has the address.
    std::thread([child] { waitpid(child, nullptr, 0); }).detach();
  }
  posix_spawn_file_actions_destroy(&actions);
}

int run_studio(const StudioCommandOptions& options) {
  std::error_code code;
  const fs::path given(options.path);
  if (!fs::exists(given, code)) {
    std::cerr << "fmpc studio: error: '" << options.path << "' does not exist; give a rule file or a folder\n";
    return kExitErrors;
  }
  studio::StudioOptions studio;
  studio.port = options.port;
  if (fs::is_directory(given, code)) {
    studio.root = given;
  } else {
    studio.root = fs::absolute(given).parent_path();
    studio.opened = given.filename().string();
  }
  // SIGINT and SIGTERM are taken by one thread, which stops the server: the server's own threads never see them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  studio::StudioServer server;
  std::string error;
  if (!server.start(studio, error)) {
    std::cerr << "fmpc studio: error: " << error << "\n";
    return kExitErrors;
  }
  std::cout << "fmpc studio: serving " << fs::canonical(studio.root, code).string() << " at\n  " << server.url()
            << "\n(open it in a browser on this machine; Ctrl-C stops the studio)" << std::endl;
  if (!options.no_browser) open_browser(server.url());
  std::thread waiter([&] {
    int signal = 0;
    sigwait(&signals, &signal);
    server.stop();
  });
  const bool served = server.serve();
  pthread_kill(waiter.native_handle(), SIGTERM);  // wakes the waiter when the server stopped on its own
  waiter.join();
  if (!served) {
    std::cerr << "fmpc studio: error: the server stopped unexpectedly\n";
    return kExitErrors;
  }
  std::cout << "fmpc studio: stopped" << std::endl;
  return kExitOk;
}

}  // namespace

void register_studio_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<StudioCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "studio",
      "Open rule files in a browser (docs/studio.md): the text with live diagnostics, the rules as a table,\n"
      "membership functions to drag, a patient panel, control surfaces, validation against measured data, two\n"
      "versions compared over patients, and the patient's scene in 3-D. Serves 127.0.0.1 only, at a free port, with\n"
      "a session token in the address it prints; files outside the opened folder are refused. Runs until Ctrl-C.");
  command->add_option("path", options->path, "A rule file (its folder is opened) or a folder");
  command->add_option("--port", options->port, "Port to listen on (0: a free one)")->check(CLI::Range(0, 65535));
  command->add_flag("--no-browser", options->no_browser, "Print the address only; do not ask the desktop to open it");
  command->callback([options, &exit_code] { exit_code = run_studio(*options); });
}

}  // namespace fmpc::cli
