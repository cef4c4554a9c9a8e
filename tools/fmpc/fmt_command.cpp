#include <CLI/CLI.hpp>
#include <iostream>

#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/rule_file_loader.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"

namespace fmpc::cli {

namespace {

struct FmtOptions {
  std::vector<std::string> files;
  bool check = false;
  bool to_stdout = false;
};

int run_fmt(const FmtOptions& options) {
  int status = kExitOk;
  std::vector<std::pair<std::string, std::string>> rewrites;
  for (const std::string& path : options.files) {
    DiagnosticList diagnostics;
    SourceFiles sources;
    std::string error;
    const std::optional<std::string> text = read_text_file(path, sim::kMaxRuleFileBytes, "rule file", error);
    if (!text) {
      diagnostics.error(SourceRange{path, 0, 0, 0, 0}, error);
    } else if (const Dialect dialect = detect_dialect(*text); dialect != Dialect::Fmpc) {
      diagnostics.error(SourceRange{path, 1, 1, 1, 9},
                        std::string("this is a ") + dialect_name(dialect) + " file; fmt lays out fmpc files only",
                        {"convert it first: fmpc convert " + path + " --to fmpc -o NEW.fis"});
    }
    std::optional<std::string> formatted;
    if (!diagnostics.has_errors()) {
      sources.add(path, *text);
      formatted = format_fmpc(path, *text, diagnostics);
    }
    print_diagnostics(diagnostics, sources, std::cerr);
    if (!formatted) {
      status = kExitErrors;
      continue;
    }
    if (options.check) {
      if (*formatted != *text) {
        std::cout << path << ": not in canonical layout (run: fmpc fmt " << path << ")\n";
        if (status == kExitOk) status = kExitWarnings;
      }
    } else if (options.to_stdout) {
      std::cout << *formatted;
    } else if (*formatted != *text) {
      rewrites.emplace_back(path, *formatted);
    }
  }
  // The files are rewritten together, all or none: after an error in any file, none is touched.
  if (rewrites.empty()) return status;
  if (status == kExitErrors) {
    std::cerr << "fmpc fmt: no file rewritten (" << rewrites.size() << " would change): fix the errors above first\n";
    return status;
  }
  std::string error;
  if (!write_text_files_atomically(rewrites, error)) {
    std::cerr << "fmpc fmt: error: " << error << '\n';
    return kExitErrors;
  }
  return status;
}

}  // namespace

void register_fmt_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<FmtOptions>();
  CLI::App* command =
      app.add_subcommand("fmt",
                         "Rewrite fmpc rule files in the canonical layout (comments kept; idempotent; atomic writes).\n"
                         "--check exits 1 when a file is not in canonical layout.");
  command->add_option("files", options->files, "fmpc rule files to lay out in place")->required();
  auto* check = command->add_flag("--check", options->check,
                                  "Change nothing; list files that are not in canonical layout and exit 1");
  command->add_flag("--stdout", options->to_stdout, "Print the canonical text instead of rewriting the file")
      ->excludes(check);
  command->callback([options, &exit_code] { exit_code = run_fmt(*options); });
}

}  // namespace fmpc::cli
