#include <CLI/CLI.hpp>
#include <iostream>

#include "compiler/frontend/fll.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/passes/mamdani_to_sugeno.h"
#include "compiler/passes/rename_duplicate_terms.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"

namespace fmpc::cli {

namespace {

struct ConvertOptions {
  std::string file;
  std::string to;
  std::string output = "-";
  std::string system;
};

int run_convert(const ConvertOptions& options) {
  LoadedRuleFile file = load_rule_file_from_disk(options.file);
  if (file.diagnostics.has_errors()) {
    print_diagnostics(file.diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  DiagnosticList diagnostics;
  std::string text;
  if (options.to == "fmpc") {
    RuleFile selected = file.rules;
    if (!options.system.empty()) {
      const FuzzySystem* system = select_system(file, options.system, diagnostics);
      selected.systems.clear();
      if (system) selected.systems.push_back(*system);
    }
    for (FuzzySystem& system : selected.systems) {
      const std::vector<std::string> renames = rename_duplicate_terms(system);
      if (!renames.empty())
        diagnostics.warning(system.range, "renamed-term",
                            "system '" + system.name + "' repeats term names, which fmpc rules cannot tell apart; " +
                                std::to_string(renames.size()) + " terms renamed",
                            renames);
    }
    text = write_fmpc(selected);
  } else if (options.to == "sugeno") {
    // The converted system is written in the dialect the file was read in (fmpc text or MATLAB .fis).
    if (const FuzzySystem* system = select_system(file, options.system, diagnostics)) {
      FuzzySystem sugeno = *system;
      convert_mamdani_to_sugeno(sugeno, diagnostics);
      if (!diagnostics.has_errors()) {
        if (file.dialect == Dialect::Matlab) {
          text = write_matlab_fis(sugeno, diagnostics);
        } else if (file.dialect == Dialect::Fll) {
          text = write_fll(sugeno, diagnostics);
        } else if (file.dialect == Dialect::Fcl) {
          text = write_fcl(sugeno, diagnostics);
        } else {
          RuleFile converted;
          converted.path = file.rules.path;
          converted.systems.push_back(std::move(sugeno));
          text = "# Converted from " + options.file + " by `fmpc convert --to sugeno` (MATLAB convertToSugeno):\n" +
                 "# each output term is the constant at its centroid; weighted-average defuzzification.\n\n" +
                 write_fmpc(converted);
        }
      }
    }
  } else if (const FuzzySystem* system = select_system(file, options.system, diagnostics)) {
    if (options.to == "fll") text = write_fll(*system, diagnostics);
    else if (options.to == "fcl") text = write_fcl(*system, diagnostics);
    else text = write_matlab_fis(*system, diagnostics);
  }
  print_diagnostics(diagnostics, file.sources, std::cerr);
  if (diagnostics.has_errors()) return kExitErrors;
  std::string error;
  if (!write_text_file_atomically(options.output, text, error)) {
    std::cerr << options.output << ": error: " << error << '\n';
    return kExitErrors;
  }
  return kExitOk;
}

}  // namespace

void register_convert_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* command = app.add_subcommand(
      "convert",
      "Convert a rule file between the fmpc language, MATLAB's .fis format (versions 1 and 2 read, 2.0 written),\n"
      "fuzzylite's FLL and IEC 61131-7 FCL, or a Mamdani system into a Sugeno one (--to sugeno, as MATLAB's\n"
      "convertToSugeno; written in the file's own format). What the target cannot hold is a warning or an error.");
  command->add_option("file", options->file, "Rule file to convert (fmpc, MATLAB .fis, FLL or FCL)")->required();
  command->add_option("--to", options->to, "Target format")
      ->required()
      ->check(CLI::IsMember({"fmpc", "matlab", "fll", "fcl", "sugeno"}));
  command->add_option("-o,--output", options->output, "Output file, written atomically (default stdout)");
  command->add_option("--system", options->system, "Which system of the file to convert (MATLAB holds one)");
  command->callback([options, &exit_code] { exit_code = run_convert(*options); });
}

}  // namespace fmpc::cli
